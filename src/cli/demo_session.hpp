// The session of `vecat demo` (src/cli/demo.cpp runs it): its constants, the master's view of the cycle,
// and the class whose phases demo_phases.cpp holds. Internal to the program (namespace demo_detail).
#pragma once

#include <fmt/core.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <span>
#include <thread>
#include <vector>

#include "cia402/drive.hpp"
#include "cia402/profile_generator.hpp"
#include "cli/demo.hpp"
#include "cli/demo_process_data.hpp"
#include "cli/telemetry_commands.hpp"
#include "common/bytes.hpp"
#include "device/device_description.hpp"
#include "device/drive_objects.hpp"
#include "esc/segment.hpp"
#include "esc/sii_image.hpp"
#include "esi/esi_writer.hpp"
#include "faults/injector.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "net/netns.hpp"
#include "net/pcapng_writer.hpp"
#include "net/raw_socket.hpp"
#include "net/realtime.hpp"
#include "network/build.hpp"
#include "network/network_file.hpp"
#include "protocol/cia402.hpp"
#include "protocol/cia402_objects.hpp"
#include "protocol/coe.hpp"
#include "serve/server.hpp"

namespace vecat::cli::demo_detail {

using protocol::AlState;
namespace cia = protocol::cia402;
namespace obj = protocol::obj;
namespace mfr = device::mfr;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// The signal that interrupted the demo (0: none); set by its handler (demo.cpp).
extern std::atomic<int> g_signal;

constexpr double kRev = 1 << 20;               // increments per motor revolution (default factor group)
constexpr std::uint32_t kCycleNs = 1'000'000;  // process data cycle = SYNC0 cycle
// The master sends its frame this long after SYNC0, as the reference clock sees it: the drives take the
// outputs at the next SYNC0, 700 us later.
constexpr std::int64_t kSendPhaseNs = 300'000;
constexpr unsigned kDriftFrames = 3000;
// 0x10F1:02, see the dc phase: 0 turns the sync error counter's limit off.
constexpr std::uint16_t kSyncErrorLimit = 0;
// Homing of drive 1: method 19 finds the falling edge of a home switch that is active above kHomeSwitch
// (machine increments). The home offset is that same position, so drive 1 keeps the coordinates drive 2
// has: the gantry partner follows drive 1's absolute set-point and does not home itself.
constexpr std::int8_t kHomingMethod = 19;
constexpr std::int32_t kHomeSwitch = 1 << 18;

// The process data the master maps in the PDO mapping phase, and where each field lands in the image.
struct PdoEntry {
    std::uint16_t index;
    std::uint8_t bits;
    const char* name;
};
constexpr PdoEntry kRxPdo[] = {{obj::controlword.index, 16, "controlword"},
                               {obj::modes_of_operation.index, 8, "mode"},
                               {0x0000, 8, "gap"},
                               {obj::target_position.index, 32, "target position"}};
constexpr PdoEntry kTxPdo[] = {{obj::statusword.index, 16, "statusword"},
                               {obj::modes_of_operation_display.index, 8, "mode display"},
                               {0x0000, 8, "gap"},
                               {obj::position_actual_value.index, 32, "position"},
                               {obj::velocity_actual_value.index, 32, "velocity"},
                               {obj::following_error_actual_value.index, 32, "following error"},
                               {obj::error_code.index, 16, "error code"},
                               {0x0000, 16, "gap"}};
namespace rx {
constexpr std::size_t kControlword = 0, kMode = 2, kTarget = 4, kSize = 8;
}
namespace tx {
constexpr std::size_t kStatusword = 0, kMode = 2, kPosition = 4, kVelocity = 8, kFollowingError = 12,
                      kErrorCode = 16, kSize = 20;
}

// Controlword commands and bits, statusword bits (protocol/cia402.hpp).
constexpr std::uint16_t kShutdown = cia::cmd::Shutdown, kSwitchOn = cia::cmd::SwitchOn,
                        kEnable = cia::cmd::EnableOperation, kFaultReset = cia::cmd::FaultReset;
constexpr std::uint16_t kHomingStart = cia::cw::HomingStart;
constexpr auto kCsp = static_cast<std::int8_t>(cia::Mode::CyclicPosition);
constexpr auto kHoming = static_cast<std::int8_t>(cia::Mode::Homing);
constexpr std::uint16_t kSwFault = cia::sw::Fault, kSwTargetReached = cia::sw::TargetReached,
                        kSwHomingAttained = cia::sw::Bit12, kSwHomingError = cia::sw::Bit13;

using DriveState = cia::State;

// The demo's short names, in the order of the states.
inline const char* short_name(DriveState s) {
    static const char* const kNames[] = {"not ready", "disabled",  "ready",          "switched on",
                                         "enabled",   "quickstop", "fault reaction", "FAULT"};
    return kNames[static_cast<int>(s)];
}

// Where the mapping the demo writes to its own drives (kRxPdo, kTxPdo) puts each object.
inline DriveLayout fixed_layout(std::size_t slave) {
    DriveLayout l;
    l.slave = slave;
    l.controlword = rx::kControlword;
    l.mode = rx::kMode;
    l.target = rx::kTarget;
    l.statusword = tx::kStatusword;
    l.mode_display = tx::kMode;
    l.position = tx::kPosition;
    l.velocity = tx::kVelocity;
    l.following_error = tx::kFollowingError;
    l.error_code = tx::kErrorCode;
    return l;
}

// Cycle statistics of the master's loop.

struct CycleStats {
    std::uint64_t cycles = 0;
    std::uint64_t misses = 0;  // in OP: no reply or a wrong working counter
    std::uint64_t late = 0;    // the loop woke more than a cycle late and restarted its clock
    double rtt_sum_us = 0, rtt_max_us = 0;
    // Phase of the frame against SYNC0 (reference clock), minus kSendPhaseNs, once locked.
    std::uint64_t phase_samples = 0;
    double phase_sq_sum_us = 0, phase_max_us = 0;
    double rtt_mean_us() const { return cycles ? rtt_sum_us / static_cast<double>(cycles) : 0.0; }
    double phase_rms_us() const {
        return phase_samples ? std::sqrt(phase_sq_sum_us / static_cast<double>(phase_samples)) : 0.0;
    }
};

class Demo {
  public:
    // network: the network file's devices (--network); empty: a line of o.slaves vecat drives.
    Demo(const DemoOptions& o, network::BuiltNetwork network)
        : opt_(o),
          dev_(device::default_drive()),
          on_network_(network.segment != nullptr),
          gantry_(!on_network_ && o.slaves >= 2),
          io_bus_(std::move(network.io)),
          seg_(on_network_ ? std::move(network.segment)
                           : cia402::make_drive_segment(
                                 dev_, o.slaves, {},
                                 gantry_ ? cia402::TwinsyncPreset::Gantry : cia402::TwinsyncPreset::None)),
          slave_sock_("vecat-s"),
          master_sock_("vecat-m"),
          pcap_(o.outdir + "/demo.pcapng", "vecat-s"),
          injector_(*seg_),
          scope_(*seg_, serve_opt_),
          master_(master_sock_),
          tty_(isatty(STDOUT_FILENO) == 1) {
        serve_opt_.pcap = &pcap_;
        serve_opt_.filter = &injector_;
        // The master's cycle sleeps and the server's ticks end on time instead of up to 50 us late; the
        // server thread inherits the slack from this one.
        net::set_current_thread_timer_slack(net::RealtimeOptions::kTightTimerSlackNs);
        server_ = std::thread([this] { net::serve(*seg_, slave_sock_, serve_opt_, serve_stop_); });
    }
    ~Demo() { stop_server(); }

    int run();

  private:
    struct Phase {
        const char* name;
        const char* what;
        bool (Demo::*run)();
    };
    static const Phase kPhases[];
    // On a network file: the drives found are moved, the I/O terminals' outputs written and inputs read back.
    static const Phase kNetworkPhases[];
    std::span<const Phase> phases() const;

    bool scan();
    bool preop();
    bool map_pdos();
    bool process_data();  // on a network: the mapping the devices have, the drives among them
    bool io();
    bool dc();
    bool safeop();
    bool op();
    bool enable();
    bool csp_move();
    bool homing();
    bool fault();
    bool disable();
    bool init();

    bool cycle();
    // Cycles until done() holds (true) or max_cycles pass / a signal arrives (false).
    template <class Done>
    bool cycle_until(Done done, unsigned max_cycles);
    bool enable_drives();
    bool move_to(std::int32_t target, double limit_rev_s);
    bool sdo(std::size_t slave, std::uint16_t index, std::uint8_t sub, std::uint32_t value, unsigned bytes);
    bool fail(std::string why) {
        why_ = std::move(why);
        return false;
    }
    std::string left_enabled() const {
        return fmt::format("drive 1 left OPERATION ENABLED: statusword 0x{:04X} ({}), error code 0x{:04X}",
                           axes_[0].statusword, short_name(axes_[0].state()), axes_[0].error_code);
    }
    bool interrupted() const { return g_signal.load() != 0; }
    void set_al(AlState s) { al_ = s; }
    // The gantry slave (drive 2) takes its control and set-points from drive 1 over TWINsync.
    bool follows_twinsync(std::size_t i) const { return gantry_ && i == 1; }

    template <class... Args>
    void note(fmt::format_string<Args...> f, Args&&... args);
    void status_line(bool force);
    void shut_down();
    void stop_server();
    void write_files();
    void summary(double seconds, std::size_t phases_done);

    DemoOptions opt_;
    device::DeviceDescription dev_;
    bool on_network_;
    bool gantry_;
    std::shared_ptr<io::IoBus> io_bus_;  // a network's I/O terminals (wires) live as long as its segment
    std::unique_ptr<esc::Segment> seg_;
    net::RawSocket slave_sock_;
    net::RawSocket master_sock_;
    net::PcapngWriter pcap_;
    faults::FaultInjector injector_;
    net::ServeOptions serve_opt_;
    DemoScope scope_;
    std::atomic<bool> serve_stop_{false};
    std::thread server_;
    master::Master master_;
    bool tty_;

    std::vector<Axis> axes_;
    IoExercise io_;
    bool io_running_ = false;  // the io phase writes the terminals' outputs each cycle
    unsigned io_step_ = 0;
    AlState al_ = AlState::Init;
    const char* phase_ = "";
    std::string why_;
    bool dc_running_ = false;
    bool tracking_ = false;  // measure the gantry difference
    Clock::time_point next_{};
    std::int64_t correction_ns_ = 0;
    Clock::time_point last_status_{};
    bool status_shown_ = false;
    CycleStats stats_;
    // Figures for the summary.
    double worst_gantry_ = 0;
    std::uint32_t dc_difference_ns_ = 0;
};

template <class... Args>
void Demo::note(fmt::format_string<Args...> f, Args&&... args) {
    if (tty_ && status_shown_) fmt::print("\r\033[2K");
    status_shown_ = false;
    fmt::print(f, std::forward<Args>(args)...);
    fmt::print("\n");
    std::fflush(stdout);
}

template <class Done>
bool Demo::cycle_until(Done done, unsigned max_cycles) {
    for (unsigned c = 0; c < max_cycles && !interrupted(); ++c) {
        cycle();
        if (done()) return true;
    }
    return false;
}

}  // namespace vecat::cli::demo_detail
