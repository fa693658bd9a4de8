#include "coe/coe_application.hpp"

#include "coe/module_idents.hpp"
#include "protocol/cia402_objects.hpp"

namespace vecat::coe {

CoeApplication::CoeApplication(const device::DeviceDescription& d,
                               std::shared_ptr<const std::vector<device::ObjectDescription>> objects)
    : od_(objects ? ObjectDictionary(std::move(objects)) : ObjectDictionary(device::dictionary_objects(d))),
      identity_(d.identity) {
    map_ = std::make_unique<ProcessDataMap>(od_, d);
    sdo_ = std::make_unique<SdoServer>(od_, [this] { return state_; });
    // Quirks of a less complete device (device/quirks.hpp): what its SII and ESI say, the SDO server does.
    if (d.quirks.no_sdo_info) sdo_->set_information_served(false);
    if (d.quirks.no_complete_access) sdo_->set_complete_access_served(false);
    if (d.quirks.sdo_download_echo) sdo_->set_download_echo(true);
    sync_ = std::make_unique<SyncParameters>(od_, d);
    dc_ = sync_->dc_mode();
    pending_outputs_.reserve(1536);  // a whole frame's worth: no allocation in the cycle
    error_register_ = od_.find(protocol::obj::error_register);
    error_code_ = od_.find(protocol::obj::error_code);
    // An object mapped into the active RxPDOs is written by the master's outputs in SAFEOP and OP.
    od_.download_guard = [this](const Entry& e, AlState st) {
        if ((st == AlState::SafeOp || st == AlState::Op) && map_->is_rx_mapped(e))
            return SdoAbort::MappedToRxPdo;
        return SdoAbort::None;
    };
    install_parameter_objects(od_, nullptr);
}

RestoreReport CoeApplication::attach_parameter_store(std::string path) {
    store_ = std::make_unique<ParameterStore>(od_, identity_, std::move(path));
    install_parameter_objects(od_, store_.get());
    auto rep = store_->restore_at_start();
    if (rep.load.status == LoadStatus::Corrupt || rep.load.status == LoadStatus::OtherDevice)
        sdo_->emergency({emcy::DataSet, 0, {'P', 'R', 'M', static_cast<std::uint8_t>(rep.load.status), 0}});
    return rep;
}

CoeApplication::~CoeApplication() = default;

void CoeApplication::raise_fault(std::uint16_t code, std::uint8_t bits, std::array<std::uint8_t, 5> data) {
    std::uint8_t reg = 0;
    if (error_register_) {
        reg =
            static_cast<std::uint8_t>(error_register_->get<std::uint8_t>() | bits | error_register::Generic);
        error_register_->set(reg);
    }
    // 0x603F holds the drive's own fault code; communication errors only show in 0x1001.
    if (error_code_ && bits != error_register::Communication) error_code_->set(code);
    sdo_->emergency({code, reg, data});
}

void CoeApplication::clear_faults() {
    if (error_register_) error_register_->set(std::uint8_t{0});
    if (error_code_) error_code_->set(std::uint16_t{0});
    sdo_->emergency({emcy::ErrorReset, 0, {}});
}

protocol::AlStatusCode CoeApplication::check_transition(AlState from, AlState to) {
    requested_ = to;
    if (sync_watch_)
        ++*sync_watch_;  // (check_safeop chooses the mode, whether the transition is made or not)
    if (from == AlState::PreOp && to == AlState::SafeOp) {
        // The modules first (ETG.5001.1): a device configured for other modules has no valid mapping to
        // check.
        if (const auto modules = check_module_idents(od_); modules != protocol::AlStatusCode::NoError)
            return modules;
        if (const auto code = map_->validate(); code != protocol::AlStatusCode::NoError) return code;
        const auto code = sync_->check_safeop();
        dc_ = sync_->dc_mode();  // (it chooses the mode, whether the transition is made or not)
        return code;
    }
    if (from == AlState::SafeOp && to == AlState::Op) return sync_->check_op();
    return protocol::AlStatusCode::NoError;
}

void CoeApplication::on_state_change(AlState from, AlState to) {
    state_ = to;
    requested_ = to;
    inputs_latched_ = false;
    if (to != AlState::Op) outputs_received_ = false;
    outputs_pending_ = false;
    sync_->on_state_change(from, to);
    dc_ = sync_->dc_mode();
    if (sync_watch_) ++*sync_watch_;
}

void CoeApplication::attach(esc::Slave& slave) {
    sync_->attach(slave);
}

void CoeApplication::on_revision_change(std::uint32_t revision) {
    if (auto* e = od_.find(protocol::obj::identity::revision)) e->set(revision);
    identity_.revision = revision;
}

esc::OpReadiness CoeApplication::op_readiness(std::uint64_t now_ns, std::uint64_t since_ns) {
    return sync_->op_readiness(now_ns, since_ns);
}

void CoeApplication::tick(std::uint64_t now_ns) {
    if (dc_) sync_->tick(now_ns, state_);  // (outside DC mode it has nothing to watch)
    sdo_->tick(now_ns);
}

std::uint64_t CoeApplication::next_event_ns() const {
    return std::min(dc_ ? sync_->next_deadline_ns(state_) : ~std::uint64_t{0}, sdo_->next_deadline_ns());
}

void CoeApplication::sync_event(unsigned signal, std::uint64_t now_ns) {
    // The device's periods up to the event first: what the event does (new outputs, a sync error that
    // takes them away) starts at the event, however late the firmware takes it.
    advance_to(now_ns);
    if (!sync_->on_sync_event(signal, now_ns, state_)) return;
    if (outputs_pending_) {
        map_->copy_outputs(pending_outputs_);
        outputs_pending_ = false;
    }
    cycle(now_ns, state_ == AlState::Op && outputs_received_);
}

bool CoeApplication::refresh_inputs(Bytes inputs) {
    if (!dc_) return false;
    map_->copy_inputs(inputs);
    inputs_latched_ = true;
    return true;
}

void CoeApplication::on_al_error(protocol::AlStatusCode code) {
    if (code == protocol::AlStatusCode::NoError) {
        // Acknowledged: the communication error is gone.
        if (error_register_ && (error_register_->get<std::uint8_t>() & error_register::Communication))
            clear_faults();
        return;
    }
    std::uint16_t e = emcy::Communication;
    if (code == protocol::AlStatusCode::SyncManagerWatchdog)
        e = emcy::LifeGuard;
    else if (requested_ == AlState::SafeOp)
        e = emcy::PreOpToSafeOp;
    else if (requested_ == AlState::Op)
        e = emcy::SafeOpToOp;
    requested_ = state_;  // the checked transition is over; a later refusal must not reuse it
    const auto c = static_cast<std::uint16_t>(code);
    // Manufacturer bytes: the AL status code, little-endian.
    raise_fault(e, error_register::Communication,
                {static_cast<std::uint8_t>(c), static_cast<std::uint8_t>(c >> 8), 0, 0, 0});
}

void CoeApplication::exchange(std::uint64_t now_ns, ConstBytes outputs, bool apply, Bytes inputs) {
    const bool applied = apply && !outputs.empty();
    advance_to(now_ns);
    if (applied && dc_) {
        // DC synchronous: the outputs take effect at the next SYNC0 (SYNC1) event, whenever in the cycle
        // the frame came (ETG.1020 synchronisation: the application reads SM2 at the sync event). Taken at
        // once, a set-point would start its interpolation at a time that jitters with the frame's arrival.
        pending_outputs_.assign(outputs.begin(), outputs.end());
        outputs_pending_ = true;
    } else if (applied) {
        map_->copy_outputs(outputs);
    }
    outputs_received_ |= applied && state_ == AlState::Op;
    if (!dc_) cycle(now_ns, applied);
    // DC synchronous: the input buffer holds what the device latched at the last SYNC0 (SYNC1) event
    // (ETG.1020 synchronisation: inputs are latched at the sync event and written once per cycle), not
    // whatever its state is when the firmware happens to run; before the first event, its state.
    if (!dc_ || !inputs_latched_) map_->copy_inputs(inputs);
    ++exchanges_;
}

void CoeApplication::outputs_safe_state() {
    // Safe state of the outputs: every RxPDO-mapped object back to zero (controlword 0: disable voltage).
    static constexpr std::uint8_t kZeros[8] = {};
    for (const auto& f : map_->outputs())
        if (f.entry) f.entry->assign(ConstBytes(kZeros, std::min<std::size_t>(8, f.entry->capacity())));
}

esc::MailboxProtocol* CoeApplication::mailbox_protocol(protocol::MailboxType t) {
    return t == protocol::MailboxType::CoE ? sdo_.get() : nullptr;
}

std::unique_ptr<esc::Segment> make_coe_segment(const device::DeviceDescription& d, std::size_t n,
                                               const esc::EscConfig& cfg) {
    return make_coe_segment(esc::DeviceModel::of(d), n, cfg);
}

std::unique_ptr<esc::Segment> make_coe_segment(const esc::DeviceModel& m, std::size_t n,
                                               const esc::EscConfig& cfg) {
    // The factory also rebuilds a restarted slave, of the same model.
    return esc::make_segment(
        m, n, cfg,
        [objects = m.dictionary](const device::DeviceDescription& dd) -> std::unique_ptr<esc::Application> {
            return std::make_unique<CoeApplication>(dd, objects);
        });
}

namespace {
constexpr std::uint16_t kSimulatedFault = 0x2101;  // the vecat drive's fault injection object
}  // namespace

bool CoeApplication::simulates_faults() {
    const Entry* e = od_.find(kSimulatedFault, 0);
    return e && e->type() == protocol::DataType::Unsigned16;
}

void CoeApplication::simulate_fault(std::uint16_t code) {
    if (simulates_faults()) od_.find(kSimulatedFault, 0)->set(code);
}

}  // namespace vecat::coe
