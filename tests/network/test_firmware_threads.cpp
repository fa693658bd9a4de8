// The slaves' firmware on several threads (esc::FirmwareThreads, Segment::set_firmware_threads, vecat run
// --threads): every item of every batch runs once; slaves that share state form one group; and a network
// served with three threads answers the master byte for byte as with one, also with the firmware after each
// frame running beside the next frame (Segment::start_deferred_firmware).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "cia402/drive.hpp"
#include "common/bytes.hpp"
#include "device/device_description.hpp"
#include "esc/firmware_threads.hpp"
#include "esc/segment.hpp"
#include "network_support.hpp"
#include "protocol/cia402_objects.hpp"

namespace vecat::network {
namespace {

using protocol::AlState;

constexpr std::uint64_t kMs = 1'000'000;

struct Batch {
    std::vector<int> runs;
    std::atomic<std::uint64_t> spin_sink{0};
};

void count_item(void* context, std::size_t item) {
    auto& b = *static_cast<Batch*>(context);
    ++b.runs[item];  // items are distinct: no two threads touch one counter
    // A little work, so that the workers get items while the caller works too.
    std::uint64_t x = item;
    for (int i = 0; i < 200; ++i)
        x = x * 6364136223846793005ull + 1442695040888963407ull;
    b.spin_sink.fetch_add(x & 1, std::memory_order_relaxed);
}

TEST(FirmwareThreads, EveryItemOfEveryBatchRunsOnceAndTheWorkersTakePart) {
    esc::FirmwareThreads threads(3);
    ASSERT_EQ(threads.threads(), 3u);
    Batch b;
    std::size_t batches = 0;
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    // Batches of every size, back to back, so that a worker late for one batch meets the next (it must not
    // run an item of the next batch as one of the last). At least 20,000, and until the workers ran some.
    // Every other batch has up to 300 items: those are claimed several at a time (kChunksPerThread), with
    // a last chunk that is shorter.
    while (batches < 20'000 ||
           (threads.items_on_workers() == 0 && std::chrono::steady_clock::now() < until)) {
        const std::size_t count = batches % 2 == 0 ? batches % 41 : (batches * 37) % 301;
        b.runs.assign(count, 0);
        threads.run(count, &count_item, &b);
        for (std::size_t i = 0; i < count; ++i)
            ASSERT_EQ(b.runs[i], 1) << "item " << i << " of batch " << batches << " (" << count << " items)";
        ++batches;
    }
    EXPECT_GT(threads.items_on_workers(), 0u);
}

TEST(FirmwareThreads, ASleepingWorkerWakesUpForTheNextBatch) {
    esc::FirmwareThreads threads(2, 1'000'000);  // sleeps after 1 ms without a batch
    Batch b;
    b.runs.assign(40, 0);
    threads.run(40, &count_item, &b);
    std::this_thread::sleep_for(std::chrono::milliseconds(30));  // the worker is asleep by now
    const std::uint64_t before = threads.items_on_workers();
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (threads.items_on_workers() == before && std::chrono::steady_clock::now() < until) {
        b.runs.assign(40, 0);
        threads.run(40, &count_item, &b);
        ASSERT_EQ(std::count(b.runs.begin(), b.runs.end(), 1), 40);
    }
    EXPECT_GT(threads.items_on_workers(), before);
}

// A worker that stalls in the middle of its chunk (as when the scheduler preempts it) keeps the caller
// waiting for its items: run() returns with every item done, and the wait shows in the figures the soak
// reports (FirmwareThreads::long_waits, longest_wait_ns).
struct StallingBatch {
    std::thread::id caller;
    std::atomic<int> done{0};
    std::atomic<bool> stalled{false};
};

void stall_on_a_worker(void* context, std::size_t) {
    auto& b = *static_cast<StallingBatch*>(context);
    if (std::this_thread::get_id() != b.caller && !b.stalled.exchange(true))
        std::this_thread::sleep_for(std::chrono::milliseconds(30));
    b.done.fetch_add(1);
}

TEST(FirmwareThreads, AWorkerThatStallsKeepsTheCallerWaitingAndTheWaitIsCounted) {
    esc::FirmwareThreads threads(2, 1'000'000'000);  // the worker keeps spinning between batches
    StallingBatch b;
    b.caller = std::this_thread::get_id();
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    // Batches until the worker claimed an item (and so stalled in one of them).
    while (!b.stalled && std::chrono::steady_clock::now() < until) {
        b.done = 0;
        threads.run(64, &stall_on_a_worker, &b);
        ASSERT_EQ(b.done.load(), 64);  // run() returned with every item done
    }
    ASSERT_TRUE(b.stalled) << "the worker never took an item";
    EXPECT_GE(threads.long_waits(), 1u);
    EXPECT_GE(threads.longest_wait_ns(), 20'000'000u);  // (the caller ran its own items first)
}

TEST(FirmwareThreads, OneThreadRunsEverythingOnTheCaller) {
    esc::FirmwareThreads threads(1);
    Batch b;
    b.runs.assign(10, 0);
    threads.run(10, &count_item, &b);
    EXPECT_EQ(std::count(b.runs.begin(), b.runs.end(), 1), 10);
    EXPECT_EQ(threads.items_on_workers(), 0u);
}

// Six drives (the first two coupled by TWINsync), two output terminals, three input terminals (two wired to
// the first output terminal, one to a signal), a drive whose touch probe input is wired to the second
// output terminal.
constexpr const char* kNetwork = R"(
devices:
  - {name: valves, device: digital-out, channels: 8}
  - {name: lamps, device: digital-out, channels: 8}
  - name: sensors
    device: digital-in
    channels: 8
    inputs:
      0: {wire: valves:0}
  - name: more
    device: digital-in
    channels: 8
    inputs:
      1: {wire: valves:1}
  - name: clock
    device: digital-in
    channels: 8
    inputs:
      0: {signal: square, period_ms: 3}
  - {name: a1, device: drive}
  - {name: a2, device: drive}
  - {name: a3, device: drive}
  - name: a4
    device: drive
    inputs:
      0: {wire: lamps:2}
  - {name: a5, device: drive}
  - {name: a6, device: drive}
)";

TEST(FirmwareGroups, SlavesThatShareStateRunInOneGroup) {
    test::ServedNetwork s{kNetwork};
    esc::Segment& seg = *s.built.segment;
    // valves + sensors + more; lamps + a4; the others alone.
    EXPECT_EQ(seg.firmware_group(0), seg.firmware_group(2));
    EXPECT_EQ(seg.firmware_group(0), seg.firmware_group(3));
    EXPECT_EQ(seg.firmware_group(1), seg.firmware_group(8));
    EXPECT_NE(seg.firmware_group(0), seg.firmware_group(1));
    EXPECT_NE(seg.firmware_group(4), seg.firmware_group(0));
    EXPECT_NE(seg.firmware_group(5), seg.firmware_group(6));
    EXPECT_EQ(seg.firmware_groups(), 8u);
    // A wire from output PDO entries of ESI devices (examples/networks/modular.yaml: io, io-defaults, rack,
    // levels wired to io and rack).
    test::ServedNetwork modular{std::string(VECAT_SOURCE_DIR) + "/examples/networks/modular.yaml",
                                test::ServedNetwork::From::File};
    esc::Segment& m = *modular.built.segment;
    ASSERT_EQ(m.size(), 4u);
    EXPECT_EQ(m.firmware_group(0), m.firmware_group(3));
    EXPECT_EQ(m.firmware_group(2), m.firmware_group(3));
    EXPECT_NE(m.firmware_group(1), m.firmware_group(3));
    EXPECT_EQ(m.firmware_groups(), 2u);
    // Drives coupled by TWINsync step each other: one group.
    auto line = cia402::make_drive_segment(device::default_drive(), 4);
    EXPECT_EQ(line->firmware_group(0), line->firmware_group(1));
    EXPECT_NE(line->firmware_group(1), line->firmware_group(2));
    EXPECT_EQ(line->firmware_groups(), 3u);
}

// How the second copy of a network runs its firmware (answers_as_with_one_thread).
enum class Threaded {
    Batches,  // each batch of runs on three threads, the caller waiting for it
    Beside,   // the firmware after each frame on three threads beside the next frame (as the serve loop)
    // The same, handed over after every second frame only: a batch then takes the firmware of the frames
    // deferred since the last, each at its frame's time
    SeveralFramesBeside,
};

// The same network twice, one copy with three firmware threads: the master reads the same bytes from both
// in every cycle, with every drive moving in cyclic synchronous position mode and the wired outputs
// toggling; and the workers did take part. frame_gap_ns: the time between the frames of a cycle.
void answers_as_with_one_thread(const std::string& network, Threaded how, std::uint64_t frame_gap_ns = 0) {
    constexpr std::uint64_t kStart = 1'000'000'000;
    test::ServedNetwork plain{network, test::ServedNetwork::From::Text, kStart};
    test::ServedNetwork threaded{network, test::ServedNetwork::From::Text, kStart};
    esc::FirmwareThreads threads(3);
    esc::Segment& seg = *threaded.built.segment;
    seg.set_firmware_threads(&threads);
    for (test::ServedNetwork* n : {&plain, &threaded})
        ASSERT_TRUE(n->master.startup(AlState::Op));
    ASSERT_EQ(plain.link.now_ns(), threaded.link.now_ns()) << "both start-ups took the same time";
    // Runs are counted from here on, over the cycles that both copies run alike.
    const std::uint64_t started[2] = {plain.built.segment->counters().firmware_runs,
                                      seg.counters().firmware_runs};
    if (how != Threaded::Batches) {
        seg.set_deferred_firmware(true);
        threaded.link.set_firmware_beside(how == Threaded::Beside ? 1 : 2);
    }
    for (test::ServedNetwork* n : {&plain, &threaded})
        n->link.set_time_step(frame_gap_ns);
    const std::size_t n_slaves = plain.master.slaves().size();
    const test::CspOutputs csp(plain.master.slaves()[5]);  // every drive has the default mapping
    ASSERT_TRUE(csp.valid());
    std::size_t differences = 0;
    int wired_ones = 0;  // cycles in which the wired input read 1
    int cycles = 0;
    const std::uint64_t on_workers_before = threads.items_on_workers();
    // 600 cycles; more until the worker took part (on a loaded machine a spinning worker may get no CPU for
    // a while, and the caller then runs every group itself).
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    for (int i = 0; i < 600 || (threads.items_on_workers() == on_workers_before &&
                                std::chrono::steady_clock::now() < until);
         ++i) {
        const std::uint16_t control = i < 5 ? 0x06 : i < 10 ? 0x07 : 0x0F;
        const std::uint64_t t = plain.link.now_ns() + kMs;
        for (test::ServedNetwork* n : {&plain, &threaded}) {
            n->master.outputs(0)[0] = static_cast<std::uint8_t>(i);      // valves
            n->master.outputs(1)[0] = static_cast<std::uint8_t>(i / 3);  // lamps
            for (std::size_t d = 5; d < n_slaves; ++d) {
                const std::int32_t position = i < 20 ? 0 : (i - 20) * 1'000 * static_cast<std::int32_t>(d);
                csp.write(n->master, d, control, position);
            }
            // Now and then a tick between frames (a serve loop's), at the same time in both.
            if (i % 7 == 3) n->built.segment->tick(t - 400'000);
            n->link.set_time(t);
            ASSERT_EQ(n->master.exchange_process_data().value_or(0), n->master.expected_wkc());
        }
        // (As the serve loop does when no frame comes.)
        seg.run_deferred_firmware();
        differences += test::differing_inputs(plain.master, threaded.master);
        // The input "sensors" channel 0 is wired to the output "valves" channel 0 (bit 0 of i).
        wired_ones += threaded.master.inputs(2)[0] & 1u;
        ++cycles;
    }
    EXPECT_EQ(differences, 0u);
    // The drives did move, the wires did carry, and the workers ran some of the groups.
    auto* drive = dynamic_cast<cia402::Drive*>(&seg.slave(10).app());
    ASSERT_NE(drive, nullptr);
    EXPECT_GT(drive->position_actual(), 1'000'000);
    EXPECT_GT(wired_ones, cycles / 3);  // the output toggles every cycle: about half of them
    EXPECT_LT(wired_ones, 2 * cycles / 3);
    EXPECT_GT(threads.items_on_workers(), on_workers_before);
    EXPECT_EQ(plain.built.segment->counters().firmware_runs - started[0],
              seg.counters().firmware_runs - started[1])
        << "start-ups: " << started[0] << " and " << started[1] << " runs";
    // Frames were answered while the firmware of the frames before them ran: several in every cycle, at least
    // one when it is handed over after every second frame; and then batches of several frames.
    if (how == Threaded::Beside) {
        EXPECT_GT(seg.counters().beside_firmware, static_cast<std::uint64_t>(cycles));
    }
    if (how == Threaded::SeveralFramesBeside) {
        EXPECT_GE(seg.counters().beside_firmware, static_cast<std::uint64_t>(cycles));
        EXPECT_GT(seg.counters().background_frames, seg.counters().background_batches);
    }
}

TEST(FirmwareThreads, ANetworkAnswersAsWithOneThread) {
    answers_as_with_one_thread(kNetwork, Threaded::Batches);
}

// kNetwork and 300 more drives: the process data takes several frames a cycle, the outputs first, each
// frame for other drives than the one before. The firmware after each frame runs on the workers while the
// next frame is answered, at the frame's time (frames 20 us apart), and every answer is the same as with one
// thread and the firmware run after each frame.
TEST(FirmwareThreads, FirmwareBesideTheNextFrameAnswersAsAfterEachFrame) {
    std::string network = kNetwork;
    for (int i = 7; i < 307; ++i)
        network += "  - {name: a" + std::to_string(i) + ", device: drive}\n";
    answers_as_with_one_thread(network, Threaded::Beside, 20'000);
}

// The same, the firmware handed over after every second frame only: each batch runs the firmware of the
// frames deferred since the last (as when the serve loop finds the workers still at the batch before), each
// at its frame's time. The frames come 90 us apart, so that a servo period often falls between two of
// them: run at the last frame's time instead, the drives answer otherwise (tried: 43,569 differences).
TEST(FirmwareThreads, FirmwareOfSeveralFramesBesideTheNextFrameAnswersAsAfterEachFrame) {
    std::string network = kNetwork;
    for (int i = 7; i < 307; ++i)
        network += "  - {name: a" + std::to_string(i) + ", device: drive}\n";
    answers_as_with_one_thread(network, Threaded::SeveralFramesBeside, 90'000);
}

}  // namespace
}  // namespace vecat::network
