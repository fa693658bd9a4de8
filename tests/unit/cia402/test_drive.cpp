// The CiA 402 drive behind its dictionary: state machine through the controlword, every operation mode
// against the simulated mechanics, limits, faults, touch probe and the factor group. Most tests drive the
// dictionary directly in PREOP (the drive runs on the slave's timer ticks, like a master using SDO); the
// cyclic modes are also tested end to end through process data in OP.
// Long (about 840 lines) because it is one fixture for the whole drive: each test is short and reads alone.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <thread>

#include "cia402/drive.hpp"
#include "master/coe_client.hpp"
#include "protocol/cia402.hpp"
#include "protocol/cia402_objects.hpp"
#include "serve/in_process_link.hpp"
#include "test_support.hpp"

namespace cia = vecat::protocol::cia402;

namespace obj = vecat::protocol::obj;

namespace vecat::cia402 {
namespace {

constexpr std::uint64_t kMs = 1'000'000;

struct DriveTest : ::testing::Test {
    test::Bench b{1, {}, device::default_drive(), &make_drive_segment};
    Drive& drive() { return dynamic_cast<Drive&>(b.slave(0).app()); }
    coe::ObjectDictionary& od() { return b.od(0); }
    coe::Entry& e(std::uint16_t i, std::uint8_t s = 0) {
        coe::Entry* x = od().find(i, s);
        EXPECT_NE(x, nullptr) << std::hex << i;
        return *x;
    }
    coe::Entry& e(protocol::ObjectRef r) { return e(r.index, r.subindex); }
    template <class T>
    void set(std::uint16_t i, T v, std::uint8_t s = 0) {
        e(i, s).set(v);
    }
    template <class T>
    void set(protocol::ObjectRef r, T v) {
        e(r).set(v);
    }
    std::uint16_t statusword() { return e(obj::statusword).get<std::uint16_t>(); }
    std::int32_t position() { return e(obj::position_actual_value).get<std::int32_t>(); }
    std::int32_t velocity() { return e(obj::velocity_actual_value).get<std::int32_t>(); }
    void run_ms(double ms) { b.advance(static_cast<std::uint64_t>(ms * 1e6)); }
    // Runs in 1 ms steps until pred holds; the time it took (ms) or -1 after limit_ms.
    double run_until(const std::function<bool()>& pred, double limit_ms,
                     const std::function<void()>& each = {}) {
        for (int t = 0; t <= limit_ms; ++t) {
            if (pred()) return t;
            run_ms(1);
            if (each) each();
        }
        return -1;
    }
    void SetUp() override {
        std::string why;
        ASSERT_TRUE(b.master.startup(protocol::AlState::PreOp, &why)) << why;
        run_ms(1);
    }
    void enable(Mode m) {
        set<std::int8_t>(obj::modes_of_operation, static_cast<std::int8_t>(m));
        set<std::uint16_t>(obj::controlword, 0x06);
        run_ms(1);
        set<std::uint16_t>(obj::controlword, 0x07);
        run_ms(1);
        set<std::uint16_t>(obj::controlword, 0x0F);
        run_ms(1);
        ASSERT_EQ(cia::decode_state(statusword()), cia::State::OperationEnabled) << std::hex << statusword();
        ASSERT_EQ(e(obj::modes_of_operation_display).get<std::int8_t>(), static_cast<std::int8_t>(m));
    }
    // A profile position move with the bit 4 / bit 12 handshake; returns the time to target reached (ms).
    double pp_move(std::int32_t target, std::uint16_t extra_bits = 0) {
        set<std::int32_t>(obj::target_position, target);
        set<std::uint16_t>(obj::controlword, static_cast<std::uint16_t>(0x1F | extra_bits));
        const double ack = run_until([&] { return statusword() & sw::Bit12; }, 10);
        EXPECT_GE(ack, 0) << "set-point not acknowledged";
        set<std::uint16_t>(obj::controlword, static_cast<std::uint16_t>(0x0F | extra_bits));
        run_ms(1);
        EXPECT_FALSE(statusword() & sw::Bit12);
        return run_until([&] { return statusword() & sw::TargetReached; }, 20000) + ack + 1;
    }
};

TEST_F(DriveTest, EnableSequenceShowsEveryStateInTheStatusword) {
    EXPECT_EQ(statusword(), 0x0250);  // switch on disabled, voltage enabled, remote
    set<std::uint16_t>(obj::controlword, 0x06);
    run_ms(1);
    EXPECT_EQ(statusword() & 0x027F, 0x0231);
    set<std::uint16_t>(obj::controlword, 0x07);
    run_ms(1);
    EXPECT_EQ(statusword() & 0x027F, 0x0233);
    set<std::uint16_t>(obj::controlword, 0x0F);
    run_ms(1);
    EXPECT_EQ(statusword() & 0x027F, 0x0237);
    EXPECT_EQ(drive().cia402_state(), State::OperationEnabled);
    set<std::uint16_t>(obj::controlword, 0x00);
    run_ms(1);
    EXPECT_EQ(statusword() & 0x027F, 0x0250);
}

TEST_F(DriveTest, ModesOfOperationDisplayFollowsSupportedModesOnly) {
    for (int mi : {1, 3, 4, 6, 8, 9, 10}) {
        const auto m = static_cast<std::int8_t>(mi);
        set<std::int8_t>(obj::modes_of_operation, m);
        run_ms(1);
        EXPECT_EQ(e(obj::modes_of_operation_display).get<std::int8_t>(), m);
    }
    set<std::int8_t>(obj::modes_of_operation,
                     7);  // interpolated position: not supported, display keeps the last mode
    run_ms(1);
    EXPECT_EQ(e(obj::modes_of_operation_display).get<std::int8_t>(), 10);
    EXPECT_EQ(e(obj::supported_drive_modes).get<std::uint32_t>(), 0x3ADu);
}

TEST_F(DriveTest, ProfilePositionTrapezoidTakesTheClosedFormTime) {
    enable(Mode::ProfilePosition);
    const std::int32_t start = position();
    set<std::uint32_t>(obj::profile_velocity, 500'000);
    set<std::uint32_t>(obj::profile_acceleration, 5'000'000);
    set<std::uint32_t>(obj::profile_deceleration, 5'000'000);
    const std::int32_t target = start + 1'000'000;
    // Watch the demand while moving: it never exceeds V.
    double peak_demand = 0;
    set<std::int32_t>(obj::target_position, target);
    set<std::uint16_t>(obj::controlword, 0x1F);
    run_ms(1);
    ASSERT_TRUE(statusword() & sw::Bit12);
    set<std::uint16_t>(obj::controlword, 0x0F);
    const double t =
        run_until([&] { return statusword() & sw::TargetReached; }, 5000,
                  [&] {
                      peak_demand = std::max(
                          peak_demand, std::abs(e(obj::velocity_demand_value).get<std::int32_t>() * 1.0));
                  });
    ASSERT_GT(t, 0);
    ProfileLimits l{500'000, 5'000'000, 5'000'000, 0};
    const double expect_ms = ProfileGenerator::rest_to_rest_duration(1'000'000, l) * 1e3;
    EXPECT_NEAR(expect_ms, 2100.0, 1.0);  // 0.1 s ramps + 2 s cruise: d/V + V/A
    std::printf("PP trapezoid 1e6 units: target reached after %.0f ms, closed-form profile %.1f ms\n", t,
                expect_ms);
    // Reached = profile done + position window for the window time (10 ms) + settling.
    EXPECT_GE(t + 1, expect_ms);
    EXPECT_LE(t, expect_ms + 40);
    EXPECT_LE(peak_demand, 500'000 * 1.0001);
    EXPECT_LE(std::abs(position() - target), 100);
    EXPECT_LE(std::abs(e(obj::following_error_actual_value).get<std::int32_t>()), 100);
}

TEST_F(DriveTest, ProfilePositionJerkLimitedNeverExceedsTheLimits) {
    enable(Mode::ProfilePosition);
    set<std::int16_t>(obj::motion_profile_type, 3);
    set<std::uint32_t>(obj::profile_jerk::jerk_1, 50'000'000);
    set<std::uint32_t>(obj::profile_velocity, 400'000);
    set<std::uint32_t>(obj::profile_acceleration, 4'000'000);
    set<std::uint32_t>(obj::profile_deceleration, 2'000'000);
    const std::int32_t start = position();
    std::vector<double> v;
    set<std::int32_t>(obj::target_position, start + 600'000);
    set<std::uint16_t>(obj::controlword, 0x1F);
    run_ms(1);
    set<std::uint16_t>(obj::controlword, 0x0F);
    const double t = run_until([&] { return statusword() & sw::TargetReached; }, 5000,
                               [&] { v.push_back(e(obj::velocity_demand_value).get<std::int32_t>()); });
    ASSERT_GT(t, 0);
    ProfileLimits l{400'000, 4'000'000, 2'000'000, 50'000'000};
    const double expect_ms = ProfileGenerator::rest_to_rest_duration(600'000, l) * 1e3;
    std::printf("PP jerk-limited 6e5 units: target reached after %.0f ms, closed-form profile %.1f ms\n", t,
                expect_ms);
    EXPECT_GE(t + 1, expect_ms);
    EXPECT_LE(t, expect_ms + 40);
    for (std::size_t i = 1; i < v.size(); ++i) {
        EXPECT_LE(v[i], 400'000 * 1.0001);
        // Velocity demand sampled every ms: acceleration within A+ / A- (+1 count rounding per sample).
        EXPECT_LE(v[i] - v[i - 1], 4'000'000 * 1e-3 + 2) << i;
        EXPECT_GE(v[i] - v[i - 1], -2'000'000 * 1e-3 - 2) << i;
    }
    EXPECT_LE(std::abs(position() - (start + 600'000)), 100);
}

TEST_F(DriveTest, ProfilePositionRelativeAndSetOfSetPoints) {
    enable(Mode::ProfilePosition);
    set<std::uint32_t>(obj::profile_velocity, 1'000'000);
    const std::int32_t start = position();
    ASSERT_GT(pp_move(start + 200'000), 0);
    // Relative (bit 6): 0x607A is added to the previous target.
    ASSERT_GT(pp_move(50'000, 0x40), 0);
    EXPECT_NEAR(position(), start + 250'000, 100);
    // Set of set-points (bit 5 = 0): a second set-point during a move is buffered; bit 12 stays set
    // until the buffer is free again.
    set<std::int32_t>(obj::target_position, start + 1'250'000);
    set<std::uint16_t>(obj::controlword, 0x1F);
    run_ms(2);
    set<std::uint16_t>(obj::controlword, 0x0F);
    run_ms(100);
    EXPECT_FALSE(statusword() & sw::Bit12);
    set<std::int32_t>(obj::target_position, start);
    set<std::uint16_t>(obj::controlword, 0x1F);
    run_ms(2);
    set<std::uint16_t>(obj::controlword, 0x0F);
    run_ms(2);
    EXPECT_TRUE(statusword() & sw::Bit12) << "buffered set-point keeps the acknowledge";
    // The first target is reached before the axis returns.
    double furthest = 0;
    const double t =
        run_until([&] { return (statusword() & sw::TargetReached) && !(statusword() & sw::Bit12); }, 10000,
                  [&] { furthest = std::max(furthest, drive().position_actual() - start); });
    ASSERT_GT(t, 0);
    EXPECT_NEAR(furthest, 1'250'000, 200);
    EXPECT_NEAR(position(), start, 100);
}

TEST_F(DriveTest, ProfilePositionChangeImmediately) {
    enable(Mode::ProfilePosition);
    set<std::uint32_t>(obj::profile_velocity, 1'000'000);
    const std::int32_t start = position();
    set<std::int32_t>(obj::target_position, start + 2'000'000);
    set<std::uint16_t>(obj::controlword, 0x3F);
    run_ms(2);
    set<std::uint16_t>(obj::controlword, 0x2F);
    run_ms(300);
    // New target behind: with bit 5 the axis turns around at once.
    set<std::int32_t>(obj::target_position, start + 100'000);
    set<std::uint16_t>(obj::controlword, 0x3F);
    run_ms(2);
    set<std::uint16_t>(obj::controlword, 0x2F);
    double furthest = 0;
    ASSERT_GT(run_until([&] { return statusword() & sw::TargetReached; }, 10000,
                        [&] { furthest = std::max(furthest, drive().position_actual() - start); }),
              0);
    EXPECT_LT(furthest, 1'000'000);
    EXPECT_NEAR(position(), start + 100'000, 100);
}

TEST_F(DriveTest, VelocityOverrideAndPositionCompensationOfTheProfileModes) {
    enable(Mode::ProfilePosition);
    set<std::uint32_t>(obj::profile_velocity, 400'000);
    set<std::uint32_t>(0x2110, 500'000);  // 50 %
    const std::int32_t start = position();
    double peak = 0;
    set<std::int32_t>(obj::target_position, start + 800'000);
    set<std::uint16_t>(obj::controlword, 0x1F);
    run_ms(1);
    set<std::uint16_t>(obj::controlword, 0x0F);
    run_until([&] { return position() > start + 400'000; }, 5000,
              [&] { peak = std::max(peak, e(obj::velocity_demand_value).get<std::int32_t>() * 1.0); });
    EXPECT_NEAR(peak, 200'000, 200);
    // Back to 100 %: the cruise velocity returns to V.
    set<std::uint32_t>(0x2110, 1'000'000);
    run_ms(150);
    EXPECT_NEAR(e(obj::velocity_demand_value).get<std::int32_t>(), 400'000, 200);
    ASSERT_GT(run_until([&] { return statusword() & sw::TargetReached; }, 5000), 0);
    EXPECT_NEAR(position(), start + 800'000, 100);
    // Position compensation: 50000 extra within a length of 400000 of a 1e6 move.
    master::CoeClient c(b.master, 0x1001);
    ASSERT_EQ(c.download_value<std::int32_t>(0x2111, 1, 50'000).abort, protocol::SdoAbort::None);
    ASSERT_EQ(c.download_value<std::uint32_t>(0x2111, 2, 400'000).abort, protocol::SdoAbort::None);
    set<std::int32_t>(obj::target_position, start + 1'800'000);
    set<std::uint16_t>(obj::controlword, 0x1F);
    run_ms(200);
    set<std::uint16_t>(obj::controlword, 0x0F);
    ASSERT_EQ(c.download_value<std::uint8_t>(0x2111, 3, 1).abort, protocol::SdoAbort::None);
    ASSERT_GT(run_until([&] { return statusword() & sw::TargetReached; }, 10000), 0);
    EXPECT_NEAR(position(), start + 1'850'000, 100);
}

TEST_F(DriveTest, ProfileVelocityReachesTheTargetAndHaltShowsSpeedZero) {
    enable(Mode::ProfileVelocity);
    set<std::uint32_t>(obj::profile_acceleration, 2'000'000);
    set<std::uint32_t>(obj::profile_deceleration, 2'000'000);
    set<std::int32_t>(obj::target_velocity, 300'000);
    const double t = run_until([&] { return statusword() & sw::TargetReached; }, 2000);
    // 0.15 s ramp, then the velocity window time (10 ms).
    EXPECT_GT(t, 140);
    EXPECT_LT(t, 220);
    EXPECT_NEAR(velocity(), 300'000, 1000);
    EXPECT_FALSE(statusword() & sw::Bit12);       // speed is not zero
    set<std::uint16_t>(obj::controlword, 0x10F);  // halt
    const double stop = run_until([&] { return statusword() & sw::Bit12; }, 2000);
    EXPECT_GT(stop, 140);
    EXPECT_LT(stop, 230);
    EXPECT_TRUE(statusword() & sw::TargetReached);
    EXPECT_LT(std::abs(velocity()), 20);
}

TEST_F(DriveTest, ProfileTorqueRampsWithTheSlopeAndAcceleratesTheInertia) {
    enable(Mode::ProfileTorque);
    set<std::uint32_t>(obj::max_profile_velocity,
                       200'000'000);              // the speed limit (0x6080, 5000 rpm) stays out of the way
    set<std::uint32_t>(obj::torque_slope, 1000);  // per mille per second
    set<std::int16_t>(obj::target_torque, 100);   // 10 % of 1.27 Nm
    run_ms(50);
    const double half = e(obj::torque_demand).get<std::int16_t>();
    EXPECT_NEAR(half, 50, 2);
    EXPECT_FALSE(statusword() & sw::TargetReached);
    run_ms(60);
    EXPECT_TRUE(statusword() & sw::TargetReached);
    // Constant 0.127 Nm on 3.6e-5 kg m^2 (minus friction 0.01 Nm): a = 3250 rad/s^2.
    const double v0 = drive().mechanics().velocity();
    run_ms(10);
    const double a = (drive().mechanics().velocity() - v0) / 0.01;
    EXPECT_NEAR(a, (0.127 - 0.01 - 5e-5 * drive().mechanics().velocity()) / 3.6e-5, 150);
}

TEST_F(DriveTest, QuickStopDeceleratesWithTheQuickStopRampAndDisables) {
    enable(Mode::ProfileVelocity);
    set<std::uint32_t>(obj::profile_acceleration, 10'000'000);
    set<std::int32_t>(obj::target_velocity, 500'000);
    run_ms(200);
    ASSERT_NEAR(velocity(), 500'000, 2000);
    set<std::uint32_t>(obj::quick_stop_deceleration, 5'000'000);
    set<std::uint16_t>(obj::controlword, 0x0B);  // quick stop
    run_ms(1);
    EXPECT_EQ(cia::decode_state(statusword()), cia::State::QuickStopActive);  // quick stop active
    const double t =
        run_until([&] { return cia::decode_state(statusword()) == cia::State::SwitchOnDisabled; }, 2000);
    EXPECT_GT(t, 90);  // 500000 / 5e6 = 100 ms
    EXPECT_LT(t, 130);
    EXPECT_EQ(drive().cia402_state(), State::SwitchOnDisabled);
}

TEST_F(DriveTest, SoftwareLimitStopsTheMoveAndSetsInternalLimit) {
    enable(Mode::ProfilePosition);
    // 0x2112 = 2: a target beyond 0x607D is clamped to the limit (the vecat drive refuses it by default:
    // tests/conformance/test_tx1250_nc_ptp.cpp).
    set<std::uint8_t>(0x2112, 2);
    const std::int32_t start = position();
    set<std::int32_t>(obj::software_position_limit::min, start - 100'000);
    set<std::int32_t>(obj::software_position_limit::max, start + 300'000);
    set<std::uint32_t>(obj::profile_velocity, 1'000'000);
    ASSERT_GT(pp_move(start + 2'000'000), 0);
    EXPECT_NEAR(position(), start + 300'000, 100);
    EXPECT_TRUE(statusword() & sw::InternalLimit);
    // Opposite direction accepted.
    ASSERT_GT(pp_move(start), 0);
    EXPECT_NEAR(position(), start, 100);
    EXPECT_FALSE(statusword() & sw::InternalLimit);
}

// The TX1250 objects through the dictionary (their behaviours: tests/conformance/test_tx1250_nc_ptp.cpp).
// 0x2112 = 0 by default: a target beyond 0x607D is not acknowledged and faults with 0x8612.
TEST_F(DriveTest, TargetBeyondTheSoftwareLimitFaultsWith8612) {
    enable(Mode::ProfilePosition);
    EXPECT_EQ(e(0x2112).get<std::uint8_t>(), 0);
    const std::int32_t start = position();
    set<std::int32_t>(obj::software_position_limit::min, start - 100'000);
    set<std::int32_t>(obj::software_position_limit::max, start + 300'000);
    set<std::int32_t>(obj::target_position, start + 2'000'000);
    set<std::uint16_t>(obj::controlword, 0x1F);
    bool acknowledged = false;
    ASSERT_GT(run_until([&] { return drive().cia402_state() == State::Fault; }, 500,
                        [&] { acknowledged = acknowledged || (statusword() & sw::Bit12); }),
              0);
    EXPECT_FALSE(acknowledged);
    EXPECT_EQ(e(obj::error_code).get<std::uint16_t>(), fault::ReferenceLimit);
    EXPECT_NEAR(position(), start, 100);
}

// 0x607B makes the axis modulo (0x6064 in the range), 0x60F2 bit 7 only positive; 0x2114 with mode 1
// makes the next set-point "new velocity and new end position" (case 2: VNew at once).
TEST_F(DriveTest, ModuloRangeDirectionOptionAndNewVelocityObjects) {
    constexpr std::int32_t R = 1 << 20;
    set<std::int32_t>(obj::position_range_limit::min, 0);
    set<std::int32_t>(obj::position_range_limit::max, R);
    set<std::uint16_t>(obj::positioning_option_code, 0x80);
    enable(Mode::ProfilePosition);
    set<std::uint32_t>(obj::profile_velocity, 400'000);
    ASSERT_GE(position(), 0);
    ASSERT_LT(position(), R);
    const double from = drive().position_actual();
    const std::int32_t target = (position() + R - R / 4) % R;  // a quarter behind: 3/4 R forward
    double vmin = 0;
    ASSERT_GT(pp_move(target), 0);
    EXPECT_NEAR(position(), target, 100);
    EXPECT_NEAR(drive().position_actual() - from, 0.75 * R, 100);
    // APos an eighth of the range behind the axis (in the range: the nearest position), EPos half a range
    // ahead: case 2, VNew = 100000 at once.
    set<std::int32_t>(0x2114, (position() + R - R / 8) % R, 1);
    set<std::uint32_t>(0x2114, 100'000, 2);
    set<std::uint8_t>(0x2114, 1, 3);
    set<std::uint16_t>(obj::positioning_option_code, 0x80);
    set<std::int32_t>(obj::target_position, (position() + R / 2) % R);
    set<std::uint16_t>(obj::controlword, 0x1F);
    run_ms(300);
    EXPECT_NEAR(e(obj::velocity_demand_value).get<std::int32_t>(), 100'000, 200);
    set<std::uint16_t>(obj::controlword, 0x0F);
    ASSERT_GT(
        run_until([&] { return statusword() & sw::TargetReached; }, 10000,
                  [&] { vmin = std::min<double>(vmin, e(obj::velocity_demand_value).get<std::int32_t>()); }),
        0);
    EXPECT_GE(vmin, 0);
}

// 0x2111:4-8: the compensation's velocity increase limits the distance; the compensation stop.
TEST_F(DriveTest, PositionCompensationDynamicsAndStopObjects) {
    enable(Mode::ProfilePosition);
    set<std::uint32_t>(obj::profile_velocity, 400'000);
    const std::int32_t start = position();
    master::CoeClient c(b.master, 0x1001);
    // D = 200000 over L = 400000 at VP = 400000 (T = 1 s) with VK = 50000: at most about 50000.
    ASSERT_EQ(c.download_value<std::int32_t>(0x2111, 1, 200'000).abort, protocol::SdoAbort::None);
    ASSERT_EQ(c.download_value<std::uint32_t>(0x2111, 2, 400'000).abort, protocol::SdoAbort::None);
    ASSERT_EQ(c.download_value<std::uint32_t>(0x2111, 4, 400'000).abort, protocol::SdoAbort::None);
    ASSERT_EQ(c.download_value<std::uint32_t>(0x2111, 5, 50'000).abort, protocol::SdoAbort::None);
    set<std::int32_t>(obj::target_position, start + 1'800'000);
    set<std::uint16_t>(obj::controlword, 0x1F);
    run_ms(200);
    set<std::uint16_t>(obj::controlword, 0x0F);
    ASSERT_EQ(c.download_value<std::uint8_t>(0x2111, 3, 1).abort, protocol::SdoAbort::None);
    ASSERT_GT(run_until([&] { return statusword() & sw::TargetReached; }, 10000), 0);
    const double first = position() - (start + 1'800'000);
    EXPECT_GT(first, 40'000);
    EXPECT_LT(first, 50'500);
    // The same, stopped early with 0x2111:8: less is compensated.
    const std::int32_t again = position();
    set<std::int32_t>(obj::target_position, again + 1'800'000);
    set<std::uint16_t>(obj::controlword, 0x1F);
    run_ms(200);
    set<std::uint16_t>(obj::controlword, 0x0F);
    ASSERT_EQ(c.download_value<std::uint8_t>(0x2111, 3, 1).abort, protocol::SdoAbort::None);
    run_ms(300);
    ASSERT_EQ(c.download_value<std::uint8_t>(0x2111, 8, 1).abort, protocol::SdoAbort::None);
    EXPECT_EQ(e(0x2111, 8).get<std::uint8_t>(), 0);
    ASSERT_GT(run_until([&] { return statusword() & sw::TargetReached; }, 10000), 0);
    const double second = position() - (again + 1'800'000);
    EXPECT_GT(second, 5'000);
    EXPECT_LT(second, first - 10'000);
}

TEST_F(DriveTest, HardwareLimitSwitchBlocksItsDirectionOnly) {
    const std::int32_t start = position();
    set<std::int32_t>(0x2100, start + 200'000, 2);  // positive limit switch (increments = user units here)
    enable(Mode::ProfileVelocity);
    set<std::uint32_t>(obj::profile_acceleration, 5'000'000);
    set<std::uint32_t>(obj::quick_stop_deceleration, 20'000'000);
    set<std::int32_t>(obj::target_velocity, 400'000);
    ASSERT_GT(run_until([&] { return e(obj::digital_inputs).get<std::uint32_t>() & 2; }, 3000), 0);
    run_ms(100);
    EXPECT_LT(std::abs(velocity()), 50);
    EXPECT_TRUE(statusword() & sw::InternalLimit);
    EXPECT_LT(position(), start + 200'000 + 10'000);  // 400000^2 / (2 * 2e7) = 4000 past the switch
    set<std::int32_t>(obj::target_velocity, -400'000);
    ASSERT_GT(run_until([&] { return !(e(obj::digital_inputs).get<std::uint32_t>() & 2); }, 3000), 0);
    run_ms(20);
    EXPECT_LT(velocity(), -100'000);
    EXPECT_FALSE(statusword() & sw::InternalLimit);
}

TEST_F(DriveTest, FollowingErrorFaultsWith8611AndAnEmergency) {
    enable(Mode::CyclicPosition);
    set<std::uint32_t>(obj::following_error_window, 10'000);
    set<std::uint16_t>(obj::following_error_time_out, 5);
    set<std::uint16_t>(obj::max_torque, 50);  // weak motor: it cannot follow a big step
    set<std::int32_t>(obj::target_position, position() + 5'000'000);
    ASSERT_GT(run_until([&] { return drive().cia402_state() == State::Fault; }, 500), 0);
    EXPECT_EQ(e(obj::error_code).get<std::uint16_t>(), fault::FollowingError);
    EXPECT_TRUE(e(0x1001).get<std::uint8_t>() & coe::error_register::DeviceProfile);
    EXPECT_EQ(cia::decode_state(statusword()), cia::State::Fault);
    master::CoeClient c(b.master, 0x1001);
    c.upload(0x1000, 0);
    bool seen = false;
    for (const auto& em : c.emergencies())
        seen |= em.error_code == fault::FollowingError;
    EXPECT_TRUE(seen);
}

TEST_F(DriveTest, InjectedFaultNeedsTheCauseGoneBeforeReset) {
    enable(Mode::ProfileVelocity);
    master::CoeClient c(b.master, 0x1001);
    EXPECT_EQ(c.download_value<std::uint16_t>(0x2101, 0, 0x1234).abort, protocol::SdoAbort::ValueRange);
    ASSERT_EQ(c.download_value<std::uint16_t>(0x2101, 0, fault::Encoder).abort, protocol::SdoAbort::None);
    run_ms(2);
    EXPECT_EQ(drive().cia402_state(), State::Fault);
    EXPECT_EQ(e(obj::error_code).get<std::uint16_t>(), fault::Encoder);
    set<std::uint16_t>(obj::controlword, 0x80);
    run_ms(2);
    EXPECT_EQ(drive().cia402_state(), State::Fault) << "reset refused while the encoder is broken";
    set<std::uint16_t>(obj::controlword, 0x00);
    ASSERT_EQ(c.download_value<std::uint16_t>(0x2101, 0, 0).abort, protocol::SdoAbort::None);
    run_ms(1);
    set<std::uint16_t>(obj::controlword, 0x80);
    run_ms(2);
    EXPECT_EQ(drive().cia402_state(), State::SwitchOnDisabled);
    EXPECT_EQ(e(obj::error_code).get<std::uint16_t>(), 0);
    EXPECT_EQ(e(0x1001).get<std::uint8_t>(), 0);
    c.upload(0x1000, 0);
    c.upload(0x1000, 0);
    ASSERT_FALSE(c.emergencies().empty());
    EXPECT_EQ(c.emergencies().front().error_code, fault::Encoder);
    EXPECT_EQ(c.emergencies().back().error_code, 0x0000);  // error reset
}

TEST_F(DriveTest, StalledMotorAtFullTorqueTripsTheOverCurrentProtection) {
    // A load that holds the motor: 300 % torque (6.35 A, over twice the rated 3 A) against a 300 % load.
    set<std::int16_t>(0x2100, 3000, 5);
    enable(Mode::CyclicTorque);
    set<std::int16_t>(obj::target_torque, 3000);
    const double t = run_until([&] { return drive().cia402_state() == State::Fault; }, 10000);
    // I2t: (i^2 - rated^2) t = (peak^2 - rated^2) * 1 s  ->  t = 72 / (6.35^2 - 9) = 2.34 s.
    EXPECT_NEAR(t, 2340, 60);
    EXPECT_EQ(e(obj::error_code).get<std::uint16_t>(), fault::OverCurrent);
    EXPECT_TRUE(e(0x1001).get<std::uint8_t>() & coe::error_register::Current);
}

TEST_F(DriveTest, TouchProbeLatchesTheIndexPulseExactly) {
    enable(Mode::ProfileVelocity);
    // TP1 enabled, single, trigger on the zero impulse, positive edge.
    set<std::uint16_t>(obj::touch_probe_function, 0x0015);
    set<std::int32_t>(obj::target_velocity, 200'000);
    const std::int32_t start = position();
    ASSERT_GT(run_until([&] { return e(obj::touch_probe_status).get<std::uint16_t>() & 0x02; }, 6000), 0);
    const std::int32_t latched = e(obj::touch_probe_1_positive_value).get<std::int32_t>();
    // The index comes once per revolution (2^20 increments, 1:1 user units).
    EXPECT_EQ(latched % (1 << 20), 0) << latched;
    EXPECT_GT(latched, start);
    EXPECT_LE(latched, start + (1 << 20));
    EXPECT_EQ(e(obj::touch_probe_status).get<std::uint16_t>() & 0x07, 0x03);
    // Single mode: the next index does not overwrite it.
    run_ms(6000);
    EXPECT_EQ(e(obj::touch_probe_1_positive_value).get<std::int32_t>(), latched);
}

TEST_F(DriveTest, TouchProbeOnTheDigitalInput) {
    enable(Mode::ProfileVelocity);
    set<std::uint16_t>(obj::touch_probe_function, 0x0033);  // TP1 enabled, continuous, input, both edges
    set<std::int32_t>(obj::target_velocity, 100'000);
    run_ms(300);
    set<std::uint8_t>(0x2100, 1, 6);
    run_ms(1);
    const std::int32_t rise = e(obj::touch_probe_1_positive_value).get<std::int32_t>();
    EXPECT_NEAR(rise, position(), 200);
    EXPECT_TRUE(e(obj::digital_inputs).get<std::uint32_t>() & (1u << 16));
    run_ms(100);
    set<std::uint8_t>(0x2100, 0, 6);
    run_ms(1);
    EXPECT_NEAR(e(obj::touch_probe_1_negative_value).get<std::int32_t>() - rise, 10'000,
                300);  // 100 ms at 100000/s
    EXPECT_EQ(e(obj::touch_probe_status).get<std::uint16_t>() & 0x07, 0x07);
}

TEST_F(DriveTest, FactorGroupConvertsUserUnitsExactly) {
    // 1 user unit = 1 um with a 5 mm feed per revolution: 2^20 increments per 5000 units.
    set<std::uint32_t>(obj::feed_constant::feed, 5000);
    run_ms(1);
    enable(Mode::ProfilePosition);
    const std::int32_t start = position();
    set<std::uint32_t>(obj::profile_velocity, 10'000);
    set<std::uint32_t>(obj::profile_acceleration, 100'000);
    set<std::uint32_t>(obj::profile_deceleration, 100'000);
    set<std::uint32_t>(obj::position_window, 1);
    ASSERT_GT(pp_move(start + 5000), 0);
    // 5000 user units = one revolution of the motor = 2^20 increments.
    EXPECT_NEAR(static_cast<double>(e(obj::position_actual_internal_value).get<std::int32_t>()) -
                    start * 1048576.0 / 5000,
                1 << 20, 210);
    EXPECT_EQ(position(), start + 5000);
    EXPECT_NEAR(drive().mechanics().position() / (2 * 3.14159265358979), (start + 5000) / 5000.0, 1e-4);
}

// Bad input: random values written into every drive object (as a master could by SDO or PDO) while the
// drive is enabled and moving never produce NaN, a crash or a hang; the drive keeps answering.
TEST_F(DriveTest, RandomValuesInEveryDriveObjectNeverBreakTheSimulation) {
    std::vector<coe::Entry*> targets;
    for (auto& o : od().objects())
        if ((o.index() >= 0x2000 && o.index() < 0x2200) || (o.index() >= 0x6000 && o.index() < 0x7000))
            for (auto& en : o.entries())
                if (en.subindex() != 0 || o.entries().size() == 1)
                    if (en.capacity() <= 8) targets.push_back(const_cast<coe::Entry*>(&en));
    ASSERT_GT(targets.size(), 60u);
    std::mt19937 rng(402);
    for (int round = 0; round < 3000; ++round) {
        if (round % 200 == 0) {
            set<std::uint16_t>(obj::controlword, 0x80);
            run_ms(1);
            set<std::uint16_t>(obj::controlword, 0x06);
            run_ms(1);
            set<std::uint16_t>(obj::controlword, 0x0F);
        }
        coe::Entry* en = targets[rng() % targets.size()];
        std::uint8_t v[8];
        for (auto& x : v)
            x = static_cast<std::uint8_t>(rng());
        // Half of the values small, so that modes and option codes are hit often.
        if (rng() % 2) std::fill(v + 1, v + 8, static_cast<std::uint8_t>((v[0] & 0x80) ? 0xFF : 0));
        en->assign(ConstBytes(v, en->capacity()));
        run_ms(static_cast<double>(1 + rng() % 5));
        ASSERT_TRUE(std::isfinite(drive().position_actual())) << round;
        ASSERT_TRUE(std::isfinite(drive().velocity_actual())) << round;
        ASSERT_TRUE(std::isfinite(drive().position_demand())) << round;
        ASSERT_TRUE(std::isfinite(drive().mechanics().velocity())) << round;
    }
    master::CoeClient c(b.master, 0x1001);
    EXPECT_TRUE(c.upload(obj::statusword.index, 0).ok());
}

// Homing (0x6098) on the simulated switches and index pulse; the found home then reads as 0x607C.
struct DriveHoming : DriveTest {
    void home(std::int8_t method, std::int32_t offset) {
        set<std::int8_t>(obj::homing_method, method);
        set<std::int32_t>(obj::home_offset, offset);
        set<std::uint32_t>(obj::homing_speeds::search_for_switch, 400'000);
        set<std::uint32_t>(obj::homing_speeds::search_for_zero, 50'000);
        set<std::uint32_t>(obj::homing_acceleration, 4'000'000);
        enable(Mode::Homing);
        EXPECT_EQ(statusword() & (sw::TargetReached | sw::Bit12 | sw::Bit13),
                  sw::TargetReached);  // not started
        set<std::uint16_t>(obj::controlword, 0x1F);
        elapsed = run_until(
            [&] {
                return (statusword() & (sw::TargetReached | sw::Bit12)) == (sw::TargetReached | sw::Bit12) ||
                       (statusword() & sw::Bit13);
            },
            30000);
    }
    // User position of machine increment inc after homing (1:1 factors).
    std::int64_t user_of(std::int64_t inc) {
        return inc + (position() - e(obj::position_actual_internal_value).get<std::int32_t>());
    }
    double elapsed = 0;
};

TEST_F(DriveHoming, Method37TakesTheCurrentPositionAtOnce) {
    const std::int32_t inc = e(obj::position_actual_internal_value).get<std::int32_t>();
    home(37, 12'345);
    EXPECT_GE(elapsed, 0);
    EXPECT_LE(elapsed, 2);
    EXPECT_EQ(statusword() & (sw::TargetReached | sw::Bit12 | sw::Bit13), sw::TargetReached | sw::Bit12);
    EXPECT_EQ(user_of(inc), 12'345);
    EXPECT_EQ(position(), 12'345);
}

TEST_F(DriveHoming, Method35IsTheSameAsMethod37) {
    home(35, -7);
    EXPECT_TRUE(statusword() & sw::Bit12);
    EXPECT_EQ(position(), -7);
}

TEST_F(DriveHoming, Method1NegativeLimitSwitchAndIndexPulse) {
    set<std::int32_t>(0x2100, -300'000, 1);  // negative limit switch (increments)
    home(1, 1000);
    ASSERT_GT(elapsed, 0) << std::hex << statusword();
    EXPECT_FALSE(statusword() & sw::Bit13);
    // The first index pulse to the right of the switch: machine increment 0 (one per 2^20).
    EXPECT_EQ(user_of(0), 1000);
    EXPECT_FALSE(e(obj::digital_inputs).get<std::uint32_t>() & 1) << "ends off the limit switch";
}

TEST_F(DriveHoming, Method3HomeSwitchAndIndexPulse) {
    set<std::int32_t>(0x2100, 1'500'000, 3);  // home switch active from 1.5e6 increments up
    home(3, 0);
    ASSERT_GT(elapsed, 0) << std::hex << statusword();
    EXPECT_FALSE(statusword() & sw::Bit13);
    // Method 3: the first index pulse left of the rising edge of the positive home switch: 2^20.
    EXPECT_EQ(user_of(1 << 20), 0);
}

TEST_F(DriveHoming, Method19HomeSwitchEdgeWithinOneSlowCycle) {
    set<std::int32_t>(0x2100, 500'000, 3);
    home(19, 0);
    ASSERT_GT(elapsed, 0);
    // The edge itself is home: found within one servo period at the zero-search speed (50000 * 250 us).
    EXPECT_NEAR(static_cast<double>(user_of(500'000)), 0.0, 50'000 * 250e-6 + 2);
}

TEST_F(DriveHoming, UnsupportedMethodReportsAHomingError) {
    home(15, 0);
    EXPECT_TRUE(statusword() & sw::Bit13);
    EXPECT_FALSE(statusword() & sw::Bit12);
}

TEST(FactorGroup, ConvertsExactlyAndRefusesFactorsBeyond62Bits) {
    FactorGroup f;  // 2^20 increments per revolution, feed 5000 units per revolution, gear 3:7
    f.feed = 5000;
    f.gear_motor_revolutions = 3;
    f.gear_shaft_revolutions = 7;
    ASSERT_TRUE(f.valid());
    // increments per unit = 2^20 * 3 / (7 * 5000) = 3145728 / 35000, reduced by 8: 393216 / 4375.
    EXPECT_EQ(f.numerator(), 393216);
    EXPECT_EQ(f.denominator(), 4375);
    EXPECT_EQ(f.user_to_increments(4375), 393216);
    EXPECT_EQ(f.user_to_increments(-1), -90);  // floor(-89.88)
    EXPECT_EQ(f.increments_to_user(393216), 4375);
    EXPECT_EQ(f.increments_to_user(f.user_to_increments(123'456'789)), 123'456'788);  // floor both ways
    // Products of three 32-bit factors that do not reduce: refused instead of overflowing.
    f.encoder_increments = 4'294'967'291u;  // primes
    f.gear_motor_revolutions = 4'294'967'279u;
    f.feed_shaft_revolutions = 4'294'967'231u;
    EXPECT_FALSE(f.valid());
    EXPECT_EQ(f.numerator(), 1);
    f.feed = 0;
    EXPECT_FALSE(f.valid());
}

// End to end: the cyclic modes through process data in OP, as a master runs them.
struct DriveCyclic : DriveTest {
    void SetUp() override {
        std::string why;
        ASSERT_TRUE(b.master.startup(protocol::AlState::Op, &why)) << why;
    }
    Bytes out() { return b.master.outputs(0); }
    ConstBytes in() { return b.master.inputs(0); }
    void cycle(std::uint16_t cw, std::int8_t mode, std::int32_t pos, std::int32_t vel = 0,
               std::int16_t torque = 0) {
        auto o = out();
        st_le16(o.data(), cw);
        o[2] = static_cast<std::uint8_t>(mode);
        st_le32(o.data() + 4, static_cast<std::uint32_t>(pos));
        st_le32(o.data() + 8, static_cast<std::uint32_t>(vel));
        st_le16(o.data() + 12, static_cast<std::uint16_t>(torque));
        ASSERT_EQ(b.master.exchange_process_data().value_or(0), b.master.expected_wkc());
        b.advance(kMs);
    }
    std::uint16_t sw_in() { return ld_le16(in().data()); }
    std::int32_t pos_in() { return static_cast<std::int32_t>(ld_le32(in().data() + 4)); }
    std::int32_t vel_in() { return static_cast<std::int32_t>(ld_le32(in().data() + 8)); }
};

TEST_F(DriveCyclic, CyclicSynchronousPositionFollowsASineWithSmallFollowingError) {
    cycle(0, 8, 0);
    const std::int32_t p0 = pos_in();
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        for (int i = 0; i < 3; ++i)
            cycle(cw, 8, p0);
    ASSERT_EQ(cia::decode_state(sw_in()), cia::State::OperationEnabled);
    EXPECT_TRUE(sw_in() & sw::Bit12);
    double worst = 0, worst_lag = 0;
    const double amp = 500'000, w = 2 * 3.14159265358979;  // 1 Hz, peak velocity 3.1e6 units/s
    std::int32_t sent = p0;
    for (int k = 0; k < 2000; ++k) {
        const double t = k * 1e-3;
        const std::int32_t previous = sent;
        sent = p0 + static_cast<std::int32_t>(std::lround(amp * (1 - std::cos(w * t))));
        cycle(0x0F, 8, sent);
        worst = std::max(worst,
                         std::abs(static_cast<double>(static_cast<std::int32_t>(ld_le32(in().data() + 14)))));
        // The actual position lies within the last interpolation segment (plus the following error).
        const double lo = std::min(previous, sent) - worst, hi = std::max(previous, sent) + worst;
        worst_lag = std::max(worst_lag, std::max(lo - pos_in(), pos_in() - hi));
    }
    // With velocity and acceleration feed-forward the position loop error stays below 0.5 % of the
    // amplitude; without it, it would be v/kp = 3.1e6 / 100 = 31000.
    EXPECT_LT(worst, 2500);
    EXPECT_GT(worst, 0);
    EXPECT_LE(worst_lag, 1);
    EXPECT_FALSE(sw_in() & sw::Bit13);
}

TEST_F(DriveCyclic, CyclicSynchronousVelocityAndTorque) {
    cycle(0, 9, 0);
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        for (int i = 0; i < 3; ++i)
            cycle(cw, 9, 0, 0);
    for (int k = 0; k < 300; ++k)
        cycle(0x0F, 9, 0, 250'000);
    EXPECT_NEAR(vel_in(), 250'000, 2500);
    // CST from 5e6 units/s (30 rad/s): -2 % torque (-0.0254 Nm) plus friction (0.01 Nm + viscous) brakes
    // the axis at about 1000 rad/s^2.
    for (int k = 0; k < 300; ++k)
        cycle(0x0F, 9, 0, 5'000'000);
    const double w0 = drive().mechanics().velocity();
    for (int k = 0; k < 10; ++k)
        cycle(0x0F, 10, 0, 0, -20);
    const double decel = (w0 - drive().mechanics().velocity()) / 0.010;
    EXPECT_NEAR(decel, (0.0254 + 0.01 + 5e-5 * w0) / 3.6e-5, 60);
    EXPECT_NEAR(static_cast<std::int16_t>(ld_le16(in().data() + 12)), -20, 1);
}

// In DC synchronous mode (0x1C32:01 = 2) the outputs take effect at the next SYNC0, not when the frame
// comes: the drive's set-points are then sampled on the SYNC0 grid whatever the frames' jitter. In free
// run they are taken at once. Runs on the host's clock (SYNC0 every 1 ms); a try on which a SYNC0 fell
// during the exchange itself is repeated. A stall of a loaded test machine of some 100 ms between two
// exchanges takes the drive to SAFEOP, as it would a real one (SM watchdog 0x001B, or in DC mode the sync
// monitoring 0x002C): the whole check then starts over on a new line.
TEST(DriveSync, OutputsTakeEffectAtSync0InDcModeAndAtOnceInFreeRun) {
    // One attempt; false if the slave left OP on the way.
    const auto attempt = [](bool dc) {
        auto dev = device::default_drive();
        auto seg = make_drive_segment(dev, 1);
        net::InProcessLink link(*seg);  // host time: SYNC0 pulses come as time passes
        master::MasterOptions mo;
        mo.dc.enable = dc;
        mo.dc.sync0_cycle_ns = 1'000'000;
        mo.dc.static_drift_frames = 10;
        mo.dc.start_delay_ns = 5'000'000;
        master::Master m(link, mo);
        std::string why;
        if (!m.startup(protocol::AlState::Op, &why)) {
            ADD_FAILURE() << why;
            return true;  // not a stall: no new attempt
        }
        const auto in_op = [&] { return seg->slave(0).state() == protocol::AlState::Op; };
        auto& od = dynamic_cast<Drive&>(seg->slave(0).app()).dictionary();
        EXPECT_EQ(od.find(0x1C32, 1)->get<std::uint16_t>(), dc ? 2 : 1);
        const auto& pulses = seg->slave(0).esc().dc().counters().sync_pulses[0];
        for (std::int32_t target = 1000; target < 1100; ++target) {
            st_le32(m.outputs(0).data() + 4, static_cast<std::uint32_t>(target));
            const auto before = pulses;
            const auto wkc = m.exchange_process_data().value_or(0);
            if (!in_op()) return false;
            EXPECT_EQ(wkc, m.expected_wkc());
            if (pulses != before) continue;  // a SYNC0 fell during the exchange
            const std::int32_t now = od.find(obj::target_position)->get<std::int32_t>();
            if (!dc) {
                EXPECT_EQ(now, target);
                return true;
            }
            EXPECT_NE(now, target);
            // Past the next SYNC0 (the firmware runs on the next frame).
            std::this_thread::sleep_for(std::chrono::microseconds(1200));
            const auto wkc2 = m.exchange_process_data().value_or(0);
            if (!in_op()) return false;
            EXPECT_EQ(wkc2, m.expected_wkc());
            EXPECT_GT(pulses, before);
            EXPECT_EQ(od.find(obj::target_position)->get<std::int32_t>(), target);
            return true;
        }
        ADD_FAILURE() << "a SYNC0 fell during each of 100 exchanges";
        return true;
    };
    for (const bool dc : {true, false}) {
        SCOPED_TRACE(dc ? "DC SYNC0" : "free run");
        bool done = false;
        for (int i = 0; i < 5 && !done; ++i)
            done = attempt(dc);
        EXPECT_TRUE(done) << "the slave left OP in each of 5 attempts";
    }
}

}  // namespace
}  // namespace vecat::cia402
