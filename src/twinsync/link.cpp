#include "twinsync/link.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

namespace vecat::twinsync {

std::optional<std::uint32_t> baud_rate(std::uint16_t sel) noexcept {
    constexpr std::array<std::uint32_t, 7> kBaud = {4'000'000, 2'000'000, 1'000'000, 800'000,
                                                    500'000,   400'000,   250'000};
    if (sel >= kBaud.size()) return std::nullopt;
    return kBaud[sel];
}

std::optional<std::uint32_t> switching_frequency_hz(std::uint8_t code) noexcept {
    constexpr std::array<std::uint32_t, 6> kHz = {2000, 4000, 6000, 8000, 12000, 16000};
    if (code >= kHz.size()) return std::nullopt;
    return kHz[code];
}

std::optional<std::uint64_t> sampling_time_ns(std::uint8_t code) noexcept {
    const auto f = switching_frequency_hz(code);
    if (!f) return std::nullopt;
    // Chapter 2: "TWIN sampling time (dependent on the switching frequency, 250 us or 125 us)", "at 4 kHz,
    // 250 us or at 8 kHz, 125 us". The specification gives 125 us for 8 kHz only.
    return *f == 8000 ? kSamplingTime8kHzNs : kSamplingTimeNs;
}

std::uint64_t frame_time_ns(std::size_t bytes, std::uint32_t baud) noexcept {
    if (baud == 0) return UINT64_MAX;
    return (static_cast<std::uint64_t>(bytes) * 10u * 1'000'000'000ull + baud - 1) / baud;
}

std::string check_link(const LinkConfig& c) {
    const auto baud = baud_rate(c.baud_selection);
    if (!baud) return fmt::format("P2709[0] baud rate selection {} is not 0..6", c.baud_selection);
    const auto pdo = pdo_bytes(c.layout, c.frame_size_selection);
    const auto frame = frame_bytes(c.layout, c.frame_size_selection);
    if (!pdo || !frame)
        return fmt::format("P2709[1] frame size selection {} is not 0..13", c.frame_size_selection);
    const auto period = sampling_time_ns(c.switching_frequency);
    if (!period) return fmt::format("P0302 switching frequency {} is not 0..5", c.switching_frequency);
    const std::uint64_t t = frame_time_ns(*frame, *baud);
    if (t > *period)
        return fmt::format(
            "a {}-byte frame takes {:.1f} us at {} kBaud, longer than the TWIN sampling time of "
            "{:.1f} us: raise the baud rate (P2709[0]) or reduce the frame size (P2709[1])",
            *frame, static_cast<double>(t) / 1000.0, *baud / 1000, static_cast<double>(*period) / 1000.0);
    if (c.send_pdo_bytes > *pdo)
        return fmt::format("the send mapping P2615 needs {} bytes, the frame size selection {} carries {}",
                           c.send_pdo_bytes, c.frame_size_selection, *pdo);
    if (c.receive_pdo_bytes > *pdo)
        return fmt::format("the receive mapping P2616 needs {} bytes, the frame size selection {} carries {}",
                           c.receive_pdo_bytes, c.frame_size_selection, *pdo);
    return {};
}

bool Channel::chance(std::uint32_t per_million) noexcept {
    if (per_million == 0) return false;
    rng_ ^= rng_ << 13;
    rng_ ^= rng_ >> 7;
    rng_ ^= rng_ << 17;
    return rng_ % 1'000'000u < per_million;
}

void Channel::send(int end, ConstBytes frame, std::uint64_t t_ns) noexcept {
    const int e = end & 1;
    if (cable_broken() || frame.size() > kMaxFrameBytes) return;
    const std::uint32_t drop =
        std::max({faults_.drop_per_million, injected_[0].drop_per_million, injected_[1].drop_per_million});
    const std::uint32_t corrupt = std::max(
        {faults_.corrupt_per_million, injected_[0].corrupt_per_million, injected_[1].corrupt_per_million});
    if (faults_.drop_next > 0 || chance(drop)) {
        if (faults_.drop_next > 0) --faults_.drop_next;
        ++dropped_;
        return;
    }
    Slot& s = ring_[e][head_[e]];
    head_[e] = (head_[e] + 1) % ring_[e].size();
    std::copy(frame.begin(), frame.end(), s.bytes.begin());
    s.size = frame.size();
    s.t_ns = t_ns;
    s.fresh = true;
    if (faults_.corrupt_next > 0 || chance(corrupt)) {
        if (faults_.corrupt_next > 0) --faults_.corrupt_next;
        // A bit error on the line: the CRC no longer matches.
        s.bytes[s.size - 1] ^= 0x10;
        ++corrupted_;
    }
}

ConstBytes Channel::receive(int end, std::uint64_t t_ns) noexcept {
    const int from = (end & 1) ^ 1;
    Slot* best = nullptr;
    for (auto& s : ring_[from])
        if (s.fresh && s.t_ns < t_ns && (!best || s.t_ns > best->t_ns)) best = &s;
    if (!best || cable_broken()) return {};
    // Older frames still waiting are superseded: the receiver only keeps the latest.
    for (auto& s : ring_[from])
        if (s.t_ns <= best->t_ns) s.fresh = false;
    return ConstBytes(best->bytes.data(), best->size);
}

void Channel::sync_pulse(int end, std::uint64_t t_ns) noexcept {
    last_pulse_[end & 1] = t_ns;
    pulsed_[end & 1] = true;
}

bool Channel::sync_seen(int end, std::uint64_t since_ns) const noexcept {
    const int from = (end & 1) ^ 1;
    if (sync_line_dead() || !pulsed_[from]) return false;
    return last_pulse_[from] >= since_ns;
}

void SyncController::step(double period_ns, double drift_ppm, std::int16_t sync_ticks, bool pulse,
                          Source source) {
    if (source == Source::FieldbusSynchronised) {
        // Both control cycles follow the fieldbus's clock (EtherCAT DC): no phase to SYNC_OUT builds up.
        phase_ns_ = 0;
        locked_ = true;
        return;
    }
    phase_ns_ += period_ns * drift_ppm * 1e-6;
    if (pulse && source == Source::Twin) {
        const double max = std::max<double>(sync_ticks, 0) * kNsPerTick;
        phase_ns_ -= std::clamp(0.5 * phase_ns_, -max, max);
    }
    const double a = std::abs(phase_ns_);
    if (!pulse)
        locked_ = false;
    else if (a < kLockNs)
        locked_ = true;
    else if (a > kLoseNs)
        locked_ = false;
}

}  // namespace vecat::twinsync
