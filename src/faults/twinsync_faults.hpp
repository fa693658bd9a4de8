// The TWINsync faults of the injector (twinsync_cable_break, twinsync_crc_errors, twinsync_sync_loss):
// they act through the drive's own fault injection object 0x2104, so they are what a user could also set
// by SDO, and the drives see them exactly like a real cable fault.
#pragma once

#include "esc/segment.hpp"
#include "faults/injector.hpp"

namespace vecat::faults {

class TwinsyncFaults final : public FaultHandler {
  public:
    explicit TwinsyncFaults(esc::Segment& seg) : seg_(seg) {}
    void start(const FaultSpec& f, std::uint64_t now_ns) override;
    void stop(const FaultSpec& f, std::uint64_t now_ns) override;

  private:
    void write(const FaultSpec& f, bool on);
    esc::Segment& seg_;
};

// Registers the handler for the three TWINsync fault kinds.
void register_twinsync_faults(FaultInjector& injector, TwinsyncFaults& handler);

}  // namespace vecat::faults
