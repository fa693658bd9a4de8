// When the slaves' firmware runs around frames (Segment: firmware when it is needed). A frame reads a slave
// only after its firmware has caught up; a slave runs after a frame only if the frame gave its firmware
// work (Esc::take_firmware_work); a slave that no frame reads still runs within its lag bound. Counted with
// SegmentCounters::firmware_runs on a network of one input terminal, one output terminal and one drive.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "cia402/drive.hpp"
#include "common/bytes.hpp"
#include "device/device_description.hpp"
#include "esc/segment.hpp"
#include "network_support.hpp"
#include "protocol/cia402_objects.hpp"
#include "protocol/frame.hpp"
#include "protocol/registers.hpp"
#include "serve/in_process_link.hpp"

namespace vecat::network {
namespace {

using protocol::AlState;
using protocol::Command;
using protocol::Reg;

constexpr std::uint64_t kMs = 1'000'000;

constexpr const char* kNetwork = R"(
devices:
  - {name: in, device: digital-in, channels: 8}
  - {name: out, device: digital-out, channels: 8}
  - {name: axis, device: drive}
)";

struct Cycling : ::testing::Test {
    test::ServedNetwork s{kNetwork, test::ServedNetwork::From::Text, 1'000'000'000};
    esc::Segment& seg() { return *s.built.segment; }
    std::uint64_t runs() { return seg().counters().firmware_runs; }
    void SetUp() override {
        ASSERT_TRUE(s.master.startup(AlState::Op));
        // A few cycles so that every slave is in its steady state.
        for (int i = 0; i < 3; ++i)
            cycle();
    }
    void cycle() {
        s.link.set_time(s.link.now_ns() + kMs);
        ASSERT_EQ(s.master.exchange_process_data().value_or(0), s.master.expected_wkc());
    }
};

TEST_F(Cycling, ACycleRunsEachSlaveOnlyForWhatItsProcessDataNeed) {
    const std::uint64_t before = runs();
    cycle();
    // The input terminal catches up before the frame reads it and has nothing to do after; the output
    // terminal is not read, and takes its outputs after the frame; the drive does both.
    EXPECT_EQ(runs() - before, 4u);
    // A second frame within the local cycle finds every slave it reads current: only the written ones run.
    const std::uint64_t again = runs();
    ASSERT_EQ(s.master.exchange_process_data().value_or(0), s.master.expected_wkc());
    EXPECT_EQ(runs() - again, 2u);
}

TEST_F(Cycling, TheSystemTimeFrmwAndTheReceiveTimeLatchGiveTheFirmwareNoWork) {
    s.link.set_time(s.link.now_ns() + 10'000);  // within the local cycle: no slave is due for its own cycle
    const std::uint64_t before = runs();
    std::array<std::uint8_t, 8> time{};
    std::array<std::uint8_t, 4> latch{};
    const auto ref = s.master.slaves().front().station;
    master::DatagramRequest dg[2] = {
        {Command::BWR, protocol::datagram::address(0, protocol::addr(Reg::DcRecvTimePort0)),
         Bytes(latch.data(), 4)},
        {Command::FRMW, protocol::datagram::address(ref, protocol::addr(Reg::DcSystemTime)),
         Bytes(time.data(), 8)}};
    ASSERT_TRUE(s.master.transact_frame(dg));
    EXPECT_EQ(dg[0].wkc, 3);
    EXPECT_EQ(dg[1].wkc, 3);
    EXPECT_EQ(runs(), before);
    // A register the firmware keeps (AL status) is read after the firmware caught up, and a write that
    // is work for the firmware (AL control) makes it run after the frame.
    s.link.set_time(s.link.now_ns() + kMs);
    const std::uint64_t read_before = runs();
    EXPECT_EQ(s.master.read_al_status(ref).state(), AlState::Op);
    EXPECT_EQ(runs() - read_before, 1u);
    const std::uint64_t write_before = runs();
    ASSERT_TRUE(
        s.master.write16(ref, protocol::addr(Reg::AlControl), static_cast<std::uint16_t>(AlState::Op)));
    EXPECT_EQ(runs() - write_before, 1u);
}

TEST_F(Cycling, ASlaveThatNoFrameReadsStillRunsWithinItsLagBound) {
    // After a run of every slave, the segment wants the firmware again at the latest after the lag bound,
    // though no slave of this network has a deadline of its own that soon.
    const std::uint64_t now = s.link.now_ns() + kMs;
    s.link.set_time(now);
    seg().tick(now);
    EXPECT_LE(seg().next_firmware_ns(), now + 16 * seg().local_cycle_ns());
    EXPECT_GT(seg().next_firmware_ns(), now);
}

TEST_F(Cycling, AHaltWithoutChangeLeavesTheSlavesSchedulesAlone) {
    // The fault injector states every slave's halt each time a fault starts or ends: a slave whose halt
    // does not change keeps its deadlines (a reset would run every slave of a large line at the next frame).
    const std::uint64_t now = s.link.now_ns() + kMs;
    s.link.set_time(now);
    seg().tick(now);
    const std::uint64_t next = seg().next_firmware_ns();
    ASSERT_GT(next, now);
    for (std::size_t k = 0; k < seg().size(); ++k)
        seg().set_firmware_halted(k, false);
    EXPECT_EQ(seg().next_firmware_ns(), next);
    // A halt that changes starts the slave's schedule anew: it runs (only its ESC) at once.
    seg().set_firmware_halted(1, true);
    EXPECT_LE(seg().next_firmware_ns(), now);
    seg().tick(now);
    seg().set_firmware_halted(1, false);
    EXPECT_LE(seg().next_firmware_ns(), now);
    cycle();
}

TEST_F(Cycling, AFrameReadsEveryServoPeriodUpToItsOwnTime) {
    // The drive says when its next servo period is due (Application::next_cycle_ns). A frame at that time,
    // even less than a local cycle after the drive's last run, finds the period stepped.
    auto* drive = dynamic_cast<cia402::Drive*>(&seg().slave(2).app());
    ASSERT_NE(drive, nullptr);
    const std::uint64_t next = drive->next_cycle_ns();
    // The drive's firmware last runs 100 us before that (a write of AL control gives it work).
    s.link.set_time(next - 100'000);
    ASSERT_TRUE(s.master.write16(s.master.slaves()[2].station, protocol::addr(Reg::AlControl),
                                 static_cast<std::uint16_t>(AlState::Op)));
    ASSERT_LT(drive->simulated_time_ns(), next);
    // A read of AL status (which gives the firmware no work after it) at that time.
    s.link.set_time(next);
    EXPECT_EQ(s.master.read_al_status(s.master.slaves()[2].station).state(), AlState::Op);
    EXPECT_EQ(drive->simulated_time_ns(), next);
}

// Two copies of one network, the firmware of one of them also run between frames (a server's catch-up
// ticks, 600 us and 150 us before each frame): the master reads the same bytes from both in every cycle,
// with the drive moving in cyclic synchronous position mode. When the firmware runs does not change what
// a frame reads, only where the work is done.
TEST(FirmwareBetweenFrames, TheMasterReadsTheSameAsWithoutIt) {
    constexpr std::uint64_t kStart = 1'000'000'000;
    test::ServedNetwork plain{kNetwork, test::ServedNetwork::From::Text, kStart};
    test::ServedNetwork ticked{kNetwork, test::ServedNetwork::From::Text, kStart};
    for (test::ServedNetwork* n : {&plain, &ticked})
        ASSERT_TRUE(n->master.startup(AlState::Op));
    const test::CspOutputs csp(plain.master.slaves()[2]);
    ASSERT_TRUE(csp.valid());
    ASSERT_EQ(plain.link.now_ns(), ticked.link.now_ns()) << "both start-ups took the same time";
    std::int32_t position = 0;
    std::size_t differences = 0;
    std::uint64_t in_frames[2] = {0, 0};  // firmware runs while the frames were processed
    for (int i = 0; i < 400; ++i) {
        const std::uint16_t control = i < 5 ? 0x06 : i < 10 ? 0x07 : 0x0F;
        if (i >= 20) position += 2'000;
        const std::uint64_t t = plain.link.now_ns() + kMs;
        for (test::ServedNetwork* n : {&plain, &ticked}) {
            csp.write(n->master, 2, control, position);
            if (n == &ticked) {
                n->built.segment->tick(t - 600'000);
                n->built.segment->tick(t - 150'000);
            }
            n->link.set_time(t);
            const std::uint64_t before = n->built.segment->counters().firmware_runs;
            ASSERT_EQ(n->master.exchange_process_data().value_or(0), n->master.expected_wkc());
            in_frames[n == &ticked] += n->built.segment->counters().firmware_runs - before;
        }
        differences += test::differing_inputs(plain.master, ticked.master);
    }
    EXPECT_EQ(differences, 0u);
    // The drive did move, and the ticks did take work out of the frames.
    auto* drive = dynamic_cast<cia402::Drive*>(&plain.built.segment->slave(2).app());
    ASSERT_NE(drive, nullptr);
    EXPECT_GT(drive->position_actual(), 500'000);
    EXPECT_LT(in_frames[1], in_frames[0]);
}

// Two I/O terminals, one wired to the other, and 70 drives: the process data take several frames.
std::string many_frames() {
    std::string text = R"(
devices:
  - {name: valves, device: digital-out, channels: 8}
  - name: sensors
    device: digital-in
    channels: 8
    inputs:
      0: {wire: valves:0}
)";
    for (int i = 1; i <= 70; ++i)
        text += "  - {name: d" + std::to_string(i) + ", device: drive}\n";
    return text;
}

// A segment served in-process to the project master, whose frames sent back to back reach the line 20 us
// apart.
struct Served {
    explicit Served(std::unique_ptr<esc::Segment> s) : seg(std::move(s)), link(*seg), master(link) {
        link.set_time(1'000'000'000);
        link.set_time_step(20'000);
    }
    std::unique_ptr<esc::Segment> seg;
    net::InProcessLink link;
    master::Master master;
};

Served many_frames_network() {
    return Served(build_network(parse_network(many_frames()), "net.yaml").segment);
}

// Two copies of one network brought to OP, one of them with its firmware deferred across frames; 300 cycles
// of several frames each, period_ns apart (cycle i: the drives from first_drive on move in cyclic synchronous
// position mode, and the callback writes what else it likes), after each of which the deferred firmware runs
// (no frame waits any more). How many slaves' inputs differed, summed over the cycles, and how many frames
// passed deferred firmware.
struct Compared {
    std::size_t differences = 0;
    std::uint64_t past_deferred = 0;
};
bool to_op(Served& n) {
    return n.master.startup(AlState::Op);
}
template <class EachCycle, class BringUp = decltype(&to_op)>
Compared compare_deferring(Served& plain, Served& deferring, std::size_t first_drive, EachCycle&& each,
                           BringUp&& bring_up = to_op, std::uint64_t period_ns = kMs) {
    Compared c;
    for (Served* n : {&plain, &deferring})
        EXPECT_TRUE(bring_up(*n));
    EXPECT_EQ(plain.link.now_ns(), deferring.link.now_ns()) << "both start-ups took the same time";
    esc::Segment& seg = *deferring.seg;
    seg.set_deferred_firmware(true);
    EXPECT_GE(plain.master.process_data_frames(), 3u);
    const test::CspOutputs csp(plain.master.slaves()[first_drive]);
    EXPECT_TRUE(csp.valid());
    if (!csp.valid()) return c;
    const std::uint64_t past_before = seg.counters().past_deferred_firmware;
    for (int i = 0; i < 300; ++i) {
        const std::uint16_t control = i < 5 ? 0x06 : i < 10 ? 0x07 : 0x0F;
        for (Served* n : {&plain, &deferring}) {
            each(*n, i);
            for (std::size_t d = first_drive; d < n->master.slaves().size(); ++d)
                csp.write(n->master, d, control,
                          i < 20 ? 0 : (i - 20) * 500 * static_cast<std::int32_t>(d + 1));
            n->link.set_time(n->link.now_ns() + period_ns - 20'000 * n->master.process_data_frames());
            EXPECT_EQ(n->master.exchange_process_data().value_or(0), n->master.expected_wkc());
        }
        seg.run_deferred_firmware();
        c.differences += test::differing_inputs(plain.master, deferring.master);
    }
    c.past_deferred = seg.counters().past_deferred_firmware - past_before;
    return c;
}

// The frames of a cycle answered before the firmware of the frames before them ran (as vecat run answers the
// frames waiting in its socket, Segment::firmware_deferred) read what they read when the firmware runs after
// each frame: the slaves such a frame concerns are none the deferred firmware runs, or it runs first (the
// sensors' input is wired to the valves' output, which the first frame writes).
TEST(FirmwareBetweenFrames, FramesAnsweredBeforeTheFirmwareOfThoseBeforeThemReadTheSame) {
    Served plain = many_frames_network(), deferring = many_frames_network();
    int wired_ones = 0;
    const Compared c = compare_deferring(plain, deferring, 2, [&](Served& n, int i) {
        n.master.outputs(0)[0] = static_cast<std::uint8_t>(i);  // the valves
        if (&n == &deferring) wired_ones += n.master.inputs(1)[0] & 1u;
    });
    EXPECT_EQ(c.differences, 0u);
    // Frames did pass deferred firmware, the wire did carry, the drives did move.
    EXPECT_GE(c.past_deferred, 300u);  // at least one a cycle
    EXPECT_GT(wired_ones, 100);
    EXPECT_LT(wired_ones, 200);
    auto* drive = dynamic_cast<cia402::Drive*>(&deferring.seg->slave(40).app());
    ASSERT_NE(drive, nullptr);
    EXPECT_GT(drive->position_actual(), 1'000'000);
}

// The same on a line of 70 vecat drives whose first two are coupled by TWINsync (as vecat run --slaves N
// makes it): the coupled pair steps each other and takes its SYNC pulses before every frame, so the frames
// after one that gave the pair work run the deferred firmware first; the other frames still defer.
TEST(FirmwareBetweenFrames, FramesAnsweredBeforeTheFirmwareOfThoseBeforeThemWithACoupledPairReadTheSame) {
    const auto line = [] { return Served(cia402::make_drive_segment(device::default_drive(), 70)); };
    Served plain = line(), deferring = line();
    ASSERT_TRUE(deferring.seg->slave(0).app().coupled());
    // SYNC0 every 1 ms on every drive, from the same system time in both copies, before OP: the drives run
    // DC-synchronous (a servo period at each pulse), and the pair takes its pulses before every frame.
    const auto start_sync = [](Served& n) {
        return n.master.startup(AlState::SafeOp) && n.master.configure_dc(1'000'000'000'000) &&
               n.master.compensate_static_drift(100) &&
               std::all_of(n.master.slaves().begin(), n.master.slaves().end(),
                           [&](const master::SlaveInfo& s) {
                               return n.master.start_sync(s.station, 1'000'000, 0, 5'000'000);
                           }) &&
               n.master.request_state(AlState::Op);
    };
    // Cycles 3 us longer than SYNC0's: the pulses move through the cycle, between its frames too.
    const Compared c = compare_deferring(
        plain, deferring, 0, [](Served&, int) {}, start_sync, kMs + 3'000);
    EXPECT_EQ(c.differences, 0u);
    EXPECT_GE(c.past_deferred, 250u);  // the last frame of nearly every cycle (the first carries the FRMW)
    EXPECT_GE(deferring.seg->slave(1).esc().dc().counters().sync_pulses[0], 250u);
    for (const std::size_t k : {std::size_t{1}, std::size_t{40}}) {
        auto* drive = dynamic_cast<cia402::Drive*>(&deferring.seg->slave(k).app());
        ASSERT_NE(drive, nullptr);
        EXPECT_GT(drive->position_actual(), 100'000) << "drive " << k;
        EXPECT_EQ(drive->sync_mode(), coe::SyncMode::DcSync0) << "drive " << k;
    }
}

}  // namespace
}  // namespace vecat::network
