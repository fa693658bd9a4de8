// One axis of the SoE drive (one drive number of ETG.1000.6 5.6): its IDN table (drive_idns.cpp), its
// telegrams (S-0-0015, S-0-0024, S-0-0016), its procedure commands (S-0-0099, S-0-0127, S-0-0128) with
// their execution time, and its motion: the CiA 402 drive core (cia402::DriveCore) under the SERCOS
// profile. The master control word S-0-0134 becomes the core's controlword, the operation mode
// S-0-0032..S-0-0035 its cyclic synchronous mode, the commands S-0-0047/S-0-0036/S-0-0080 its set-points;
// the core's state, feedback and faults become the drive status word S-0-0135, S-0-0051/S-0-0040/S-0-0084
// and the class 1 diagnostic S-0-0011. What each case does: src/soe/README.md.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "cia402/drive_core.hpp"
#include "soe/idn_table.hpp"

namespace vecat::soe {

// The IDNs the drive knows (IEC 61800-7-204 numbers; P-0-0100 and P-0-0101 are vecat's).
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
inline constexpr Idn SecondaryOperationMode1 = protocol::s_idn(33);
inline constexpr Idn SecondaryOperationMode2 = protocol::s_idn(34);
inline constexpr Idn SecondaryOperationMode3 = protocol::s_idn(35);
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
inline constexpr Idn CommandDuration = protocol::p_idn(101);
}  // namespace idn

// S-0-0015 (telegram type): the standard telegrams 0-6 fix the MDT and AT lists; 7 is the application
// telegram, configured through S-0-0024 and S-0-0016.
inline constexpr std::uint16_t kApplicationTelegram = 7;
inline constexpr std::uint16_t kDefaultTelegram = 4;  // MDT: S-0-0047; AT: S-0-0051

// Master control word S-0-0134 (IEC 61800-7-204): bit 15 drive on, bit 14 drive enable, bit 13 drive halt
// (0: halt, 1: run), bits 8-9 the operation mode selected (0: S-0-0032, 1-3: S-0-0033..S-0-0035).
namespace control {
inline constexpr std::uint16_t DriveOn = 0x8000;
inline constexpr std::uint16_t DriveEnable = 0x4000;
inline constexpr std::uint16_t Run = 0x2000;  // "drive halt" released
inline constexpr std::uint16_t ModeMask = 0x0300;
inline constexpr unsigned ModeShift = 8;
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

// S-0-0011 class 1 diagnostic bits the drive sets (IEC 61800-7-204, the SERCOS C1D), each for the drive
// core's fault (0x603F code) that shut the drive down.
namespace c1d {
inline constexpr std::uint16_t OverloadShutdown = 0x0001;    // bit 0: the I2t protection (0x2310)
inline constexpr std::uint16_t FeedbackError = 0x0020;       // bit 5: the encoder (0x7305)
inline constexpr std::uint16_t ExcessiveDeviation = 0x0800;  // bit 11: following error (0x8611)
inline constexpr std::uint16_t TravelLimit = 0x2000;         // bit 13: travel limit exceeded (0x8612)
inline constexpr std::uint16_t Manufacturer = 0x8000;        // bit 15: any other fault of the core
}  // namespace c1d

// Operation mode codes of S-0-0032..S-0-0035 (IEC 61800-7-204): bits 0-2 the mode, bit 3 "without lag"
// (the drive runs the same loops either way).
namespace op_mode {
inline constexpr std::uint16_t ModeMask = 0x0007;
inline constexpr std::uint16_t None = 0;
inline constexpr std::uint16_t Torque = 1;
inline constexpr std::uint16_t Velocity = 2;
inline constexpr std::uint16_t PositionFeedback1 = 3;
inline constexpr std::uint16_t PositionFeedback2 = 4;  // the drive has one encoder: as feedback 1
}  // namespace op_mode

// Scaling of the cyclic values (what a unit is): a position unit is one encoder increment, 2^20 per motor
// revolution (S-0-0047, S-0-0051, S-0-0159); a velocity unit 0.0001 rpm (S-0-0036, S-0-0040, S-0-0091:
// attribute 4 decimals); a torque unit 0.1 % of the rated torque (S-0-0080, S-0-0084: 1 decimal; the
// core's per mille).
inline constexpr double kIncrementsPerRevolution = 1u << 20;
inline constexpr double kVelocityUnitsPerRpm = 10000.0;

// Default execution time of a procedure command (P-0-0101, in µs; 0: at once).
inline constexpr std::uint32_t kDefaultCommandDurationUs = 2000;
inline constexpr std::uint32_t kMaxCommandDurationUs = 10'000'000;

// The IDN table of one axis, with its defaults (telegram 4).
std::vector<IdnEntry> drive_idns();

class SoeAxis {
  public:
    SoeAxis();
    SoeAxis(const SoeAxis&) = delete;
    SoeAxis& operator=(const SoeAxis&) = delete;

    IdnTable& table() { return table_; }
    const IdnTable& table() const { return table_; }
    // The IDNs of the MDT and AT after the control and status word, as configured now, and their bytes
    // (with the control and status word).
    const std::vector<IdnEntry*>& mdt() const { return mdt_; }
    const std::vector<IdnEntry*>& at() const { return at_; }
    unsigned mdt_bytes() const { return mdt_bytes_; }
    unsigned at_bytes() const { return at_bytes_; }

    // The phase (PREOP = CP2, SAFEOP = CP3, OP = CP4); below OP the control word is 0.
    void set_phase(protocol::AlState s);
    protocol::AlState phase() const { return phase_; }
    // The outputs go to their safe state: control word 0.
    void safe_state() { control_ = 0; }
    // This axis's MDT block (control word, then the S-0-0024 IDNs); at least mdt_bytes().
    void take_mdt(ConstBytes block);
    // This axis's AT block (status word, then the S-0-0016 IDNs); at least at_bytes().
    void put_at(Bytes block) const;
    // Runs the drive core's servo periods and the procedure commands up to now_ns (host time).
    void advance(std::uint64_t now_ns);
    // When a procedure command in progress finishes (host time), or nullopt.
    std::optional<std::uint64_t> next_event_ns() const;

    void refresh(IdnEntry& e);
    // The drive's checks and effect of a value write that passed IdnTable::check_write.
    std::optional<SoeError> write_value(IdnEntry& e, ConstBytes value);
    // Procedure commands that finished (their data state changed) since the last call, oldest first.
    bool take_finished(Idn& i);
    bool has_finished() const { return finished_count_ > 0; }
    // What the CP3 transition check (S-0-0127) asks when it executes: whether the slave's process data
    // SyncManagers fit the telegrams of every axis (set by the device; unset: they do).
    void set_sm_check(std::function<bool()> sm_ok) { sm_ok_ = std::move(sm_ok); }

    std::uint16_t status_word() const { return status_; }
    std::uint16_t control_word() const { return control_; }
    std::uint16_t class1_diagnostic() const { return c1d_; }
    const cia402::DriveCore& core() const { return *core_; }
    std::int64_t signed_value(Idn idn) const;

  private:
    struct Pending {
        IdnEntry* command = nullptr;
        std::uint64_t due_ns = 0;
    };

    void configure(std::uint16_t telegram);
    void rebuild_map();
    void read_parameters();
    void read_command();
    std::uint16_t core_controlword() const;
    void servo_period();
    void update_status();
    std::optional<SoeError> command(IdnEntry& e, std::uint16_t input);
    void finish(IdnEntry& e);
    bool execute(Idn idn);
    void set_value(Idn idn, std::int64_t v);

    IdnTable table_;
    std::vector<IdnEntry*> mdt_, at_;
    unsigned mdt_bytes_ = 0, at_bytes_ = 0;
    protocol::AlState phase_ = protocol::AlState::Init;
    std::uint16_t control_ = 0, status_ = 0, c1d_ = 0;
    bool command_change_ = false;
    std::function<bool()> sm_ok_;

    // The drive core and its inputs/outputs; stepped every servo period of host time.
    std::unique_ptr<cia402::DriveCore> core_;
    cia402::DriveIo io_;
    bool started_ = false;
    std::uint64_t sim_ns_ = 0;  // host time of the last servo period
    std::uint64_t now_ns_ = 0;  // the last host time seen (a command written now starts at it)
    bool fault_reset_ = false;  // S-0-0099 executed: the next period sends the fault reset edge

    // Procedure commands in progress (at most one per command IDN) and those that finished.
    static constexpr std::size_t kCommands = 3;
    std::array<Pending, kCommands> pending_{};
    std::array<Idn, kCommands> finished_{};
    std::size_t finished_count_ = 0;
};

}  // namespace vecat::soe
