// The cyclic path (receive, process, send) allocates no memory and takes no lock: every operator new is
// counted (allocation_counter.cpp), and so is every mutex, condition variable, semaphore and futex call
// (lock_counter.cpp).
#include <gtest/gtest.h>
#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <mutex>
#include <new>
#include <shared_mutex>
#include <thread>

#include "allocation_counter.hpp"
#include "cia402/drive.hpp"
#include "coe/coe_application.hpp"
#include "esc/firmware_threads.hpp"
#include "lock_counter.hpp"
#include "net/netns.hpp"
#include "net/raw_socket.hpp"
#include "network/build.hpp"
#include "report/master_checks.hpp"
#include "serve/server.hpp"
#include "telemetry/sampler.hpp"
#include "test_support.hpp"

using namespace vecat;
using namespace vecat::test;

static bool g_netns = false;

// The lock counter sees what the standard library's locks end in (else the tests below prove nothing).
TEST(NoLock, CounterSeesTheStandardLocks) {
    std::mutex m;
    std::shared_mutex sm;
    std::condition_variable cv;
    auto before = test::lock_calls();
    { std::lock_guard g(m); }
    EXPECT_GE(test::lock_calls() - before, 1u);
    before = test::lock_calls();
    { std::shared_lock g(sm); }
    EXPECT_GE(test::lock_calls() - before, 1u);
    before = test::lock_calls();
    {
        std::unique_lock g(m);
        cv.wait_for(g, std::chrono::microseconds(1));
    }
    EXPECT_GE(test::lock_calls() - before, 2u);
    // What std::atomic::wait/notify and std::latch end in when they have to wait.
    int word = 0;
    before = test::lock_calls();
    syscall(SYS_futex, &word, FUTEX_WAKE_PRIVATE, 1, nullptr, nullptr, 0);
    EXPECT_EQ(test::lock_calls() - before, 1u);
}

TEST(NoAllocation, SegmentProcessingOfCyclicFrames) {
    Bench b(4);
    ASSERT_TRUE(b.master.startup(protocol::AlState::Op));
    // A typical cyclic frame: LRW over the process image + FRMW of the reference clock's system time.
    std::vector<std::uint8_t> img(4 * (16 + 28), 0);
    std::uint8_t t[8] = {};
    master::DatagramRequest dg[2] = {{protocol::Command::LRW, 0x00010000, Bytes(img.data(), img.size())},
                                     {protocol::Command::FRMW, 0x09101001, Bytes(t, 8)}};
    for (int i = 0; i < 10; ++i)
        ASSERT_TRUE(b.master.transact_frame(dg));
    const auto before = test::allocations();
    const auto locks_before = test::lock_calls();
    for (int i = 0; i < 10000; ++i) {
        b.link.set_time(2'000'000'000ull + static_cast<std::uint64_t>(i) * 1'000'000);
        ASSERT_TRUE(b.master.transact_frame(dg));
        ASSERT_EQ(dg[0].wkc, 12);
    }
    EXPECT_EQ(test::allocations() - before, 0u);
    EXPECT_EQ(test::lock_calls() - locks_before, 0u);
}

// A tree of mixed devices (network file: coupler, I/O terminals on its E-bus with signals and wires on their
// inputs, one of them from an output PDO entry of a modular device of an ESI file, a junction with drives and
// terminals on its ports), watched by the report on the master: cycles of process data through it allocate
// nothing and take no lock.
TEST(NoAllocation, MixedNetworkTreeWithTheReportOnTheMaster) {
    auto built = network::build_network(network::parse_network(R"(
devices:
  - name: coupler
    device: coupler
  - name: di
    device: digital-in
    upstream: coupler:3
    inputs:
      0: {signal: square, period_ms: 4}
      1: {wire: do:3}
  - name: ai
    device: analog-in
    inputs:
      0: {signal: sine, period_ms: 20, amplitude: 1000}
      1: {wire: ao:0}
      2: {wire: mod:0x7000:0}
  - name: ao
    device: analog-out
  - name: mod
    esi: )" VECAT_SOURCE_DIR R"(/examples/networks/modular-io.xml
    type: VECAT-MOD-3
  - name: junction
    device: junction
    upstream: coupler:1
  - name: d1
    device: drive
    upstream: junction:3
  - name: do
    device: digital-out
    upstream: junction:1
  - name: d2
    device: drive
    upstream: junction:2
)"),
                                        "tree");
    net::InProcessLink link(*built.segment);
    report::MasterChecks checks(*built.segment);
    // The telemetry's sampler after each frame, as the serve loop calls it: I/O samples of the terminals,
    // axis samples of the drives (the queue fills up: a full queue is no allocation either).
    auto queue = std::make_unique<telemetry::TelemetryQueue>();
    telemetry::Sampler sampler(*built.segment, *queue);
    link.set_observer(&checks);
    master::Master m(link);
    link.set_time(1'000'000'000);
    ASSERT_TRUE(m.startup(protocol::AlState::Op));
    for (int i = 0; i < 10; ++i)
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
    const auto before = test::allocations();
    const auto locks_before = test::lock_calls();
    for (int i = 0; i < 10000; ++i) {
        const std::uint64_t t = 1'001'000'000ull + static_cast<std::uint64_t>(i) * 1'000'000;  // 1 ms cycles
        link.set_time(t);
        built.segment->tick(t);
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
        sampler.on_frame(t);
    }
    EXPECT_EQ(test::allocations() - before, 0u);
    EXPECT_EQ(test::lock_calls() - locks_before, 0u);
    EXPECT_GT(sampler.stats().io_samples, 0u);
    EXPECT_TRUE(checks.findings().empty()) << report::summary(checks);
}

// The drive's servo steps in every mode (profile planning, homing, interpolation, mechanics) allocate
// nothing either: CSP, PP with new set-points, PV, CST and homing through process data in OP.
TEST(NoAllocation, DriveMovingInEveryMode) {
    Bench b(2, {}, device::default_drive(), &cia402::make_drive_segment);
    ASSERT_TRUE(b.master.startup(protocol::AlState::Op));
    auto run = [&](int cycles, std::int8_t mode, std::uint16_t cw, std::int32_t pos, std::int32_t vel) {
        for (int i = 0; i < cycles; ++i) {
            for (std::size_t s = 0; s < 2; ++s) {
                auto o = b.master.outputs(s);
                st_le16(o.data(), cw);
                o[2] = static_cast<std::uint8_t>(mode);
                st_le32(o.data() + 4, static_cast<std::uint32_t>(pos + i * 1000));
                st_le32(o.data() + 8, static_cast<std::uint32_t>(vel));
                st_le16(o.data() + 12, 50);
            }
            ASSERT_EQ(b.master.exchange_process_data().value_or(0), b.master.expected_wkc());
            b.advance(1'000'000);
        }
    };
    auto all_modes = [&] {
        run(3, 8, 0x06, 0, 0);
        run(3, 8, 0x07, 0, 0);
        run(200, 8, 0x0F, 0, 0);        // CSP ramp
        run(50, 1, 0x1F, 300'000, 0);   // PP new set-point (bit 4 high)
        run(50, 1, 0x0F, 300'000, 0);   // PP moving
        run(50, 1, 0x3F, -200'000, 0);  // PP change immediately
        run(100, 3, 0x0F, 0, 200'000);  // PV
        run(50, 9, 0x0F, 0, -100'000);  // CSV
        run(50, 10, 0x0F, 0, 0);        // CST
        run(5, 6, 0x0F, 0, 0);          // HM: method 35 (default) ...
        run(50, 6, 0x1F, 0, 0);         // ... started
        run(20, 3, 0x0B, 0, 0);         // quick stop
        run(5, 3, 0x00, 0, 0);
    };
    all_modes();  // the first pass may set up what it needs
    const auto before = test::allocations();
    const auto locks_before = test::lock_calls();
    all_modes();
    EXPECT_EQ(test::allocations() - before, 0u);
    EXPECT_EQ(test::lock_calls() - locks_before, 0u);
}

// The serve loop and the master's socket, blocking and busy-polling, with enough drives that the process
// data needs two frames per cycle.
// threads > 1: the firmware on that many threads (esc::FirmwareThreads), whose worker spins through the test
// (its sleep, a futex, comes only after a pause in the batches: see firmware_threads.hpp).
// gap_us > 0: the master pauses that long after every 20th cycle, longer than the loop's longest catch-up
// period (ServeOptions::kMaxCatchUpUs), so that it ticks between cycles (in parts on a line of 40: see
// kTickPart in server.cpp), and a frame may come while it does.
// drives: the line's length; with more than 40 the outputs take frames of their own, and with threads the
// firmware after such a frame runs beside the next one (Segment::start_deferred_firmware).
void serve_loop_allocates_nothing(bool busy, const char* m_if, const char* s_if, bool ring = false,
                                  unsigned threads = 1, unsigned gap_us = 0, std::size_t drives = 40) {
    std::string why;
    ASSERT_TRUE(net::create_veth_pair(m_if, s_if, &why)) << why;
    auto seg = cia402::make_drive_segment(device::default_drive(), drives);
    net::RawSocket ss(s_if), ms(m_if);
    ms.set_busy_poll(busy);
    if (ring) {
        ASSERT_TRUE(ss.enable_rx_ring(&why)) << why;
        ASSERT_TRUE(ms.enable_rx_ring(&why)) << why;
    }
    std::atomic<bool> stop{false};
    net::ServeOptions opt;
    opt.busy_poll = busy;
    net::ServeCounters count;
    opt.counters = &count;
    esc::FirmwareThreads firmware(threads, 600'000'000'000);
    if (threads > 1) opt.firmware_threads = &firmware;
    std::thread srv([&] { net::serve(*seg, ss, opt, stop); });
    struct Join {
        std::atomic<bool>& stop;
        std::thread& t;
        ~Join() {
            stop = true;
            if (t.joinable()) t.join();
        }
    } join{stop, srv};
    master::MasterOptions mo;
    // Spinning threads get no wake-up preference from the scheduler: on a loaded machine a reply may take
    // tens of milliseconds. This test is about allocations, not latency.
    mo.reply_timeout_us = 300'000;
    mo.dc.enable = true;
    mo.dc.sync0_cycle_ns = 0;
    mo.dc.static_drift_frames = 100;
    master::Master m(ms, mo);
    const bool up = m.startup(protocol::AlState::Op, &why);
    for (std::size_t i = 0; i < m.last_states().size() && !up; ++i)
        why +=
            " " + std::to_string(m.last_states()[i].status) + "/" + std::to_string(m.last_states()[i].code);
    ASSERT_TRUE(up) << why;
    const std::size_t cycle_frames = m.process_data_frames();
    ASSERT_EQ(cycle_frames > 2, drives > 40);
    for (int i = 0; i < 50; ++i)
        m.exchange_process_data();
    const auto before = test::allocations();
    const auto locks_before = test::lock_calls();
    const std::uint64_t frames_before = count.frames.load(), wakeups_before = count.wakeups.load(),
                        ticks_before = count.ticks.load();
    const std::uint64_t on_workers_before = firmware.items_on_workers();
    const std::uint64_t beside_before = seg->counters().beside_firmware;
    int ok = 0;
    int cycles = 0;
    // 1,000 cycles; with firmware threads, more until the worker took part (on a loaded machine a spinning
    // worker may get no CPU for a while; the serve loop's thread then runs every group itself).
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (cycles < 1000 || (threads > 1 && firmware.items_on_workers() == on_workers_before &&
                             std::chrono::steady_clock::now() < until)) {
        ok += m.exchange_process_data().value_or(0) == m.expected_wkc();
        ++cycles;
        if (gap_us && cycles % 20 == 0) std::this_thread::sleep_for(std::chrono::microseconds(gap_us));
    }
    const auto allocs = test::allocations() - before;
    const auto locks = test::lock_calls() - locks_before;
    // The live counters saw every frame of the cycles (each reply came back, so each was processed). How
    // many passes waited depends on the timing: a frame that was already there when the reply before it went
    // out (the second of a cycle, or the next cycle's first) takes a pass that does not wait.
    const auto frames = count.frames.load() - frames_before;
    EXPECT_EQ(frames, cycle_frames * static_cast<unsigned>(cycles));
    EXPECT_GT(count.wakeups.load(), wakeups_before);
    EXPECT_EQ(ok, cycles);
    EXPECT_EQ(allocs, 0u);
    // Both threads count: the master's and the serve loop's (and the firmware's worker).
    EXPECT_EQ(locks, 0u);
    // Each frame writes the outputs of 20 drives: a batch of runs after it, for the worker too.
    if (threads > 1) {
        EXPECT_GT(firmware.items_on_workers(), on_workers_before);
    }
    if (gap_us) {
        EXPECT_GT(count.ticks.load(), ticks_before);
    }
    // (Read after the serve loop stopped: its thread writes the segment's counters.)
    stop = true;
    srv.join();
    if (threads > 1 && drives > 40) {
        // Frames waiting when the reply before them went out were answered beside that frame's firmware.
        EXPECT_GT(seg->counters().beside_firmware, beside_before);
    }
}

TEST(NoAllocation, RawSocketServeLoop) {
    if (!g_netns) GTEST_SKIP() << "needs root for a private network namespace";
    serve_loop_allocates_nothing(false, "na-m", "na-s");
}

TEST(NoAllocation, RawSocketServeLoopWithFirmwareThreads) {
    if (!g_netns) GTEST_SKIP() << "needs root for a private network namespace";
    serve_loop_allocates_nothing(false, "na-m4", "na-s4", false, 2);
}

// 200 drives: five frames of outputs, and the firmware after each on the worker while the next is answered.
TEST(NoAllocation, RawSocketServeLoopWithFirmwareBesideTheFrames) {
    if (!g_netns) GTEST_SKIP() << "needs root for a private network namespace";
    serve_loop_allocates_nothing(false, "nf-m", "nf-s", false, 2, 0, 200);
}

// Ticks between the cycles: the loop runs them in parts and looks at its socket between parts.
TEST(NoAllocation, RawSocketServeLoopTickingBetweenCycles) {
    if (!g_netns) GTEST_SKIP() << "needs root for a private network namespace";
    serve_loop_allocates_nothing(false, "nt-m", "nt-s", false, 2, 12'000);
}

TEST(NoAllocation, RawSocketServeLoopBusyPoll) {
    if (!g_netns) GTEST_SKIP() << "needs root for a private network namespace";
    serve_loop_allocates_nothing(true, "nb-m", "nb-s");
}

// The same through PACKET_MMAP receive rings on both ends (which also shows that the ring delivers every
// reply: 1000 cycles with the right working counter, DC start-up included).
TEST(NoAllocation, RawSocketServeLoopWithReceiveRings) {
    if (!g_netns) GTEST_SKIP() << "needs root for a private network namespace";
    serve_loop_allocates_nothing(false, "nr-m", "nr-s", true);
}

TEST(NoAllocation, RawSocketServeLoopBusyPollWithReceiveRings) {
    if (!g_netns) GTEST_SKIP() << "needs root for a private network namespace";
    serve_loop_allocates_nothing(true, "nq-m", "nq-s", true);
}

int main(int argc, char** argv) {
    g_netns = net::enter_private_netns();
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
