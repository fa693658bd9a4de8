// `vecat demo` end to end: the program makes its own network namespace and veth pair (root needed, the
// tests skip otherwise), runs every phase and writes its files; Ctrl-C part-way still stops it cleanly.
#include <gtest/gtest.h>

#include <signal.h>
#include <unistd.h>
#include <cstdlib>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "child_process.hpp"
#include "device/device_description.hpp"
#include "esc/sii_image.hpp"
#include "esi/esi_reader.hpp"
#include "pcapng_reader.hpp"
#include "telemetry/recording.hpp"

using namespace vecat;
namespace fs = std::filesystem;

namespace {

const char* const kPhases[] = {"scan",   "preop",    "pdo-mapping", "dc",    "safeop",  "op",
                               "enable", "csp-move", "homing",      "fault", "disable", "init"};

std::string read_text(const fs::path& p) {
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

// The files every run writes, checked for content: capture, ESI, SII, scope.
void expect_files(const fs::path& dir) {
    const auto frames = test::read_pcapng_frames((dir / "demo.pcapng").string());
    EXPECT_GT(frames.size(), 100u);
    for (const auto& f : frames) {
        ASSERT_GE(f.size(), 14u);
        EXPECT_EQ(f[12] << 8 | f[13], 0x88A4) << "every captured frame is EtherCAT";
    }
    const auto dev = device::default_drive();
    const auto esi = esi::import_esi_file((dir / "vecat-drive.xml").string());
    EXPECT_EQ(esi.desc.identity.vendor_id, dev.identity.vendor_id);
    EXPECT_EQ(esi.desc.identity.product_code, dev.identity.product_code);
    EXPECT_EQ(esi.desc.identity.revision, dev.identity.revision);
    std::ifstream f(dir / "vecat-drive.sii", std::ios::binary);
    const std::vector<std::uint8_t> sii((std::istreambuf_iterator<char>(f)),
                                        std::istreambuf_iterator<char>());
    EXPECT_EQ(sii, esc::build_sii_image(dev));
    const auto info = protocol::parse_sii(sii);
    EXPECT_EQ(info.identity.vendor_id, dev.identity.vendor_id);
    EXPECT_EQ(info.identity.product_code, dev.identity.product_code);
    EXPECT_GT(fs::file_size(dir / "scope.csv"), 1000u);
    EXPECT_GT(fs::file_size(dir / "scope.svg"), 1000u);
}

// The demo makes its own network namespace: as root, or as an ordinary user in an unprivileged user
// namespace of its own (net::enter_private_netns).
bool namespaces_usable() {
    return geteuid() == 0 || std::system("/usr/bin/unshare -Urn true >/dev/null 2>&1") == 0;
}

}  // namespace

TEST(Demo, RunsEveryPhaseAndWritesItsFiles) {
    if (!namespaces_usable())
        GTEST_SKIP() << "needs root or unprivileged user namespaces for its network namespace";
    const fs::path dir = fs::temp_directory_path() / ("vecat-demo-test-" + std::to_string(getpid()));
    fs::remove_all(dir);
    const std::string log = dir.string() + ".log";
    test::ChildProcess demo({VECAT_BINARY, "demo", "--cycles", "300", "-o", dir.string()}, log);
    const auto rc = demo.wait_for(std::chrono::seconds(60));
    const std::string out = read_text(log);
    ASSERT_TRUE(rc.has_value()) << "still running after 60 s:\n" << out;
    EXPECT_EQ(*rc, 0) << out;
    // Each phase announced, then done; nothing failed.
    std::size_t at = 0;
    for (const char* p : kPhases) {
        at = out.find(std::string("] ") + p + ":", at);
        ASSERT_NE(at, std::string::npos) << "phase " << p << " missing:\n" << out;
        EXPECT_NE(out.find("done in", at), std::string::npos) << p;
    }
    EXPECT_EQ(out.find("FAILED"), std::string::npos) << out;
    EXPECT_NE(out.find("12 of 12 phases"), std::string::npos) << out;
    EXPECT_NE(out.find("homing attained"), std::string::npos) << out;
    EXPECT_NE(out.find("error code 0x603F = 0x8611"), std::string::npos) << out;
    expect_files(dir);
    fs::remove_all(dir);
    fs::remove(log);
}

TEST(Demo, CtrlCStopsItCleanlyAndStillWritesTheFiles) {
    if (!namespaces_usable())
        GTEST_SKIP() << "needs root or unprivileged user namespaces for its network namespace";
    const fs::path dir = fs::temp_directory_path() / ("vecat-demo-sigint-" + std::to_string(getpid()));
    fs::remove_all(dir);
    const std::string log = dir.string() + ".log";
    // The default move takes 3 s: Ctrl-C lands in the middle of it.
    test::ChildProcess demo({VECAT_BINARY, "demo", "-o", dir.string()}, log);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (read_text(log).find("csp-move:") == std::string::npos) {
        ASSERT_LT(std::chrono::steady_clock::now(), deadline) << read_text(log);
        ASSERT_FALSE(demo.wait_for(std::chrono::milliseconds(0)).has_value()) << read_text(log);
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const auto t0 = std::chrono::steady_clock::now();
    kill(demo.pid, SIGINT);
    const auto rc = demo.wait_for(std::chrono::seconds(5));
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::string out = read_text(log);
    ASSERT_TRUE(rc.has_value()) << "still running 5 s after SIGINT:\n" << out;
    EXPECT_EQ(*rc, 130) << out;  // 128 + SIGINT, as documented
    EXPECT_LT(s, 5.0);
    EXPECT_NE(out.find("interrupted by signal 2 in phase csp-move"), std::string::npos) << out;
    EXPECT_NE(out.find("line INIT"), std::string::npos) << out;
    EXPECT_EQ(out.find("homing:"), std::string::npos) << "no phase runs after the signal";
    expect_files(dir);
    fs::remove_all(dir);
    fs::remove(log);
}

// `vecat demo --network`: a coupler, an output terminal whose channels are wired to an input terminal, and a
// drive. The demo finds the drive by its device type and its objects by the mapping it reads, moves it, and
// writes a walking bit to the outputs, which the wired inputs show.
TEST(Demo, OnANetworkFileItMovesTheDrivesAndExercisesTheIo) {
    if (!namespaces_usable())
        GTEST_SKIP() << "needs root or unprivileged user namespaces for its network namespace";
    const fs::path dir = fs::temp_directory_path() / ("vecat-demo-net-" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path file = dir / "machine.yaml";
    std::ofstream(file) << R"(devices:
  - name: coupler
    device: coupler
  - name: valves
    device: digital-out
    channels: 4
    upstream: coupler:3
  - name: sensors
    device: digital-in
    channels: 4
    inputs:
      0: {wire: valves:0}
      1: {wire: valves:1}
      2: {wire: valves:2}
      3: {wire: valves:3}
  - name: axis
    device: drive
    upstream: coupler:1
)";
    const std::string log = dir.string() + ".log";
    test::ChildProcess demo(
        {VECAT_BINARY, "demo", "--network", file.string(), "--cycles", "300", "-o", (dir / "out").string()},
        log);
    const auto rc = demo.wait_for(std::chrono::seconds(60));
    const std::string out = read_text(log);
    ASSERT_TRUE(rc.has_value()) << "still running after 60 s:\n" << out;
    EXPECT_EQ(*rc, 0) << out;
    EXPECT_EQ(out.find("FAILED"), std::string::npos) << out;
    EXPECT_NE(out.find("11 of 11 phases"), std::string::npos) << out;
    EXPECT_NE(out.find("on slave 0 port 3"), std::string::npos) << "the topology, from the DL status:\n"
                                                                << out;
    EXPECT_NE(out.find("1 drive(s) to move, 2 I/O device(s)"), std::string::npos) << out;
    EXPECT_NE(out.find("all drives enabled"), std::string::npos) << out;
    EXPECT_NE(out.find(" 0 working-counter misses"), std::string::npos) << out;
    // The walking bit over four channels in 800 cycles: the wired inputs change as the outputs do.
    const auto at = out.find("inputs changed ");
    ASSERT_NE(at, std::string::npos) << out;
    EXPECT_GE(std::stoi(out.substr(at + 15)), 4) << out;
    EXPECT_GT(test::read_pcapng_frames((dir / "out" / "demo.pcapng").string()).size(), 100u);
    // The scope has the I/O lanes (one per channel: valves' outputs, sensors' inputs), and the samples show
    // the wired inputs following the walking bit of the outputs.
    const std::string svg = read_text((dir / "out" / "scope.svg").string());
    for (const char* lane : {"io.in0", "io.in3", "io.out0", "io.out3"})
        EXPECT_NE(svg.find(lane), std::string::npos) << lane;
    telemetry::Recording rec;
    std::string why;
    ASSERT_TRUE(telemetry::read_csv((dir / "out" / "scope.csv").string(), rec, &why)) << why;
    unsigned out_high = 0, in_high = 0;
    for (const auto& s : rec.io) {
        out_high += static_cast<unsigned>(s.out_channels == 4 && s.out[2] != 0);  // valves
        in_high += static_cast<unsigned>(s.in_channels == 4 && s.in[2] != 0);     // sensors
    }
    EXPECT_GT(out_high, 0u);
    EXPECT_GT(in_high, 0u);
    fs::remove_all(dir);
    fs::remove(log);
}

// A network file the demo cannot build is refused before anything runs, naming the line.
TEST(Demo, ABadNetworkFileIsRefusedWithItsLine) {
    const fs::path file =
        fs::temp_directory_path() / ("vecat-demo-bad-" + std::to_string(getpid()) + ".yaml");
    std::ofstream(file) << "devices:\n  - name: a\n    device: drive\n  - name: b\n    device: teapot\n";
    const std::string log = file.string() + ".log";
    test::ChildProcess demo({VECAT_BINARY, "demo", "--network", file.string(), "-o", "/nonexistent/x"}, log);
    const auto rc = demo.wait_for(std::chrono::seconds(20));
    const std::string out = read_text(log);
    ASSERT_TRUE(rc.has_value()) << out;
    EXPECT_EQ(*rc, 2) << out;
    EXPECT_NE(out.find(":5:"), std::string::npos) << "names line 5:\n" << out;
    fs::remove(file);
    fs::remove(log);
}
