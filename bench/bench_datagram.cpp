// The datagram engine: cost of one frame through a segment of N drives in OP (Segment::process_frame, no
// network). The counter per_slave is the time per frame divided by the number of slaves.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <memory>
#include <vector>

#include "bench/drive_line.hpp"
#include "cia402/drive.hpp"
#include "master/master.hpp"
#include "protocol/registers.hpp"
#include "serve/in_process_link.hpp"

namespace {

using namespace vecat;

using Line = bench::DriveLine;

// A frame of datagrams (command, address, length), data zero unless copied in afterwards.
struct Frame {
    std::vector<std::uint8_t> bytes;  // the template
    std::vector<std::uint8_t> work;   // processed in place
    std::size_t len = 0;
    struct Dg {
        protocol::Command cmd;
        std::uint32_t address;
        std::size_t size;
    };
    explicit Frame(std::initializer_list<Dg> dgs) {
        std::size_t off = protocol::kEthHeaderSize + protocol::kEcatHeaderSize;
        bytes.assign(1600, 0);
        std::fill_n(bytes.begin(), 6, 0xFF);
        std::fill_n(bytes.begin() + 6, 6, 0x10);
        bytes[12] = 0x88;
        bytes[13] = 0xA4;
        std::size_t i = 0;
        for (const auto& d : dgs) {
            std::uint8_t* p = bytes.data() + off;
            p[0] = static_cast<std::uint8_t>(d.cmd);
            p[1] = static_cast<std::uint8_t>(i);
            st_le32(p + 2, d.address);
            st_le16(p + 6, static_cast<std::uint16_t>(d.size | (++i < dgs.size() ? 0x8000 : 0)));
            off += protocol::kDatagramHeaderSize + d.size + protocol::kWkcSize;
        }
        st_le16(bytes.data() + protocol::kEthHeaderSize,
                static_cast<std::uint16_t>((off - protocol::kEthHeaderSize - protocol::kEcatHeaderSize) |
                                           0x1000));
        len = std::max(off, protocol::kMinEthFrame);
        work = bytes;
    }
    std::uint8_t* data(std::size_t dg_offset) {
        return bytes.data() + protocol::kEthHeaderSize + protocol::kEcatHeaderSize +
               protocol::kDatagramHeaderSize + dg_offset;
    }
    bool run(esc::Segment& seg, std::uint64_t now) {
        std::memcpy(work.data(), bytes.data(), len);
        std::size_t l = len;
        return seg.process_frame(Bytes(work.data(), work.size()), l, now);
    }
};

const std::uint32_t kFrmwAddress =
    0x1001u | (static_cast<std::uint32_t>(protocol::addr(protocol::Reg::DcSystemTime)) << 16);

void per_slave(benchmark::State& state, std::size_t n) {
    state.counters["per_slave"] =
        benchmark::Counter(static_cast<double>(state.iterations() * n),
                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// FPRD of the AL status of the first slave: every slave compares the address.
void BM_Fprd(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    Line line(n);
    Frame f({{protocol::Command::FPRD, 0x1001u | (0x0130u << 16), 2}});
    for (auto _ : state)
        benchmark::DoNotOptimize(f.run(*line.seg, line.now));
    per_slave(state, n);
}
BENCHMARK(BM_Fprd)->Arg(1)->Arg(10)->Arg(100);

// LRW of 32 bytes at the start of the process image (the first slave's outputs and part of the next).
void BM_Lrw32(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    Line line(n);
    Frame f({{protocol::Command::LRW, 0x00010000, 32}});
    std::memcpy(f.data(0), line.m->outputs(0).data(),
                std::min<std::size_t>(32, line.m->process_image_size()));
    for (auto _ : state)
        benchmark::DoNotOptimize(f.run(*line.seg, line.now));
    per_slave(state, n);
}
BENCHMARK(BM_Lrw32)->Arg(1)->Arg(10)->Arg(100);

// The cyclic frames of a line: LRW over the whole image plus the FRMW of the reference clock in the first,
// in as many frames as the image needs, carrying the master's outputs.
std::vector<Frame> cyclic_frames(Line& line) {
    std::vector<Frame> frames;
    const std::size_t image = line.m->process_image_size();
    for (std::size_t off = 0; off < image; off += master::Master::kMaxLrwBytes) {
        const std::size_t k = std::min(image - off, master::Master::kMaxLrwBytes);
        const std::uint32_t laddr = 0x00010000u + static_cast<std::uint32_t>(off);
        if (off == 0)
            frames.emplace_back(
                Frame({{protocol::Command::LRW, laddr, k}, {protocol::Command::FRMW, kFrmwAddress, 8}}));
        else
            frames.emplace_back(Frame({{protocol::Command::LRW, laddr, k}}));
        std::memcpy(frames.back().data(0), line.m->outputs(0).data() + off, k);
    }
    return frames;
}

// The cyclic exchange: LRW over the whole image plus the FRMW of the reference clock, in as many frames as
// the image needs (100 drives: 4 frames). range(1) = 0: time stands still (the ESC engine and the firmware's
// process data exchange only); 1: 1 ms passes per cycle (also 4 servo periods of every drive). 512 drives
// (16 frames): the state the cycle touches no longer fits a core's L2 cache, and the time per slave grows
// (see bench/README.md, "Large networks").
void BM_CyclicLrwFrmw(benchmark::State& state) {
    const auto n = static_cast<std::size_t>(state.range(0));
    const bool advance = state.range(1) != 0;
    Line line(n);
    std::vector<Frame> frames = cyclic_frames(line);
    for (auto _ : state) {
        if (advance) line.now += 1'000'000;
        for (auto& f : frames)
            benchmark::DoNotOptimize(f.run(*line.seg, line.now));
    }
    per_slave(state, n);
    state.SetLabel(std::to_string(frames.size()) + " frame(s)" +
                   (advance ? ", 1 ms per cycle" : ", time frozen"));
}
BENCHMARK(BM_CyclicLrwFrmw)->ArgsProduct({{1, 10, 100, 512}, {0, 1}});

// The same cyclic frames (time frozen) as the serve loop handles them: the firmware of the slaves runs after
// the reply is sent (Segment::set_deferred_firmware). The time reported is the reply path, what the
// frame's round trip contains; the counter firmware_after_ns is the firmware's run after it, per cycle.
// Both are timed per iteration on the steady clock, less the cost of reading it (measured at the start).
void BM_CyclicReplyPath(benchmark::State& state) {
    using Clock = std::chrono::steady_clock;
    const auto n = static_cast<std::size_t>(state.range(0));
    Line line(n);
    line.seg->set_deferred_firmware(true);
    std::vector<Frame> frames = cyclic_frames(line);
    // The cost of one clock reading: the smallest of many empty intervals.
    double overhead = 1e9;
    for (int i = 0; i < 10000; ++i) {
        const auto a = Clock::now();
        const auto b = Clock::now();
        overhead = std::min(overhead, std::chrono::duration<double>(b - a).count());
    }
    double firmware = 0;
    for (auto _ : state) {
        double reply = 0;
        for (auto& f : frames) {
            const auto t0 = Clock::now();
            benchmark::DoNotOptimize(f.run(*line.seg, line.now));
            const auto t1 = Clock::now();
            line.seg->run_deferred_firmware();
            const auto t2 = Clock::now();
            reply += std::max(0.0, std::chrono::duration<double>(t1 - t0).count() - overhead);
            firmware += std::max(0.0, std::chrono::duration<double>(t2 - t1).count() - overhead);
        }
        state.SetIterationTime(reply);
    }
    per_slave(state, n);
    state.counters["firmware_after_ns"] = firmware * 1e9 / static_cast<double>(state.iterations());
    state.counters["clock_read_ns"] = overhead * 1e9;
    state.SetLabel(std::to_string(frames.size()) + " frame(s), time frozen, firmware after the reply");
}
BENCHMARK(BM_CyclicReplyPath)->Arg(1)->Arg(10)->Arg(100)->Arg(512)->UseManualTime();

}  // namespace
