// The CiA 402 state machine: every row of the transition table, the automatic transitions, the option
// codes and the statusword bits.
#include <gtest/gtest.h>

#include <map>
#include <vector>

#include "cia402/state_machine.hpp"

namespace vecat::cia402 {
namespace {

constexpr std::uint16_t kShutdown = 0x06, kSwitchOn = 0x07, kEnable = 0x0F, kDisableVoltage = 0x00,
                        kQuickStop = 0x02, kReset = 0x80;

std::uint16_t controlword_for(Command c) {
    switch (c) {
        case Command::Shutdown:
            return kShutdown;
        case Command::SwitchOn:
            return kSwitchOn;
        case Command::EnableOperation:
            return kEnable;
        case Command::DisableVoltage:
            return kDisableVoltage;
        case Command::QuickStop:
            return kQuickStop;
        case Command::FaultReset:
            return kReset;
        case Command::None:
            break;
    }
    return 0;
}

// Brings a machine into a state along the standard path (axis at rest).
void reach(StateMachine& sm, State s, const OptionCodes& oc) {
    sm.update(0, false, true, oc);  // 0, 1
    ASSERT_EQ(sm.state(), State::SwitchOnDisabled);
    if (s == State::SwitchOnDisabled) return;
    sm.update(kShutdown, false, true, oc);
    if (s == State::ReadyToSwitchOn) return;
    sm.update(kSwitchOn, false, true, oc);
    if (s == State::SwitchedOn) return;
    sm.update(kEnable, false, true, oc);
    if (s == State::OperationEnabled) return;
    if (s == State::QuickStopActive) {
        sm.update(kQuickStop, false, false, oc);  // still moving: stays in QUICK STOP ACTIVE
        return;
    }
    FAIL() << "no path to " << to_string(s);
}

TEST(Cia402StateMachine, StartsNotReadyAndGoesToSwitchOnDisabledByItself) {
    StateMachine sm;
    EXPECT_EQ(sm.state(), State::NotReadyToSwitchOn);
    EXPECT_EQ(sm.statusword_bits(), 0x0000);
    sm.update(0, false, true, {});
    EXPECT_EQ(sm.state(), State::SwitchOnDisabled);
    EXPECT_EQ(sm.last_transition(), 1);
}

TEST(Cia402StateMachine, DecodesTheControlwordCommandsOfTheStandard) {
    EXPECT_EQ(decode_command(0x0006, 0), Command::Shutdown);
    EXPECT_EQ(decode_command(0x000E, 0), Command::Shutdown);  // bit 3 is "x" for shutdown
    EXPECT_EQ(decode_command(0x0007, 0), Command::SwitchOn);
    EXPECT_EQ(decode_command(0x000F, 0), Command::EnableOperation);
    EXPECT_EQ(decode_command(0x001F, 0), Command::EnableOperation);  // bits 4-6 belong to the mode
    EXPECT_EQ(decode_command(0x0000, 0), Command::DisableVoltage);
    EXPECT_EQ(decode_command(0x000D, 0), Command::DisableVoltage);
    EXPECT_EQ(decode_command(0x0002, 0), Command::QuickStop);
    EXPECT_EQ(decode_command(0x000B, 0), Command::QuickStop);
    EXPECT_EQ(decode_command(0x0080, 0x0000), Command::FaultReset);
    EXPECT_EQ(decode_command(0x0080, 0x0080), Command::DisableVoltage);  // held high: no new edge
    EXPECT_EQ(decode_command(0x008F, 0x0080), Command::EnableOperation);
}

// Every row: from its state, the command leads to the row's state with the row's transition number.
TEST(Cia402StateMachine, EveryRowOfTheTransitionTable) {
    ASSERT_EQ(transition_table().size(), 14u);
    for (const auto& row : transition_table()) {
        SCOPED_TRACE(std::string(to_string(row.from)) + " --" + std::to_string(row.number) + "--> " +
                     to_string(row.to));
        OptionCodes oc;
        oc.quick_stop = 6;  // stays in QUICK STOP ACTIVE, so rows from there can be reached
        StateMachine sm;
        reach(sm, row.from, oc);
        ASSERT_EQ(sm.state(), row.from);
        // At rest, so slow-down stops end at once.
        sm.update(controlword_for(row.command), false, true, oc);
        EXPECT_EQ(sm.state(), row.to);
        EXPECT_EQ(sm.last_transition(), row.number);
    }
}

// Commands that are not in the table leave the state unchanged.
TEST(Cia402StateMachine, CommandsWithoutARowChangeNothing) {
    const std::vector<State> states = {State::SwitchOnDisabled, State::ReadyToSwitchOn, State::SwitchedOn,
                                       State::OperationEnabled};
    const std::vector<Command> cmds = {Command::Shutdown, Command::SwitchOn, Command::EnableOperation,
                                       Command::DisableVoltage, Command::QuickStop};
    int unchanged = 0;
    for (State s : states)
        for (Command c : cmds) {
            bool has_row = false;
            for (const auto& r : transition_table())
                has_row |= r.from == s && r.command == c;
            if (has_row) continue;
            StateMachine sm;
            reach(sm, s, {});
            sm.update(controlword_for(c), false, true, {});
            EXPECT_EQ(sm.state(), s) << to_string(s) << " cmd " << int(c);
            ++unchanged;
        }
    // SWITCH ON DISABLED ignores 4 commands, READY TO SWITCH ON 1, SWITCHED ON 1, OPERATION ENABLED 1.
    EXPECT_EQ(unchanged, 7);
}

TEST(Cia402StateMachine, StatuswordBitsPerState) {
    // CiA 402 Table 30 patterns (bits 0-3, 5, 6) plus voltage enabled (bit 4).
    const std::map<State, std::uint16_t> expected = {{State::SwitchOnDisabled, 0x0050},
                                                     {State::ReadyToSwitchOn, 0x0031},
                                                     {State::SwitchedOn, 0x0033},
                                                     {State::OperationEnabled, 0x0037},
                                                     {State::QuickStopActive, 0x0017}};
    for (const auto& [s, bits] : expected) {
        OptionCodes oc;
        oc.quick_stop = 6;
        StateMachine sm;
        reach(sm, s, oc);
        EXPECT_EQ(sm.statusword_bits(), bits) << to_string(s);
        // The masks of the standard identify the state.
        if (s == State::SwitchOnDisabled) {
            EXPECT_EQ(bits & 0x4F, 0x40);
        } else if (s == State::QuickStopActive) {
            EXPECT_EQ(bits & 0x6F, 0x07);
        } else {
            EXPECT_EQ(bits & 0x6F, (bits & 0x0F) | 0x20);
        }
    }
}

TEST(Cia402StateMachine, FaultReactionThenFaultThenResetOnTheRisingEdgeOnly) {
    OptionCodes oc;  // fault reaction 2: quick stop ramp
    StateMachine sm;
    reach(sm, State::OperationEnabled, oc);
    sm.update(kEnable, true, false, oc);  // 13
    EXPECT_EQ(sm.state(), State::FaultReactionActive);
    EXPECT_EQ(sm.last_transition(), 13);
    EXPECT_EQ(sm.stop(), StopKind::QuickStopRamp);
    EXPECT_TRUE(sm.drive_enabled());
    EXPECT_EQ(sm.statusword_bits() & 0x4F, 0x0F);
    sm.update(kEnable, true, false, oc);  // still braking
    EXPECT_EQ(sm.state(), State::FaultReactionActive);
    sm.update(kEnable, true, true, oc);  // 14
    EXPECT_EQ(sm.state(), State::Fault);
    EXPECT_EQ(sm.last_transition(), 14);
    EXPECT_FALSE(sm.drive_enabled());
    EXPECT_EQ(sm.statusword_bits() & 0x4F, 0x08);
    // Reset while the fault is still present: refused.
    sm.update(kReset, true, true, oc);
    EXPECT_EQ(sm.state(), State::Fault);
    // Fault gone, bit 7 still high: no edge, nothing happens.
    sm.update(kReset, false, true, oc);
    EXPECT_EQ(sm.state(), State::Fault);
    sm.update(0, false, true, oc);
    sm.update(kReset, false, true, oc);  // 15
    EXPECT_EQ(sm.state(), State::SwitchOnDisabled);
    EXPECT_EQ(sm.last_transition(), 15);
}

TEST(Cia402StateMachine, FaultReactionZeroCoastsStraightToFault) {
    OptionCodes oc;
    oc.fault_reaction = 0;
    StateMachine sm;
    reach(sm, State::OperationEnabled, oc);
    sm.update(kEnable, true, false, oc);
    EXPECT_EQ(sm.state(), State::Fault);
    EXPECT_FALSE(sm.drive_enabled());
}

TEST(Cia402StateMachine, FaultWhileDisabledNeedsNoReaction) {
    StateMachine sm;
    reach(sm, State::ReadyToSwitchOn, {});
    sm.update(kShutdown, true, true, {});
    EXPECT_EQ(sm.state(), State::Fault);
    sm.raise_fault({});  // already in fault: nothing changes
    EXPECT_EQ(sm.state(), State::Fault);
}

TEST(Cia402StateMachine, QuickStopOptionCodesOneToFourEndInSwitchOnDisabled) {
    const std::map<int, StopKind> kinds = {{1, StopKind::SlowDownRamp},
                                           {2, StopKind::QuickStopRamp},
                                           {3, StopKind::CurrentLimit},
                                           {4, StopKind::VoltageLimit}};
    for (const auto& [code, kind] : kinds) {
        OptionCodes oc;
        oc.quick_stop = static_cast<std::int16_t>(code);
        StateMachine sm;
        reach(sm, State::OperationEnabled, oc);
        sm.update(kQuickStop, false, false, oc);
        EXPECT_EQ(sm.state(), State::QuickStopActive);
        EXPECT_EQ(sm.stop(), kind);
        EXPECT_TRUE(sm.drive_enabled());
        EXPECT_FALSE(sm.following_setpoints());
        sm.update(kQuickStop, false, true, oc);  // stopped: 12 by itself
        EXPECT_EQ(sm.state(), State::SwitchOnDisabled) << code;
        EXPECT_EQ(sm.last_transition(), 12);
    }
}

TEST(Cia402StateMachine, QuickStopOptionCodesFiveToEightStayAndReturnWithTransition16) {
    for (int code = 5; code <= 8; ++code) {
        OptionCodes oc;
        oc.quick_stop = static_cast<std::int16_t>(code);
        StateMachine sm;
        reach(sm, State::OperationEnabled, oc);
        sm.update(kQuickStop, false, false, oc);
        sm.update(kQuickStop, false, true, oc);
        EXPECT_EQ(sm.state(), State::QuickStopActive);
        EXPECT_TRUE(sm.drive_enabled());  // holds the axis
        sm.update(kEnable, false, true, oc);
        EXPECT_EQ(sm.state(), State::OperationEnabled);
        EXPECT_EQ(sm.last_transition(), 16);
        EXPECT_TRUE(sm.following_setpoints());
    }
}

TEST(Cia402StateMachine, QuickStopOptionZeroDisablesAtOnce) {
    OptionCodes oc;
    oc.quick_stop = 0;
    StateMachine sm;
    reach(sm, State::OperationEnabled, oc);
    sm.update(kQuickStop, false, false, oc);
    EXPECT_EQ(sm.state(), State::SwitchOnDisabled);
    EXPECT_EQ(sm.last_transition(), 12);
}

TEST(Cia402StateMachine, DisableOperationSlowsDownBeforeSwitchedOn) {
    OptionCodes oc;  // 0x605C = 1: slow down ramp
    StateMachine sm;
    reach(sm, State::OperationEnabled, oc);
    sm.update(kSwitchOn, false, false, oc);
    EXPECT_EQ(sm.state(), State::OperationEnabled);
    EXPECT_EQ(sm.stop(), StopKind::SlowDownRamp);
    EXPECT_FALSE(sm.following_setpoints());
    sm.update(kSwitchOn, false, true, oc);
    EXPECT_EQ(sm.state(), State::SwitchedOn);
    EXPECT_EQ(sm.last_transition(), 5);
    // With 0x605C = 0 the drive function is disabled at once.
    oc.disable_operation = 0;
    StateMachine sm2;
    reach(sm2, State::OperationEnabled, oc);
    sm2.update(kSwitchOn, false, false, oc);
    EXPECT_EQ(sm2.state(), State::SwitchedOn);
}

TEST(Cia402StateMachine, ShutdownOptionCodes) {
    OptionCodes oc;  // 0x605B = 0: disable at once
    StateMachine sm;
    reach(sm, State::OperationEnabled, oc);
    sm.update(kShutdown, false, false, oc);
    EXPECT_EQ(sm.state(), State::ReadyToSwitchOn);
    EXPECT_EQ(sm.last_transition(), 8);
    oc.shutdown = 1;
    StateMachine sm2;
    reach(sm2, State::OperationEnabled, oc);
    sm2.update(kShutdown, false, false, oc);
    EXPECT_EQ(sm2.state(), State::OperationEnabled);
    EXPECT_EQ(sm2.stop(), StopKind::SlowDownRamp);
    sm2.update(kEnable, false, false, oc);  // enable operation again cancels the slow-down
    EXPECT_TRUE(sm2.following_setpoints());
    sm2.update(kShutdown, false, false, oc);
    sm2.update(kDisableVoltage, false, false, oc);  // disable voltage overrides it: 9
    EXPECT_EQ(sm2.state(), State::SwitchOnDisabled);
    EXPECT_EQ(sm2.last_transition(), 9);
}

TEST(Cia402StateMachine, StopKindsFromOptionCodes) {
    OptionCodes oc;
    oc.halt = 2;
    EXPECT_EQ(stop_for(StopOption::None, oc), StopKind::None);
    for (int c = 0; c <= 4; ++c) {
        oc.fault_reaction = static_cast<std::int16_t>(c);
        const StopKind k = stop_for(StopOption::FaultReaction, oc);
        const StopKind want[] = {StopKind::Coast, StopKind::SlowDownRamp, StopKind::QuickStopRamp,
                                 StopKind::CurrentLimit, StopKind::VoltageLimit};
        EXPECT_EQ(k, want[c]);
    }
    const StopKind halts[] = {StopKind::SlowDownRamp, StopKind::QuickStopRamp, StopKind::CurrentLimit,
                              StopKind::VoltageLimit};
    for (int c = 1; c <= 4; ++c) {
        oc.halt = static_cast<std::int16_t>(c);
        EXPECT_EQ(stop_for(StopOption::Halt, oc), halts[c - 1]);
    }
    oc.disable_operation = -1;  // manufacturer specific: slow down
    EXPECT_EQ(stop_for(StopOption::DisableOperation, oc), StopKind::SlowDownRamp);
}

}  // namespace
}  // namespace vecat::cia402

namespace vecat::cia402 {
namespace {

// protocol::cia402::decode_state is the inverse of the state machine's statusword: every state, reached the
// way a drive reaches it, reads back as itself, also with the other statusword bits set.
TEST(Cia402StateMachine, DecodeStateIsTheInverseOfTheStatuswordForEveryState) {
    namespace cia = protocol::cia402;
    std::vector<State> seen;
    auto check = [&](const StateMachine& sm) {
        const std::uint16_t bits = sm.statusword_bits();
        EXPECT_EQ(cia::decode_state(bits), sm.state()) << to_string(sm.state()) << std::hex << " 0x" << bits;
        // Warning, remote, target reached, internal limit and the mode bits do not change the state.
        const std::uint16_t others = cia::sw::Warning | cia::sw::Remote | cia::sw::TargetReached |
                                     cia::sw::InternalLimit | cia::sw::Bit12 | cia::sw::Bit13 | 0xC100;
        EXPECT_EQ(cia::decode_state(static_cast<std::uint16_t>(bits | others)), sm.state())
            << to_string(sm.state());
        seen.push_back(sm.state());
    };
    OptionCodes oc;
    oc.quick_stop = 6;  // stay in QUICK STOP ACTIVE
    StateMachine sm;
    check(sm);  // NOT READY TO SWITCH ON
    for (State s : {State::SwitchOnDisabled, State::ReadyToSwitchOn, State::SwitchedOn,
                    State::OperationEnabled, State::QuickStopActive}) {
        StateMachine m;
        reach(m, s, oc);
        check(m);
    }
    StateMachine f;
    reach(f, State::OperationEnabled, oc);
    f.update(kEnable, true, false, oc);  // 13: FAULT REACTION ACTIVE
    check(f);
    f.update(kEnable, true, true, oc);  // 14: FAULT
    check(f);
    EXPECT_EQ(seen.size(), 8u);
    // A pattern Table 30 does not give has no state.
    EXPECT_FALSE(cia::decode_state(0x0001).has_value());
}

}  // namespace
}  // namespace vecat::cia402
