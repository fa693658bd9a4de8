// The MSD drive parameters of the TWINsync option (specification CB08759-001 chapter 4) and the few
// general drive parameters its operation modes use, as parameter numbers. vecat exposes drive parameter
// Pnnnn as the CoE object 0x2000 + nnnn (P2580 -> 0x2A14). The MSD numbers array elements from 0
// (P2650[0], P2650[1]); CoE keeps subindex 0 for the number of entries, so element k is subindex k + 1.
// A parameter that is not an array (P2617) is the CoE VAR at subindex 0.
#pragma once

#include <cstdint>

namespace vecat::twinsync {

constexpr std::uint16_t object_index(std::uint16_t parameter) noexcept {
    return static_cast<std::uint16_t>(0x2000 + parameter);
}
constexpr std::uint16_t parameter_of(std::uint16_t index) noexcept {
    return static_cast<std::uint16_t>(index - 0x2000);
}

namespace p {
// General drive parameters used by the TWINsync operation modes.
inline constexpr std::uint16_t DriveComInit = 149;         // P0149 MPRO_DRVCOM_Init (4.1.2: force an init)
inline constexpr std::uint16_t ControlSelector = 159;      // P0159 MPRO_CTRL_SEL (TWINSYNC = 10)
inline constexpr std::uint16_t SetpointSelector = 165;     // P0165 MPRO_REF_SEL (TWINSYNC = 11)
inline constexpr std::uint16_t LocalResolution = 270;      // P0270 resolution factor (local)
inline constexpr std::uint16_t SpeedActualRpm = 281;       // P0281 speed actual value (rpm, Float32)
inline constexpr std::uint16_t ControlMode = 300;          // P0300 CON_CfgCon (TCON 1, SCON 2, PCON 3)
inline constexpr std::uint16_t SetpointMode = 301;         // P0301 setpoint mode (IP-Mode = 1)
inline constexpr std::uint16_t SwitchingFrequency = 302;   // P0302 CON_SwitchFreq
inline constexpr std::uint16_t PositionActual = 412;       // P0412 position actual value
inline constexpr std::uint16_t EncoderChannel3 = 507;      // P0507 selector for encoder channel 3
inline constexpr std::uint16_t CommutationEncoder = 520;   // P0520 encoder for commutation
inline constexpr std::uint16_t SpeedEncoder = 521;         // P0521 encoder for speed control
inline constexpr std::uint16_t GantryPositionLimit = 744;  // P0744 max. position tracking error
inline constexpr std::uint16_t SpeedSetpointRpm = 764;     // P0764 speed set-point (rpm, Float32)
inline constexpr std::uint16_t TorqueActualScaled = 2272;  // P2272 torque actual value (scaled, Int16)
// The TWINsync option.
inline constexpr std::uint16_t Setting = 2580;           // MPRO_TWIN_Setting (operation mode)
inline constexpr std::uint16_t MasterTorqueTF = 2581;    // filter time of the master's torque (VE), ms
inline constexpr std::uint16_t SlaveInverted = 2583;     // 1 / -1
inline constexpr std::uint16_t SpeedUp = 2584;           // % of the main set-point
inline constexpr std::uint16_t SpeedUpMinimum = 2585;    // rpm
inline constexpr std::uint16_t ActSpeedMaster = 2587;    // rpm (Float32)
inline constexpr std::uint16_t GantrySpeedLimit = 2595;  // max. speed tracking error (rpm)
inline constexpr std::uint16_t LocalRefTorque = 2596;
inline constexpr std::uint16_t LocalActTorque = 2597;
inline constexpr std::uint16_t LocalRefSpeed = 2598;
inline constexpr std::uint16_t LocalActSpeed = 2599;
inline constexpr std::uint16_t LocalRefPos = 2600;
inline constexpr std::uint16_t LocalActPos = 2601;
inline constexpr std::uint16_t LocalScaling = 2602;  // [0] torque Nm, [1] speed rpm
inline constexpr std::uint16_t RemoteRefTorque = 2603;
inline constexpr std::uint16_t RemoteActTorque = 2604;
inline constexpr std::uint16_t RemoteRefSpeed = 2605;
inline constexpr std::uint16_t RemoteActSpeed = 2606;
inline constexpr std::uint16_t RemoteRefPos = 2607;
inline constexpr std::uint16_t RemoteActPos = 2608;
inline constexpr std::uint16_t RemoteScaling = 2609;  // [0] torque Nm, [1] speed rpm, [2] current 100 mA
inline constexpr std::uint16_t SlaveCtrlWord = 2611;
inline constexpr std::uint16_t SlaveStatus = 2612;
inline constexpr std::uint16_t MaxFaultTime = 2613;  // ms (Float32)
inline constexpr std::uint16_t Mode = 2614;          // OFF / SLAVE / MASTER
inline constexpr std::uint16_t ProcessSendData = 2615;
inline constexpr std::uint16_t ProcessReceiveData = 2616;
inline constexpr std::uint16_t Statusword = 2617;  // received TWINsync status word
inline constexpr std::uint16_t SyncTicks = 2618;   // gain of the synchronisation controller, 15 ns/tick
inline constexpr std::uint16_t CommStatus = 2619;
inline constexpr std::uint16_t SystemLoad = 2623;    // ns (Float32)
inline constexpr std::uint16_t CurrentError = 2650;  // [0] error number, [1] error location
inline constexpr std::uint16_t Config = 2651;
inline constexpr std::uint16_t RemoteResolution = 2652;  // P2652 resolution factor (master)
inline constexpr std::uint16_t GearNumerator = 2653;
inline constexpr std::uint16_t GearDenominator = 2654;
inline constexpr std::uint16_t ReferenceValues = 2697;  // [2] reference current (100 mA), 4.1.6
inline constexpr std::uint16_t RemoteAcc = 2700;
inline constexpr std::uint16_t SyncSel = 2701;
inline constexpr std::uint16_t LocalRefFFSpeed = 2702;  // speed set-point for the feed-forward (scaled)
inline constexpr std::uint16_t PhyLinkConfig = 2709;    // [0] baud rate, [1] frame size
// Virtual encoder: single-turn angle of the master (16 bit).
inline constexpr std::uint16_t LocalActEps = 4220;
inline constexpr std::uint16_t RemoteActEps = 4221;
// Rack-and-pinion drive control: current and speed set-points of the process controller.
inline constexpr std::uint16_t RpdcCurrentTx = 4202;
inline constexpr std::uint16_t RpdcCurrentRx = 4203;
inline constexpr std::uint16_t RpdcSpeed = 4204;
}  // namespace p

// P0301 setpoint mode: the slave tables of chapter 6 require IP-Mode (1).
inline constexpr std::uint16_t kSetpointModeIp = 1;
// P0507 selector for encoder channel 3: TWINSYNC (6); P0520 / P0521: channel 3 = CH3 (3) (tables 6.1, 6.2).
inline constexpr std::uint16_t kEncoderChannel3Twinsync = 6;
inline constexpr std::uint16_t kEncoderCh3 = 3;

// P2614 TOPT_TWIN_Mode.
enum class Role : std::uint16_t { Off = 0, Slave = 1, Master = 2 };

// P0159 / P0165 selection values that hand control / set-points to TWINsync. Any other value keeps the
// EtherCAT controlword 0x6040 and the CiA 402 set-points.
inline constexpr std::uint16_t kControlByTwinsync = 10;
inline constexpr std::uint16_t kSetpointByTwinsync = 11;

// P2701 TOPT_TWIN_SyncSel.
enum class SyncSelection : std::uint16_t {
    SlaveByTwin = 0,      // SLAVE_SYNC_ISR
    SlaveByFieldbus = 1,  // SLAVE_SYNC_COM
    SlaveByTwinEnc = 2,   // SLAVE_SYNC_ENC
    MasterNoComSync = 3,  // MASTER_NO_COM_SYNC
};

// P2651 bits.
inline constexpr std::uint32_t kConfigNoSlaveStateCheck = 1u << 2;

// P2619 TOPT_TWIN_CommStatus bits (table 4.1). Bit 0 "no error" is set while no error bit is.
namespace comm_status {
inline constexpr std::uint16_t NoError = 1u << 0;
inline constexpr std::uint16_t CommunicationLost = 1u << 1;
inline constexpr std::uint16_t SwitchingFrequency = 1u << 2;
inline constexpr std::uint16_t ModeConflict = 1u << 3;
inline constexpr std::uint16_t DriveComState = 1u << 5;
}  // namespace comm_status

}  // namespace vecat::twinsync
