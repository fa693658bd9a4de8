#include "coe/sync_parameters.hpp"

#include <algorithm>

#include "protocol/cia402_objects.hpp"
#include "protocol/registers.hpp"

namespace vecat::coe {

using protocol::AlState;
using protocol::AlStatusCode;

namespace {

constexpr std::uint16_t kOutPar = protocol::obj::sync_parameter::outputs;
constexpr std::uint16_t kInPar = protocol::obj::sync_parameter::inputs;
// Subindices of 0x1C32/0x1C33 (ETG.1020 Table 78).
namespace sub {
namespace sp = protocol::obj::sync_parameter;
constexpr std::uint8_t SyncMode = sp::sync_mode;
constexpr std::uint8_t CycleTime = sp::cycle_time;
constexpr std::uint8_t ShiftTime = sp::shift_time;
constexpr std::uint8_t MinimumCycleTime = sp::minimum_cycle_time;
constexpr std::uint8_t GetCycleTime = sp::get_cycle_time;
constexpr std::uint8_t Sync0CycleTime = sp::sync0_cycle_time;
constexpr std::uint8_t SmEventMissed = sp::sm_event_missed;
constexpr std::uint8_t CycleTimeTooSmall = sp::cycle_time_too_small;
constexpr std::uint8_t ShiftTimeTooShort = sp::shift_time_too_short;
constexpr std::uint8_t SyncError = sp::sync_error;
}  // namespace sub

constexpr std::uint16_t kErrorSettings = protocol::obj::error_settings::index;
constexpr std::uint8_t kSyncErrorLimit = protocol::obj::error_settings::sync_error_counter_limit.subindex;
constexpr std::uint16_t kInterpolationPeriod = protocol::obj::interpolation_time_period::index;

// ETG.1020 21.1.3: the sync error counter goes up by 3 for each missed event and down by 1 for each good one.
constexpr std::uint16_t kErrorStep = 3;

// value x 10^index seconds = ns, with value <= 255 (0x60C2:01 is UNSIGNED8); ms, then us, then the others.
bool interpolation_period(std::uint64_t ns, std::uint8_t& value, std::int8_t& index) {
    struct Unit {
        std::int8_t index;
        std::uint64_t ns;
    };
    static constexpr Unit kUnits[] = {{-3, 1'000'000}, {-6, 1'000}, {-4, 100'000}, {-5, 10'000}};
    for (const auto& u : kUnits) {
        if (ns % u.ns == 0 && ns / u.ns >= 1 && ns / u.ns <= 255) {
            value = static_cast<std::uint8_t>(ns / u.ns);
            index = u.index;
            return true;
        }
    }
    return false;
}

}  // namespace

SyncParameters::SyncParameters(ObjectDictionary& od, const device::DeviceDescription& d) : od_(od) {
    if (auto sm = d.sm_index_of_type(device::SmType::Outputs)) sm_out_ = static_cast<int>(*sm);
    has_inputs_ = d.sm_index_of_type(device::SmType::Inputs).has_value();
    for (const auto& m : d.dc_modes)
        if (m.assign_activate != 0) dc_supported_ = true;
    slave_cycle_value_ = static_cast<std::uint32_t>(get(kOutPar, sub::CycleTime));
    requested_ = static_cast<SyncMode>(get(kOutPar, sub::SyncMode));
    mode_ = requested_;
    // 0x1C32:01 takes the modes this device has; anything else is refused when written.
    if (Entry* e = od_.find(kOutPar, sub::SyncMode)) {
        e->hooks().on_download = [this](const Entry&, ConstBytes v) {
            const std::uint16_t m = v.size() >= 2 ? ld_le16(v.data()) : (v.empty() ? 0xFFFF : v[0]);
            const bool dc = m == static_cast<std::uint16_t>(SyncMode::DcSync0) ||
                            m == static_cast<std::uint16_t>(SyncMode::DcSync1);
            if (m == static_cast<std::uint16_t>(SyncMode::FreeRun) ||
                m == static_cast<std::uint16_t>(SyncMode::SmSynchronous) || (dc && dc_supported_))
                return SdoAbort::None;
            return SdoAbort::ValueRange;
        };
        e->hooks().after_download = [this](Entry& en) {
            mode_written_ = true;
            requested_ = static_cast<SyncMode>(en.get<std::uint16_t>());
        };
    }
    // 0x1C32:08 "Get cycle time": 2 resets the error counters (ETG.1020 Table 78).
    if (Entry* e = od_.find(kOutPar, sub::GetCycleTime)) {
        e->hooks().after_download = [this](Entry& en) {
            if (en.get<std::uint16_t>() == 2) {
                put<std::uint16_t>(kOutPar, sub::SmEventMissed, 0);
                put<std::uint16_t>(kOutPar, sub::CycleTimeTooSmall, 0);
                put<std::uint16_t>(kOutPar, sub::ShiftTimeTooShort, 0);
                en.set(std::uint16_t{0});
            }
        };
    }
}

void SyncParameters::attach(esc::Slave& slave) {
    slave_ = &slave;
}

template <class T>
void SyncParameters::put(std::uint16_t index, std::uint8_t s, T v) {
    if (Entry* e = od_.find(index, s)) e->set(v);
}

std::uint64_t SyncParameters::get(std::uint16_t index, std::uint8_t s) const {
    const Object* o = od_.find(index);
    const Entry* e = o ? o->entry(s) : nullptr;
    return e ? e->as_uint64() : 0;
}

std::uint32_t SyncParameters::min_cycle_ns() const {
    return std::max<std::uint32_t>(kGranularityNs,
                                   static_cast<std::uint32_t>(get(kOutPar, sub::MinimumCycleTime)));
}

bool SyncParameters::cycle_supported(std::uint32_t ns) const {
    return ns >= min_cycle_ns() && ns <= kMaxCycleNs && ns % kGranularityNs == 0;
}

std::uint64_t SyncParameters::cycle_time_ns() const {
    if (dc_mode()) return app_cycle_ns_;
    return get(kOutPar, sub::CycleTime);
}

AlStatusCode SyncParameters::check_safeop() {
    if (!slave_) return AlStatusCode::NoError;
    const esc::Esc& esc = slave_->esc();
    const std::uint8_t act = esc.peek(protocol::addr(protocol::Reg::DcActivation));
    const bool cyclic = act & esc::dc_act::CyclicOperation;
    const bool s0 = act & esc::dc_act::Sync0;
    const bool s1 = act & esc::dc_act::Sync1;
    const SyncMode requested = requested_;
    const auto written_cycle = static_cast<std::uint32_t>(get(kOutPar, sub::CycleTime));
    const bool cycle_written = written_cycle != slave_cycle_value_ && written_cycle != 0;
    const bool wants_dc = requested == SyncMode::DcSync0 || requested == SyncMode::DcSync1;

    if (s0 || s1) {
        if (!dc_supported_) return AlStatusCode::SyncNotSupported;
        if (!cyclic || !s0) return AlStatusCode::InvalidDcSyncConfig;
        if (requested == SyncMode::DcSync1 && !s1) return AlStatusCode::InvalidDcSyncConfig;
        const std::uint32_t c0 = esc.peek32(protocol::addr(protocol::Reg::DcSync0CycleTime));
        const std::uint32_t c1 = esc.peek32(protocol::addr(protocol::Reg::DcSync1CycleTime));
        if (!cycle_supported(c0)) return AlStatusCode::DcInvalidSync0CycleTime;
        const SyncMode m = requested == SyncMode::DcSync1 ? SyncMode::DcSync1 : SyncMode::DcSync0;
        std::uint32_t app = c0;
        if (m == SyncMode::DcSync1) {
            app = (c1 / c0 + 1) * c0;  // SYNC1 follows every (c1 / c0 + 1)-th SYNC0
            if (!cycle_supported(app)) return AlStatusCode::DcInvalidSync1CycleTime;
        }
        if (cycle_written && written_cycle != app) return AlStatusCode::DcInvalidSyncCycleTime;
        mode_ = m;
        app_cycle_ns_ = app;
        checked_cycle0_ns_ = c0;
        return AlStatusCode::NoError;
    }
    if (wants_dc) return AlStatusCode::InvalidDcSyncConfig;  // DC expected, SYNC0 not activated
    if (requested != SyncMode::FreeRun && requested != SyncMode::SmSynchronous)
        return AlStatusCode::SyncNotSupported;
    if (cycle_written && (written_cycle < min_cycle_ns() || written_cycle > kMaxCycleNs))
        return AlStatusCode::DcInvalidSyncCycleTime;
    mode_ = requested;
    app_cycle_ns_ = 0;
    checked_cycle0_ns_ = 0;
    return AlStatusCode::NoError;
}

AlStatusCode SyncParameters::check_op() {
    if (dc_mode() || mode_written_ || !slave_) return AlStatusCode::NoError;
    const std::uint8_t act = slave_->esc().peek(protocol::addr(protocol::Reg::DcActivation));
    if (!(act & (esc::dc_act::Sync0 | esc::dc_act::Sync1))) return AlStatusCode::NoError;
    const AlStatusCode code = check_safeop();
    if (code != AlStatusCode::NoError) return code;
    publish();
    sync_events_ = 0;
    error_counter_ = 0;
    return AlStatusCode::NoError;
}

void SyncParameters::publish() {
    const auto m = static_cast<std::uint16_t>(mode_);
    put<std::uint16_t>(kOutPar, sub::SyncMode, m);
    std::uint16_t in_mode = m;
    if (mode_ == SyncMode::SmSynchronous) in_mode = static_cast<std::uint16_t>(SyncMode::Sm2Event);
    if (has_inputs_) put<std::uint16_t>(kInPar, sub::SyncMode, in_mode);
    if (dc_mode()) {
        const std::uint32_t shift =
            mode_ == SyncMode::DcSync1
                ? (slave_ ? slave_->esc().peek32(protocol::addr(protocol::Reg::DcSync1CycleTime)) %
                                checked_cycle0_ns_
                          : 0)
                : 0;
        for (std::uint16_t idx : {kOutPar, kInPar}) {
            put<std::uint32_t>(idx, sub::CycleTime, app_cycle_ns_);
            put<std::uint32_t>(idx, sub::Sync0CycleTime, checked_cycle0_ns_);
            put<std::uint32_t>(idx, sub::ShiftTime, shift);
        }
        slave_cycle_value_ = app_cycle_ns_;
        // The interpolation period follows SYNC: 0x60C2:01 x 10^0x60C2:02 s = the cycle time, in CiA 402's
        // format (0x60C2:01 UNSIGNED8); a device with its own format (the HIWIN D2's one UNSIGNED16 in
        // 62.5 us) sets it itself.
        std::uint8_t value = 0;
        std::int8_t index = 0;
        const Entry* period = od_.find(kInterpolationPeriod, 1);
        if (period && period->type() == protocol::DataType::Unsigned8 &&
            interpolation_period(app_cycle_ns_, value, index)) {
            put<std::uint8_t>(kInterpolationPeriod, 1, value);
            put<std::int8_t>(kInterpolationPeriod, 2, index);
        }
    }
    for (std::uint16_t idx : {kOutPar, kInPar}) {
        put<std::uint16_t>(idx, sub::SmEventMissed, 0);
        put<std::uint16_t>(idx, sub::CycleTimeTooSmall, 0);
        put<std::uint16_t>(idx, sub::ShiftTimeTooShort, 0);
        put<std::uint8_t>(idx, sub::SyncError, 0);
    }
}

void SyncParameters::on_state_change(AlState from, AlState to) {
    if (from == AlState::PreOp && to == AlState::SafeOp) {
        publish();
        sync_events_ = 0;
        error_counter_ = 0;
        faulted_ = false;
        last_event_ns_ = 0;
        if (slave_) {
            not_delivered_at_last_ = slave_->esc().dc().counters().pulses_not_delivered;
            sm_writes_at_last_ =
                sm_out_ >= 0 ? slave_->esc().sm_buffer_writes(static_cast<unsigned>(sm_out_)) : 0;
        }
    }
    if (to == AlState::PreOp || to == AlState::Init) mode_ = requested_;
    if (to == AlState::Op) {
        error_counter_ = 0;
        faulted_ = false;
    }
}

esc::OpReadiness SyncParameters::op_readiness(std::uint64_t now_ns, std::uint64_t since_ns) const {
    if (!dc_mode() || !slave_) return {};
    const auto st = slave_->esc().dc().sync_state();
    if (st.sync0 && st.cycle0_ns != checked_cycle0_ns_) return {false, AlStatusCode::PllError};
    if (st.sync0 && !st.sync0_pending && sync_events_ >= 2)
        return {};  // SYNC runs: the drive's cycle is locked on it
    if (now_ns - since_ns > kSyncWaitNs) return {false, AlStatusCode::NoSyncError};
    return {false, AlStatusCode::NoError};
}

void SyncParameters::raise(AlStatusCode code) {
    if (faulted_ || !slave_) return;
    faulted_ = true;
    slave_->raise_error(code, AlState::SafeOp);
}

bool SyncParameters::on_sync_event(unsigned signal, std::uint64_t now_ns, AlState state) {
    if (!dc_mode() || !slave_) return false;
    if (signal != (mode_ == SyncMode::DcSync1 ? 1u : 0u)) return false;
    if (state != AlState::SafeOp && state != AlState::Op) return false;
    ++sync_events_;
    ++counters_.cycles;
    last_event_ns_ = now_ns;
    const esc::Esc& esc = slave_->esc();
    // Cycles the firmware could not run (more pulses than one run could take): cycle time too small.
    const std::uint64_t nd = esc.dc().counters().pulses_not_delivered;
    const std::uint64_t missed_cycles = nd - not_delivered_at_last_;
    not_delivered_at_last_ = nd;
    // New outputs since the previous event? (SM2 event missed otherwise.)
    const std::uint64_t w = sm_out_ >= 0 ? esc.sm_buffer_writes(static_cast<unsigned>(sm_out_)) : 0;
    const bool missed = sm_out_ >= 0 && w == sm_writes_at_last_;
    sm_writes_at_last_ = w;
    if (state != AlState::Op) return true;
    auto bump = [&](std::uint8_t s, std::uint64_t by) {
        for (std::uint16_t idx : {kOutPar, kInPar}) {
            const std::uint64_t v = std::min<std::uint64_t>(get(idx, s) + by, 0xFFFF);
            put<std::uint16_t>(idx, s, static_cast<std::uint16_t>(v));
        }
    };
    if (missed_cycles) {
        counters_.cycles_missed += missed_cycles;
        bump(sub::CycleTimeTooSmall, missed_cycles);
    }
    if (missed) {
        ++counters_.sm_events_missed;
        bump(sub::SmEventMissed, 1);
        error_counter_ = static_cast<std::uint16_t>(error_counter_ + kErrorStep);
    } else if (error_counter_ > 0) {
        --error_counter_;
    }
    const auto limit = static_cast<std::uint16_t>(get(kErrorSettings, kSyncErrorLimit));
    if (limit > 0 && error_counter_ > limit && !faulted_) {
        ++counters_.sync_errors;
        put<std::uint8_t>(kOutPar, sub::SyncError, 1);
        put<std::uint8_t>(kInPar, sub::SyncError, 1);
        raise(AlStatusCode::FatalSyncError);
    }
    return true;
}

std::uint64_t SyncParameters::next_deadline_ns(AlState state) const {
    if (!dc_mode() || !slave_ || faulted_ || state != AlState::Op || last_event_ns_ == 0)
        return ~std::uint64_t{0};
    return last_event_ns_ + std::max<std::uint64_t>(kSyncLostMinNs, 3ull * app_cycle_ns_) + 1;
}

void SyncParameters::tick(std::uint64_t now_ns, AlState state) {
    if (!dc_mode() || !slave_ || faulted_) return;
    if (state != AlState::SafeOp && state != AlState::Op) return;
    const auto st = slave_->esc().dc().sync_state();
    if (st.sync0 && st.cycle0_ns != checked_cycle0_ns_) {
        raise(AlStatusCode::PllError);
        return;
    }
    if (state != AlState::Op) return;
    if (now_ns >= next_deadline_ns(state)) {
        put<std::uint8_t>(kOutPar, sub::SyncError, 1);
        put<std::uint8_t>(kInPar, sub::SyncError, 1);
        raise(AlStatusCode::FatalSyncError);  // SYNC0 stopped while the drive runs on it
    }
}

}  // namespace vecat::coe
