// Telemetry without DDS: the lock-free queue, the sampler on an in-process line of drives driven by the
// project's master (values against what the master read, decimation, events, no allocation), the CSV
// round trip and the scope picture.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <new>
#include <set>
#include <thread>

#include "allocation_counter.hpp"
#include "cia402/drive.hpp"
#include "protocol/cia402.hpp"
#include "telemetry/plot.hpp"
#include "telemetry/recording.hpp"
#include "telemetry/sampler.hpp"
#include "test_support.hpp"

namespace vecat::telemetry {
namespace {

// ---- Queue

TEST(SpscQueue, KeepsOrderAndCountsWhatDoesNotFit) {
    SpscQueue<int, 4> q;
    for (int i = 0; i < 4; ++i)
        EXPECT_TRUE(q.push(i));
    EXPECT_FALSE(q.push(99));
    EXPECT_FALSE(q.push(100));
    EXPECT_EQ(q.overflows(), 2u);
    int v = -1;
    for (int i = 0; i < 4; ++i) {
        ASSERT_TRUE(q.pop(v));
        EXPECT_EQ(v, i);
    }
    EXPECT_FALSE(q.pop(v));
    EXPECT_TRUE(q.push(5));  // room again after the consumer caught up
    ASSERT_TRUE(q.pop(v));
    EXPECT_EQ(v, 5);
}

TEST(SpscQueue, TwoThreadsLoseNothingThatWasAccepted) {
    SpscQueue<std::uint64_t, 256> q;
    constexpr std::uint64_t kN = 200'000;
    std::vector<std::uint64_t> accepted_log;
    std::uint64_t accepted = 0;
    std::thread producer([&] {
        for (std::uint64_t i = 0; i < kN; ++i)
            if (q.push(i)) ++accepted;
    });
    std::uint64_t received = 0, last = 0;
    bool ordered = true, done = false;
    while (!done) {
        std::uint64_t v;
        while (q.pop(v)) {
            if (received && v <= last) ordered = false;
            last = v;
            ++received;
        }
        done = received + q.overflows() == kN;
    }
    producer.join();
    EXPECT_TRUE(ordered);
    EXPECT_EQ(received, accepted);
    EXPECT_EQ(received + q.overflows(), kN);
}

// ---- Sampler on two drives in OP, driven through process data by the project's master

struct SamplerTest : ::testing::Test {
    test::Bench b{2, {}, device::default_drive(), &cia402::make_drive_segment};
    TelemetryQueue q;

    void SetUp() override {
        std::string why;
        ASSERT_TRUE(b.master.startup(protocol::AlState::Op, &why)) << why;
    }
    // One 1 ms cycle: CSP set-points, one LRW, then the sampler as the serve loop calls it.
    void cycle(Sampler& s, std::uint16_t cw, std::int32_t p0, std::int32_t p1) {
        for (std::size_t i = 0; i < 2; ++i) {
            auto o = b.master.outputs(i);
            st_le16(o.data(), cw);
            o[2] = 8;
            st_le32(o.data() + 4, static_cast<std::uint32_t>(i == 0 ? p0 : p1));
        }
        b.now += 1'000'000;
        b.link.set_time(b.now);
        ASSERT_EQ(b.master.exchange_process_data().value_or(0), b.master.expected_wkc());
        s.on_frame(b.now);
    }
    Recording drain() {
        Recording r;
        Record rec;
        while (q.pop(rec))
            r.add(rec);
        return r;
    }
};

TEST_F(SamplerTest, AxisSamplesCarryWhatTheMasterReadInTheSameCycle) {
    Sampler s(*b.seg, q);
    std::int32_t a0 = 0, b0 = 0;
    cycle(s, 0, 0, 0);
    a0 = static_cast<std::int32_t>(ld_le32(b.master.inputs(0).data() + 4));
    b0 = static_cast<std::int32_t>(ld_le32(b.master.inputs(1).data() + 4));
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        for (int i = 0; i < 5; ++i)
            cycle(s, cw, a0, b0);
    drain();
    // Before a frame reaches it the slave's firmware catches up with the servo periods since its last run
    // and writes its inputs (Segment::set_local_cycle_ns); the firmware after the frame takes the new
    // outputs, and no servo period passes in between. So the sample taken after the frame holds what the
    // master read in that same frame, as a real slave in free run whose cycle just ended gives.
    int compared = 0;
    for (int k = 1; k <= 200; ++k) {
        cycle(s, 0x0F, a0 + 400 * k, b0 - 200 * k);
        const Recording r = drain();
        ASSERT_EQ(r.axes.size(), 2u);
        for (const AxisSample& a : r.axes) {
            auto in = b.master.inputs(a.slave);
            EXPECT_EQ(a.time_ns, b.now);
            EXPECT_EQ(a.statusword, ld_le16(in.data()));
            EXPECT_EQ(a.mode, 8);
            EXPECT_EQ(a.position_actual, static_cast<std::int32_t>(ld_le32(in.data() + 4)));
            EXPECT_EQ(a.velocity_actual, static_cast<std::int32_t>(ld_le32(in.data() + 8)));
            EXPECT_EQ(a.controlword, 0x0F);
            EXPECT_EQ(a.cia402_state, static_cast<std::uint8_t>(cia402::State::OperationEnabled));
            EXPECT_EQ(a.position_demand - a.position_actual, a.following_error);
            ++compared;
        }
    }
    EXPECT_EQ(compared, 400);
}

TEST_F(SamplerTest, DecimationKeepsEveryNthCycle) {
    SamplerOptions o;
    o.decimation = 4;
    o.status_every = 5;
    Sampler s(*b.seg, q, o);
    for (int i = 0; i < 100; ++i)
        cycle(s, 0, 0, 0);
    const Recording r = drain();
    EXPECT_EQ(r.axes.size(), 2u * 25u);
    EXPECT_EQ(r.status.size(), 2u * 5u);
    // Every 4th frame (the exchange counts also hold the firmware's runs before frames).
    for (std::size_t i = 2; i < r.axes.size(); ++i)
        if (r.axes[i].slave == r.axes[i - 2].slave) {
            EXPECT_EQ(r.axes[i].time_ns - r.axes[i - 2].time_ns, 4'000'000u);
            EXPECT_GT(r.axes[i].cycle, r.axes[i - 2].cycle);
        }
    EXPECT_EQ(s.stats().samples, 50u);
    for (const auto& st : r.status)
        EXPECT_EQ(st.al_status, static_cast<std::uint8_t>(protocol::AlState::Op));
}

TEST_F(SamplerTest, StateChangesFaultsAndEmergenciesAreEvents) {
    Sampler s(*b.seg, q);
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        for (int i = 0; i < 3; ++i)
            cycle(s, cw, 0, 0);
    // Simulated over-current on drive 1 (manufacturer object 0x2101).
    b.od(1).find(0x2101, 0)->set<std::uint16_t>(cia402::fault::OverCurrent);
    for (int i = 0; i < 10; ++i)
        cycle(s, 0x0F, 0, 0);
    ASSERT_TRUE(b.master.request_state(protocol::AlState::SafeOp));
    s.on_frame(b.now);
    const Recording r = drain();
    auto count = [&](EventKind k, std::uint16_t slave) {
        return std::count_if(r.events.begin(), r.events.end(),
                             [&](const Event& e) { return e.kind == k && e.slave == slave; });
    };
    // Not ready to switch on -> switch on disabled (the drive's first servo period, before the first
    // controlword takes effect) -> ready -> switched on -> enabled on both; drive 1 then fault reaction,
    // fault.
    EXPECT_EQ(count(EventKind::Cia402State, 0), 4);
    EXPECT_GE(count(EventKind::Cia402State, 1), 5);
    EXPECT_EQ(count(EventKind::Fault, 0), 0);
    ASSERT_EQ(count(EventKind::Fault, 1), 1);
    const auto fault = std::find_if(r.events.begin(), r.events.end(),
                                    [](const Event& e) { return e.kind == EventKind::Fault; });
    EXPECT_EQ(fault->code, cia402::fault::OverCurrent);
    EXPECT_GE(count(EventKind::Emergency, 1), 1);
    EXPECT_EQ(count(EventKind::AlState, 0), 1);  // OP -> SAFEOP
    const auto al = std::find_if(r.events.begin(), r.events.end(),
                                 [](const Event& e) { return e.kind == EventKind::AlState; });
    EXPECT_EQ(al->old_value, static_cast<int>(protocol::AlState::Op));
    EXPECT_EQ(al->new_value, static_cast<int>(protocol::AlState::SafeOp));
}

// A slave restarted while sampling (power off and on, or a hot connect group plugged back) is a new object:
// the sampler binds it again instead of reading the one that went, and shows the restart as the change of
// AL state it is. (Under AddressSanitizer the old code read freed memory here.)
TEST_F(SamplerTest, ARestartedSlaveIsSampledAgainNotTheOneThatWent) {
    Sampler s(*b.seg, q);
    for (int i = 0; i < 3; ++i)
        cycle(s, 0x06, 0, 0);
    ASSERT_TRUE(b.seg->restart_slave(1));
    s.on_frame(b.now);
    const Recording r = drain();
    const auto restarted = std::find_if(r.events.begin(), r.events.end(), [](const Event& e) {
        return e.kind == EventKind::AlState && e.slave == 1;
    });
    ASSERT_NE(restarted, r.events.end());
    EXPECT_EQ(restarted->old_value, static_cast<int>(protocol::AlState::Op));
    EXPECT_EQ(restarted->new_value, static_cast<int>(protocol::AlState::Init));
    EXPECT_EQ(std::count_if(r.events.begin(), r.events.end(),
                            [](const Event& e) { return e.kind == EventKind::Emergency; }),
              0);  // the new application's counters are not the old one's
}

// The CiA 402 state of a sample is its statusword decoded: through enable, a fault and its reset it is
// the state of the drive's state machine, also in the events. The TWINsync samples are the drive's link.
TEST_F(SamplerTest, Cia402StateIsTheStatuswordDecodedAndFollowsTheDrive) {
    Sampler s(*b.seg, q);
    auto drive = [&](std::uint16_t i) -> const cia402::Drive& {
        return dynamic_cast<const cia402::Drive&>(b.seg->slave(i).app());
    };
    std::set<std::uint8_t> seen;
    std::vector<std::int64_t> events1;  // drive 1's states, as the events give them
    int compared = 0;
    auto check = [&](std::uint16_t cw, int cycles) {
        for (int i = 0; i < cycles; ++i) {
            cycle(s, cw, 0, 0);
            const Recording r = drain();
            for (const AxisSample& a : r.axes) {
                const auto st = static_cast<std::uint8_t>(drive(a.slave).cia402_state());
                EXPECT_EQ(a.cia402_state, st)
                    << "slave " << a.slave << " statusword 0x" << std::hex << a.statusword;
                EXPECT_EQ(protocol::cia402::decode_state(a.statusword), drive(a.slave).cia402_state());
                seen.insert(a.cia402_state);
                ++compared;
            }
            for (const Event& e : r.events)
                if (e.kind == EventKind::Cia402State && e.slave == 1) events1.push_back(e.new_value);
            // The two drives are cabled by TWINsync (make_drive_segment): a link sample with each axis
            // sample.
            ASSERT_EQ(r.twinsync.size(), r.axes.size());
            for (const TwinsyncSample& t : r.twinsync) {
                const twinsync::LinkStatus* ls = drive(t.slave).twinsync_status();
                ASSERT_NE(ls, nullptr);
                EXPECT_EQ(t.frames_sent, ls->frames_sent);
                EXPECT_EQ(t.frames_received, ls->frames_received);
            }
        }
    };
    check(0, 2);
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        check(cw, 3);
    b.od(1).find(0x2101, 0)->set<std::uint16_t>(cia402::fault::OverCurrent);  // simulated over-current
    check(0x0F, 10);
    b.od(1).find(0x2101, 0)->set<std::uint16_t>(0);
    check(0x00, 3);
    check(0x80, 3);  // fault reset
    EXPECT_GT(compared, 0);
    using protocol::cia402::State;
    for (const State st : {State::SwitchOnDisabled, State::ReadyToSwitchOn, State::SwitchedOn,
                           State::OperationEnabled, State::Fault})
        EXPECT_TRUE(seen.count(static_cast<std::uint8_t>(st))) << protocol::cia402::to_string(st);
    ASSERT_FALSE(events1.empty());
    EXPECT_EQ(events1.back(), static_cast<std::int64_t>(State::SwitchOnDisabled));
    EXPECT_NE(std::find(events1.begin(), events1.end(), static_cast<std::int64_t>(State::Fault)),
              events1.end());
}

TEST_F(SamplerTest, CyclicPathAllocatesNothingAndAFullQueueIsCountedNotWaitedFor) {
    Sampler s(*b.seg, q);
    for (int i = 0; i < 10; ++i)
        cycle(s, 0, 0, 0);
    const std::uint64_t before = test::allocations();
    for (int i = 0; i < 20'000; ++i)  // nobody empties the queue: it fills up
        s.sample_all(b.now + static_cast<std::uint64_t>(i));
    EXPECT_EQ(test::allocations() - before, 0u);
    EXPECT_GT(q.overflows(), 0u);
    EXPECT_EQ(q.size_approx(), TelemetryQueue::capacity());
    // Once there is room, the loss is reported as an event.
    Record r;
    for (int i = 0; i < 100; ++i)
        q.pop(r);
    const auto lost = q.overflows();
    cycle(s, 0, 0, 0);
    bool reported = false;
    while (q.pop(r))
        if (auto* e = std::get_if<Event>(&r); e && e->kind == EventKind::Overflow)
            reported = e->new_value == static_cast<std::int64_t>(lost);
    EXPECT_TRUE(reported);
}

// A CoE device that is not vecat's drive but has the CiA 402 objects (here the drive's dictionary without
// its behaviour, as a copy made by vecat clone serves it) gives axis samples too: its state is what its
// statusword shows. It has no TWINsync card.
TEST(Sampler, AnyDeviceWithTheStatuswordGivesAxisSamples) {
    test::Bench b{1, {}, device::default_drive(), &coe::make_coe_segment};
    std::string why;
    ASSERT_TRUE(b.master.startup(protocol::AlState::Op, &why)) << why;
    TelemetryQueue q;
    Sampler s(*b.seg, q);
    coe::Entry* statusword = b.od(0).find(0x6041, 0);
    ASSERT_NE(statusword, nullptr);
    auto cycle_with = [&](std::uint16_t sw) {
        statusword->set<std::uint16_t>(sw);
        b.now += 1'000'000;
        b.link.set_time(b.now);
        ASSERT_TRUE(b.master.exchange_process_data().has_value());
        s.on_frame(b.now);
    };
    using protocol::cia402::State;
    cycle_with(0x0237);  // operation enabled, remote
    cycle_with(0x0218);  // fault
    cycle_with(0x004F);  // no state of Table 30
    Recording r;
    Record rec;
    while (q.pop(rec))
        r.add(rec);
    ASSERT_EQ(r.axes.size(), 3u);
    EXPECT_EQ(r.axes[0].cia402_state, static_cast<std::uint8_t>(State::OperationEnabled));
    EXPECT_EQ(r.axes[0].statusword, 0x0237);
    EXPECT_EQ(r.axes[1].cia402_state, static_cast<std::uint8_t>(State::Fault));
    EXPECT_EQ(r.axes[2].cia402_state, kNoCia402State);
    EXPECT_TRUE(r.twinsync.empty());
    std::vector<std::int64_t> states;
    for (const Event& e : r.events)
        if (e.kind == EventKind::Cia402State) states.push_back(e.new_value);
    EXPECT_EQ(states, (std::vector<std::int64_t>{static_cast<std::int64_t>(State::OperationEnabled),
                                                 static_cast<std::int64_t>(State::Fault), kNoCia402State}));
}

// ---- CSV and picture

Recording synthetic() {
    Recording r;
    for (int i = 0; i < 500; ++i)
        for (std::uint16_t s = 0; s < 2; ++s) {
            AxisSample a;
            a.time_ns = 5'000'000'000'000ull + static_cast<std::uint64_t>(i) * 1'000'000;
            a.cycle = static_cast<std::uint64_t>(i);
            a.slave = s;
            a.statusword = 0x1237;
            a.mode = -3;
            a.position_demand = (s ? -1 : 1) * i * 1000;
            a.position_actual = a.position_demand - 50;
            a.following_error = 50;
            a.torque_actual = static_cast<std::int16_t>(-i);
            a.velocity_actual = 1'000'000;
            r.axes.push_back(a);
        }
    TwinsyncSample t;
    t.time_ns = 5'000'000'000'000ull;
    t.sync_offset_ns = -1234;
    t.tracking_error = 1.5f;
    t.frames_received = 1ull << 40;
    r.twinsync.push_back(t);
    Event e;
    e.time_ns = 5'000'000'000'001ull;
    e.kind = EventKind::Fault;
    e.code = 0x2310;
    e.new_value = -7;
    r.events.push_back(e);
    return r;
}

TEST(Csv, WhatIsWrittenReadsBackTheSame) {
    const Recording r = synthetic();
    const auto dir = std::filesystem::temp_directory_path() / ("vecat-tel-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "rec.csv").string();
    std::string why;
    ASSERT_TRUE(write_csv(r, path, &why)) << why;
    EXPECT_TRUE(std::filesystem::exists(dir / "rec-twinsync.csv"));
    EXPECT_TRUE(std::filesystem::exists(dir / "rec-events.csv"));
    EXPECT_FALSE(std::filesystem::exists(dir / "rec-status.csv"));
    Recording back;
    ASSERT_TRUE(read_csv(path, back, &why)) << why;
    ASSERT_EQ(back.axes.size(), r.axes.size());
    for (std::size_t i = 0; i < r.axes.size(); ++i) {
        EXPECT_EQ(back.axes[i].time_ns, r.axes[i].time_ns);
        EXPECT_EQ(back.axes[i].position_actual, r.axes[i].position_actual);
        EXPECT_EQ(back.axes[i].torque_actual, r.axes[i].torque_actual);
        EXPECT_EQ(back.axes[i].mode, r.axes[i].mode);
    }
    ASSERT_EQ(back.twinsync.size(), 1u);
    EXPECT_EQ(back.twinsync[0].sync_offset_ns, -1234);
    EXPECT_EQ(back.twinsync[0].frames_received, 1ull << 40);
    EXPECT_FLOAT_EQ(back.twinsync[0].tracking_error, 1.5f);
    ASSERT_EQ(back.events.size(), 1u);
    EXPECT_EQ(back.events[0].kind, EventKind::Fault);
    EXPECT_EQ(back.events[0].new_value, -7);
    std::filesystem::remove_all(dir);
}

TEST(Plot, TicksAreRoundNumbersCoveringTheRange) {
    const auto unit = nice_ticks(0, 1, 5);
    ASSERT_EQ(unit.size(), 6u);
    for (std::size_t i = 0; i < unit.size(); ++i)
        EXPECT_NEAR(unit[i], 0.2 * static_cast<double>(i), 1e-12);
    const auto t = nice_ticks(-523'000, 498'000, 5);
    ASSERT_FALSE(t.empty());
    EXPECT_GE(t.front(), -523'000);
    EXPECT_LE(t.back(), 498'000);
    EXPECT_EQ(t[1] - t[0], 250'000);
    EXPECT_TRUE(nice_ticks(1, 1).empty());
}

TEST(Plot, OnePanelPerGroupWithUnitsLegendAndCurves) {
    std::string why;
    const auto groups =
        parse_signal_groups("position_actual+position_demand,following_error,twinsync.sync_offset_ns", &why);
    ASSERT_EQ(groups.size(), 3u) << why;
    EXPECT_TRUE(parse_signal_groups("position_actual,nonsense", &why).empty());
    EXPECT_NE(why.find("nonsense"), std::string::npos);

    const Plot p = make_plot(synthetic(), groups, "test move");
    ASSERT_EQ(p.panels.size(), 3u);
    EXPECT_EQ(p.panels[0].series.size(), 4u);  // two slaves x two signals
    EXPECT_EQ(p.panels[0].unit, "inc");
    EXPECT_EQ(p.panels[2].unit, "ns");
    EXPECT_DOUBLE_EQ(p.panels[0].series[0].t.front(), 0.0);  // time from the first record
    EXPECT_NEAR(p.panels[0].series[0].t.back(), 0.499, 1e-9);
    const std::string svg = render_svg(p);
    EXPECT_NE(svg.find("test move"), std::string::npos);
    EXPECT_NE(svg.find("position [\u00d710\u00b3 inc]"), std::string::npos);  // +-499000: in thousands
    EXPECT_NE(svg.find("following error [inc]"), std::string::npos);
    EXPECT_NE(svg.find("sync offset [ns]"), std::string::npos);
    EXPECT_NE(svg.find("slave 1 position_demand"), std::string::npos);
    EXPECT_NE(svg.find("time [s]"), std::string::npos);
    std::size_t polylines = 0;
    for (auto at = svg.find("<polyline"); at != std::string::npos; at = svg.find("<polyline", at + 1))
        ++polylines;
    EXPECT_EQ(polylines, 4u + 2u + 1u);
    // Only slave 0.
    const Plot one = make_plot(synthetic(), groups, "", {0});
    EXPECT_EQ(one.panels[0].series.size(), 2u);
    EXPECT_EQ(one.panels[0].series[0].label, "position_actual");
}

}  // namespace
}  // namespace vecat::telemetry
