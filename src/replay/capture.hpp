// A capture of a master talking to slaves (pcap or pcapng, read through libpcap), as the replay needs it:
// the EtherCAT frames with their time stamps and frame numbers, each master frame paired with the reply
// that came back for it. Frames of other protocols are counted and left out; a file that libpcap cannot
// read, a link type other than Ethernet, or a truncated file are reported as such.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/bytes.hpp"

namespace vecat::replay {

struct CapturedFrame {
    std::size_t number = 0;     // in the file, from 1 (as Wireshark numbers them)
    std::uint64_t time_ns = 0;  // time stamp in the file
    std::vector<std::uint8_t> bytes;
};

struct Capture {
    std::vector<CapturedFrame> frames;  // the EtherCAT frames (commands), in file order
    std::size_t total = 0;              // frames in the file
    std::size_t other_protocol = 0;     // ... not EtherCAT, or EtherCAT frames that fail the frame checks
    std::string problem;                // empty, or why reading stopped early (truncated file, ...)
};

// Reads a pcap or pcapng file. Throws CaptureError when the file cannot be opened as a capture at all
// (missing, not a capture, a link type other than Ethernet); a file that breaks off later keeps the frames
// before the break and names the break in problem.
Capture read_capture(const std::string& path);
// The same from bytes in memory (the fuzz target), name used in messages.
Capture read_capture(ConstBytes file, const std::string& name = "<capture>");

class CaptureError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// A master's frame and the reply the capture holds for it.
struct Exchange {
    std::size_t request = 0;  // index into Capture::frames
    std::size_t reply = 0;
    bool request_recorded = true;  // false: the capture holds only the reply (some capture set-ups record
                                   // the returning frames only); the request is rebuilt from it
};

struct Pairing {
    std::vector<Exchange> exchanges;  // in the order the master sent the frames
    std::size_t unanswered = 0;       // master frames without a reply in the capture (lost on the line)
};

// A reply is the frame the ESCs sent back: the same datagrams (command, index, length) as a master frame
// before it, with bit 1 of the first source address byte set (every ESC sets it in the frames it forwards,
// ESC datasheet section I, "Frame processing": a real ESC returns 01:01:01:01:01:01 as 03:01:01:01:01:01).
Pairing pair_frames(const Capture& c);

}  // namespace vecat::replay
