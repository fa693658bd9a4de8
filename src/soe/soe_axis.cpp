#include "soe/soe_axis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vecat::soe {

using cia402::Mode;
using cia402::State;
using protocol::AlState;
namespace cmd = protocol::cia402::cmd;
namespace cw = protocol::cia402::cw;

namespace {

// The standard telegrams of S-0-0015 (IEC 61800-7-204): the IDNs of the MDT and of the AT after the
// control and status word. 7, the application telegram, keeps what S-0-0024 and S-0-0016 say.
struct Telegram {
    std::vector<std::uint16_t> mdt, at;
};
Telegram standard_telegram(std::uint16_t type) {
    const std::uint16_t torque = idn::TorqueCommand.raw, velocity = idn::VelocityCommand.raw,
                        position = idn::PositionCommand.raw, position_fb = idn::PositionFeedback.raw,
                        velocity_fb = idn::VelocityFeedback.raw;
    switch (type) {
        case 1:
            return {{torque}, {}};
        case 2:
            return {{velocity}, {velocity_fb}};
        case 3:
            return {{velocity}, {position_fb}};
        case 4:
            return {{position}, {position_fb}};
        case 5:
            return {{position, velocity}, {position_fb, velocity_fb}};
        case 6:
            return {{velocity}, {}};
        default:
            return {};
    }
}

bool contains(const IdnEntry* list, std::uint16_t idn) {
    if (!list) return false;
    const auto w = list->words();
    return std::find(w.begin(), w.end(), idn) != w.end();
}

bool faulted(State s) {
    return s == State::Fault || s == State::FaultReactionActive;
}

// The class 1 diagnostic bit of a fault of the drive core.
std::uint16_t c1d_bit(std::uint16_t fault_code) {
    switch (fault_code) {
        case cia402::fault::FollowingError:
            return c1d::ExcessiveDeviation;
        case cia402::fault::OverCurrent:
            return c1d::OverloadShutdown;
        case cia402::fault::Encoder:
            return c1d::FeedbackError;
        case cia402::fault::ReferenceLimit:
            return c1d::TravelLimit;
        default:
            return c1d::Manufacturer;
    }
}

// S-0-0032..S-0-0035 mode code -> the drive core's cyclic synchronous mode.
Mode core_mode(std::uint16_t code) {
    switch (code & op_mode::ModeMask) {
        case op_mode::Torque:
            return Mode::CyclicTorque;
        case op_mode::Velocity:
            return Mode::CyclicVelocity;
        case op_mode::PositionFeedback1:
        case op_mode::PositionFeedback2:
            return Mode::CyclicPosition;
        default:
            return Mode::None;
    }
}

// Longest stretch of host time the core catches up at once (a debugger, a stopped master).
constexpr std::uint64_t kMaxCatchUpNs = 200'000'000;
// The ramps the drive brakes with (halt, drive off, a fault reaction), in increments/s^2.
constexpr double kDeceleration = 50 * kIncrementsPerRevolution;
constexpr double kQuickStopDeceleration = 100 * kIncrementsPerRevolution;

}  // namespace

SoeAxis::SoeAxis()
    : table_(drive_idns()), core_(std::make_unique<cia402::DriveCore>(cia402::MotorParameters{})) {
    rebuild_map();
    read_parameters();
    core_->start(io_);
    update_status();
}

void SoeAxis::rebuild_map() {
    auto resolve = [this](Idn list, std::vector<IdnEntry*>& out, unsigned& bytes) {
        out.clear();
        bytes = 2;  // the control (status) word is always there, not in the list (SOEM adds its 16 bits too)
        if (const IdnEntry* l = table_.find(list))
            for (const std::uint16_t w : l->words())
                if (IdnEntry* e = table_.find(Idn{w}); e && !e->attribute.list) {
                    out.push_back(e);
                    bytes += static_cast<unsigned>(e->attribute.element_size());
                }
    };
    resolve(idn::MdtConfiguration, mdt_, mdt_bytes_);
    resolve(idn::AtConfiguration, at_, at_bytes_);
}

void SoeAxis::configure(std::uint16_t telegram) {
    if (telegram == kApplicationTelegram) return;
    const Telegram t = standard_telegram(telegram);
    table_.find(idn::MdtConfiguration)->set_words(t.mdt);
    table_.find(idn::AtConfiguration)->set_words(t.at);
    rebuild_map();
}

// The parameters of the core that the IDNs set; the others keep the core's defaults (src/soe/README.md).
void SoeAxis::read_parameters() {
    cia402::DriveParameters& p = io_.parameters;
    // S-0-0159 monitoring window: the following error window, without delay (0x6065, 0x6066 = 0).
    p.following_error_window = static_cast<std::uint32_t>(std::min<std::uint64_t>(
        table_.find(idn::MonitoringWindow)->number(), std::numeric_limits<std::int32_t>::max()));
    p.following_error_timeout = 0;
    // S-0-0091 bipolar velocity limit (0.0001 rpm) -> maximum motor speed 0x6080 (rpm, 0: none).
    p.max_motor_speed = static_cast<std::uint32_t>(
        static_cast<double>(table_.find(idn::VelocityLimit)->number()) / kVelocityUnitsPerRpm);
    // No software position limits (a 0/0 pair switches them off), the drive's own braking ramps.
    p.software_limit_min = 0;
    p.software_limit_max = 0;
    p.profile_deceleration = static_cast<std::uint32_t>(kDeceleration);
    p.quick_stop_deceleration = static_cast<std::uint32_t>(kQuickStopDeceleration);
    core_->configure(io_);
}

// The controlword that takes the core's state machine towards what S-0-0134 asks (IEC 61800-7-204): drive
// enable (bit 14) off: torque off at once (disable voltage, logic ready); enable on, drive on (bit 15) off:
// power on without torque (switched on; from operation, "disable operation" brakes the axis first); both on:
// in operation; halt (bit 13 = 0) holds the axis. An S-0-0099 reset sends the fault reset edge.
std::uint16_t SoeAxis::core_controlword() const {
    const State s = core_->state();
    if (fault_reset_ && s == State::Fault) return cmd::FaultReset;
    const bool on = (control_ & control::DriveOn) != 0;
    std::uint16_t c = cmd::DisableVoltage;
    if ((control_ & control::DriveEnable) == 0)
        c = cmd::DisableVoltage;
    else if (s == State::SwitchOnDisabled || s == State::NotReadyToSwitchOn)
        c = cmd::Shutdown;  // transition 2 first
    else if (s == State::ReadyToSwitchOn || !on)
        c = cmd::SwitchOn;  // transition 3 (or 5 from operation)
    else
        c = cmd::EnableOperation;  // transition 4
    if ((control_ & control::Run) == 0) c |= cw::Halt;
    return c;
}

void SoeAxis::read_command() {
    cia402::DriveCommand& c = io_.command;
    c.controlword = core_controlword();
    const unsigned which = (control_ & control::ModeMask) >> control::ModeShift;
    const Idn mode_idn{static_cast<std::uint16_t>(idn::PrimaryOperationMode.raw + which)};
    const IdnEntry* m = table_.find(mode_idn);
    c.mode = static_cast<std::int8_t>(core_mode(m ? static_cast<std::uint16_t>(m->number()) : 0));
    c.target_position = static_cast<std::int32_t>(signed_value(idn::PositionCommand));
    const double rpm = static_cast<double>(signed_value(idn::VelocityCommand)) / kVelocityUnitsPerRpm;
    c.target_velocity = static_cast<std::int32_t>(
        std::clamp(std::llround(rpm * kIncrementsPerRevolution / 60.0),
                   static_cast<long long>(std::numeric_limits<std::int32_t>::min()),
                   static_cast<long long>(std::numeric_limits<std::int32_t>::max())));
    c.target_torque = static_cast<std::int16_t>(signed_value(idn::TorqueCommand));
}

void SoeAxis::servo_period() {
    read_command();
    core_->step(io_);
    const cia402::DriveFeedback& f = io_.feedback;
    if (f.raised) c1d_ |= c1d_bit(f.raised->code);
    if (fault_reset_ && !faulted(core_->state())) {
        fault_reset_ = false;
        c1d_ = 0;
    }
    set_value(idn::PositionFeedback, f.position_actual);
    const double rpm = static_cast<double>(f.velocity_actual) * 60.0 / kIncrementsPerRevolution;
    set_value(idn::VelocityFeedback, std::llround(rpm * kVelocityUnitsPerRpm));
    set_value(idn::TorqueFeedback, f.torque_actual);
    update_status();
}

void SoeAxis::advance(std::uint64_t now_ns) {
    now_ns_ = std::max(now_ns_, now_ns);
    if (!started_) {
        started_ = true;
        sim_ns_ = now_ns;
    }
    const std::uint64_t period = core_->period_ns();
    if (now_ns > sim_ns_ && now_ns - sim_ns_ > kMaxCatchUpNs) sim_ns_ = now_ns - kMaxCatchUpNs;
    while (now_ns >= sim_ns_ + period) {
        sim_ns_ += period;
        servo_period();
    }
    for (Pending& p : pending_)
        if (p.command && p.due_ns <= now_ns_) {
            IdnEntry* e = p.command;
            p = {};
            finish(*e);
        }
}

std::optional<std::uint64_t> SoeAxis::next_event_ns() const {
    std::optional<std::uint64_t> t;
    for (const Pending& p : pending_)
        if (p.command && (!t || p.due_ns < *t)) t = p.due_ns;
    return t;
}

void SoeAxis::set_phase(AlState s) {
    phase_ = s;
    if (s != AlState::Op) control_ = 0;
    update_status();
}

void SoeAxis::take_mdt(ConstBytes block) {
    control_ = phase_ == AlState::Op ? ld_le16(block.data()) : 0;
    std::size_t off = 2;
    for (IdnEntry* e : mdt_) {
        std::copy_n(block.begin() + static_cast<std::ptrdiff_t>(off), e->value.size(), e->value.begin());
        off += e->value.size();
    }
    update_status();
}

void SoeAxis::put_at(Bytes block) const {
    st_le16(block.data(), status_);
    std::size_t off = 2;
    for (const IdnEntry* e : at_) {
        std::copy(e->value.begin(), e->value.end(), block.begin() + static_cast<std::ptrdiff_t>(off));
        off += e->value.size();
    }
}

// S-0-0135 from the core's state: in operation (3) while operation is enabled (or a quick stop brakes),
// power ready (2) switched on, logic ready (1) otherwise, not ready (0) and bit 13 while the class 1
// diagnostic holds an error.
void SoeAxis::update_status() {
    const State s = core_->state();
    std::uint16_t ready = status::LogicReady;
    if (c1d_ != 0 || faulted(s))
        ready = status::NotReady;
    else if (s == State::OperationEnabled || s == State::QuickStopActive)
        ready = status::InOperation;
    else if (s == State::SwitchedOn)
        ready = status::PowerReady;
    status_ = static_cast<std::uint16_t>(ready << status::ReadyShift);
    if (ready == status::NotReady) status_ |= status::Class1Error;
    if (ready == status::InOperation) status_ |= static_cast<std::uint16_t>(control_ & control::ModeMask);
    if (command_change_) status_ |= status::CommandChange;
}

std::int64_t SoeAxis::signed_value(Idn i) const {
    const IdnEntry* e = table_.find(i);
    if (!e) return 0;
    const std::uint64_t v = e->number();
    const unsigned bits = static_cast<unsigned>(e->attribute.element_size() * 8);
    if (bits >= 64) return static_cast<std::int64_t>(v);
    const std::uint64_t sign = std::uint64_t{1} << (bits - 1);
    return static_cast<std::int64_t>((v ^ sign) - sign);
}

void SoeAxis::set_value(Idn i, std::int64_t v) {
    if (IdnEntry* e = table_.find(i)) e->set_number(static_cast<std::uint64_t>(v));
}

void SoeAxis::refresh(IdnEntry& e) {
    if (e.idn == idn::StatusWord) e.set_number(status_);
    if (e.idn == idn::ControlWord) e.set_number(control_);
    if (e.idn == idn::Class1Diagnostic) e.set_number(c1d_);
    if (e.idn == idn::DiagnosticMessage) {
        std::string_view m = core_->state() == State::OperationEnabled ? "in operation" : "ready";
        if (c1d_ & c1d::ExcessiveDeviation)
            m = "F: excessive deviation (S-0-0011 bit 11)";
        else if (c1d_ & c1d::OverloadShutdown)
            m = "F: overload shutdown (S-0-0011 bit 0)";
        else if (c1d_ & c1d::FeedbackError)
            m = "F: feedback error (S-0-0011 bit 5)";
        else if (c1d_ & c1d::TravelLimit)
            m = "F: travel limit exceeded (S-0-0011 bit 13)";
        else if (c1d_ != 0)
            m = "F: drive fault (S-0-0011 bit 15)";
        e.value.assign(m.begin(), m.end());
    }
}

std::optional<SoeError> SoeAxis::write_value(IdnEntry& e, ConstBytes value) {
    if (e.attribute.command) return command(e, value.size() >= 2 ? ld_le16(value.data()) : 0);
    const bool cyclic_phase = phase_ == AlState::SafeOp || phase_ == AlState::Op;
    // A value of the MDT is the master's cyclic data in CP3/CP4: a mailbox write would be overwritten.
    if (cyclic_phase && std::find(mdt_.begin(), mdt_.end(), &e) != mdt_.end()) return SoeError::DataCyclic;
    if (e.idn == idn::MdtConfiguration || e.idn == idn::AtConfiguration) {
        // The lists are the application telegram's; a standard telegram fixes them.
        if (table_.find(idn::TelegramType)->number() != kApplicationTelegram)
            return SoeError::DataProtectedBySettings;
        const IdnEntry* allowed =
            table_.find(e.idn == idn::MdtConfiguration ? idn::MdtConfigurable : idn::AtConfigurable);
        for (std::size_t i = 0; i + 1 < value.size(); i += 2)
            if (!contains(allowed, ld_le16(value.data() + i))) return SoeError::DataInvalid;
    }
    e.value.assign(value.begin(), value.end());
    if (e.idn == idn::TelegramType) configure(static_cast<std::uint16_t>(e.number()));
    if (e.idn == idn::MdtConfiguration || e.idn == idn::AtConfiguration) rebuild_map();
    if (e.idn == idn::MonitoringWindow || e.idn == idn::VelocityLimit) read_parameters();
    return std::nullopt;
}

// A procedure command (IEC 61800-7-204): the master writes 3 (set and enable) to start it, 1 to interrupt
// it, 0 to clear it. Started, its acknowledgment (data state) reads 0x7 "in progress" for the command's
// execution time (P-0-0101; 0: at once), then 0x3 (executed) or 0xF (error); the command change bit of
// S-0-0135 is set and a notification is sent (finish()).
std::optional<SoeError> SoeAxis::command(IdnEntry& e, std::uint16_t input) {
    auto drop_pending = [&] {
        for (Pending& p : pending_)
            if (p.command == &e) p = {};
    };
    switch (input) {
        case command_input::Cancel:
            drop_pending();
            e.data_state = command_state::NotSet;
            command_change_ = false;
            break;
        case command_input::SetNotEnabled:
            // Interrupts a command not yet executed (not started, or in progress).
            if (e.data_state != command_state::NotSet && e.data_state != command_state::InProgress &&
                e.data_state != command_state::Interrupted)
                return SoeError::CommandNotInterruptible;
            drop_pending();
            e.data_state = command_state::Interrupted;
            break;
        case command_input::SetAndEnable: {
            if (e.data_state != command_state::NotSet && e.data_state != command_state::Interrupted)
                return SoeError::CommandActive;
            // The transition checks run in the phase they lead from.
            if ((e.idn == idn::Cp3TransitionCheck && phase_ != AlState::PreOp) ||
                (e.idn == idn::Cp4TransitionCheck && phase_ != AlState::SafeOp))
                return SoeError::CommandNotNow;
            const std::uint64_t us = table_.find(idn::CommandDuration)->number();
            e.set_number(input);
            if (us == 0) {
                finish(e);
                return std::nullopt;
            }
            e.data_state = command_state::InProgress;
            for (Pending& p : pending_)
                if (!p.command) {
                    p = {&e, now_ns_ + us * 1000};
                    break;
                }
            break;
        }
        default:
            return SoeError::DataInvalid;
    }
    e.set_number(input);
    update_status();
    return std::nullopt;
}

void SoeAxis::finish(IdnEntry& e) {
    e.data_state = execute(e.idn) ? command_state::Executed : command_state::Error;
    command_change_ = true;
    bool listed = false;
    for (std::size_t k = 0; k < finished_count_; ++k)
        listed = listed || finished_[k] == e.idn;
    if (!listed && finished_count_ < finished_.size()) finished_[finished_count_++] = e.idn;
    update_status();
}

bool SoeAxis::take_finished(Idn& i) {
    if (finished_count_ == 0) return false;
    i = finished_[0];
    std::copy(finished_.begin() + 1, finished_.begin() + static_cast<std::ptrdiff_t>(finished_count_),
              finished_.begin());
    --finished_count_;
    return true;
}

bool SoeAxis::execute(Idn i) {
    if (i == idn::ResetClass1Diagnostic) {
        // The core leaves its fault with the next servo period's fault reset edge; without one, at once.
        if (faulted(core_->state()))
            fault_reset_ = true;
        else
            c1d_ = 0;
        return true;
    }
    if (i == idn::Cp3TransitionCheck) return !sm_ok_ || sm_ok_();
    return true;  // S-0-0128: the drive has nothing to wait for before CP4
}

}  // namespace vecat::soe
