// Conformance to the Beckhoff TwinCAT 2 NC PTP manual TX1250 (../shared/seeds/002_e8a90447e16f9bd4.txt):
// the profile generator of the drive's profile modes follows the NC's master axis (chapter 2), and two
// drives coupled by TWINsync behave as its master/slave groups (chapter 3). One test per behaviour, named
// after the section it checks. About 600 lines: the manual's sections in one file, in its order, so that
// the index in README.md points to one place (the benches of chapter 3 are small fixtures on TwinBench).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <vector>

#include "device/drive_objects.hpp"
#include "drive_core_bench.hpp"
#include "master/coe_client.hpp"
#include "unit/cia402/twin_bench.hpp"

namespace vecat::cia402::conformance {
namespace {

struct Tx1250 : DriveCoreBench {
    // A profile position move started with the bit 4 handshake.
    void start_move(std::int32_t target, std::uint16_t extra = 0) {
        io.command.target_position = target;
        io.command.controlword = cmd::EnableOperation | cw::NewSetpoint | extra;
        run_ms(1);
        io.command.controlword = cmd::EnableOperation;
    }
    double demand_velocity() const { return io.feedback.velocity_demand; }
    // Runs until target reached (at most limit_ms), calling each(ms) after every millisecond.
    template <class F>
    void run_to_target(int limit_ms, F&& each) {
        for (int ms = 0; ms < limit_ms && !target_reached(); ++ms) {
            run_ms(1);
            each(ms);
        }
    }
    // The largest demand velocity until target reached.
    double peak_velocity(int limit_ms) {
        double peak = 0;
        run_to_target(limit_ms, [&](int) { peak = std::max(peak, std::abs(demand_velocity())); });
        return peak;
    }
};

// 2.1 Start parameters, note 4: "If the target position P is outside of the software limit switches
// (Pmin, Pmax), the start is refused and an error is generated." A profile position target beyond 0x607D
// is not acknowledged (statusword bit 12 stays 0), the axis does not move, and the drive faults with 0x8612
// (0x2112 = 0, the vecat drive's default).
TEST_F(Tx1250, Tx1250_2_1_TargetBeyondTheSoftwareLimitIsRefusedWithAnError) {
    io.parameters.software_limit_min = -4 * kRev;
    io.parameters.software_limit_max = 4 * kRev;
    io.parameters.software_limit_reaction = limit_reaction::Fault;
    enable(Mode::ProfilePosition);
    const std::int32_t start = io.feedback.position_actual;
    io.command.target_position = 6 * kRev;
    io.command.controlword = cmd::EnableOperation | cw::NewSetpoint;
    std::uint16_t raised = 0;
    bool acknowledged = false;
    for (int i = 0; i < 400; ++i) {
        core.step(io);
        if (io.feedback.raised) raised = io.feedback.raised->code;
        acknowledged = acknowledged || (io.feedback.statusword & sw::Bit12);
    }
    EXPECT_FALSE(acknowledged);
    EXPECT_EQ(raised, fault::ReferenceLimit);
    EXPECT_EQ(core.state(), State::Fault);
    EXPECT_NEAR(io.feedback.position_actual, start, 50) << "the start is refused: no motion";
}

// The same refusal without the error (0x2112 = 1): no acknowledge, bit 11 "internal limit active" while
// the refused set-point is the last one; the next target within the limits is accepted and reached.
TEST_F(Tx1250, Tx1250_2_1_TargetBeyondTheSoftwareLimitIsRefusedWithoutFault) {
    io.parameters.software_limit_min = -4 * kRev;
    io.parameters.software_limit_max = 4 * kRev;
    io.parameters.software_limit_reaction = limit_reaction::Refuse;
    enable(Mode::ProfilePosition);
    io.command.target_position = -5 * kRev;
    io.command.controlword = cmd::EnableOperation | cw::NewSetpoint;
    run_ms(50);
    EXPECT_FALSE(io.feedback.statusword & sw::Bit12);
    EXPECT_TRUE(io.feedback.statusword & sw::InternalLimit);
    EXPECT_EQ(core.state(), State::OperationEnabled);
    EXPECT_LT(std::abs(demand_velocity()), 1);
    io.command.controlword = cmd::EnableOperation;
    run_ms(1);
    start_move(kRev);
    EXPECT_FALSE(io.feedback.statusword & sw::InternalLimit);
    run_to_target(3000, [](int) {});
    EXPECT_NEAR(io.feedback.position_actual, kRev, 100);
}

// A modulo axis: 0x607B [0, R) (TX1250 2.1: "the position can also be displayed in modulo values").
struct Tx1250Modulo : Tx1250 {
    static constexpr std::int32_t R = kRev;
    void SetUp() override {
        Tx1250::SetUp();
        io.parameters.position_range_min = 0;
        io.parameters.position_range_max = R;
        core.configure(io);  // as the adapter does before each advance
        enable(Mode::ProfilePosition);
    }
    // A move with the rotary axis direction option (0x60F2 bits 6/7); the continuous position it ended
    // at, and the smallest and largest demand velocity on the way.
    double move(std::int32_t target, unsigned direction, double& vmin, double& vmax) {
        io.parameters.positioning_option = static_cast<std::uint16_t>(direction << 6);
        start_move(target);
        vmin = vmax = 0;
        run_to_target(8000, [&](int) {
            vmin = std::min(vmin, demand_velocity());
            vmax = std::max(vmax, demand_velocity());
        });
        EXPECT_TRUE(target_reached());
        return core.position_actual();
    }
};

// 0x6064 (and 0x6062) wrap in the range while the axis turns on.
TEST_F(Tx1250Modulo, Tx1250_2_1_ModuloPositionWrapsInTheRange) {
    io.command.mode = static_cast<std::int8_t>(Mode::ProfileVelocity);
    io.command.target_velocity = 2 * kRev;
    int wraps = 0;
    std::int32_t last = io.feedback.position_actual;
    for (int ms = 0; ms < 2000; ++ms) {
        run_ms(1);
        const std::int32_t p = io.feedback.position_actual;
        ASSERT_GE(p, 0);
        ASSERT_LT(p, R);
        ASSERT_GE(io.feedback.position_demand, 0);
        ASSERT_LT(io.feedback.position_demand, R);
        if (p < last - R / 2) ++wraps;
        last = p;
    }
    EXPECT_GE(wraps, 3) << "about 3.9 turns in 2 s at 2 rev/s";
    EXPECT_GT(core.position_actual(), 3 * R) << "the axis itself moves on";
}

// Only positive (0x60F2 bit 7): from 0.75 R to 0.25 R the axis goes forward over the end of the range.
TEST_F(Tx1250Modulo, Tx1250_2_1_ModuloOnlyPositiveGoesOverTheRangeEnd) {
    double lo = 0, hi = 0;
    ASSERT_NEAR(move(3 * R / 4, Axis::kRotaryLinear, lo, hi), 0.75 * R, 100);
    EXPECT_NEAR(move(R / 4, Axis::kRotaryOnlyPositive, lo, hi), 1.25 * R, 100);
    EXPECT_GE(lo, -1) << "never backwards";
    EXPECT_NEAR(io.feedback.position_actual, R / 4, 100);
}

// Only negative (0x60F2 bit 6): from 0 to 0.75 R the axis goes backwards a quarter of the range.
TEST_F(Tx1250Modulo, Tx1250_2_1_ModuloOnlyNegativeGoesBackwards) {
    double lo = 0, hi = 0;
    EXPECT_NEAR(move(3 * R / 4, Axis::kRotaryOnlyNegative, lo, hi), -0.25 * R, 100);
    EXPECT_LE(hi, 1) << "never forwards";
    EXPECT_NEAR(io.feedback.position_actual, 3 * R / 4, 100);
}

// The shortest way (bits 6 and 7): 0 -> 0.9 R is 0.1 R backwards; half a range goes positive (CiA 402).
// As a linear axis (0), 0.9 R -> 0.1 R stays in the range: 0.8 R backwards.
TEST_F(Tx1250Modulo, Tx1250_2_1_ModuloShortestWayAndLinear) {
    double lo = 0, hi = 0;
    EXPECT_NEAR(move(9 * R / 10, Axis::kRotaryShortest, lo, hi), -0.1 * R, 100);
    EXPECT_NEAR(io.feedback.position_actual, 9 * R / 10, 100);
    EXPECT_NEAR(move(R / 10, Axis::kRotaryLinear, lo, hi), -0.9 * R, 100);
    EXPECT_NEAR(io.feedback.position_actual, R / 10, 100);
    EXPECT_NEAR(move(6 * R / 10, Axis::kRotaryShortest, lo, hi), -0.4 * R, 100) << "half a range: positive";
    EXPECT_GE(lo, -1);
}

// "If a modulo position is specified as being greater than or equal to the modulo factor, the target
// position is ... only reached after the modulo position has been passed over once or several times":
// 2.5 R with only positive makes two whole turns and stops at 0.5 R.
TEST_F(Tx1250Modulo, Tx1250_2_1_ModuloTargetBeyondTheRangeAddsTurns) {
    double lo = 0, hi = 0;
    EXPECT_NEAR(move(5 * R / 2, Axis::kRotaryOnlyPositive, lo, hi), 2.5 * R, 100);
    EXPECT_NEAR(io.feedback.position_actual, R / 2, 100);
}

// 2.2 Override: the override scales the target velocity online (0x2110, ppm of 100 %), "reaching the new
// velocity level as quickly as possible"; back to 100 % the axis returns to V.
TEST_F(Tx1250, Tx1250_2_2_OverrideChangesTheVelocityOnline) {
    enable(Mode::ProfilePosition);
    start_move(20 * kRev);
    run_ms(300);
    EXPECT_NEAR(demand_velocity(), 2 * kRev, 1);
    io.parameters.velocity_override = 750'000;
    run_ms(300);
    EXPECT_NEAR(demand_velocity(), 1.5 * kRev, 1);
    io.parameters.velocity_override = 1'000'000;
    run_ms(300);
    EXPECT_NEAR(demand_velocity(), 2 * kRev, 1);
}

// 2.2 Override types (0x2113): types 1 and 3 scale "the target velocity level calculated and possibly
// reduced at axis start", types 2 and 4 "the target velocity specified by the user". A move of 0.1 rev
// cannot reach V = 2 rev/s (trapezoid, A = 20 rev/s^2: sqrt(A d) = 1.41 rev/s); at 50 % type 1 cruises at
// half of that level, type 2 at half of V.
TEST_F(Tx1250, Tx1250_2_2_OverrideTypesReferToTheReducedOrTheUserVelocity) {
    enable(Mode::ProfilePosition);
    io.parameters.velocity_override = 500'000;
    const double level = std::sqrt(20.0 * 0.1) * kRev;
    for (std::uint8_t type : std::initializer_list<std::uint8_t>{1, 2, 3, 4}) {
        io.parameters.override_type = type;
        const std::int32_t from = io.feedback.position_actual;
        start_move(from + kRev / 10);
        const double peak = peak_velocity(3000);
        const double expected = 0.5 * (type % 2 == 1 ? level : 2.0 * kRev);
        EXPECT_NEAR(peak, expected, 0.01 * kRev) << "type " << int(type);
        EXPECT_NEAR(io.feedback.position_actual, from + kRev / 10, 100);
    }
}

// 2.2 Override types 1/2 vs 3/4 when the new level is not achievable: a move at 20 % of V close to its
// end gets 100 %. Types 1 and 2 keep the old runtime table "without notification"; types 3 and 4 go to
// "a smaller optimal velocity level" above the old one.
TEST_F(Tx1250, Tx1250_2_2_OverrideNotAchievableKeepsTheTableOrReducesTheLevel) {
    enable(Mode::ProfilePosition);
    for (std::uint8_t type : std::initializer_list<std::uint8_t>{1, 2, 3, 4}) {
        io.parameters.override_type = type;
        io.parameters.velocity_override = 200'000;
        run_ms(1);
        const std::int32_t from = io.feedback.position_actual;
        const std::int32_t target = from + kRev;
        start_move(target);
        // 0.1 rev before the target: reaching 2 rev/s and braking from it would take about 0.2 rev.
        for (int ms = 0; ms < 5000 && io.feedback.position_demand < target - kRev / 10; ++ms)
            run_ms(1);
        io.parameters.velocity_override = 1'000'000;
        const double peak = peak_velocity(3000);
        if (type <= 2)
            EXPECT_NEAR(peak, 0.4 * kRev, 0.01 * kRev) << "type " << int(type) << " keeps its table";
        else
            EXPECT_GT(peak, 0.6 * kRev) << "type " << int(type) << " speeds up as far as it can";
        EXPECT_NEAR(io.feedback.position_actual, target, 100);
    }
}

// 2.2 Stop: "stop is realized via override 0.0"; the axis stops on its braking ramp, holds, and goes on to
// its target once the override is raised again.
TEST_F(Tx1250, Tx1250_2_2_StopIsOverrideZero) {
    enable(Mode::ProfilePosition);
    const std::int32_t target = 6 * kRev;
    start_move(target);
    run_ms(300);
    io.parameters.velocity_override = 0;
    run_ms(400);
    EXPECT_EQ(demand_velocity(), 0);
    const std::int32_t held = io.feedback.position_actual;
    run_ms(200);
    EXPECT_NEAR(io.feedback.position_actual, held, 50);
    EXPECT_LT(held, target - kRev);
    io.parameters.velocity_override = 1'000'000;
    run_ms(4000);
    EXPECT_NEAR(io.feedback.position_actual, target, 100);
    EXPECT_TRUE(target_reached());
}

// 2.3 New end position: "if the axis has exceeded the new target or cannot be stopped before it, the axis
// is stopped internally and then automatically moved back to the new target position" (PP change set
// immediately, bit 5).
TEST_F(Tx1250, Tx1250_2_3_NewEndPositionBehindTheAxisStopsAndReturns) {
    enable(Mode::ProfilePosition);
    start_move(10 * kRev);
    run_ms(1200);  // at V = 2 rev/s, about 2.2 rev on
    const std::int32_t now = io.feedback.position_actual;
    ASSERT_GT(now, 2 * kRev);
    const std::int32_t new_target = kRev;
    start_move(new_target, cw::ChangeSetImmediately);
    std::int32_t furthest = now;
    for (int ms = 0; ms < 4000 && !target_reached(); ++ms) {
        run_ms(1);
        furthest = std::max(furthest, io.feedback.position_actual);
    }
    EXPECT_GT(furthest, now) << "the axis stops forward first (it cannot reverse at once)";
    EXPECT_NEAR(io.feedback.position_actual, new_target, 100);
    EXPECT_TRUE(target_reached());
}

// 2.5 Position compensation: an additional distance D within a length L of the move (0x2111); "compensation
// is complete once the distance L + D has been travelled", so the move ends at its target plus D.
TEST_F(Tx1250, Tx1250_2_5_PositionCompensationAddsTheDistance) {
    enable(Mode::ProfilePosition);
    const std::int32_t target = 8 * kRev;
    start_move(target);
    run_ms(300);
    const double d = 0.25 * kRev;
    core.compensate(d, 4.0 * kRev);
    run_ms(6000);
    EXPECT_NEAR(io.feedback.position_actual, target + d, 100);
    EXPECT_TRUE(target_reached());
}

// 2.4 New velocity and new end position (0x2114: APos, VNew, mode 1). A move from 0 to 10 rev at
// VOld = 2 rev/s is at Pos = 2.1 rev when the request comes (a new set-point with "change set
// immediately"); VNew = 1 rev/s. Each case of the manual, positive logical direction.
struct Tx1250NewVelocity : Tx1250 {
    void SetUp() override {
        Tx1250::SetUp();
        enable(Mode::ProfilePosition);
        start_move(10 * kRev);
        run_ms(1100);
        ASSERT_NEAR(io.feedback.position_demand, 2.1 * kRev, 0.05 * kRev);
    }
    // The request; then the demand velocity at each of the probe positions passed, the extreme velocities
    // and the end position.
    struct Seen {
        double at[2] = {0, 0};
        double vmin = 0, vmax = 0;
        double end = 0;
    };
    Seen request(double epos, double apos, double probe1 = 0, double probe2 = 0) {
        io.parameters.activation_mode = 1;
        io.parameters.activation_position = static_cast<std::int32_t>(apos * kRev);
        io.parameters.activation_velocity = kRev;
        start_move(static_cast<std::int32_t>(epos * kRev), cw::ChangeSetImmediately);
        Seen s;
        const double probes[2] = {probe1 * kRev, probe2 * kRev};
        run_to_target(20000, [&](int) {
            const double p = io.feedback.position_demand, v = demand_velocity();
            for (int i = 0; i < 2; ++i)
                if (probes[i] != 0 && s.at[i] == 0 && p >= probes[i]) s.at[i] = v;
            s.vmin = std::min(s.vmin, v);
            s.vmax = std::max(s.vmax, v);
        });
        EXPECT_TRUE(target_reached());
        s.end = io.feedback.position_actual;
        return s;
    }
};

// Case 1, Pos <= APos <= EPos: "the new target velocity is activated once position APos has been crossed".
TEST_F(Tx1250NewVelocity, Tx1250_2_4_Case1_NewVelocityAfterTheActivationPosition) {
    const Seen s = request(8, 4, 3.5, 5);
    EXPECT_NEAR(s.at[0], 2 * kRev, 0.02 * kRev) << "VOld before APos";
    EXPECT_NEAR(s.at[1], kRev, 0.02 * kRev) << "VNew after APos";
    EXPECT_NEAR(s.end, 8 * kRev, 100);
}

// Case 2, APos <= Pos <= EPos: "the activation position has already been crossed, and the target
// velocity NewV is activated instantaneously".
TEST_F(Tx1250NewVelocity, Tx1250_2_4_Case2_ActivationPositionCrossedNewVelocityAtOnce) {
    const Seen s = request(8, 1, 2.5, 5);
    EXPECT_NEAR(s.at[0], kRev, 0.02 * kRev);
    EXPECT_NEAR(s.at[1], kRev, 0.02 * kRev);
    EXPECT_NEAR(s.end, 8 * kRev, 100);
}

// Case 3, APos <= EPos <= Pos: "a stop is activated, and the system is returned automatically with the
// old target velocity VOld".
TEST_F(Tx1250NewVelocity, Tx1250_2_4_Case3_BehindStopsAndReturnsWithTheOldVelocity) {
    const Seen s = request(1, 0.5);
    EXPECT_NEAR(s.vmin, -2 * kRev, 0.02 * kRev) << "back at VOld";
    EXPECT_NEAR(s.end, kRev, 100);
}

// Case 4, Pos <= EPos <= APos: "only the new end position and the old target velocity VOld is activated,
// but not the new target velocity".
TEST_F(Tx1250NewVelocity, Tx1250_2_4_Case4_ActivationPositionBeyondTheEndKeepsTheOldVelocity) {
    const Seen s = request(6, 8, 3, 5);
    EXPECT_NEAR(s.at[0], 2 * kRev, 0.02 * kRev);
    EXPECT_NEAR(s.at[1], 2 * kRev, 0.02 * kRev);
    EXPECT_NEAR(s.end, 6 * kRev, 100);
}

// Case 5, EPos <= APos <= Pos: "a stop is activated, and the system is returned automatically with the
// old target velocity VOld to the new end position" (VNew at APos on the way back: "not implemented").
TEST_F(Tx1250NewVelocity, Tx1250_2_4_Case5_BehindWithActivationBetweenReturnsWithTheOldVelocity) {
    const Seen s = request(0.5, 1);
    EXPECT_NEAR(s.vmin, -2 * kRev, 0.02 * kRev);
    EXPECT_NEAR(s.end, 0.5 * kRev, 100);
}

// Case 6, EPos <= Pos <= APos: "a stop is activated, and the system is returned automatically with the
// old target velocity to the new end position".
TEST_F(Tx1250NewVelocity, Tx1250_2_4_Case6_BehindWithActivationAheadReturnsWithTheOldVelocity) {
    const Seen s = request(1, 5);
    EXPECT_NEAR(s.vmin, -2 * kRev, 0.02 * kRev);
    EXPECT_NEAR(s.end, kRev, 100);
}

// 2.5 Start parameters: the compensation's own velocity increase VK and slopes AK+/AK- (0x2111:4-7). "If
// the position compensation cannot be carried out with the specified compensation parameters, then the
// maximum possible compensation is automatically carried out": VK = 0.2 rev/s over L = 2 rev at VP = V
// = 2 rev/s (T = 1 s), AK+ = AK- = 20 rev/s^2 compensates VK (T - VK/AK) = 0.198 rev of D = 1 rev.
TEST_F(Tx1250, Tx1250_2_5_CompensationDynamicsGiveTheMaximumPossibleDistance) {
    enable(Mode::ProfilePosition);
    const std::int32_t target = 8 * kRev;
    start_move(target);
    run_ms(300);
    CompensationLimits c;
    c.velocity = 0.2 * kRev;
    c.acceleration = c.deceleration = 20.0 * kRev;
    c.process_velocity = 2.0 * kRev;
    core.compensate(1.0 * kRev, 2.0 * kRev, c);
    run_ms(6000);
    EXPECT_NEAR(io.feedback.position_actual, target + 0.198 * kRev, 200);
    EXPECT_TRUE(target_reached());
}

// 2.5 Compensation stop (0x2111:8): "terminates axis compensation ... by replacing the distance to be
// compensated D with the actually compensated distance at the end of the compensation". Stopped after a
// quarter of L, the move ends short of target + D but beyond the target.
TEST_F(Tx1250, Tx1250_2_5_CompensationStopKeepsWhatWasCompensated) {
    enable(Mode::ProfilePosition);
    const std::int32_t target = 8 * kRev;
    start_move(target);
    run_ms(300);
    const double d = 0.5 * kRev;
    core.compensate(d, 4.0 * kRev);
    run_ms(500);  // a quarter of L = 4 rev at 2 rev/s
    core.stop_compensation();
    run_ms(6000);
    const double compensated = io.feedback.position_actual - target;
    EXPECT_GT(compensated, 0.05 * kRev);
    EXPECT_LT(compensated, 0.6 * d);
    EXPECT_TRUE(target_reached());
}

using namespace twin_test;

struct Tx1250Group : TwinBench {
    Tx1250Group() : TwinBench(&position_line) {}
};

// 3.1 NC error handling, INSTANTANEOUS (the default): "in the event of an error in one axis, the NC
// immediately initiates an error reaction, and halts all the axes involved in the master/slave group". A
// linear slave axis (PCON, 3.2) coupled over TWINsync whose drive faults in motion halts its master drive
// (39-02, src/cia402/README.md): both axes come to rest.
TEST_F(Tx1250Group, Tx1250_3_1_AnErrorHaltsTheWholeGroup) {
    enable_gantry();  // the slave drive switched on by its master's control word (P0159 = 10)
    std::int32_t p = pos(0);
    const std::int32_t s0 = pos(1);
    for (int i = 0; i < 200; ++i)
        cycle(0x0F, p += 400);
    ASSERT_GT(pos(1) - s0, 40'000) << "the slave follows";
    e(1, 0x2101).set<std::uint16_t>(fault::FollowingError);  // the slave drive faults
    for (int i = 0; i < 20; ++i)
        cycle(0x0F, p += 400);  // the NC would go on commanding the master
    EXPECT_EQ(drive(0).twinsync_error(), twinsync::error::OtherAxis);
    for (int i = 0; i < 300; ++i)
        cycle(0x0F, p += 400);
    EXPECT_EQ(drive(0).cia402_state(), State::Fault);
    EXPECT_EQ(drive(1).cia402_state(), State::Fault);
    EXPECT_LT(std::abs(drive(0).velocity_actual()), 100);
    EXPECT_LT(std::abs(drive(1).velocity_actual()), 100);
}

// 3.3 Cyclic slave axes: a linear slave axis (PCON over TWINsync) whose coupling factor, the gear
// P2653/P2654, changes while coupled and moving. The slave is switched on by its own EtherCAT controlword
// (P0159 = 0, profile velocity mode, which it ignores while coupled) so that it can be halted alone once
// decoupled; AccBound 0x2115 bounds the acceleration a change of the factor causes.
struct Tx1250CyclicSlave : TwinBench {
    Tx1250CyclicSlave() : TwinBench(&position_line) {}
    static constexpr std::uint32_t kAccBound = 4'000'000;  // units/s^2
    static constexpr int kStep = 400;                      // the master's way per 1 ms cycle
    std::int32_t p = 0;                                    // the master's position set-point
    bool factor_in_pdo = false;  // the gear numerator P2653 in the slave drive's RxPDO (0x1602)
    static constexpr std::size_t kFactorOffset = 16;  // after RxPDO 0x1600 (16 bytes)

    void SetUp() override {
        TwinBench::SetUp();
        namespace tp = twinsync::p;
        if (factor_in_pdo) map_factor();
        par(1, tp::ControlSelector).set<std::uint16_t>(0);
        par(1, tp::GearNumerator).set<std::int32_t>(1000);  // factor 1000/1000
        par(1, tp::GearDenominator).set<std::int32_t>(1000);
        par(0, tp::Config).set<std::uint32_t>(twinsync::kConfigNoSlaveStateCheck);
        drive(1).twinsync_port().reconfigure();
        e(1, device::mfr::coupling_acc_bound.index).set<std::uint32_t>(kAccBound);
        p = pos(0);
        for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
            for (int i = 0; i < 5; ++i)
                cycle(cw, p, cw, 3, 0);
        for (int i = 0; i < 50; ++i)
            cycle(0x0F, p, 0x0F, 3, 0);  // both at rest: the slave couples
        ASSERT_EQ(drive(0).cia402_state(), State::OperationEnabled);
        ASSERT_EQ(drive(1).cia402_state(), State::OperationEnabled);
    }
    void numerator(std::int32_t n) {
        if (factor_in_pdo)
            st_le32(b.master.outputs(1).data() + kFactorOffset, static_cast<std::uint32_t>(n));
        else
            par(1, twinsync::p::GearNumerator).set<std::int32_t>(n);
    }
    // The PLC's cyclic interface: P2653 (object 0x2A5D) mapped into RxPDO 0x1602 and assigned after 0x1600
    // (ETG.1020 PDO mapping by SDO in PRE-OPERATIONAL), then back to OPERATIONAL.
    void map_factor() {
        ASSERT_TRUE(b.master.request_state(protocol::AlState::PreOp));
        master::CoeClient c(b.master, 0x1002);
        const auto gear =
            static_cast<std::uint32_t>(twinsync::object_index(twinsync::p::GearNumerator)) << 16 | 32u;
        ASSERT_TRUE(c.download_value<std::uint8_t>(0x1602, 0, 0).ok());
        ASSERT_TRUE(c.download_value<std::uint32_t>(0x1602, 1, gear).ok());
        ASSERT_TRUE(c.download_value<std::uint8_t>(0x1602, 0, 1).ok());
        ASSERT_TRUE(c.download_value<std::uint8_t>(0x1C12, 0, 0).ok());
        ASSERT_TRUE(c.download_value<std::uint16_t>(0x1C12, 1, 0x1600).ok());
        ASSERT_TRUE(c.download_value<std::uint16_t>(0x1C12, 2, 0x1602).ok());
        ASSERT_TRUE(c.download_value<std::uint8_t>(0x1C12, 0, 2).ok());
        // As a master re-mapping in PRE-OPERATIONAL: the process data SyncManagers of both drives are
        // deactivated (activate register 0x0806 = 0) before they are configured with the new length.
        for (std::uint16_t station : {std::uint16_t{0x1001}, std::uint16_t{0x1002}})
            for (unsigned sm : {2u, 3u}) {
                std::uint8_t off[1] = {0};
                ASSERT_EQ(b.master.fpwr(station, static_cast<std::uint16_t>(protocol::sm_addr(sm) + 6), off),
                          1);
            }
        ASSERT_TRUE(b.master.configure_process_data());
        ASSERT_EQ(b.master.outputs(1).size(), kFactorOffset + 4);
        ASSERT_TRUE(b.master.request_state(protocol::AlState::SafeOp))
            << "AL status code " << b.master.read_al_status(0x1002).code;
        numerator(1000);
        b.master.exchange_process_data();
        ASSERT_TRUE(b.master.request_state(protocol::AlState::Op));
    }
    // n cycles with the master advancing `step` a cycle; the slave's position before and after each.
    std::vector<double> run(int n, int step = kStep, std::uint16_t cw1 = 0x0F) {
        std::vector<double> x{static_cast<double>(pos(1))};
        for (int i = 0; i < n; ++i) {
            cycle(0x0F, p += step, cw1, 3, 0);
            x.push_back(pos(1));
        }
        return x;
    }
    // The slave's velocity (units/s) over the w ms from sample i.
    static double velocity(const std::vector<double>& x, std::size_t i, std::size_t w) {
        return (x[i + w] - x[i]) / (static_cast<double>(w) * 1e-3);
    }
    // The largest acceleration (units/s^2) between consecutive 10 ms velocities: a second difference,
    // an average of the acceleration over 20 ms that smooths the loops' ripple of a few increments.
    static double peak_acceleration(const std::vector<double>& x) {
        double peak = 0;
        for (std::size_t i = 0; i + 20 < x.size(); ++i)
            peak = std::max(peak, std::abs(velocity(x, i + 10, 10) - velocity(x, i, 10)) / 10e-3);
        return peak;
    }
    static double largest_step(const std::vector<double>& x) {
        double s = 0;
        for (std::size_t i = 1; i < x.size(); ++i)
            s = std::max(s, std::abs(x[i] - x[i - 1]));
        return s;
    }
};

// "Each online change of the coupling factor causes a discontinuity in the velocity ... the coupling
// factor arriving via the cyclic interface is therefore smoothed (= filtered). Smoothing is parameterized
// by limiting the amount of the slave axis acceleration." A factor step from 1 to 2 at 400,000 units/s:
// the slave accelerates by 400,000 units/s at AccBound (4,000,000 units/s^2, so in about 100 ms) and no
// faster, then moves at twice the master's velocity; its position never jumps.
TEST_F(Tx1250CyclicSlave, Tx1250_3_3_FactorStepAtSpeedIsSmoothedToAccBound) {
    const std::vector<double> cruise = run(300);
    EXPECT_NEAR(velocity(cruise, 250, 50), 1000.0 * kStep, 0.01 * 1000.0 * kStep) << "factor 1";
    numerator(2000);
    const std::vector<double> x = run(400);
    const double peak = peak_acceleration(x);
    // The set-point's acceleration is AccBound (4.0e6 through the ramp); the position loop, which has no
    // acceleration feed-forward from TWINsync, overshoots it by about 15 % where the ramp starts.
    EXPECT_LE(peak, 1.2 * kAccBound);
    EXPECT_GE(peak, 0.8 * kAccBound) << "the factor moves at the bound, not slower";
    // Half-way through the smoothing the slave is between the two velocities.
    EXPECT_NEAR(velocity(x, 45, 10), 1.5 * 1000.0 * kStep, 0.1 * 1000.0 * kStep);
    // Afterwards: factor x master velocity.
    EXPECT_NEAR(velocity(x, 300, 100), 2.0 * 1000.0 * kStep, 0.01 * 1000.0 * kStep);
    // No position jump: no cycle moves more than the new factor's way (plus the loops' ripple).
    EXPECT_LE(largest_step(x), 2.0 * kStep * 1.05);
    // Without AccBound the factor applies at once (a linear slave axis, 3.2): back to 1 within a few ms.
    e(1, device::mfr::coupling_acc_bound.index).set<std::uint32_t>(0);
    numerator(1000);
    const std::vector<double> y = run(100);
    EXPECT_GT(peak_acceleration(y), 2.0 * kAccBound);
    EXPECT_NEAR(velocity(y, 50, 50), 1000.0 * kStep, 0.01 * 1000.0 * kStep);
}

// 3.3 "the decoupling can be done online: the slave is thereby converted into a master, which continues
// to move as if it were still a slave, but which can also be stopped independently of the former master."
// Decoupled (P0165 back to EtherCAT) half-way through the smoothing of a factor step, the slave goes on at
// the velocity of the factor it had reached, though the master stops; then it is halted on its own.
TEST_F(Tx1250CyclicSlave, Tx1250_3_3_OnlineDecouplingGoesOnThenStopsAlone) {
    run(300);
    numerator(2000);
    const std::vector<double> x = run(50);
    const double v_decouple = velocity(x, 40, 10);
    ASSERT_GT(v_decouple, 1.2 * 1000.0 * kStep);
    ASSERT_LT(v_decouple, 1.8 * 1000.0 * kStep) << "still smoothing";
    par(1, twinsync::p::SetpointSelector).set<std::uint16_t>(0);
    const std::vector<double> free = run(100, 0);  // the master stops (at its CSP set-point)
    EXPECT_NEAR(velocity(free, 50, 50), v_decouple, 0.05 * v_decouple) << "goes on as if still coupled";
    EXPECT_EQ(drive(1).cia402_state(), State::OperationEnabled);
    run(300, 0, 0x10F);  // halt (controlword bit 8) of the slave alone
    const std::vector<double> halted = run(50, 0, 0x10F);
    EXPECT_LE(halted.back() - halted.front(), 5.0) << "stopped";
    EXPECT_EQ(drive(1).cia402_state(), State::OperationEnabled);
}

// 3.3: the coupling factor "set through the cyclic PLC-NC interface within the PLC cycle". The gear
// numerator P2653 is RxPDO-mappable: written in every process data cycle, it is the factor the slave
// follows (smoothed as above), without an SDO.
struct Tx1250CyclicSlaveByPdo : Tx1250CyclicSlave {
    Tx1250CyclicSlaveByPdo() { factor_in_pdo = true; }
};

TEST_F(Tx1250CyclicSlaveByPdo, Tx1250_3_3_FactorArrivesInTheRxPdo) {
    const std::vector<double> cruise = run(300);
    EXPECT_NEAR(velocity(cruise, 250, 50), 1000.0 * kStep, 0.01 * 1000.0 * kStep);
    numerator(1500);  // 1.5 in the next cycle's outputs
    const std::vector<double> x = run(300);
    EXPECT_EQ(par(1, twinsync::p::GearNumerator).get<std::int32_t>(), 1500);
    EXPECT_LE(peak_acceleration(x), 1.2 * kAccBound);
    EXPECT_NEAR(velocity(x, 200, 100), 1.5 * 1000.0 * kStep, 0.01 * 1000.0 * kStep);
}

}  // namespace
}  // namespace vecat::cia402::conformance
