// The replay of a capture against vecat: the master's frames of a real capture go to an emulated line in
// their recorded order and at their recorded times, and every reply datagram is held against the recorded
// one: the working counter always, the data of register and memory reads byte by byte (each difference
// judged by classify.hpp), the data of logical reads as process data.
//
// The line comes from a network file, or from the capture itself (recover.hpp): the slaves' SII images as
// the master read them, their ESC information registers and DL status.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "esc/segment.hpp"
#include "replay/capture.hpp"
#include "replay/classify.hpp"
#include "replay/recover.hpp"

namespace vecat::replay {

// One datagram whose reply differs from the recorded one.
struct Difference {
    std::size_t frame = 0;     // the recorded reply's frame number
    std::size_t datagram = 0;  // in the frame, from 0
    std::uint8_t command = 0;
    std::uint16_t adp = 0;
    std::uint16_t ado = 0;  // or the low half of a logical address
    std::uint16_t recorded_wkc = 0, replayed_wkc = 0;
    std::uint16_t first_byte = 0;  // register address of the first byte that differs (data differences)
    // Data from first_byte on (up to kShownBytes): as recorded, as vecat replied.
    static constexpr std::size_t kShownBytes = 8;
    std::vector<std::uint8_t> recorded, replayed;
    Verdict verdict = Verdict::Differs;
    bool working_counter = false;  // the working counter differs (else the data)
    bool no_reply = false;         // vecat returned no frame
};

// Per command and address: how often each outcome was seen.
struct Tally {
    std::size_t datagrams = 0;
    std::size_t wkc_differs = 0;
    std::size_t wkc_timing = 0;       // ... of which by timing
    std::size_t data_differs = 0;     // behaviour
    std::size_t data_excused = 0;     // time-dependent, counters, process data
    std::vector<std::size_t> frames;  // first few frames where something differs
};

struct ReplayReport {
    std::size_t exchanges = 0;
    std::size_t rebuilt_requests = 0;  // exchanges whose request the capture did not hold
    std::size_t unanswered = 0;        // master frames without a recorded reply (not replayed)
    std::size_t datagrams = 0;
    std::size_t wkc_same = 0;
    std::size_t reads = 0;  // register and memory reads with known request data
    std::size_t reads_same = 0;
    std::size_t reads_time = 0;     // differ only in time-dependent bytes
    std::size_t reads_counter = 0;  // ... in counters (and time-dependent bytes)
    std::size_t reads_padding = 0;  // ... in a mailbox read's bytes past its message (and the above)
    std::size_t reads_timing =
        0;                       // the real device gave vecat's data to the same read shortly before or after
    std::size_t wkc_timing = 0;  // working counters that differ the same way
    std::size_t process_reads = 0;  // logical reads
    std::size_t process_same = 0;
    std::vector<Difference> differences;                                 // the first max_differences
    std::map<std::pair<std::uint8_t, std::uint16_t>, Tally> by_address;  // (command, ado)

    double wkc_percent() const;
    // Register and memory reads whose data is the recorded one, or differs only where the values depend on
    // time, counters or the device's speed (timing).
    double data_percent() const;
};

struct ReplayOptions {
    std::size_t max_differences = 200;
    std::uint64_t tick_ns = 250'000;  // the shortest time between two firmware runs without a frame
    // How far (in exchanges, and in time) the same read is looked for when judging a difference as timing.
    std::size_t timing_exchanges = 64;
    std::uint64_t timing_ns = 500'000'000;
};

ReplayReport replay(const Capture& capture, const Pairing& pairing, esc::Segment& line,
                    const ReplayOptions& options = {});

// The line a capture was taken on, rebuilt from it (recover_line): one slave per position, made from the
// SII image the master read (a slave whose SII was not read gets a bare device, named in notes), with the
// ESC information registers it reported and the tree its DL status gives.
std::unique_ptr<esc::Segment> build_recovered_line(const RecoveredLine& line,
                                                   std::vector<std::string>& notes);

// The SII image of a recovered slave: the words the capture holds, 0xFFFF elsewhere (an erased EEPROM).
std::vector<std::uint8_t> recovered_sii_image(const RecoveredSlave& s);

// The report as text: figures, then the differences per command and address with frame numbers.
std::string format_report(const ReplayReport& r);

}  // namespace vecat::replay
