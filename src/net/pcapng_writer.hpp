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
    // Throws std::system_error if the file cannot be created.
    explicit PcapngWriter(const std::string& path, const std::string& ifname = "vecat");
    ~PcapngWriter();
    PcapngWriter(const PcapngWriter&) = delete;
    PcapngWriter& operator=(const PcapngWriter&) = delete;

    // Timestamp in ns since the Unix epoch; direction: 1 inbound, 2 outbound (epb_flags).
    void write(ConstBytes frame, std::uint64_t unix_ns, int direction);
    void flush();
    std::uint64_t frames() const { return frames_; }

  private:
    std::FILE* f_ = nullptr;
    std::uint64_t frames_ = 0;
};

}  // namespace vecat::net
