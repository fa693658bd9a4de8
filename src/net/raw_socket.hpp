// AF_PACKET raw socket bound to EtherType 0x88A4 on one interface.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "net/link.hpp"

namespace vecat::net {

class RawSocket final : public Link {
  public:
    // Opens the socket; throws std::system_error when the interface does not exist or on missing rights.
    explicit RawSocket(const std::string& ifname, bool promiscuous = true);
    ~RawSocket() override;
    RawSocket(const RawSocket&) = delete;
    RawSocket& operator=(const RawSocket&) = delete;

    bool send(ConstBytes frame) override;
    // Waits up to timeout_us: asleep in ppoll(), or spinning on the socket in busy-poll mode.
    long receive(Bytes buf, std::int64_t timeout_us) override;
    // Busy-poll mode: receive() never sleeps (lowest latency, one core busy while waiting).
    void set_busy_poll(bool on) { busy_poll_ = on; }
    bool busy_poll() const { return busy_poll_; }
    // Receives through a PACKET_MMAP ring (TPACKET_V2) shared with the kernel instead of one recvmsg()
    // per frame: a frame waiting in the ring is taken with a memory read, and busy-poll spins on the ring
    // without system calls. False (and the socket unchanged) when the kernel refuses.
    bool enable_rx_ring(std::string* why = nullptr);
    bool rx_ring() const { return ring_ != nullptr; }
    // Non-blocking receive: returns 0 at once when nothing is queued.
    long try_receive(Bytes buf);
    int fd() const { return fd_; }
    // Kernel receive time (CLOCK_REALTIME, ns) of the last frame try_receive/receive returned; 0 if unknown.
    std::uint64_t last_receive_realtime_ns() const { return last_rx_realtime_ns_; }
    const std::string& ifname() const { return ifname_; }
    // Link state of the interface: up with a carrier (a veth end whose peer is up).
    bool carrier() const;

  private:
    long take_from_ring(Bytes buf);

    int fd_ = -1;
    std::uint8_t* ring_ = nullptr;  // mmap()ed RX ring: ring_frames_ slots of ring_frame_size_ bytes
    std::size_t ring_bytes_ = 0;
    unsigned ring_frames_ = 0;
    unsigned ring_frame_size_ = 0;
    unsigned ring_next_ = 0;  // the slot the kernel fills next
    int ifindex_ = 0;
    std::string ifname_;
    std::uint64_t last_rx_realtime_ns_ = 0;
    bool busy_poll_ = false;
};

}  // namespace vecat::net
