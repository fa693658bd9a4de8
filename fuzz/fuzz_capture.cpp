// Fuzz target: the capture reader and the replay (replay::read_capture through libpcap, pair_frames,
// recover_line, build_recovered_line, replay). Input: the bytes of a pcap or pcapng file.
// Invariants: a file is read or refused with a CaptureError naming it; nothing else is thrown. Every exchange
// points at frames of the capture, its reply after (or at) its request; the replay compares each recorded
// reply datagram once, and its figures stay within the counts.
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "replay/replay.hpp"

using namespace vecat;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    replay::Capture c;
    try {
        c = replay::read_capture(ConstBytes(data, size), "fuzz.pcapng");
    } catch (const replay::CaptureError& e) {
        VECAT_FUZZ_CHECK(std::string(e.what()).rfind("fuzz.pcapng: ", 0) == 0);
        return 0;
    }
    VECAT_FUZZ_CHECK(c.frames.size() + c.other_protocol == c.total);
    const replay::Pairing p = replay::pair_frames(c);
    for (const auto& e : p.exchanges) {
        VECAT_FUZZ_CHECK(e.request < c.frames.size() && e.reply < c.frames.size());
        VECAT_FUZZ_CHECK(e.reply >= e.request);
        VECAT_FUZZ_CHECK(e.request_recorded == (e.reply != e.request));
    }
    replay::RecoveredLine line = replay::recover_line(c, p);
    VECAT_FUZZ_CHECK(line.slaves.size() == line.slave_count &&
                     line.slave_count <= replay::kMaxRecoveredSlaves);
    if (line.slave_count > 16) return 0;  // a long line costs time, not coverage
    std::vector<std::string> notes;
    auto seg = replay::build_recovered_line(line, notes);
    VECAT_FUZZ_CHECK(seg->size() == line.slave_count);
    const replay::ReplayReport r = replay::replay(c, p, *seg);
    VECAT_FUZZ_CHECK(r.exchanges == p.exchanges.size());
    VECAT_FUZZ_CHECK(r.wkc_same <= r.datagrams);
    VECAT_FUZZ_CHECK(r.reads_same + r.reads_time + r.reads_counter + r.reads_timing <= r.reads);
    VECAT_FUZZ_CHECK(r.process_same <= r.process_reads);
    return 0;
}
