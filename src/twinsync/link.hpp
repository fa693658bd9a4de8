// The physical TWINsync link: the EIA485 UART (P2709 baud rate and frame size against the TWIN sampling
// time), the cable between two option cards with its SYNC_OUT line and injectable faults, and the
// synchronisation of the slave drive's control cycle to the master's SYNC_OUT pulse.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "common/bytes.hpp"
#include "twinsync/telegram.hpp"

namespace vecat::twinsync {

// P2709[0]: 0 = 4 MBaud ... 6 = 250 kBaud.
std::optional<std::uint32_t> baud_rate(std::uint16_t selection) noexcept;
// P0302 switching frequency code (as in the status word: 0 2 kHz, 1 4 kHz, 2 6 kHz, 3 8 kHz, 4 12 kHz,
// 5 16 kHz) and the TWIN sampling time, the speed control cycle in which the drives exchange their
// telegrams (chapter 2): 125 us at 8 kHz, 250 us at every other frequency (the specification knows only
// these two sampling times and gives 125 us for 8 kHz alone).
inline constexpr std::uint64_t kSamplingTimeNs = 250'000;
inline constexpr std::uint64_t kSamplingTime8kHzNs = 125'000;
std::optional<std::uint64_t> sampling_time_ns(std::uint8_t switching_frequency) noexcept;
std::optional<std::uint32_t> switching_frequency_hz(std::uint8_t code) noexcept;
// UART time of a frame: 10 bits per byte (start, 8 data, stop).
std::uint64_t frame_time_ns(std::size_t bytes, std::uint32_t baud) noexcept;

struct LinkConfig {
    std::uint16_t baud_selection = 0;        // P2709[0]
    std::uint16_t frame_size_selection = 0;  // P2709[1]
    Layout layout = Layout::Standard;
    std::uint8_t switching_frequency = 1;  // P0302
    std::size_t send_pdo_bytes = 0;        // bytes the send mapping fills
    std::size_t receive_pdo_bytes = 0;     // bytes the receive mapping takes
};
// Empty when the configuration works; otherwise the reason, for the user.
std::string check_link(const LinkConfig& c);

// The cable between two option cards (end 0 and end 1). Frames are delivered to the other end; a frame
// sent at time t is seen by a receiver from its next control cycle on. The SYNC_OUT line carries the
// pulse of whichever end is master. Faults are injected per cable.
class Channel {
  public:
    struct Faults {
        bool cable_break = false;               // nothing passes in either direction, no sync pulses
        bool sync_loss = false;                 // the SYNC line is dead, data still passes
        std::uint32_t corrupt_next = 0;         // the next n frames (either direction) arrive with a bad CRC
        std::uint32_t drop_next = 0;            // the next n frames are lost
        std::uint32_t corrupt_per_million = 0;  // random corruption rate (deterministic sequence)
        std::uint32_t drop_per_million = 0;
    };

    // Faults a drive injects through its own dictionary (0x2104), combined with faults() of the cable.
    struct Injected {
        bool cable_break = false;
        bool sync_loss = false;
        std::uint32_t corrupt_per_million = 0;
        std::uint32_t drop_per_million = 0;
    };
    void inject(int end, const Injected& i) { injected_[end & 1] = i; }
    bool cable_broken() const noexcept {
        return faults_.cable_break || injected_[0].cable_break || injected_[1].cable_break;
    }
    bool sync_line_dead() const noexcept {
        return cable_broken() || faults_.sync_loss || injected_[0].sync_loss || injected_[1].sync_loss;
    }

    // The local oscillator of the drive at each end (ppm against the nominal frequency).
    void set_oscillator_ppm(int end, double ppm) { ppm_[end & 1] = ppm; }
    double oscillator_ppm(int end) const { return ppm_[end & 1]; }

    void send(int end, ConstBytes frame, std::uint64_t t_ns) noexcept;
    // The newest frame from the other end sent before t_ns and not yet received; empty span if none.
    ConstBytes receive(int end, std::uint64_t t_ns) noexcept;
    // The master end emits its SYNC_OUT pulse; the other end sees it unless the line is broken.
    void sync_pulse(int end, std::uint64_t t_ns) noexcept;
    bool sync_seen(int end, std::uint64_t since_ns) const noexcept;

    Faults& faults() { return faults_; }
    const Faults& faults() const { return faults_; }
    std::uint64_t frames_corrupted() const { return corrupted_; }
    std::uint64_t frames_dropped() const { return dropped_; }

  private:
    struct Slot {
        std::array<std::uint8_t, kMaxFrameBytes> bytes{};
        std::size_t size = 0;
        std::uint64_t t_ns = 0;
        bool fresh = false;
    };
    bool chance(std::uint32_t per_million) noexcept;

    std::array<std::array<Slot, 4>, 2> ring_{};  // per direction (index = sending end)
    std::array<std::size_t, 2> head_{};
    std::array<std::uint64_t, 2> last_pulse_{};  // per sending end
    std::array<bool, 2> pulsed_{};
    std::array<double, 2> ppm_{};
    Faults faults_;
    std::array<Injected, 2> injected_{};
    std::uint64_t corrupted_ = 0, dropped_ = 0;
    std::uint64_t rng_ = 0x9E3779B97F4A7C15ull;
};

// The slave's synchronisation controller: each control cycle it measures the phase of its own cycle
// against the last SYNC_OUT pulse and shifts its next cycle by at most P2618 x 15 ns. The phase moves by
// the oscillator difference of the two drives. Locked within 1 us; lost beyond 2 us (hysteresis).
class SyncController {
  public:
    static constexpr double kNsPerTick = 15.0;
    static constexpr double kLockNs = 1000.0;
    static constexpr double kLoseNs = 2000.0;
    static constexpr double kInitialPhaseNs = 10'000.0;  // where an unsynchronised slave cycle starts

    void reset() {
        phase_ns_ = kInitialPhaseNs;
        locked_ = false;
    }
    // Where the slave's cycle takes its synchronisation from (P2701): SYNC_OUT through the controller,
    // or the fieldbus, which holds it only while the fieldbus runs synchronised (EtherCAT DC).
    enum class Source : std::uint8_t { Twin, FieldbusSynchronised, FieldbusFreeRun };
    // One control cycle of period_ns; drift_ppm = slave oscillator minus master oscillator; pulse: a
    // SYNC_OUT pulse arrived during the cycle.
    void step(double period_ns, double drift_ppm, std::int16_t sync_ticks, bool pulse, Source source);
    double phase_ns() const { return phase_ns_; }
    bool locked() const { return locked_; }

  private:
    double phase_ns_ = kInitialPhaseNs;
    bool locked_ = false;
};

}  // namespace vecat::twinsync
