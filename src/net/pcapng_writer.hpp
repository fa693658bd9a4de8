// Writes frames to a pcapng file (section header, one Ethernet interface, enhanced packet blocks) that
// Wireshark and tshark open. Writing a frame does not allocate.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

#include "common/bytes.hpp"

namespace vecat::net {

class PcapngWriter {
  public:
    // Throws std::system_error if the file cannot be created. limit_bytes bounds the file (0: no bound):
    // frames that would pass it are counted in dropped() instead of written, so a long run cannot fill
    // the disk.
    explicit PcapngWriter(const std::string& path, const std::string& ifname = "vecat",
                          std::uint64_t limit_bytes = kDefaultLimitBytes);
    ~PcapngWriter();
    PcapngWriter(const PcapngWriter&) = delete;
    PcapngWriter& operator=(const PcapngWriter&) = delete;

    // Direction of a frame (the epb_flags option of the Enhanced Packet Block).
    static constexpr int kInbound = 1;
    static constexpr int kOutbound = 2;
    // Timestamp in ns since the Unix epoch; direction: kInbound or kOutbound.
    void write(ConstBytes frame, std::uint64_t unix_ns, int direction);
    void flush();
    std::uint64_t frames() const { return frames_; }
    std::uint64_t dropped() const { return dropped_; }
    std::uint64_t bytes() const { return bytes_; }

    static constexpr std::uint64_t kDefaultLimitBytes = 1ull << 30;

  private:
    std::FILE* f_ = nullptr;
    std::uint64_t frames_ = 0;
    std::uint64_t dropped_ = 0;
    std::uint64_t bytes_ = 0;
    std::uint64_t limit_ = 0;
};

}  // namespace vecat::net
