// Fault injection end to end: `vecat run --scenario FILE --control SOCKET` on a veth pair in a private
// network namespace, the project's master on the other end, `vecat fault ...` on the control socket.
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "child_process.hpp"
#include "master/master.hpp"
#include "net/netns.hpp"
#include "net/raw_socket.hpp"
#include "test_support.hpp"

using namespace vecat;
using protocol::AlState;

namespace {

bool g_netns = false;

using Process = test::ChildProcess;

std::string temp(const std::string& name) {
    return (std::filesystem::temp_directory_path() / (name + "-" + std::to_string(getpid()))).string();
}

TEST(VethFaults, ScenarioCutsTheLineAndTheControlSocketRepairsIt) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    std::string why;
    ASSERT_TRUE(net::create_veth_pair("fm", "fs", &why)) << why;
    const std::string scenario = temp("vecat-scenario") + ".yaml", sock_path = temp("vecat-faults") + ".sock";
    {
        std::ofstream f(scenario);
        // Frames 0-4 see the whole line, then it is cut behind slave 1.
        f << "events:\n  - at_cycle: 5\n    start: link_down\n    id: cut\n    slave: 1\n    port: 1\n";
    }
    Process vecat({VECAT_BINARY, "run", "--iface", "fs", "--slaves", "3", "--scenario", scenario, "--control",
                   sock_path});
    ASSERT_GT(vecat.pid, 0);
    for (int i = 0; i < 50 && !std::filesystem::exists(sock_path); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    net::RawSocket sock("fm");
    master::Master m(sock);
    for (int i = 0; i < 5; ++i)
        EXPECT_EQ(m.count_slaves(), 3) << "frame " << i;
    EXPECT_EQ(m.count_slaves(), 2);  // frame 5: the scenario's cable break

    auto fault = [&](const std::string& args) {
        return test::run_capture(std::string(VECAT_BINARY) + " fault " + args + " --socket " + sock_path +
                                 " 2>&1");
    };
    EXPECT_EQ(fault("list"), "ok 1 active\ncut link_down port=1 slave=1\n");
    EXPECT_EQ(fault("clear cut"), "ok 1 cleared\n");
    EXPECT_EQ(m.count_slaves(), 3);

    // An AL error forced from the command line, as the master reads it.
    ASSERT_TRUE(m.startup(AlState::PreOp, &why)) << why;
    EXPECT_EQ(fault("inject al_error slave=2 code=0x0021"), "ok al_error#1\n");
    const auto s = m.read_al_status(m.slaves()[2].station);
    ASSERT_TRUE(s.ok);
    EXPECT_TRUE(s.error());
    EXPECT_EQ(s.code, 0x0021);
    EXPECT_EQ(s.state(), AlState::PreOp);
    EXPECT_NE(fault("inject warp_drive slave=0").find("error"), std::string::npos);
    std::filesystem::remove(scenario);
}

}  // namespace

int main(int argc, char** argv) {
    std::string why;
    g_netns = net::enter_private_netns(&why);
    if (!g_netns) std::fprintf(stderr, "veth fault tests skipped: %s\n", why.c_str());
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
