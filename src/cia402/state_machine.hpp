// The CiA 402 (IEC 61800-7-201 6.3) power drive system state machine, as a table: the controlword command
// decoded in the current state selects the next state, the transition number of the standard and the stop
// the drive performs on the way (option codes 0x605A-0x605E).
#pragma once

#include <cstdint>
#include <span>

#include "protocol/cia402.hpp"

namespace vecat::cia402 {

// The states, their names and the controlword/statusword bits are the protocol's (protocol/cia402.hpp).
using protocol::cia402::State;
using protocol::cia402::to_string;

// Device control commands of the controlword (bits 0-3 and 7).
enum class Command : std::uint8_t {
    None,
    Shutdown,         // 0xxx x110
    SwitchOn,         // 0xxx 0111 (in OPERATION ENABLED: disable operation)
    EnableOperation,  // 0xxx 1111 (in READY TO SWITCH ON: switch on + enable operation)
    DisableVoltage,   // 0xxx xx0x
    QuickStop,        // 0xxx x01x
    FaultReset,       // bit 7 rising edge
};
// Decodes the command; bit 7 counts only on its rising edge (previous controlword).
Command decode_command(std::uint16_t controlword, std::uint16_t previous) noexcept;

// How the drive stops on the way out of OPERATION ENABLED (or in QUICK STOP ACTIVE / FAULT REACTION ACTIVE).
enum class StopKind : std::uint8_t {
    None,           // keep following the set-points
    Coast,          // disable the drive function at once: no torque
    SlowDownRamp,   // profile deceleration 0x6084 (or the mode's own deceleration)
    QuickStopRamp,  // quick stop deceleration 0x6085
    CurrentLimit,   // brake at the torque limit
    VoltageLimit,   // as current limit (no voltage model)
};

// Which option code governs the stop of a transition.
enum class StopOption : std::uint8_t { None, Shutdown, DisableOperation, QuickStop, FaultReaction, Halt };

struct TransitionRow {
    State from;
    Command command;
    State to;
    std::uint8_t number;  // CiA 402 transition number
    StopOption stop;      // stop performed before the drive function is disabled
};
// Every commanded transition (the automatic ones, 0, 1, 12, 13 and 14, are made by StateMachine::update).
std::span<const TransitionRow> transition_table() noexcept;

struct OptionCodes {
    std::int16_t quick_stop = 2;         // 0x605A
    std::int16_t shutdown = 0;           // 0x605B
    std::int16_t disable_operation = 1;  // 0x605C
    std::int16_t halt = 1;               // 0x605D
    std::int16_t fault_reaction = 2;     // 0x605E
};

StopKind stop_for(StopOption which, const OptionCodes& oc) noexcept;

class StateMachine {
  public:
    // One drive cycle. fault: a fault condition is present (transition 13, and fault reset refused while it
    // lasts). at_rest: the axis has stopped (ends stop ramps).
    void update(std::uint16_t controlword, bool fault, bool at_rest, const OptionCodes& oc);
    // Forces a fault now (fault reaction), as update(..., fault = true) would.
    void raise_fault(const OptionCodes& oc);

    State state() const { return state_; }
    // The drive function: torque is produced (OPERATION ENABLED, QUICK STOP ACTIVE, a fault reaction or a
    // stop with torque in progress).
    bool drive_enabled() const;
    // Set-points are followed (OPERATION ENABLED and no stop in progress).
    bool following_setpoints() const { return state_ == State::OperationEnabled && stop_ == StopKind::None; }
    // The stop in progress (None when the drive follows its set-points or is disabled).
    StopKind stop() const { return stop_; }
    // Statusword bits 0-6 for the state (voltage enabled, bit 4, is always set: the DC bus is up).
    std::uint16_t statusword_bits() const;
    std::uint8_t last_transition() const { return last_transition_; }
    std::uint64_t transitions() const { return transitions_; }

  private:
    void go(State to, std::uint8_t number);

    State state_ = State::NotReadyToSwitchOn;
    StopKind stop_ = StopKind::None;
    State after_stop_ = State::OperationEnabled;  // where a stop in OPERATION ENABLED leads
    std::uint8_t after_stop_number_ = 0;
    std::uint16_t previous_ = 0;
    std::uint8_t last_transition_ = 0;
    std::uint64_t transitions_ = 0;
};

}  // namespace vecat::cia402
