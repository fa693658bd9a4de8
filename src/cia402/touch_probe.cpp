#include "cia402/touch_probe.hpp"

#include <algorithm>
#include <cmath>

namespace vecat::cia402 {
namespace {

// 0x60B8 bits of one probe, and its 0x60B9 status bits.
constexpr std::uint16_t kEnable = 0x01, kContinuous = 0x02, kPositiveEdge = 0x10, kNegativeEdge = 0x20;
constexpr std::uint16_t kEnabled = 0x01, kPositiveStored = 0x02, kNegativeStored = 0x04;

}  // namespace

std::optional<double> TouchProbe::index_crossing(double from, double to, double period, double offset) {
    const double lo = std::min(from, to), hi = std::max(from, to);
    if (!(period > 0) || !(hi > lo)) return std::nullopt;
    const double crossing = std::ceil((lo - offset) / period) * period + offset;
    if (crossing <= hi && crossing > lo) return crossing;
    return std::nullopt;
}

TouchProbe::Latched TouchProbe::step(const Period& p, const FactorRatios& ratios, double home_shift) {
    Latched out;
    // HIWIN: probe 2 does not exist (its function bits are ignored, its status stays 0).
    const std::uint16_t fn = p.on_index_only ? static_cast<std::uint16_t>(p.function & 0x00FF) : p.function;
    if (!(fn & (kEnable | kEnable << 8))) {
        // Both disabled (as the loop below would leave them): no latch, status cleared.
        status_ = 0;
        previous_function_ = fn;
        previous_inputs_ = p.inputs;
        return out;
    }
    for (int n = 0; n < 2; ++n) {
        const unsigned shift = 8u * static_cast<unsigned>(n);
        const std::uint16_t f = static_cast<std::uint16_t>(fn >> shift);
        const std::uint16_t pf = static_cast<std::uint16_t>(previous_function_ >> shift);
        std::uint16_t st = static_cast<std::uint16_t>(status_ >> shift) & 0xFF;
        if (!(f & kEnable)) {
            st = 0;  // disabled: status cleared
        } else {
            st |= kEnabled;
            // Arming: enabling the probe or an edge enable bit rising clears the stored flags.
            if (!(pf & kEnable)) st = kEnabled;
            if ((f & kPositiveEdge) && !(pf & kPositiveEdge))
                st &= static_cast<std::uint16_t>(~kPositiveStored);
            if ((f & kNegativeEdge) && !(pf & kNegativeEdge))
                st &= static_cast<std::uint16_t>(~kNegativeStored);
            const bool continuous = f & kContinuous;
            // 0: touch probe input, 1: zero impulse (index); HIWIN's one trigger is the index.
            const unsigned source = p.on_index_only ? 1u : (f >> 2) & 0x03u;
            bool rise = false, fall = false;
            double at_inc = p.machine_inc;
            if (source == 0) {
                const bool now = p.inputs & (1u << n);
                const bool before = previous_inputs_ & (1u << n);
                rise = now && !before;
                fall = !now && before;
            } else if (source == 1) {
                // Index pulse once per motor revolution at the configured offset: the exact crossing.
                if (const auto crossing = index_crossing(p.previous_inc, p.machine_inc, ratios.per_revolution,
                                                         p.index_offset)) {
                    rise = fall = true;
                    at_inc = *crossing;
                }
            }
            const double user = static_cast<double>(ratios.increments_to_user(floor64(at_inc))) + home_shift;
            const std::int32_t latched = wrap32(floor64(user));
            if (rise && (f & kPositiveEdge) && (continuous || !(st & kPositiveStored))) {
                out.set[n][0] = true;
                out.value[n][0] = latched;
                st |= kPositiveStored;
            }
            if (fall && (f & kNegativeEdge) && (continuous || !(st & kNegativeStored))) {
                out.set[n][1] = true;
                out.value[n][1] = latched;
                st |= kNegativeStored;
            }
        }
        status_ = static_cast<std::uint16_t>((status_ & ~(0xFFu << shift)) | (st << shift));
    }
    previous_function_ = fn;
    previous_inputs_ = p.inputs;
    return out;
}

}  // namespace vecat::cia402
