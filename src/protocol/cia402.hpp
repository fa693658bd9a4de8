// The CiA 402 (IEC 61800-7-201) controlword 0x6040 and statusword 0x6041 as the master and the drive
// exchange them: the bits, the device control commands, and decode_state(), which reads the state of the
// power drive system back from a statusword (6.3.3, Table 30). The drive's state machine
// (src/cia402/state_machine.cpp) encodes the statusword; decode_state is its inverse, tested for every state.
#pragma once

#include <cstdint>
#include <optional>

namespace vecat::protocol::cia402 {

// The states of the power drive system state machine (IEC 61800-7-201 6.3.2, Figure 22).
enum class State : std::uint8_t {
    NotReadyToSwitchOn,
    SwitchOnDisabled,
    ReadyToSwitchOn,
    SwitchedOn,
    OperationEnabled,
    QuickStopActive,
    FaultReactionActive,
    Fault,
};

constexpr const char* to_string(State s) noexcept {
    switch (s) {
        case State::NotReadyToSwitchOn:
            return "NOT READY TO SWITCH ON";
        case State::SwitchOnDisabled:
            return "SWITCH ON DISABLED";
        case State::ReadyToSwitchOn:
            return "READY TO SWITCH ON";
        case State::SwitchedOn:
            return "SWITCHED ON";
        case State::OperationEnabled:
            return "OPERATION ENABLED";
        case State::QuickStopActive:
            return "QUICK STOP ACTIVE";
        case State::FaultReactionActive:
            return "FAULT REACTION ACTIVE";
        case State::Fault:
            return "FAULT";
    }
    return "?";
}

// Modes of operation 0x6060 / display 0x6061 (6.4.1, Table 31: the values the vecat drive knows).
enum class Mode : std::int8_t {
    None = 0,
    ProfilePosition = 1,
    ProfileVelocity = 3,
    ProfileTorque = 4,
    Homing = 6,
    CyclicPosition = 8,
    CyclicVelocity = 9,
    CyclicTorque = 10,
};

// Controlword bits (6.3.1, Table 28; the operation mode specific bits 4-6, 8 and 9 of 6.3.1.2).
namespace cw {
inline constexpr std::uint16_t SwitchOn = 1u << 0;
inline constexpr std::uint16_t EnableVoltage = 1u << 1;
inline constexpr std::uint16_t QuickStop = 1u << 2;  // active low: 0 requests the quick stop
inline constexpr std::uint16_t EnableOperation = 1u << 3;
inline constexpr std::uint16_t FaultReset = 1u << 7;  // counts on its rising edge
inline constexpr std::uint16_t Halt = 1u << 8;
// Profile position (IEC 61800-7-201 6.7.2.2, Table 40).
inline constexpr std::uint16_t NewSetpoint = 1u << 4;
inline constexpr std::uint16_t ChangeSetImmediately = 1u << 5;
inline constexpr std::uint16_t Relative = 1u << 6;
inline constexpr std::uint16_t ChangeOnSetpoint = 1u << 9;
// Homing (6.6.2.2, Table 35).
inline constexpr std::uint16_t HomingStart = 1u << 4;

}  // namespace cw

// Device control commands (Table 29): the controlword values (bits 0-3 and 7) a master writes.
namespace cmd {
inline constexpr std::uint16_t Shutdown = 0x0006;
inline constexpr std::uint16_t SwitchOn = 0x0007;
inline constexpr std::uint16_t DisableOperation = 0x0007;  // SwitchOn, from OPERATION ENABLED
inline constexpr std::uint16_t EnableOperation = 0x000F;
inline constexpr std::uint16_t DisableVoltage = 0x0000;
inline constexpr std::uint16_t QuickStop = 0x0002;
inline constexpr std::uint16_t FaultReset = 0x0080;  // the rising edge of bit 7
}  // namespace cmd

// Statusword bits (6.3.3, Table 30 and the mode specific bits 10, 12 and 13).
namespace sw {
inline constexpr std::uint16_t ReadyToSwitchOn = 1u << 0;
inline constexpr std::uint16_t SwitchedOn = 1u << 1;
inline constexpr std::uint16_t OperationEnabled = 1u << 2;
inline constexpr std::uint16_t Fault = 1u << 3;
inline constexpr std::uint16_t VoltageEnabled = 1u << 4;
inline constexpr std::uint16_t QuickStop = 1u << 5;  // active low: 0 while a quick stop is active
inline constexpr std::uint16_t SwitchOnDisabled = 1u << 6;
inline constexpr std::uint16_t Warning = 1u << 7;
inline constexpr std::uint16_t Remote = 1u << 9;
inline constexpr std::uint16_t TargetReached = 1u << 10;
inline constexpr std::uint16_t InternalLimit = 1u << 11;
inline constexpr std::uint16_t Bit12 = 1u << 12;  // PP set-point acknowledge, PV speed zero, HM attained,
                                                  // CSx drive follows the command value
inline constexpr std::uint16_t Bit13 = 1u << 13;  // PP/CSP following error, HM homing error

// The bits that tell the state: 0-3, 5 and 6 (bit 5 only where Table 30 gives it).
inline constexpr std::uint16_t StateMask = 0x006F;
inline constexpr std::uint16_t StateMaskNoQuickStop = 0x004F;
}  // namespace sw

// The state a statusword shows (Table 30); nullopt for a pattern the table does not give.
constexpr std::optional<State> decode_state(std::uint16_t statusword) noexcept {
    const std::uint16_t a = statusword & sw::StateMaskNoQuickStop;  // xxxx xxxx x?xx ????
    const std::uint16_t b = statusword & sw::StateMask;             // xxxx xxxx x??x ????
    if (a == 0x0000) return State::NotReadyToSwitchOn;              // x0xx 0000
    if (a == 0x0040) return State::SwitchOnDisabled;                // x1xx 0000
    if (b == 0x0021) return State::ReadyToSwitchOn;                 // x01x 0001
    if (b == 0x0023) return State::SwitchedOn;                      // x01x 0011
    if (b == 0x0027) return State::OperationEnabled;                // x01x 0111
    if (b == 0x0007) return State::QuickStopActive;                 // x00x 0111
    if (a == 0x000F) return State::FaultReactionActive;             // x0xx 1111
    if (a == 0x0008) return State::Fault;                           // x0xx 1000
    return std::nullopt;
}

}  // namespace vecat::protocol::cia402
