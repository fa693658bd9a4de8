#include "protocol/sii.hpp"

#include <algorithm>

namespace vecat::protocol {

std::uint8_t sii_config_crc(ConstBytes data) {
    std::uint8_t crc = 0xFF;
    const std::size_t n = std::min<std::size_t>(data.size(), sii::kConfigAreaSize);
    for (std::size_t i = 0; i < n; ++i) {
        crc ^= data[i];
        for (int bit = 0; bit < 8; ++bit)
            crc = static_cast<std::uint8_t>((crc & 0x80) ? (crc << 1) ^ 0x07 : (crc << 1));
    }
    return crc;
}

std::string SiiInfo::string_at(unsigned idx) const {
    if (idx == 0 || idx > strings.size()) return {};
    return strings[idx - 1];
}

SiiInfo parse_sii(ConstBytes image) {
    SiiInfo s;
    auto word = [&](unsigned w) -> std::uint16_t { return read_le16(image, 2 * w).value_or(0xFFFF); };
    auto dword = [&](unsigned w) -> std::uint32_t { return read_le32(image, 2 * w).value_or(0xFFFFFFFF); };
    if (image.size() < 2 * sii::FirstCategory) {
        s.errors.push_back("image shorter than the 128-byte header");
        return s;
    }
    s.pdi_control = word(sii::PdiControl);
    s.station_alias = word(sii::StationAlias);
    s.checksum_ok = sii_config_crc(image.first(sii::kConfigAreaSize)) == image[2 * sii::Checksum];
    if (!s.checksum_ok) s.errors.push_back("configuration area checksum (word 7) does not match");
    s.identity = {dword(sii::VendorId), dword(sii::ProductCode), dword(sii::RevisionNo),
                  dword(sii::SerialNo)};
    s.boot_rx_mbx_offset = word(sii::BootRxMailboxOffset);
    s.boot_rx_mbx_size = word(sii::BootRxMailboxSize);
    s.boot_tx_mbx_offset = word(sii::BootTxMailboxOffset);
    s.boot_tx_mbx_size = word(sii::BootTxMailboxSize);
    s.std_rx_mbx_offset = word(sii::StdRxMailboxOffset);
    s.std_rx_mbx_size = word(sii::StdRxMailboxSize);
    s.std_tx_mbx_offset = word(sii::StdTxMailboxOffset);
    s.std_tx_mbx_size = word(sii::StdTxMailboxSize);
    s.mailbox_protocols = word(sii::MailboxProtocol);
    s.size_word = word(sii::Size);
    s.version = word(sii::Version);

    std::size_t pos = 2 * sii::FirstCategory;
    while (true) {
        auto type = read_le16(image, pos);
        if (!type) {
            s.errors.push_back("category list runs past the end of the image (no end marker)");
            break;
        }
        if (*type == sii::kEndMarker) break;
        auto len_words = read_le16(image, pos + 2);
        if (!len_words) {
            s.errors.push_back("truncated category header");
            break;
        }
        const std::size_t start = pos + sii::kCategoryHeaderSize;
        const std::size_t len = 2u * *len_words;
        if (start + len > image.size()) {
            s.errors.push_back("category " + std::to_string(*type) + " runs past the end of the image");
            break;
        }
        ConstBytes data = image.subspan(start, len);
        switch (static_cast<sii::Category>(*type & sii::kCategoryIdMask)) {
            case sii::Category::Strings: {
                if (data.empty()) break;
                const unsigned n = data[0];
                std::size_t p = 1;
                for (unsigned i = 0; i < n; ++i) {
                    if (p >= data.size()) {
                        s.errors.push_back("string table truncated");
                        break;
                    }
                    const unsigned l = data[p++];
                    if (p + l > data.size()) {
                        s.errors.push_back("string runs past its category");
                        break;
                    }
                    s.strings.push_back(sii_text_to_utf8(
                        std::string_view(reinterpret_cast<const char*>(data.data() + p), l)));
                    p += l;
                }
                break;
            }
            case sii::Category::General:
                if (data.size() < sii::kGeneralSize) {
                    s.errors.push_back("General category shorter than 32 bytes");
                    break;
                }
                if (data.size() != sii::kGeneralSize) s.errors.push_back("General category is not 32 bytes");
                s.has_general = true;
                s.group_idx = data[sii::general::GroupIdx];
                s.image_idx = data[sii::general::ImgIdx];
                s.order_idx = data[sii::general::OrderIdx];
                s.name_idx = data[sii::general::NameIdx];
                s.coe_details = data[sii::general::CoeDetails];
                s.foe_details = data[sii::general::FoeDetails];
                s.eoe_details = data[sii::general::EoeDetails];
                s.flags = data[sii::general::Flags];
                s.ebus_current = static_cast<std::int16_t>(ld_le16(data.data() + sii::general::EbusCurrent));
                s.physical_ports = ld_le16(data.data() + sii::general::PhysicalPorts);
                break;
            case sii::Category::Fmmu:
                s.fmmus.assign(data.begin(), data.end());
                break;
            case sii::Category::SyncM:
                for (std::size_t p = 0; p + sii::kSyncMSize <= data.size(); p += sii::kSyncMSize)
                    s.sync_managers.push_back({ld_le16(data.data() + p), ld_le16(data.data() + p + 2),
                                               data[p + 4], data[p + 5], data[p + 6], data[p + 7]});
                break;
            case sii::Category::TxPdo:
            case sii::Category::RxPdo: {
                auto& list =
                    (*type & sii::kCategoryIdMask) == static_cast<std::uint16_t>(sii::Category::TxPdo)
                        ? s.tx_pdos
                        : s.rx_pdos;
                std::size_t p = 0;
                while (p + sii::kPdoSize <= data.size()) {
                    SiiPdo pdo{ld_le16(data.data() + p),     data[p + 3], data[p + 4], data[p + 5],
                               ld_le16(data.data() + p + 6), {}};
                    const unsigned n = data[p + 2];
                    p += sii::kPdoSize;
                    for (unsigned i = 0; i < n; ++i, p += sii::kPdoEntrySize) {
                        if (p + sii::kPdoEntrySize > data.size()) {
                            s.errors.push_back("PDO entries run past their category");
                            break;
                        }
                        pdo.entries.push_back({ld_le16(data.data() + p), data[p + 2], data[p + 3],
                                               data[p + 4], data[p + 5], ld_le16(data.data() + p + 6)});
                    }
                    list.push_back(std::move(pdo));
                }
                break;
            }
            case sii::Category::Dc:
                for (std::size_t p = 0; p + sii::kDcModeSize <= data.size(); p += sii::kDcModeSize) {
                    SiiDcMode m;
                    m.cycle_time0 = ld_le32(data.data() + p);
                    m.shift_time0 = ld_le32(data.data() + p + 4);
                    m.shift_time1 = ld_le32(data.data() + p + 8);
                    m.sync1_cycle_factor = static_cast<std::int16_t>(ld_le16(data.data() + p + 12));
                    m.assign_activate = ld_le16(data.data() + p + 14);
                    m.sync0_cycle_factor = static_cast<std::int16_t>(ld_le16(data.data() + p + 16));
                    m.name = std::to_string(data[p + 18]);  // resolved below
                    m.description = std::to_string(data[p + 19]);
                    s.dc_modes.push_back(m);
                }
                break;
            default:
                break;
        }
        pos = start + len;
    }
    for (auto& m : s.dc_modes) {
        m.name = s.string_at(static_cast<unsigned>(std::stoul(m.name)));
        m.description = s.string_at(static_cast<unsigned>(std::stoul(m.description)));
    }
    return s;
}

std::string sii_text_to_utf8(std::string_view latin1) {
    std::string out;
    out.reserve(latin1.size());
    for (const char ch : latin1) {
        const auto c = static_cast<unsigned char>(ch);
        if (c < 0x80) {
            out += ch;
        } else {
            out += static_cast<char>(0xC0 | (c >> 6));
            out += static_cast<char>(0x80 | (c & 0x3F));
        }
    }
    return out;
}

std::string utf8_to_sii_text(std::string_view utf8) {
    std::string out;
    out.reserve(utf8.size());
    for (std::size_t i = 0; i < utf8.size();) {
        const auto c = static_cast<unsigned char>(utf8[i]);
        const auto cont = [&](std::size_t k) {
            return i + k < utf8.size() && (static_cast<unsigned char>(utf8[i + k]) & 0xC0) == 0x80;
        };
        unsigned n = c < 0x80             ? 1
                     : (c & 0xE0) == 0xC0 ? 2
                     : (c & 0xF0) == 0xE0 ? 3
                     : (c & 0xF8) == 0xF0 ? 4
                                          : 0;
        bool valid = n >= 1;
        for (unsigned k = 1; valid && k < n; ++k)
            valid = cont(k);
        if (!valid || (n == 2 && c < 0xC2)) {  // no UTF-8 sequence (or an overlong one): the byte as it is
            out += static_cast<char>(c);
            ++i;
            continue;
        }
        if (n == 1) {
            out += static_cast<char>(c);
        } else if (n == 2 && c <= 0xC3) {  // U+0080..U+00FF: in ISO 8859-1
            out += static_cast<char>(((c & 0x03) << 6) | (static_cast<unsigned char>(utf8[i + 1]) & 0x3F));
        } else {
            out += '?';
        }
        i += n;
    }
    return out;
}

}  // namespace vecat::protocol
