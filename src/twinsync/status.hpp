// What a TWINsync option card reports about its link: the values behind P2612, P2617, P2619 and P2623,
// and the counters a scope or the telemetry shows. Filled by the drive's TWINsync port every control cycle.
// And what the drive tells the port about itself (LocalState, made by the drive core's TWINsync coupling),
// and the interface of a device that reports a link (StatusSource).
#pragma once

#include <cstdint>

#include "twinsync/telegram.hpp"

namespace vecat::twinsync {

struct LinkStatus {
    std::uint16_t mode = 0;                // P2614: 0 OFF, 1 SLAVE, 2 MASTER
    std::uint8_t setting = 0;              // P2580 operation mode
    std::uint16_t tx_statusword = 0;       // TWINsync status word sent (table 4.5)
    std::uint16_t rx_statusword = 0;       // P2617: TWINsync status word received
    std::uint16_t comm_status = 0;         // P2619 bits
    std::uint16_t slave_control_word = 0;  // P2611
    std::uint16_t slave_status = 0;        // P2612
    std::uint64_t frames_sent = 0;
    std::uint64_t frames_received = 0;  // valid frames (CRC correct)
    std::uint64_t crc_errors = 0;
    std::uint64_t frames_missing = 0;   // control cycles without a frame from the other drive
    std::uint64_t initialisations = 0;  // P0149 MPRO_DRVCOM_Init writes that re-initialised the link
    std::int64_t sync_offset_ns = 0;    // slave: phase of its control cycle against the master's SYNC_OUT
    bool synchronised = false;          // slave: locked to SYNC_OUT (the master reports true)
    bool link_ok = false;               // valid frames within P2613
    std::uint8_t error_number = 0;      // MSD error (40 or 39), 0 = none
    std::uint8_t error_location = 0;
    float tracking_error = 0;  // gantry: master position minus slave position (user units)
};

// A device with a TWINsync option card, as the telemetry sees it: its link status (nullptr while no cable
// is connected). The drive (cia402::Drive) is one; an application that is one is found by a cross-cast
// from esc::Application, without knowing the drive class.
class StatusSource {
  public:
    virtual const LinkStatus* twinsync_status() const = 0;

  protected:
    ~StatusSource() = default;
};

// What the drive tells the port about itself every cycle.
struct LocalState {
    DriveComState state = DriveComState::SwitchOnDisabled;
    bool fault = false;
    bool homed = false;
    bool transition = false;        // a state change is in progress (P2612 OpInProgress)
    std::uint16_t controlword = 0;  // the drive's own CiA 402 controlword (a master sends it on)
    bool homing_mode = false;
    bool fieldbus_synchronised = false;  // the drive's cycle runs on EtherCAT DC (SYNC0)
    // For the gantry monitoring (master: 29 / slave: 30), in the units of the telegram.
    double position = 0;  // user units
    double speed_rpm = 0;
    double torque_nm = 0;
    double rated_torque_nm = 1;
};

}  // namespace vecat::twinsync
