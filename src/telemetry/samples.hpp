// What the telemetry carries, as plain C++ structures (no DDS): one record per axis and sampled cycle, the
// EtherCAT status of each slave, the TWINsync link of each drive that has one, events, and the channels of
// each I/O terminal. The sampler
// fills them on the cyclic thread; the publisher converts them to the IDL types (vecat_telemetry.idl).
#pragma once

#include <array>
#include <cstdint>
#include <variant>

namespace vecat::telemetry {

// AxisSample::cia402_state of a statusword that shows no state (IEC 61800-7-201 Table 30).
inline constexpr std::uint8_t kNoCia402State = 0xFF;

// One axis in one sampled cycle. Drive values are those of the dictionary objects, as a master reads them
// over EtherCAT (user units of the drive's factor group; torque in per mille of the rated torque).
struct AxisSample {
    std::uint64_t time_ns = 0;  // host CLOCK_MONOTONIC: receive time of the frame that was processed
    std::uint64_t cycle = 0;    // process data exchanges of the slave so far
    std::uint16_t slave = 0;    // position on the line
    std::uint8_t axis = 0;
    std::uint8_t cia402_state = 0;     // protocol::cia402::State the statusword shows, or kNoCia402State
    std::int8_t mode = 0;              // 0x6061 modes of operation display
    std::uint16_t controlword = 0;     // 0x6040
    std::uint16_t statusword = 0;      // 0x6041
    std::uint16_t error_code = 0;      // 0x603F
    std::int32_t position_demand = 0;  // 0x6062
    std::int32_t position_actual = 0;  // 0x6064
    std::int32_t velocity_actual = 0;  // 0x606C
    std::int16_t torque_actual = 0;    // 0x6077
    std::int32_t following_error = 0;  // 0x60F4
};

// The EtherCAT side of one slave (published at a lower rate, and whenever the AL state changes).
struct SlaveStatus {
    std::uint64_t time_ns = 0;
    std::uint16_t slave = 0;
    std::uint8_t al_status = 0;              // AL status register 0x0130 (state | error flag 0x10)
    std::uint16_t al_status_code = 0;        // 0x0134
    std::int32_t dc_time_difference_ns = 0;  // 0x092C as a signed value
    std::uint8_t watchdog_pd_expiries = 0;   // 0x0442
    std::uint8_t watchdog_pdi_expiries = 0;  // 0x0443
    std::uint32_t rx_errors = 0;             // 0x0300-0x0307: invalid frames and RX errors, all ports
    std::uint32_t lost_links = 0;            // 0x0310-0x0313, all ports
    std::uint64_t frames = 0;                // process data exchanges
    std::uint64_t mailbox_errors = 0;
    std::uint64_t emergencies = 0;  // CoE emergencies sent
};

// TWINsync status of one drive (twinsync::LinkStatus reduced to what a scope shows).
struct TwinsyncSample {
    std::uint64_t time_ns = 0;
    std::uint16_t slave = 0;
    std::uint8_t axis = 0;
    std::uint8_t mode = 0;  // 0 OFF, 1 SLAVE, 2 MASTER
    std::uint16_t tx_statusword = 0;
    std::uint16_t rx_statusword = 0;
    std::uint16_t comm_status = 0;
    bool synchronised = false;
    bool link_ok = false;
    std::uint8_t error_number = 0;
    std::uint64_t frames_sent = 0;
    std::uint64_t frames_received = 0;
    std::uint64_t crc_errors = 0;
    std::uint64_t frames_missing = 0;
    std::int64_t sync_offset_ns = 0;
    float tracking_error = 0;  // user units
};

// I/O channels one IoSample holds per direction; a terminal with more shows its first kIoChannels (the
// others are not sampled: in_channels/out_channels say how many the sample holds).
inline constexpr unsigned kIoChannels = 16;

// The channels of one I/O terminal (io::InputTerminal, io::OutputTerminal) in one sampled cycle, as the
// process image holds them: a digital channel 0 or 1, an analog one the raw signed 16-bit value.
struct IoSample {
    std::uint64_t time_ns = 0;      // host CLOCK_MONOTONIC: receive time of the frame that was processed
    std::uint64_t cycle = 0;        // process data exchanges of the slave so far
    std::uint16_t slave = 0;        // position on the line
    bool analog = false;            // the channels are analog (raw counts), else digital (bits)
    std::uint8_t in_channels = 0;   // valid entries of in (inputs the terminal sends to the master)
    std::uint8_t out_channels = 0;  // valid entries of out (outputs the master writes)
    std::array<std::int16_t, kIoChannels> in{};
    std::array<std::int16_t, kIoChannels> out{};
};

enum class EventKind : std::uint8_t {
    AlState = 1,       // AL status register changed (old/new: 0x0130), code: 0x0134
    Cia402State = 2,   // old/new: AxisSample::cia402_state (the statusword decoded)
    Mode = 3,          // modes of operation display changed
    Fault = 4,         // a new non-zero 0x603F error code (code)
    FaultCleared = 5,  // 0x603F back to zero (old: the code)
    Emergency = 6,     // a CoE emergency was sent (new: emergencies so far, code: 0x603F at the time)
    Overflow = 7,      // the telemetry queue was full (new: records lost so far)
};
const char* to_string(EventKind k) noexcept;

struct Event {
    std::uint64_t time_ns = 0;
    std::uint16_t slave = 0;
    std::uint8_t axis = 0;
    EventKind kind = EventKind::AlState;
    std::uint32_t code = 0;
    std::int64_t old_value = 0;
    std::int64_t new_value = 0;
};

// What goes through the queue from the cyclic thread to the publisher (trivially copyable).
using Record = std::variant<AxisSample, SlaveStatus, TwinsyncSample, Event, IoSample>;

}  // namespace vecat::telemetry
