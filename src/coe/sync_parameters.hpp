// Application synchronisation of a CoE slave (ETG.1020 clause 21 "Synchronization", ETG.1000.6 5.6.7.4.8):
// the SM output/input parameter objects 0x1C32/0x1C33, the choice between free run, SM-synchronous and
// DC SYNC0/SYNC1 at PREOP -> SAFEOP, the wait for SYNC0 at SAFEOP -> OP, and the synchronisation counters
// and errors in SAFEOP/OP.
//
// Supported cycle times (the drive's "supported set"): multiples of 125 us from max(125 us, 0x1C32:05) to
// 4 ms. That includes the HIWIN D2's 250 us, 500 us, 1 ms, 2 ms and 4 ms.
//
// AL status codes (as the Beckhoff slave stack code uses them, ETG.1000.6 Table 11):
//  - 0x0030 invalid DC SYNC configuration: 0x1C32:01 asks for DC but 0x0981 has no SYNC0 (or no cyclic
//    operation), SYNC1 activated without SYNC0, or DC SYNC1 mode without SYNC1;
//  - 0x0036 / 0x0037 DC SYNC0 / SYNC1 cycle time: not in the supported set (below 0x1C32:05, above 4 ms, not
//    a multiple of 125 us, 0 = single shot);
//  - 0x0035 invalid sync cycle time: 0x1C32:02 written by the master and different from the cycle the
//    configuration gives (or outside the supported range in free run / SM-synchronous mode);
//  - 0x0028 synchronisation not supported: a mode this device does not have (0x1C32:04);
//  - 0x002D no sync error: SAFEOP -> OP in DC mode and SYNC0 does not run within kSyncWaitNs;
//  - 0x0032 PLL error: the SYNC0 cycle time changed after it was checked (the drive cannot lock on it);
//  - 0x002C fatal sync error: in OP, SYNC0 stopped, or the sync error counter passed 0x10F1:02 (+3 per
//    SYNC event without new outputs, -1 per good one, ETG.1020; a limit of 0 disables the check).
#pragma once

#include <cstdint>

#include "coe/object_dictionary.hpp"
#include "device/device_description.hpp"
#include "esc/slave.hpp"
#include "protocol/al_status.hpp"

namespace vecat::coe {

// 0x1C32:01 / 0x1C33:01 values (ETG.1020 Table 79).
enum class SyncMode : std::uint16_t {
    FreeRun = 0x0000,
    SmSynchronous = 0x0001,  // 0x1C32: synchronous with the SM2 event
    DcSync0 = 0x0002,
    DcSync1 = 0x0003,
    Sm2Event = 0x0022,  // 0x1C33 only: inputs synchronous with the SM2 event
};

struct SyncCounters {
    std::uint64_t cycles = 0;            // application cycles run on SYNC events
    std::uint64_t sm_events_missed = 0;  // SYNC events in OP without new outputs since the previous one
    std::uint64_t cycles_missed = 0;     // SYNC events the firmware could not take (cycle time too small)
    std::uint64_t sync_errors = 0;       // times the sync error counter passed its limit
};

class SyncParameters {
  public:
    static constexpr std::uint32_t kGranularityNs = 125'000;
    static constexpr std::uint32_t kMaxCycleNs = 4'000'000;
    static constexpr std::uint64_t kSyncWaitNs = 1'000'000'000;  // SAFEOP -> OP wait for SYNC0
    static constexpr std::uint64_t kSyncLostMinNs = 2'000'000;   // SYNC0 silence in OP (at least 3 cycles)

    SyncParameters(ObjectDictionary& od, const device::DeviceDescription& d);
    void attach(esc::Slave& slave);

    // PREOP -> SAFEOP: chooses the mode from 0x1C32:01 and the DC activation (0x0981); NoError or the code.
    protocol::AlStatusCode check_safeop();
    // SAFEOP -> OP: a master that activated SYNC0 only in SAFEOP (SOEM's ecx_dcsync0 after ecx_config_map)
    // without choosing a mode in 0x1C32:01 gets DC mode now, with the same checks as at PREOP -> SAFEOP.
    protocol::AlStatusCode check_op();
    // Entering SAFEOP from PREOP publishes the mode and cycle (0x1C32/0x1C33, 0x60C2) and resets the
    // counters.
    void on_state_change(protocol::AlState from, protocol::AlState to);
    esc::OpReadiness op_readiness(std::uint64_t now_ns, std::uint64_t since_ns) const;
    // A SYNC pulse: true when it is the one the application cycle runs on (DC mode). Counts and may raise
    // the fatal sync error through the slave.
    bool on_sync_event(unsigned signal, std::uint64_t now_ns, protocol::AlState state);
    // Time-driven supervision (SYNC lost in OP, PLL).
    void tick(std::uint64_t now_ns, protocol::AlState state);
    // When tick() would find SYNC lost if no SYNC event came before (~0: it cannot).
    std::uint64_t next_deadline_ns(protocol::AlState state) const;

    SyncMode mode() const { return mode_; }
    bool dc_mode() const { return mode_ == SyncMode::DcSync0 || mode_ == SyncMode::DcSync1; }
    // The application cycle: SYNC0 (SYNC1) cycle in DC mode, 0x1C32:02 otherwise, 0 if unknown.
    std::uint64_t cycle_time_ns() const;
    const SyncCounters& counters() const { return counters_; }
    std::uint16_t sync_error_counter() const { return error_counter_; }

    // Whether a cycle time is in the supported set (see above).
    bool cycle_supported(std::uint32_t ns) const;

  private:
    void publish();
    void raise(protocol::AlStatusCode code);
    std::uint32_t min_cycle_ns() const;
    template <class T>
    void put(std::uint16_t index, std::uint8_t sub, T v);
    std::uint64_t get(std::uint16_t index, std::uint8_t sub) const;

    ObjectDictionary& od_;
    esc::Slave* slave_ = nullptr;
    int sm_out_ = -1;
    bool dc_supported_ = false;
    bool has_inputs_ = false;
    SyncMode mode_ = SyncMode::SmSynchronous;
    std::uint32_t app_cycle_ns_ = 0;       // checked at PREOP -> SAFEOP
    std::uint32_t checked_cycle0_ns_ = 0;  // SYNC0 cycle register then
    std::uint32_t slave_cycle_value_ = 0;  // 0x1C32:02 as the slave last set it (else: written by the master)
    std::uint64_t sync_events_ = 0;        // cycle events since SAFEOP
    std::uint64_t last_event_ns_ = 0;
    std::uint64_t sm_writes_at_last_ = 0;
    std::uint64_t not_delivered_at_last_ = 0;
    std::uint16_t error_counter_ = 0;
    bool faulted_ = false;
    bool mode_written_ = false;                     // the master wrote 0x1C32:01
    SyncMode requested_ = SyncMode::SmSynchronous;  // 0x1C32:01 as configured (the slave overwrites it)
    SyncCounters counters_;
};

}  // namespace vecat::coe
