// vecat demo: the session's loop (the cyclic exchange, phase-locked to SYNC0), its status line, the tables
// of phases, the summary and the files written at the end. The phases themselves: demo_phases.cpp.
#include "cli/demo.hpp"

#include "cli/demo_session.hpp"

namespace vecat::cli {
namespace demo_detail {

std::atomic<int> g_signal{0};

namespace {
void on_signal(int s) {
    g_signal.store(s);
}
}  // namespace

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
        note(
            "vecat demo: network {} ({} devices) on veth pair vecat-m <-> vecat-s in a private network "
            "namespace",
            opt_.network, seg_->size());
    else
        note(
            "vecat demo: {} virtual drive(s) on veth pair vecat-m <-> vecat-s in a private network "
            "namespace{}",
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

}  // namespace demo_detail

int run_demo(const DemoOptions& o) {
    using namespace demo_detail;
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
