// Chained segments end to end: three vecat processes in a private network namespace form one line over
// veth pairs (master - A - B - C, each `vecat run --iface IN --downstream OUT` but the last), and the
// project's master finds the same line as on one process emulating all the slaves.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "master/master.hpp"
#include "net/netns.hpp"
#include "net/raw_socket.hpp"

extern char** environ;

using namespace vecat;
using esc::AlState;

namespace {

bool g_netns = false;

// One `vecat run` serving on iface (and passing frames on to downstream when given).
struct Vecat {
    pid_t pid = -1;
    Vecat(const std::string& iface, unsigned slaves, const std::string& downstream = {}) {
        std::vector<std::string> args{VECAT_BINARY, "run",      "--iface",
                                      iface,        "--slaves", std::to_string(slaves)};
        if (!downstream.empty()) args.insert(args.end(), {"--downstream", downstream});
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
    for (int i = 0; i < 200; ++i)
        r.good_cycles += m.exchange_process_data().value_or(0) == r.expected_wkc;
    r.max_sys_diff = m.max_system_time_difference().value_or(~0u);
    EXPECT_TRUE(m.request_state(AlState::Init));
    return r;
}

}  // namespace

TEST(ChainVeth, ThreeProcessesFormTheSameLineAsOne) {
    if (!g_netns) GTEST_SKIP() << "needs root for a private network namespace";
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

int main(int argc, char** argv) {
    std::string why;
    g_netns = net::enter_private_netns(&why);
    if (!g_netns) std::fprintf(stderr, "veth tests skipped: %s\n", why.c_str());
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
