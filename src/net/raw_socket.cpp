#include "net/raw_socket.hpp"

#include <arpa/inet.h>
#include <linux/if_packet.h>
#include <net/ethernet.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <system_error>

#ifndef PACKET_IGNORE_OUTGOING
#define PACKET_IGNORE_OUTGOING 23
#endif

namespace vecat::net {

namespace {
constexpr std::uint16_t kEtherCat = 0x88A4;
[[noreturn]] void fail(const std::string& what) {
    throw std::system_error(errno, std::generic_category(), what);
}
}  // namespace

RawSocket::RawSocket(const std::string& ifname, bool promiscuous) : ifname_(ifname) {
    fd_ = ::socket(AF_PACKET, SOCK_RAW, htons(kEtherCat));
    if (fd_ < 0) fail("socket(AF_PACKET) (needs CAP_NET_RAW)");
    ifindex_ = static_cast<int>(if_nametoindex(ifname.c_str()));
    if (ifindex_ == 0) {
        const int e = errno;
        ::close(fd_);
        errno = e;
        fail("interface " + ifname);
    }
    sockaddr_ll sll{};
    sll.sll_family = AF_PACKET;
    sll.sll_protocol = htons(kEtherCat);
    sll.sll_ifindex = ifindex_;
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&sll), sizeof(sll)) < 0) {
        const int e = errno;
        ::close(fd_);
        errno = e;
        fail("bind " + ifname);
    }
    // Never see the frames this socket sends (a slave must not process its own replies).
    int one = 1;
    ::setsockopt(fd_, SOL_PACKET, PACKET_IGNORE_OUTGOING, &one, sizeof(one));
    if (promiscuous) {
        packet_mreq mr{};
        mr.mr_ifindex = ifindex_;
        mr.mr_type = PACKET_MR_PROMISC;
        ::setsockopt(fd_, SOL_PACKET, PACKET_ADD_MEMBERSHIP, &mr, sizeof(mr));
    }
    // Drop what was queued before the bind (frames of other protocols that raced in).
    std::uint8_t junk[1600];
    while (::recv(fd_, junk, sizeof(junk), MSG_DONTWAIT) > 0) {
    }
}

RawSocket::~RawSocket() {
    if (fd_ >= 0) ::close(fd_);
}

bool RawSocket::send(ConstBytes frame) {
    const ssize_t n = ::send(fd_, frame.data(), frame.size(), 0);
    return n == static_cast<ssize_t>(frame.size());
}

long RawSocket::try_receive(Bytes buf) {
    while (true) {
        sockaddr_ll from{};
        socklen_t fl = sizeof(from);
        const ssize_t n = ::recvfrom(fd_, buf.data(), buf.size(), MSG_DONTWAIT | MSG_TRUNC,
                                     reinterpret_cast<sockaddr*>(&from), &fl);
        if (n < 0) return (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) ? 0 : -1;
        if (from.sll_pkttype == PACKET_OUTGOING) continue;       // kernels without PACKET_IGNORE_OUTGOING
        if (static_cast<std::size_t>(n) > buf.size()) continue;  // truncated: not a valid EtherCAT frame
        return n;
    }
}

long RawSocket::receive(Bytes buf, std::int64_t timeout_us) {
    if (long n = try_receive(buf); n != 0) return n;
    pollfd p{fd_, POLLIN, 0};
    // ppoll: microsecond timeouts (SYNC pulses of 125 us must not wait for a millisecond poll).
    const std::int64_t us = timeout_us <= 0 ? 0 : timeout_us;
    const timespec ts{static_cast<time_t>(us / 1'000'000), static_cast<long>((us % 1'000'000) * 1000)};
    const int r = ::ppoll(&p, 1, &ts, nullptr);
    if (r < 0) return errno == EINTR ? 0 : -1;
    if (r == 0) return 0;
    return try_receive(buf);
}

}  // namespace vecat::net
