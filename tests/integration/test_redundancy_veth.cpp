// Cable redundancy end to end: `vecat run --iface A --redundant-iface B` in a private network namespace,
// the project's master behind a link over two raw sockets that does what a redundant master does (the
// frame out of the primary port, a BRD dummy of the same index out of the secondary one; with the ring
// broken, the primary's result again out of the secondary port). A cable break inside the ring (control
// socket, link_down) and the master's second cable pulled out (the veth end goes down) cost no cycle; the
// ring closes again. An interface in use is refused.
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "faults/control.hpp"
#include "master/master.hpp"
#include "net/netns.hpp"
#include "net/raw_socket.hpp"
#include "protocol/registers.hpp"
#include "redundant_raw_link.hpp"

using namespace vecat;
using protocol::AlState;

namespace {

bool g_netns = false;

// `vecat run ARGS`, stopped with SIGINT at the end of its scope.
std::vector<std::string> vecat_run(std::vector<std::string> args) {
    args.insert(args.begin(), {VECAT_BINARY, "run"});
    return args;
}
constexpr std::chrono::seconds kRefusalWait{10};

std::string control(const std::string& sock, const std::string& cmd) {
    std::string reply;
    if (!faults::send_control_command(sock, cmd, reply)) return "unreachable";
    return reply;
}

}  // namespace

TEST(RedundancyVeth, RingSurvivesABreakAndClosesAgain) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    std::string why;
    for (auto [x, y] : {std::pair{"rdm", "rds"}, std::pair{"rdm2", "rds2"}})
        ASSERT_TRUE(net::create_veth_pair(x, y, &why)) << why;
    const std::string sock = "/tmp/vecat-redundancy-" + std::to_string(getpid()) + ".sock";
    test::ChildProcess v(
        vecat_run({"--iface", "rds", "--redundant-iface", "rds2", "--slaves", "4", "--control", sock}));
    ASSERT_GT(v.pid, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(400));

    test::RedundantRawLink link("rdm", "rdm2");
    master::MasterOptions o;
    o.reply_timeout_us = 20'000;
    master::Master m(link, o);
    ASSERT_EQ(m.count_slaves(), 4);
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    const std::uint16_t expected = m.expected_wkc();
    const auto cycles = [&](int n) {
        int good = 0;
        for (int i = 0; i < n; ++i)
            good += m.exchange_process_data().value_or(0) == expected;
        return good;
    };
    const auto all_in_op = [&] {
        for (std::uint16_t st = 0x1001; st <= 0x1004; ++st) {
            const auto al = m.read16(st, protocol::addr(protocol::Reg::AlStatus));
            if (!al || (*al & 0x1F) != static_cast<std::uint16_t>(AlState::Op)) return false;
        }
        return true;
    };
    EXPECT_EQ(cycles(100), 100);
    EXPECT_GT(link.whole_, 0u);
    EXPECT_EQ(link.broken_, 0u);

    // The cable between slave 1 and slave 2 breaks.
    EXPECT_EQ(control(sock, "inject link_down slave=1 port=1 id=cut").rfind("ok", 0), 0u);
    const unsigned broken_before = link.broken_;
    EXPECT_EQ(cycles(200), 200);
    EXPECT_GE(link.broken_, broken_before + 200);
    EXPECT_TRUE(all_in_op());
    // Auto loop control closed the ports at the break; the lost link counters counted.
    EXPECT_EQ(m.read16(0x1002, protocol::addr(protocol::Reg::LostLinkCounter)).value_or(0) >> 8, 1);
    EXPECT_EQ(m.read16(0x1003, protocol::addr(protocol::Reg::LostLinkCounter)).value_or(0) & 0xFF, 1);

    // The cable is back: the ring is whole again.
    EXPECT_EQ(control(sock, "clear cut").rfind("ok", 0), 0u);
    const unsigned whole_before = link.whole_;
    EXPECT_EQ(cycles(200), 200);
    EXPECT_GE(link.whole_, whole_before + 200);
    EXPECT_TRUE(all_in_op());

    // The master's second cable pulled out: an open line from the primary port.
    ASSERT_EQ(system("ip link set rdm2 down"), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // vecat looks at the carrier every 10 ms
    EXPECT_EQ(cycles(20), 20);
    EXPECT_GT(link.primary_only_, 0u);
    ASSERT_EQ(system("ip link set rdm2 up"), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const unsigned whole_again = link.whole_;
    EXPECT_EQ(cycles(50), 50);
    EXPECT_GE(link.whole_, whole_again + 50);
    EXPECT_TRUE(m.request_state(AlState::Init));
    EXPECT_EQ(v.stop(), 0);
}

TEST(RedundancyVeth, AnInterfaceInUseIsRefused) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    std::string why;
    ASSERT_TRUE(net::create_veth_pair("rum", "rus", &why)) << why;
    ASSERT_TRUE(net::create_veth_pair("rum2", "rus2", &why)) << why;
    EXPECT_EQ(test::ChildProcess(vecat_run({"--iface", "rus", "--redundant-iface", "rus", "--slaves", "2"}))
                  .wait_for(kRefusalWait),
              2);
    EXPECT_EQ(test::ChildProcess(vecat_run({"--iface", "rus", "--redundant-iface", "rus2", "--downstream",
                                            "rum2", "--slaves", "2"}))
                  .wait_for(kRefusalWait),
              2);
}

int main(int argc, char** argv) {
    std::string why;
    g_netns = net::enter_private_netns(&why);
    if (!g_netns) std::fprintf(stderr, "veth tests skipped: %s\n", why.c_str());
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
