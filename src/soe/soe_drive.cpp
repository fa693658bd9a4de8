#include "soe/soe_drive.hpp"

#include <algorithm>
#include <cstdlib>

namespace vecat::soe {

using protocol::AlState;

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

}  // namespace

SoeDrive::SoeDrive(const device::DeviceDescription&) : table_(drive_idns()) {
    rebuild_map();
}

std::unique_ptr<esc::Application> make_soe_drive(const device::DeviceDescription& d) {
    return std::make_unique<SoeDrive>(d);
}

std::unique_ptr<esc::Segment> make_soe_segment(const device::DeviceDescription& d, std::size_t n,
                                               const esc::EscConfig& cfg) {
    return esc::make_segment(esc::DeviceModel::of(d), n, cfg, make_soe_drive);
}

void SoeDrive::attach(esc::Slave& slave) {
    slave_ = &slave;
    auto server = std::make_unique<SoeServer>(*this);
    server_ = server.get();
    slave.add_mailbox_protocol(std::move(server));
}

void SoeDrive::rebuild_map() {
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

void SoeDrive::configure(std::uint16_t telegram) {
    if (telegram == kApplicationTelegram) return;
    const Telegram t = standard_telegram(telegram);
    table_.find(idn::MdtConfiguration)->set_words(t.mdt);
    table_.find(idn::AtConfiguration)->set_words(t.at);
    rebuild_map();
}

void SoeDrive::on_state_change(AlState, AlState to) {
    state_ = to;
    if (to != AlState::Op) {
        enabled_ = false;
        control_ = 0;
    }
    step(false);
}

void SoeDrive::outputs_safe_state() {
    control_ = 0;
    enabled_ = false;
}

std::int64_t SoeDrive::signed_value(Idn i) const {
    const IdnEntry* e = table_.find(i);
    if (!e) return 0;
    const std::uint64_t v = e->number();
    const unsigned bits = static_cast<unsigned>(e->attribute.element_size() * 8);
    if (bits >= 64) return static_cast<std::int64_t>(v);
    const std::uint64_t sign = std::uint64_t{1} << (bits - 1);
    return static_cast<std::int64_t>((v ^ sign) - sign);
}

void SoeDrive::set_value(Idn i, std::int64_t v) {
    if (IdnEntry* e = table_.find(i)) e->set_number(static_cast<std::uint64_t>(v));
}

void SoeDrive::exchange(std::uint64_t, ConstBytes outputs, bool apply_outputs, Bytes inputs) {
    const bool apply = apply_outputs && outputs.size() >= mdt_bytes_;
    if (apply) {
        control_ = ld_le16(outputs.data());
        std::size_t off = 2;
        for (IdnEntry* e : mdt_) {
            std::copy_n(outputs.begin() + static_cast<std::ptrdiff_t>(off), e->value.size(),
                        e->value.begin());
            off += e->value.size();
        }
    }
    step(apply);
    if (inputs.size() < at_bytes_) return;
    st_le16(inputs.data(), status_);
    std::size_t off = 2;
    for (const IdnEntry* e : at_) {
        std::copy(e->value.begin(), e->value.end(), inputs.begin() + static_cast<std::ptrdiff_t>(off));
        off += e->value.size();
    }
}

// The drive: a follower. Enabled (drive on, enable, in OP with outputs), the feedback takes the command of
// each cycle: position feedback 1 = position command, velocity feedback = velocity command, torque feedback
// = torque command. A position command further from the feedback than the monitoring window (S-0-0159)
// shuts the drive down with "excessive deviation" in S-0-0011 until S-0-0099 clears it. Halt (bit 13 = 0)
// holds the position.
void SoeDrive::step(bool apply) {
    const bool on = apply && state_ == AlState::Op && (control_ & control::DriveOn);
    const bool enable = on && (control_ & control::DriveEnable) && c1d_ == 0;
    enabled_ = enable;
    const bool run = enabled_ && (control_ & control::Run);
    if (run) {
        // Looked up in the resolved MDT (no allocation in the cycle).
        const bool position_mapped = std::any_of(
            mdt_.begin(), mdt_.end(), [](const IdnEntry* m) { return m->idn == idn::PositionCommand; });
        if (position_mapped) {
            const std::int64_t cmd = signed_value(idn::PositionCommand);
            const std::int64_t fb = signed_value(idn::PositionFeedback);
            const auto window = static_cast<std::int64_t>(table_.find(idn::MonitoringWindow)->number());
            if (std::llabs(cmd - fb) > window) {
                c1d_ |= c1d::ExcessiveDeviation;
                enabled_ = false;
            } else {
                set_value(idn::PositionFeedback, cmd);
            }
        }
    }
    const bool moving = run && enabled_;
    set_value(idn::VelocityFeedback, moving ? signed_value(idn::VelocityCommand) : 0);
    set_value(idn::TorqueFeedback, moving ? signed_value(idn::TorqueCommand) : 0);
    std::uint16_t ready = status::LogicReady;
    if (c1d_ != 0)
        ready = status::NotReady;
    else if (enabled_)
        ready = status::InOperation;
    else if (on)
        ready = status::PowerReady;
    status_ = static_cast<std::uint16_t>(ready << status::ReadyShift);
    if (c1d_ != 0) status_ |= status::Class1Error;
    if (enabled_) status_ |= static_cast<std::uint16_t>(control_ & control::ModeMask);
    if (command_change_) status_ |= status::CommandChange;
}

void SoeDrive::refresh(unsigned, IdnEntry& e) {
    if (e.idn == idn::StatusWord) e.set_number(status_);
    if (e.idn == idn::ControlWord) e.set_number(control_);
    if (e.idn == idn::Class1Diagnostic) e.set_number(c1d_);
    if (e.idn == idn::DiagnosticMessage) {
        const std::string_view m =
            c1d_ ? "F: excessive deviation (S-0-0011 bit 11)" : (enabled_ ? "in operation" : "ready");
        e.value.assign(m.begin(), m.end());
    }
}

std::optional<SoeError> SoeDrive::write_value(unsigned, IdnEntry& e, ConstBytes value) {
    if (e.attribute.command) return command(e, value.size() >= 2 ? ld_le16(value.data()) : 0);
    const bool cyclic_phase = state_ == AlState::SafeOp || state_ == AlState::Op;
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
    return std::nullopt;
}

// A procedure command (IEC 61800-7-204): the master writes 3 (set and enable) to start it, 1 to interrupt
// it, 0 to clear it. The drive executes at once; the acknowledgment (data state) becomes 3 (executed) or
// 0xF (error), the command change bit of S-0-0135 is set and a notification is sent.
std::optional<SoeError> SoeDrive::command(IdnEntry& e, std::uint16_t input) {
    switch (input) {
        case command_input::Cancel:
            e.data_state = command_state::NotSet;
            command_change_ = false;
            break;
        case command_input::SetNotEnabled:
            if (e.data_state != command_state::NotSet) return SoeError::CommandNotInterruptible;
            e.data_state = command_state::Interrupted;
            break;
        case command_input::SetAndEnable: {
            if (e.data_state != command_state::NotSet && e.data_state != command_state::Interrupted)
                return SoeError::CommandActive;
            // The transition checks run in the phase they lead from.
            if ((e.idn == idn::Cp3TransitionCheck && state_ != AlState::PreOp) ||
                (e.idn == idn::Cp4TransitionCheck && state_ != AlState::SafeOp))
                return SoeError::CommandNotNow;
            e.data_state = execute(e.idn) ? command_state::Executed : command_state::Error;
            command_change_ = true;
            notify(e.idn);
            break;
        }
        default:
            return SoeError::DataInvalid;
    }
    e.set_number(input);
    step(false);
    return std::nullopt;
}

bool SoeDrive::execute(Idn i) {
    if (i == idn::ResetClass1Diagnostic) {
        c1d_ = 0;
        return true;
    }
    if (i == idn::Cp3TransitionCheck) {
        // CP3 needs the process data SyncManagers as long as the telegrams configured.
        if (!slave_) return true;
        const auto& d = slave_->description();
        const auto out = d.sm_index_of_type(device::SmType::Outputs);
        const auto in = d.sm_index_of_type(device::SmType::Inputs);
        return out && in && slave_->esc().sm_config(*out).length == mdt_bytes_ &&
               slave_->esc().sm_config(*in).length == at_bytes_;
    }
    return true;  // S-0-0128: the drive has nothing to wait for before CP4
}

void SoeDrive::notify(Idn i) {
    for (std::size_t k = 0; k < notes_count_; ++k)
        if (notes_[k] == i) return;
    if (notes_count_ == kMaxNotes)
        return;  // bounded: the oldest are still there, the master reads them first
    notes_[notes_count_++] = i;
}

bool SoeDrive::take_notification(unsigned& drive, Idn& i) {
    if (notes_count_ == 0) return false;
    drive = 0;
    i = notes_[0];
    std::copy(notes_.begin() + 1, notes_.begin() + static_cast<std::ptrdiff_t>(notes_count_), notes_.begin());
    --notes_count_;
    return true;
}

}  // namespace vecat::soe
