#include "esc/sii_image.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>

namespace vecat::esc {
namespace {

namespace sii = protocol::sii;
using protocol::sii_config_crc;

using Buffer = std::vector<std::uint8_t>;

// The string table of the Strings category; index 0 means "no string".
class StringTable {
  public:
    // Without a Strings category (quirk sii_without=strings) every string is "none".
    explicit StringTable(bool kept = true) : kept_(kept) {}
    std::uint8_t add(const std::string& s) {
        if (s.empty() || !kept_) return 0;
        if (auto it = index_.find(s); it != index_.end()) return it->second;
        if (strings_.size() >= 255) throw std::length_error("SII: more than 255 strings");
        strings_.push_back(s);  // cut to 255 bytes when written, after its conversion to ISO 8859-1
        const auto idx = static_cast<std::uint8_t>(strings_.size());
        index_.emplace(s, idx);
        return idx;
    }
    const std::vector<std::string>& strings() const { return strings_; }

  private:
    bool kept_ = true;
    std::vector<std::string> strings_;
    std::map<std::string, std::uint8_t> index_;
};

void append_category(Buffer& out, sii::Category type, Buffer data) {
    if (data.size() % 2) data.push_back(0);
    LeWriter w(out);
    w.u16(static_cast<std::uint16_t>(type));
    w.u16(static_cast<std::uint16_t>(data.size() / 2));
    w.bytes(data);
}

Buffer pdo_category(const std::vector<device::Pdo>& pdos, StringTable& st) {
    Buffer b;
    LeWriter w(b);
    for (const auto& p : pdos) {
        w.u16(p.index);
        w.u8(static_cast<std::uint8_t>(p.entries.size()));
        w.u8(p.assigned ? p.sm : 0xFF);
        w.u8(0);  // DC sync
        w.u8(st.add(p.name));
        std::uint16_t flags = 0;
        if (p.mandatory) flags |= 0x0001;
        if (p.fixed) flags |= 0x0010;
        w.u16(flags);
        for (const auto& e : p.entries) {
            w.u16(e.index);
            w.u8(e.subindex);
            w.u8(st.add(e.name));
            w.u8(e.index == 0 ? 0 : static_cast<std::uint8_t>(e.type));
            w.u8(e.bit_length);
            w.u16(0);
        }
    }
    return b;
}

}  // namespace

std::vector<std::uint8_t> build_sii_image(const device::DeviceDescription& d) {
    Buffer img(128, 0);
    auto word = [&](unsigned w, std::uint16_t v) { st_le16(img.data() + 2 * w, v); };
    auto dword = [&](unsigned w, std::uint32_t v) { st_le32(img.data() + 2 * w, v); };

    word(sii::PdiControl, d.pdi_control);
    word(sii::PdiConfig, d.pdi_config);
    word(sii::SyncImpulseLen, d.sync_impulse_len);
    word(sii::StationAlias, d.station_alias);
    img[2 * sii::Checksum] = sii_config_crc(ConstBytes(img.data(), sii::kConfigAreaSize));
    dword(sii::VendorId, d.identity.vendor_id);
    dword(sii::ProductCode, d.identity.product_code);
    dword(sii::RevisionNo, d.identity.revision);
    dword(sii::SerialNo, d.identity.serial);

    const auto* mbx_out = d.sm_of_type(device::SmType::MailboxOut);
    const auto* mbx_in = d.sm_of_type(device::SmType::MailboxIn);
    if (mbx_out && mbx_in) {
        word(sii::StdRxMailboxOffset, mbx_out->start);
        word(sii::StdRxMailboxSize, mbx_out->length);
        word(sii::StdTxMailboxOffset, mbx_in->start);
        word(sii::StdTxMailboxSize, mbx_in->length);
        if (const auto boot = d.bootstrap_mailbox()) {
            word(sii::BootRxMailboxOffset, boot->out_start);
            word(sii::BootRxMailboxSize, boot->out_length);
            word(sii::BootTxMailboxOffset, boot->in_start);
            word(sii::BootTxMailboxSize, boot->in_length);
        }
        word(sii::MailboxProtocol, d.mailbox_protocols);
    }
    const unsigned kbit = d.eeprom_size_bytes * 8 / 1024;
    word(sii::Size, static_cast<std::uint16_t>(kbit > 0 ? kbit - 1 : 0));
    word(sii::Version, 1);

    // SOEM shows SII string #1 as the slave's name, so the device name is added first.
    StringTable st(!(d.quirks.sii_without & device::sii_optional::Strings));
    const std::uint8_t name_idx = st.add(d.name);
    const std::uint8_t group_idx = st.add(d.group_type);
    const std::uint8_t order_idx = st.add(d.order_code);

    Buffer general;
    {
        LeWriter w(general);
        w.u8(group_idx);
        w.u8(0);  // image
        w.u8(order_idx);
        w.u8(name_idx);
        w.u8(0);  // reserved
        w.u8((d.mailbox_protocols & device::mbx_proto::CoE) ? d.coe_details : 0);
        w.u8((d.mailbox_protocols & device::mbx_proto::FoE) ? d.foe_details : 0);
        w.u8(d.eoe_details);
        w.u8((d.mailbox_protocols & device::mbx_proto::SoE) ? d.soe_channels : 0);
        w.u8(0);  // DS402 channels
        w.u8(0);  // SysmanClass
        w.u8(d.general_flags);
        w.u16(static_cast<std::uint16_t>(d.ebus_current_ma));
        w.u8(group_idx);
        w.u8(0);        // reserved
        w.u16(0x0011);  // physical ports: port 0 and 1 MII
        w.u16(0);       // physical memory address
        w.fill(sii::kGeneralSize - general.size(), 0);
    }

    Buffer fmmu;
    for (auto f : d.fmmus)
        fmmu.push_back(static_cast<std::uint8_t>(f));
    if (fmmu.size() % 2) fmmu.push_back(0xFF);

    Buffer syncm;
    {
        LeWriter w(syncm);
        for (const auto& s : d.sync_managers) {
            w.u16(s.start);
            w.u16(s.length);
            w.u8(s.control);
            w.u8(0);
            w.u8(s.enable);
            w.u8(static_cast<std::uint8_t>(s.type));
        }
    }
    Buffer txpdo = pdo_category(d.tx_pdos, st);
    Buffer rxpdo = pdo_category(d.rx_pdos, st);

    Buffer dc;
    {
        LeWriter w(dc);
        for (const auto& m : d.dc_modes) {
            w.u32(m.cycle_time0);
            w.u32(m.shift_time0);
            w.u32(m.shift_time1);
            w.u16(static_cast<std::uint16_t>(m.sync1_cycle_factor));
            w.u16(m.assign_activate);
            w.u16(static_cast<std::uint16_t>(m.sync0_cycle_factor));
            w.u8(st.add(m.name));
            w.u8(st.add(m.description));
            w.fill(4, 0);
        }
    }

    Buffer strings;
    {
        LeWriter w(strings);
        w.u8(static_cast<std::uint8_t>(st.strings().size()));
        for (const auto& text : st.strings()) {
            // ISO 8859-1 in the image (protocol::utf8_to_sii_text); at most 255 bytes.
            const std::string s = protocol::utf8_to_sii_text(text).substr(0, 255);
            w.u8(static_cast<std::uint8_t>(s.size()));
            w.str(s);
        }
    }

    // Categories a device may lack (ETG.2010; quirk sii_without): the master must then take the
    // names, the PDOs and the DC modes elsewhere (CoE, the ESI file).
    const std::uint8_t without = d.quirks.sii_without;
    if (!(without & device::sii_optional::Strings)) append_category(img, sii::Category::Strings, strings);
    append_category(img, sii::Category::General, general);
    append_category(img, sii::Category::Fmmu, fmmu);
    append_category(img, sii::Category::SyncM, syncm);
    const bool pdo = !(without & device::sii_optional::Pdo);
    if (pdo && !txpdo.empty()) append_category(img, sii::Category::TxPdo, txpdo);
    if (pdo && !rxpdo.empty()) append_category(img, sii::Category::RxPdo, rxpdo);
    if (!dc.empty() && !(without & device::sii_optional::Dc)) append_category(img, sii::Category::Dc, dc);
    LeWriter(img).u16(sii::kEndMarker);
    LeWriter(img).u16(0xFFFF);

    if (img.size() > d.eeprom_size_bytes)
        throw std::length_error("SII image does not fit the EEPROM size of the device description");
    img.resize(d.eeprom_size_bytes, 0xFF);
    return img;
}

}  // namespace vecat::esc
