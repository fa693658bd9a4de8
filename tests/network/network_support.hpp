// What the network tests share: the refusal of a network file's text, and a network served in-process to
// the project master.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>

#include "master/master.hpp"
#include "network/build.hpp"
#include "network/network_file.hpp"
#include "protocol/cia402_objects.hpp"
#include "serve/in_process_link.hpp"

namespace vecat::test {

// The refusal of a network file's text, read and its devices made (build_network): the message, "" if
// accepted.
inline std::string build_refusal(const std::string& text) {
    try {
        network::build_network(network::parse_network(text, "net.yaml"), "net.yaml");
    } catch (const network::NetworkFileError& e) {
        return e.what();
    }
    return "";
}

// A network built from a network file's text (From::Text) or from the file at a path (From::File), served
// in-process to the project master; start_ns: the link's time to start at (0: as the link starts).
struct ServedNetwork {
    enum class From { Text, File };
    explicit ServedNetwork(const std::string& s, From from = From::Text, std::uint64_t start_ns = 0)
        : built(from == From::Text ? network::build_network(network::parse_network(s), "net.yaml")
                                   : network::build_network(network::read_network_file(s), s)),
          link(*built.segment),
          master(link) {
        if (start_ns) link.set_time(start_ns);
    }
    network::BuiltNetwork built;
    net::InProcessLink link;
    master::Master master;
};

// Where a vecat drive's default RxPDO has controlword, mode of operation and target position (all found:
// valid()), and the cyclic synchronous position command written into a master's outputs of that drive.
struct CspOutputs {
    explicit CspOutputs(const master::SlaveInfo& drive)
        : cw(master::find_entry(drive.out_entries, protocol::obj::controlword.index)),
          mode(master::find_entry(drive.out_entries, protocol::obj::modes_of_operation.index)),
          target(master::find_entry(drive.out_entries, protocol::obj::target_position.index)) {}
    bool valid() const { return cw && mode && target; }
    void write(master::Master& m, std::size_t slave, std::uint16_t control, std::int32_t position) const {
        const Bytes out = m.outputs(slave);
        st_le16(out.data() + cw->bit_offset / 8, control);
        out[mode->bit_offset / 8] = 8;  // cyclic synchronous position
        st_le32(out.data() + target->bit_offset / 8, static_cast<std::uint32_t>(position));
    }
    const master::MappedEntry* cw;
    const master::MappedEntry* mode;
    const master::MappedEntry* target;
};

// How many slaves' input images differ between two masters of the same network (after a cycle of each).
inline std::size_t differing_inputs(master::Master& a, master::Master& b) {
    std::size_t n = 0;
    for (std::size_t k = 0; k < a.slaves().size(); ++k) {
        const ConstBytes x = a.inputs(k), y = b.inputs(k);
        if (!std::equal(x.begin(), x.end(), y.begin(), y.end())) ++n;
    }
    return n;
}

}  // namespace vecat::test
