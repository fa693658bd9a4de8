#include "network/wire_point.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

#include "network/network_file.hpp"
#include "protocol/data_type.hpp"

namespace vecat::network {

// A wire's output of a device of an ESI file or SII dump (docs/network-file.md): channel N, its N-th one-bit
// output PDO entry of the default mapping (the assigned RxPDOs in order, their entries packed, gaps count);
// 0xINDEX:SUB, that output PDO entry (1 to 32 bits). An entry of the default mapping has its place in the
// image; a device with a CoE dictionary shows the entry's object instead (make_app). objects: the dictionary
// of a device with a CoE mailbox, whose master may assign the RxPDOs the default leaves out: 0xINDEX:SUB may
// name an entry of those too, if the dictionary has its object; such a point has no place in the image
// (in_image false) and reads only its object. nullptr: a device without CoE, its default mapping only.
// Throws the line's NetworkFileError (at: "FILE:LINE: NAME: ") when the device has no such output.
io::ImagePoint wire_point(const device::DeviceDescription& d,
                          const std::vector<device::ObjectDescription>* objects, const std::string& target,
                          const io::Signal& s, const std::string& at) {
    std::vector<std::string> mapped;  // the entries the RxPDOs looked at map, each once
    const auto note = [&](const device::PdoEntry& e) {
        std::string name = fmt::format("0x{:04X}:{}", e.index, e.subindex);
        if (std::find(mapped.begin(), mapped.end(), name) == mapped.end()) mapped.push_back(std::move(name));
    };
    const auto named = [&](const device::PdoEntry& e) {
        if (e.index != s.wire_index || e.subindex != s.wire_subindex) return false;
        if (e.bit_length < 1 || e.bit_length > 32)
            throw NetworkFileError(fmt::format("{}wire: {}: 0x{:04X}:{} has {} bits; a wire takes 1 to 32",
                                               at, target, e.index, e.subindex, e.bit_length));
        return true;
    };
    std::uint32_t offset = 0;
    unsigned bits = 0;  // one-bit entries so far
    for (const auto& p : d.rx_pdos) {
        if (!p.assigned) continue;
        for (const auto& e : p.entries) {
            const bool real = e.index != 0;
            if (real && s.wire_entry && named(e))
                return {offset, e.bit_length, protocol::is_signed(e.type), e.index, e.subindex};
            if (real && !s.wire_entry && e.bit_length == 1 && bits++ == s.channel)
                return {offset, 1, false, e.index, e.subindex};
            if (real) note(e);
            offset += e.bit_length;
        }
    }
    // An entry of an RxPDO the default assignment leaves out: its object, once a master assigns the RxPDO.
    if (s.wire_entry && objects) {
        for (const auto& p : d.rx_pdos) {
            if (p.assigned) continue;
            for (const auto& e : p.entries) {
                if (e.index == 0) continue;
                if (!named(e)) {
                    note(e);
                    continue;
                }
                const auto o =
                    std::find_if(objects->begin(), objects->end(),
                                 [&](const device::ObjectDescription& x) { return x.index == e.index; });
                if (o == objects->end() || !o->entry(e.subindex))
                    throw NetworkFileError(
                        fmt::format("{}wire: {}: its dictionary lacks 0x{:04X}:{} (of RxPDO 0x{:04X}, not "
                                    "assigned by default)",
                                    at, target, e.index, e.subindex, p.index));
                return {0, e.bit_length, protocol::is_signed(e.type), e.index, e.subindex, false};
            }
        }
    }
    if (s.wire_entry) {
        const std::size_t shown = std::min<std::size_t>(mapped.size(), 8);
        throw NetworkFileError(fmt::format(
            "{}wire: {} maps no output PDO entry 0x{:04X}:{} (its {}RxPDOs map {}{})", at, target,
            s.wire_index, s.wire_subindex, objects ? "" : "default ",
            mapped.empty() ? std::string("nothing")
                           : fmt::format("{}", fmt::join(mapped.begin(), mapped.begin() + shown, ", ")),
            mapped.size() > shown ? ", ..." : ""));
    }
    throw NetworkFileError(
        bits == 0
            ? fmt::format(
                  "{}wire: {} has no one-bit outputs in its default RxPDOs; name an entry: {}:0xINDEX:SUB",
                  at, target, target)
            : fmt::format("{}wire: {} has one-bit outputs 0-{} (its RxPDO entries of one bit, in order)", at,
                          target, bits - 1));
}

}  // namespace vecat::network
