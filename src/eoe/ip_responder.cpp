#include "eoe/ip_responder.hpp"

#include <algorithm>

namespace vecat::eoe {

using protocol::Ip4;
using protocol::MacAddress;

namespace {

// Network byte order (big-endian) fields of Ethernet, ARP, IPv4 and ICMP.
std::uint16_t ld_be16(const std::uint8_t* p) noexcept {
    return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}
std::uint32_t ld_be32(const std::uint8_t* p) noexcept {
    return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}
void st_be16(std::uint8_t* p, std::uint16_t v) noexcept {
    p[0] = static_cast<std::uint8_t>(v >> 8);
    p[1] = static_cast<std::uint8_t>(v);
}
void st_be32(std::uint8_t* p, std::uint32_t v) noexcept {
    for (int i = 0; i < 4; ++i)
        p[i] = static_cast<std::uint8_t>(v >> (24 - 8 * i));
}

// Ethernet header (IEEE 802.3): destination, source, EtherType.
constexpr std::size_t kDst = 0;
constexpr std::size_t kSrc = 6;
constexpr std::size_t kType = 12;

// ARP for IPv4 over Ethernet (RFC 826), after the Ethernet header.
constexpr std::size_t kArpSize = 28;
constexpr std::uint16_t kArpHwEthernet = 1;
constexpr std::uint8_t kArpHwLen = 6;
constexpr std::uint8_t kArpProtoLen = 4;
constexpr std::uint16_t kArpRequest = 1;
constexpr std::uint16_t kArpReply = 2;
constexpr std::size_t kArpHw = 0, kArpProto = 2, kArpHwLenAt = 4, kArpProtoLenAt = 5, kArpOp = 6, kArpSha = 8,
                      kArpSpa = 14, kArpTha = 18, kArpTpa = 24;
// Ethernet frames are at least 60 bytes without FCS; shorter replies are padded.
constexpr std::size_t kMinFrame = 60;

// IPv4 header (RFC 791).
constexpr std::size_t kIpMinHeader = 20;
constexpr std::size_t kIpVersionIhl = 0, kIpTotalLength = 2, kIpFlagsFragment = 6, kIpTtl = 8,
                      kIpProtocol = 9, kIpChecksum = 10, kIpSrc = 12, kIpDst = 16;
constexpr std::uint16_t kIpMoreFragments = 0x2000;
constexpr std::uint16_t kIpFragmentOffset = 0x1FFF;
constexpr std::uint8_t kIpProtoIcmp = 1;
constexpr std::uint8_t kReplyTtl = 64;
// ICMP echo (RFC 792).
constexpr std::size_t kIcmpHeader = 8;
constexpr std::size_t kIcmpType = 0, kIcmpCode = 1, kIcmpChecksum = 2;
constexpr std::uint8_t kIcmpEchoRequest = 8;
constexpr std::uint8_t kIcmpEchoReply = 0;

void ethernet_reply_header(ConstBytes request, const MacAddress& mac, Bytes out) noexcept {
    std::copy_n(request.begin() + kSrc, protocol::kMacSize, out.begin() + kDst);
    std::copy(mac.begin(), mac.end(), out.begin() + kSrc);
    std::copy_n(request.begin() + kType, 2, out.begin() + kType);
}

Answer arp(ConstBytes frame, const MacAddress& mac, Ip4 ip, Bytes out, std::size_t& len) noexcept {
    if (frame.size() < kEthernetHeaderSize + kArpSize) return Answer::None;
    const std::uint8_t* a = frame.data() + kEthernetHeaderSize;
    if (ld_be16(a + kArpHw) != kArpHwEthernet || ld_be16(a + kArpProto) != kEtherTypeIpv4 ||
        a[kArpHwLenAt] != kArpHwLen || a[kArpProtoLenAt] != kArpProtoLen ||
        ld_be16(a + kArpOp) != kArpRequest || ld_be32(a + kArpTpa) != ip)
        return Answer::None;
    const std::size_t n = std::max(kEthernetHeaderSize + kArpSize, kMinFrame);
    if (out.size() < n) return Answer::None;
    std::fill_n(out.begin(), n, std::uint8_t{0});
    ethernet_reply_header(frame, mac, out);
    std::uint8_t* r = out.data() + kEthernetHeaderSize;
    std::copy_n(a, kArpOp, r);  // hardware and protocol type and lengths as asked
    st_be16(r + kArpOp, kArpReply);
    std::copy(mac.begin(), mac.end(), r + kArpSha);
    st_be32(r + kArpSpa, ip);
    std::copy_n(a + kArpSha, kArpHwLen + kArpProtoLen, r + kArpTha);  // the asker's MAC and IP
    len = n;
    return Answer::ArpReply;
}

Answer echo(ConstBytes frame, const MacAddress& mac, Ip4 ip, Bytes out, std::size_t& len) noexcept {
    if (frame.size() < kEthernetHeaderSize + kIpMinHeader) return Answer::None;
    const ConstBytes pkt = frame.subspan(kEthernetHeaderSize);
    const std::size_t ihl = static_cast<std::size_t>(pkt[kIpVersionIhl] & 0x0F) * 4;
    const std::size_t total = ld_be16(pkt.data() + kIpTotalLength);
    if ((pkt[kIpVersionIhl] >> 4) != 4 || ihl < kIpMinHeader || total < ihl + kIcmpHeader ||
        total > pkt.size())
        return Answer::None;
    // Fragmented datagrams are not reassembled: a device stack of this size answers whole ones only.
    if (ld_be16(pkt.data() + kIpFlagsFragment) & (kIpMoreFragments | kIpFragmentOffset)) return Answer::None;
    if (pkt[kIpProtocol] != kIpProtoIcmp || ld_be32(pkt.data() + kIpDst) != ip) return Answer::None;
    if (internet_checksum(pkt.first(ihl)) != 0) return Answer::None;
    const ConstBytes icmp = pkt.subspan(ihl, total - ihl);
    if (icmp[kIcmpType] != kIcmpEchoRequest || icmp[kIcmpCode] != 0 || internet_checksum(icmp) != 0)
        return Answer::None;
    const std::size_t n = kEthernetHeaderSize + total;
    if (out.size() < std::max(n, kMinFrame)) return Answer::None;
    std::fill_n(out.begin(), std::max(n, kMinFrame), std::uint8_t{0});
    ethernet_reply_header(frame, mac, out);
    std::uint8_t* r = out.data() + kEthernetHeaderSize;
    std::copy_n(pkt.begin(), total, r);
    r[kIpTtl] = kReplyTtl;
    std::copy_n(pkt.begin() + kIpSrc, 4, r + kIpDst);  // back to the sender
    st_be32(r + kIpSrc, ip);
    st_be16(r + kIpChecksum, 0);
    st_be16(r + kIpChecksum, internet_checksum(ConstBytes(r, ihl)));
    std::uint8_t* ic = r + ihl;
    ic[kIcmpType] = kIcmpEchoReply;
    st_be16(ic + kIcmpChecksum, 0);
    st_be16(ic + kIcmpChecksum, internet_checksum(ConstBytes(ic, total - ihl)));
    len = std::max(n, kMinFrame);
    return Answer::EchoReply;
}

}  // namespace

std::optional<MacAddress> destination_mac(ConstBytes frame) noexcept {
    if (frame.size() < kEthernetHeaderSize) return std::nullopt;
    return protocol::EthernetHeader::unpack(frame.first<protocol::EthernetHeader::kSize>()).destination;
}

Answer answer(ConstBytes frame, const MacAddress& mac, Ip4 ip, Bytes out, std::size_t& len) noexcept {
    len = 0;
    const auto dst = destination_mac(frame);
    if (!dst || ip == 0) return Answer::None;
    const std::uint16_t type =
        protocol::EthernetHeader::unpack(frame.first<protocol::EthernetHeader::kSize>()).ether_type;
    if (type == kEtherTypeArp && (*dst == protocol::kBroadcastMac || *dst == mac))
        return arp(frame, mac, ip, out, len);
    if (type == kEtherTypeIpv4 && *dst == mac) return echo(frame, mac, ip, out, len);
    return Answer::None;
}

std::uint16_t internet_checksum(ConstBytes b) noexcept {
    std::uint32_t sum = 0;
    std::size_t i = 0;
    for (; i + 1 < b.size(); i += 2)
        sum += ld_be16(b.data() + i);
    if (i < b.size()) sum += static_cast<std::uint32_t>(b[i]) << 8;
    while (sum >> 16)
        sum = (sum & 0xFFFF) + (sum >> 16);
    return static_cast<std::uint16_t>(~sum);
}

}  // namespace vecat::eoe
