// AF_PACKET raw socket bound to EtherType 0x88A4 on one interface.
#pragma once

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
    // Non-blocking receive: returns 0 at once when nothing is queued.
    long try_receive(Bytes buf);
    int fd() const { return fd_; }
    // Kernel receive time (CLOCK_REALTIME, ns) of the last frame try_receive/receive returned; 0 if unknown.
    std::uint64_t last_receive_realtime_ns() const { return last_rx_realtime_ns_; }
    const std::string& ifname() const { return ifname_; }
    // Link state of the interface: up with a carrier (a veth end whose peer is up).
    bool carrier() const;

  private:
    int fd_ = -1;
    int ifindex_ = 0;
    std::string ifname_;
    std::uint64_t last_rx_realtime_ns_ = 0;
    bool busy_poll_ = false;
};

}  // namespace vecat::net
