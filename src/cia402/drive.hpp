// The CiA 402 drive as a CoE slave: the application (coe::CoeApplication) that runs the drive core
// (drive_core.hpp, which knows no EtherCAT) on the drive's dictionary. The adapter binds the core's typed
// DriveIo to the dictionary once, through the named objects (protocol/cia402_objects.hpp,
// device/drive_objects.hpp), and every servo period (250 us of simulated time) copies the set-points in,
// steps the core, copies statusword and actual values back, and runs the TWINsync option card around the
// step. Time comes from the slave (frames, SYNC0 and timer ticks); the simulation advances in fixed periods,
// so it is deterministic for a given cycle time.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "cia402/drive_core.hpp"
#include "cia402/drive_io.hpp"
#include "cia402/twinsync_port.hpp"
#include "coe/coe_application.hpp"
#include "twinsync/status.hpp"

namespace vecat::cia402 {

class VariantObjects;  // drive_variant.hpp

// Mode, supported(), fault:: codes and sw:: bits: drive_io.hpp.

class Drive : public coe::CoeApplication, public twinsync::StatusSource {
    friend std::shared_ptr<twinsync::Channel> connect_twinsync(Drive&, Drive&, double, double);

  public:
    static constexpr std::uint64_t kServoPeriodNs = DriveCore::kPeriodNs;

    // objects: see CoeApplication.
    explicit Drive(const device::DeviceDescription& d,
                   std::shared_ptr<const std::vector<device::ObjectDescription>> objects = {});
    ~Drive() override;

    State cia402_state() const { return core_->state(); }
    Mode mode() const { return core_->mode(); }
    const Mechanics& mechanics() const { return core_->mechanics(); }
    // Demand and actual values in user units (as in 0x6062/0x6064, without the 32-bit wrap).
    double position_demand() const { return core_->position_demand(); }
    double position_actual() const { return core_->position_actual(); }
    double velocity_actual() const { return core_->velocity_actual(); }
    std::uint64_t servo_steps() const { return core_->steps(); }
    // Of those, the periods skipped because the drive had settled (for tests and benchmarks).
    std::uint64_t skipped_servo_steps() const { return core_->skipped_steps(); }
    // The servo period now: kServoPeriodNs, or the TWIN sampling time of P0302 (125 us at 8 kHz).
    std::uint64_t servo_period_ns() const { return period_ns_; }
    std::uint64_t simulated_time_ns() const { return sim_ns_; }
    // The next servo period: a frame that reads the drive at or after it finds it stepped up to then.
    std::uint64_t next_cycle_ns() const override { return started_ ? sim_ns_ + period_ns_ : 0; }
    // The TWINsync option card of this drive, and its status (nullptr when no cable is connected).
    twinsync::Port& twinsync_port() { return *twin_; }
    const twinsync::LinkStatus* twinsync_status() const override {
        return twin_->channel() ? &twin_->status() : nullptr;
    }
    // The TWINsync error the drive has raised as a fault (40-xx, 39-xx), if any.
    std::optional<twinsync::ErrorId> twinsync_error() const { return core_->twinsync_error(); }

    // The digital outputs 0x60FE:1 masked by 0x60FE:2 (CiA 402 6.3.9: an output is set only where its mask
    // bit is), 4 bytes little-endian as a wire of a network file shows them: bit N is channel N. Kept up to
    // date each servo period once publish_digital_outputs() was called (empty before).
    const std::vector<std::uint8_t>& digital_output_image() const { return digital_output_image_; }
    void publish_digital_outputs() { digital_output_image_.assign(4, 0); }

    // esc::Application
    void tick(std::uint64_t now_ns) override;
    // coe::CoeApplication: the drive simulates faults, through 0x2101 where that is the vecat drive's
    // object, directly on a device whose manufacturer objects are its own (the HIWIN D2).
    bool simulates_faults() override;
    void simulate_fault(std::uint16_t code) override;

    // The dictionary entries of the DriveIo, bound once (drive.cpp).
    struct Objects;

  protected:
    // Touch probe inputs 1 and 2 (bits 0 and 1) driven from outside the drive each servo period (a wire or
    // signal of a network file), besides 0x2100:6; nullopt: none.
    virtual std::optional<std::uint8_t> wired_probe_inputs(std::uint64_t /*sim_ns*/) { return std::nullopt; }

    void cycle(std::uint64_t now_ns, bool outputs_applied) override;
    void advance_to(std::uint64_t now_ns) override { advance(now_ns); }
    bool coupled() const override { return twin_partner_ != nullptr; }
    // Drives coupled by TWINsync step each other: both name the pair.
    void shared_state(std::vector<const void*>& keys) const override {
        if (twin_partner_) keys.push_back(std::min<const void*>(this, twin_partner_));
    }

  private:
    void advance(std::uint64_t now_ns);
    void step_to(std::uint64_t t_ns);
    // publish: the period's feedback values go to the dictionary (DriveCore::step).
    void servo_step(bool publish = true);
    bool same_probe_inputs();
    void write_digital_outputs();  // digital_output_image()
    template <class F>
    void for_each_parameter(F&& f);
    void read_parameters();
    void configure();
    template <class F>
    void for_each_command(F&& f);
    void read_command();
    void read_twinsync();
    // The period's events, and its values when `publish`.
    void write_feedback(bool publish = true);
    void write_twinsync_values();
    twinsync::LocalState twinsync_local() const;

    std::unique_ptr<VariantObjects> variant_;  // before o_: which manufacturer objects it binds
    std::unique_ptr<Objects> o_;
    std::unique_ptr<DriveCore> core_;
    DriveIo io_;
    std::uint32_t parameter_writes_ = 0;  // writes to the parameters' entries (EntryHooks::writes)
    std::uint64_t mapping_seen_ = ~std::uint64_t{0};     // the RxPDO mapping last checked for parameters
    bool maps_parameters_ = false;                       // ... maps one of them
    std::uint64_t outputs_seen_ = 0;                     // outputs changed when last counted
    std::uint32_t command_writes_ = 0;                   // ... to the command's (and process data outputs)
    std::uint32_t command_read_ = ~std::uint32_t{0};     // command_writes_ when it was last read
    std::uint32_t parameters_read_ = ~std::uint32_t{0};  // parameter_writes_ when they were last read
    std::uint64_t sim_ns_ = 0;
    std::uint64_t period_ns_ = kServoPeriodNs;  // servo_period_ns()
    // P0302 (TWINsync switching frequency) when period_ns_ was last worked out from it (configure()).
    static constexpr std::uint32_t kNoSwitchingFrequency = 0x10000;  // the device has no P0302
    std::uint32_t switching_seen_ = ~std::uint32_t{0};
    bool started_ = false;
    // The DriveIo's inputs are what the dictionary and the TWINsync port gave the last period
    // (Drive::advance)
    bool quiet_ = false;
    std::uint8_t probe_inputs_object_ = 0;            // 0x2100:6 as last read
    std::vector<std::uint8_t> digital_output_image_;  // see digital_output_image()
    // TWINsync: the option card, and the drive at the other end of its cable (they step in lockstep).
    std::unique_ptr<twinsync::Port> twin_;
    Drive* twin_partner_ = nullptr;
};

// Connects the TWINsync option cards of two drives by a cable (a: end 0, b: end 1). Their oscillators
// differ by the given ppm, which the slave's synchronisation controller has to follow.
std::shared_ptr<twinsync::Channel> connect_twinsync(Drive& a, Drive& b, double ppm_a = 20.0,
                                                    double ppm_b = -20.0);

// Ready-made TWINsync set-ups of the first two drives of a line (`vecat run --twinsync ...`).
enum class TwinsyncPreset { None, Gantry, Position, Speed };
// Writes the parameters of both drives (drive a master, drive b slave controlled through TWINsync).
void apply_twinsync_preset(Drive& master, Drive& slave, TwinsyncPreset p);

// A segment of n drives; drives 1 and 2 (if there are two) are connected by a TWINsync cable, with the
// preset applied.
std::unique_ptr<esc::Segment> make_drive_segment(const device::DeviceDescription& d, std::size_t n,
                                                 const esc::EscConfig& cfg, TwinsyncPreset preset);
std::unique_ptr<esc::Segment> make_drive_segment(const device::DeviceDescription& d, std::size_t n,
                                                 const esc::EscConfig& cfg = {});
// The same from a model built once (esc::DeviceModel::of).
std::unique_ptr<esc::Segment> make_drive_segment(const esc::DeviceModel& m, std::size_t n,
                                                 const esc::EscConfig& cfg = {},
                                                 TwinsyncPreset preset = TwinsyncPreset::None);

}  // namespace vecat::cia402
