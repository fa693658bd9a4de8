// The drive core's inputs and outputs, typed and without EtherCAT: what the CoE adapter (cia402::Drive,
// drive.cpp) copies out of the dictionary before a servo period and back into it afterwards. Each field
// names the object it comes from or goes to; its default is the value the drive uses when the dictionary
// has no such object (a vendor's ESI without it).
//
// When the adapter reads what:
//   - DriveParameters (the profile parameters 0x605A-0x60C6 and the manufacturer objects 0x2003,
//     0x2100-0x2110) only after one of their entries was written (coe::EntryHooks::writes counts SDO
//     downloads, process data outputs and every Entry::set/assign, also a TWINsync receive mapping's), so
//     an unchanged dictionary costs the servo period nothing; checked before each advance and after the
//     TWINsync port's receive in each period;
//   - DriveCommand (controlword, mode, set-points) the same way, after a write or process data outputs;
//   - TwinsyncInputs every servo period, after the receive (the remote values it has just written); the
//     TWINsync parameters only while the link is on, the local references P2602 with DriveParameters.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>

#include "cia402/factor_group.hpp"
#include "cia402/state_machine.hpp"
#include "cia402/touch_probe.hpp"
#include "protocol/cia402.hpp"
#include "twinsync/errors.hpp"
#include "twinsync/mapping.hpp"

namespace vecat::cia402 {

// Modes of operation (0x6060/0x6061), protocol/cia402.hpp.
using protocol::cia402::Mode;
// The modes the drive runs (0x6502 = 0x3AD): PP, PV, PT, HM, CSP, CSV, CST.
bool supported(Mode m) noexcept;

// 0x603F error codes the drive raises (IEC 61800-7-201 / CiA 402 error code table).
namespace fault {
inline constexpr std::uint16_t OverCurrent = 0x2310;     // continuous over current
inline constexpr std::uint16_t Encoder = 0x7305;         // incremental sensor 1 fault
inline constexpr std::uint16_t FollowingError = 0x8611;  // following error
inline constexpr std::uint16_t ReferenceLimit = 0x8612;  // reference limit (limit switch reached)
bool injectable(std::uint16_t code) noexcept;
}  // namespace fault

// 0x2112, a profile position target beyond the software position limits 0x607D (src/cia402/README.md,
// "Targets beyond the software position limits"): refused in every case but Clamp (the set-point is not
// acknowledged, statusword bit 11 until a target is accepted).
namespace limit_reaction {
inline constexpr std::uint8_t Fault = 0;   // refused, and the fault 0x8612 (TX1250 2.1: "an error")
inline constexpr std::uint8_t Refuse = 1;  // refused, no fault: the axis goes on with what it did
inline constexpr std::uint8_t Clamp = 2;   // accepted, the target clamped to the limit
}  // namespace limit_reaction

// Statusword bits (CiA 402 6.3.3), protocol/cia402.hpp.
namespace sw = protocol::cia402::sw;

// The small strategies in which the drives behind different devices differ. The CoE adapter sets them
// once from the device's DriveVariant (drive_variant.hpp); the defaults are the vecat drive's.
enum class HomingConvention : std::uint8_t {
    Cia402,  // 0x6098 names the methods of homing.hpp as CiA 402 numbers them
    Hiwin,   // HIWIN guide 9.4: 0 no homing, 1-6 and 33/34 with a home switch the axis passes through
             // (a dog), and the accuracy compensation of 0x2010 bit 0 (statusword bit 15)
};
enum class InterpolationFormat : std::uint8_t {
    ValueIndex,   // CiA 402: 0x60C2:1 (UINT8) x 10^0x60C2:2 s
    Ticks62_5us,  // HIWIN guide 9.1.2: 0x60C2:1 (UINT16) in 62.5 us
};
struct DriveStrategy {
    HomingConvention homing = HomingConvention::Cia402;
    InterpolationFormat interpolation = InterpolationFormat::ValueIndex;
    // HIWIN guide 10: touch probe 1 only, triggered by the encoder's zero signal (Z phase) whatever its
    // trigger selection (0x60B8 0x0011 latches on the index).
    bool probe_on_index = false;
    // The home switch is a dog of this many increments from 0x2100:3 (0: active from 0x2100:3 upwards).
    std::int32_t home_switch_length = 0;
};

// Parameters: the profile objects and the manufacturer objects, read again after a write.
struct DriveParameters {
    DriveStrategy strategy;                              // set once by the adapter
    OptionCodes options;                                 // 0x605A-0x605E
    FactorGroup factors;                                 // 0x608F, 0x6091, 0x6092 (applied only when valid)
    std::uint32_t rated_current = 3000;                  // 0x6075, mA
    std::uint32_t rated_torque = 1000;                   // 0x6076, mNm
    std::uint32_t following_error_window = 0xFFFFFFFFu;  // 0x6065 (0xFFFFFFFF: monitoring off)
    std::uint16_t following_error_timeout = 0;           // 0x6066, ms
    std::uint32_t position_window = 0;                   // 0x6067
    std::uint16_t position_window_time = 0;              // 0x6068, ms
    std::uint16_t velocity_window = 0;                   // 0x606D
    std::uint16_t velocity_window_time = 0;              // 0x606E, ms
    std::uint16_t velocity_threshold = 10;               // 0x606F
    std::uint16_t velocity_threshold_time = 0;           // 0x6070, ms
    std::uint16_t max_torque = 3000;                     // 0x6072, per mille
    std::uint16_t positive_torque_limit = 3000;          // 0x60E0
    std::uint16_t negative_torque_limit = 3000;          // 0x60E1
    std::uint32_t max_profile_velocity = 0xFFFFFFFFu;    // 0x607F
    std::uint32_t max_motor_speed = 0;                   // 0x6080, rpm (0: none)
    std::uint32_t profile_velocity = 1;                  // 0x6081
    std::uint32_t profile_acceleration = 1;              // 0x6083
    std::uint32_t profile_deceleration = 1;              // 0x6084
    std::uint32_t quick_stop_deceleration = 1;           // 0x6085
    std::uint32_t max_acceleration = 0;                  // 0x60C5 (0: none)
    std::uint32_t max_deceleration = 0;                  // 0x60C6 (0: none)
    std::int16_t motion_profile_type = 0;                // 0x6086 (0 trapezoid, else jerk-limited)
    std::uint32_t profile_jerk = 0;                      // 0x60A4:1
    std::uint32_t torque_slope = 0;                      // 0x6087, per mille/s
    // 0x607D:1/2. Absent, they read as INT32_MIN/INT32_MAX for "enabled" (min < max) and as 0 for the
    // clamp, as the drive always did (Axis::software_limits_enabled): a dictionary without 0x607D clamps
    // every position set-point to 0 (a known quirk, kept).
    std::optional<std::int32_t> software_limit_min, software_limit_max;
    std::int32_t home_offset = 0;           // 0x607C
    std::int8_t homing_method = 0;          // 0x6098
    std::uint32_t homing_speed_switch = 0;  // 0x6099:1
    std::uint32_t homing_speed_zero = 0;    // 0x6099:2
    std::uint32_t homing_acceleration = 0;  // 0x609A
    std::uint16_t interpolation_value = 1;  // 0x60C2:1 (strategy.interpolation says its unit)
    std::int8_t interpolation_index = -3;   // 0x60C2:2
    // The manufacturer objects of the vecat drive (src/cia402/README.md).
    std::uint32_t gain_position_kp = 0;        // 0x2003:1 (0: tuned from the motor)
    std::uint32_t gain_velocity_kp = 0;        // 0x2003:2
    std::uint32_t gain_velocity_ti = 0;        // 0x2003:3
    std::uint32_t gain_current_bandwidth = 0;  // 0x2003:4
    std::int32_t negative_limit_switch = std::numeric_limits<std::int32_t>::min();  // 0x2100:1
    std::int32_t positive_limit_switch = std::numeric_limits<std::int32_t>::max();  // 0x2100:2
    std::int32_t home_switch = std::numeric_limits<std::int32_t>::max();            // 0x2100:3
    std::int32_t index_pulse_offset = 0;                                            // 0x2100:4
    std::int16_t load_torque = 0;                                                   // 0x2100:5, per mille
    std::uint8_t probe_inputs = 0;                                                  // 0x2100:6
    std::uint8_t limit_switch_reaction = 0;                                         // 0x2100:7 (1: fault)
    std::uint16_t simulated_fault = 0;                                              // 0x2101
    std::uint32_t velocity_override = 1'000'000;                                    // 0x2110, ppm
    // 0x2112: what a profile position target beyond 0x607D gets (limit_reaction). Without the object it
    // is clamped to the limit, as the drive always did.
    std::uint8_t software_limit_reaction = limit_reaction::Clamp;
    // 0x2113: the override type of TX1250 2.2 (1-4; out of range reads as 4).
    std::uint8_t override_type = 4;
    // 0x2114:1-3: new velocity at an activation position (TX1250 2.4): APos, VNew, mode (1: each new
    // profile position set-point is a "new velocity and new end position" request; 0: off).
    std::int32_t activation_position = 0;
    std::uint32_t activation_velocity = 0;
    std::uint8_t activation_mode = 0;
    // 0x2115 AccBound (TX1250 3.3): the TWINsync PCON slave's acceleration caused by a change of its
    // coupling factor P2653/P2654 is at most this (user units/s^2); 0: the factor applies at once.
    std::uint32_t coupling_acc_bound = 0;
    // 0x607B:1/2: position range limit; min < max and narrower than INT32 makes the axis modulo
    // (range max - min: max is the same point as min). 0x60F2: positioning option code (bits 6/7: the
    // rotary axis direction option).
    std::int32_t position_range_min = std::numeric_limits<std::int32_t>::min();
    std::int32_t position_range_max = std::numeric_limits<std::int32_t>::max();
    std::uint16_t positioning_option = 0;
    bool fieldbus_synchronised = false;  // the slave's cycle runs on SYNC0/SYNC1 (0x1C32:1)
};

// The set-points of one servo period.
struct DriveCommand {
    std::uint16_t controlword = 0;     // 0x6040
    std::int8_t mode = 0;              // 0x6060
    std::int32_t target_position = 0;  // 0x607A
    std::int32_t target_velocity = 0;  // 0x60FF
    std::int16_t target_torque = 0;    // 0x6071
    std::int32_t position_offset = 0;  // 0x60B0
    std::int32_t velocity_offset = 0;  // 0x60B1
    std::int16_t torque_offset = 0;    // 0x60B2
    std::uint16_t probe_function = 0;  // 0x60B8
    std::uint16_t input_function = 0;  // HIWIN 0x2010 (bit 0: accuracy compensation after homing)
};

// The TWINsync option card this period (what the port found on receive) and the TWINsync parameters
// (MSD parameter Pnnnn, object 0x2000 + nnnn; src/twinsync/README.md).
struct TwinsyncInputs {
    bool active = false;                  // a cable and P2614 not OFF
    bool follows = false;                 // a slave on TWINsync's set-points (P0165)
    bool has_data = false;                // valid data from the partner since the link came up
    bool fresh = false;                   // a valid telegram arrived in this period
    bool controlled_by_twinsync = false;  // a slave on TWINsync's control word (P0159)
    bool link_ok = false;
    twinsync::Role role = twinsync::Role::Off;
    twinsync::Role partner_role = twinsync::Role::Off;  // the partner's TWINsync status word
    bool partner_enabled = false;                       // the partner is in DriveCom state Control
    const twinsync::ModeInfo* mode = nullptr;           // P2580
    std::uint16_t received_control_word = 0;            // P2611
    std::optional<twinsync::ErrorId> pending_error;     // the monitoring's finding this period
    std::uint16_t control_mode = 3;                     // P0300 (1 TCON, 2 SCON, 3 PCON)
    std::uint32_t config = 0;                           // P2651
    std::int16_t inverted = 1;                          // P2583
    float speed_up = 0;                                 // P2584, %
    float speed_up_minimum = 0;                         // P2585, rpm
    float act_speed_master = 0;                         // P2587, rpm
    float local_torque_reference = 1.0f;                // P2602[0], Nm
    float local_speed_reference = 1.0f;                 // P2602[1], rpm
    float remote_torque_reference = 1.0f;               // P2609[0], Nm
    float remote_speed_reference = 1.0f;                // P2609[1], rpm
    std::int16_t remote_ref_torque = 0;                 // P2603
    std::int16_t remote_act_torque = 0;                 // P2604
    std::int16_t remote_ref_speed = 0;                  // P2605
    std::int16_t remote_act_speed = 0;                  // P2606
    std::int32_t remote_ref_pos = 0;                    // P2607
    std::int32_t remote_act_pos = 0;                    // P2608
    std::uint32_t local_resolution = 1;                 // P0270
    std::uint32_t remote_resolution = 1;                // P2652
    std::int32_t gear_numerator = 1;                    // P2653
    std::int32_t gear_denominator = 1;                  // P2654
    float master_torque_tf = 0;                         // P2581, ms (VE: filter of the master's torque)
};

// The local TWINsync values (section 4.1.6: 16-bit fractions of the references P2602).
struct TwinsyncValues {
    std::int16_t ref_torque = 0;       // P2596
    std::int16_t act_torque = 0;       // P2597, also P2272
    std::int16_t ref_speed = 0;        // P2598, also P2702
    std::int16_t act_speed = 0;        // P2599
    std::int32_t ref_pos = 0;          // P2600
    std::int32_t act_pos = 0;          // P2601, also P0412
    float speed_actual_rpm = 0;        // P0281
    float speed_setpoint_rpm = 0;      // P0764
    std::uint16_t eps = 0;             // P4220: single-turn angle of the motor, 16 bit
    std::uint16_t error_number = 0;    // P2650[0]
    std::uint16_t error_location = 0;  // P2650[1]
};

// A fault the core raised this period: 0x603F code, 0x1001 bits and the emergency's manufacturer bytes.
struct RaisedFault {
    std::uint16_t code = 0;
    std::uint8_t register_bits = 0;
    std::array<std::uint8_t, 5> data{};
};

// What a servo period produces.
struct DriveFeedback {
    std::uint16_t statusword = 0;               // 0x6041
    std::int8_t mode_display = 0;               // 0x6061
    std::int32_t position_demand = 0;           // 0x6062
    std::int32_t position_internal = 0;         // 0x6063
    std::int32_t position_actual = 0;           // 0x6064
    std::int32_t velocity_demand = 0;           // 0x606B
    std::int32_t velocity_actual = 0;           // 0x606C
    std::int16_t torque_demand = 0;             // 0x6074
    std::int16_t torque_actual = 0;             // 0x6077
    std::int16_t current_actual = 0;            // 0x6078
    std::int32_t following_error = 0;           // 0x60F4
    std::int32_t position_demand_internal = 0;  // 0x60FC
    std::uint32_t digital_inputs = 0;           // 0x60FD
    std::int16_t temperature = 0;               // 0x2001, 0.1 C
    // The encoder's index (Z phase): seen since power-up (HIWIN 0x2020), and the position of the last one
    // (HIWIN 0x2021), in user units as 0x6064.
    bool index_touched = false;
    std::int32_t index_position = 0;
    // The touch probe (0x60B9, and 0x60BA-0x60BD where latched), set by a servo period only.
    bool probe = false;
    std::uint16_t probe_status = 0;
    TouchProbe::Latched probe_latched;
    // The local TWINsync values, when `twinsync` is set (every period while the link is on, otherwise
    // every 4 ms for SDO reads).
    bool twinsync = false;
    TwinsyncValues twinsync_values;
    // Faults raised and cleared this period, in this order (the adapter sends the emergencies).
    std::optional<RaisedFault> raised;
    bool cleared = false;
};

struct DriveIo {
    DriveParameters parameters;
    DriveCommand command;
    TwinsyncInputs twinsync;
    DriveFeedback feedback;  // written by the core only (its settled periods rely on it, settled.hpp)
};

}  // namespace vecat::cia402
