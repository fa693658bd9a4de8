#include "esi/esi_check.hpp"

#include <fmt/core.h>
#include <sys/wait.h>

#include <cstdio>
#include <iterator>

#include "protocol/sii.hpp"

namespace vecat::esi {
namespace {

std::string quote(const std::string& s) {
    std::string q = "'";
    for (char c : s)
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

void check_pdos(const char* what, const std::vector<device::Pdo>& esi,
                const std::vector<protocol::SiiPdo>& sii, std::vector<std::string>& out) {
    if (esi.size() != sii.size())
        out.push_back(fmt::format("{}: ESI has {} PDOs, SII {}", what, esi.size(), sii.size()));
    for (std::size_t i = 0; i < std::min(esi.size(), sii.size()); ++i) {
        const auto& a = esi[i];
        const auto& b = sii[i];
        if (a.index != b.index)
            out.push_back(fmt::format("{} #{}: index ESI 0x{:04X}, SII 0x{:04X}", what, i, a.index, b.index));
        const std::uint8_t sm = a.assigned ? a.sm : 0xFF;
        if (sm != b.sm)
            out.push_back(fmt::format("{} 0x{:04X}: SyncManager ESI {}, SII {}", what, a.index, sm, b.sm));
        if (a.entries.size() != b.entries.size())
            out.push_back(fmt::format("{} 0x{:04X}: ESI {} entries, SII {}", what, a.index, a.entries.size(),
                                      b.entries.size()));
        for (std::size_t k = 0; k < std::min(a.entries.size(), b.entries.size()); ++k) {
            const auto& x = a.entries[k];
            const auto& y = b.entries[k];
            if (x.index != y.index || x.subindex != y.subindex || x.bit_length != y.bit_length)
                out.push_back(fmt::format(
                    "{} 0x{:04X} entry {}: ESI 0x{:04X}:{} {} bits, SII 0x{:04X}:{} {} bits", what, a.index,
                    k + 1, x.index, x.subindex, x.bit_length, y.index, y.subindex, y.bit_length));
        }
    }
}

struct Region {
    std::uint16_t type = 0;  // category type; 0xFFFE: header area
    std::size_t start = 0;   // first data byte of the category
    std::size_t length = 0;  // data bytes
};

// The categories of an image and where their data lie.
std::vector<Region> regions(const std::vector<std::uint8_t>& img) {
    std::vector<Region> out;
    std::size_t pos = 2 * protocol::sii::FirstCategory;
    while (pos + 4 <= img.size()) {
        const std::uint16_t type = ld_le16(img.data() + pos);
        const std::size_t words = ld_le16(img.data() + pos + 2);
        out.push_back({type, pos, 4});  // the category header itself
        out.back().type = static_cast<std::uint16_t>(type);
        if (type == 0xFFFF) break;
        out.push_back({type, pos + 4, 2 * words});
        pos += 4 + 2 * words;
    }
    return out;
}

std::string category_name(std::uint16_t t) {
    switch (t) {
        case 10:
            return "Strings";
        case 20:
            return "DataTypes";
        case 30:
            return "General";
        case 40:
            return "FMMU";
        case 41:
            return "SyncM";
        case 50:
            return "TxPDO";
        case 51:
            return "RxPDO";
        case 60:
            return "DC";
        case 0xFFFF:
            return "End";
        default:
            return fmt::format("category {}", t);
    }
}

std::string header_word_name(std::size_t word) {
    switch (word) {
        case 0x00:
            return "PDI control";
        case 0x01:
            return "PDI configuration";
        case 0x02:
            return "SYNC impulse length";
        case 0x03:
            return "PDI configuration 2";
        case 0x04:
            return "station alias";
        case 0x07:
            return "checksum";
        case 0x08:
        case 0x09:
            return "vendor id";
        case 0x0A:
        case 0x0B:
            return "product code";
        case 0x0C:
        case 0x0D:
            return "revision";
        case 0x0E:
        case 0x0F:
            return "serial number";
        case 0x14:
        case 0x15:
        case 0x16:
        case 0x17:
            return "bootstrap mailbox";
        case 0x18:
        case 0x19:
        case 0x1A:
        case 0x1B:
            return "standard mailbox";
        case 0x1C:
            return "mailbox protocols";
        case 0x3E:
            return "EEPROM size";
        case 0x3F:
            return "version";
        default:
            return "reserved";
    }
}

std::string general_field(std::size_t off) {
    static const char* names[] = {"group string index",
                                  "image string index",
                                  "order string index",
                                  "name string index",
                                  "reserved",
                                  "CoE details",
                                  "FoE details",
                                  "EoE details",
                                  "SoE channels",
                                  "DS402 channels",
                                  "SysmanClass",
                                  "flags",
                                  "EBus current",
                                  "EBus current",
                                  "group string index (compat)",
                                  "reserved",
                                  "physical ports",
                                  "physical ports",
                                  "physical memory address",
                                  "physical memory address"};
    return off < std::size(names) ? names[off] : "reserved";
}

std::string why_category(std::uint16_t type, std::size_t off) {
    switch (type) {
        case 10:
            return "string table: vecat adds the device name first (masters show string 1 as the name), then "
                   "group and order code, then PDO, entry and DC names";
        case 30:
            if (off <= 3 || off == 14) return "string index: the string tables are ordered differently";
            if (off == 5) return "CoE details: vecat sets the SDO bit and the ESI CoE flags";
            if (off == 16 || off == 17) return "physical ports: vecat always declares two MII ports";
            return "General field " + general_field(off) + " differs";
        case 40:
            return "FMMU padding byte: vecat pads an odd count with 0xFF, 0x00 and 0xFF both mean unused";
        case 50:
        case 51:
            return "PDO category: vecat writes every ESI PDO with its entries";
        case 60:
            return "DC category: vecat writes the ESI Dc op modes";
        default:
            return category_name(type) + " content differs";
    }
}

}  // namespace

std::vector<SiiByteDiff> diff_sii(const std::vector<std::uint8_t>& gen,
                                  const std::vector<std::uint8_t>& ref) {
    std::vector<SiiByteDiff> out;
    const auto rg = regions(gen), rr = regions(ref);
    auto locate = [](const std::vector<Region>& rs, std::size_t i) -> const Region* {
        for (const auto& r : rs)
            if (i >= r.start && i < r.start + r.length) return &r;
        return nullptr;
    };
    const std::size_t common = std::min(gen.size(), ref.size());
    for (std::size_t i = 0; i < common; ++i) {
        if (gen[i] == ref[i]) continue;
        SiiByteDiff d{i, gen[i], ref[i], {}, {}};
        if (i < 2 * protocol::sii::FirstCategory) {
            const std::size_t w = i / 2;
            d.where = fmt::format("word 0x{:02X} {}", w, header_word_name(w));
            if (w == protocol::sii::Checksum)
                d.why = "checksum over words 0..6, which differ";
            else if (w == protocol::sii::Size)
                d.why = fmt::format("EEPROM size: generated image {} bytes, reference {} bytes", gen.size(),
                                    ref.size());
            else
                d.why = "header value from the ESI differs";
            out.push_back(d);
            continue;
        }
        const Region* a = locate(rg, i);
        const Region* b = locate(rr, i);
        d.where = b ? fmt::format("reference {} +{}", category_name(b->type), i - b->start)
                    : std::string("reference: past its End category (unused 0xFF)");
        if (!a) {
            d.why = "generated image: past its End category";
        } else if (!b) {
            d.why = fmt::format("generated {} +{} is where the reference has ended", category_name(a->type),
                                i - a->start);
        } else if (a->type != b->type || a->start != b->start) {
            d.why = fmt::format(
                "generated {} +{} here: categories shifted (an earlier category differs in length "
                "or one image has a category the other lacks)",
                category_name(a->type), i - a->start);
        } else if (a->length == 4 && b->length == 4 && a->start + 4 <= gen.size()) {
            d.why = "category header: data length differs";
        } else {
            d.why = why_category(b->type, i - b->start);
        }
        out.push_back(d);
    }
    if (gen.size() != ref.size())
        out.push_back(
            {common, gen.size() > common ? gen[common] : -1, ref.size() > common ? ref[common] : -1,
             fmt::format("bytes {}..{}", common, std::max(gen.size(), ref.size()) - 1),
             fmt::format("image sizes differ: generated {} bytes, reference {}", gen.size(), ref.size())});
    return out;
}

bool validate_with_xmllint(const std::string& file, const std::string& xsd, std::string* output) {
    const std::string cmd = "xmllint --noout --schema " + quote(xsd) + " " + quote(file) + " 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) {
        if (output) *output = "cannot run xmllint";
        return false;
    }
    std::string out;
    char buf[4096];
    std::size_t n;
    while ((n = fread(buf, 1, sizeof buf, p)) > 0)
        out.append(buf, n);
    const int st = pclose(p);
    if (output) *output = out;
    return WIFEXITED(st) && WEXITSTATUS(st) == 0;
}

std::vector<std::string> check_consistency(const device::DeviceDescription& d,
                                           const std::vector<std::uint8_t>& image) {
    std::vector<std::string> out;
    const auto sii = protocol::parse_sii(ConstBytes(image.data(), image.size()));
    for (const auto& e : sii.errors)
        out.push_back("SII: " + e);
    auto cmp = [&](const char* what, std::uint32_t esi, std::uint32_t s) {
        if (esi != s) out.push_back(fmt::format("{}: ESI 0x{:X}, SII 0x{:X}", what, esi, s));
    };
    cmp("vendor id", d.identity.vendor_id, sii.identity.vendor_id);
    cmp("product code", d.identity.product_code, sii.identity.product_code);
    cmp("revision", d.identity.revision, sii.identity.revision);
    if (sii.sync_managers.size() != d.sync_managers.size())
        out.push_back(
            fmt::format("SyncManagers: ESI {}, SII {}", d.sync_managers.size(), sii.sync_managers.size()));
    for (std::size_t i = 0; i < std::min(sii.sync_managers.size(), d.sync_managers.size()); ++i) {
        const auto& a = d.sync_managers[i];
        const auto& b = sii.sync_managers[i];
        if (a.start != b.start)
            out.push_back(fmt::format("SM{} start: ESI 0x{:04X}, SII 0x{:04X}", i, a.start, b.start));
        if (a.length != b.length)
            out.push_back(fmt::format("SM{} length: ESI {}, SII {}", i, a.length, b.length));
        if (a.control != b.control)
            out.push_back(fmt::format("SM{} control: ESI 0x{:02X}, SII 0x{:02X}", i, a.control, b.control));
        if (static_cast<std::uint8_t>(a.type) != b.type)
            out.push_back(fmt::format("SM{} type: ESI {}, SII {}", i, static_cast<int>(a.type), b.type));
    }
    if (const auto* mo = d.sm_of_type(device::SmType::MailboxOut)) {
        cmp("mailbox out offset (SII word 0x18)", mo->start, sii.std_rx_mbx_offset);
        cmp("mailbox out size (SII word 0x19)", mo->length, sii.std_rx_mbx_size);
    }
    if (const auto* mi = d.sm_of_type(device::SmType::MailboxIn)) {
        cmp("mailbox in offset (SII word 0x1A)", mi->start, sii.std_tx_mbx_offset);
        cmp("mailbox in size (SII word 0x1B)", mi->length, sii.std_tx_mbx_size);
    }
    cmp("mailbox protocols (SII word 0x1C)", d.mailbox_protocols, sii.mailbox_protocols);
    check_pdos("RxPDO", d.rx_pdos, sii.rx_pdos, out);
    check_pdos("TxPDO", d.tx_pdos, sii.tx_pdos, out);

    // Process data SM lengths against the default PDO assignment.
    for (std::size_t i = 0; i < d.sync_managers.size(); ++i) {
        const auto& s = d.sync_managers[i];
        if (s.type == device::SmType::Outputs && s.length != d.output_bytes())
            out.push_back(fmt::format("SM{} length {} but the assigned RxPDOs need {} bytes", i, s.length,
                                      d.output_bytes()));
        if (s.type == device::SmType::Inputs && s.length != d.input_bytes())
            out.push_back(fmt::format("SM{} length {} but the assigned TxPDOs need {} bytes", i, s.length,
                                      d.input_bytes()));
    }
    // PDO entries against the dictionary.
    const auto objs = device::dictionary_objects(d);
    auto find = [&](std::uint16_t idx, std::uint8_t sub) -> const device::EntryDescription* {
        for (const auto& o : objs)
            if (o.index == idx) return o.entry(sub);
        return nullptr;
    };
    for (bool rx : {true, false}) {
        for (const auto& p : rx ? d.rx_pdos : d.tx_pdos) {
            for (const auto& e : p.entries) {
                if (e.index == 0) continue;
                const auto* de = find(e.index, e.subindex);
                if (!de) {
                    out.push_back(fmt::format("{} 0x{:04X} maps 0x{:04X}:{}, which is not in the dictionary",
                                              rx ? "RxPDO" : "TxPDO", p.index, e.index, e.subindex));
                    continue;
                }
                if (de->bit_length != e.bit_length)
                    out.push_back(fmt::format(
                        "{} 0x{:04X} maps 0x{:04X}:{} with {} bits, the dictionary has {}",
                        rx ? "RxPDO" : "TxPDO", p.index, e.index, e.subindex, e.bit_length, de->bit_length));
                const std::uint16_t need = rx ? device::access::RxPdoMappable : device::access::TxPdoMappable;
                if (!(de->access & need))
                    out.push_back(
                        fmt::format("{} 0x{:04X} maps 0x{:04X}:{}, which the dictionary does not mark "
                                    "{}-mappable",
                                    rx ? "RxPDO" : "TxPDO", p.index, e.index, e.subindex, rx ? "Rx" : "Tx"));
            }
        }
    }
    return out;
}

}  // namespace vecat::esi
