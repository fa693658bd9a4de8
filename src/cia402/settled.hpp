// The periods of a settled drive: DriveCore skips the servo periods of a drive at a fixed point.
//
// The core is a function of its own bytes and the DriveIo's inputs (parameters, command, TWINsync inputs;
// the feedback is its output): it reads no clock and no global. A period that leaves the core's bytes as it
// found them is a fixed point, and so is every later period that finds them and the same inputs again: a
// drive holding its position with its motor settled (Mechanics skips those substeps already), a disabled
// drive at rest. Settled keeps the bytes of such a period, and DriveCore skips the periods that find them.
// The inputs are compared byte for byte at every period; the core's bytes after a public method ran (wake),
// since nothing else changes them between periods: an SDO hook that called compensate(), a new servo period.
//
// Three things may still change at a fixed point and are left out of the comparison:
// - the period count (steps_);
// - the hold timers (HoldTimer): those that ran in the settled period said yes to every read, so they go on
//   saying yes; the skipped periods' time is added before the core next runs;
// - the drive temperature, which goes on towards its steady value: a skipped period updates it as the
//   period would, and shows it (0x2001), nothing else reads it.
// A settled period raised no fault, cleared none and latched no probe; the feedback it published is the one
// the skipped periods would publish. The TWINsync values (every 16th period) are worked out by the first
// 16th period at a fixed point, which runs; the later ones show its values. While the TWINsync link is on,
// nothing is skipped.
//
// Included by the drive core's sources only (DriveCore::Settled is private to DriveCore).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <tuple>
#include <utility>

#include "cia402/drive_core.hpp"

namespace vecat::cia402 {

class DriveCore::Settled {
  public:
    explicit Settled(const DriveCore& core);

    // Before a period that may settle: the core and the DriveIo it finds, and the hold timers' time
    // (begin_timers alone: before a period that finds the settled bytes).
    void take(const DriveCore& core, const DriveIo& io);
    void begin_timers(const DriveCore& core);
    // The core and the DriveIo's inputs as the settled period found them. (The feedback is the core's: a
    // skipped period leaves the settled period's, with the temperature it updates.)
    bool same_core(const DriveCore& core) const;
    bool same_io(const DriveIo& io) const;
    // After the period that take() saw begin: was it a fixed point?
    bool settled(const DriveCore& core, const DriveIo& io) const;
    // Worth a check, at the end of a batch of periods: the feedback says the drive stands. A check that
    // fails waits a few batches before the next (a motor held by its static friction stands for seconds
    // while the velocity loop's integrator winds, without settling).
    bool worth_checking(const DriveFeedback& fb) {
        if (fb.velocity_actual != 0 || fb.velocity_demand != 0) return false;
        if (backoff_ > 0) {
            --backoff_;
            return false;
        }
        return true;
    }
    void failed() { backoff_ = kBackoff; }

    bool enabled = true;              // skip_settled_periods
    bool on = false;                  // the last period that ran settled
    bool touched = true;              // a public method ran since the core's bytes were last found the same
    bool temperature_steady = false;  // a skipped period left the temperature as it was
    bool values_current = false;      // the feedback's TWINsync values were worked out at this fixed point
    std::uint64_t pending = 0;        // periods skipped since the hold timers caught up
    std::uint64_t skipped = 0;        // periods skipped in all

  private:
    static constexpr unsigned kBackoff = 16;
    static constexpr std::size_t kTimers = std::tuple_size_v<decltype(timers_)>;
    std::array<std::pair<std::size_t, std::size_t>, kTimers + 3> gaps_{};  // [from, to) of the core's bytes
    std::array<unsigned char, sizeof(DriveCore)> core_{};
    std::array<unsigned char, sizeof(DriveIo)> io_{};
    std::array<double, kTimers> timer_before_{};
    unsigned backoff_ = 0;
};

}  // namespace vecat::cia402
