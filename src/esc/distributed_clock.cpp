#include "esc/distributed_clock.hpp"

#include "esc/esc.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace vecat::esc {

using protocol::addr;
using protocol::Reg;
namespace {

bool overlaps(std::uint32_t lo, std::uint32_t hi, std::uint32_t a, std::uint32_t len) {
    return lo < a + len && hi >= a;  // hi inclusive
}

constexpr std::uint64_t kNearFutureLong = 2'147'483'648ull;  // ~2.1 s (2^31 ns)
constexpr std::uint64_t kNearFutureShort = 1'048'576ull;     // ~1 ms (2^20 ns)
constexpr std::uint64_t kMaxLoopStepNs = 100'000'000;        // longer gaps between writes count as this
constexpr std::uint64_t kMaxOverduePulses = 1024;            // beyond this, overdue pulses are skipped

// A time difference in ns, computed in double, back to an integer. At the ends of the 64-bit range (a
// master may write any start time and offset, e.g. a SYNC0 start 2^63 ns away) the product of the clock's
// rate no longer fits: it saturates instead of being converted with undefined behaviour (found by
// fuzz_frame). Such a time is centuries away either way.
std::int64_t to_ns_saturated(double v) {
    constexpr double kLimit = 9223372036854775808.0;  // 2^63
    if (v >= kLimit) return INT64_MAX;
    if (!(v > -kLimit)) return INT64_MIN;  // also NaN
    return static_cast<std::int64_t>(v);
}

// Time d after t; kNever past the end of the 64-bit system time (a master may set the offset so that it
// ends soon): no pulse comes after it, instead of a wrapped time that lies before every later time.
constexpr std::uint64_t after(std::uint64_t t, std::uint64_t d) {
    return t > DistributedClock::kNever - d ? DistributedClock::kNever : t + d;
}

std::uint16_t latch_ctrl(unsigned unit) {
    return static_cast<std::uint16_t>(addr(Reg::DcLatch0Control) + unit);
}
std::uint16_t latch_status(unsigned unit) {
    return static_cast<std::uint16_t>(addr(Reg::DcLatch0Status) + unit);
}
std::uint16_t latch_time(unsigned unit, bool positive) {
    return static_cast<std::uint16_t>(
        (positive ? addr(Reg::DcLatch0PositiveEdge) : addr(Reg::DcLatch0NegativeEdge)) + 0x10 * unit);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The time control loop
//
// A system time write compares received time + system time delay (0x0928) with the local copy of the system
// time; the difference feeds a loop that speeds the local clock up or slows it down. Like the ESC, the loop
// only ever changes the clock rate, never steps the time: the ESC adds 1 ns more or less every N periods of
// its 10 ns clock, N coming from the speed counter (start value 0x0930, adapted within +-(0x0930 - 0x7F) and
// shown in 0x0932). Modelled here as a PI controller on the rate:
//  - proportional part: diff / Tp, limited to the correction of the start value, 1 ns per (0x0930 x 10 ns);
//    Tp = 0x0930 x 12.5 us, so the proportional region is +-1.25 us whatever the start value (0x1000: Tp
//    51 ms, limit 24.4 ppm);
//  - integral part (the adapted speed counter): integrates the difference (clipped to +-20 us) with
//    Ti = Tp x 2^(0x0935 - 10), at least Tp (0x0C: Ti = 4 Tp, critically damped); limited to the fastest
//    speed counter, 1 ns per 0x7F x 10 ns (787 ppm). 100 ppm are caught within ~0.6 s (peak ~8 us) with a
//    write every 1 ms, 500 ppm within ~2.5 s;
//  - 0x092C shows the mean of the differences over 2^(0x0934) writes (sign in bit 31: 1 = local copy
//    smaller than the received time).
// This is a model of the loop's behaviour, not of its gates: it converges to the reference clock's rate, it
// compensates drifts of hundreds of ppm, it reacts to the filter registers, and it never jumps.

DistributedClock::DistributedClock(std::uint8_t* regs, double drift_ppm, std::uint64_t initial_local_ns)
    : regs_(regs), drift_ppm_(drift_ppm), anchor_local_(initial_local_ns), rate_(1.0 + drift_ppm * 1e-6) {
    reset_registers();
}

void DistributedClock::reset_registers() {
    st_le16(&regs_[addr(Reg::DcSpeedCounterStart)], 0x1000);
    st_le16(&regs_[addr(Reg::DcSpeedCounterDiff)], 0);
    regs_[addr(Reg::DcSystemTimeDiffFilterDepth)] = 0x04;
    regs_[addr(Reg::DcSpeedCounterFilterDepth)] = 0x0C;
    st_le32(&regs_[addr(Reg::DcSystemTimeDifference)], 0);
}

std::uint64_t DistributedClock::local_time(std::uint64_t host_ns) const {
    const double dt = static_cast<double>(static_cast<std::int64_t>(host_ns - anchor_host_));
    const double v = std::floor(anchor_frac_ + dt * rate_);
    return anchor_local_ + static_cast<std::uint64_t>(to_ns_saturated(v));
}

std::uint64_t DistributedClock::system_time(std::uint64_t host_ns) const {
    return local_time(host_ns) + ld_le64(&regs_[addr(Reg::DcSystemTimeOffset)]);
}

std::uint64_t DistributedClock::host_time_of(std::uint64_t sys) const {
    const std::uint64_t local = sys - ld_le64(&regs_[addr(Reg::DcSystemTimeOffset)]);
    const double dl = static_cast<double>(static_cast<std::int64_t>(local - anchor_local_)) - anchor_frac_;
    const double dh = std::ceil(dl / rate_) + 1.0;  // the first host ns at which the time has been reached
    return anchor_host_ + static_cast<std::uint64_t>(to_ns_saturated(dh));
}

void DistributedClock::reanchor(std::uint64_t host_ns) {
    const double dt = static_cast<double>(static_cast<std::int64_t>(host_ns - anchor_host_));
    const double v = anchor_frac_ + dt * rate_;
    const double whole = std::floor(v);
    anchor_local_ += static_cast<std::uint64_t>(to_ns_saturated(whole));
    anchor_frac_ = v - whole;
    anchor_host_ = host_ns;
}

void DistributedClock::set_drift_ppm(double ppm, std::uint64_t host_ns) {
    reanchor(host_ns);
    drift_ppm_ = ppm;
    rate_ = 1.0 + drift_ppm_ * 1e-6 + freq_ + phase_;
}

void DistributedClock::reset_loop() {
    freq_ = 0.0;
    phase_ = 0.0;
    filtered_acc_ = 0.0;
    filtered_diff_ = 0;
    have_write_ = false;
    st_le32(&regs_[addr(Reg::DcSystemTimeDifference)], 0);
    st_le16(&regs_[addr(Reg::DcSpeedCounterDiff)], 0);
}

void DistributedClock::system_time_written(const std::array<std::uint8_t, 8>& value, std::uint8_t byte_mask,
                                           std::uint64_t host_ns) {
    ++counters_.system_time_writes;
    const std::uint64_t mine = system_time(host_ns);
    std::array<std::uint8_t, 8> received{};
    st_le64(received.data(), mine);
    for (unsigned i = 0; i < 8; ++i)
        if (byte_mask & (1u << i)) received[i] = value[i];
    const std::uint64_t delay = ld_le32(&regs_[addr(Reg::DcSystemTimeDelay)]);
    const std::uint64_t rx = ld_le64(received.data()) + delay;
    // A 32-bit write is compared in 32 bits (the ESC's lower half of the system time).
    const std::int64_t diff =
        (byte_mask & 0xF0) != 0
            ? static_cast<std::int64_t>(rx - mine)
            : static_cast<std::int32_t>(static_cast<std::uint32_t>(rx) - static_cast<std::uint32_t>(mine));

    const unsigned depth = regs_[addr(Reg::DcSystemTimeDiffFilterDepth)] & 0x0F;
    filtered_acc_ += (static_cast<double>(diff) - filtered_acc_) / static_cast<double>(1u << depth);
    filtered_diff_ = static_cast<std::int64_t>(std::llround(filtered_acc_));
    const std::uint64_t mag =
        static_cast<std::uint64_t>(filtered_diff_ < 0 ? -filtered_diff_ : filtered_diff_);
    std::uint32_t r = static_cast<std::uint32_t>(std::min<std::uint64_t>(mag, 0x7FFFFFFF));
    if (filtered_diff_ > 0) r |= 0x80000000u;  // local copy smaller than the received time
    st_le32(&regs_[addr(Reg::DcSystemTimeDifference)], r);

    const double start =
        std::max<double>(kMinSpeedCounter, ld_le16(&regs_[addr(Reg::DcSpeedCounterStart)]) & 0x7FFF);
    const double p_max = 1.0 / (10.0 * start);
    const double f_max = 1.0 / (10.0 * kMinSpeedCounter);
    const double tp = start * (kLinearRangeNs * 10.0);  // ns; p_max * tp = kLinearRangeNs
    const int sdepth = regs_[addr(Reg::DcSpeedCounterFilterDepth)] & 0x0F;
    const double ti = tp * std::ldexp(1.0, std::max(0, sdepth - 10));
    reanchor(host_ns);
    if (have_write_) {
        const std::uint64_t dt =
            host_ns > last_write_host_ ? std::min(host_ns - last_write_host_, kMaxLoopStepNs) : 0;
        const double e = std::clamp(static_cast<double>(diff), -kIntegratorRangeNs, kIntegratorRangeNs);
        freq_ = std::clamp(freq_ + e * static_cast<double>(dt) / (tp * ti), -f_max, f_max);
    }
    phase_ = std::clamp(static_cast<double>(diff) / tp, -p_max, p_max);
    rate_ = 1.0 + drift_ppm_ * 1e-6 + freq_ + phase_;
    last_write_host_ = host_ns;
    have_write_ = true;

    // 0x0932: the adapted speed counter as the difference to the start value (sign: direction).
    const double f = std::abs(freq_);
    const double n = f > 0 ? 1.0 / (10.0 * f) : 1e18;
    const double lim = start - kMinSpeedCounter;
    const double d = std::clamp(start - n, 0.0, lim) * (freq_ < 0 ? -1.0 : 1.0);
    st_le16(&regs_[addr(Reg::DcSpeedCounterDiff)],
            static_cast<std::uint16_t>(static_cast<std::int16_t>(std::lround(d))));
}

// ---------------------------------------------------------------------------------------------
// Register access side effects

void DistributedClock::before_read(std::uint16_t lo, std::uint16_t hi, std::uint64_t host_ns) {
    if (overlaps(lo, hi, addr(Reg::DcSystemTime), 8))
        st_le64(&regs_[addr(Reg::DcSystemTime)], system_time(host_ns));
    if (overlaps(lo, hi, addr(Reg::DcActivationStatus), 1)) {
        std::uint8_t s = reg(Reg::DcActivationStatus) & dc_act::StatusStartTimeImplausible;
        const std::uint8_t act = reg(Reg::DcActivation);
        const bool first_due = next_sync0_ != kNever && next_sync0_ <= system_time(host_ns);
        if (cyclic_active_ && sync0_pending_ && !first_due && (act & dc_act::Sync0))
            s |= dc_act::StatusSync0Pending;
        if (cyclic_active_ && sync1_pending_ && (act & dc_act::Sync1)) s |= dc_act::StatusSync1Pending;
        reg(Reg::DcActivationStatus) = s;
    }
    if (overlaps(lo, hi, addr(Reg::DcSync0Status), 2)) {
        const std::uint64_t len = static_cast<std::uint64_t>(ld_le16(&regs_[addr(Reg::DcPulseLength)])) * 10;
        const std::uint64_t sys = system_time(host_ns);
        for (unsigned s = 0; s < 2; ++s) {
            bool on;
            if (len == 0)
                on = status_latched_[s];  // acknowledge mode: until read
            else
                on = counters_.sync_pulses[s] > 0 && sys >= last_pulse_[s] && sys - last_pulse_[s] < len;
            regs_[addr(Reg::DcSync0Status) + s] = on ? 0x01 : 0x00;
        }
    }
    if (overlaps(lo, hi, addr(Reg::DcStartTimeCyclic), 8))
        st_le64(&regs_[addr(Reg::DcStartTimeCyclic)],
                cyclic_active_ ? projected_next_sync0(system_time(host_ns)) : start_written_);
    if (overlaps(lo, hi, addr(Reg::DcNextSync1Pulse), 8))
        st_le64(&regs_[addr(Reg::DcNextSync1Pulse)],
                cyclic_active_ && next_sync1_ != kNever ? next_sync1_ : 0);
}

void DistributedClock::after_read(std::uint16_t lo, std::uint16_t hi) {
    const bool ack_mode = ld_le16(&regs_[addr(Reg::DcPulseLength)]) == 0;
    for (unsigned s = 0; s < 2; ++s)
        if (ack_mode && overlaps(lo, hi, addr(Reg::DcSync0Status) + s, 1)) status_latched_[s] = false;
    // Single event latches: reading the time of an edge re-arms it.
    for (unsigned u = 0; u < 2; ++u) {
        const std::uint8_t ctrl = regs_[latch_ctrl(u)];
        std::uint8_t& st = regs_[latch_status(u)];
        if ((ctrl & 0x01) && overlaps(lo, hi, latch_time(u, true), 8)) st &= static_cast<std::uint8_t>(~0x01);
        if ((ctrl & 0x02) && overlaps(lo, hi, latch_time(u, false), 8))
            st &= static_cast<std::uint8_t>(~0x02);
    }
}

void DistributedClock::after_write(std::uint16_t lo, std::uint16_t hi, const FrameTiming& t,
                                   std::uint8_t open_ports, std::uint8_t activation_before) {
    const std::uint64_t port0_ns = t.port0_ns;
    if (overlaps(lo, hi, addr(Reg::DcRecvTimePort0), 4)) {
        // Write to receive time port 0: every port latches the local time this frame passed it
        // (ETG.1000.4 9.1); the processing unit latches the whole 64 bits in 0x0918. A closed port sees no
        // frame and keeps its time.
        const std::uint64_t t0 = local_time(port0_ns);
        st_le32(&regs_[addr(Reg::DcRecvTimePort0)], static_cast<std::uint32_t>(t0));
        const std::uint64_t back[4] = {0, t.port1_ns, t.port2_ns, t.port3_ns};
        constexpr Reg regs[4] = {Reg::DcRecvTimePort0, Reg::DcRecvTimePort1, Reg::DcRecvTimePort2,
                                 Reg::DcRecvTimePort3};
        for (unsigned p = 1; p < 4; ++p)
            if ((open_ports >> p) & 1u && (t.returned_ports >> p) & 1u)
                st_le32(&regs_[addr(regs[p])], static_cast<std::uint32_t>(local_time(back[p])));
        st_le64(&regs_[addr(Reg::DcRecvTimeEcatPu)], t0);
    }
    if (overlaps(lo, hi, addr(Reg::DcSystemTimeOffset), 8)) {
        filtered_acc_ = 0.0;  // the differences measured before the new offset mean nothing now
        filtered_diff_ = 0;
    }
    if (overlaps(lo, hi, addr(Reg::DcSpeedCounterStart), 2)) {
        // Writing the speed counter start resets the control loop (0x092C, 0x0932 restart from zero).
        reanchor(port0_ns);
        reset_loop();
        rate_ = 1.0 + drift_ppm_ * 1e-6;
    }
    const bool pdi_owns_sync = (reg(Reg::DcCyclicUnitControl) & dc_act::CucSyncPdi) != 0;
    if (overlaps(lo, hi, addr(Reg::DcActivation), 1) && pdi_owns_sync)
        reg(Reg::DcActivation) = activation_before;  // the SYNC unit belongs to the PDI: ECAT write ignored
    if (overlaps(lo, hi, addr(Reg::DcStartTimeCyclic), 8)) {
        start_written_ = ld_le64(&regs_[addr(Reg::DcStartTimeCyclic)]);
        if ((reg(Reg::DcActivation) & dc_act::AutoActivation) && !pdi_owns_sync &&
            hi >= addr(Reg::DcStartTimeCyclic) + 3)
            reg(Reg::DcActivation) |= dc_act::CyclicOperation;
    }
    if (overlaps(lo, hi, addr(Reg::DcActivation), 1) || overlaps(lo, hi, addr(Reg::DcStartTimeCyclic), 8)) {
        const bool want = (reg(Reg::DcActivation) & dc_act::CyclicOperation) != 0;
        if (want && !cyclic_active_)
            activate(port0_ns);
        else if (!want && cyclic_active_)
            deactivate();
    }
}

void DistributedClock::latch_port1_receive_time(std::uint64_t host_ns) {
    st_le32(&regs_[addr(Reg::DcRecvTimePort1)], static_cast<std::uint32_t>(local_time(host_ns)));
}

// ---------------------------------------------------------------------------------------------
// SYNC out unit

void DistributedClock::activate(std::uint64_t host_ns) {
    const std::uint64_t sys = system_time(host_ns);
    const std::uint8_t act = reg(Reg::DcActivation);
    std::uint64_t first;
    if (act & dc_act::StartTime64Bit) {
        first = start_written_ > sys ? start_written_ : kNever;  // in the past: never (64-bit overflow)
    } else {
        // The start time is compared in 32 bits: a start time in the past is reached after the lower half
        // of the system time overflowed (up to 4.3 s later), as on the ESC.
        first = after(sys, static_cast<std::uint32_t>(static_cast<std::uint32_t>(start_written_) -
                                                      static_cast<std::uint32_t>(sys)));
    }
    std::uint8_t status = 0;
    if (act & dc_act::PlausibilityCheck) {
        const std::uint64_t near = (act & dc_act::NearFutureShort) ? kNearFutureShort : kNearFutureLong;
        const std::int64_t ahead = static_cast<std::int64_t>(start_written_ - sys);
        if (ahead < 0 || static_cast<std::uint64_t>(ahead) > near) {
            status |= dc_act::StatusStartTimeImplausible;
            first = sys;  // out of the near future: the SYNC signals start at once
        }
    }
    reg(Reg::DcActivationStatus) = status;
    cyclic_active_ = true;
    first_sync0_ = next_sync0_ = first;
    sync0_index_ = 0;
    sync1_index_ = 0;
    next_sync1_ = kNever;
    sync0_pending_ = true;
    sync1_pending_ = true;
    status_latched_[0] = status_latched_[1] = false;
}

std::uint64_t DistributedClock::projected_next_sync0(std::uint64_t sys) const {
    const std::uint32_t cycle0 = ld_le32(&regs_[addr(Reg::DcSync0CycleTime)]);
    if (next_sync0_ == kNever || next_sync0_ > sys || cycle0 == 0) return next_sync0_;
    const std::uint64_t periods = (sys - next_sync0_) / cycle0 + 1;
    const std::uint64_t span = periods * cycle0;
    return span / cycle0 == periods ? after(next_sync0_, span) : kNever;
}

void DistributedClock::deactivate() {
    cyclic_active_ = false;
    sync0_pending_ = sync1_pending_ = false;
    next_sync0_ = next_sync1_ = 0;
    reg(Reg::DcActivationStatus) = 0;
}

DistributedClock::SyncState DistributedClock::sync_state() const {
    SyncState s;
    const std::uint8_t act = reg(Reg::DcActivation);
    s.cyclic_active = cyclic_active_;
    s.sync0 = cyclic_active_ && (act & dc_act::Sync0);
    s.sync1 = cyclic_active_ && (act & dc_act::Sync1);
    s.sync0_pending = s.sync0 && sync0_pending_;
    s.cycle0_ns = ld_le32(&regs_[addr(Reg::DcSync0CycleTime)]);
    s.cycle1_ns = ld_le32(&regs_[addr(Reg::DcSync1CycleTime)]);
    s.next_sync0 = next_sync0_;
    s.last_sync0 = counters_.sync_pulses[0] ? last_pulse_[0] : 0;
    s.first_sync0 = first_sync0_;
    return s;
}

std::uint64_t DistributedClock::next_pulse_host_ns() const {
    if (!cyclic_active_) return kNever;
    const std::uint8_t act = reg(Reg::DcActivation);
    if (!(act & (dc_act::Sync0 | dc_act::Sync1))) return kNever;
    const std::uint64_t t = std::min(next_sync0_, next_sync1_);
    return t == kNever ? kNever : host_time_of(t);
}

std::uint64_t DistributedClock::backlog_deadline_ns(unsigned pulses) const {
    const std::uint64_t next = next_pulse_host_ns();
    if (next == kNever || pulses <= 1) return next;
    const std::uint8_t act = reg(Reg::DcActivation);
    const std::uint64_t cycle0 = ld_le32(&regs_[addr(Reg::DcSync0CycleTime)]);
    if (cycle0 == 0) return next;  // single shot: take it on time
    const std::uint64_t per = (act & dc_act::Sync1) && (act & dc_act::Sync0) ? cycle0 / 2 : cycle0;
    return next + (pulses - 1) * per;
}

unsigned DistributedClock::advance(std::uint64_t host_ns, SyncPulse* out, unsigned max) {
    if (!cyclic_active_) return 0;
    const std::uint8_t act = reg(Reg::DcActivation);
    const bool en0 = (act & dc_act::Sync0) != 0, en1 = (act & dc_act::Sync1) != 0;
    if (!en0 && !en1) return 0;
    const std::uint64_t sys = system_time(host_ns);
    const std::uint32_t cycle0 = ld_le32(&regs_[addr(Reg::DcSync0CycleTime)]);
    const std::uint32_t cycle1 = ld_le32(&regs_[addr(Reg::DcSync1CycleTime)]);
    unsigned n = 0;
    auto emit = [&](std::uint8_t sig, std::uint64_t t) {
        ++counters_.sync_pulses[sig];
        last_pulse_[sig] = t;
        status_latched_[sig] = true;
        if (n < max)
            out[n++] = SyncPulse{sig, host_time_of(t), t};
        else
            ++counters_.pulses_not_delivered;
    };
    // Far behind (the host did not poll for a long time): skip whole periods, counting them.
    if (cycle0 > 0 && next_sync0_ != kNever && sys > next_sync0_ &&
        (sys - next_sync0_) / cycle0 > kMaxOverduePulses) {
        const std::uint64_t skip = (sys - next_sync0_) / cycle0 - kMaxOverduePulses;
        next_sync0_ += skip * cycle0;
        sync0_index_ += skip;
        if (en0) {
            counters_.sync_pulses[0] += skip;
            counters_.pulses_not_delivered += skip;
        }
        if (next_sync1_ != kNever && next_sync1_ < next_sync0_) next_sync1_ = kNever;
    }
    while (true) {
        const bool s1_first = next_sync1_ != kNever && next_sync1_ < next_sync0_;
        const std::uint64_t t = s1_first ? next_sync1_ : next_sync0_;
        if (t == kNever || t > sys) break;
        if (s1_first) {
            next_sync1_ = kNever;
            ++sync1_index_;
            sync1_pending_ = false;
            if (en1) emit(1, t);
            continue;
        }
        const std::uint64_t k = sync0_index_++;
        sync0_pending_ = false;
        if (en0) emit(0, t);
        // SYNC1: cycle1 after every (cycle1 / cycle0 + 1)-th SYNC0 pulse, delayed by cycle1 % cycle0.
        if (en1) {
            const std::uint64_t q = cycle0 ? cycle1 / cycle0 : 0;
            const std::uint64_t r = cycle0 ? cycle1 % cycle0 : cycle1;
            if (cycle0 == 0 ? k == 0 : k % (q + 1) == 0) next_sync1_ = after(t, r);
        }
        next_sync0_ = cycle0 ? after(t, cycle0) : kNever;  // cycle time 0: a single pulse
    }
    return n;
}

// ---------------------------------------------------------------------------------------------
// Latch units

void DistributedClock::latch_input(unsigned unit, bool level, std::uint64_t host_ns) {
    if (unit > 1 || level == latch_level_[unit]) return;
    latch_level_[unit] = level;
    const std::uint8_t ctrl = regs_[latch_ctrl(unit)];
    std::uint8_t& st = regs_[latch_status(unit)];
    const std::uint8_t bit = level ? 0x01 : 0x02;  // positive / negative edge event
    const bool single = (ctrl & bit) != 0;
    if (!single || !(st & bit)) {
        st_le64(&regs_[latch_time(unit, level)], system_time(host_ns));
        st |= bit;
        ++counters_.latch_events[unit];
    }
    st = static_cast<std::uint8_t>(level ? (st | 0x04) : (st & ~0x04));  // bit 2: pin state
}

}  // namespace vecat::esc
