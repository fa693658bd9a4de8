#include "cia402/state_machine.hpp"

#include <array>

namespace vecat::cia402 {

Command decode_command(std::uint16_t cw, std::uint16_t previous) noexcept {
    namespace b = protocol::cia402::cw;
    if ((cw & b::FaultReset) && !(previous & b::FaultReset)) return Command::FaultReset;
    if (!(cw & b::EnableVoltage)) return Command::DisableVoltage;
    if (!(cw & b::QuickStop)) return Command::QuickStop;
    if (!(cw & b::SwitchOn)) return Command::Shutdown;
    return (cw & b::EnableOperation) ? Command::EnableOperation : Command::SwitchOn;
}

namespace {

using S = State;
using C = Command;
using O = StopOption;

constexpr std::array<TransitionRow, 14> kTable{{
    {S::SwitchOnDisabled, C::Shutdown, S::ReadyToSwitchOn, 2, O::None},
    {S::ReadyToSwitchOn, C::SwitchOn, S::SwitchedOn, 3, O::None},
    // 0x000F in READY TO SWITCH ON: transition 3 and then 4 (CiA 402 allows the combined command).
    {S::ReadyToSwitchOn, C::EnableOperation, S::OperationEnabled, 4, O::None},
    {S::SwitchedOn, C::EnableOperation, S::OperationEnabled, 4, O::None},
    {S::OperationEnabled, C::SwitchOn, S::SwitchedOn, 5, O::DisableOperation},
    {S::SwitchedOn, C::Shutdown, S::ReadyToSwitchOn, 6, O::None},
    {S::ReadyToSwitchOn, C::DisableVoltage, S::SwitchOnDisabled, 7, O::None},
    {S::ReadyToSwitchOn, C::QuickStop, S::SwitchOnDisabled, 7, O::None},
    {S::OperationEnabled, C::Shutdown, S::ReadyToSwitchOn, 8, O::Shutdown},
    {S::OperationEnabled, C::DisableVoltage, S::SwitchOnDisabled, 9, O::None},
    {S::SwitchedOn, C::DisableVoltage, S::SwitchOnDisabled, 10, O::None},
    {S::SwitchedOn, C::QuickStop, S::SwitchOnDisabled, 10, O::None},
    {S::OperationEnabled, C::QuickStop, S::QuickStopActive, 11, O::QuickStop},
    {S::QuickStopActive, C::DisableVoltage, S::SwitchOnDisabled, 12, O::None},
}};
// Transition 16 (QUICK STOP ACTIVE -> OPERATION ENABLED) depends on the quick stop option code and
// transition 15 (fault reset) on the fault being gone; update() handles both.

// The table's row of each (state, command), or none: every servo period looks one up.
constexpr std::size_t kStates = static_cast<std::size_t>(S::Fault) + 1;
constexpr std::size_t kCommands = static_cast<std::size_t>(C::FaultReset) + 1;
constexpr auto kRowOf = [] {
    std::array<std::array<std::int8_t, kCommands>, kStates> at{};
    for (auto& row : at)
        row.fill(-1);
    for (std::size_t i = kTable.size(); i-- > 0;)  // the first row of a pair wins, as in a scan
        at[static_cast<std::size_t>(kTable[i].from)][static_cast<std::size_t>(kTable[i].command)] =
            static_cast<std::int8_t>(i);
    return at;
}();

const TransitionRow* find(State s, Command c) {
    const auto si = static_cast<std::size_t>(s), ci = static_cast<std::size_t>(c);
    if (si >= kStates || ci >= kCommands) return nullptr;
    const std::int8_t i = kRowOf[si][ci];
    return i < 0 ? nullptr : &kTable[static_cast<std::size_t>(i)];
}

}  // namespace

std::span<const TransitionRow> transition_table() noexcept {
    return kTable;
}

StopKind stop_for(StopOption which, const OptionCodes& oc) noexcept {
    switch (which) {
        case StopOption::None:
            return StopKind::None;
        case StopOption::Shutdown:
            return oc.shutdown == 0 ? StopKind::Coast : StopKind::SlowDownRamp;
        case StopOption::DisableOperation:
            return oc.disable_operation == 0 ? StopKind::Coast : StopKind::SlowDownRamp;
        case StopOption::QuickStop:
            switch (oc.quick_stop) {
                case 0:
                    return StopKind::Coast;
                case 1:
                case 5:
                    return StopKind::SlowDownRamp;
                case 3:
                case 7:
                    return StopKind::CurrentLimit;
                case 4:
                case 8:
                    return StopKind::VoltageLimit;
                default:
                    return StopKind::QuickStopRamp;
            }
        case StopOption::Halt:
            // 0x605D: 1 slow down ramp, 2 quick stop ramp, 3 current limit, 4 voltage limit.
            switch (oc.halt) {
                case 2:
                    return StopKind::QuickStopRamp;
                case 3:
                    return StopKind::CurrentLimit;
                case 4:
                    return StopKind::VoltageLimit;
                default:
                    return StopKind::SlowDownRamp;
            }
        case StopOption::FaultReaction:
            switch (oc.fault_reaction) {
                case 0:
                    return StopKind::Coast;
                case 1:
                    return StopKind::SlowDownRamp;
                case 3:
                    return StopKind::CurrentLimit;
                case 4:
                    return StopKind::VoltageLimit;
                default:
                    return StopKind::QuickStopRamp;
            }
    }
    return StopKind::Coast;
}

void StateMachine::go(State to, std::uint8_t number) {
    state_ = to;
    last_transition_ = number;
    ++transitions_;
}

void StateMachine::raise_fault(const OptionCodes& oc) {
    if (state_ == State::Fault || state_ == State::FaultReactionActive) return;
    const bool torque = drive_enabled();
    go(State::FaultReactionActive, 13);
    stop_ = torque ? stop_for(StopOption::FaultReaction, oc) : StopKind::Coast;
    if (stop_ == StopKind::Coast) {
        stop_ = StopKind::None;
        go(State::Fault, 14);
    }
}

void StateMachine::update(std::uint16_t cw, bool fault, bool at_rest, const OptionCodes& oc) {
    const Command cmd = decode_command(cw, previous_);
    previous_ = cw;

    if (state_ == State::NotReadyToSwitchOn) go(State::SwitchOnDisabled, 1);  // self-test passed
    if (fault) raise_fault(oc);

    switch (state_) {
        case State::FaultReactionActive:
            if (at_rest || stop_ == StopKind::Coast) {
                stop_ = StopKind::None;
                go(State::Fault, 14);
            }
            return;
        case State::Fault:
            if (cmd == Command::FaultReset && !fault) go(State::SwitchOnDisabled, 15);
            return;
        case State::QuickStopActive:
            if (cmd == Command::DisableVoltage) {
                stop_ = StopKind::None;
                go(State::SwitchOnDisabled, 12);
                return;
            }
            // Option codes 5-8 stay in QUICK STOP ACTIVE; enable operation returns (transition 16).
            if (oc.quick_stop >= 5 && cmd == Command::EnableOperation) {
                stop_ = StopKind::None;
                go(State::OperationEnabled, 16);
                return;
            }
            if (oc.quick_stop < 5 && (at_rest || stop_ == StopKind::Coast)) {
                stop_ = StopKind::None;
                go(State::SwitchOnDisabled, 12);
            }
            return;
        case State::OperationEnabled:
            if (stop_ != StopKind::None) {
                // A slow-down of transition 5 or 8 is in progress: enable operation cancels it, other
                // commands take over; otherwise it ends when the axis is at rest.
                if (cmd == Command::EnableOperation) {
                    stop_ = StopKind::None;
                    return;
                }
                if (cmd != Command::SwitchOn && cmd != Command::Shutdown) break;
                if (const TransitionRow* r = find(state_, cmd)) {
                    after_stop_ = r->to;  // the master may change its mind between 5 and 8
                    after_stop_number_ = r->number;
                }
                if (at_rest) {
                    stop_ = StopKind::None;
                    go(after_stop_, after_stop_number_);
                }
                return;
            }
            break;
        default:
            break;
    }

    const TransitionRow* row = find(state_, cmd);
    if (!row) return;
    StopKind stop = stop_for(row->stop, oc);
    stop_ = StopKind::None;
    if (row->to == State::QuickStopActive) {
        go(State::QuickStopActive, row->number);
        stop_ = stop;
        if (stop == StopKind::Coast) {
            stop_ = StopKind::None;
            go(State::SwitchOnDisabled, 12);
        }
        return;
    }
    if (stop != StopKind::None && stop != StopKind::Coast && !at_rest) {
        // Transitions 5 and 8 with a slow-down: stay in OPERATION ENABLED until the axis stopped.
        stop_ = stop;
        after_stop_ = row->to;
        after_stop_number_ = row->number;
        return;
    }
    go(row->to, row->number);
}

bool StateMachine::drive_enabled() const {
    switch (state_) {
        case State::OperationEnabled:
        case State::QuickStopActive:
            return true;
        case State::FaultReactionActive:
            return stop_ != StopKind::Coast && stop_ != StopKind::None;
        default:
            return false;
    }
}

std::uint16_t StateMachine::statusword_bits() const {
    // Table 30. Voltage enabled (bit 4) is always set: the DC bus is up. protocol::cia402::decode_state
    // reads these patterns back (tested for every state).
    namespace b = protocol::cia402::sw;
    constexpr std::uint16_t kOn = b::ReadyToSwitchOn | b::SwitchedOn | b::OperationEnabled;
    switch (state_) {
        case State::NotReadyToSwitchOn:
            return 0x0000;
        case State::SwitchOnDisabled:
            return b::SwitchOnDisabled | b::VoltageEnabled;
        case State::ReadyToSwitchOn:
            return b::QuickStop | b::ReadyToSwitchOn | b::VoltageEnabled;
        case State::SwitchedOn:
            return b::QuickStop | b::ReadyToSwitchOn | b::SwitchedOn | b::VoltageEnabled;
        case State::OperationEnabled:
            return b::QuickStop | kOn | b::VoltageEnabled;
        case State::QuickStopActive:
            return kOn | b::VoltageEnabled;  // quick stop bit 0: active
        case State::FaultReactionActive:
            return kOn | b::Fault | b::VoltageEnabled;
        case State::Fault:
            return b::QuickStop | b::Fault | b::VoltageEnabled;
    }
    return 0;
}

}  // namespace vecat::cia402
