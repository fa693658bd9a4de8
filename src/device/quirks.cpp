#include "device/quirks.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "device/device_description.hpp"

namespace vecat::device {
namespace {

constexpr int kMaxMailboxDelayMs = 500;  // see Quirks::mailbox_delay_ns

// A decimal number of [lo, hi], the whole text.
bool whole_number(std::string_view s, unsigned lo, unsigned hi, unsigned& v) {
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    return !s.empty() && r.ec == std::errc{} && r.ptr == s.data() + s.size() && v >= lo && v <= hi;
}

std::string sii_categories(std::string_view s, std::uint8_t& bits) {
    if (s.empty()) return "sii_without: name categories: strings, pdo, dc (joined by +)";
    while (!s.empty()) {
        const auto plus = s.find('+');
        const std::string_view c = s.substr(0, plus);
        if (c == "strings")
            bits |= sii_optional::Strings;
        else if (c == "pdo")
            bits |= sii_optional::Pdo;
        else if (c == "dc")
            bits |= sii_optional::Dc;
        else
            return "sii_without: unknown category \"" + std::string(c) + "\" (strings, pdo, dc)";
        if (plus == std::string_view::npos) break;
        s.remove_prefix(plus + 1);
        if (s.empty()) return "sii_without: a category after '+'";
    }
    return "";
}

}  // namespace

std::string parse_quirk(std::string_view text, Quirks& q) {
    while (!text.empty() && text.front() == ' ')
        text.remove_prefix(1);
    while (!text.empty() && text.back() == ' ')
        text.remove_suffix(1);
    const auto eq = text.find('=');
    const std::string_view name = text.substr(0, eq);
    const std::string_view value = eq == std::string_view::npos ? std::string_view{} : text.substr(eq + 1);
    const bool flag = eq == std::string_view::npos;
    const std::string n(name);
    if (name == "no_sdo_info" || name == "no_complete_access" || name == "fixed_pdos" ||
        name == "sdo_download_echo" || name == "mailbox_open_early") {
        if (!flag) return n + ": takes no value";
        if (name == "no_sdo_info") q.no_sdo_info = true;
        if (name == "no_complete_access") q.no_complete_access = true;
        if (name == "fixed_pdos") q.fixed_pdos = true;
        if (name == "sdo_download_echo") q.sdo_download_echo = true;
        if (name == "mailbox_open_early") q.mailbox_open_early = true;
        return "";
    }
    if (flag && (name == "max_pdo_entries" || name == "mailbox_delay_ms" || name == "mailbox_drop_every" ||
                 name == "sii_without"))
        return n + ": needs a value (" + n + "=...)";
    unsigned v = 0;
    if (name == "max_pdo_entries") {
        // A mapping object has at most 254 entries (subindex 0 counts them in one byte; 255 is reserved).
        if (!whole_number(value, 1, 254, v)) return n + ": \"" + std::string(value) + "\" is not 1..254";
        q.max_pdo_entries = v;
        return "";
    }
    if (name == "mailbox_drop_every") {
        // 1 would lose every reply: a mailbox that never answers, not a quirk a master can cope with.
        if (!whole_number(value, 2, 1000, v)) return n + ": \"" + std::string(value) + "\" is not 2..1000";
        q.mailbox_drop_every = v;
        return "";
    }
    if (name == "mailbox_delay_ms") {
        double ms = 0;
        const auto r = std::from_chars(value.data(), value.data() + value.size(), ms);
        if (value.empty() || r.ec != std::errc{} || r.ptr != value.data() + value.size() ||
            !std::isfinite(ms) || ms < 0 || ms > kMaxMailboxDelayMs)
            return n + ": \"" + std::string(value) + "\" is not 0.." + std::to_string(kMaxMailboxDelayMs) +
                   " (ms)";
        q.mailbox_delay_ns = static_cast<std::uint64_t>(std::llround(ms * 1e6));
        return "";
    }
    if (name == "sii_without") return sii_categories(value, q.sii_without);
    return "unknown quirk \"" + n + "\" (" + std::string(kQuirkNames) + ")";
}

std::string to_string(const Quirks& q) {
    std::vector<std::string> parts;
    if (q.no_sdo_info) parts.emplace_back("no_sdo_info");
    if (q.no_complete_access) parts.emplace_back("no_complete_access");
    if (q.fixed_pdos) parts.emplace_back("fixed_pdos");
    if (q.sdo_download_echo) parts.emplace_back("sdo_download_echo");
    if (q.mailbox_open_early) parts.emplace_back("mailbox_open_early");
    if (q.max_pdo_entries) parts.push_back("max_pdo_entries=" + std::to_string(q.max_pdo_entries));
    if (q.mailbox_delay_ns) {
        char ms[32];
        std::snprintf(ms, sizeof ms, "%g", static_cast<double>(q.mailbox_delay_ns) / 1e6);
        parts.push_back(std::string("mailbox_delay_ms=") + ms);
    }
    if (q.mailbox_drop_every) parts.push_back("mailbox_drop_every=" + std::to_string(q.mailbox_drop_every));
    if (q.sii_without) {
        std::string c;
        const std::pair<std::uint8_t, const char*> names[] = {
            {sii_optional::Strings, "strings"}, {sii_optional::Pdo, "pdo"}, {sii_optional::Dc, "dc"}};
        for (const auto& [bit, name] : names)
            if (q.sii_without & bit) c += (c.empty() ? "" : "+") + std::string(name);
        parts.push_back("sii_without=" + c);
    }
    std::string s;
    for (const auto& p : parts)
        s += (s.empty() ? "" : ", ") + p;
    return s;
}

std::string apply_quirks(DeviceDescription& d, const Quirks& q) {
    const bool coe = (d.mailbox_protocols & mbx_proto::CoE) != 0;
    if (!coe &&
        (q.no_sdo_info || q.no_complete_access || q.max_pdo_entries || q.fixed_pdos || q.sdo_download_echo))
        return "no_sdo_info, no_complete_access, max_pdo_entries, fixed_pdos and sdo_download_echo are CoE "
               "quirks; the device has no CoE mailbox";
    if (!d.sm_of_type(SmType::MailboxOut) &&
        (q.mailbox_delay_ns || q.mailbox_drop_every || q.mailbox_open_early))
        return "mailbox_delay_ms, mailbox_drop_every and mailbox_open_early: the device has no mailbox";
    // The CoE details byte of the SII General category and the ESI Mailbox/CoE flags (ETG.2010 General,
    // ETG.2000 CoE element) come from coe_details: clearing a bit tells a master that reads them.
    if (q.no_sdo_info) d.coe_details &= static_cast<std::uint8_t>(~coe_details::SdoInfo);
    if (q.no_complete_access) d.coe_details &= static_cast<std::uint8_t>(~coe_details::CompleteAccess);
    if (q.fixed_pdos) {
        // A device with fixed process data has the PDOs it sends and receives, no alternatives: the
        // unassigned ones go, the rest are fixed (mapping read-only) and mandatory (so the assignment object
        // is read-only too, device/dictionary.cpp), as simple I/O terminals and low-cost drives show them.
        d.coe_details &= static_cast<std::uint8_t>(~(coe_details::PdoAssign | coe_details::PdoConfig));
        for (auto* pdos : {&d.rx_pdos, &d.tx_pdos}) {
            std::erase_if(*pdos, [](const Pdo& p) { return !p.assigned; });
            for (auto& p : *pdos) {
                p.fixed = true;
                p.mandatory = true;
                std::erase_if(p.excludes, [&](std::uint16_t x) {
                    return std::none_of(pdos->begin(), pdos->end(),
                                        [&](const Pdo& o) { return o.index == x; });
                });
            }
        }
    }
    if (q.max_pdo_entries) {
        for (auto* pdos : {&d.rx_pdos, &d.tx_pdos})
            for (auto& p : *pdos) {
                if (p.entries.size() > q.max_pdo_entries) {
                    char idx[8];
                    std::snprintf(idx, sizeof idx, "0x%04X", p.index);
                    return "max_pdo_entries=" + std::to_string(q.max_pdo_entries) +
                           ": the default mapping of " + idx + " has " + std::to_string(p.entries.size()) +
                           " entries";
                }
                p.capacity = static_cast<std::uint8_t>(q.max_pdo_entries);
            }
    }
    d.quirks = q;
    return "";
}

}  // namespace vecat::device
