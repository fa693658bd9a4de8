// The segment factories of the drive and the TWINsync set-ups of its first two drives: connecting two
// drives' option cards by a cable, the ready-made presets of `vecat run --twinsync`, and the segment of n
// drives that `vecat run`, the tests and vecat::testing serve.
#include <algorithm>
#include <array>

#include "cia402/drive.hpp"

namespace vecat::cia402 {

using coe::Entry;

std::shared_ptr<twinsync::Channel> connect_twinsync(Drive& a, Drive& b, double ppm_a, double ppm_b) {
    auto ch = std::make_shared<twinsync::Channel>();
    ch->set_oscillator_ppm(0, ppm_a);
    ch->set_oscillator_ppm(1, ppm_b);
    a.twinsync_port().connect(ch, 0);
    b.twinsync_port().connect(ch, 1);
    a.twin_partner_ = &b;
    b.twin_partner_ = &a;
    return ch;
}

namespace {

void set_parameter(Drive& d, std::uint16_t parameter, std::uint8_t sub, std::int64_t value) {
    if (Entry* e = d.dictionary().find(twinsync::object_index(parameter), sub)) {
        std::array<std::uint8_t, 8> v{};
        st_le64(v.data(), static_cast<std::uint64_t>(value));
        e->assign(ConstBytes(v.data(), std::min<std::size_t>(e->capacity(), 8)));
    }
}

}  // namespace

void apply_twinsync_preset(Drive& master, Drive& slave, TwinsyncPreset preset) {
    using namespace twinsync;
    if (preset == TwinsyncPreset::None) return;
    const Setting ms = preset == TwinsyncPreset::Gantry     ? Setting::PconGantryMaster
                       : preset == TwinsyncPreset::Position ? Setting::PconMaster
                                                            : Setting::SconMaster;
    const Setting ss = preset == TwinsyncPreset::Gantry     ? Setting::PconGantrySlave
                       : preset == TwinsyncPreset::Position ? Setting::PconSlave
                                                            : Setting::SconSlave;
    set_parameter(master, p::Mode, 0, static_cast<std::int64_t>(Role::Master));
    set_parameter(master, p::Setting, 0, static_cast<std::int64_t>(ms));
    set_parameter(slave, p::Mode, 0, static_cast<std::int64_t>(Role::Slave));
    set_parameter(slave, p::Setting, 0, static_cast<std::int64_t>(ss));
    set_parameter(slave, p::ControlSelector, 0, kControlByTwinsync);
    set_parameter(slave, p::SetpointSelector, 0, kSetpointByTwinsync);
    set_parameter(slave, p::SetpointMode, 0, kSetpointModeIp);  // tables 6.7, 6.8, 6.14: IP-Mode (1)
    set_parameter(slave, p::SyncSel, 0, static_cast<std::int64_t>(SyncSelection::SlaveByTwin));
    master.twinsync_port().reconfigure();
    slave.twinsync_port().reconfigure();
}

std::unique_ptr<esc::Segment> make_drive_segment(const device::DeviceDescription& d, std::size_t n,
                                                 const esc::EscConfig& cfg, TwinsyncPreset preset) {
    return make_drive_segment(esc::DeviceModel::of(d), n, cfg, preset);
}

std::unique_ptr<esc::Segment> make_drive_segment(const esc::DeviceModel& m, std::size_t n,
                                                 const esc::EscConfig& cfg, TwinsyncPreset preset) {
    // The factory also rebuilds a restarted slave, of the same model.
    auto seg = esc::make_segment(
        m, n, cfg,
        [objects = m.dictionary](const device::DeviceDescription& dd) -> std::unique_ptr<esc::Application> {
            return std::make_unique<Drive>(dd, objects);
        });
    if (n >= 2) {
        auto* a = dynamic_cast<Drive*>(&seg->slave(0).app());
        auto* b = dynamic_cast<Drive*>(&seg->slave(1).app());
        if (a && b) {
            connect_twinsync(*a, *b);
            apply_twinsync_preset(*a, *b, preset);
        }
    }
    return seg;
}

std::unique_ptr<esc::Segment> make_drive_segment(const device::DeviceDescription& d, std::size_t n,
                                                 const esc::EscConfig& cfg) {
    return make_drive_segment(d, n, cfg, TwinsyncPreset::None);
}

}  // namespace vecat::cia402
