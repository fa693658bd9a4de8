#include "net/raw_socket.hpp"

#include <arpa/inet.h>
#include <linux/if_packet.h>
#include <net/ethernet.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <time.h>
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
    fd_ = ::socket(AF_PACKET, SOCK_RAW | SOCK_CLOEXEC, htons(kEtherCat));
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
    // Kernel receive timestamps: a frame is processed as of the time it arrived, not the time the serve
    // loop got round to it (that order matters against the SYNC pulses of the DC units).
    ::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof(one));
    // Drop what was queued before the bind (frames of other protocols that raced in).
    std::uint8_t junk[1600];
    while (::recv(fd_, junk, sizeof(junk), MSG_DONTWAIT) > 0) {
    }
}

RawSocket::~RawSocket() {
    if (ring_) ::munmap(ring_, ring_bytes_);
    if (fd_ >= 0) ::close(fd_);
}

bool RawSocket::enable_rx_ring(std::string* why) {
    if (ring_) return true;
    auto refuse = [&](const char* what) {
        if (why) *why = std::string(what) + ": " + std::strerror(errno);
        return false;
    };
    int version = TPACKET_V2;
    if (::setsockopt(fd_, SOL_PACKET, PACKET_VERSION, &version, sizeof(version)) < 0)
        return refuse("PACKET_VERSION TPACKET_V2");
    // 2 KB slots hold a whole frame with the header; 64 of them are far more than a master has in flight.
    tpacket_req req{};
    req.tp_block_size = 4096;
    req.tp_frame_size = 2048;
    req.tp_block_nr = 32;
    req.tp_frame_nr = req.tp_block_size / req.tp_frame_size * req.tp_block_nr;
    if (::setsockopt(fd_, SOL_PACKET, PACKET_RX_RING, &req, sizeof(req)) < 0) return refuse("PACKET_RX_RING");
    const std::size_t bytes = static_cast<std::size_t>(req.tp_block_size) * req.tp_block_nr;
    void* m = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_LOCKED, fd_, 0);
    if (m == MAP_FAILED) m = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, 0);
    if (m == MAP_FAILED) {
        const bool ok = refuse("mmap of the RX ring");
        tpacket_req none{};
        ::setsockopt(fd_, SOL_PACKET, PACKET_RX_RING, &none, sizeof(none));
        return ok;
    }
    ring_ = static_cast<std::uint8_t*>(m);
    ring_bytes_ = bytes;
    ring_frames_ = req.tp_frame_nr;
    ring_frame_size_ = req.tp_frame_size;
    ring_next_ = 0;
    return true;
}

long RawSocket::take_from_ring(Bytes buf) {
    while (true) {
        auto* h =
            reinterpret_cast<tpacket2_hdr*>(ring_ + static_cast<std::size_t>(ring_next_) * ring_frame_size_);
        // The kernel hands the slot over by setting TP_STATUS_USER; acquire so the data is seen after it.
        const std::uint32_t status = __atomic_load_n(&h->tp_status, __ATOMIC_ACQUIRE);
        if (!(status & TP_STATUS_USER)) return 0;
        const auto* from = reinterpret_cast<const sockaddr_ll*>(reinterpret_cast<const std::uint8_t*>(h) +
                                                                TPACKET_ALIGN(sizeof(tpacket2_hdr)));
        long n = 0;
        // Outgoing (kernels without PACKET_IGNORE_OUTGOING) and cut frames (tp_snaplen < tp_len) are skipped.
        if (from->sll_pkttype != PACKET_OUTGOING && h->tp_snaplen == h->tp_len && h->tp_len <= buf.size()) {
            std::memcpy(buf.data(), reinterpret_cast<const std::uint8_t*>(h) + h->tp_mac, h->tp_snaplen);
            n = static_cast<long>(h->tp_snaplen);
            last_rx_realtime_ns_ = static_cast<std::uint64_t>(h->tp_sec) * 1'000'000'000ull +
                                   static_cast<std::uint64_t>(h->tp_nsec);
        }
        __atomic_store_n(&h->tp_status, TP_STATUS_KERNEL, __ATOMIC_RELEASE);
        ring_next_ = (ring_next_ + 1) % ring_frames_;
        if (n > 0) return n;
    }
}

bool RawSocket::send(ConstBytes frame) {
    const ssize_t n = ::send(fd_, frame.data(), frame.size(), 0);
    return n == static_cast<ssize_t>(frame.size());
}

bool RawSocket::carrier() const {
    ifreq ifr{};
    std::strncpy(ifr.ifr_name, ifname_.c_str(), IFNAMSIZ - 1);
    if (::ioctl(fd_, SIOCGIFFLAGS, &ifr) < 0) return false;
    return (ifr.ifr_flags & IFF_UP) && (ifr.ifr_flags & IFF_RUNNING);
}

long RawSocket::try_receive(Bytes buf) {
    if (ring_) return take_from_ring(buf);
    while (true) {
        sockaddr_ll from{};
        iovec iov{buf.data(), buf.size()};
        alignas(cmsghdr) std::uint8_t control[CMSG_SPACE(sizeof(timespec))];
        msghdr msg{};
        msg.msg_name = &from;
        msg.msg_namelen = sizeof(from);
        msg.msg_iov = &iov;
        msg.msg_iovlen = 1;
        msg.msg_control = control;
        msg.msg_controllen = sizeof(control);
        const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT | MSG_TRUNC);
        if (n < 0) return (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) ? 0 : -1;
        if (from.sll_pkttype == PACKET_OUTGOING) continue;       // kernels without PACKET_IGNORE_OUTGOING
        if (static_cast<std::size_t>(n) > buf.size()) continue;  // truncated: not a valid EtherCAT frame
        last_rx_realtime_ns_ = 0;
        for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
            if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
                timespec ts{};
                std::memcpy(&ts, CMSG_DATA(c), sizeof(ts));
                last_rx_realtime_ns_ = static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ull +
                                       static_cast<std::uint64_t>(ts.tv_nsec);
            }
        }
        return n;
    }
}

long RawSocket::receive(Bytes buf, std::int64_t timeout_us) {
    if (long n = try_receive(buf); n != 0) return n;
    if (busy_poll_) {
        timespec t0{}, t{};
        clock_gettime(CLOCK_MONOTONIC, &t0);
        const std::int64_t limit_ns = timeout_us * 1000;
        while (true) {
            if (long n = try_receive(buf); n != 0) return n;
            clock_gettime(CLOCK_MONOTONIC, &t);
            const std::int64_t spent = (t.tv_sec - t0.tv_sec) * 1'000'000'000ll + (t.tv_nsec - t0.tv_nsec);
            if (spent >= limit_ns) return 0;
        }
    }
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
