// Firmware when it is needed (Segment::set_local_cycle_ns, Segment::next_firmware_ns): a line whose firmware
// runs only when a frame comes and at its deadlines gives the master the same bytes, frame by frame, as a
// line whose firmware also runs at every servo period between frames (what the serve loop did before), for
// the same frame times. Two drives coupled by TWINsync and a third on its own (whose periods between two
// frames publish only the last one's feedback, Drive::advance), in DC-synchronous mode and in free run,
// through start-up, enabling, motion, SDO traffic, a drive fault with its emergency, and the master falling
// silent (the SyncManager watchdog in free run, the sync error in DC mode). Time is driven by hand, so each
// run is repeatable. The same for ticks that reach one slave each (Segment::tick_part).
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "cia402/drive.hpp"
#include "master/coe_client.hpp"
#include "protocol/cia402_objects.hpp"
#include "protocol/registers.hpp"
#include "protocol/sync_manager.hpp"
#include "test_support.hpp"

using namespace vecat;
using protocol::AlState;

namespace {

constexpr std::uint64_t kServoPeriod = cia402::Drive::kServoPeriodNs;
constexpr std::uint64_t kMs = 1'000'000;
constexpr std::size_t kDrives = 3;
// The mailbox-in SyncManager's status register (SM1, ETG.1000.4 / ESC datasheet section II 0x080D).
// SYNC0 between two servo periods of the drives, a third of a cycle after the frames.
constexpr std::int32_t kSync0Shift = 330'000;
const std::uint16_t kSm1Status = static_cast<std::uint16_t>(protocol::sm_addr(1) + protocol::sm::Status);

// PartsOfTicks: a tick at every servo period and every deadline that reaches one slave only
// (Segment::tick_part, as the serve loop's tick in parts stopped by a frame), the next one the next time.
enum class Schedule { EveryServoPeriod, WhenNeeded, PartsOfTicks };

struct Line {
    Line(Schedule s, bool dc)
        : schedule(s),
          use_dc(dc),
          desc(device::default_drive()),
          seg(cia402::make_drive_segment(desc, kDrives, {})),  // 0 and 1 cabled by TWINsync: in lockstep
          link(*seg),
          master(link) {
        link.set_time(now);
    }

    // Time passes without frames up to t: the firmware runs at every servo period, or only at the
    // deadlines the segment names.
    void pass_to(std::uint64_t t) {
        if (schedule == Schedule::EveryServoPeriod) {
            while (now + kServoPeriod <= t) {
                now += kServoPeriod;
                link.set_time(now);
                seg->tick(now);
                ++ticks;
            }
        } else if (schedule == Schedule::PartsOfTicks) {
            for (std::uint64_t d = std::min(now + kServoPeriod, seg->next_firmware_ns()); d <= t;
                 d = std::min(now + kServoPeriod, seg->next_firmware_ns())) {
                now = std::max(now, d);
                link.set_time(now);
                seg->tick_part(now, ticks % kDrives, 1);
                if (++ticks > 1'000'000) {
                    ADD_FAILURE() << "the deadlines do not move on";
                    return;
                }
            }
        } else {
            for (std::uint64_t d = seg->next_firmware_ns(); d <= t; d = seg->next_firmware_ns()) {
                now = std::max(now, d);
                link.set_time(now);
                seg->tick(now);
                if (++ticks > 1'000'000) {
                    ADD_FAILURE() << "the deadlines do not move on";
                    return;
                }
            }
        }
        now = t;
        link.set_time(now);
    }
    void put(std::uint64_t v, int bytes) {
        for (int i = 0; i < bytes; ++i)
            log.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
    // One 1 ms cycle: time passes, the process data frame, and what the master reads of each slave: its
    // inputs, AL status and code, and the mailbox-in SyncManager's status (an emergency waiting).
    std::vector<std::size_t> marks;  // where each cycle's bytes begin in the log
    void cycle() {
        marks.push_back(log.size());
        pass_to(now + kMs);
        put(master.exchange_process_data().value_or(0xFFFF), 2);
        for (std::size_t i = 0; i < kDrives; ++i) {
            const auto in = master.inputs(i);
            log.insert(log.end(), in.begin(), in.end());
            const auto st = master.slaves()[i].station;
            const auto al = master.read_al_status(st);
            put(al.status, 2);
            put(al.code, 2);
            put(master.read16(st, kSm1Status).value_or(0xFFFF), 2);
        }
    }
    bool request(AlState s) {
        std::uint8_t b[2] = {static_cast<std::uint8_t>(s), 0};
        return master.bwr(protocol::addr(protocol::Reg::AlControl), b).has_value();
    }
    void set_csp(std::size_t i, std::uint16_t cw, std::int32_t target) {
        auto o = master.outputs(i);
        st_le16(o.data(), cw);
        o[2] = 8;
        st_le32(o.data() + 4, static_cast<std::uint32_t>(target));
    }
    std::int32_t position(std::size_t i) const {
        return static_cast<std::int32_t>(ld_le32(master.inputs(i).data() + 4));
    }
    std::uint16_t statusword(std::size_t i) const { return ld_le16(master.inputs(i).data()); }

    Schedule schedule;
    bool use_dc;
    device::DeviceDescription desc;
    std::unique_ptr<esc::Segment> seg;
    net::InProcessLink link;
    master::Master master;
    std::uint64_t now = 1'000'000'000;
    std::uint64_t ticks = 0;
    std::vector<std::uint8_t> log;
    // What the scenario saw, so that the comparison is not between two lines that did nothing.
    std::int32_t travelled = 0, swung = 0;
    bool faulted = false, emergency = false, watchdog = false;
};

// The same master, step by step, on either line.
void scenario(Line& l) {
    ASSERT_TRUE(l.master.startup(AlState::PreOp));
    ASSERT_TRUE(l.master.configure_process_data());
    if (l.use_dc) {
        ASSERT_TRUE(l.master.configure_dc(900'000'000'000ull));
        for (const auto& s : l.master.slaves())
            ASSERT_TRUE(l.master.start_sync(s.station, 1'000'000, kSync0Shift, 20 * kMs));
    }
    // The SyncManager watchdog at 50 ms (0x0420 in units of 100 us with the default divider).
    for (const auto& s : l.master.slaves())
        ASSERT_TRUE(l.master.write16(s.station, protocol::addr(protocol::Reg::WatchdogTimeProcessData), 500));
    l.request(AlState::SafeOp);
    for (int i = 0; i < 30; ++i)
        l.cycle();
    l.request(AlState::Op);
    for (int i = 0; i < 100; ++i)
        l.cycle();
    for (std::size_t i = 0; i < kDrives; ++i)
        EXPECT_EQ(l.master.read_al_status(l.master.slaves()[i].station).state(), AlState::Op);
    // Enable in CSP holding the position, then move: drive 0 at a constant speed, drive 1 back and forth.
    // Drive 2 (not coupled) moves as drive 1.
    const std::int32_t p0 = l.position(0), p1 = l.position(1), p2 = l.position(2);
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        for (int i = 0; i < 10; ++i) {
            l.set_csp(0, cw, p0);
            l.set_csp(1, cw, p1);
            l.set_csp(2, cw, p2);
            l.cycle();
        }
    for (int k = 1; k <= 300; ++k) {
        const std::int32_t swing = k % 100 < 50 ? 30 * (k % 50) : 30 * (50 - k % 50);
        l.set_csp(0, 0x0F, p0 + 40 * k);
        l.set_csp(1, 0x0F, p1 + swing);
        l.set_csp(2, 0x0F, p2 + swing);
        l.cycle();
        l.swung = std::max(l.swung, l.position(2) - p2);
        if (k == 150) {
            // SDO traffic between cycles: an upload and a download (the following error window of drive 0).
            master::CoeClient c(l.master, l.master.slaves()[0].station);
            const auto r = c.upload(protocol::obj::position_actual_value.index, 0);
            ASSERT_TRUE(r.ok());
            l.log.insert(l.log.end(), r.data.begin(), r.data.end());
            ASSERT_TRUE(
                c.download_value(protocol::obj::following_error_window.index, 0, std::uint32_t{500}).ok());
        }
    }
    l.travelled = l.position(0) - p0;
    // A jump of the set-point beyond the window: drive 0 faults and sends an emergency.
    for (int k = 0; k < 40; ++k) {
        l.set_csp(0, 0x0F, p0 + 40 * 300 + 100'000);
        l.cycle();
        l.faulted |= (l.statusword(0) & 0x0008) != 0;
        const auto sm1 = l.master.read16(l.master.slaves()[0].station, kSm1Status);
        l.emergency |= sm1 && (*sm1 & protocol::sm::StatusMailboxFull) != 0;
    }
    // The master falls silent for 120 ms: the slaves notice on their own time and go to SAFEOP, in free
    // run when the SyncManager watchdog expires (0x001B), in DC mode when SYNC0 events without new outputs
    // reach the sync error limit first (0x002C); the drives see their outputs go to the safe state.
    l.pass_to(l.now + 120 * kMs);
    for (int i = 0; i < 5; ++i)
        l.cycle();
    const auto al = l.master.read_al_status(l.master.slaves()[1].station);
    l.watchdog = al.error() && al.code == (l.use_dc ? 0x002C : 0x001B);
}

// The master read the same bytes from both lines, cycle by cycle.
void expect_same_bytes(const Line& a, const Line& b) {
    ASSERT_EQ(a.log.size(), b.log.size());
    const auto diff = std::mismatch(a.log.begin(), a.log.end(), b.log.begin());
    if (diff.first != a.log.end()) {
        const auto at = static_cast<std::size_t>(diff.first - a.log.begin());
        const auto c = std::upper_bound(a.marks.begin(), a.marks.end(), at) - a.marks.begin() - 1;
        ADD_FAILURE() << "first difference in cycle " << c << ", byte " << at - a.marks[c] << " of it";
    }
}

class FirmwareSchedule : public ::testing::TestWithParam<bool> {};

TEST_P(FirmwareSchedule, RunningOnlyWhenNeededGivesTheMasterTheSameBytesAsEveryServoPeriod) {
    Line every(Schedule::EveryServoPeriod, GetParam());
    Line needed(Schedule::WhenNeeded, GetParam());
    scenario(every);
    scenario(needed);
    // The scenario did what it says on both lines.
    for (const Line* l : {&every, &needed}) {
        EXPECT_GT(l->travelled, 10'000);
        EXPECT_GT(l->swung, 1'000);
        EXPECT_TRUE(l->faulted);
        EXPECT_TRUE(l->emergency);
        EXPECT_TRUE(l->watchdog);
    }
    expect_same_bytes(every, needed);
    // And the firmware ran far less often between frames.
    EXPECT_LT(needed.ticks * 20, every.ticks) << needed.ticks << " against " << every.ticks;
}

TEST_P(FirmwareSchedule, TicksThatReachOneSlaveEachGiveTheMasterTheSameBytesAsEveryServoPeriod) {
    Line every(Schedule::EveryServoPeriod, GetParam());
    Line parts(Schedule::PartsOfTicks, GetParam());
    scenario(every);
    scenario(parts);
    for (const Line* l : {&every, &parts}) {
        EXPECT_GT(l->travelled, 10'000);
        EXPECT_TRUE(l->faulted);
        EXPECT_TRUE(l->watchdog);
    }
    expect_same_bytes(every, parts);
    // Every period had its tick, and each reached one slave.
    EXPECT_GE(parts.ticks, every.ticks);
    EXPECT_LT(parts.seg->counters().firmware_runs, every.seg->counters().firmware_runs);
}

INSTANTIATE_TEST_SUITE_P(DcAndFreeRun, FirmwareSchedule, ::testing::Values(true, false),
                         [](const auto& p) { return p.param ? "DcSync0" : "FreeRun"; });

}  // namespace
