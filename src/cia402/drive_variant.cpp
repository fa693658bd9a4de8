// The variants of the drive behind a dictionary: the vecat drive (the defaults of VariantObjects) and the
// HIWIN D2 (HIWIN Drive User Guide with EtherCAT (CoE) Interface; device/hiwin_d2.hpp has its objects).
#include "cia402/drive_variant.hpp"

#include <cmath>
#include <limits>

#include "device/hiwin_d2.hpp"

namespace vecat::cia402 {

namespace {

namespace hiwin = device::hiwin;
template <class T>
using V = coe::Value<T>;

constexpr std::int32_t kRev = 1 << 20;  // encoder increments per motor revolution (0x2001)

// The HIWIN D2: its manufacturer objects (3.6, 3.7), its homing methods (9.4), 0x60C2 in 62.5 us (9.1.2),
// touch probe 1 on the Z phase (10).
// The machine the emulated D2 drives (it has no objects for it): limit switches at -/+20 revolutions, a
// home switch dog from 3 to 4 revolutions, the index pulse a quarter revolution into each revolution.
constexpr std::int32_t kNegativeLimit = -20 * kRev, kPositiveLimit = 20 * kRev;
constexpr std::int32_t kHomeSwitch = 3 * kRev, kDogLength = kRev, kIndexOffset = kRev / 4;

class HiwinD2 final : public VariantObjects {
  public:
    explicit HiwinD2(coe::ObjectDictionary& od) : od_(od) {}

    bool vecat_objects() const override { return false; }
    std::vector<coe::Entry*> parameter_entries() override {
        return {software_limits_.entry(), hardware_limits_.entry()};
    }
    std::vector<coe::Entry*> command_entries() override { return {input_function_.entry()}; }

    void install(std::function<void()> zero_position) override {
        // 9.4: "Drive supports 8 kinds of CiA402 homing methods" and 0: another value is out of range.
        if (auto* e = od_.find(hiwin::homing_method.index, 0))
            e->hooks().on_download = [](const coe::Entry&, ConstBytes v) {
                const std::uint16_t m = v.size() >= 2 ? ld_le16(v.data()) : 0;
                return hiwin::homing_method_supported(m) ? protocol::SdoAbort::None
                                                         : protocol::SdoAbort::ValueRange;
            };
        // 3.7 0x2060: "0->1: set the multi turn encoder position to zero, 0->2: clear the multi turn encoder
        // error" (the emulated encoder has none to clear).
        if (multi_turn_reset_.bound()) {
            multi_turn_reset_.entry()->hooks().on_download = [this](const coe::Entry& e, ConstBytes) {
                multi_turn_before_ = e.get<std::uint8_t>();
                return protocol::SdoAbort::None;
            };
            multi_turn_reset_.entry()->hooks().after_download = [this, zero_position](coe::Entry& e) {
                if (multi_turn_before_ == 0 && e.get<std::uint8_t>() == 1) zero_position();
            };
        }
    }

    void read_parameters(DriveParameters& p) const override {
        // 0x2041 = 0: the software position limits 0x607D are not enforced; 0x2042 = 0: nor the limit
        // switches (the axis runs past them).
        if (software_limits_.get_or(1) == 0) {
            p.software_limit_min = std::numeric_limits<std::int32_t>::min();
            p.software_limit_max = std::numeric_limits<std::int32_t>::max();
        }
        const bool hardware = hardware_limits_.get_or(1) != 0;
        p.negative_limit_switch = hardware ? kNegativeLimit : std::numeric_limits<std::int32_t>::min();
        p.positive_limit_switch = hardware ? kPositiveLimit : std::numeric_limits<std::int32_t>::max();
    }

    void read_command(DriveCommand& c) const override {
        c.input_function = input_function_.get_or(0);
        // 3.7 0x2010 bit 1 "Reset the drive": a fault reset (controlword bit 7) while it is set.
        if (c.input_function & hiwin::input::ResetDrive) c.controlword |= protocol::cia402::cw::FaultReset;
    }

    void write_feedback(const DriveIo& io) override {
        const DriveFeedback& f = io.feedback;
        if (f.raised) {
            switch (f.raised->code) {
                case fault::Encoder:
                    events1_ |= hiwin::events1::Encoder;
                    break;
                case fault::FollowingError:
                    events1_ |= hiwin::events1::PositionErrorTooBig;
                    break;
                case fault::OverCurrent:
                    events1_ |= hiwin::events1::SoftThermal;
                    break;
                default:
                    break;
            }
        }
        if (f.cleared) events1_ = 0;
        error_events_1_.set(events1_);
        index_signal_.set(f.index_touched ? 1 : 0);
        latched_index_.set(f.index_position);
        // 0x2022 in A: 0x6078 is in 0.1 % of the continuous current 0x6075 (mA).
        motor_current_.set(static_cast<float>(f.current_actual * 1e-3 * io.parameters.rated_current * 1e-3));
    }

    // 9.1.2 II (2): in DC mode "the drive will automatically set up the content of interpolation time
    // period (0x60C2:1) in accordance with the synchronization signal cycle" (500 us: 8).
    bool synchronised(std::uint32_t sync0_cycle_ns) override {
        const bool changed = sync0_cycle_ns != synchronised_to_;
        synchronised_to_ = sync0_cycle_ns;
        if (!changed || sync0_cycle_ns == 0) return false;
        interpolation_.set(
            static_cast<std::uint16_t>(std::min<std::uint32_t>(sync0_cycle_ns / 62'500, 0xFFFF)));
        return true;
    }

  private:
    coe::ObjectDictionary& od_;
    V<std::uint16_t> input_function_ = coe::bind(od_, hiwin::input_function);
    V<std::int8_t> index_signal_ = coe::bind(od_, hiwin::index_signal);
    V<std::int32_t> latched_index_ = coe::bind(od_, hiwin::latched_index_position);
    V<float> motor_current_ = coe::bind(od_, hiwin::motor_actual_current);
    V<std::uint16_t> software_limits_ = coe::bind(od_, hiwin::software_limit_protection);
    V<std::uint16_t> hardware_limits_ = coe::bind(od_, hiwin::hardware_limit_protection);
    V<std::uint8_t> multi_turn_reset_ = coe::bind(od_, hiwin::multi_turn_reset);
    V<std::uint32_t> error_events_1_ = coe::bind(od_, hiwin::error_events_1);
    V<std::uint16_t> interpolation_ = coe::bind(od_, hiwin::interpolation_period);
    std::uint8_t multi_turn_before_ = 0;
    std::uint32_t events1_ = 0;
    std::uint32_t synchronised_to_ = 0;
};

class Vecat final : public VariantObjects {};

}  // namespace

DriveStrategy drive_strategy(device::DriveVariant v) {
    DriveStrategy s;
    if (v == device::DriveVariant::HiwinD2) {
        s.homing = HomingConvention::Hiwin;
        s.interpolation = InterpolationFormat::Ticks62_5us;
        s.probe_on_index = true;
        s.home_switch_length = kDogLength;
    }
    return s;
}

void simulated_machine(device::DriveVariant v, DriveParameters& p) {
    if (v != device::DriveVariant::HiwinD2) return;
    p.negative_limit_switch = kNegativeLimit;
    p.positive_limit_switch = kPositiveLimit;
    p.home_switch = kHomeSwitch;
    p.index_pulse_offset = kIndexOffset;
}

std::unique_ptr<VariantObjects> VariantObjects::make(device::DriveVariant v, coe::ObjectDictionary& od) {
    if (v == device::DriveVariant::HiwinD2) return std::make_unique<HiwinD2>(od);
    return std::make_unique<Vecat>();
}

}  // namespace vecat::cia402
