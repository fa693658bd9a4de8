#include "cia402/twinsync_port.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <fmt/format.h>

#include "device/object_description.hpp"

namespace vecat::twinsync {

using coe::Entry;
using protocol::SdoAbort;

// The dictionary entries the card uses, looked up once.
struct Port::Config {
    explicit Config(coe::ObjectDictionary& od) {
        auto at = [&](std::uint16_t parameter, std::uint8_t sub = 0) {
            return od.find(object_index(parameter), sub);
        };
        setting = at(p::Setting);
        mode = at(p::Mode);
        for (std::uint8_t i = 0; i < 8; ++i) {
            send[i] = at(p::ProcessSendData, static_cast<std::uint8_t>(i + 1));
            receive[i] = at(p::ProcessReceiveData, static_cast<std::uint8_t>(i + 1));
        }
        baud = at(p::PhyLinkConfig, 1);
        frame = at(p::PhyLinkConfig, 2);
        switching_frequency = at(p::SwitchingFrequency);
        control_selector = at(p::ControlSelector);
        setpoint_selector = at(p::SetpointSelector);
        setpoint_mode = at(p::SetpointMode);
        drivecom_init = at(p::DriveComInit);
        max_fault_time = at(p::MaxFaultTime);
        sync_ticks = at(p::SyncTicks);
        sync_sel = at(p::SyncSel);
        config = at(p::Config);
        rx_statusword = at(p::Statusword);
        comm_status = at(p::CommStatus);
        slave_ctrl = at(p::SlaveCtrlWord);
        slave_status = at(p::SlaveStatus);
        system_load = at(p::SystemLoad);
        error_number = at(p::CurrentError, 1);
        error_location = at(p::CurrentError, 2);
        inverted = at(p::SlaveInverted);
        remote_act_pos = at(p::RemoteActPos);
        act_speed_master = at(p::ActSpeedMaster);
        remote_act_torque = at(p::RemoteActTorque);
        remote_torque_scale = at(p::RemoteScaling, 1);
        position_limit = at(p::GantryPositionLimit);
        speed_limit = at(p::GantrySpeedLimit);
        message = od.find(0x2102, 0);
        torque_limit = od.find(0x2103, 0);
        for (std::uint8_t i = 0; i < 6; ++i)
            inject[i] = od.find(0x2104, static_cast<std::uint8_t>(i + 1));
    }
    bool complete() const { return setting && mode && send[7] && receive[7] && baud && frame; }

    Entry* setting = nullptr;
    Entry* mode = nullptr;
    Entry* send[8] = {};
    Entry* receive[8] = {};
    Entry* baud = nullptr;
    Entry* frame = nullptr;
    Entry* switching_frequency = nullptr;
    Entry* control_selector = nullptr;
    Entry* setpoint_selector = nullptr;
    Entry* setpoint_mode = nullptr;
    Entry* drivecom_init = nullptr;
    Entry* max_fault_time = nullptr;
    Entry* sync_ticks = nullptr;
    Entry* sync_sel = nullptr;
    Entry* config = nullptr;
    Entry* rx_statusword = nullptr;
    Entry* comm_status = nullptr;
    Entry* slave_ctrl = nullptr;
    Entry* slave_status = nullptr;
    Entry* system_load = nullptr;
    Entry* error_number = nullptr;
    Entry* error_location = nullptr;
    Entry* inverted = nullptr;
    Entry* remote_act_pos = nullptr;
    Entry* act_speed_master = nullptr;
    Entry* remote_act_torque = nullptr;
    Entry* remote_torque_scale = nullptr;
    Entry* position_limit = nullptr;
    Entry* speed_limit = nullptr;
    Entry* message = nullptr;
    Entry* torque_limit = nullptr;
    Entry* inject[6] = {};
};

namespace {

template <class T>
T rd(const Entry* e, T fallback = T{}) {
    return e ? e->get<T>() : fallback;
}

MappingWords words_of(Entry* const (&e)[8]) {
    MappingWords w{};
    for (std::size_t i = 0; i < 8; ++i)
        w[i] = rd<std::uint32_t>(e[i]);
    return w;
}

// Copies `bytes` little-endian bytes of a telegram field into an entry (sign- or zero-extended).
void store(Entry& e, const std::uint8_t* src, std::size_t bytes) {
    std::array<std::uint8_t, 8> v{};
    const std::size_t n = std::min<std::size_t>(bytes, v.size());
    std::memcpy(v.data(), src, n);
    if (device::is_signed(e.type()) && n > 0 && (src[n - 1] & 0x80))
        std::fill(v.begin() + static_cast<long>(n), v.end(), 0xFF);
    e.assign(ConstBytes(v.data(), std::min(e.capacity(), v.size())));
}

void load(const Entry& e, std::uint8_t* dst, std::size_t bytes) {
    const ConstBytes v = e.value();
    const bool negative = device::is_signed(e.type()) && !v.empty() && (v.back() & 0x80);
    for (std::size_t i = 0; i < bytes; ++i)
        dst[i] = i < v.size() ? v[i] : (negative ? 0xFF : 0x00);
}

}  // namespace

Port::Port(coe::ObjectDictionary& od, std::uint64_t period_ns)
    : od_(od), period_ns_(period_ns), c_(std::make_unique<Config>(od)) {
    if (!c_->complete()) return;  // a device without the TWINsync parameters
    std::vector<Entry*> checked = {c_->setting, c_->mode, c_->baud, c_->frame, c_->switching_frequency};
    for (auto* e : c_->send)
        checked.push_back(e);
    for (auto* e : c_->receive)
        checked.push_back(e);
    for (Entry* e : checked) {
        if (!e) continue;
        e->hooks().on_download = [this](const Entry& entry, ConstBytes v) {
            return validate_write(const_cast<Entry&>(entry), v);
        };
        e->hooks().after_download = [this](Entry&) { reconfigure(); };
    }
    for (Entry* e : {c_->control_selector, c_->setpoint_selector, c_->setpoint_mode})
        if (e) e->hooks().after_download = [this](Entry&) { reconfigure(); };
    // P0149 MPRO_DRVCOM_Init (4.1.2): "an initialisation be forced" after master and slave were configured.
    if (c_->drivecom_init)
        c_->drivecom_init->hooks().after_download = [this](Entry& e) {
            if (e.get<std::uint16_t>() == 0) return;
            initialise();
            e.set(std::uint16_t{0});
        };
    // One-shot injections: the next n frames on the cable.
    if (c_->inject[2])
        c_->inject[2]->hooks().after_download = [this](Entry& e) {
            if (channel_) channel_->faults().corrupt_next += e.get<std::uint32_t>();
            e.set(std::uint32_t{0});
        };
    if (c_->inject[3])
        c_->inject[3]->hooks().after_download = [this](Entry& e) {
            if (channel_) channel_->faults().drop_next += e.get<std::uint32_t>();
            e.set(std::uint32_t{0});
        };
    reconfigure();
}

Port::~Port() = default;

void Port::connect(std::shared_ptr<Channel> channel, int end) {
    channel_ = std::move(channel);
    end_ = end & 1;
    reconfigure();
}

void Port::set_message(std::string m) {
    message_ = std::move(m);
    if (c_->message)
        c_->message->assign(ConstBytes(reinterpret_cast<const std::uint8_t*>(message_.data()),
                                       std::min(message_.size(), c_->message->capacity())));
}

bool Port::resolve(const MappingWords& words, bool extended, std::vector<Mapped>& out, std::size_t& bytes,
                   std::string& why) const {
    out.clear();
    bytes = 0;
    std::size_t first = 0, last = 8;
    if (!extended) {
        if (words[0] > 7) {
            why = fmt::format("sub-ID 0 of the standard mapping counts {} objects; at most 7", words[0]);
            return false;
        }
        first = 1;
        last = 1 + words[0];
    }
    for (std::size_t i = first; i < last; ++i) {
        if (extended && words[i] == 0) continue;
        const auto m = extended ? decode_extended(words[i]) : decode_standard(words[i]);
        if (!m) {
            why = fmt::format("mapping word {:04X}.{:04X} (sub-ID {}) is not valid", words[i] >> 16,
                              words[i] & 0xFFFF, i);
            return false;
        }
        if (m->scope) {
            why = fmt::format("sub-ID {} maps scope signal {}: scope signals are not emulated by vecat", i,
                              m->parameter);
            return false;
        }
        const coe::Object* o = od_.find(object_index(m->parameter));
        Entry* e = nullptr;
        if (o) {
            auto* obj = const_cast<coe::Object*>(o);
            e = obj->code() == device::ObjectCode::Var
                    ? (m->element == 0 ? obj->entry(0) : nullptr)
                    : obj->entry(static_cast<std::uint8_t>(m->element + 1));
        }
        if (!e || e->type() == device::DataType::VisibleString) {
            why = fmt::format("sub-ID {} maps P{:04}[{}], which this drive does not have", i, m->parameter,
                              m->element);
            return false;
        }
        const std::size_t n = extended ? e->bit_length() / 8 : m->bits / 8u;
        if (n == 0 || n > 4) {
            why = fmt::format("sub-ID {} maps P{:04}[{}] of {} bits; 8, 16 or 32 are possible", i,
                              m->parameter, m->element, e->bit_length());
            return false;
        }
        out.push_back({e, n});
        bytes += n;
    }
    return true;
}

SdoAbort Port::check_configuration() {
    const auto setting = rd<std::uint8_t>(c_->setting);
    const ModeInfo* info = mode_info(setting);
    if (!info) return SdoAbort::ValueRange;
    if (!info->refusal.empty()) {
        set_message(fmt::format("P2580 = {} ({}) refused: {}", setting, info->name, info->refusal));
        return SdoAbort::CannotTransfer;
    }
    const auto role = static_cast<Role>(rd<std::uint16_t>(c_->mode));
    if (role == Role::Off) return SdoAbort::None;
    const auto automatic = automatic_mapping(info->setting);
    const MappingWords send = automatic ? automatic->send : words_of(c_->send);
    const MappingWords receive = automatic ? automatic->receive : words_of(c_->receive);
    std::vector<Mapped> s, r;
    LinkConfig lc;
    std::string why;
    if (!resolve(send, info->extended, s, lc.send_pdo_bytes, why) ||
        !resolve(receive, info->extended, r, lc.receive_pdo_bytes, why)) {
        set_message("TWINsync mapping refused: " + why);
        return SdoAbort::NotMappable;
    }
    lc.baud_selection = rd<std::uint16_t>(c_->baud);
    lc.frame_size_selection = rd<std::uint16_t>(c_->frame);
    lc.layout = info->extended ? Layout::Extended : Layout::Standard;
    lc.switching_frequency = static_cast<std::uint8_t>(rd<std::uint16_t>(c_->switching_frequency, 1));
    why = check_link(lc);
    if (!why.empty()) {
        set_message("TWINsync link refused: " + why);
        return SdoAbort::ParameterIncompatible;
    }
    return SdoAbort::None;
}

SdoAbort Port::validate_write(Entry& e, ConstBytes value) {
    // The configuration as it would be with the new value; the old one is put back either way.
    std::array<std::uint8_t, 8> old{};
    const std::size_t n = std::min(e.size(), old.size());
    std::copy_n(e.value().begin(), n, old.begin());
    if (std::find(std::begin(c_->send), std::end(c_->send), &e) != std::end(c_->send) ||
        std::find(std::begin(c_->receive), std::end(c_->receive), &e) != std::end(c_->receive)) {
        const ModeInfo* info = mode_info(rd<std::uint8_t>(c_->setting));
        if (info && automatic_mapping(info->setting)) {
            set_message(fmt::format("P2580 = {} ({}) maps automatically; set P2580 = 0 (USER) to map by hand",
                                    static_cast<unsigned>(info->setting), info->name));
            return SdoAbort::CannotTransfer;
        }
    }
    e.assign(value);
    const SdoAbort a = check_configuration();
    e.assign(ConstBytes(old.data(), n));
    if (a == SdoAbort::None) set_message("");
    return a;
}

void Port::reconfigure() {
    if (!c_->complete()) return;
    const Role before = role_;
    role_ = static_cast<Role>(rd<std::uint16_t>(c_->mode));
    mode_ = mode_info(rd<std::uint8_t>(c_->setting));
    configured_ = false;
    send_.clear();
    receive_.clear();
    if (!mode_ || !mode_->refusal.empty()) return;
    layout_ = mode_->extended ? Layout::Extended : Layout::Standard;
    if (const auto automatic = automatic_mapping(mode_->setting)) {
        for (std::size_t i = 0; i < 8; ++i) {
            c_->send[i]->set(automatic->send[i]);
            c_->receive[i]->set(automatic->receive[i]);
        }
    }
    std::size_t sb = 0, rb = 0;
    std::string why;
    if (!resolve(words_of(c_->send), mode_->extended, send_, sb, why) ||
        !resolve(words_of(c_->receive), mode_->extended, receive_, rb, why))
        return;
    pdo_size_ = pdo_bytes(layout_, rd<std::uint16_t>(c_->frame)).value_or(0);
    configured_ = sb <= pdo_size_ && rb <= pdo_size_;
    // The slave tables of chapter 6 (6.5-6.11, 6.14) require P0301 = IP-Mode (1): otherwise the slave
    // does not take TWINsync's set-points, as with P0165 not TWINSYNC.
    if (role_ == Role::Slave && rd<std::uint16_t>(c_->setpoint_selector) == kSetpointByTwinsync &&
        !setpoint_mode_fits())
        set_message(fmt::format(
            "P2580 = {} ({}) needs P0301 = 1 (IP-Mode) on the slave; with P0301 = {} it "
            "does not follow TWINsync's set-points",
            static_cast<unsigned>(mode_->setting), mode_->name, rd<std::uint16_t>(c_->setpoint_mode)));
    if (before != role_) {
        sync_.reset();
        has_data_ = false;
        fault_time_ns_ = 0;
        state_mismatch_ns_ = 0;
        pending_.reset();
        partner_ = {};
    }
}

void Port::initialise() {
    // The link starts again as after power-on: initialisation mode in the status word (bit 0 clear) until
    // valid data arrive, the slave's synchronisation controller from its initial phase, the monitoring's
    // timers from zero. The last received data stay in their parameters.
    sync_.reset();
    has_data_ = false;
    fresh_ = false;
    fault_time_ns_ = 0;
    state_mismatch_ns_ = 0;
    pending_.reset();
    partner_ = {};
    status_.link_ok = false;
    status_.synchronised = false;
    ++status_.initialisations;
    reconfigure();
}

bool Port::setpoint_mode_fits() const {
    return !mode_ || !requires_ip_mode(mode_->setting) ||
           rd<std::uint16_t>(c_->setpoint_mode, kSetpointModeIp) == kSetpointModeIp;
}

std::uint16_t Port::received_control_word() const {
    return c_->slave_ctrl ? c_->slave_ctrl->get<std::uint16_t>() : rx_drivecom_;
}

bool Port::receives(std::uint16_t parameter) const {
    if (!active() || !configured_) return false;
    const coe::Object* o = od_.find(object_index(parameter));
    if (!o) return false;
    for (const Mapped& m : receive_)
        for (const Entry& e : o->entries())
            if (&e == m.entry) return true;
    return false;
}

bool Port::follows() const {
    return active() && configured_ && role_ == Role::Slave && mode_ && mode_->follow != Follow::None &&
           rd<std::uint16_t>(c_->setpoint_selector) == kSetpointByTwinsync && setpoint_mode_fits();
}

bool Port::controlled_by_twinsync() const {
    return active() && configured_ && role_ == Role::Slave &&
           rd<std::uint16_t>(c_->control_selector) == kControlByTwinsync;
}

bool Port::partner_enabled() const {
    return partner_.drivecom_state == static_cast<std::uint8_t>(DriveComState::OperationEnabled);
}

void Port::apply_fault_injection() {
    Channel::Injected i;
    i.cable_break = rd<std::uint8_t>(c_->inject[0]) != 0;
    i.sync_loss = rd<std::uint8_t>(c_->inject[1]) != 0;
    i.corrupt_per_million = rd<std::uint32_t>(c_->inject[4]);
    i.drop_per_million = rd<std::uint32_t>(c_->inject[5]);
    channel_->inject(end_, i);
}

void Port::receive(std::uint64_t t_ns, const LocalState& local) {
    status_.mode = static_cast<std::uint16_t>(role_);
    status_.setting = mode_ ? static_cast<std::uint8_t>(mode_->setting) : 0;
    if (!active() || !configured_) {
        status_.link_ok = false;
        status_.synchronised = false;
        pending_.reset();
        // Nothing monitored, nothing wrong: P2619 bit 0 "no error" (table 4.1).
        status_.comm_status = comm_status::NoError;
        if (c_->comm_status) c_->comm_status->set(comm_status::NoError);
        return;
    }
    apply_fault_injection();
    bool valid = false;
    fresh_ = false;
    const ConstBytes frame = channel_->receive(end_, t_ns);
    if (frame.empty()) {
        ++status_.frames_missing;
    } else {
        Telegram t;
        if (decode(frame, layout_, pdo_size_, t) == DecodeError::None) {
            valid = true;
            fresh_ = true;
            ++status_.frames_received;
            has_data_ = true;
            std::size_t off = 0;
            for (const Mapped& m : receive_) {
                store(*m.entry, t.pdo.data() + off, m.bytes);
                off += m.bytes;
            }
            if (layout_ == Layout::Standard) {
                partner_ = TwinStatusWord::unpack(t.status);
                status_.rx_statusword = t.status;
                if (c_->rx_statusword) c_->rx_statusword->set(t.status);
                rx_drivecom_ = t.drivecom_word;
                if (role_ == Role::Slave && c_->slave_ctrl) c_->slave_ctrl->set(t.drivecom_word);
                if (role_ == Role::Master && c_->slave_status) c_->slave_status->set(t.drivecom_word);
            }
        } else {
            ++status_.crc_errors;
        }
    }
    // The slave's control cycle against the master's SYNC_OUT.
    if (role_ == Role::Slave) {
        const auto sel = static_cast<SyncSelection>(rd<std::uint16_t>(c_->sync_sel));
        const auto source = sel == SyncSelection::SlaveByFieldbus
                                ? (local.fieldbus_synchronised ? SyncController::Source::FieldbusSynchronised
                                                               : SyncController::Source::FieldbusFreeRun)
                                : SyncController::Source::Twin;
        const bool pulse = channel_->sync_seen(end_, t_ns >= 2 * period_ns_ ? t_ns - 2 * period_ns_ : 0);
        const double drift = channel_->oscillator_ppm(end_) - channel_->oscillator_ppm(end_ ^ 1);
        sync_.step(static_cast<double>(period_ns_), drift, rd<std::int16_t>(c_->sync_ticks, 0), pulse,
                   source);
        status_.sync_offset_ns = static_cast<std::int64_t>(std::llround(sync_.phase_ns()));
        status_.synchronised = sync_.locked();
    } else {
        status_.sync_offset_ns = 0;
        status_.synchronised = true;
    }
    monitor(local, valid);
}

void Port::monitor(const LocalState& local, bool valid) {
    const bool ok = valid && status_.synchronised;
    fault_time_ns_ = ok ? 0.0 : fault_time_ns_ + static_cast<double>(period_ns_);
    const double max_fault_ns = static_cast<double>(rd<float>(c_->max_fault_time, 10.0f)) * 1e6;
    const bool lost = fault_time_ns_ > max_fault_ns;
    status_.link_ok = has_data_ && !lost;
    pending_.reset();
    std::uint16_t bits = 0;
    const bool control = local.state == DriveComState::OperationEnabled;
    if (layout_ == Layout::Standard) {
        // Monitoring of chapter 7 (not in the extended mapping, section 4.1.2).
        if (lost) bits |= comm_status::CommunicationLost;
        if (has_data_ && !lost) {
            const auto own_frequency =
                static_cast<std::uint8_t>(rd<std::uint16_t>(c_->switching_frequency, 1));
            if (partner_.switching_frequency != own_frequency) bits |= comm_status::SwitchingFrequency;
            if (partner_.mode == role_) bits |= comm_status::ModeConflict;
        }
        // DriveCom states: up to state 5; not while the partner stops or is in its error reaction.
        const bool check_states =
            !(role_ == Role::Master && (rd<std::uint32_t>(c_->config) & kConfigNoSlaveStateCheck));
        const bool differ = status_.link_ok && control && partner_.drivecom_state < 5;
        state_mismatch_ns_ =
            (check_states && differ) ? state_mismatch_ns_ + static_cast<double>(period_ns_) : 0.0;
        if (state_mismatch_ns_ > max_fault_ns) bits |= comm_status::DriveComState;
        if (lost)
            pending_ = error::Communication;
        else if (bits & comm_status::ModeConflict)
            pending_ = error::ModeConflict;
        else if (bits & comm_status::SwitchingFrequency)
            pending_ = error::SwitchingFrequency;
        else if (bits & comm_status::DriveComState)
            pending_ = error::DriveComState;
    }
    // Gantry monitoring (section 6.2.12).
    status_.tracking_error = 0;
    if (!pending_ && status_.link_ok && mode_) {
        const double inv = rd<std::int16_t>(c_->inverted, 1) < 0 ? -1.0 : 1.0;
        if (mode_->setting == Setting::PconGantryMaster) {
            const double slave_pos = inv * rd<std::int32_t>(c_->remote_act_pos);
            status_.tracking_error = static_cast<float>(local.position - slave_pos);
            const double slave_speed = inv * static_cast<double>(rd<float>(c_->act_speed_master));
            if (control &&
                (std::abs(local.position - slave_pos) > rd<std::uint32_t>(c_->position_limit, 0xFFFFFFFFu) ||
                 std::abs(local.speed_rpm - slave_speed) > rd<float>(c_->speed_limit, 1e30f)))
                pending_ = error::SpeedDifference;
        }
        if (mode_->setting == Setting::PconGantrySlave && control) {
            const double limit = rd<std::uint16_t>(c_->torque_limit) * 1e-3 * local.rated_torque_nm;
            const double remote = rd<std::int16_t>(c_->remote_act_torque) / 32768.0 *
                                  static_cast<double>(rd<float>(c_->remote_torque_scale, 1.0f));
            if (limit > 0 && std::abs(local.torque_nm - inv * remote) > limit)
                pending_ = error::TorqueDifference;
        }
        // 39-02: the other axis reports an error (SystemError, bit 14 of its TWINsync status word, table
        // 4.5), in every operation mode with the standard mapping: a fault of either drive stops both
        // (chapter 7; TwinCAT NC's error propagation INSTANTANEOUS, TX1250 3.1). The extended mapping has no
        // status word and no monitoring (4.1.2).
        if (!pending_ && control && layout_ == Layout::Standard && partner_.system_error)
            pending_ = error::OtherAxis;
    }
    status_.comm_status = bits ? bits : comm_status::NoError;
    if (c_->comm_status) c_->comm_status->set(status_.comm_status);
}

void Port::transmit(std::uint64_t t_ns, const LocalState& local) {
    const std::uint8_t number = raised_ ? raised_->number : 0;
    const std::uint8_t location = raised_ ? raised_->location : 0;
    status_.error_number = number;
    status_.error_location = location;
    if (!active() || !configured_) return;
    if (role_ == Role::Master) channel_->sync_pulse(end_, t_ns);

    Telegram t;
    t.layout = layout_;
    t.pdo_size = static_cast<std::uint8_t>(pdo_size_);
    TwinStatusWord sw;
    sw.cyclic = has_data_;
    sw.switching_frequency = static_cast<std::uint8_t>(rd<std::uint16_t>(c_->switching_frequency, 1));
    sw.mode = role_;
    sw.drivecom_state = static_cast<std::uint8_t>(local.state);
    sw.chopper = false;
    sw.pwm_disable_event = local.state != DriveComState::OperationEnabled;
    sw.system_error = local.fault;
    sw.techopt_error = status_.comm_status != comm_status::NoError;
    t.status = sw.pack();
    status_.tx_statusword = t.status;
    if (role_ == Role::Master) {
        t.drivecom_word = control_word_from_cia402(local.controlword, local.homing_mode);
        if (c_->slave_ctrl) c_->slave_ctrl->set(t.drivecom_word);
        status_.slave_control_word = t.drivecom_word;
    } else {
        std::uint16_t st = 0;
        if (local.state == DriveComState::OperationEnabled) st |= slave_status::OperationEnabled;
        if (local.fault) st |= slave_status::Fault;
        if (local.homed) st |= slave_status::HomePositionSet;
        if (local.transition) st |= slave_status::OpInProgress;
        st |= static_cast<std::uint16_t>((static_cast<unsigned>(local.state) & 0x7u)
                                         << slave_status::DriveComShift);
        t.drivecom_word = st;
        if (c_->slave_status) c_->slave_status->set(st);
        status_.slave_status = st;
        status_.slave_control_word = received_control_word();
    }
    std::size_t off = 0;
    for (const Mapped& m : send_) {
        load(*m.entry, t.pdo.data() + off, m.bytes);
        off += m.bytes;
    }
    std::array<std::uint8_t, kMaxFrameBytes> buf{};
    const std::size_t n = encode(t, Bytes(buf.data(), buf.size()));
    channel_->send(end_, ConstBytes(buf.data(), n), t_ns);
    ++status_.frames_sent;
    // System load: the UART time of the frame in both directions (full duplex, so one frame's time).
    if (c_->system_load) {
        const auto baud = baud_rate(rd<std::uint16_t>(c_->baud)).value_or(4'000'000);
        c_->system_load->set(static_cast<float>(frame_time_ns(n, baud)));
    }
}

}  // namespace vecat::twinsync
