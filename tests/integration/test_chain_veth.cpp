// Chained segments end to end: three vecat processes in a private network namespace form one line over
// veth pairs (master - A - B - C, each `vecat run --iface IN --downstream OUT` but the last), and the
// project's master finds the same line as on one process emulating all the slaves.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "master/master.hpp"
#include "net/netns.hpp"
#include "net/raw_socket.hpp"

extern char** environ;

using namespace vecat;
using protocol::AlState;

namespace {

bool g_netns = false;

// One `vecat run` serving on iface (and passing frames on to downstream when given).
struct Vecat {
    pid_t pid = -1;
    Vecat(const std::string& iface, unsigned slaves, const std::string& downstream = {})
        : Vecat(iface, slaves,
                downstream.empty() ? std::vector<std::string>{}
                                   : std::vector<std::string>{"--downstream", downstream}) {}
    Vecat(const std::string& iface, unsigned slaves, const std::vector<std::string>& extra) {
        std::vector<std::string> args{VECAT_BINARY, "run",      "--iface",
                                      iface,        "--slaves", std::to_string(slaves)};
        args.insert(args.end(), extra.begin(), extra.end());
        std::vector<char*> argv;
        for (auto& a : args)
            argv.push_back(a.data());
        argv.push_back(nullptr);
        if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) pid = -1;
    }
    int stop() {
        if (pid <= 0) return -1;
        kill(pid, SIGINT);
        int st = 0;
        waitpid(pid, &st, 0);
        pid = -1;
        return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    }
    ~Vecat() {
        if (pid > 0) stop();
    }
};

struct LineResult {
    int count = 0;
    std::vector<master::SlaveInfo> slaves;
    std::uint16_t expected_wkc = 0;
    unsigned good_cycles = 0;
    std::uint32_t max_sys_diff = 0;
    double cycle_us = 0;  // mean round trip of a process data frame
};

// Start-up to OP with DC delays and offsets (no SYNC0), identities, 200 process data cycles, and back.
LineResult bring_up(const std::string& iface) {
    LineResult r;
    net::RawSocket sock(iface);
    master::MasterOptions o;
    o.dc.enable = true;
    o.dc.sync0_cycle_ns = 0;
    o.dc.static_drift_frames = 200;
    // Each process latches its receive times when the frame reaches it, tens of microseconds apart on a
    // loaded machine: 0x092C follows the jitter of that transit (see DEVELOPERS.md, chained segments).
    o.dc.max_sync_diff_ns = 200'000;
    master::Master m(sock, o);
    r.count = m.count_slaves();
    std::string why;
    EXPECT_TRUE(m.startup(AlState::Op, &why)) << why;
    r.slaves = m.slaves();
    r.expected_wkc = m.expected_wkc();
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < 200; ++i)
        r.good_cycles += m.exchange_process_data().value_or(0) == r.expected_wkc;
    r.cycle_us =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / 200;
    r.max_sys_diff = m.max_system_time_difference().value_or(~0u);
    EXPECT_TRUE(m.request_state(AlState::Init));
    return r;
}

}  // namespace

TEST(ChainVeth, ThreeProcessesFormTheSameLineAsOne) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    std::string why;
    // master - A (2 slaves) - B (1 slave) - C (2 slaves); and a reference pair for one process of 5.
    for (auto [x, y] : {std::pair{"chm", "cha"}, std::pair{"chao", "chb"}, std::pair{"chbo", "chc"},
                        std::pair{"chrm", "chrs"}})
        ASSERT_TRUE(net::create_veth_pair(x, y, &why)) << why;
    Vecat one("chrs", 5);
    Vecat c("chc", 2), b("chb", 1, "chbo"), a("cha", 2, "chao");
    ASSERT_GT(one.pid, 0);
    ASSERT_GT(a.pid, 0);
    ASSERT_GT(b.pid, 0);
    ASSERT_GT(c.pid, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(400));

    const auto t0 = std::chrono::steady_clock::now();
    const LineResult ref = bring_up("chrm");
    const auto t1 = std::chrono::steady_clock::now();
    const LineResult r = bring_up("chm");
    const auto t2 = std::chrono::steady_clock::now();
    std::printf(
        "[ ChainVeth ] start-up + 200 cycles: one process %.2f s, three processes %.2f s; |0x092C| "
        "%u ns vs %u ns\n",
        std::chrono::duration<double>(t1 - t0).count(), std::chrono::duration<double>(t2 - t1).count(),
        ref.max_sys_diff, r.max_sys_diff);

    std::printf("[ ChainVeth ] process data round trip: one process %.1f us, three processes %.1f us\n",
                ref.cycle_us, r.cycle_us);
    EXPECT_EQ(ref.count, 5);
    EXPECT_EQ(r.count, ref.count);
    ASSERT_EQ(r.slaves.size(), ref.slaves.size());
    for (std::size_t i = 0; i < r.slaves.size(); ++i) {
        const auto &s = r.slaves[i], &x = ref.slaves[i];
        EXPECT_EQ(s.position, x.position) << i;
        EXPECT_EQ(s.station, x.station) << i;
        EXPECT_EQ(s.sii.identity.vendor_id, x.sii.identity.vendor_id) << i;
        EXPECT_EQ(s.sii.identity.product_code, x.sii.identity.product_code) << i;
        EXPECT_EQ(s.sii.identity.revision, x.sii.identity.revision) << i;
        EXPECT_EQ(s.sii.identity.serial, x.sii.identity.serial) << i;
        EXPECT_EQ(s.dl_status, x.dl_status) << i;
        EXPECT_EQ(s.out_bytes, x.out_bytes) << i;
        EXPECT_EQ(s.dc_delay_ns, x.dc_delay_ns) << i;
    }
    EXPECT_EQ(r.expected_wkc, ref.expected_wkc);
    EXPECT_EQ(ref.good_cycles, 200u);
    EXPECT_EQ(r.good_cycles, 200u);
    // Unplugged behind B (C's end of the cable goes down): B closes the line, which now ends after three
    // slaves; plugged in again, C is back.
    auto count = [] {
        net::RawSocket sock("chm");
        master::Master m(sock);
        return m.count_slaves();
    };
    ASSERT_EQ(system("ip link set chc down"), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // vecat looks at the link every 10 ms
    EXPECT_EQ(count(), 3);
    ASSERT_EQ(system("ip link set chc up"), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    EXPECT_EQ(count(), 5);
    EXPECT_EQ(a.stop(), 0);
    EXPECT_EQ(b.stop(), 0);
    EXPECT_EQ(c.stop(), 0);
    EXPECT_EQ(one.stop(), 0);
}

// A measurement, not a check (run it with --gtest_also_run_disabled_tests): the time control loops of
// drifting clocks (+-50 ppm) in three processes against one, 2 s of reference clock distribution at 1 ms
// in OP; prints the worst |0x092C| of the line every 100 ms after the first second.
TEST(ChainVeth, DISABLED_SystemTimeDifferenceAcrossProcesses) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    std::string why;
    for (auto [x, y] : {std::pair{"dhm", "dha"}, std::pair{"dhao", "dhb"}, std::pair{"dhbo", "dhc"},
                        std::pair{"dhrm", "dhrs"}})
        ASSERT_TRUE(net::create_veth_pair(x, y, &why)) << why;
    auto start = [&](const std::string& in, unsigned n, const std::string& out) {
        std::vector<std::string> extra{"--dc-drift-ppm", "50"};
        if (!out.empty()) extra.insert(extra.end(), {"--downstream", out});
        return std::make_unique<Vecat>(in, n, extra);
    };
    auto one = start("dhrs", 5, ""), c = start("dhc", 2, ""), b = start("dhb", 1, "dhbo"),
         a = start("dha", 2, "dhao");
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    for (const std::string iface : {"dhrm", "dhm"}) {
        net::RawSocket sock(iface);
        master::MasterOptions o;
        o.dc.enable = true;
        o.dc.sync0_cycle_ns = 0;
        o.dc.static_drift_frames = 1000;
        o.dc.max_sync_diff_ns = 200'000;
        master::Master m(sock, o);
        ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
        std::uint32_t worst = 0;
        auto next = std::chrono::steady_clock::now();
        for (int i = 0; i < 2000; ++i) {
            next += std::chrono::milliseconds(1);
            std::this_thread::sleep_until(next);
            m.exchange_process_data();
            if (i >= 1000 && i % 100 == 99)
                if (auto d = m.max_system_time_difference()) worst = std::max(worst, *d);
        }
        std::printf("[ ChainVeth ] %s: worst |0x092C| %u ns\n",
                    iface == "dhm" ? "three processes" : "one process", worst);
        m.request_state(AlState::Init);
    }
}

int main(int argc, char** argv) {
    std::string why;
    g_netns = net::enter_private_netns(&why);
    if (!g_netns) std::fprintf(stderr, "veth tests skipped: %s\n", why.c_str());
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
