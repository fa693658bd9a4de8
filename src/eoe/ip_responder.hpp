// The little IP stack of an EoE device: what a real device with an IP address answers on its own (ARP
// requests for its address, ICMP echo requests to it), so a master that routes IP through EoE can ping the
// device. Frames are parsed with bounds checks only; nothing else of IP is spoken (RFC 826 ARP, RFC 791
// IPv4, RFC 792 ICMP echo).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

#include "common/bytes.hpp"
#include "protocol/eoe.hpp"

namespace vecat::eoe {

inline constexpr std::size_t kEthernetHeaderSize = protocol::kEthHeaderSize;
inline constexpr std::uint16_t kEtherTypeIpv4 = 0x0800;
inline constexpr std::uint16_t kEtherTypeArp = 0x0806;

// The destination MAC address of an Ethernet frame (nullopt when shorter than a header).
std::optional<protocol::MacAddress> destination_mac(ConstBytes frame) noexcept;

// What answer() made of a frame.
enum class Answer : std::uint8_t {
    None,       // not for the device's own stack (or not a request it answers)
    ArpReply,   // an ARP request for the device's IP address: out holds the reply
    EchoReply,  // an ICMP echo request to the device's IP address: out holds the reply
};

// The device's answer to a frame the master sent, written into out (at most out.size() bytes); its length
// in len. mac and ip: the device's own addresses.
Answer answer(ConstBytes frame, const protocol::MacAddress& mac, protocol::Ip4 ip, Bytes out,
              std::size_t& len) noexcept;

// The Internet checksum (RFC 1071) of b, folded and complemented.
std::uint16_t internet_checksum(ConstBytes b) noexcept;

}  // namespace vecat::eoe
