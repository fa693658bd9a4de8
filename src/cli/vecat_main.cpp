// vecat: the command line program. Past 600 lines because it declares every subcommand and the options of
// `run`/`exec` (about 50); the work of each subcommand lives in its own file beside it.
#include <fmt/core.h>
#include <signal.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <thread>

#include "cia402/drive.hpp"
#include "cia402/profile_generator.hpp"
#include "cli/clone_command.hpp"
#include "cli/demo.hpp"
#include "cli/exec.hpp"
#include "cli/fault_cli.hpp"
#include "cli/network_commands.hpp"
#include "cli/replay_command.hpp"
#include "cli/telemetry_commands.hpp"
#include "coe/coe_application.hpp"
#include "common/file.hpp"
#include "device/device_description.hpp"
#include "device/soe_drive.hpp"
#include "eoe/eoe_bridge.hpp"
#include "eoe/eoe_server.hpp"
#include "esc/segment.hpp"
#include "esc/sii_image.hpp"
#include "esi/esi_check.hpp"
#include "esi/esi_reader.hpp"
#include "esi/esi_writer.hpp"
#include "foe/foe_server.hpp"
#include "master/master.hpp"
#include "net/netns.hpp"
#include "net/privileges.hpp"
#include "net/raw_socket.hpp"
#include "net/realtime.hpp"
#include "network/build.hpp"
#include "network/eni.hpp"
#include "network/eni_network.hpp"
#include "report/init_cmd_check.hpp"
#include "report/master_checks.hpp"
#include "serve/server.hpp"
#include "soe/soe_drive.hpp"

namespace {

std::atomic<bool> g_stop{false};

void on_signal(int) {
    g_stop.store(true);
}

void install_signals() {
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
}

// The built-in SoE drives' names for --device (src/soe: not CiA 402 drives over CoE, served by their own
// application): one axis, two axes.
constexpr const char* kSoeDrive = "soe-drive";
constexpr const char* kSoeDrive2 = "soe-drive-2";

// The device to emulate: a built-in drive (--device NAME, the vecat drive without it), or one device of
// a vendor ESI file.
std::optional<vecat::device::DeviceDescription> load_device(const std::string& esi_path,
                                                            const vecat::esi::DeviceSelector& sel,
                                                            bool for_emulation = false) {
    if (esi_path.empty()) {
        if (!sel.type) return vecat::device::default_drive();
        if (auto d = vecat::device::builtin_drive(*sel.type)) return d;
        if (*sel.type == kSoeDrive) return vecat::device::soe_drive();
        if (*sel.type == kSoeDrive2) return vecat::device::soe_drive(2);
        std::string names;
        for (auto n : vecat::device::builtin_drive_names())
            names += (names.empty() ? "" : ", ") + std::string(n);
        names += std::string(", ") + kSoeDrive + ", " + kSoeDrive2;
        fmt::print(stderr, "vecat: --device {}: no such built-in device (without --esi: {})\n", *sel.type,
                   names);
        return std::nullopt;
    }
    try {
        auto r = vecat::esi::import_esi_file(esi_path, sel);
        for (const auto& n : r.notes)
            fmt::print(stderr, "vecat: {}: {}\n", esi_path, n);
        if (for_emulation) {
            for (const auto& n : vecat::esi::complete_for_emulation(r.desc))
                fmt::print(stderr, "vecat: {}: {}\n", esi_path, n);
            if (auto b = vecat::device::adopt_builtin_rules(r.desc))
                fmt::print(stderr,
                           "vecat: {}: the built-in {} by its identity: its behaviour and PDO rules\n",
                           esi_path, *b);
        }
        return r.desc;
    } catch (const std::exception& e) {
        fmt::print(stderr, "vecat: {}: {}\n", esi_path, e.what());
        return std::nullopt;
    }
}

// Parameter persistence: one file per slave position in dir; a stored set is applied before the first
// frame. Returns false when the directory cannot be used.
bool attach_parameter_stores(vecat::esc::Segment& seg, const std::string& dir, std::FILE* log) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) {
        fmt::print(stderr, "vecat: cannot create the parameter directory {}: {}\n", dir, ec.message());
        return false;
    }
    for (std::size_t i = 0; i < seg.size(); ++i) {
        auto* app = dynamic_cast<vecat::coe::CoeApplication*>(&seg.slave(i).app());
        if (!app) continue;
        const auto rep = app->attach_parameter_store(fmt::format("{}/slave-{}.param", dir, i));
        using vecat::coe::LoadStatus;
        if (rep.load.status == LoadStatus::Loaded)
            fmt::print(log, "vecat: slave {}: {} stored parameters applied{}\n", i, rep.applied,
                       rep.refused ? fmt::format(", {} refused (kept their defaults)", rep.refused) : "");
        else if (rep.load.status != LoadStatus::Missing)
            fmt::print(stderr, "vecat: slave {}: stored parameters {} ({}); using the defaults\n", i,
                       vecat::coe::to_string(rep.load.status), rep.load.detail);
    }
    return true;
}

int write_output(const std::string& out, const std::string& data) {
    if (out.empty() || out == "-") {
        std::fwrite(data.data(), 1, data.size(), stdout);
        return 0;
    }
    std::ofstream f(out, std::ios::binary);
    f.write(data.data(), static_cast<std::streamsize>(data.size()));
    return f ? 0 : 1;
}

// vecat run --report-fail: the master broke a rule of the report.
constexpr int kReportFailed = 3;

// Everything `vecat run` is given on its command line.
struct RunOptions {
    std::string iface;
    unsigned slaves = 2;
    std::string pcap_path;
    unsigned pcap_limit_mb = 1024;
    bool busy = false;     // --busy-poll
    bool rx_ring = false;  // --rx-ring: PACKET_MMAP receive ring
    bool allow_busy_if = false;
    double drift_ppm = 0.0;
    std::string esi_path;
    vecat::esi::DeviceSelector sel;
    std::string param_dir;
    vecat::cli::RunFaultOptions fault_opts;
    vecat::cli::TelemetryOptions telemetry;
    vecat::cia402::TwinsyncPreset twinsync = vecat::cia402::TwinsyncPreset::None;
    vecat::net::RealtimeOptions rt;
    std::int64_t tick_us = vecat::net::ServeOptions{}.tick_us;
    std::string downstream;
    std::string network_path;         // --network: the devices and their cabling from a file
    std::string eni_path;             // --eni: the network of an ENI (EtherCATConfig) file
    std::string esi_dir;              // --esi-dir: vendor ESI files for the devices an ENI names
    std::string report_path;          // --report: JUnit XML of the checks on the master
    bool report_fail = false;         // --report-fail: exit 3 when a check failed
    vecat::foe::FoeOptions foe;       // --foe-dir, --foe-max-size, --foe-password
    std::string redundant_iface;      // --redundant-iface: the master's second port (cable redundancy)
    std::vector<std::string> quirks;  // --quirk: of every device of the line (device/quirks.hpp)
    std::string eoe_tap;              // --eoe-tap: the EoE devices' Ethernet sides as TAP PREFIXn
    unsigned threads = 1;             // --threads: threads that run the slaves' firmware
};

// Several observers of the frames (the report's checks), each called in turn.
struct FanOut final : vecat::net::FrameObserver {
    std::vector<vecat::net::FrameObserver*> to;
    void on_request(vecat::ConstBytes f, std::uint64_t now_ns) override {
        for (auto* o : to)
            o->on_request(f, now_ns);
    }
    void on_reply(vecat::ConstBytes f, std::uint64_t now_ns) override {
        for (auto* o : to)
            o->on_reply(f, now_ns);
    }
};

// Serves until stop. ready (when given) is set once the serve loop runs; messages go to log. vecat run
// gives g_stop and stdout; vecat exec its own flag and stderr (COMMAND's output stays its own).
int cmd_run(const RunOptions& o, std::atomic<bool>& stop, std::atomic<bool>* ready = nullptr,
            std::FILE* log = stdout) {
    const auto& [iface, slaves, pcap_path, pcap_limit_mb, busy, rx_ring, allow_busy_if, drift_ppm, esi_path,
                 sel, param_dir, fault_opts, telemetry, twinsync, rt, tick_us, downstream, network_path,
                 eni_path, esi_dir, report_path, report_fail, foe_opts, redundant_iface, quirks, eoe_tap,
                 threads] = o;
    std::string why;
    for (const std::string& i : {iface, downstream, redundant_iface}) {
        if (i.empty() || allow_busy_if || !vecat::net::interface_in_use(i, &why)) continue;
        fmt::print(stderr,
                   "vecat: refusing to serve on {}: {}.\n"
                   "       EtherCAT takes over the whole link; use a veth pair or a dedicated NIC, or pass "
                   "--allow-used-interface.\n",
                   i, why);
        return 2;
    }
    if (!downstream.empty() && downstream == iface) {
        fmt::print(stderr, "vecat: --downstream must be another interface than --iface\n");
        return 2;
    }
    if (!redundant_iface.empty() && (redundant_iface == iface || redundant_iface == downstream)) {
        fmt::print(stderr, "vecat: --redundant-iface {} is in use already (--iface or --downstream)\n",
                   redundant_iface);
        return 2;
    }
    if (!redundant_iface.empty() && !downstream.empty()) {
        fmt::print(stderr,
                   "vecat: --redundant-iface and --downstream: a chained line has no redundancy cable\n");
        return 2;
    }
    std::unique_ptr<vecat::esc::Segment> seg;
    std::string served;  // what the start line names
    // With --eni and --report: the ENI's register writes, which the master's are compared with.
    std::vector<vecat::report::ExpectedWrite> eni_writes;
    std::shared_ptr<vecat::io::IoBus> io_bus;  // the I/O terminals of a network file (fault set_input)
    if (!network_path.empty() || !eni_path.empty()) {
        const std::string& file = eni_path.empty() ? network_path : eni_path;
        try {
            vecat::network::NetworkFile f;
            if (eni_path.empty()) {
                f = vecat::network::read_network_file(file);
            } else {
                const auto eni = vecat::network::read_eni_file(file);
                auto n = vecat::network::network_from_eni(eni, {esi_dir});
                for (const auto& x : n.notes)
                    fmt::print(stderr, "vecat: {}\n", x);
                eni_writes = vecat::report::expected_writes(eni, n);
                f = std::move(n.file);
            }
            auto built = vecat::network::build_network(f, file);
            for (const auto& n : built.notes)
                fmt::print(stderr, "vecat: {}\n", n);
            seg = std::move(built.segment);
            io_bus = std::move(built.io);
        } catch (const vecat::network::NetworkFileError& e) {
            fmt::print(stderr, "vecat: {}\n", e.what());
            return 1;
        }
        served = fmt::format("network {} ({} devices)", file, seg->size());
    } else {
        auto loaded = load_device(esi_path, sel, true);
        if (!loaded) return 1;
        if (!quirks.empty()) {
            vecat::device::Quirks q;
            std::string bad;
            for (const auto& t : quirks)
                if (const auto w = vecat::device::parse_quirk(t, q); !w.empty() && bad.empty()) bad = w;
            if (bad.empty()) bad = vecat::device::apply_quirks(*loaded, q);
            if (!bad.empty()) {
                fmt::print(stderr, "vecat: --quirk: {}\n", bad);
                return 2;
            }
        }
        const auto& dev = *loaded;
        if (esi_path.empty() && (sel.type == kSoeDrive || sel.type == kSoeDrive2))
            seg = vecat::esc::make_segment(vecat::esc::DeviceModel::of(dev), slaves, {},
                                           vecat::soe::make_soe_drive);
        else
            seg = vecat::cia402::make_drive_segment(dev, slaves, {}, twinsync);
        served = fmt::format("{} x \"{}\" (vendor 0x{:08X}, product 0x{:08X})", slaves, dev.name,
                             dev.identity.vendor_id, dev.identity.product_code);
        if (dev.quirks.any()) served += fmt::format(" with quirks {}", vecat::device::to_string(dev.quirks));
    }
    if (!redundant_iface.empty() && !seg->redundant()) {
        // No redundancy: port in the network file: the cable leaves port 1 of the last slave.
        if (!seg->set_redundancy(seg->size() - 1, 1, &why)) {
            fmt::print(stderr,
                       "vecat: --redundant-iface: {} (give redundancy: NAME:PORT in the network file)\n",
                       why);
            return 1;
        }
    }
    if (!param_dir.empty() && !attach_parameter_stores(*seg, param_dir, log)) return 1;
    // FoE and the BOOT state's firmware update for every device that declares FoE (src/foe/README.md).
    if (const auto n = vecat::foe::attach_foe(*seg, foe_opts); n > 0 && !foe_opts.dir.empty())
        fmt::print(log, "vecat: FoE files of {} slave(s) in {}/slave-N\n", n, foe_opts.dir);
    // EoE for every device that declares it; with --eoe-tap its Ethernet side is a TAP (src/eoe/README.md).
    const std::size_t eoe_devices = vecat::eoe::attach_eoe(*seg);
    std::unique_ptr<vecat::eoe::EoeBridge> eoe_bridge;
    if (!eoe_tap.empty()) {
        try {
            eoe_bridge = std::make_unique<vecat::eoe::EoeBridge>(*seg, eoe_tap);
        } catch (const std::exception& e) {
            fmt::print(stderr, "vecat: --eoe-tap: {}\n", e.what());
            return 1;
        }
        if (eoe_devices == 0) fmt::print(stderr, "vecat: --eoe-tap: no device of the line declares EoE\n");
        for (std::size_t i = 0; i < eoe_bridge->size(); ++i)
            fmt::print(log, "vecat: EoE Ethernet side of a device on TAP {}\n", eoe_bridge->tap(i).name());
    }
    // DC oscillators: +drift, -drift, +drift... against the host clock (neighbours differ by 2 x drift).
    for (std::size_t i = 0; i < seg->size(); ++i)
        seg->slave(i).esc().dc().set_drift_ppm(i % 2 ? -drift_ppm : drift_ppm, vecat::net::monotonic_ns());
    std::unique_ptr<vecat::net::RawSocket> sock, down, second;
    try {
        sock = std::make_unique<vecat::net::RawSocket>(iface);
        if (!downstream.empty()) down = std::make_unique<vecat::net::RawSocket>(downstream);
        if (!redundant_iface.empty()) second = std::make_unique<vecat::net::RawSocket>(redundant_iface);
    } catch (const std::exception& e) {
        fmt::print(stderr, "vecat: {}\n", e.what());
        return 1;
    }
    if (rx_ring) {
        for (auto* s : {sock.get(), down.get(), second.get()})
            if (s && !s->enable_rx_ring(&why))
                fmt::print(stderr, "vecat: {}: no receive ring ({}); using recvmsg\n", s->ifname(), why);
    }
    std::unique_ptr<vecat::net::PcapngWriter> pcap;
    if (!pcap_path.empty())
        pcap =
            std::make_unique<vecat::net::PcapngWriter>(pcap_path, iface, std::uint64_t{pcap_limit_mb} << 20);
    bool faults_ok = true;
    auto faults = vecat::cli::start_fault_session(*seg, fault_opts, faults_ok, io_bus);
    if (!faults_ok) return 1;
    if (!ready) install_signals();
    fmt::print(log, "vecat: {} on {}; Ctrl-C stops\n", served, iface);
    std::fflush(log);  // a program that starts vecat run reads this line to know it serves
    vecat::net::ServeOptions opt;
    opt.busy_poll = busy;
    opt.pcap = pcap.get();
    if (faults) opt.filter = faults->injector.get();
    opt.tick_us = tick_us;
    opt.downstream = down.get();
    opt.secondary = second.get();
    opt.side = eoe_bridge.get();
    if (second)
        fmt::print(log, "vecat: port {} of slave {} cabled back to {} (cable redundancy; {})\n",
                   seg->redundancy_port(), seg->redundancy_slave(), redundant_iface,
                   second->carrier() ? "link up" : "no link yet");
    if (down)
        fmt::print(log, "vecat: port 1 of the last slave cabled to {} ({})\n", downstream,
                   down->carrier() ? "link up: the line goes on" : "no link yet: the line closes here");
    std::unique_ptr<vecat::report::MasterChecks> checks;
    std::unique_ptr<vecat::report::InitCmdCheck> init_cmds;
    FanOut observers;
    if (!report_path.empty()) {
        checks = std::make_unique<vecat::report::MasterChecks>(*seg);
        opt.observer = checks.get();
        if (!eni_path.empty()) {
            init_cmds = std::make_unique<vecat::report::InitCmdCheck>(*seg, eni_writes);
            observers.to = {checks.get(), init_cmds.get()};
            opt.observer = &observers;
        }
    }
    auto tel = vecat::cli::RunTelemetry::start(*seg, telemetry, opt);
    if (!tel) return 2;
    // The firmware's workers, made before the serve loop's thread is pinned (they run on any CPU).
    std::unique_ptr<vecat::esc::FirmwareThreads> firmware;
    if (threads > 1) {
        firmware = std::make_unique<vecat::esc::FirmwareThreads>(threads);
        opt.firmware_threads = firmware.get();
        if (rt.fifo_priority > 0 && !firmware->set_fifo_priority(rt.fifo_priority, &why)) {
            fmt::print(stderr, "vecat: {}\n", why);
            return 1;
        }
        fmt::print(log, "vecat: the slaves' firmware runs on {} threads ({} firmware groups)\n", threads,
                   seg->firmware_groups());
    }
    // The serve loop runs on this thread: pinning, SCHED_FIFO and locked memory apply to it.
    if (!vecat::net::apply_realtime(rt, &why)) {
        fmt::print(stderr, "vecat: {}\n", why);
        return 1;
    }
    // The slaves' state on huge pages (a large network's cycle misses the TLB less), before the first
    // frame can come: collapsing a heap of a hundred MiB takes tens of milliseconds.
    if (!vecat::net::back_heap_with_huge_pages(&why)) fmt::print(log, "vecat: {} (serving without)\n", why);
    // Socket, files, control socket, DDS and scheduling are set up: from here on the process needs no
    // capability (see net/privileges.hpp).
    std::string cap_why;
    if (!vecat::net::drop_all_capabilities(&cap_why))
        fmt::print(stderr, "vecat: cannot drop capabilities: {}\n", cap_why);
    if (ready) *ready = true;
    const auto st = vecat::net::serve(*seg, *sock, opt, stop);
    tel.reset();
    if (faults) vecat::cli::print_fault_summary(*faults);
    fmt::print(log, "vecat: {} frames received, {} answered, {} dropped as malformed\n", st.received, st.sent,
               seg->counters().dropped);
    if (down)
        fmt::print(log, "vecat: {} frames passed on to {}, {} came back\n", st.sent_downstream, downstream,
                   st.returned);
    if (second)
        fmt::print(log, "vecat: {} frames received on {}, {} replies sent out of it\n", st.received_secondary,
                   redundant_iface, st.sent_secondary);
    if (pcap)
        fmt::print(
            log, "vecat: capture written to {} ({} frames{})\n", pcap_path, pcap->frames(),
            pcap->dropped() ? fmt::format(", {} not written: --pcap-limit-mb reached", pcap->dropped()) : "");
    for (std::size_t i = 0; i < seg->size(); ++i) {
        const auto& dc = seg->slave(i).esc().dc();
        const auto sync = dc.sync_state();
        if (dc.counters().sync_pulses[0] == 0) continue;
        const double span =
            sync.cycle0_ns ? static_cast<double>(sync.last_sync0 - sync.first_sync0) / sync.cycle0_ns + 1.0
                           : 0.0;
        fmt::print(log,
                   "vecat: slave {}: {} SYNC0 pulses ({} not taken by the firmware), {:.0f} cycles of {} ns "
                   "between the first and the last\n",
                   i, dc.counters().sync_pulses[0], dc.counters().pulses_not_delivered, span, sync.cycle0_ns);
    }
    if (init_cmds) fmt::print(log, "vecat: the master against the ENI's InitCmds:\n{}", init_cmds->summary());
    if (checks) {
        fmt::print(log, "{}", vecat::report::summary(*checks));
        if (write_output(report_path, vecat::report::junit_xml(*checks)) != 0) {
            fmt::print(stderr, "vecat: cannot write the report to {}\n", report_path);
            return 1;
        }
        fmt::print(log, "vecat: report written to {}\n", report_path);
        if (report_fail && !checks->findings().empty()) return kReportFailed;
    }
    return 0;
}

int cmd_esi_generate(const std::string& out, const std::string& esi_path,
                     const vecat::esi::DeviceSelector& sel) {
    auto dev = load_device(esi_path, sel);
    if (!dev) return 1;
    return write_output(out, vecat::esi::write_esi(*dev));
}

int cmd_esi_check(const std::string& file, const std::string& sii_path, const std::string& xsd,
                  const vecat::esi::DeviceSelector& sel) {
    int problems = 0;
    std::string msg;
    if (!xsd.empty() && xsd == VECAT_DEFAULT_XSD && !std::filesystem::exists(xsd)) {
        // The built-in path is the build tree's copy of ETG's schema (not shipped with vecat): an installed
        // vecat without it checks everything else and says so.
        fmt::print("{}: schema not checked: {} is not there (give one with --schema)\n", file, xsd);
    } else if (!xsd.empty()) {
        if (!vecat::esi::validate_with_xmllint(file, xsd, &msg)) {
            fmt::print("{}: not valid against {}:\n{}", file, xsd, msg);
            ++problems;
        } else {
            fmt::print("{}: valid against {}\n", file, xsd);
        }
    }
    auto dev = load_device(file, sel);
    if (!dev) return 1;
    std::vector<std::uint8_t> img;
    if (!sii_path.empty()) {
        std::string why;
        const auto bytes = vecat::read_whole_file(sii_path, vecat::kMaxSiiFileBytes, why);
        if (!bytes) {
            fmt::print(stderr, "vecat: {}: {}\n", sii_path, why);
            return 1;
        }
        img.assign(bytes->begin(), bytes->end());
    } else {
        img = vecat::esc::build_sii_image(*dev);
    }
    for (const auto& line : vecat::esi::check_consistency(*dev, img)) {
        fmt::print("{}: {}\n", sii_path.empty() ? file : sii_path, line);
        ++problems;
    }
    if (problems == 0) fmt::print("{}: ESI, SII and dictionary agree\n", file);
    return problems ? 1 : 0;
}

int cmd_sii_generate(const std::string& out, const std::string& esi_path,
                     const vecat::esi::DeviceSelector& sel) {
    auto dev = load_device(esi_path, sel);
    if (!dev) return 1;
    const auto img = vecat::esc::build_sii_image(*dev);
    if (out.empty() || out == "-") {
        std::fwrite(img.data(), 1, img.size(), stdout);
        return 0;
    }
    std::ofstream f(out, std::ios::binary);
    f.write(reinterpret_cast<const char*>(img.data()), static_cast<std::streamsize>(img.size()));
    return f ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"vecat: a virtual EtherCAT servo drive"};
    app.require_subcommand(1);

    auto* run = app.add_subcommand("run", "Serve virtual slaves on a network interface");
    auto* exec = app.add_subcommand("exec",
                                    "Run a command in a private network namespace (no root needed: a user "
                                    "namespace) in which vecat serves "
                                    "the slaves on one end of a veth pair; the command gets the other end");
    RunOptions ro;
    vecat::cli::ExecOptions eo;
    run->add_option("-i,--iface", ro.iface,
                    "Interface to serve on (one end of a veth pair, or a dedicated NIC)")
        ->required();
    run->add_option("--downstream", ro.downstream,
                    "Chained segments: cable port 1 of the last slave to this interface (a veth pair to the "
                    "next vecat run); frames go on along the line while it has a link");
    run->add_option("--redundant-iface", ro.redundant_iface,
                    "Cable redundancy: the master's second port. The far end of the line (redundancy: in "
                    "the network file, else port 1 of the last slave) is cabled back to this interface");
    run->add_flag(
        "--allow-used-interface", ro.allow_busy_if,
        "Serve even on an interface that has an IP address, the default route or a bridge/bond master");
    bool no_network = false;
    exec->add_flag("--no-network", no_network,
                   "Serve no slaves: only the private namespaces, for a test runner that starts its own "
                   "networks in them (vecat run on veth pairs it makes)");
    exec->add_flag(
        "--redundant", eo.redundant,
        "Cable redundancy: a second veth pair is the master's second port ({iface2}, VECAT_IFACE2); "
        "the far end of the line (redundancy: in the network file, else port 1 of the last slave) "
        "is cabled back to it");
    exec->add_option("command", eo.command,
                     "The command and its arguments (after --); {iface} is replaced "
                     "by the master's interface, also given as VECAT_IFACE")
        ->required();
    exec->footer(
        "Example: vecat exec -n 2 -- slaveinfo {iface}\n"
        "With --redundant: vecat exec -n 4 --redundant -- my_redundant_master {iface} {iface2}\n"
        "Exit code: the command's (128 + N after signal N); 125 when vecat could not set up the namespace or "
        "serve, 126 when the command cannot be executed, 127 when it is not found. The namespaces, the veth "
        "pair and every process the command started are gone when vecat exec returns, and when it is "
        "killed.");
    std::string esi_path, device_type;
    std::uint32_t product = 0;
    std::optional<std::uint32_t> revision;
    std::vector<std::string> modules;
    auto add_esi_options = [&](CLI::App* c, bool esi_option) {
        if (esi_option) c->add_option("--esi", esi_path, "Emulate a device described by this ESI file");
        c->add_option(
            "--device", device_type,
            "Device of the ESI file by its Type name; without --esi a built-in drive: drive (the "
            "vecat drive, the default), hiwin-d2 (the HIWIN D2 CoE drive), soe-drive (the AX5000-like SoE "
            "drive) or soe-drive-2 (the same with two axes, AX5206-like)");
        c->add_option("--product", product, "Device of the ESI file by its product code (0x... accepted)");
        c->add_option("--revision", revision,
                      "Revision of that device (0x... accepted); without it the file's first one. An error "
                      "names the revisions the file has");
        c->add_option(
             "--modules", modules,
             "A modular device of the ESI file: the module of each slot in slot order, comma-separated: "
             "a module Type or ModuleIdent (0x... accepted), empty for an empty slot; slots after "
             "the list keep their default module (docs/network-file.md, Modules in slots)")
            ->delimiter(',')
            ->allow_extra_args(false);
    };
    const std::map<std::string, vecat::cia402::TwinsyncPreset> presets = {
        {"off", vecat::cia402::TwinsyncPreset::None},
        {"gantry", vecat::cia402::TwinsyncPreset::Gantry},
        {"position", vecat::cia402::TwinsyncPreset::Position},
        {"speed", vecat::cia402::TwinsyncPreset::Speed}};
    // The options of what is served, the same for vecat run and vecat exec.
    for (auto* c : {run, exec}) {
        c->add_option("-n,--slaves", ro.slaves,
                      "Number of slaves on the line (drives 1 and 2 are connected by a TWINsync cable)")
            ->check(CLI::Range(1u, 512u));
        c->add_option(
             "--twinsync", ro.twinsync,
             "TWINsync between drives 1 and 2 preset: off (configure it by CoE), gantry (P2580 29/30), "
             "position (PCON 7/8) or speed (SCON 5/6); drive 2 is then controlled through TWINsync")
            ->transform(CLI::CheckedTransformer(presets, CLI::ignore_case));
        c->add_option(
             "--network", ro.network_path,
             "Serve the devices and cabling of this network file (docs/network-file.md) instead of a "
             "line of drives")
            ->excludes(c->get_option("--slaves"))
            ->excludes(c->get_option("--twinsync"));
        c->add_option("--eni", ro.eni_path,
                      "Serve the network of this ENI file (EtherCATConfig XML as configurators export it; "
                      "docs/eni.md) instead of a line of drives")
            ->excludes(c->get_option("--slaves"))
            ->excludes(c->get_option("--twinsync"))
            ->excludes(c->get_option("--network"));
        c->add_option("--esi-dir", ro.esi_dir,
                      "With --eni: a folder of vendor ESI files; a slave whose identity one describes is "
                      "made from it (dictionary included)");
        c->add_option("--pcap", ro.pcap_path, "Write every frame in and out to this pcapng file");
        c->add_option("--report", ro.report_path,
                      "Check what the master does against the rules of the EtherCAT specifications and write "
                      "the result as JUnit XML to this file (a summary is printed at exit); with --eni, also "
                      "the master's register writes per AL transition against the ENI's InitCmds");
        c->add_flag("--report-fail", ro.report_fail,
                    "With --report: exit with 3 when the master broke a rule (vecat exec: when COMMAND "
                    "itself succeeded)");
        c->add_flag("--busy-poll,!--blocking", ro.busy,
                    "Spin on the socket instead of sleeping in poll() (lowest latency, one core busy); "
                    "--blocking (the default) suits laptops");
        c->add_option("--cpu", ro.rt.cpu, "Pin the serve loop to this CPU");
        c->add_option("--fifo", ro.rt.fifo_priority,
                      "Run the serve loop under SCHED_FIFO with this priority (1..99; with --busy-poll the "
                      "kernel's RT throttling stalls it for 50 ms a second unless that is turned off)")
            ->check(CLI::Range(1, 99));
        c->add_flag("--mlock", ro.rt.lock_memory, "Lock all memory (mlockall): no page faults while serving");
        c->add_option("--tick-us", ro.tick_us,
                      "The slaves' local cycle: a slave without a cycle of its own (a drive has its servo "
                      "period) whose firmware last ran this long ago or longer catches up before a frame "
                      "reads it; also the shortest time between firmware runs without frames (between "
                      "frames the firmware runs for its deadlines and so that the work a frame finds waiting "
                      "stays small)")
            ->check(CLI::Range(10, 100000));
        c->add_option("--threads", ro.threads,
                      "Threads that run the slaves' firmware: the serve loop's and N-1 workers. The runs "
                      "that a frame needs (the catch-up of the slaves it reads, the runs after it) are "
                      "spread over them by groups of slaves that share no state (drives coupled by "
                      "TWINsync and wired I/O stay together); results are the same as with one thread. "
                      "For large networks; a worker spins while frames keep coming")
            ->check(CLI::Range(1, 64))
            ->capture_default_str();
        c->add_flag("--rx-ring", ro.rx_ring,
                    "Receive through a PACKET_MMAP ring shared with the kernel instead of one recvmsg() per "
                    "frame");
        c->add_option("--pcap-limit-mb", ro.pcap_limit_mb, "Largest capture file in MiB (0: no limit)")
            ->capture_default_str();
        c->add_option("--dc-drift-ppm", ro.drift_ppm,
                      "DC clock drift of the slaves in ppm (alternating sign along the line)")
            ->check(CLI::Range(-1000.0, 1000.0));
        c->add_option("--param-dir", ro.param_dir,
                      "Keep each slave's parameters (0x1010 store / 0x1011 restore) in DIR/slave-N.param");
        c->add_option("--foe-dir", ro.foe.dir,
                      "Keep the FoE files of each slave in DIR/slave-N (without it: in memory); firmware "
                      "files (*.efw) are written there in BOOT");
        c->add_option("--foe-max-size", ro.foe.max_file_size,
                      "Largest file an FoE write or read may have, in bytes (larger: FoE error 0x8003)")
            ->capture_default_str();
        c->add_option("--foe-password", ro.foe.password,
                      "Password every FoE request must carry (0x... accepted; a wrong one: FoE error 0x800A)")
            ->capture_default_str();
        c->add_option("--eoe-tap", ro.eoe_tap,
                      "Give each device that declares EoE an Ethernet side: a TAP interface PREFIXn (n: the "
                      "slave's position from 0) in vecat's network namespace; frames the master sends "
                      "through EoE to other addresses go out of it, frames from it go to the master")
            ->option_text("PREFIX");
        c->add_option("--quirk", ro.quirks,
                      "Make every device of the line less complete, as some real devices are (repeatable, or "
                      "a comma-separated list): " +
                          std::string(vecat::device::kQuirkNames) +
                          " (docs/network-file.md, Quirks); with --network: quirks: per device in the file")
            ->delimiter(',')
            ->allow_extra_args(false)
            ->excludes(c->get_option("--network"))
            ->excludes(c->get_option("--eni"));
        add_esi_options(c, true);
        vecat::cli::add_run_fault_options(c, ro.fault_opts);
        vecat::cli::add_telemetry_options(c, ro.telemetry);
    }
    vecat::cli::FaultCommand fault_cmd;
    vecat::cli::add_fault_command(app, fault_cmd);

    auto* demo =
        app.add_subcommand("demo", "Run virtual slaves and the bundled master on a private veth pair");
    vecat::cli::DemoOptions demo_opt;
    demo->add_option("-n,--slaves", demo_opt.slaves,
                     "Number of slaves (drives 1 and 2 are a TWINsync gantry when there are two or more)")
        ->check(CLI::Range(1u, 64u))
        ->capture_default_str();
    demo->add_option("--cycles", demo_opt.cycles,
                     "Cycles of 1 ms of the CSP move (out for half of them, back for the other half)")
        ->check(CLI::Range(100u, 600000u))
        ->capture_default_str();
    demo->add_option("-o,--output", demo_opt.outdir,
                     "Directory for the ESI file, SII image, capture and scope plot")
        ->capture_default_str();
    demo->add_option(
            "--network", demo_opt.network,
            "Run on the devices of a network file (docs/network-file.md) instead of a line of drives: "
            "the CiA 402 drives found are moved, the I/O devices' outputs written and inputs read back")
        ->excludes("--slaves");
    demo->footer(
        "Phases: scan, preop, pdo-mapping, dc, safeop, op, enable, csp-move, homing, fault, disable, init.\n"
        "With --network: scan (with the topology), preop, process-data, dc, safeop, op, enable, csp-move, "
        "io,\n"
        "disable, init.\n"
        "Exit code 0 when every phase is done, 1 when one failed, 2 for a network file it refused, 130 "
        "after\n"
        "Ctrl-C (128 + the signal); the files are written in every case.");

    auto* sii = app.add_subcommand("sii", "SII EEPROM tools");
    sii->require_subcommand(1);
    auto* sii_gen = sii->add_subcommand(
        "generate", "Write the SII EEPROM image of the default drive (or of --device, --esi)");
    std::string sii_out;
    sii_gen->add_option("-o,--output", sii_out, "Output file (standard output when omitted)");
    add_esi_options(sii_gen, true);

    auto* esi = app.add_subcommand("esi", "ESI (EtherCAT Slave Information) tools");
    esi->require_subcommand(1);
    auto* esi_gen = esi->add_subcommand(
        "generate", "Write the ESI XML file of the default drive (or of --device, --esi)");
    std::string esi_out;
    esi_gen->add_option("-o,--output", esi_out, "Output file (standard output when omitted)");
    add_esi_options(esi_gen, true);
    auto* esi_chk = esi->add_subcommand(
        "check",
        "Validate an ESI file against the schema and check it against an SII image and its dictionary");
    std::string check_file, check_sii, check_xsd = std::string(VECAT_DEFAULT_XSD);
    esi_chk->add_option("file", check_file, "ESI file")->required();
    esi_chk->add_option("--sii", check_sii,
                        "SII image to compare (default: the one generated from the file)");
    esi_chk->add_option("--schema", check_xsd, "EtherCATInfo.xsd to validate against (\"\" skips)");
    add_esi_options(esi_chk, false);

    auto* network = app.add_subcommand("network", "Network files: devices and their cabling");
    network->require_subcommand(1);
    auto* network_chk = network->add_subcommand(
        "check", "Read a network file, make its devices and list them, or say what is wrong");
    std::string network_file;
    network_chk->add_option("file", network_file, "Network file (YAML), or an ENI file (XML)")->required();
    std::string network_esi_dir, eni_out = "network.yaml";
    network_chk->add_option("--esi-dir", network_esi_dir, "For an ENI: a folder of vendor ESI files");
    auto* network_eni = network->add_subcommand(
        "from-eni", "Write the network file equivalent to an ENI file (and the SII images it names)");
    network_eni->add_option("file", network_file, "ENI file (EtherCATConfig XML)")->required();
    network_eni
        ->add_option("-o,--output", eni_out,
                     "Network file to write; the SII images of devices made from the ENI alone go "
                     "beside it as NAME.sii")
        ->capture_default_str();
    network_eni->add_option("--esi-dir", network_esi_dir,
                            "A folder of vendor ESI files; a slave whose identity one describes is named "
                            "by its ESI file");
    auto* scope = vecat::cli::add_scope_command(app);
    auto* replay = vecat::cli::add_replay_command(app);
    auto* clone = vecat::cli::add_clone_command(app);

    CLI11_PARSE(app, argc, argv);
    vecat::esi::DeviceSelector sel;
    if (!device_type.empty()) sel.type = device_type;
    if (product != 0) sel.product_code = product;
    sel.revision = revision;
    if (!modules.empty()) {
        if (esi_path.empty() && !*esi_chk) {
            fmt::print(stderr, "vecat: --modules chooses the modules of a device of an --esi file\n");
            return 2;
        }
        sel.modules.emplace();
        for (const auto& m : modules)
            sel.modules->push_back(m == "empty" ? std::nullopt : std::optional<std::string>(m));
    }
    ro.esi_path = esi_path;
    ro.sel = sel;
    if (!ro.esi_dir.empty() && ro.eni_path.empty()) {
        fmt::print(stderr, "vecat: --esi-dir goes with --eni\n");
        return 2;
    }
    if (!ro.eni_path.empty() && !esi_path.empty()) {
        fmt::print(stderr,
                   "vecat: --eni and --esi exclude each other (use --esi-dir for an ENI's devices)\n");
        return 2;
    }
    if (!ro.network_path.empty() && !esi_path.empty()) {
        fmt::print(stderr,
                   "vecat: --network and --esi exclude each other (a network file names its ESI files)\n");
        return 2;
    }
    if (*run) return cmd_run(ro, g_stop);
    if (*exec) {
        ro.iface = eo.slave_interface;
        eo.serve = !no_network;
        if (eo.redundant) ro.redundant_iface = eo.redundant_slave_interface;
        if (!ro.fault_opts.control.empty())
            eo.environment.emplace_back("VECAT_CONTROL", ro.fault_opts.control);
        return vecat::cli::run_exec(eo, [&ro](std::atomic<bool>& stop, std::atomic<bool>& ready,
                                              std::FILE* log) { return cmd_run(ro, stop, &ready, log); });
    }
    if (*fault_cmd.cmd) return vecat::cli::run_fault_command(fault_cmd);
    if (*scope) return vecat::cli::run_scope();
    if (*replay) return vecat::cli::run_replay();
    if (*clone) return vecat::cli::run_clone();
    if (*network_chk) return vecat::cli::cmd_network_check(network_file, network_esi_dir);
    if (*network_eni) return vecat::cli::cmd_network_from_eni(network_file, eni_out, network_esi_dir);
    if (*esi_gen) return cmd_esi_generate(esi_out, esi_path, sel);
    if (*esi_chk) return cmd_esi_check(check_file, check_sii, check_xsd, sel);
    if (*demo) return vecat::cli::run_demo(demo_opt);
    if (*sii_gen) return cmd_sii_generate(sii_out, esi_path, sel);
    return 0;
}
