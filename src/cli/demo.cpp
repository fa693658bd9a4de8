// vecat demo (about 880 lines): the table of phases, their steps on the project's master, the status line
// and the files written at the end. One program; splitting the phases from the status line is left to do.
#include "cli/demo.hpp"

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
#include "network/build.hpp"
#include "network/network_file.hpp"
#include "net/pcapng_writer.hpp"
#include "net/raw_socket.hpp"
#include "net/realtime.hpp"
#include "protocol/cia402.hpp"
#include "protocol/cia402_objects.hpp"
#include "protocol/coe.hpp"
#include "serve/server.hpp"

namespace vecat::cli {
namespace {

using protocol::AlState;
namespace cia = protocol::cia402;
namespace obj = protocol::obj;
namespace mfr = device::mfr;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

std::atomic<int> g_signal{0};
void on_signal(int s) {
    g_signal.store(s);
}

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
const char* short_name(DriveState s) {
    static const char* const kNames[] = {"not ready", "disabled",  "ready",          "switched on",
                                         "enabled",   "quickstop", "fault reaction", "FAULT"};
    return kNames[static_cast<int>(s)];
}

// Where the mapping the demo writes to its own drives (kRxPdo, kTxPdo) puts each object.
DriveLayout fixed_layout(std::size_t slave) {
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
                           : cia402::make_drive_segment(dev_, o.slaves, {},
                                                        gantry_ ? cia402::TwinsyncPreset::Gantry
                                                                : cia402::TwinsyncPreset::None)),
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

const Demo::Phase Demo::kPhases[] = {
    {"scan", "count the slaves, give them station addresses, read their SII", &Demo::scan},
    {"preop", "mailboxes, INIT -> PREOP, drive 1's homing set-up by SDO", &Demo::preop},
    {"pdo-mapping", "the master writes 0x1600/0x1A00 and 0x1C12/0x1C13 by SDO", &Demo::map_pdos},
    {"dc", "distributed clocks: delays, offsets, drift compensation, SYNC0 at 1 ms", &Demo::dc},
    {"safeop", "PREOP -> SAFEOP, cyclic frames phase-locked to SYNC0", &Demo::safeop},
    {"op", "SAFEOP -> OP", &Demo::op},
    {"enable", "CiA 402: controlword 6, 7, 15 in CSP", &Demo::enable},
    {"csp-move", "jerk-limited CSP move, one revolution out and back", &Demo::csp_move},
    {"homing", "drive 1 in homing mode (6), method 19 on the home switch", &Demo::homing},
    {"fault", "injected following error on drive 1, then fault reset and a move", &Demo::fault},
    {"disable", "controlword 6, then 0", &Demo::disable},
    {"init", "SYNC0 off, back to INIT", &Demo::init},
};

const Demo::Phase Demo::kNetworkPhases[] = {
    {"scan", "count the slaves, give them station addresses, read their SII, work out the topology",
     &Demo::scan},
    {"preop", "mailboxes, INIT -> PREOP", &Demo::preop},
    {"process-data", "the mapping each device has; the CiA 402 drives among them", &Demo::process_data},
    {"dc", "distributed clocks: delays, offsets, drift compensation, SYNC0 at 1 ms on the drives", &Demo::dc},
    {"safeop", "PREOP -> SAFEOP, cyclic frames phase-locked to SYNC0", &Demo::safeop},
    {"op", "SAFEOP -> OP", &Demo::op},
    {"enable", "CiA 402: controlword 6, 7, 15 in CSP", &Demo::enable},
    {"csp-move", "jerk-limited CSP move of every drive, one revolution out and back", &Demo::csp_move},
    {"io", "a walking bit on the output terminals, the inputs read back", &Demo::io},
    {"disable", "controlword 6, then 0", &Demo::disable},
    {"init", "SYNC0 off, back to INIT", &Demo::init},
};

std::span<const Demo::Phase> Demo::phases() const {
    return on_network_ ? std::span<const Phase>(kNetworkPhases) : std::span<const Phase>(kPhases);
}

template <class... Args>
void Demo::note(fmt::format_string<Args...> f, Args&&... args) {
    if (tty_ && status_shown_) fmt::print("\r\033[2K");
    status_shown_ = false;
    fmt::print(f, std::forward<Args>(args)...);
    fmt::print("\n");
    std::fflush(stdout);
}

void Demo::status_line(bool force) {
    const auto now = Clock::now();
    // In place on a terminal ten times a second; a plain line every second into a pipe or file.
    if (!force && now - last_status_ < (tty_ ? milliseconds(100) : milliseconds(1000))) return;
    last_status_ = now;
    std::string s = fmt::format("  [{}] {}", phase_, protocol::to_string(al_));
    for (std::size_t i = 0; i < axes_.size() && i < 2; ++i)
        s += fmt::format(" | d{} {} {}", i + 1, short_name(axes_[i].state()), axes_[i].position);
    if (axes_.size() > 2) s += fmt::format(" | +{} drives", axes_.size() - 2);
    if (!io_.empty()) s += fmt::format(" | io {} input changes", io_.input_changes());
    s += fmt::format(" | {} cycles, {} misses | rtt {:.0f}/{:.0f} us", stats_.cycles, stats_.misses,
                     stats_.rtt_mean_us(), stats_.rtt_max_us);
    if (stats_.phase_samples)
        s += fmt::format(" | SYNC0 phase err {:.0f}/{:.0f} us", stats_.phase_rms_us(), stats_.phase_max_us);
    if (tty_)
        fmt::print("\r\033[2K{}", s);
    else
        fmt::print("{}\n", s);
    status_shown_ = tty_;
    std::fflush(stdout);
}

// ---- The cyclic exchange

bool Demo::cycle() {
    // Wait for this cycle's slot; with DC the slot moves to keep the frame at kSendPhaseNs after SYNC0.
    next_ += std::chrono::nanoseconds(kCycleNs + correction_ns_);
    correction_ns_ = 0;
    const auto now = Clock::now();
    if (next_ + std::chrono::nanoseconds(kCycleNs) < now) {
        // More than a cycle late (a loaded machine): skip the lost slots, keeping the phase to SYNC0.
        while (next_ < now)
            next_ += std::chrono::nanoseconds(kCycleNs);
        ++stats_.late;
    }
    std::this_thread::sleep_until(next_);

    for (const auto& a : axes_)
        a.write_outputs(master_.outputs(a.layout.slave));
    if (io_running_) io_.write_outputs(master_, io_step_++);
    const auto t0 = Clock::now();
    const auto wkc = master_.exchange_process_data();
    const double rtt = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    ++stats_.cycles;
    stats_.rtt_sum_us += rtt;
    stats_.rtt_max_us = std::max(stats_.rtt_max_us, rtt);
    const bool ok = wkc && *wkc == master_.expected_wkc();
    if (!ok && al_ == AlState::Op) ++stats_.misses;
    if (wkc) {
        for (auto& a : axes_)
            a.read_inputs(master_.inputs(a.layout.slave));
        io_.read_inputs(master_);
    }
    if (dc_running_ && wkc) {
        // Phase-locked loop on the reference clock's time, read by the FRMW in this frame.
        const auto phase = static_cast<std::int64_t>(master_.reference_time() % kCycleNs);
        std::int64_t err = phase - kSendPhaseNs;
        if (err > kCycleNs / 2) err -= kCycleNs;
        if (err < -static_cast<std::int64_t>(kCycleNs / 2)) err += kCycleNs;
        correction_ns_ = std::clamp<std::int64_t>(-err / 4, -100'000, 100'000);
        const double e = std::abs(static_cast<double>(err)) / 1000.0;
        if (e < 100.0 || stats_.phase_samples) {  // count from the first lock on
            ++stats_.phase_samples;
            stats_.phase_sq_sum_us += e * e;
            stats_.phase_max_us = std::max(stats_.phase_max_us, e);
        }
    }
    if (tracking_ && gantry_)
        worst_gantry_ = std::max(worst_gantry_, std::abs(static_cast<double>(axes_[0].position) -
                                                         static_cast<double>(axes_[1].position)));
    status_line(false);
    return ok;
}

template <class Done>
bool Demo::cycle_until(Done done, unsigned max_cycles) {
    for (unsigned c = 0; c < max_cycles && !interrupted(); ++c) {
        cycle();
        if (done()) return true;
    }
    return false;
}

bool Demo::sdo(std::size_t slave, std::uint16_t index, std::uint8_t sub, std::uint32_t value,
               unsigned bytes) {
    master::CoeClient c(master_, master_.slaves()[slave].station);
    std::uint8_t b[4];
    st_le32(b, value);
    const auto r = c.download(index, sub, ConstBytes(b, bytes));
    if (r.ok()) return true;
    return fail(fmt::format("slave {}: SDO download 0x{:04X}:{:02X} = 0x{:X}: {}", slave, index, sub, value,
                            r.transport_ok ? std::string(protocol::describe(r.abort)) : "no reply"));
}

// ---- Phases

bool Demo::scan() {
    const int n = master_.count_slaves();
    if (n <= 0) return fail("no slave answered the BRD");
    if (!master_.reset_slaves() || !master_.assign_station_addresses() || !master_.read_slave_information())
        return fail("station addresses or SII could not be read");
    for (const auto& s : master_.slaves()) {
        note(
            "       slave {} @0x{:04X} \"{}\": vendor 0x{:08X} product 0x{:08X} revision 0x{:08X}, {} FMMUs, "
            "{} SMs, DC {}",
            s.position, s.station, s.sii.device_name(), s.sii.identity.vendor_id, s.sii.identity.product_code,
            s.sii.identity.revision, s.fmmu_count, s.sm_count,
            (s.features & protocol::feature::DcAvailable) ? "yes" : "no");
        // A tree: the parent each slave hangs on (from the DL status of every slave, as SOEM computes it).
        if (on_network_)
            note("         {}", s.parent < 0 ? std::string("on the master")
                                             : fmt::format("on slave {} port {}", s.parent, s.parent_port));
    }
    if (!on_network_) {
        axes_.clear();
        for (std::size_t i = 0; i < master_.slaves().size(); ++i)
            axes_.push_back(Axis{fixed_layout(i)});
    }
    return true;
}

bool Demo::preop() {
    if (!master_.configure_mailboxes()) return fail("mailbox SyncManagers could not be written");
    if (!master_.request_state(AlState::PreOp)) return fail("the slaves refused PREOP");
    set_al(AlState::PreOp);
    if (on_network_) return true;
    // Drive 1's machine has its home switch at kHomeSwitch; the homing phase searches it.
    if (!sdo(0, mfr::machine::home_switch.index, mfr::machine::home_switch.subindex,
             static_cast<std::uint32_t>(kHomeSwitch), 4) ||
        !sdo(0, obj::homing_method.index, 0, static_cast<std::uint8_t>(kHomingMethod), 1) ||
        !sdo(0, obj::homing_speeds::index, obj::homing_speeds::search_for_switch.subindex,
             static_cast<std::uint32_t>(kRev / 2), 4) ||  // search the switch at 0.5 rev/s
        !sdo(0, obj::homing_speeds::index, obj::homing_speeds::search_for_zero.subindex,
             static_cast<std::uint32_t>(kRev / 16), 4) ||  // the edge at 1/16 rev/s
        !sdo(0, obj::homing_acceleration.index, 0, static_cast<std::uint32_t>(4 * kRev), 4) ||
        !sdo(0, obj::home_offset.index, 0, static_cast<std::uint32_t>(kHomeSwitch), 4))
        return false;
    note(
        "       drive 1: home switch 0x{:04X}:{:02X} = {}, method 0x{:04X} = {}, speeds 0x{:04X} = {} / {}, "
        "home offset 0x{:04X} = {}",
        mfr::machine::home_switch.index, mfr::machine::home_switch.subindex, kHomeSwitch,
        obj::homing_method.index, kHomingMethod, obj::homing_speeds::index, kRev / 2, kRev / 16,
        obj::home_offset.index, kHomeSwitch);
    return true;
}

bool Demo::map_pdos() {
    auto map = [&](std::size_t s, std::uint16_t assign, std::uint16_t pdo,
                   std::span<const PdoEntry> entries) {
        if (!sdo(s, assign, 0, 0, 1) || !sdo(s, pdo, 0, 0, 1)) return false;
        std::uint8_t sub = 0;
        for (const auto& e : entries)
            if (!sdo(s, pdo, ++sub, static_cast<std::uint32_t>(e.index) << 16 | e.bits, 4)) return false;
        return sdo(s, pdo, 0, sub, 1) && sdo(s, assign, 1, pdo, 2) && sdo(s, assign, 0, 1, 1);
    };
    for (std::size_t s = 0; s < master_.slaves().size(); ++s)
        if (!map(s, 0x1C12, 0x1600, kRxPdo) || !map(s, 0x1C13, 0x1A00, kTxPdo)) return false;
    auto describe = [](std::span<const PdoEntry> entries) {
        std::string d;
        for (const auto& e : entries)
            d += e.index ? fmt::format("{}0x{:04X} {}", d.empty() ? "" : ", ", e.index, e.name)
                         : fmt::format("{}{}-bit gap", d.empty() ? "" : ", ", e.bits);
        return d;
    };
    note("       RxPDO 0x1600: {}", describe(kRxPdo));
    note("       TxPDO 0x1A00: {}", describe(kTxPdo));
    // The master reads the sizes back from 0x1C12/0x1C13 and sets SM2/SM3 and the FMMUs.
    if (!master_.configure_process_data()) return fail("SM2/SM3 and FMMUs could not be configured");
    for (const auto& s : master_.slaves())
        if (s.out_bytes != rx::kSize || s.in_bytes != tx::kSize)
            return fail(fmt::format("slave {} reads back {} / {} bytes instead of {} / {}", s.position,
                                    s.out_bytes, s.in_bytes, rx::kSize, tx::kSize));
    note("       process image: {} bytes in {} LRW frame(s), expected working counter {}",
         master_.process_image_size(), master_.process_data_frames(), master_.expected_wkc());
    return true;
}

bool Demo::process_data() {
    // The master reads each CoE device's PDO assignment and mapping (0x1C12/0x1C13, 0x16xx/0x1Axx) and the
    // others' from their SII, and sets SM2/SM3 and the FMMUs.
    if (!master_.configure_process_data()) return fail("SM2/SM3 and FMMUs could not be configured");
    std::vector<std::string> lines;
    axes_ = find_drives(master_, lines);
    io_ = IoExercise(master_, axes_);
    for (const auto& l : lines)
        note("       {}", l);
    note("       {} drive(s) to move, {} I/O device(s) with process data", axes_.size(), io_.size());
    note("       process image: {} bytes in {} LRW frame(s), expected working counter {}",
         master_.process_image_size(), master_.process_data_frames(), master_.expected_wkc());
    return true;
}

bool Demo::io() {
    if (io_.empty()) {
        note("       no I/O device with process data");
        return true;
    }
    io_running_ = true;
    const std::uint64_t before = io_.input_changes();
    cycle_until([] { return false; }, std::max(opt_.cycles / 3, 800u));
    io_running_ = false;
    if (interrupted()) return fail("interrupted");
    for (const auto& l : io_.report(master_))
        note("       {}", l);
    note("       inputs changed {} times in the phase", io_.input_changes() - before);
    return true;
}

bool Demo::dc() {
    // Sync mode DC SYNC0. The sync error limit 0x10F1:02 goes from 4 to kSyncErrorLimit (no limit): this
    // master runs on an ordinary (not real-time) host, where a wake-up a millisecond late now and then, or a
    // stall of several milliseconds under load (a limit of 100 was exceeded in CI), would otherwise stop the
    // line with 0x002C. The init phase reports what was missed (0x1C32:0B).
    // On a network only the drives get SYNC0; a device that refuses these objects keeps its own settings.
    for (const auto& a : axes_) {
        const std::size_t s = a.layout.slave;
        if (!sdo(s, 0x1C32, 1, 2, 2) || !sdo(s, 0x10F1, 2, kSyncErrorLimit, 2)) {
            if (!on_network_) return false;
            note("       slave {}: {}; its sync mode stays as it is", s, why_);
        }
    }
    if (!master_.configure_dc() || master_.dc_reference() == 0)
        return fail("propagation delays / system time offsets could not be set");
    for (const auto& s : master_.slaves())
        note("       slave {}: propagation delay {} ns{}", s.position, s.dc_delay_ns,
             s.station == master_.dc_reference() ? " (reference clock)" : "");
    for (unsigned sent = 0; sent < kDriftFrames; sent += 500) {
        if (interrupted()) return fail("interrupted");
        if (!master_.compensate_static_drift(500)) return fail("drift compensation frames got no reply");
    }
    const auto deadline = Clock::now() + milliseconds(5000);
    std::optional<std::uint32_t> diff;
    while (!interrupted()) {
        master_.distribute_reference_clock();
        diff = master_.max_system_time_difference();
        if (diff && *diff <= 10'000) break;
        if (Clock::now() > deadline) return fail("the system time difference stays above 10 us");
    }
    if (!diff) return fail("interrupted");
    dc_difference_ns_ = *diff;
    for (const auto& a : axes_) {
        const auto& s = master_.slaves()[a.layout.slave];
        if ((s.features & protocol::feature::DcAvailable) && !master_.start_sync(s.station, kCycleNs, 0))
            return fail(fmt::format("slave {}: SYNC0 could not be started", s.position));
    }
    note(
        "       {} FRMW frames; largest system time difference 0x092C: {} ns; SYNC0 every {} us from 100 ms "
        "on",
        kDriftFrames, *diff, kCycleNs / 1000);
    dc_running_ = true;
    return true;
}

bool Demo::safeop() {
    if (!master_.request_state(AlState::SafeOp)) {
        const auto& st = master_.last_states();
        std::string codes;
        for (std::size_t i = 0; i < st.size(); ++i)
            codes += fmt::format(" slave {}: 0x{:02X} code 0x{:04X}", i, st[i].status, st[i].code);
        return fail("the slaves refused SAFEOP:" + codes);
    }
    set_al(AlState::SafeOp);
    // Lock the loop on SYNC0 before OP: 200 cycles.
    next_ = Clock::now();
    cycle_until([] { return false; }, 200);
    note("       master loop locked: frames at {} us after SYNC0, phase error rms {:.1f} us, max {:.1f} us",
         kSendPhaseNs / 1000, stats_.phase_rms_us(), stats_.phase_max_us);
    return !interrupted() || fail("interrupted");
}

bool Demo::op() {
    for (auto& a : axes_) {
        a.target = a.position;
        a.mode = kCsp;
    }
    cycle();
    if (!master_.request_state(AlState::Op)) return fail("the slaves refused OP");
    set_al(AlState::Op);
    stats_ = {};  // statistics of the cyclic phases in OP
    return true;
}

bool Demo::enable_drives() {
    for (auto& a : axes_) {
        a.target = a.position;
        a.mode = kCsp;
    }
    auto all = [&](DriveState s) {
        return [this, s] {
            return std::all_of(axes_.begin(), axes_.end(), [s](const Axis& a) { return a.state() == s; });
        };
    };
    const std::pair<std::uint16_t, DriveState> steps[] = {{kShutdown, DriveState::ReadyToSwitchOn},
                                                          {kSwitchOn, DriveState::SwitchedOn},
                                                          {kEnable, DriveState::OperationEnabled}};
    for (const auto& [cw, state] : steps) {
        for (std::size_t i = 0; i < axes_.size(); ++i)
            axes_[i].controlword = cw;
        if (!cycle_until(all(state), 500))
            return fail(
                fmt::format("drives did not reach \"{}\" (controlword 0x{:02X})", short_name(state), cw));
    }
    for (auto& a : axes_)
        a.target = a.position;
    return true;
}

bool Demo::enable() {
    if (axes_.empty()) {
        note("       no drive to enable");
        return true;
    }
    if (!enable_drives()) return false;
    note("       all drives enabled{}", gantry_ ? " (drive 2 by drive 1's controlword over TWINsync)" : "");
    return true;
}

// A jerk-limited move of drive 1 to target; drives 3.. (not coupled) make the same move from where they are.
bool Demo::move_to(std::int32_t target, double limit_rev_s) {
    const cia402::ProfileLimits limits{limit_rev_s * kRev, 10 * kRev, 10 * kRev, 100 * kRev};
    const double from = axes_[0].position;
    cia402::ProfileGenerator gen;
    gen.reset({from, 0, 0});
    gen.move_to(target, limits);
    std::vector<std::int32_t> start(axes_.size());
    for (std::size_t i = 0; i < axes_.size(); ++i)
        start[i] = axes_[i].position;
    for (unsigned c = 0; c < 20000 && !gen.done() && !interrupted(); ++c) {
        const double p = gen.step(1e-3).p;
        for (std::size_t i = 0; i < axes_.size(); ++i)
            if (!follows_twinsync(i))
                axes_[i].target = start[i] + static_cast<std::int32_t>(std::lround(p - from));
        cycle();
        if (axes_[0].state() != DriveState::OperationEnabled) return fail(left_enabled());
    }
    // Settle: drive 1 within 1/1000 revolution of the target.
    cycle_until([&] { return std::abs(axes_[0].position - target) < kRev / 1000; }, 500);
    return !interrupted() || fail("interrupted");
}

bool Demo::csp_move() {
    if (axes_.empty()) {
        note("       no drive to move");
        return true;
    }
    constexpr double kOut = kRev;
    const cia402::ProfileLimits limits{kRev, 10 * kRev, 10 * kRev, 100 * kRev};
    std::vector<cia402::ProfileGenerator> gen(axes_.size());
    std::vector<double> start(axes_.size());
    for (std::size_t i = 0; i < axes_.size(); ++i) {
        start[i] = axes_[i].position;
        gen[i].reset({start[i], 0, 0});
        gen[i].move_to(start[i] + (i % 2 ? -kOut : kOut), limits);
    }
    double worst_ferr = 0;
    tracking_ = true;
    const auto t0 = Clock::now();
    unsigned c = 0;
    for (; !interrupted(); ++c) {
        if (c == opt_.cycles / 2)
            for (std::size_t i = 0; i < axes_.size(); ++i)
                gen[i].move_to(start[i], limits);
        bool done = c >= opt_.cycles / 2;
        for (std::size_t i = 0; i < axes_.size(); ++i) {
            // Drive 2 of the gantry takes its set-points over TWINsync; the master commands the others.
            if (follows_twinsync(i)) continue;
            axes_[i].target = static_cast<std::int32_t>(std::lround(gen[i].step(1e-3).p));
            done = done && gen[i].done();
        }
        cycle();
        worst_ferr = std::max(worst_ferr, std::abs(static_cast<double>(axes_[0].following_error)));
        if (axes_[0].state() != DriveState::OperationEnabled) return fail(left_enabled());
        if (done && c >= opt_.cycles) break;
        if (c > opt_.cycles + 20000) return fail("the move did not end");
    }
    tracking_ = false;
    if (interrupted()) return fail("interrupted");
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    note(
        "       {} cycles in {:.0f} ms; drive 1 back at {} (started at {:.0f}); largest following error "
        "{:.0f} "
        "increments",
        c + 1, ms, axes_[0].position, start[0], worst_ferr);
    if (gantry_)
        note(
            "       gantry: largest difference drive 1 - drive 2 read over EtherCAT: {:.0f} increments "
            "({:.3f} % of "
            "a revolution)",
            worst_gantry_, worst_gantry_ / kRev * 100.0);
    return true;
}

bool Demo::homing() {
    auto& d1 = axes_[0];
    const std::int32_t before = d1.position;
    d1.target = d1.position;
    d1.mode = kHoming;
    d1.controlword = kEnable;
    if (!cycle_until([&] { return d1.mode_display == kHoming; }, 100))
        return fail("drive 1 did not enter HM");
    d1.controlword = kEnable | kHomingStart;
    tracking_ = true;
    const auto t0 = Clock::now();
    const bool ended = cycle_until(
        [&] {
            return (d1.statusword & (kSwHomingError | kSwFault)) ||
                   ((d1.statusword & kSwHomingAttained) && (d1.statusword & kSwTargetReached));
        },
        15000);
    tracking_ = false;
    if (!ended) return fail(interrupted() ? "interrupted" : "homing did not end within 15 s");
    if (d1.statusword & kSwFault) return fail(left_enabled());
    if (d1.statusword & kSwHomingError)
        return fail(fmt::format("homing error, statusword 0x{:04X}", d1.statusword));
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    // Back to CSP, holding the position.
    d1.controlword = kEnable;
    d1.target = d1.position;
    d1.mode = kCsp;
    if (!cycle_until([&] { return d1.mode_display == kCsp; }, 100))
        return fail("drive 1 did not return to CSP");
    note(
        "       homing attained (statusword 0x{:04X}) after {:.0f} ms: the switch edge now reads {} "
        "(0x{:04X}); drive 1 "
        "stopped at {}, {} beyond it (it started at {})",
        d1.statusword, ms, kHomeSwitch, obj::home_offset.index, d1.position, kHomeSwitch - d1.position,
        before);
    if (gantry_)
        note(
            "       drive 2 followed the search over TWINsync and is at {} (difference {}); the home offset "
            "keeps "
            "the gantry's coordinates, drive 2 does not home itself",
            axes_[1].position, d1.position - axes_[1].position);
    return true;
}

bool Demo::fault() {
    auto& d1 = axes_[0];
    const auto injected =
        injector_.submit("inject following_error slave=0 id=demo-fault", milliseconds(1000));
    if (injected.rfind("ok", 0) != 0) return fail("fault injection: " + injected);
    note("       injector: {} (drive 1's simulated fault 0x2101 = 0x8611)", injected);
    unsigned seen_after = 0;
    if (!cycle_until([&] { return ++seen_after, (d1.statusword & kSwFault) != 0; }, 500))
        return fail("drive 1 did not report the fault");
    // A reset is only taken once the fault reaction is over: wait for it (drive 2's monitoring reacts to
    // its partner's fault over TWINsync a few cycles later).
    cycle_until([] { return false; }, 20);
    cycle_until(
        [&] {
            return std::none_of(axes_.begin(), axes_.end(),
                                [](const Axis& a) { return a.state() == DriveState::FaultReactionActive; });
        },
        2000);
    for (std::size_t i = 0; i < axes_.size() && i < 2; ++i)
        note("       drive {}: statusword 0x{:04X} ({}), error code 0x{:04X} = 0x{:04X}{}", i + 1,
             axes_[i].statusword, short_name(axes_[i].state()), obj::error_code.index, axes_[i].error_code,
             i == 0 ? fmt::format(", seen {} cycles after the injection", seen_after) : "");
    for (std::size_t i = 0; i < axes_.size() && i < 2; ++i) {
        master::CoeClient c(master_, master_.slaves()[i].station);
        for (int k = 0; k < 8; ++k) {
            cycle();  // the cycle goes on between the mailbox reads
            const auto msg = c.receive(milliseconds(0));
            if (!msg) break;
            if (msg->payload.size() >= 10 &&
                protocol::coe_service(ld_le16(msg->payload.data())) == protocol::CoeService::Emergency)
                note("       drive {}: emergency 0x{:04X}, error register 0x{:02X}", i + 1,
                     ld_le16(msg->payload.data() + 2), msg->payload[4]);
        }
    }
    const auto cleared = injector_.submit("clear demo-fault", milliseconds(1000));
    // Fault reset: bit 7 rising (drive 2 gets it over TWINsync); pulsed again if a drive missed the edge.
    auto no_fault = [&] {
        return std::none_of(axes_.begin(), axes_.end(),
                            [](const Axis& a) { return a.statusword & kSwFault; });
    };
    bool reset = false;
    for (int pulse = 0; pulse < 5 && !reset && !interrupted(); ++pulse) {
        for (auto& a : axes_)
            a.controlword = 0;
        cycle_until([] { return false; }, 5);
        for (auto& a : axes_)
            a.controlword = kFaultReset;
        reset = cycle_until(no_fault, 200);
    }
    if (!reset)
        return fail(
            interrupted()
                ? "interrupted"
                : fmt::format("the fault reset did not clear the fault: statuswords 0x{:04X} 0x{:04X}, "
                              "error codes 0x{:04X} 0x{:04X}",
                              axes_[0].statusword, axes_.back().statusword, axes_[0].error_code,
                              axes_.back().error_code));
    note(
        "       injector: clear demo-fault: {}; fault reset (controlword 0x80) cleared both drives; enabling "
        "again",
        cleared);
    if (!enable_drives()) return false;
    const std::int32_t from = d1.position;
    tracking_ = true;
    const bool moved = move_to(0, 1.0);
    tracking_ = false;
    if (!moved) return false;
    note("       moved again: drive 1 from {} to {}", from, d1.position);
    return true;
}

bool Demo::disable() {
    for (auto& a : axes_)
        a.controlword = kShutdown;
    const bool ready = cycle_until(
        [&] {
            return std::all_of(axes_.begin(), axes_.end(),
                               [](const Axis& a) { return a.state() == DriveState::ReadyToSwitchOn; });
        },
        500);
    if (!ready) return fail(interrupted() ? "interrupted" : "drives did not reach \"ready\"");
    for (auto& a : axes_)
        a.controlword = 0;
    cycle_until([] { return false; }, 10);
    return !interrupted() || fail("interrupted");
}

bool Demo::init() {
    // The drives' own count of SYNC0 events without new outputs (0x1C32:0B), read while still in OP.
    std::string missed;
    for (const auto& a : axes_) {
        const std::size_t i = a.layout.slave;
        master::CoeClient c(master_, master_.slaves()[i].station);
        const auto r = c.upload(0x1C32, 0x0B);
        missed += fmt::format("{}slave {}: {}", missed.empty() ? "" : ", ", i,
                              r.ok() && r.data.size() >= 2 ? std::to_string(ld_le16(r.data.data())) : "?");
    }
    if (!axes_.empty()) note("       SYNC0 events without new outputs (0x1C32:0B): {}", missed);
    for (const auto& s : master_.slaves())
        if (s.has_dc) master_.stop_sync(s.station);
    dc_running_ = false;
    if (!master_.request_state(AlState::Init)) return fail("the slaves did not go back to INIT");
    set_al(AlState::Init);
    return true;
}

// After a failure or a signal: drives off, SYNC0 off, INIT; each step bounded.
void Demo::shut_down() {
    if (al_ == AlState::Op || al_ == AlState::SafeOp) {
        for (auto& a : axes_)
            a.controlword = 0;
        for (int i = 0; i < 20; ++i)
            cycle();
    }
    for (const auto& s : master_.slaves())
        if (s.has_dc) master_.stop_sync(s.station);
    dc_running_ = false;
    if (al_ != AlState::Init && master_.request_state(AlState::Init, milliseconds(1000)))
        set_al(AlState::Init);
    note("       drives disabled, line {}", protocol::to_string(al_));
}

void Demo::stop_server() {
    serve_stop_ = true;
    if (server_.joinable()) server_.join();
}

void Demo::write_files() {
    const std::string& dir = opt_.outdir;
    pcap_.flush();
    note("files in {}/:", dir);
    if (!on_network_) {
        const std::string esi = dir + "/vecat-drive.xml", sii = dir + "/vecat-drive.sii";
        std::ofstream(esi) << esi::write_esi(dev_);
        const auto img = esc::build_sii_image(dev_);
        std::ofstream(sii, std::ios::binary)
            .write(reinterpret_cast<const char*>(img.data()), static_cast<std::streamsize>(img.size()));
        note("  ESI file     {}", esi);
        note("  SII image    {} ({} bytes)", sii, img.size());
    }
    note("  capture      {}/demo.pcapng ({} frames; wireshark reads it)", dir, pcap_.frames());
    const auto scope =
        scope_.write(dir,
                     gantry_ ? "vecat demo: TWINsync gantry, drive 1 commanded, drive 2 following"
                             : "vecat demo: drives in CSP",
                     gantry_ ? "position_actual+position_demand,twinsync.tracking_error,velocity_actual"
                             : "position_actual+position_demand,following_error,velocity_actual");
    for (const auto& f : scope)
        note("  scope        {}", f);
}

void Demo::summary(double seconds, std::size_t phases_done) {
    note("summary: {} of {} phases in {:.1f} s; {} cycles in OP, {} working-counter misses, {} late wake-ups",
         phases_done, phases().size(), seconds, stats_.cycles, stats_.misses, stats_.late);
    note(
        "  round trip mean {:.0f} us, max {:.0f} us; frame phase against SYNC0: rms {:.1f} us, max {:.1f} us",
        stats_.rtt_mean_us(), stats_.rtt_max_us, stats_.phase_rms_us(), stats_.phase_max_us);
    if (gantry_)
        note("  gantry: largest difference drive 1 - drive 2 {:.0f} increments ({:.3f} % of a revolution)",
             worst_gantry_, worst_gantry_ / kRev * 100.0);
    std::string pulses;
    for (std::size_t i = 0; i < seg_->size(); ++i)
        pulses += fmt::format("{}slave {}: {}", i ? ", " : "", i,
                              seg_->slave(i).esc().dc().counters().sync_pulses[0]);
    note("  DC: system time difference {} ns at SYNC0 start; SYNC0 pulses {}", dc_difference_ns_, pulses);
}

int Demo::run() {
    if (on_network_)
        note("vecat demo: network {} ({} devices) on veth pair vecat-m <-> vecat-s in a private network namespace",
             opt_.network, seg_->size());
    else
        note("vecat demo: {} virtual drive(s) on veth pair vecat-m <-> vecat-s in a private network namespace{}",
             opt_.slaves, gantry_ ? "; drives 1 and 2 are a TWINsync gantry (drive 2 follows drive 1)" : "");
    const auto t0 = Clock::now();
    std::size_t done = 0;
    bool failed = false;
    for (const auto& p : phases()) {
        if (interrupted()) break;
        phase_ = p.name;
        note("[{:2}/{}] {}: {}", done + 1, phases().size(), p.name, p.what);
        const auto t = Clock::now();
        if (!(this->*p.run)()) {
            if (!interrupted()) {
                note("       FAILED: {}", why_);
                for (const auto& sl : master_.slaves()) {
                    const auto al = master_.read_al_status(sl.station);
                    if (al.ok && (al.error() || al.state() != al_))
                        note("       slave {}: AL status 0x{:02X}, AL status code 0x{:04X}", sl.position,
                             al.status, al.code);
                }
                failed = true;
            }
            break;
        }
        ++done;
        note("       done in {:.0f} ms", std::chrono::duration<double, std::milli>(Clock::now() - t).count());
    }
    const int sig = g_signal.load();
    if (sig) note("vecat demo: interrupted by signal {} in phase {}: stopping", sig, phase_);
    phase_ = "stop";
    if (sig || failed) shut_down();
    const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    stop_server();
    summary(seconds, done);
    write_files();
    if (sig) return kDemoInterruptedBase + sig;
    return failed ? kDemoFailed : kDemoOk;
}

}  // namespace

int run_demo(const DemoOptions& o) {
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    // A network file is read and built before anything else: a bad one is refused with its line.
    network::BuiltNetwork network;
    if (!o.network.empty()) {
        try {
            network = network::build_network(network::read_network_file(o.network), o.network);
        } catch (const network::NetworkFileError& e) {
            fmt::print(stderr, "vecat demo: {}\n", e.what());
            return kDemoBadNetwork;
        }
        for (const auto& n : network.notes)
            fmt::print(stderr, "vecat demo: {}\n", n);
    }
    std::string why;
    if (!net::enter_private_netns(&why) || !net::create_veth_pair("vecat-m", "vecat-s", &why)) {
        fmt::print(stderr, "vecat demo: cannot create its network namespace and veth pair: {}\n", why);
        return kDemoFailed;
    }
    std::error_code ec;
    std::filesystem::create_directories(o.outdir, ec);
    if (ec) {
        fmt::print(stderr, "vecat demo: cannot create {}: {}\n", o.outdir, ec.message());
        return kDemoFailed;
    }
    try {
        Demo d(o, std::move(network));
        return d.run();
    } catch (const std::exception& e) {
        fmt::print(stderr, "vecat demo: {}\n", e.what());
        return kDemoFailed;
    }
}

}  // namespace vecat::cli
