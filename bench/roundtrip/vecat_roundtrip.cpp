// vecat-roundtrip: round-trip times of cyclic frames over veth pairs, vecat against a raw reflector.
//
// The program moves itself into a private network namespace and creates two veth pairs there:
//   rt-m0 <-> rt-r0   the reflector: a thread that sends every frame back unchanged (the floor),
//   rt-m1 <-> rt-v1   vecat: net::serve (the loop `vecat run` runs) in a thread, N CiA 402 drives.
// The project's master drives both with the same code (Master::transact_frame), the same socket class
// and options, the same wait mode. vecat runs in-process so that both servers are threads of one program
// with the same pinning and scheduling; the segment and serve loop are exactly those of `vecat run`.
//
// --mode latency  alternates blocks of cycles between the reflector and vecat (the idle server is
//                 parked in poll() so that at most two threads spin on two cores) and prints median,
//                 p99, p99.9 and max round trip of each and the ratio vecat/reflector.
// --mode soak     vecat only: N cycles at the period, counting working-counter misses (no reply within
//                 the timeout, or a wrong working counter) and late replies, and the serve thread's CPU.
#include <fmt/core.h>
#include <pthread.h>
#include <signal.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <thread>
#include <vector>

#include "bench/roundtrip/cycle_log.hpp"
#include "bench/summary.hpp"
#include "cia402/drive.hpp"
#include "master/master.hpp"
#include "net/netns.hpp"
#include "net/raw_socket.hpp"
#include "net/realtime.hpp"
#include "network/build.hpp"
#include "protocol/registers.hpp"
#include "serve/server.hpp"

using namespace vecat;

namespace {

constexpr int kSkip = 77;  // ctest: skipped (no root for the namespace)

// Ctrl-C (or SIGTERM) ends the run early; the figures of the cycles done are printed.
std::atomic<bool> g_interrupted{false};
void on_signal(int) {
    g_interrupted = true;
}

std::uint64_t now_ns() {
    return net::monotonic_ns();
}

std::uint64_t thread_cpu_ns(pthread_t t) {
    clockid_t id{};
    if (pthread_getcpuclockid(t, &id) != 0) return 0;
    timespec ts{};
    clock_gettime(id, &ts);
    return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<std::uint64_t>(ts.tv_nsec);
}

// Waits until t (monotonic ns), asleep: in busy-poll mode only the wait for a reply spins, so that the
// master and a spinning server do not fight over the two cores between cycles.
void wait_until(std::uint64_t t) {
    const timespec ts{static_cast<time_t>(t / 1'000'000'000ull), static_cast<long>(t % 1'000'000'000ull)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
}

using bench::summarize;
using bench::Summary;

void print_summary(const char* name, const Summary& s) {
    fmt::print(
        "  {:<10} {:>9} frames  median {:7.2f} us  p99 {:7.2f} us  p99.9 {:7.2f} us  max {:8.2f} us  "
        "mean {:7.2f} us\n",
        name, s.n, s.p50 / 1e3, s.p99 / 1e3, s.p999 / 1e3, s.max / 1e3, s.mean / 1e3);
}

struct Options {
    std::string mode = "latency";
    std::uint64_t cycles = 0;  // 0: 20000 (latency) / 10000 (soak)
    unsigned period_us = 1000;
    unsigned slaves = 1;
    bool busy = false;
    bool rx_ring = false;
    std::string cpu;  // "M,S": master thread on M, server threads on S
    int fifo = 0;
    bool mlock = false;
    unsigned timeout_us = 0;  // 0: the period (at least 1000 us)
    unsigned late_us = 0;     // 0: half the period
    bool dc = true;
    bool with_reflector = false;  // soak: every cycle also sends the frames to the reflector
    std::int64_t tick_us = net::ServeOptions{}.tick_us;
    std::int64_t catch_up_us = net::ServeOptions{}.catch_up_budget_us;
    std::string network;   // a network file instead of a line of drives
    unsigned threads = 1;  // threads that run the slaves' firmware (vecat run --threads)
    std::uint64_t spin_us = esc::FirmwareThreads::kSpinNs / 1000;
    std::string cycle_log;  // soak: a line per cycle into this file (CSV)
};

// The drives are enabled (6, 7, 15) in CSP and hold the position they had, so that every cycle runs the
// whole drive model (the default mapping: controlword, mode, pad, target / statusword, mode, pad, position).
void set_drive_outputs(master::Master& m, std::uint64_t cycle, std::vector<std::int32_t>& hold) {
    const std::uint16_t cw = cycle < 10 ? 0x06 : cycle < 20 ? 0x07 : 0x0F;
    for (std::size_t i = 0; i < m.slaves().size(); ++i) {
        auto out = m.outputs(i);
        auto in = m.inputs(i);
        if (out.size() < 8 || in.size() < 8) continue;
        if (cycle == 5) hold[i] = static_cast<std::int32_t>(ld_le32(in.data() + 4));
        st_le16(out.data(), cw);
        out[2] = 8;
        st_le32(out.data() + 4, static_cast<std::uint32_t>(hold[i]));
    }
}

// The same frames a master would send the reflector: as many LRW frames as vecat's image needs, the first
// with the FRMW of the reference clock.
struct ReflectorFrames {
    std::vector<std::vector<std::uint8_t>> lrw;
    std::array<std::uint8_t, 8> time{};
    std::vector<master::DatagramRequest> dgs;
    std::vector<std::span<master::DatagramRequest>> frames;
    explicit ReflectorFrames(const master::Master& m, bool with_dc) {
        std::size_t left = m.process_image_size();
        while (left > 0) {
            const std::size_t n = std::min(left, master::Master::kMaxLrwBytes);
            lrw.emplace_back(n, 0);
            left -= n;
        }
        dgs.reserve(lrw.size() + 1);
        for (std::size_t c = 0; c < lrw.size(); ++c) {
            const std::size_t first = dgs.size();
            dgs.push_back({protocol::Command::LRW, 0x00010000, Bytes(lrw[c].data(), lrw[c].size())});
            if (c == 0 && with_dc)
                dgs.push_back(
                    {protocol::Command::FRMW,
                     0x1001u |
                         (static_cast<std::uint32_t>(protocol::addr(protocol::Reg::DcSystemTime)) << 16),
                     Bytes(time.data(), time.size())});
            frames.emplace_back(dgs.data() + first, dgs.size() - first);
        }
    }
    // The same frames as the master's exchange_process_data, sent as it sends them: back to back.
    bool exchange(master::Master& r) { return r.transact_frames(frames); }
};

// Time the hypervisor gave this machine's CPUs to others ("steal" of /proc/stat), in ms: a stall of the
// whole machine shows up here and not in anything the program does.
std::uint64_t host_steal_ms() {
    std::FILE* f = std::fopen("/proc/stat", "r");
    if (!f) return 0;
    unsigned long long v[8] = {};
    const int n = std::fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3],
                              &v[4], &v[5], &v[6], &v[7]);
    std::fclose(f);
    if (n != 8) return 0;
    const long hz = sysconf(_SC_CLK_TCK);
    return hz > 0 ? v[7] * 1000ull / static_cast<unsigned long long>(hz) : 0;
}

// One cycle that missed: when, how long the exchange took, how late the master itself woke up.
struct Miss {
    std::uint64_t cycle = 0;
    std::uint64_t exchange_ns = 0;
    std::uint32_t wake_ns = 0;
    bool reflector = false;
};

struct CpuSplit {
    int master = -1, server = -1;
};

CpuSplit parse_cpu(const std::string& s) {
    CpuSplit c;
    if (s.empty()) return c;
    const auto comma = s.find(',');
    c.master = std::stoi(s.substr(0, comma));
    c.server = comma == std::string::npos ? c.master : std::stoi(s.substr(comma + 1));
    return c;
}

void realtime_or_warn(const char* who, int cpu, int fifo) {
    // Pinning and SCHED_FIFO as asked, and always a tight timer slack (without SCHED_FIFO a timed sleep may
    // otherwise end up to 50 us late). A setting that fails is reported; the run goes on without it.
    net::RealtimeOptions rt;
    rt.cpu = cpu;
    rt.fifo_priority = fifo;
    std::string why;
    if (!net::apply_realtime(rt, &why)) fmt::print(stderr, "{}: {}\n", who, why);
}

int run(const Options& o) {
    std::string why;
    if (!net::enter_private_netns(&why)) {
        fmt::print(stderr, "vecat-roundtrip: {}\n", why);
        return kSkip;
    }
    if (!net::create_veth_pair("rt-m0", "rt-r0", &why) || !net::create_veth_pair("rt-m1", "rt-v1", &why)) {
        fmt::print(stderr, "vecat-roundtrip: {}\n", why);
        return 1;
    }
    if (o.mlock && !net::lock_all_memory(&why)) fmt::print(stderr, "vecat-roundtrip: {}\n", why);
    const bool latency = o.mode == "latency";
    const std::uint64_t cycles = o.cycles ? o.cycles : (latency ? 20000 : 10000);
    const std::uint64_t period_ns = static_cast<std::uint64_t>(o.period_us) * 1000;
    const unsigned timeout_us = o.timeout_us ? o.timeout_us : std::max(o.period_us, 1000u);
    const std::uint64_t late_ns = o.late_us ? o.late_us * 1000ull : std::max<std::uint64_t>(period_ns / 2, 1);
    const CpuSplit cpu = parse_cpu(o.cpu);

    std::unique_ptr<esc::Segment> seg;
    if (!o.network.empty()) {
        try {
            seg = network::build_network(network::read_network_file(o.network), o.network).segment;
        } catch (const network::NetworkFileError& e) {
            fmt::print(stderr, "vecat-roundtrip: {}\n", e.what());
            return 1;
        }
    } else {
        seg = cia402::make_drive_segment(device::default_drive(), o.slaves);
    }
    // As vecat run does before it serves.
    std::string huge_why;
    if (!net::back_heap_with_huge_pages(&huge_why)) fmt::print("vecat-roundtrip: {}\n", huge_why);
    net::RawSocket refl_sock("rt-r0"), vecat_sock("rt-v1");
    net::RawSocket m_refl_sock("rt-m0"), m_vecat_sock("rt-m1");
    m_refl_sock.set_busy_poll(o.busy);
    m_vecat_sock.set_busy_poll(o.busy);
    if (o.rx_ring)
        for (net::RawSocket* sk : {&refl_sock, &vecat_sock, &m_refl_sock, &m_vecat_sock})
            if (!sk->enable_rx_ring(&why)) {
                fmt::print(stderr, "vecat-roundtrip: {}: no receive ring: {}\n", sk->ifname(), why);
                return 1;
            }

    std::atomic<bool> stop{false}, park_vecat{false}, park_refl{true};
    // The reflector: receive, send the same bytes back. Nothing else.
    std::thread reflector([&] {
        realtime_or_warn("reflector", cpu.server, o.fifo);
        std::array<std::uint8_t, 2048> buf{};
        while (!stop.load(std::memory_order_relaxed)) {
            const bool spin = o.busy && !park_refl.load(std::memory_order_relaxed);
            const long n = spin ? refl_sock.try_receive(Bytes(buf.data(), buf.size()))
                                : refl_sock.receive(Bytes(buf.data(), buf.size()), 1000);
            if (n > 0) refl_sock.send(ConstBytes(buf.data(), static_cast<std::size_t>(n)));
        }
    });
    // The firmware's workers, made here: not pinned to the server's CPU.
    std::unique_ptr<esc::FirmwareThreads> firmware;
    if (o.threads > 1) {
        firmware = std::make_unique<esc::FirmwareThreads>(o.threads, o.spin_us * 1000);
        if (o.fifo && !firmware->set_fifo_priority(o.fifo, &why))
            fmt::print(stderr, "vecat-roundtrip: {}\n", why);
    }
    net::ServeOptions sopt;
    sopt.firmware_threads = firmware.get();
    sopt.busy_poll = o.busy;
    sopt.park = &park_vecat;
    sopt.tick_us = o.tick_us;
    sopt.catch_up_budget_us = o.catch_up_us;
    net::ServeCounters serve_count;
    sopt.counters = &serve_count;
    std::thread server([&] {
        realtime_or_warn("server", cpu.server, o.fifo);
        net::serve(*seg, vecat_sock, sopt, stop);
    });
    realtime_or_warn("master", cpu.master, o.fifo);

    master::MasterOptions mopt;
    mopt.dc.enable = o.dc;
    mopt.dc.sync0_cycle_ns = 0;  // DC offsets and delays, FRMW in every cycle; the drives free-run
    mopt.dc.static_drift_frames = 1000;
    master::Master m(m_vecat_sock, mopt);
    int rc = 0;
    fmt::print(
        "vecat-roundtrip: {} mode, {} cycles, period {} us, {} slave(s), {} receive{}{}{}\n", o.mode, cycles,
        o.period_us, seg->size(),
        std::string(o.busy ? "busy-poll" : "blocking") + (o.rx_ring ? " (RX ring)" : ""),
        cpu.master >= 0 ? fmt::format(", master on CPU {}, servers on CPU {}", cpu.master, cpu.server) : "",
        o.fifo ? fmt::format(", SCHED_FIFO {}", o.fifo) : "", o.mlock ? ", memory locked" : "");
    if (!m.startup(protocol::AlState::Op, &why)) {
        fmt::print(stderr, "vecat-roundtrip: start-up failed: {}\n", why);
        rc = 1;
    } else {
        m.options().retries = 0;
        m.options().reply_timeout_us = timeout_us;
        master::Master r(m_refl_sock, m.options());
        ReflectorFrames rf(m, o.dc && m.dc_reference() != 0);
        fmt::print("  {} process data frame(s) per cycle, {} bytes of LRW, FRMW {}\n",
                   m.process_data_frames(), m.process_image_size(),
                   m.dc_reference() ? "in the first" : "none");
        std::vector<std::int32_t> hold(m.slaves().size(), 0);
        std::vector<std::uint32_t> rt_vecat, rt_refl, wake;
        rt_vecat.reserve(cycles);
        rt_refl.reserve(latency || o.with_reflector ? cycles : 0);
        wake.reserve(cycles);
        std::uint64_t misses = 0, no_reply = 0, late = 0, refl_lost = 0, refl_late = 0, c_vecat = 0;
        std::vector<Miss> miss_log;
        miss_log.reserve(64);
        const bool soak_refl = !latency && o.with_reflector;
        std::vector<bench::CycleRow> rows;
        const bool log_cycles = !latency && !o.cycle_log.empty();
        rows.reserve(log_cycles ? cycles : 0);  // no allocation in the cycles
        std::uint16_t worst_wkc = 0xFFFF;
        // Warm-up: drives enabled, caches and branch predictors warm.
        for (std::uint64_t c = 0; c < 200; ++c) {
            set_drive_outputs(m, c, hold);
            m.exchange_process_data();
            wait_until(now_ns() + 200'000);
        }
        const std::uint64_t block =
            latency ? std::max<std::uint64_t>(20, period_ns ? 20'000'000 / period_ns : 200) : cycles;
        const pthread_t srv_handle = server.native_handle();
        const std::uint64_t cpu0 = thread_cpu_ns(srv_handle), wall0 = now_ns();
        const std::uint64_t wakeups0 = serve_count.wakeups.load(), frames0 = serve_count.frames.load(),
                            ticks0 = serve_count.ticks.load(),
                            behind0 = serve_count.frames_behind_tick.load(),
                            behind_ns0 = serve_count.behind_tick_ns.load();
        rusage ru0{};
        getrusage(RUSAGE_SELF, &ru0);
        const std::uint64_t steal0 = host_steal_ms();
        std::uint64_t next = now_ns() + period_ns;
        std::uint64_t done = 0;
        bool refl_turn = latency;
        // Soak with the reflector: one exchange with it, its losses and late replies counted apart.
        bench::CycleRow row;
        std::uint64_t row_cpu = cpu0, row_waits = firmware ? firmware->long_waits() : 0,
                      row_wakeups = wakeups0;
        const auto exchange_reflector = [&] {
            const std::uint64_t r0 = now_ns();
            const bool ok = rf.exchange(r);
            const std::uint64_t r1 = now_ns();
            row.reflector_ns = static_cast<std::uint32_t>(std::min<std::uint64_t>(r1 - r0, 0xFFFFFFFF));
            row.reflector_ok = ok;
            if (!ok) {
                ++refl_lost;
                if (miss_log.size() < miss_log.capacity())
                    miss_log.push_back({done, r1 - r0, wake.empty() ? 0 : wake.back(), true});
            } else {
                if (r1 - r0 > late_ns) ++refl_late;
                rt_refl.push_back(static_cast<std::uint32_t>(r1 - r0));
            }
        };
        const std::uint64_t report_every = std::max<std::uint64_t>(cycles / 10, 1);
        while (done < cycles && !g_interrupted) {
            const std::uint64_t n = std::min(block, cycles - done);
            if (latency) {
                park_refl = !refl_turn;
                park_vecat = refl_turn;
            }
            for (std::uint64_t i = 0; i < n && !g_interrupted; ++i) {
                if (period_ns) {
                    wait_until(next);
                    const std::uint64_t woke = now_ns();
                    wake.push_back(
                        static_cast<std::uint32_t>(std::min<std::uint64_t>(woke - next, 0xFFFFFFFF)));
                    next += period_ns;
                    // A master that overslept does not send a burst to catch up.
                    if (next < woke) next = woke + period_ns;
                }
                const bool measured = i >= 2;  // the first frames after a switch wake a parked server
                if (refl_turn) {
                    const std::uint64_t t0 = now_ns();
                    const bool ok = rf.exchange(r);
                    const std::uint64_t t1 = now_ns();
                    if (!ok)
                        ++refl_lost;
                    else if (measured)
                        rt_refl.push_back(static_cast<std::uint32_t>(t1 - t0));
                } else {
                    // The floor under the same conditions: the same frames to the reflector in the same
                    // cycle. Whichever goes second finds both CPUs awake, so the order alternates from cycle
                    // to cycle.
                    const bool refl_first = soak_refl && (done & 1) != 0;
                    row = bench::CycleRow{};
                    row.wake_ns = wake.empty() ? 0 : wake.back();
                    row.reflector_first = refl_first;
                    if (refl_first) exchange_reflector();
                    set_drive_outputs(m, 200 + c_vecat, hold);
                    const std::uint64_t t0 = now_ns();
                    const auto w = m.exchange_process_data();
                    const std::uint64_t t1 = now_ns();
                    ++c_vecat;
                    row.vecat_ns = static_cast<std::uint32_t>(std::min<std::uint64_t>(t1 - t0, 0xFFFFFFFF));
                    row.vecat_ok = w && *w == m.expected_wkc();
                    if (!w || *w != m.expected_wkc()) {
                        ++misses;
                        no_reply += !w;
                        if (w) worst_wkc = std::min(worst_wkc, *w);
                        if (miss_log.size() < miss_log.capacity())
                            miss_log.push_back({done, t1 - t0, wake.empty() ? 0 : wake.back(), false});
                    } else {
                        if (t1 - t0 > late_ns) ++late;
                        if (measured || !latency) rt_vecat.push_back(static_cast<std::uint32_t>(t1 - t0));
                    }
                    if (soak_refl && !refl_first) exchange_reflector();
                    if (log_cycles && rows.size() < cycles) {
                        const std::uint64_t cpu_now = thread_cpu_ns(srv_handle),
                                            waits = firmware ? firmware->long_waits() : 0,
                                            wakeups_now = serve_count.wakeups.load();
                        row.serve_cpu_ns = static_cast<std::uint32_t>(cpu_now - row_cpu);
                        row.long_waits = static_cast<std::uint32_t>(waits - row_waits);
                        row.wakeups = static_cast<std::uint32_t>(wakeups_now - row_wakeups);
                        row_cpu = cpu_now;
                        row_waits = waits;
                        row_wakeups = wakeups_now;
                        rows.push_back(row);
                    }
                }
                ++done;
                if (!latency && done % report_every == 0) {
                    fmt::print("  {:>9}/{} cycles, {} working-counter misses, {} late\n", done, cycles,
                               misses, late);
                    std::fflush(stdout);
                }
            }
            if (latency) refl_turn = !refl_turn;
        }
        const std::uint64_t wall = now_ns() - wall0, cpu_srv = thread_cpu_ns(srv_handle) - cpu0;
        const std::uint64_t wakeups = serve_count.wakeups.load() - wakeups0,
                            frames = serve_count.frames.load() - frames0,
                            ticks = serve_count.ticks.load() - ticks0,
                            behind = serve_count.frames_behind_tick.load() - behind0,
                            behind_ns = serve_count.behind_tick_ns.load() - behind_ns0;
        rusage ru1{};
        getrusage(RUSAGE_SELF, &ru1);
        const std::uint64_t steal = host_steal_ms() - steal0;
        park_refl = true;
        park_vecat = true;

        fmt::print("round trip (send to reply received, master side):\n");
        Summary sv = summarize(rt_vecat);
        if (latency) {
            Summary sr = summarize(rt_refl);
            print_summary("reflector", sr);
            print_summary("vecat", sv);
            if (sr.p50)
                fmt::print("  ratio vecat/reflector: median {:.2f}, p99 {:.2f}, p99.9 {:.2f}\n",
                           static_cast<double>(sv.p50) / sr.p50, static_cast<double>(sv.p99) / sr.p99,
                           static_cast<double>(sv.p999) / sr.p999);
            if (refl_lost) fmt::print("  reflector: {} frames lost\n", refl_lost);
        } else {
            print_summary("vecat", sv);
            if (soak_refl) {
                Summary sr = summarize(rt_refl);
                print_summary("reflector", sr);
            }
        }
        if (period_ns) {
            Summary sw = summarize(wake);
            fmt::print("  master wake-up lateness: median {:.2f} us, p99.9 {:.2f} us, max {:.2f} us\n",
                       sw.p50 / 1e3, sw.p999 / 1e3, sw.max / 1e3);
        }
        if (g_interrupted) fmt::print("interrupted after {} cycles\n", done);
        fmt::print("vecat: {} cycles, {} working-counter misses (timeout {} us), {} late replies (> {} us)\n",
                   c_vecat, misses, timeout_us, late, static_cast<double>(late_ns) / 1000.0);
        if (misses)
            fmt::print(
                "  of the misses {} without reply in time, {} with a wrong working counter{}\n", no_reply,
                misses - no_reply,
                misses > no_reply ? fmt::format(" (lowest {} of {})", worst_wkc, m.expected_wkc()) : "");
        if (soak_refl)
            fmt::print("reflector: {} cycles, {} frames without reply in time, {} late replies\n", c_vecat,
                       refl_lost, refl_late);
        for (const Miss& x : miss_log)
            fmt::print("  miss at cycle {} ({}): exchange {:.2f} us, master woke {:.2f} us late\n", x.cycle,
                       x.reflector ? "reflector" : "vecat", static_cast<double>(x.exchange_ns) / 1e3,
                       static_cast<double>(x.wake_ns) / 1e3);
        fmt::print("host: {} ms of CPU time stolen by the hypervisor during the run (/proc/stat steal)\n",
                   steal);
        auto secs = [](const timeval& a, const timeval& b) {
            return static_cast<double>(b.tv_sec - a.tv_sec) +
                   static_cast<double>(b.tv_usec - a.tv_usec) * 1e-6;
        };
        const double tv = secs(ru0.ru_utime, ru1.ru_utime) + secs(ru0.ru_stime, ru1.ru_stime);
        fmt::print(
            "  serve thread CPU: {:.3f} s in {:.3f} s = {:.1f} % of a core{}; whole process {:.1f} %\n",
            static_cast<double>(cpu_srv) / 1e9, static_cast<double>(wall) / 1e9,
            100.0 * static_cast<double>(cpu_srv) / static_cast<double>(wall),
            latency ? " (includes the reflector phases, parked)" : "",
            100.0 * tv / (static_cast<double>(wall) / 1e9));
        if (firmware) {
            fmt::print(
                "  firmware on {} threads: {} groups of slaves run by the workers (the rest by the serve "
                "thread); the whole process's figure includes the workers\n",
                firmware->threads(), firmware->items_on_workers());
            fmt::print(
                "  the serve thread waited {} times {} us or more for items a worker had claimed; "
                "longest wait {:.1f} us\n",
                firmware->long_waits(), esc::FirmwareThreads::kLongWaitNs / 1000,
                static_cast<double>(firmware->longest_wait_ns()) / 1e3);
        }
        // Busy-polling, a loop pass is a poll, not a wake-up: the figure means something only when blocking.
        if (c_vecat > 0 && !o.busy)
            fmt::print(
                "  serve loop per vecat cycle: {:.2f} wake-ups, {:.2f} frames, {:.2f} firmware runs without "
                "a frame (deadlines, catch-up ticks; catch-up period at the end {} us)\n",
                static_cast<double>(wakeups) / static_cast<double>(c_vecat),
                static_cast<double>(frames) / static_cast<double>(c_vecat),
                static_cast<double>(ticks) / static_cast<double>(c_vecat),
                serve_count.catch_up_ns.load() / 1000);
        if (c_vecat > 0)
            fmt::print(
                "  frames that arrived while a tick ran: {:.2f} per cycle, waiting {:.1f} us on average\n",
                static_cast<double>(behind) / static_cast<double>(c_vecat),
                behind ? static_cast<double>(behind_ns) / static_cast<double>(behind) / 1000.0 : 0.0);
        if (log_cycles) bench::write_cycle_log(o.cycle_log, rows);
        if (misses) rc = 1;
    }
    stop = true;
    server.join();
    reflector.join();
    // (After the serve loop stopped: its thread writes these.) All cycles, the warm-up's included.
    const esc::SegmentCounters& sc = seg->counters();
    if (sc.frames > 0)
        fmt::print(
            "  segment: {} frames, {} firmware runs of a slave, {} frames answered while the firmware of "
            "frames before them was still to run ({} of them while it ran on the firmware threads; the "
            "firmware of {} frames in {} batches there)\n",
            sc.frames, sc.firmware_runs, sc.past_deferred_firmware, sc.beside_firmware, sc.background_frames,
            sc.background_batches);
    return rc;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"vecat-roundtrip: cyclic round trips over veth, vecat against a raw reflector"};
    Options o;
    app.add_option("--mode", o.mode,
                   "latency: vecat against the reflector; soak: vecat alone, misses counted")
        ->check(CLI::IsMember({"latency", "soak"}));
    app.add_option("--cycles", o.cycles, "Cycles (default 20000 latency, 10000 soak)");
    app.add_option("--period-us", o.period_us, "Cycle period in us (0: back to back)");
    auto* slaves =
        app.add_option("--slaves", o.slaves, "Virtual drives on the line")->check(CLI::Range(1u, 512u));
    app.add_option("--network", o.network,
                   "Serve the devices of this network file instead of a line of drives")
        ->excludes(slaves);
    app.add_flag("--busy-poll,!--blocking", o.busy, "Spin on the sockets (default: sleep in poll)");
    app.add_flag("--rx-ring", o.rx_ring,
                 "All four sockets receive through PACKET_MMAP rings (default: one recvmsg per frame)");
    app.add_option("--threads", o.threads, "Threads that run the slaves' firmware (as vecat run --threads)")
        ->check(CLI::Range(1, 64));
    app.add_option("--spin-us", o.spin_us,
                   "With --threads: how long a firmware worker spins without work before it sleeps")
        ->capture_default_str();
    app.add_option("--cpu", o.cpu, "Pin the master thread to CPU M and the server threads to S: M,S");
    app.add_option("--fifo", o.fifo, "SCHED_FIFO priority of all threads (1..99)")->check(CLI::Range(0, 99));
    app.add_flag("--mlock", o.mlock, "Lock all memory (mlockall)");
    app.add_option("--timeout-us", o.timeout_us,
                   "Reply deadline; later counts as a miss (default: the period)");
    app.add_option("--late-us", o.late_us, "A reply later than this is late (default: half the period)");
    app.add_flag("!--no-dc", o.dc, "No DC: LRW only, no FRMW");
    app.add_flag("--with-reflector", o.with_reflector,
                 "Soak: every cycle also sends the same frames to the raw reflector, whose losses are "
                 "counted apart (the floor under the same conditions)");
    app.add_option(
        "--tick-us", o.tick_us,
        "The slaves' local cycle and shortest firmware tick between frames (as vecat run --tick-us)");
    app.add_option("--catch-up-us", o.catch_up_us,
                   "Budget of firmware work a frame may find waiting (net::ServeOptions::catch_up_budget_us)")
        ->check(CLI::Range(10, 100000));
    app.add_option("--cycle-log", o.cycle_log,
                   "Soak: write a line per cycle to this CSV file (how late the master woke, both exchanges, "
                   "the serve thread's CPU time and wake-ups, its long waits for a worker), to see what a "
                   "run of misses looked like");
    CLI11_PARSE(app, argc, argv);
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    return run(o);
}
