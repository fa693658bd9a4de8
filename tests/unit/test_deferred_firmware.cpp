// Deferred firmware at the segment (Segment::firmware_deferred): a frame that comes while the firmware of the
// frames before it is still to run keeps it deferred only when nothing it does could see that firmware. One
// of those conditions: no slave's deadline is due at its time. Then the catch-up before it runs the slaves
// with a deadline due, and would take a deferred slave along at the wrong time.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "device/device_description.hpp"
#include "esc/segment.hpp"
#include "test_support.hpp"

using namespace vecat;
using namespace vecat::test;

namespace {

// An application that records when its firmware ran, and has a deadline of its own when given one.
class Recording final : public esc::ProcessImageApplication {
  public:
    Recording() : ProcessImageApplication(0, 0) {}
    void tick(std::uint64_t now_ns) override { runs.push_back(now_ns); }
    std::uint64_t next_event_ns() const override { return deadline; }
    std::vector<std::uint64_t> runs;
    std::uint64_t deadline = esc::DistributedClock::kNever;
};

constexpr std::uint8_t kApwr = 0x02, kFprd = 0x04, kFpwr = 0x05;
constexpr std::uint64_t kUs = 1'000;

constexpr std::uint64_t t0 = 1'000'000'000;

// Three slaves with station addresses 0x1001.. (APWR 0x0010), whose firmware the segment defers.
std::unique_ptr<esc::Segment> three_slaves() {
    auto seg = esc::make_segment(device::default_drive(), 3, {}, [](const device::DeviceDescription&) {
        return std::make_unique<Recording>();
    });
    seg->set_deferred_firmware(true);
    for (std::uint16_t k = 0; k < 3; ++k) {
        raw_datagram(*seg, kApwr, phys(static_cast<std::uint16_t>(-k), 0x0010),
                     {static_cast<std::uint8_t>(k + 1), 0x10}, t0);
        seg->run_deferred_firmware();
    }
    return seg;
}

// A frame at t gives slave 0 work (a write of AL control); whether its firmware was deferred.
bool give_slave_0_work(esc::Segment& seg, std::uint64_t t) {
    return raw_datagram(seg, kFpwr, phys(0x1001, 0x0120), {0x02, 0}, t).wkc == 1 && seg.firmware_deferred();
}

TEST(DeferredFirmware, AFrameAtADueDeadlineRunsTheDeferredFirmwareAtItsOwnTimeFirst) {
    auto seg = three_slaves();
    const auto app = [&](std::size_t k) { return dynamic_cast<Recording*>(&seg->slave(k).app()); };
    // Every slave runs at t0; slave 1 then has a deadline 50 us later.
    app(1)->deadline = t0 + 50 * kUs;
    seg->tick(t0);
    ASSERT_EQ(seg->next_firmware_ns(), t0 + 50 * kUs);
    // A frame at t0 + 10 us gives slave 0 work (AL control); its firmware is deferred.
    const std::uint64_t t1 = t0 + 10 * kUs;
    ASSERT_TRUE(give_slave_0_work(*seg, t1));
    // A frame at t0 + 60 us, past slave 1's deadline, reads slave 2 only.
    const std::uint64_t t2 = t0 + 60 * kUs;
    EXPECT_EQ(raw_datagram(*seg, kFprd, phys(0x1003, 0x0130), {0, 0}, t2).wkc, 1);
    seg->run_deferred_firmware();
    // Slave 0 ran for the first frame at that frame's time, not at the second's; slave 1 at its deadline's
    // frame.
    EXPECT_EQ(app(0)->runs.back(), t1);
    EXPECT_EQ(app(1)->runs.back(), t2);
}

// The deadline a deferred run sets is not known before that run: a frame more than a local cycle after the
// first deferred frame runs that firmware first, so that a deadline it sets within the local cycle (a
// pending state change's poll, here the application's own) is taken at this frame, not missed.
TEST(DeferredFirmware, AFrameALocalCycleLaterRunsTheDeferredFirmwareFirst) {
    auto seg = three_slaves();
    const auto app = [&](std::size_t k) { return dynamic_cast<Recording*>(&seg->slave(k).app()); };
    seg->tick(t0);
    // Slave 0 gets work at t1; its run there sets a deadline 100 us later.
    const std::uint64_t t1 = t0 + 10 * kUs;
    ASSERT_TRUE(give_slave_0_work(*seg, t1));
    app(0)->deadline = t1 + 100 * kUs;
    // A frame for slave 2 a local cycle and more after t1.
    const std::uint64_t t2 = t1 + seg->local_cycle_ns() + 50 * kUs;
    EXPECT_EQ(raw_datagram(*seg, kFprd, phys(0x1003, 0x0130), {0, 0}, t2).wkc, 1);
    // Slave 0 ran at t1, and for its deadline before that frame was processed (at the frame's time).
    ASSERT_GE(app(0)->runs.size(), 2u);
    EXPECT_EQ(app(0)->runs[app(0)->runs.size() - 2], t1);
    EXPECT_EQ(app(0)->runs.back(), t2);
}

// A frame that concerns a deferred slave runs its deferred firmware first; a deadline that run sets at or
// before this frame's time (a watchdog shorter than the time between the frames, here the application's
// own) is then due, and is taken before the frame reads the slave, as without the deferral.
TEST(DeferredFirmware, ADeadlineTheDeferredRunSetsBeforeTheFrameIsTakenBeforeTheFrameReads) {
    auto seg = three_slaves();
    const auto app = [&](std::size_t k) { return dynamic_cast<Recording*>(&seg->slave(k).app()); };
    seg->tick(t0);
    // Slave 0 gets work at t1; its run there will set a deadline 20 us later.
    const std::uint64_t t1 = t0 + 10 * kUs;
    ASSERT_TRUE(give_slave_0_work(*seg, t1));
    app(0)->deadline = t1 + 20 * kUs;
    // A frame 50 us after t1 (within the local cycle) reads slave 0.
    const std::uint64_t t2 = t1 + 50 * kUs;
    ASSERT_LT(t2, t1 + seg->local_cycle_ns());
    EXPECT_EQ(raw_datagram(*seg, kFprd, phys(0x1001, 0x0130), {0, 0}, t2).wkc, 1);
    // Slave 0 ran at t1, then for its deadline before the frame read it.
    ASSERT_GE(app(0)->runs.size(), 2u);
    EXPECT_EQ(app(0)->runs[app(0)->runs.size() - 2], t1);
    EXPECT_EQ(app(0)->runs.back(), t2);
}

}  // namespace
