// The TWINsync coupling of the drive core (MSD TWINsync option, specification CB08759-001; see
// src/twinsync/README.md): what the drive does with the option card's findings, apart from EtherCAT.
//   - the controlword: a slave controlled through TWINsync (P0159) obeys the master drive's control word
//     P2611; a master keeps its enable back until its slave is in state Control (unless P2651 bit 2);
//   - the set-points: a slave on TWINsync's set-points (P0165) follows its master drive in position
//     (absolute or in increments, the latter with a coupling factor that may change while coupled,
//     smoothed by AccBound 0x2115: TX1250 3.3), speed (with speed-up or torque precontrol) or torque,
//     coupling only at standstill of both axes; decoupled in motion it goes on at its velocity until it is
//     stopped, halted or given a new set-point;
//   - the errors of the monitoring (40-xx, 39-xx) become faults in state Control (chapter 7);
//   - the local values the telegram sends (P2596-P2601, P4220, P2650) and the drive's state for the
//     port (twinsync::LocalState).
// The option card itself, bound to the dictionary, is twinsync_port.hpp; DriveCore runs this part.
#pragma once

#include <cstdint>
#include <optional>

#include "cia402/drive_io.hpp"
#include "cia402/mechanics.hpp"
#include "cia402/operation_mode.hpp"
#include "cia402/state_machine.hpp"
#include "twinsync/errors.hpp"
#include "twinsync/status.hpp"

namespace vecat::cia402 {

class TwinsyncCoupling {
  public:
    // The controlword the drive obeys this period (the TWINsync control word arrived with the receive).
    std::uint16_t controlword(std::uint16_t own, const TwinsyncInputs& t, State state);

    // The error the drive raised as a fault (kept until the fault is reset), and the fault that raises it.
    std::optional<twinsync::ErrorId> error() const { return error_; }
    RaisedFault raise(twinsync::ErrorId e);
    void clear_error() { error_.reset(); }
    // The raised error is still what the monitoring finds (the fault is present).
    bool error_present(const TwinsyncInputs& t) const { return error_ && t.pending_error == error_; }

    // Before the set-points of a period: a slave that follows no more (link, selector) decouples, and goes
    // on in motion if it was following set-points. Returns whether the axis follows TWINsync.
    bool update(Axis& a, const TwinsyncInputs& t, bool following_setpoints);
    // The drive function stopped or a stop ramp runs: no coupling, no decoupled motion.
    void release(Axis& a) { a.coupled = continuing_ = false; }
    // A mode was selected: the decoupled motion ends.
    void end_motion() { continuing_ = false; }
    // One period (dt seconds) following the master drive.
    void follow(Axis& a, const TwinsyncInputs& t, double dt);
    // Decoupled motion: one period at the velocity of the coupling. false: a new set-point, target or
    // mode ended it (the mode takes over in this period).
    bool continuing() const { return continuing_; }
    bool continue_motion(Axis& a, double dt);

    // Homing attained once (sent in the TWINsync status word).
    void set_homed() { homed_ = true; }

    // The drive's state for the port.
    twinsync::LocalState local(State state, StopKind stop, std::uint16_t controlword, bool homing_mode,
                               bool synchronised, const Axis& a, const Mechanics& m) const;
    // The local values of the telegram; active_fault: the 0x603F code shown in P2650 without a TWINsync
    // error.
    TwinsyncValues values(const Axis& a, const Mechanics& m, double machine_increments,
                          std::uint16_t active_fault, const TwinsyncInputs& t) const;

  private:
    void hold_for_coupling(Axis& a);
    // REFPOS (6.2.10): the master's homing carries over to the slave; see follow().
    void take_master_reference(Axis& a, const TwinsyncInputs& t, double dt);
    // PCON (TX1250 3.3): moves the applied coupling factor towards the commanded one within AccBound.
    void smooth_factor(double commanded, std::int32_t delta, std::uint32_t acc_bound, double dt);

    std::optional<twinsync::ErrorId> error_;
    std::int32_t master_last_ = 0;  // master position at the previous cycle (PCON increments)
    double factor_ = 1;             // PCON: the coupling factor applied (smoothed by AccBound, 0x2115)
    std::uint16_t control_ = 0, previous_control_ = 0;
    bool continuing_ = false, continue_halting_ = false;
    double continue_velocity_ = 0;
    std::int32_t continue_target_position_ = 0, continue_target_velocity_ = 0;
    bool homed_ = false;
    // REFPOS: the master's position set-point in the last two telegrams (for its re-referencing).
    std::int32_t refpos_last_ = 0;
    std::int64_t refpos_step_ = 0;
    int refpos_seen_ = 0;         // telegrams seen since coupling (0, 1, 2 = both of the above valid)
    double torque_filtered_ = 0;  // VE: the master's torque after the P2581 filter (per mille)
};

}  // namespace vecat::cia402
