// The SoE drive (an AX5000-like servo drive, device::soe_drive()): its IDNs (drive_idns.cpp), the cyclic
// telegrams they configure (S-0-0015 telegram type, S-0-0024 MDT and S-0-0016 AT configuration lists, as
// SOEM's ecx_readIDNmap reads them), the procedure commands (S-0-0099, S-0-0127, S-0-0128) with their
// notifications, and the drive itself: a follower in position mode under the SERCOS master control word
// (S-0-0134) and drive status word (S-0-0135). Not the CiA 402 drive core: see src/soe/README.md.
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
#include "soe/soe_server.hpp"

namespace vecat::soe {

// The IDNs the drive knows (IEC 61800-7-204 numbers; P-0-0100 is vecat's).
namespace idn {
inline constexpr Idn NcCycleTime = protocol::s_idn(1);
inline constexpr Idn CommunicationCycleTime = protocol::s_idn(2);
inline constexpr Idn Class1Diagnostic = protocol::s_idn(11);
inline constexpr Idn TelegramType = protocol::s_idn(15);
inline constexpr Idn AtConfiguration = protocol::s_idn(16);
inline constexpr Idn AllOperationData = protocol::s_idn(17);
inline constexpr Idn MdtConfiguration = protocol::s_idn(24);
inline constexpr Idn ManufacturerVersion = protocol::s_idn(30);
inline constexpr Idn PrimaryOperationMode = protocol::s_idn(32);
inline constexpr Idn VelocityCommand = protocol::s_idn(36);
inline constexpr Idn VelocityFeedback = protocol::s_idn(40);
inline constexpr Idn PositionCommand = protocol::s_idn(47);
inline constexpr Idn PositionFeedback = protocol::s_idn(51);
inline constexpr Idn TorqueCommand = protocol::s_idn(80);
inline constexpr Idn TorqueFeedback = protocol::s_idn(84);
inline constexpr Idn VelocityLimit = protocol::s_idn(91);
inline constexpr Idn DiagnosticMessage = protocol::s_idn(95);
inline constexpr Idn ResetClass1Diagnostic = protocol::s_idn(99);
inline constexpr Idn Cp3TransitionCheck = protocol::s_idn(127);
inline constexpr Idn Cp4TransitionCheck = protocol::s_idn(128);
inline constexpr Idn ControlWord = protocol::s_idn(134);
inline constexpr Idn StatusWord = protocol::s_idn(135);
inline constexpr Idn ControllerType = protocol::s_idn(140);
inline constexpr Idn MonitoringWindow = protocol::s_idn(159);
inline constexpr Idn AtConfigurable = protocol::s_idn(187);
inline constexpr Idn MdtConfigurable = protocol::s_idn(188);
inline constexpr Idn DataContainer = protocol::p_idn(100);
}  // namespace idn

// S-0-0015 (telegram type): the standard telegrams 0-6 fix the MDT and AT lists; 7 is the application
// telegram, configured through S-0-0024 and S-0-0016.
inline constexpr std::uint16_t kApplicationTelegram = 7;
inline constexpr std::uint16_t kDefaultTelegram = 4;  // MDT: S-0-0047; AT: S-0-0051

// Master control word S-0-0134 (IEC 61800-7-204): bit 15 drive on, bit 14 drive enable, bit 13 drive halt
// (0: halt, 1: run), bits 8-9 the operation mode selected.
namespace control {
inline constexpr std::uint16_t DriveOn = 0x8000;
inline constexpr std::uint16_t DriveEnable = 0x4000;
inline constexpr std::uint16_t Run = 0x2000;  // "drive halt" released
inline constexpr std::uint16_t ModeMask = 0x0300;
}  // namespace control

// Drive status word S-0-0135: bits 14-15 readiness (0: not ready, fault; 1: logic ready; 2: control and
// power ready, drive on; 3: in operation, torque on), bit 13 drive shut down by an error of the class 1
// diagnostic, bits 8-9 the operation mode in effect, bit 5 a procedure command's acknowledgment changed.
namespace status {
inline constexpr std::uint16_t ReadyShift = 14;
inline constexpr std::uint16_t NotReady = 0;
inline constexpr std::uint16_t LogicReady = 1;
inline constexpr std::uint16_t PowerReady = 2;
inline constexpr std::uint16_t InOperation = 3;
inline constexpr std::uint16_t Class1Error = 0x2000;
inline constexpr std::uint16_t ModeMask = 0x0300;
inline constexpr std::uint16_t CommandChange = 0x0020;
}  // namespace status

// S-0-0011 class 1 diagnostic bits the drive sets.
namespace c1d {
inline constexpr std::uint16_t ExcessiveDeviation = 0x0800;  // bit 11: the command left the monitoring window
}  // namespace c1d

// The IDN table of the drive, with its defaults (telegram 4).
std::vector<IdnEntry> drive_idns();

class SoeDrive final : public esc::Application, public SoeDevice {
  public:
    explicit SoeDrive(const device::DeviceDescription& d);

    // esc::Application
    unsigned output_bytes() const override { return mdt_bytes_; }
    unsigned input_bytes() const override { return at_bytes_; }
    void on_state_change(protocol::AlState from, protocol::AlState to) override;
    void exchange(std::uint64_t now_ns, ConstBytes outputs, bool apply_outputs, Bytes inputs) override;
    void outputs_safe_state() override;
    void attach(esc::Slave& slave) override;

    // SoeDevice
    unsigned drives() const override { return 1; }
    IdnTable& table(unsigned) override { return table_; }
    protocol::AlState phase() const override { return state_; }
    void refresh(unsigned drive, IdnEntry& e) override;
    std::optional<SoeError> write_value(unsigned drive, IdnEntry& e, ConstBytes value) override;
    bool take_notification(unsigned& drive, Idn& idn) override;
    bool has_notification() const override { return notes_count_ > 0; }

    SoeServer* server() { return server_; }
    std::uint16_t status_word() const { return status_; }
    std::uint16_t class1_diagnostic() const { return c1d_; }
    // The IDNs of the MDT and AT after the control and status word, as configured now.
    const std::vector<IdnEntry*>& mdt() const { return mdt_; }
    const std::vector<IdnEntry*>& at() const { return at_; }

  private:
    void configure(std::uint16_t telegram);
    void rebuild_map();
    void step(bool apply);
    std::optional<SoeError> command(IdnEntry& e, std::uint16_t input);
    bool execute(Idn idn);
    void notify(Idn idn);
    std::int64_t signed_value(Idn idn) const;
    void set_value(Idn idn, std::int64_t v);

    IdnTable table_;
    esc::Slave* slave_ = nullptr;
    SoeServer* server_ = nullptr;  // owned by the slave (esc::Slave::add_mailbox_protocol)
    protocol::AlState state_ = protocol::AlState::Init;
    std::vector<IdnEntry*> mdt_, at_;
    unsigned mdt_bytes_ = 0, at_bytes_ = 0;
    std::uint16_t control_ = 0, status_ = 0, c1d_ = 0;
    bool enabled_ = false;
    bool command_change_ = false;
    // Notifications waiting (a procedure command finished), oldest first.
    static constexpr std::size_t kMaxNotes = 4;
    std::array<Idn, kMaxNotes> notes_{};
    std::size_t notes_count_ = 0;
};

// The application of a slave of the SoE drive (network/build.cpp, `vecat run --device soe-drive`).
std::unique_ptr<esc::Application> make_soe_drive(const device::DeviceDescription& d);
// A segment of n slaves of the device, each an SoE drive.
std::unique_ptr<esc::Segment> make_soe_segment(const device::DeviceDescription& d, std::size_t n,
                                               const esc::EscConfig& cfg = {});

}  // namespace vecat::soe
