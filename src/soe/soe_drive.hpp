// The SoE drive (an AX5000-like servo drive, device::soe_drive()): one axis, or two like an AX5206
// (device::soe_drive(2)), each a drive number of SoE with its own IDN table and its MDT/AT block in the
// process data (soe_axis.hpp: the telegrams, the procedure commands, the CiA 402 drive core under the SERCOS
// profile). This is the application of the slave: the process data of all axes, the notifications, the
// time. See src/soe/README.md.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "device/device_description.hpp"
#include "esc/segment.hpp"
#include "esc/slave.hpp"
#include "soe/idn_table.hpp"
#include "soe/soe_axis.hpp"
#include "soe/soe_server.hpp"

namespace vecat::soe {

// Drive numbers a device may have (ETG.1000.6 5.6.1: 3 bits in the SoE header).
inline constexpr unsigned kMaxDrives = 8;

class SoeDrive final : public esc::Application, public SoeDevice {
  public:
    // As many axes as the device's SoE channels (1 to kMaxDrives).
    explicit SoeDrive(const device::DeviceDescription& d);

    // esc::Application
    unsigned output_bytes() const override;
    unsigned input_bytes() const override;
    void on_state_change(protocol::AlState from, protocol::AlState to) override;
    void exchange(std::uint64_t now_ns, ConstBytes outputs, bool apply_outputs, Bytes inputs) override;
    void outputs_safe_state() override;
    void tick(std::uint64_t now_ns) override;
    std::uint64_t next_event_ns() const override;
    void attach(esc::Slave& slave) override;

    // SoeDevice
    unsigned drives() const override { return static_cast<unsigned>(axes_.size()); }
    IdnTable& table(unsigned drive) override { return axes_[drive]->table(); }
    protocol::AlState phase() const override { return state_; }
    void refresh(unsigned drive, IdnEntry& e) override { axes_[drive]->refresh(e); }
    std::optional<SoeError> write_value(unsigned drive, IdnEntry& e, ConstBytes value) override;
    bool take_notification(unsigned& drive, Idn& idn) override;
    bool has_notification() const override;

    SoeServer* server() { return server_; }
    SoeAxis& axis(unsigned drive = 0) { return *axes_[drive]; }
    std::uint16_t status_word(unsigned drive = 0) const { return axes_[drive]->status_word(); }
    std::uint16_t class1_diagnostic(unsigned drive = 0) const { return axes_[drive]->class1_diagnostic(); }
    // The IDNs of the MDT and AT after the control and status word, as configured now.
    const std::vector<IdnEntry*>& mdt(unsigned drive = 0) const { return axes_[drive]->mdt(); }
    const std::vector<IdnEntry*>& at(unsigned drive = 0) const { return axes_[drive]->at(); }

  private:
    bool sync_managers_fit() const;

    std::vector<std::unique_ptr<SoeAxis>> axes_;
    esc::Slave* slave_ = nullptr;
    SoeServer* server_ = nullptr;  // owned by the slave (esc::Slave::add_mailbox_protocol)
    protocol::AlState state_ = protocol::AlState::Init;
    unsigned next_note_ = 0;  // the axis whose finished command is notified next (round robin)
};

// The application of a slave of the SoE drive (network/build.cpp, `vecat run --device soe-drive`).
std::unique_ptr<esc::Application> make_soe_drive(const device::DeviceDescription& d);
// A segment of n slaves of the device, each an SoE drive.
std::unique_ptr<esc::Segment> make_soe_segment(const device::DeviceDescription& d, std::size_t n,
                                               const esc::EscConfig& cfg = {});

}  // namespace vecat::soe
