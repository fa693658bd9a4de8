#include "esi/esi_check.hpp"

#include <fmt/core.h>
#include <sys/wait.h>

#include <cstdio>

#include "esc/sii_image.hpp"

namespace vecat::esi {
namespace {

std::string quote(const std::string& s) {
    std::string q = "'";
    for (char c : s)
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

void check_pdos(const char* what, const std::vector<device::Pdo>& esi, const std::vector<esc::SiiPdo>& sii,
                std::vector<std::string>& out) {
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

}  // namespace

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
    const auto sii = esc::parse_sii(ConstBytes(image.data(), image.size()));
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
