#include "soe/soe_drive.hpp"

#include <algorithm>

namespace vecat::soe {

using protocol::AlState;

SoeDrive::SoeDrive(const device::DeviceDescription& d) {
    const unsigned n = std::clamp<unsigned>(d.soe_channels, 1, kMaxDrives);
    for (unsigned i = 0; i < n; ++i) {
        axes_.push_back(std::make_unique<SoeAxis>());
        axes_.back()->set_sm_check([this] { return sync_managers_fit(); });
    }
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

// The MDT (SM2) is drive 0's block (control word, its S-0-0024 IDNs), then drive 1's...; the AT (SM3) the
// same with the status word and S-0-0016 (IEC 61800-7-204; SOEM's ecx_readIDNmap sums drives 0-7 so).
unsigned SoeDrive::output_bytes() const {
    unsigned n = 0;
    for (const auto& a : axes_)
        n += a->mdt_bytes();
    return n;
}

unsigned SoeDrive::input_bytes() const {
    unsigned n = 0;
    for (const auto& a : axes_)
        n += a->at_bytes();
    return n;
}

bool SoeDrive::sync_managers_fit() const {
    // CP3 needs the process data SyncManagers as long as the telegrams configured.
    if (!slave_) return true;
    const auto& d = slave_->description();
    const auto out = d.sm_index_of_type(device::SmType::Outputs);
    const auto in = d.sm_index_of_type(device::SmType::Inputs);
    return out && in && slave_->esc().sm_config(*out).length == output_bytes() &&
           slave_->esc().sm_config(*in).length == input_bytes();
}

void SoeDrive::on_state_change(AlState, AlState to) {
    state_ = to;
    for (auto& a : axes_)
        a->set_phase(to);
}

void SoeDrive::outputs_safe_state() {
    for (auto& a : axes_)
        a->safe_state();
}

void SoeDrive::tick(std::uint64_t now_ns) {
    for (auto& a : axes_)
        a->advance(now_ns);
}

std::uint64_t SoeDrive::next_event_ns() const {
    std::uint64_t t = esc::DistributedClock::kNever;
    for (const auto& a : axes_)
        if (const auto due = a->next_event_ns()) t = std::min(t, *due);
    return t;
}

void SoeDrive::exchange(std::uint64_t now_ns, ConstBytes outputs, bool apply_outputs, Bytes inputs) {
    if (apply_outputs && outputs.size() >= output_bytes()) {
        std::size_t off = 0;
        for (auto& a : axes_) {
            a->take_mdt(outputs.subspan(off, a->mdt_bytes()));
            off += a->mdt_bytes();
        }
    }
    for (auto& a : axes_)
        a->advance(now_ns);
    if (inputs.size() < input_bytes()) return;
    std::size_t off = 0;
    for (const auto& a : axes_) {
        a->put_at(inputs.subspan(off, a->at_bytes()));
        off += a->at_bytes();
    }
}

std::optional<SoeError> SoeDrive::write_value(unsigned drive, IdnEntry& e, ConstBytes value) {
    return axes_[drive]->write_value(e, value);
}

bool SoeDrive::has_notification() const {
    return std::any_of(axes_.begin(), axes_.end(), [](const auto& a) { return a->has_finished(); });
}

// One notification per call, the axes in turn (each axis keeps its finished commands, bounded).
bool SoeDrive::take_notification(unsigned& drive, Idn& i) {
    for (unsigned k = 0; k < axes_.size(); ++k) {
        const unsigned d = (next_note_ + k) % static_cast<unsigned>(axes_.size());
        if (axes_[d]->take_finished(i)) {
            drive = d;
            next_note_ = (d + 1) % static_cast<unsigned>(axes_.size());
            return true;
        }
    }
    return false;
}

}  // namespace vecat::soe
