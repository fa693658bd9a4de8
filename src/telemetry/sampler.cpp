#include "telemetry/sampler.hpp"

#include "coe/coe_application.hpp"
#include "common/bytes.hpp"
#include "io/terminals.hpp"
#include "protocol/cia402.hpp"
#include "protocol/cia402_objects.hpp"
#include "protocol/registers.hpp"
#include "twinsync/status.hpp"

namespace vecat::telemetry {

const char* to_string(EventKind k) noexcept {
    switch (k) {
        case EventKind::AlState:
            return "al_state";
        case EventKind::Cia402State:
            return "cia402_state";
        case EventKind::Mode:
            return "mode";
        case EventKind::Fault:
            return "fault";
        case EventKind::FaultCleared:
            return "fault_cleared";
        case EventKind::Emergency:
            return "emergency";
        case EventKind::Overflow:
            return "overflow";
    }
    return "unknown";
}

// One slave and the objects read from it, looked up once.
struct Sampler::Slot {
    std::uint16_t position = 0;
    esc::Slave* slave = nullptr;
    coe::CoeApplication* coe = nullptr;  // nullptr: no CoE (status only)
    // A CiA 402 device: its dictionary has the statusword 0x6041 (axis samples, CiA 402 state events).
    bool axis = false;
    const twinsync::StatusSource* twinsync = nullptr;  // nullptr: no TWINsync option card
    // An I/O terminal (IoSample): its process image and how its channels are laid out there.
    esc::ProcessImageApplication* io = nullptr;  // nullptr: no I/O terminal
    io::ChannelKind io_kind = io::ChannelKind::Digital;
    std::uint8_t io_in = 0;   // channels sampled from the inputs (at most kIoChannels)
    std::uint8_t io_out = 0;  // channels sampled from the outputs
    // The CiA 402 objects (unbound where the device has none: they read 0).
    coe::Value<std::uint16_t> controlword;
    coe::Value<std::uint16_t> statusword;
    coe::Value<std::uint16_t> error_code;
    coe::Value<std::int8_t> mode;
    coe::Value<std::int32_t> position_demand;
    coe::Value<std::int32_t> position_actual;
    coe::Value<std::int32_t> velocity_actual;
    coe::Value<std::int16_t> torque_actual;
    coe::Value<std::int32_t> following_error;
    std::uint64_t last_exchange = 0;
    std::uint64_t exchanges_seen = 0;  // exchanges since sampling started (decimation)
    std::uint64_t samples = 0;
    // Previous values for the event detection.
    std::uint8_t al_status = 0;
    std::uint16_t statusword_seen = 0;  // the statusword cia402_state was decoded from
    std::uint8_t cia402_state = 0;
    std::int8_t mode_value = 0;
    std::uint16_t fault = 0;
    std::uint64_t emergencies = 0;
};

namespace {

namespace obj = protocol::obj;

template <class T>
T read(const coe::Value<T>& v) {
    return v.get_or(T{});
}

// Channel c of a terminal's image (io/terminals.hpp): bit c of a digital one, the little-endian signed
// 16-bit value at byte 2c of an analog one; 0 beyond the image.
std::int16_t channel(const std::vector<std::uint8_t>& img, io::ChannelKind kind, unsigned c) {
    if (kind == io::ChannelKind::Digital)
        return c / 8 < img.size() ? static_cast<std::int16_t>((img[c / 8] >> (c % 8)) & 1u) : std::int16_t{0};
    return 2 * c + 1 < img.size() ? static_cast<std::int16_t>(ld_le16(&img[2 * c])) : std::int16_t{0};
}

std::uint8_t sampled_channels(unsigned n) {
    return static_cast<std::uint8_t>(n < kIoChannels ? n : kIoChannels);
}

// The CiA 402 state the statusword shows (IEC 61800-7-201 Table 30), kNoCia402State for a pattern of none.
std::uint8_t cia402_state(std::uint16_t statusword) {
    const auto st = protocol::cia402::decode_state(statusword);
    return st ? static_cast<std::uint8_t>(*st) : kNoCia402State;
}

}  // namespace

Sampler::Sampler(esc::Segment& seg, TelemetryQueue& q, SamplerOptions opt)
    : seg_(seg), q_(q), opt_(opt), slaves_epoch_(seg.slaves_epoch()) {
    if (opt_.decimation == 0) opt_.decimation = 1;
    if (opt_.status_every == 0) opt_.status_every = 1;
    slots_.resize(seg.size());
    for (std::size_t i = 0; i < seg.size(); ++i) {
        Slot& s = slots_[i];
        bind(s, i);
        s.al_status = s.slave->esc().al_status();
        if (s.axis) {
            s.statusword_seen = read<std::uint16_t>(s.statusword);
            s.cia402_state = cia402_state(s.statusword_seen);
        }
        s.mode_value = read<std::int8_t>(s.mode);
        s.fault = read<std::uint16_t>(s.error_code);
    }
}

void Sampler::bind(Slot& s, std::size_t i) {
    s.position = static_cast<std::uint16_t>(i);
    s.slave = &seg_.slave(i);
    s.coe = dynamic_cast<coe::CoeApplication*>(&s.slave->app());
    s.twinsync = dynamic_cast<const twinsync::StatusSource*>(&s.slave->app());
    s.controlword = {};
    s.statusword = {};
    s.error_code = {};
    s.mode = {};
    s.position_demand = {};
    s.position_actual = {};
    s.velocity_actual = {};
    s.torque_actual = {};
    s.following_error = {};
    s.axis = false;
    s.io = nullptr;
    s.io_in = s.io_out = 0;
    if (auto* in = dynamic_cast<io::InputTerminal*>(&s.slave->app())) {
        s.io = in;
        s.io_kind = in->kind();
        s.io_in = sampled_channels(in->channels());
    } else if (auto* out = dynamic_cast<io::OutputTerminal*>(&s.slave->app())) {
        s.io = out;
        s.io_kind = out->kind();
        s.io_out = sampled_channels(out->channels());
    }
    if (s.io) s.last_exchange = s.io->exchanges();
    if (!s.coe) return;
    auto& od = s.coe->dictionary();
    s.controlword = coe::bind(od, obj::controlword);
    s.statusword = coe::bind(od, obj::statusword);
    s.error_code = coe::bind(od, obj::error_code);
    s.mode = coe::bind(od, obj::modes_of_operation_display);
    s.position_demand = coe::bind(od, obj::position_demand_value);
    s.position_actual = coe::bind(od, obj::position_actual_value);
    s.velocity_actual = coe::bind(od, obj::velocity_actual_value);
    s.torque_actual = coe::bind(od, obj::torque_actual_value);
    s.following_error = coe::bind(od, obj::following_error_actual_value);
    s.axis = s.statusword.bound();
    s.last_exchange = s.coe->exchanges();
    s.emergencies = s.coe->sdo_server().counters().emergencies_sent;
}

void Sampler::follow_slaves() {
    if (seg_.slaves_epoch() == slaves_epoch_) return;
    // A slave restarted (a new Slave object, power off or hot connect) or the slaves moved: every slot binds
    // the slave at its position again. What the events compare with stays the slot's, so a restart shows as
    // the change of state it is; the counters start from the new application's.
    slaves_epoch_ = seg_.slaves_epoch();
    if (slots_.size() != seg_.size()) slots_.resize(seg_.size());
    for (std::size_t i = 0; i < slots_.size(); ++i)
        bind(slots_[i], i);
}

Sampler::~Sampler() = default;

void Sampler::on_frame(std::uint64_t now_ns) {
    follow_slaves();
    ++stats_.frames;
    for (auto& s : slots_) {
        detect_events(s, now_ns);
        if (s.io) {
            const std::uint64_t ex = s.io->exchanges();
            if (ex == s.last_exchange) continue;
            s.last_exchange = ex;
            if (s.exchanges_seen++ % opt_.decimation == 0) sample_io(s, now_ns);
            continue;
        }
        if (!s.coe) continue;
        const std::uint64_t ex = s.coe->exchanges();
        if (ex == s.last_exchange) continue;
        s.last_exchange = ex;
        if (s.exchanges_seen++ % opt_.decimation == 0) sample(s, now_ns);
    }
    const std::uint64_t lost = q_.overflows();
    if (lost != overflows_reported_ && !slots_.empty()) {
        // Reported once the queue has room again.
        Event e;
        e.time_ns = now_ns;
        e.kind = EventKind::Overflow;
        e.old_value = static_cast<std::int64_t>(overflows_reported_);
        e.new_value = static_cast<std::int64_t>(lost);
        if (q_.push(Record{e})) overflows_reported_ = lost;
    }
}

void Sampler::sample_all(std::uint64_t now_ns) {
    follow_slaves();
    for (auto& s : slots_) {
        detect_events(s, now_ns);
        if (s.io)
            sample_io(s, now_ns);
        else
            sample(s, now_ns);
    }
}

void Sampler::sample_io(Slot& s, std::uint64_t now_ns) {
    IoSample io;
    io.time_ns = now_ns;
    io.cycle = s.io->exchanges();
    io.slave = s.position;
    io.analog = s.io_kind == io::ChannelKind::Analog;
    io.in_channels = s.io_in;
    io.out_channels = s.io_out;
    for (unsigned c = 0; c < s.io_in; ++c)
        io.in[c] = channel(s.io->inputs(), s.io_kind, c);
    for (unsigned c = 0; c < s.io_out; ++c)
        io.out[c] = channel(s.io->outputs(), s.io_kind, c);
    if (q_.push(Record{io})) ++stats_.io_samples;
    if (s.samples++ % opt_.status_every == 0) status(s, now_ns);
}

void Sampler::sample(Slot& s, std::uint64_t now_ns) {
    if (s.axis) {
        AxisSample a;
        a.time_ns = now_ns;
        a.cycle = s.coe->exchanges();
        a.slave = s.position;
        // The statusword detect_events read and decoded just before, in the same frame.
        a.statusword = s.statusword_seen;
        a.cia402_state = s.cia402_state;
        a.mode = read<std::int8_t>(s.mode);
        a.controlword = read<std::uint16_t>(s.controlword);
        a.error_code = read<std::uint16_t>(s.error_code);
        a.position_demand = read<std::int32_t>(s.position_demand);
        a.position_actual = read<std::int32_t>(s.position_actual);
        a.velocity_actual = read<std::int32_t>(s.velocity_actual);
        a.torque_actual = read<std::int16_t>(s.torque_actual);
        a.following_error = read<std::int32_t>(s.following_error);
        if (q_.push(Record{a})) ++stats_.samples;
        if (const twinsync::LinkStatus* ts = s.twinsync ? s.twinsync->twinsync_status() : nullptr) {
            TwinsyncSample t;
            t.time_ns = now_ns;
            t.slave = s.position;
            t.mode = static_cast<std::uint8_t>(ts->mode);
            t.tx_statusword = ts->tx_statusword;
            t.rx_statusword = ts->rx_statusword;
            t.comm_status = ts->comm_status;
            t.synchronised = ts->synchronised;
            t.link_ok = ts->link_ok;
            t.error_number = ts->error_number;
            t.frames_sent = ts->frames_sent;
            t.frames_received = ts->frames_received;
            t.crc_errors = ts->crc_errors;
            t.frames_missing = ts->frames_missing;
            t.sync_offset_ns = ts->sync_offset_ns;
            t.tracking_error = ts->tracking_error;
            q_.push(Record{t});
        }
    }
    if (s.samples++ % opt_.status_every == 0) status(s, now_ns);
}

void Sampler::status(Slot& s, std::uint64_t now_ns) {
    const esc::Esc& e = s.slave->esc();
    SlaveStatus st;
    st.time_ns = now_ns;
    st.slave = s.position;
    st.al_status = e.al_status();
    st.al_status_code = e.al_status_code();
    // 0x092C: bit 31 is the sign (1: local copy of the system time smaller than the received one).
    const std::uint32_t diff = e.peek32(protocol::addr(protocol::Reg::DcSystemTimeDifference));
    const std::int32_t mag = static_cast<std::int32_t>(diff & 0x7FFF'FFFFu);
    st.dc_time_difference_ns = (diff & 0x8000'0000u) ? -mag : mag;
    st.watchdog_pd_expiries = e.peek(protocol::addr(protocol::Reg::WatchdogCounterProcessData));
    st.watchdog_pdi_expiries = e.peek(protocol::addr(protocol::Reg::WatchdogCounterPdi));
    for (std::uint16_t i = 0; i < 8; ++i)
        st.rx_errors += e.peek(static_cast<std::uint16_t>(protocol::addr(protocol::Reg::RxErrorCounter) + i));
    for (std::uint16_t i = 0; i < 4; ++i)
        st.lost_links +=
            e.peek(static_cast<std::uint16_t>(protocol::addr(protocol::Reg::LostLinkCounter) + i));
    st.mailbox_errors = s.slave->counters().mailbox_errors;
    if (s.io) st.frames = s.io->exchanges();
    if (s.coe) {
        st.frames = s.coe->exchanges();
        st.emergencies = s.coe->sdo_server().counters().emergencies_sent;
    }
    q_.push(Record{st});
}

void Sampler::event(const Slot& s, std::uint64_t now_ns, EventKind k, std::uint32_t code,
                    std::int64_t old_value, std::int64_t new_value) {
    Event e;
    e.time_ns = now_ns;
    e.slave = s.position;
    e.kind = k;
    e.code = code;
    e.old_value = old_value;
    e.new_value = new_value;
    if (q_.push(Record{e})) ++stats_.events;
}

void Sampler::detect_events(Slot& s, std::uint64_t now_ns) {
    const esc::Esc& e = s.slave->esc();
    const std::uint8_t al = e.al_status();
    if (al != s.al_status) {
        event(s, now_ns, EventKind::AlState, e.al_status_code(), s.al_status, al);
        s.al_status = al;
        status(s, now_ns);
    }
    if (s.axis) {
        const auto sw = read<std::uint16_t>(s.statusword);
        if (sw != s.statusword_seen) {  // the state is the statusword's: decoded when that changed
            s.statusword_seen = sw;
            const std::uint8_t st = cia402_state(sw);
            if (st != s.cia402_state) {
                event(s, now_ns, EventKind::Cia402State, 0, s.cia402_state, st);
                s.cia402_state = st;
            }
        }
    }
    if (!s.coe) return;
    const auto m = read<std::int8_t>(s.mode);
    if (m != s.mode_value) {
        event(s, now_ns, EventKind::Mode, 0, s.mode_value, m);
        s.mode_value = m;
    }
    const auto f = read<std::uint16_t>(s.error_code);
    if (f != s.fault) {
        if (f != 0)
            event(s, now_ns, EventKind::Fault, f, s.fault, f);
        else
            event(s, now_ns, EventKind::FaultCleared, s.fault, s.fault, 0);
        s.fault = f;
    }
    const std::uint64_t em = s.coe->sdo_server().counters().emergencies_sent;
    if (em != s.emergencies) {
        event(s, now_ns, EventKind::Emergency, f, static_cast<std::int64_t>(s.emergencies),
              static_cast<std::int64_t>(em));
        s.emergencies = em;
    }
}

}  // namespace vecat::telemetry
