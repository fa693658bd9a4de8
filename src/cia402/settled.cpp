#include "cia402/settled.hpp"

#include <algorithm>
#include <cstring>

namespace vecat::cia402 {

namespace {

template <class T>
const unsigned char* bytes(const T& t) {
    return reinterpret_cast<const unsigned char*>(&t);
}

// The DriveIo's inputs: everything before the feedback, which only the core writes.
std::size_t inputs_size(const DriveIo& io) {
    return static_cast<std::size_t>(bytes(io.feedback) - bytes(io));
}

}  // namespace

DriveCore::Settled::Settled(const DriveCore& core) {
    // The bytes compared: all of the core but the period count, the temperature and the hold timers.
    const auto offset = [&](const auto* member) {
        return static_cast<std::size_t>(bytes(*member) - bytes(core));
    };
    std::array<std::pair<std::size_t, std::size_t>, kTimers + 2> skip{};
    skip[0] = {offset(&core.steps_), sizeof(core.steps_)};
    skip[1] = {offset(&core.temperature_), sizeof(core.temperature_)};
    for (std::size_t i = 0; i < kTimers; ++i)
        skip[i + 2] = {offset(core.timers_[i]), sizeof(HoldTimer)};
    std::sort(skip.begin(), skip.end());
    std::size_t from = 0;
    for (std::size_t i = 0; i < skip.size(); ++i) {
        gaps_[i] = {from, skip[i].first};
        from = skip[i].first + skip[i].second;
    }
    gaps_.back() = {from, sizeof(DriveCore)};
}

void DriveCore::Settled::take(const DriveCore& core, const DriveIo& io) {
    std::memcpy(core_.data(), bytes(core), core_.size());
    std::memcpy(io_.data(), bytes(io), inputs_size(io));
    begin_timers(core);
}

void DriveCore::Settled::begin_timers(const DriveCore& core) {
    for (std::size_t i = 0; i < kTimers; ++i) {
        core.timers_[i]->begin_period();
        timer_before_[i] = core.timers_[i]->seconds();
    }
}

bool DriveCore::Settled::same_core(const DriveCore& core) const {
    const unsigned char* c = bytes(core);
    for (const auto& [from, to] : gaps_)
        if (std::memcmp(c + from, core_.data() + from, to - from) != 0) return false;
    return true;
}

bool DriveCore::Settled::same_io(const DriveIo& io) const {
    return std::memcmp(bytes(io), io_.data(), inputs_size(io)) == 0;
}

bool DriveCore::Settled::settled(const DriveCore& core, const DriveIo& io) const {
    const DriveFeedback& fb = io.feedback;
    if (fb.raised || fb.cleared) return false;
    for (const auto& edges : fb.probe_latched.set)
        if (edges[0] || edges[1]) return false;
    for (std::size_t i = 0; i < kTimers; ++i)
        if (!core.timers_[i]->settled(timer_before_[i])) return false;
    return same_core(core) && same_io(io);
}

std::uint64_t DriveCore::skipped_steps() const {
    return settled_->skipped;
}

void DriveCore::skip_settled_periods(bool on) {
    wake();
    settled_->on = settled_->values_current = false;
    settled_->enabled = on;
}

void DriveCore::catch_up_skipped() {
    Settled& s = *settled_;
    if (s.pending == 0) return;
    const double dt = static_cast<double>(period_ns_) * 1e-9;
    for (HoldTimer* t : timers_)
        if (t->running()) t->catch_up(s.pending, dt);
    s.pending = 0;
}

void DriveCore::wake() {
    catch_up_skipped();
    settled_->touched = true;
}

}  // namespace vecat::cia402
