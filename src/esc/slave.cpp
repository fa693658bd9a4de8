// The slave's firmware (slave.hpp): the AL state machine, the mailbox layer with its quirks and the process
// data exchange, run by the segment after frames, before frames that must find it current, and at its
// deadlines. About 630 lines: the three share the slave's state and its run order (Slave::run).
#include "esc/slave.hpp"

#include <algorithm>
#include <cstring>

namespace vecat::esc {

using protocol::addr;
using protocol::AlState;
using protocol::AlStatusCode;
using protocol::is_valid_state;
using protocol::kAlErrorFlag;
using protocol::kAlIdentFlag;
using protocol::kAlStateMask;
using protocol::kMailboxHeaderSize;
using protocol::kMaxMailboxSize;
using protocol::kMaxSms;
using protocol::MailboxError;
using protocol::MailboxHeader;
using protocol::MailboxType;
using protocol::make_mailbox_error;
using protocol::parse_mailbox_header;
using protocol::Reg;
using protocol::sm_addr;
using protocol::write_mailbox_header;
namespace al_event = protocol::al_event;
namespace sm = protocol::sm;
namespace {

constexpr unsigned rank(AlState s) {
    switch (s) {
        case AlState::Init:
            return 0;
        case AlState::Boot:
            return 0;
        case AlState::PreOp:
            return 1;
        case AlState::SafeOp:
            return 2;
        case AlState::Op:
            return 3;
    }
    return 0;
}

constexpr unsigned row(AlState s) {
    switch (s) {
        case AlState::Init:
            return 0;
        case AlState::PreOp:
            return 1;
        case AlState::Boot:
            return 2;
        case AlState::SafeOp:
            return 3;
        case AlState::Op:
            return 4;
    }
    return 0;
}

// ETG.1000.6 Table 9 (state transitions). Rows: from; columns: to (INIT, PREOP, BOOT, SAFEOP, OP).
using A = AlAction;
constexpr AlAction kAlTable[5][5] = {
    /* INIT   */ {A::Stay, A::CheckMailbox, A::CheckBoot, A::Refuse, A::Refuse},
    /* PREOP  */ {A::Down, A::Stay, A::Refuse, A::CheckProcessData, A::Refuse},
    /* BOOT   */ {A::Down, A::Refuse, A::Stay, A::Refuse, A::Refuse},
    /* SAFEOP */ {A::Down, A::Down, A::Refuse, A::Stay, A::CheckOutputs},
    /* OP     */ {A::Down, A::Down, A::Refuse, A::Down, A::Stay},
};

}  // namespace

AlAction al_transition(AlState from, AlState to) noexcept {
    return kAlTable[row(from)][row(to)];
}

void ProcessImageApplication::exchange(std::uint64_t, ConstBytes out, bool apply, Bytes in) {
    // std::copy_n, not memcpy: a device without outputs or inputs (an I/O terminal, a coupler) has an
    // empty image whose data() may be null.
    if (apply) std::copy_n(out.begin(), std::min(out.size(), outputs_.size()), outputs_.begin());
    std::copy_n(inputs_.begin(), std::min(in.size(), inputs_.size()), in.begin());
    ++exchanges_;
}

void ProcessImageApplication::outputs_safe_state() {
    std::fill(outputs_.begin(), outputs_.end(), 0);
}

// Reply sink writing into the slave's bounded reply queue.
class SlaveReplySink final : public MailboxReplySink {
  public:
    explicit SlaveReplySink(Slave& s) : s_(s) {}
    Bytes reply_buffer() override {
        const std::size_t mbx_len =
            s_.sm_mbx_in_ >= 0 ? s_.esc_.sm_config(static_cast<unsigned>(s_.sm_mbx_in_)).length : 0;
        const std::size_t payload = mbx_len > kMailboxHeaderSize ? mbx_len - kMailboxHeaderSize : 0;
        auto& slot = s_.q_count_ < Slave::kReplySlots
                         ? s_.queue_[(s_.q_head_ + s_.q_count_) % Slave::kReplySlots]
                         : overflow_;
        return Bytes(slot.data() + kMailboxHeaderSize, std::min(payload, slot.size() - kMailboxHeaderSize));
    }
    void commit(MailboxType type, std::size_t payload_len) override {
        if (s_.q_count_ >= Slave::kReplySlots) {
            ++s_.counters_.mailbox_replies_dropped;
            return;
        }
        const std::size_t slot_i = (s_.q_head_ + s_.q_count_) % Slave::kReplySlots;
        auto& slot = s_.queue_[slot_i];
        s_.reply_counter_ = static_cast<std::uint8_t>(s_.reply_counter_ % 7 + 1);
        MailboxHeader h;
        h.length = static_cast<std::uint16_t>(payload_len);
        h.type = static_cast<std::uint8_t>(type);
        h.counter = s_.reply_counter_;
        write_mailbox_header(Bytes(slot.data(), kMailboxHeaderSize), h);
        s_.queue_len_[slot_i] = kMailboxHeaderSize + payload_len;
        s_.queue_due_[slot_i] = s_.now_ns_ + s_.desc_.quirks.mailbox_delay_ns;
        ++s_.q_count_;
    }

    bool can_commit() const override { return s_.q_count_ < Slave::kReplySlots; }
    std::size_t pending() const override {
        const bool in_sm =
            s_.sm_mbx_in_ >= 0 && s_.esc_.sm_mailbox_full(static_cast<unsigned>(s_.sm_mbx_in_));
        return s_.q_count_ + (in_sm ? 1 : 0);
    }

  private:
    Slave& s_;
    std::vector<std::uint8_t> overflow_ = std::vector<std::uint8_t>(kMaxMailboxSize);
};

DeviceModel DeviceModel::of(const device::DeviceDescription& d) {
    return {std::make_shared<const device::DeviceDescription>(d),
            std::make_shared<const std::vector<std::uint8_t>>(build_sii_image(d)),
            std::make_shared<const std::vector<device::ObjectDescription>>(device::dictionary_objects(d))};
}

Slave::Slave(const device::DeviceDescription& desc, EscConfig esc_cfg, std::unique_ptr<Application> app)
    : Slave(DeviceModel::of(desc), esc_cfg, std::move(app)) {}

Slave::Slave(const DeviceModel& model, EscConfig esc_cfg, std::unique_ptr<Application> app)
    : model_(model), desc_(*model_.description), app_(std::move(app)), esc_(esc_cfg, *model_.sii_image) {
    coe_ = app_->mailbox_protocol(MailboxType::CoE);
    // A SyncManager past the ESC's 16 does not exist (a description made in code may list more).
    auto idx = [&](device::SmType t) {
        auto i = desc_.sm_index_of_type(t);
        return i && *i < kMaxSms ? static_cast<int>(*i) : -1;
    };
    sm_mbx_out_ = idx(device::SmType::MailboxOut);
    sm_mbx_in_ = idx(device::SmType::MailboxIn);
    sm_out_ = idx(device::SmType::Outputs);
    sm_in_ = idx(device::SmType::Inputs);
    decl_out_ = desc_.sm_of_type(device::SmType::Outputs);
    decl_in_ = desc_.sm_of_type(device::SmType::Inputs);
    const auto may_bypass = [](const device::SyncManagerConfig* decl, int smi) {
        return decl && smi >= 0 &&
               (!(decl->enable & device::sm_enable::Enable) || (decl->enable & device::sm_enable::Virtual));
    };
    out_may_bypass_ = may_bypass(decl_out_, sm_out_);
    in_may_bypass_ = may_bypass(decl_in_, sm_in_);
    // Mailbox buffers of the mailbox sizes the description declares (an ESI may declare more than the
    // usual 1486 bytes; a master fills such a mailbox with several datagrams).
    const auto boot = desc_.bootstrap_mailbox();
    const auto mbx_size = [&](device::SmType t) {
        const auto* c = desc_.sm_of_type(t);
        const std::size_t boot_len =
            !boot ? 0 : (t == device::SmType::MailboxOut ? boot->out_length : boot->in_length);
        return std::max<std::size_t>({kMaxMailboxSize, c ? c->length : std::size_t{0}, boot_len});
    };
    rx_.resize(mbx_size(device::SmType::MailboxOut));
    last_reply_.resize(mbx_size(device::SmType::MailboxIn));
    for (auto& q : queue_)
        q.resize(mbx_size(device::SmType::MailboxIn));
    outputs_.resize(2048);
    inputs_.resize(2048);
    sink_ = std::make_unique<SlaveReplySink>(*this);
    app_->attach(*this);
    set_sm_group(true, false);
    set_sm_group(false, false);
    publish_status();
}

Slave::~Slave() = default;

void Slave::set_sm_group(bool mailbox, bool active) {
    if (esc_.device_emulation()) return;  // no PDI that could deactivate a SyncManager
    const int a = mailbox ? sm_mbx_out_ : sm_out_;
    const int b = mailbox ? sm_mbx_in_ : sm_in_;
    if (a >= 0) esc_.pdi_deactivate_sm(static_cast<unsigned>(a), !active);
    if (b >= 0) esc_.pdi_deactivate_sm(static_cast<unsigned>(b), !active);
}

void Slave::publish_status() {
    // Under device emulation the ESC keeps AL status itself (INIT at power-up, then what the master wrote).
    if (esc_.device_emulation()) return;
    std::uint8_t st = static_cast<std::uint8_t>(state_);
    std::uint16_t code = static_cast<std::uint16_t>(code_);
    if (error_) {
        st |= kAlErrorFlag;
    } else if (ident_) {
        st |= kAlIdentFlag;
        code = esc_.peek16(addr(Reg::StationAlias));
    }
    esc_.pdi_write_al_status(st, error_ ? code : (ident_ ? code : 0));
}

void Slave::enter(AlState to, std::uint64_t now_ns) {
    const AlState from = state_;
    if (from == to) return;
    if (to == AlState::Init || to == AlState::Boot) {
        set_sm_group(false, false);
        set_sm_group(true, false);
        reset_mailbox();
        // BOOT: the mailbox runs on the bootstrap mailbox configuration (checked by CheckBoot).
        if (to == AlState::Boot) set_sm_group(true, true);
    } else if (to == AlState::PreOp) {
        if (rank(from) > rank(AlState::PreOp)) set_sm_group(false, false);
        if (from == AlState::Init) set_sm_group(true, true);
    } else if (to == AlState::SafeOp && from == AlState::PreOp) {
        set_sm_group(false, true);
        outputs_at_safeop_ = sm_out_ >= 0 ? esc_.sm_buffer_writes(static_cast<unsigned>(sm_out_)) : 0;
    }
    if (from == AlState::Op) app_->outputs_safe_state();
    op_pending_ = false;
    state_ = to;
    app_->on_state_change(from, to);
    for (auto& p : own_protocols_)
        p->on_state_change(from, to);
    (void)now_ns;
}

void Slave::reset_mailbox() {
    if (coe_) coe_->reset();
    for (auto& p : own_protocols_)
        p->reset();
    q_head_ = q_count_ = 0;
    last_counter_ = 0;
    last_reply_len_ = 0;
    lost_reply_waiting_ = false;
}

void Slave::add_mailbox_protocol(std::unique_ptr<MailboxProtocol> p) {
    own_protocols_.push_back(std::move(p));
}

MailboxProtocol* Slave::mailbox_protocol(MailboxType t) {
    for (auto& p : own_protocols_)
        if (p->type() == t) return p.get();
    return app_->mailbox_protocol(t);
}

std::uint32_t Slave::sii_revision() const {
    const auto& ee = esc_.eeprom();
    return 2 * protocol::sii::RevisionNo + 3 < ee.size() ? ld_le32(&ee[2 * protocol::sii::RevisionNo]) : 0;
}

void Slave::apply_firmware_revision(std::uint32_t revision) {
    esc_.pdi_write_eeprom_word(protocol::sii::RevisionNo, static_cast<std::uint16_t>(revision));
    esc_.pdi_write_eeprom_word(protocol::sii::RevisionNo + 1, static_cast<std::uint16_t>(revision >> 16));
    app_->on_revision_change(revision);
}

void Slave::set_error(AlStatusCode code, AlState stay, std::uint64_t now_ns) {
    error_ = true;
    code_ = code;
    if (stay != state_) enter(stay, now_ns);
    app_->on_al_error(code);
}

void Slave::clear_error() {
    if (!error_) return;
    error_ = false;
    code_ = AlStatusCode::NoError;
    app_->on_al_error(AlStatusCode::NoError);
}

void Slave::raise_error(AlStatusCode code, AlState fallback) {
    if (esc_.device_emulation()) return;  // no firmware whose error AL status could show
    const AlState target = rank(fallback) < rank(state_) ? fallback : state_;
    set_error(code, target, 0);
    publish_status();
}

// INIT -> BOOT (ETG.1000.6 6.4, Table 9; AL status codes of ETG.1000.6 Table 11): a device without bootstrap
// answers 0x0013; SM0 and SM1 must be the bootstrap mailbox of the SII (words 0x0014-0x0017), else 0x0015.
AlStatusCode Slave::check_boot_mailbox_config() const {
    const auto boot = desc_.bootstrap_mailbox();
    if (!boot) return AlStatusCode::BootstrapNotSupported;
    if (sm_mbx_out_ < 0 || sm_mbx_in_ < 0) return AlStatusCode::InvalidMailboxConfigBoot;
    const auto c0 = esc_.sm_config(static_cast<unsigned>(sm_mbx_out_));
    const auto c1 = esc_.sm_config(static_cast<unsigned>(sm_mbx_in_));
    const bool ok0 = c0.ecat_enabled && c0.valid && c0.start == boot->out_start &&
                     c0.length == boot->out_length &&
                     (c0.control & 0x0F) == (sm::CtrlModeMailbox | sm::CtrlDirWrite);
    const bool ok1 = c1.ecat_enabled && c1.valid && c1.start == boot->in_start &&
                     c1.length == boot->in_length &&
                     (c1.control & 0x0F) == (sm::CtrlModeMailbox | sm::CtrlDirRead);
    return ok0 && ok1 ? AlStatusCode::NoError : AlStatusCode::InvalidMailboxConfigBoot;
}

AlStatusCode Slave::check_mailbox_config() const {
    const auto* out = desc_.sm_of_type(device::SmType::MailboxOut);
    const auto* in = desc_.sm_of_type(device::SmType::MailboxIn);
    if (!out || !in) return AlStatusCode::NoError;  // a device without mailbox
    if (sm_mbx_out_ < 0 || sm_mbx_in_ < 0) return AlStatusCode::InvalidMailboxConfigPreOp;  // past SM 15
    const auto c0 = esc_.sm_config(static_cast<unsigned>(sm_mbx_out_));
    const auto c1 = esc_.sm_config(static_cast<unsigned>(sm_mbx_in_));
    const bool ok0 = c0.ecat_enabled && c0.start == out->start && c0.length == out->length &&
                     (c0.control & 0x0F) == (sm::CtrlModeMailbox | sm::CtrlDirWrite);
    const bool ok1 = c1.ecat_enabled && c1.start == in->start && c1.length == in->length &&
                     (c1.control & 0x0F) == (sm::CtrlModeMailbox | sm::CtrlDirRead);
    return ok0 && ok1 ? AlStatusCode::NoError : AlStatusCode::InvalidMailboxConfigPreOp;
}

// The process data SyncManagers as the device declares them (ESI Sm, SII SyncM: ETG.2000, ETG.2010): mode
// and direction of its ControlByte (buffered, or 1-buffer mode 0x22/0x26), Enable="0" (the master may leave
// it off: the FMMU reads the memory), Virtual="1" (no hardware SyncManager: nothing to check).
AlStatusCode Slave::check_process_data_config() const {
    auto check = [&](int smi, device::SmType type, unsigned bytes, std::uint8_t dflt_ctrl) {
        const auto* decl = desc_.sm_of_type(type);
        if (smi < 0 || !decl) return bytes == 0;
        if (decl->enable & device::sm_enable::Virtual) return true;
        const auto c = esc_.sm_config(static_cast<unsigned>(smi));
        if (bytes == 0) return !c.ecat_enabled || c.length == 0;
        if (!(decl->enable & device::sm_enable::Enable) && !c.ecat_enabled) return true;
        const std::uint8_t declared = decl->control & (sm::CtrlModeMask | sm::CtrlDirMask);
        const std::uint8_t ctrl = decl->control ? declared : dflt_ctrl;
        return c.ecat_enabled && c.valid && c.length == bytes &&
               (c.control & (sm::CtrlModeMask | sm::CtrlDirMask)) == ctrl;
    };
    if (!check(sm_out_, device::SmType::Outputs, app_->output_bytes(),
               sm::CtrlModeBuffered | sm::CtrlDirWrite))
        return AlStatusCode::InvalidOutputConfig;
    if (!check(sm_in_, device::SmType::Inputs, app_->input_bytes(), sm::CtrlModeBuffered | sm::CtrlDirRead))
        return AlStatusCode::InvalidInputConfig;
    return AlStatusCode::NoError;
}

bool Slave::read_outputs(unsigned len) {
    if (len == 0 || sm_out_ < 0) return false;
    if (through_sm(sm_out_, out_may_bypass_))
        return esc_.pdi_buffer_read(static_cast<unsigned>(sm_out_), Bytes(outputs_.data(), len));
    esc_.pdi_read_memory(decl_out_->start, Bytes(outputs_.data(), len));
    return true;
}

void Slave::write_inputs(unsigned len) {
    if (len == 0 || sm_in_ < 0) return;
    if (through_sm(sm_in_, in_may_bypass_))
        esc_.pdi_buffer_write(static_cast<unsigned>(sm_in_), ConstBytes(inputs_.data(), len));
    else
        esc_.pdi_write_memory(decl_in_->start, ConstBytes(inputs_.data(), len));
}

void Slave::handle_al_control(std::uint64_t now_ns) {
    const std::uint16_t ctrl = esc_.pdi_read_al_control();
    if (esc_.device_emulation()) {
        // The ESC has set AL status to the value written, without any check (ESC datasheet section II
        // 0x0130); the device follows the state it shows.
        const std::uint8_t req = ctrl & kAlStateMask;
        // PREOP -> SAFEOP with the EEPROM offered to the PDI clears 0x0502 bit 4 as a firmware's access
        // does (an EL1004 with device emulation and digital I/O, ../shared/data/pcap; esc README).
        if (req == static_cast<std::uint8_t>(AlState::SafeOp) && state_ == AlState::PreOp)
            esc_.pdi_use_eeprom();
        if (is_valid_state(req)) enter(static_cast<AlState>(req), now_ns);
        return;
    }
    const std::uint8_t req = ctrl & kAlStateMask;
    const bool ack = ctrl & kAlErrorFlag;
    ident_ = (ctrl & kAlIdentFlag) != 0;
    if (error_ && !ack) {
        // With the error indication set only INIT is obeyed without acknowledge (ETG.1000.6 6.4.1.4).
        if (req == static_cast<std::uint8_t>(AlState::Init)) {
            clear_error();
            enter(AlState::Init, now_ns);
        }
        publish_status();
        return;
    }
    if (ack) clear_error();
    op_pending_ = false;
    const AlState fallback = state_ == AlState::Op ? AlState::SafeOp : state_;
    if (!is_valid_state(req)) {
        set_error(AlStatusCode::UnknownRequestedState, fallback, now_ns);
        publish_status();
        return;
    }
    const AlState to = static_cast<AlState>(req);
    AlStatusCode code = AlStatusCode::NoError;
    switch (al_transition(state_, to)) {
        case AlAction::Stay:
            break;
        case AlAction::Down:
            enter(to, now_ns);
            break;
        case AlAction::CheckMailbox:
            // The firmware reads the mailbox SyncManagers of its SII to check them (a device without
            // mailbox has none to read), if the master offered it the EEPROM (0x0500).
            if (desc_.sm_of_type(device::SmType::MailboxOut)) esc_.pdi_use_eeprom();
            code = check_mailbox_config();
            if (code == AlStatusCode::NoError) code = app_->check_transition(state_, to);
            if (code == AlStatusCode::NoError)
                enter(to, now_ns);
            else
                set_error(code, AlState::Init, now_ns);
            break;
        case AlAction::CheckBoot:
            esc_.pdi_use_eeprom();  // the bootstrap mailbox configuration of the SII
            code = check_boot_mailbox_config();
            if (code == AlStatusCode::NoError) code = app_->check_transition(state_, to);
            if (code == AlStatusCode::NoError)
                enter(to, now_ns);
            else
                set_error(code, AlState::Init, now_ns);
            break;
        case AlAction::CheckProcessData:
            // The application first checks its mapping (0x0024/0x0025), then the SMs are compared with it
            // and with the process data SyncManagers the firmware reads from its SII.
            esc_.pdi_use_eeprom();
            code = app_->check_transition(state_, to);
            if (code == AlStatusCode::NoError) code = check_process_data_config();
            if (code == AlStatusCode::NoError)
                enter(to, now_ns);
            else
                set_error(code, AlState::PreOp, now_ns);
            break;
        case AlAction::CheckOutputs:
            code = app_->check_transition(state_, to);
            if (code != AlStatusCode::NoError) {
                set_error(code, AlState::SafeOp, now_ns);
            } else {
                op_pending_ = true;  // stays SAFEOP until the outputs are valid and the application ready
                op_pending_since_ = now_ns;
                try_enter_op(now_ns);
            }
            break;
        case AlAction::Refuse:
            set_error(AlStatusCode::InvalidRequestedStateChange, fallback, now_ns);
            break;
    }
    publish_status();
}

bool Slave::outputs_valid() const {
    if (app_->output_bytes() == 0 || sm_out_ < 0 || !through_sm(sm_out_, out_may_bypass_)) return true;
    return esc_.sm_buffer_writes(static_cast<unsigned>(sm_out_)) > outputs_at_safeop_;
}

void Slave::service_mailbox() {
    if (sm_mbx_out_ < 0 || sm_mbx_in_ < 0) return;
    const auto out_idx = static_cast<unsigned>(sm_mbx_out_);
    const auto in_idx = static_cast<unsigned>(sm_mbx_in_);
    // Repeat request (ETG.1000.4 5.6.3): re-send the last reply, then toggle the acknowledge.
    if (esc_.pdi_take_sm_activation_event()) {
        const bool req = esc_.sm_repeat_request(in_idx);
        const bool ack =
            (esc_.peek(static_cast<std::uint16_t>(sm_addr(in_idx) + sm::PdiControl)) & sm::PdiRepeatAck) != 0;
        if (req != ack) {
            ++counters_.mailbox_repeats;
            if (last_reply_len_ && !esc_.sm_mailbox_full(in_idx))
                esc_.pdi_mailbox_put(in_idx, ConstBytes(last_reply_.data(), last_reply_len_));
            lost_reply_waiting_ = false;
            esc_.pdi_set_repeat_ack(in_idx, req);
        }
    }
    if (esc_.sm_mailbox_full(out_idx) && esc_.pdi_mailbox_take(out_idx, Bytes(rx_.data(), rx_.size()))) {
        ++counters_.mailbox_requests;
        // The ESC copies at most rx_.size() bytes: never look further. (Asked only now: a run without a
        // request need not read the SyncManager's registers.)
        const std::size_t rx_len = std::min<std::size_t>(esc_.sm_config(out_idx).length, rx_.size());
        const auto h = parse_mailbox_header(ConstBytes(rx_.data(), std::min(rx_len, rx_.size())));
        auto& sink = *sink_;
        auto error_reply = [&](MailboxError e) {
            ++counters_.mailbox_errors;
            const std::size_t n = make_mailbox_error(sink.reply_buffer(), e);
            sink.commit(MailboxType::Error, n);
        };
        if (!h || rx_len < kMailboxHeaderSize) {
            error_reply(MailboxError::Syntax);
        } else if (h->length > rx_len - kMailboxHeaderSize) {
            error_reply(MailboxError::InvalidSize);
        } else if (h->counter != 0 && h->counter == last_counter_) {
            ++counters_.mailbox_duplicates;  // the same request again: executed once only
        } else {
            if (h->counter != 0) last_counter_ = h->counter;
            MailboxProtocol* proto = mailbox_protocol(static_cast<MailboxType>(h->type));
            // In BOOT the bootloader serves FoE alone (ETG.1000.6 6.4): CoE and the rest are unsupported.
            if (proto && state_ == AlState::Boot && !proto->served_in_boot()) proto = nullptr;
            const ConstBytes payload(rx_.data() + kMailboxHeaderSize, h->length);
            if (interceptor_ && interceptor_->intercept(*this, *h, payload, proto, sink)) {
                // taken over by fault injection
            } else if (h->type == static_cast<std::uint8_t>(MailboxType::Error) || !proto) {
                error_reply(MailboxError::UnsupportedProtocol);
            } else {
                proto->handle(*h, payload, sink);
            }
        }
    }
    post_replies();
}

template <class F>
void Slave::for_each_sending_protocol(F&& f) const {
    // Outside BOOT: the application's CoE (emergencies, SDO information) and the slave's own protocols.
    if (state_ == AlState::Boot) return;
    if (coe_ && coe_->has_output()) f(*coe_);
    for (const auto& p : own_protocols_)
        if (p->has_output()) f(*p);
}

void Slave::post_replies() {
    if (sm_mbx_out_ < 0 || sm_mbx_in_ < 0) return;
    for_each_sending_protocol([&](MailboxProtocol& p) { p.poll(*sink_); });
    if (q_count_ > 0) send_pending_replies();
    // Quirk mailbox_open_early: the buffer the master emptied is opened for the next message at once.
    if (desc_.quirks.mailbox_open_early) esc_.pdi_mailbox_open(static_cast<unsigned>(sm_mbx_in_));
}

bool Slave::mailbox_output_pending() const {
    if (sm_mbx_out_ < 0 || sm_mbx_in_ < 0 || state_ == AlState::Init) return false;
    bool pending = q_count_ > 0;
    for_each_sending_protocol([&](MailboxProtocol&) { pending = true; });
    // (Asked last: mostly nothing is pending, and the SyncManager's state is one more cache line.)
    return pending && !esc_.sm_mailbox_full(static_cast<unsigned>(sm_mbx_in_));  // the master has not read
}

void Slave::send_pending_replies() {
    const auto in_idx = static_cast<unsigned>(sm_mbx_in_);
    const unsigned drop_every = desc_.quirks.mailbox_drop_every;
    // A lost reply (quirk) holds the queue until the master's repeat request has brought it back.
    while (q_count_ > 0 && !lost_reply_waiting_ && !esc_.sm_mailbox_full(in_idx)) {
        if (queue_due_[q_head_] > now_ns_) break;  // quirk mailbox_delay_ms: not yet
        const auto& slot = queue_[q_head_];
        const std::size_t len = queue_len_[q_head_];
        // Quirk mailbox_drop_every: every Kth reply never reaches SM1, as if the firmware lost it; it stays
        // the last reply, which the repeat request (ETG.1000.4 5.6.3) puts into SM1.
        const bool lost = drop_every != 0 && (replies_out_ + 1) % drop_every == 0;
        if (!lost && !esc_.pdi_mailbox_put(in_idx, ConstBytes(slot.data(), len))) break;
        ++replies_out_;
        if (lost) {
            ++counters_.mailbox_replies_lost;
            lost_reply_waiting_ = true;
        }
        std::memcpy(last_reply_.data(), slot.data(), len);
        last_reply_len_ = len;
        q_head_ = (q_head_ + 1) % kReplySlots;
        --q_count_;
    }
}

void Slave::exchange_process_data(std::uint64_t now_ns) {
    const unsigned out_len = std::min<unsigned>(app_->output_bytes(), static_cast<unsigned>(outputs_.size()));
    const unsigned in_len = std::min<unsigned>(app_->input_bytes(), static_cast<unsigned>(inputs_.size()));
    const bool have_out = read_outputs(out_len);
    app_->exchange(now_ns, have_out ? ConstBytes(outputs_.data(), out_len) : ConstBytes{},
                   state_ == AlState::Op && have_out, Bytes(inputs_.data(), in_len));
    write_inputs(in_len);
}

void Slave::run(std::uint64_t now_ns) {
    now_ns_ = now_ns;
    esc_.tick(now_ns);
    // SYNC pulses first: they happened at their own times, before anything this run does at now_ns (an AL
    // state change the master asked for, new outputs, the application's periods up to now_ns), however
    // late the run is.
    deliver_sync_pulses(now_ns);
    const std::uint32_t ev = esc_.al_events();
    if ((ev & al_event::AlControl) &&
        (al_control_latency_ns_ == 0 || now_ns >= esc_.al_control_written_ns() + al_control_latency_ns_))
        handle_al_control(now_ns);
    if (ev & al_event::WatchdogProcessData) {
        esc_.pdi_clear_al_event(al_event::WatchdogProcessData);
        ++counters_.watchdog_expiries;
        if (state_ == AlState::Op && !esc_.device_emulation()) {  // else the outputs only go to 0
            set_error(AlStatusCode::SyncManagerWatchdog, AlState::SafeOp, now_ns);
            publish_status();
        }
    }
    if (op_pending_) try_enter_op(now_ns);
    if (state_ != AlState::Init) service_mailbox();
    if (rank(state_) >= rank(AlState::SafeOp)) exchange_process_data(now_ns);
    app_->tick(now_ns);
    // What the application raised in its cycles just now (the emergency of a fault) goes into the
    // mailbox at once, as a firmware that polls its mailbox after its cycle: whenever this run happens
    // (a tick between frames, or the catch-up before one), the next frame finds it.
    if (state_ != AlState::Init) post_replies();
}

std::uint64_t Slave::next_event_ns(std::uint64_t poll_ns) const {
    std::uint64_t t = std::min(esc_.watchdog_deadline_ns(), app_->next_event_ns());
    t = std::min(t, esc_.dc().backlog_deadline_ns(kMaxPulsesPerRun / 2));
    if (op_pending_) t = std::min(t, poll_ns);
    if (esc_.al_events() & al_event::AlControl)
        t = std::min(t, esc_.al_control_written_ns() + al_control_latency_ns_);
    // A reply held back by the quirk mailbox_delay_ms goes into SM1 at its time, frames or not.
    if (q_count_ > 0 && !lost_reply_waiting_ && queue_due_[q_head_] > now_ns_)
        t = std::min(t, queue_due_[q_head_]);
    return t;
}

void Slave::try_enter_op(std::uint64_t now_ns) {
    const OpReadiness r = app_->op_readiness(now_ns, op_pending_since_);
    if (r.error != AlStatusCode::NoError) {
        op_pending_ = false;
        set_error(r.error, AlState::SafeOp, now_ns);
    } else if (r.ready && outputs_valid()) {
        enter(AlState::Op, now_ns);
    } else if (!outputs_valid() && now_ns - op_pending_since_ > kOutputsValidTimeoutNs) {
        op_pending_ = false;
        set_error(AlStatusCode::NoValidOutputs, AlState::SafeOp, now_ns);
    } else {
        return;  // still waiting (the application bounds its own wait)
    }
    publish_status();
}

void Slave::deliver_sync_pulses(std::uint64_t now_ns) {
    const unsigned n = esc_.pdi_take_sync_pulses(now_ns, pulses_.data(), kMaxPulsesPerRun);
    if (n == 0) return;
    esc_.pdi_clear_al_event(al_event::Sync0 | al_event::Sync1);
    for (unsigned i = 0; i < n; ++i)
        app_->sync_event(pulses_[i].signal, pulses_[i].host_ns);
    if (rank(state_) < rank(AlState::SafeOp) || sm_in_ < 0) return;
    const unsigned in_len = std::min<unsigned>(app_->input_bytes(), static_cast<unsigned>(inputs_.size()));
    if (in_len > 0 && app_->refresh_inputs(Bytes(inputs_.data(), in_len))) write_inputs(in_len);
}

}  // namespace vecat::esc
