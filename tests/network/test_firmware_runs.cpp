// When the slaves' firmware runs around frames (Segment: firmware when it is needed). A frame reads a slave
// only after its firmware has caught up; a slave runs after a frame only if the frame gave its firmware
// work (Esc::take_firmware_work); a slave that no frame reads still runs within its lag bound. Counted with
// SegmentCounters::firmware_runs on a network of one input terminal, one output terminal and one drive.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>

#include "common/bytes.hpp"
#include "esc/segment.hpp"
#include "network_support.hpp"
#include "protocol/frame.hpp"
#include "protocol/registers.hpp"

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

}  // namespace
}  // namespace vecat::network
