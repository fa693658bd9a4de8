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
