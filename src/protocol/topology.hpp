// The tree of a network, as a master works it out from the DL status (0x0110) of every slave in the order
// the frame reaches them (ESC datasheet section I, frame processing: ports in the order 0 -> 3 -> 1 -> 2).
// Each slave's port 0 faces the master; every other port that is open with communication has a device
// behind it, which the frame reaches next, depth first.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace vecat::protocol {

// The ports open with communication (bit p): DL status bits 9+2p..8+2p = 10b (ESC datasheet section II,
// 0x0110).
std::uint8_t open_ports(std::uint16_t dl_status) noexcept;

struct Upstream {
    int parent = -1;    // the slave whose port `port` this slave's port 0 is cabled to; -1: the master
    unsigned port = 0;  // 1..3
};

// Per slave, where its port 0 is cabled, from the open ports of every slave in frame order.
std::vector<Upstream> topology_from_open_ports(std::span<const std::uint8_t> open_ports);

// The order in which a frame reaches the devices of a tree: depth first from device 0, each device's ports
// in the order 3, 1, 2 after port 0 (ESC datasheet section I, frame processing). children[d][p] is the device
// cabled to port p of device d, -1 for none. A device reached twice (cables in a loop) is taken once; devices
// not reached from device 0 are not in the order. Empty for no devices.
std::vector<std::size_t> frame_order(std::span<const std::array<int, 4>> children);

}  // namespace vecat::protocol
