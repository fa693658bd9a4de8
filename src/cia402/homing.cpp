#include "cia402/homing.hpp"

#include <algorithm>
#include <cmath>

namespace vecat::cia402 {

namespace {

// An edge counts when it is crossed at no more than this multiple of speed_zero.
constexpr double kApproachTolerance = 1.5;
// The index pulse must follow the edge within this many index periods.
constexpr double kIndexSearchPeriods = 2.0;

bool positive_finite(double v) {
    return std::isfinite(v) && v > 0;
}

int sign(double v) {
    return v > 0 ? 1 : (v < 0 ? -1 : 0);
}

}  // namespace

bool Homing::describe(int method, Method& m) {
    using R = Reference;
    m = Method{};
    if (method == 35 || method == 37) {
        m.immediate = true;
        return true;
    }
    if (method == 33 || method == 34) {
        m.final_dir = method == 33 ? -1 : 1;
        m.index = true;
        return true;
    }
    int base = method;
    if (method >= 17 && method <= 30) {
        base = method - 16;
    } else if (method >= 1 && method <= 14) {
        m.index = true;
    } else {
        return false;
    }
    // {reference, final direction, rising, initial direction (window only)}
    struct Row {
        R reference;
        int final_dir;
        bool rising;
        int initial_dir;
    };
    static constexpr Row rows[14] = {
        {R::NegativeLimit, +1, false, 0},  // 1
        {R::PositiveLimit, -1, false, 0},  // 2
        {R::HomeAbove, -1, false, 0},      // 3
        {R::HomeAbove, +1, true, 0},       // 4
        {R::HomeBelow, +1, false, 0},      // 5
        {R::HomeBelow, -1, true, 0},       // 6
        {R::HomeWindow, -1, false, +1},    // 7: lower edge
        {R::HomeWindow, +1, true, +1},     // 8: lower edge
        {R::HomeWindow, -1, true, +1},     // 9: upper edge
        {R::HomeWindow, +1, false, +1},    // 10: upper edge
        {R::HomeWindow, +1, false, -1},    // 11: upper edge
        {R::HomeWindow, -1, true, -1},     // 12: upper edge
        {R::HomeWindow, +1, true, -1},     // 13: lower edge
        {R::HomeWindow, -1, false, -1},    // 14: lower edge
    };
    const Row& r = rows[base - 1];
    m.reference = r.reference;
    m.final_dir = r.final_dir;
    m.rising = r.rising;
    m.initial_dir = r.initial_dir;
    return true;
}

bool Homing::supported(int method) {
    Method m;
    return describe(method, m);
}

bool Homing::uses_index(int method) {
    Method m;
    return describe(method, m) && m.index;
}

bool Homing::start(int method, const HomingParameters& p, double actual_position) {
    Method m;
    if (!describe(method, m)) return false;
    if (!std::isfinite(actual_position) || !std::isfinite(p.home_offset)) return false;
    if (!m.immediate) {
        if (!positive_finite(p.speed_switch) || !positive_finite(p.speed_zero) ||
            !positive_finite(p.acceleration))
            return false;
        if (m.index && (!positive_finite(p.index_period) || !std::isfinite(p.index_phase))) return false;
    }
    if (!std::isfinite(p.standstill_velocity) || p.standstill_velocity < 0) return false;

    method_ = method;
    method_info_ = m;
    params_ = p;
    fault_ = HomingFault::None;
    primed_ = false;
    searching_ = true;
    signal_ = false;
    region_known_ = false;
    region_ = 0;
    search_dir_ = m.initial_dir;
    reversals_ = 0;
    command_dir_ = 0;
    command_velocity_ = 0;
    prev_position_ = actual_position;
    index_from_ = actual_position;
    home_position_ = 0;
    last_velocity_ = 0;
    event_pending_ = false;
    if (m.immediate) {
        phase_ = Phase::Stop;
        found(actual_position);
        return true;
    }
    status_ = HomingStatus::InProgress;
    phase_ = m.reference == Reference::None ? Phase::Index : Phase::Edge;
    return true;
}

HomingOutput Homing::update(double actual_position, double actual_velocity, const HomingSignals& s) {
    last_velocity_ = actual_velocity;
    if (status_ == HomingStatus::InProgress) {
        step(actual_position, actual_velocity, s);
    } else {
        command_velocity_ = 0;
    }
    prev_position_ = actual_position;

    HomingOutput out;
    out.velocity = command_velocity_;
    out.acceleration = params_.acceleration;
    out.status = status_;
    out.target_reached = target_reached();
    out.home_found = event_pending_;
    out.home_position = home_position_;
    event_pending_ = false;
    return out;
}

bool Homing::reference_active(const HomingSignals& s) const {
    switch (method_info_.reference) {
        case Reference::NegativeLimit:
            return s.negative_limit;
        case Reference::PositiveLimit:
            return s.positive_limit;
        case Reference::HomeAbove:
        case Reference::HomeBelow:
        case Reference::HomeWindow:
            return s.home_switch;
        case Reference::None:
            break;
    }
    return false;
}

// The region the axis is in after the reference signal changed to `active` while moving in direction
// `moving` (one-sided signals know their inactive side without it).
int Homing::region_after_change(bool active, int moving) const {
    if (active) return 0;
    switch (method_info_.reference) {
        case Reference::NegativeLimit:
        case Reference::HomeBelow:
            return 1;
        case Reference::PositiveLimit:
        case Reference::HomeAbove:
            return -1;
        case Reference::HomeWindow:
        case Reference::None:
            break;
    }
    return moving >= 0 ? 1 : -1;
}

void Homing::step(double pos, double vel, const HomingSignals& s) {
    const Method& m = method_info_;
    int moving = sign(pos - prev_position_);
    if (moving == 0) moving = sign(vel);
    if (moving == 0) moving = command_dir_;

    if (phase_ == Phase::Edge) {
        const bool active = reference_active(s);
        if (!primed_) {
            signal_ = active;
            if (active || m.reference != Reference::HomeWindow) {
                region_ = region_after_change(active, 0);
                region_known_ = true;
            }
        } else if (active != signal_) {
            signal_ = active;
            const bool was_known = region_known_;
            const int was = region_;
            region_ = region_after_change(active, moving);
            region_known_ = true;
            searching_ = false;
            if (was_known && was == pre_region() && region_ == post_region() &&
                std::abs(vel) <= kApproachTolerance * params_.speed_zero) {
                if (!m.index) {
                    found(pos);
                    return;
                }
                phase_ = Phase::Index;
                index_from_ = pos;
            }
        }
    }
    primed_ = true;

    if (phase_ == Phase::Index) {
        if (search_index(pos)) return;
        if ((pos - index_from_) * m.final_dir > kIndexSearchPeriods * params_.index_period) {
            fail(HomingFault::IndexNotFound);
            return;
        }
    }

    // The command of this cycle.
    int dir = 0;
    double speed = params_.speed_zero;
    if (phase_ == Phase::Index) {
        dir = m.final_dir;
    } else if (!region_known_) {
        dir = search_dir_;
        speed = params_.speed_switch;
    } else {
        const int pre = pre_region();
        dir = region_ == pre ? m.final_dir : (pre > region_ ? 1 : -1);
        if (searching_) speed = params_.speed_switch;
    }

    // Limit switches in the direction of motion.
    const bool limit_ahead = (dir < 0 && s.negative_limit) || (dir > 0 && s.positive_limit);
    if (limit_ahead) {
        const bool is_reference =
            phase_ == Phase::Edge && ((dir < 0 && m.reference == Reference::NegativeLimit) ||
                                      (dir > 0 && m.reference == Reference::PositiveLimit));
        if (!is_reference) {
            if (phase_ == Phase::Edge && !region_known_) {
                if (reversals_ > 0) {
                    fail(HomingFault::HomeSwitchNotFound);
                    return;
                }
                ++reversals_;
                search_dir_ = -search_dir_;
                dir = search_dir_;
            } else {
                fail(HomingFault::LimitSwitch);
                return;
            }
        }
    }
    command_dir_ = dir;
    command_velocity_ = dir * speed;
}

// Looks for an index pulse between the previous and the current actual position, beyond index_from_.
bool Homing::search_index(double pos) {
    const double period = params_.index_period;
    const double phase = params_.index_phase;
    if (method_info_.final_dir > 0) {
        const double lo = std::max(prev_position_, index_from_);
        if (pos <= lo) return false;
        const double x = (std::floor((lo - phase) / period) + 1) * period + phase;
        if (x > pos) return false;
        found(x);
        return true;
    }
    const double hi = std::min(prev_position_, index_from_);
    if (pos >= hi) return false;
    const double x = (std::ceil((hi - phase) / period) - 1) * period + phase;
    if (x < pos) return false;
    found(x);
    return true;
}

void Homing::found(double home) {
    home_position_ = home;
    status_ = HomingStatus::Attained;
    phase_ = Phase::Stop;
    command_dir_ = 0;
    command_velocity_ = 0;
    event_pending_ = true;
}

void Homing::fail(HomingFault f) {
    fault_ = f;
    status_ = HomingStatus::Error;
    phase_ = Phase::Stop;
    command_dir_ = 0;
    command_velocity_ = 0;
}

void Homing::halt() {
    if (status_ != HomingStatus::InProgress) return;
    status_ = HomingStatus::Interrupted;
    phase_ = Phase::Stop;
    command_dir_ = 0;
    command_velocity_ = 0;
}

void Homing::abort() {
    if (status_ != HomingStatus::InProgress) return;
    status_ = HomingStatus::Interrupted;
    phase_ = Phase::Idle;
    command_dir_ = 0;
    command_velocity_ = 0;
}

double Homing::standstill() const {
    return params_.standstill_velocity > 0 ? params_.standstill_velocity : 0.01 * params_.speed_zero;
}

bool Homing::target_reached() const {
    switch (status_) {
        case HomingStatus::InProgress:
            return false;
        case HomingStatus::NotStarted:
            return true;
        case HomingStatus::Interrupted:
        case HomingStatus::Attained:
        case HomingStatus::Error:
            break;
    }
    return std::abs(last_velocity_) <= standstill();
}

std::uint16_t Homing::statusword_bits() const {
    namespace b = homing_status_bits;
    std::uint16_t bits = target_reached() ? b::TargetReached : 0;
    if (status_ == HomingStatus::Attained) bits |= b::HomingAttained;
    if (status_ == HomingStatus::Error) bits |= b::HomingError;
    return bits;
}

}  // namespace vecat::cia402
