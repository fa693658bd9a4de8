// `vecat exec`: the command runs in a private namespace where vecat serves the slaves; its exit status comes
// back; nothing it started outlives it, also when vecat is killed; an ordinary user can do all of it
// (unprivileged user namespaces). Run as root, the test also runs vecat exec as an ordinary user it creates.
#include <gtest/gtest.h>
#include <pwd.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "child_process.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using vecat::test::ChildProcess;

const std::string kVecat = VECAT_BINARY;
const std::string kProbe = VECAT_EXEC_PROBE;

std::string temp_path(const std::string& name) {
    return (fs::temp_directory_path() / (name + "-" + std::to_string(::getpid()))).string();
}

std::string read_file(const std::string& path) {
    std::ifstream f(path);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

struct Result {
    int status = -1;
    std::string output;
};

// Runs args to its end (at most 60 s), standard output and error together.
Result run(std::vector<std::string> args) {
    const auto out = temp_path("vecat-exec-out");
    Result r;
    ChildProcess p(std::move(args), out);
    r.status = p.wait_for(60s).value_or(-1);
    r.output = read_file(out);
    fs::remove(out);
    return r;
}

// The pids of processes whose command line is exactly "sleep <marker>".
std::vector<pid_t> sleepers(const std::string& marker) {
    std::vector<pid_t> found;
    const std::string want = std::string("sleep") + '\0' + marker + '\0';
    for (const auto& e : fs::directory_iterator("/proc")) {
        const auto name = e.path().filename().string();
        if (name.find_first_not_of("0123456789") != std::string::npos) continue;
        if (read_file(e.path().string() + "/cmdline") == want) found.push_back(std::stoi(name));
    }
    return found;
}

bool eventually(const std::function<bool()>& f, std::chrono::milliseconds limit = 10s) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (!f()) {
        if (std::chrono::steady_clock::now() > deadline) return false;
        std::this_thread::sleep_for(20ms);
    }
    return true;
}

bool user_namespaces_usable() {
    return run({"/usr/bin/unshare", "-Urn", "true"}).status == 0;
}

#define SKIP_WITHOUT_NAMESPACES()                                                                        \
    do {                                                                                                 \
        if (::geteuid() != 0 && !user_namespaces_usable()) {                                             \
            GTEST_SKIP() << "neither root nor unprivileged user namespaces: vecat exec cannot make its " \
                            "namespace";                                                                 \
        }                                                                                                \
    } while (0)

TEST(Exec, TheCommandScansTheServedSlavesOnTheInterfaceItIsGiven) {
    SKIP_WITHOUT_NAMESPACES();
    const auto r = run({kVecat, "exec", "-n", "2", "--", kProbe, "{iface}", "2"});
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("slave 2: station 0x1002, vendor 0x00000A3C"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("100 of 100 cycles"), std::string::npos) << r.output;
    // The interface also comes as VECAT_IFACE.
    const auto e = run({kVecat, "exec", "--", "/bin/sh", "-c", "test \"$VECAT_IFACE\" = vecat-m"});
    EXPECT_EQ(e.status, 0) << e.output;
}

TEST(Exec, TheReportOnTheMasterIsWrittenAndFailsTheRunWhenTheMasterBrokeARule) {
    SKIP_WITHOUT_NAMESPACES();
    const auto xml = temp_path("vecat-report.xml");
    // The project master's start-up and cycles break no rule.
    const auto ok =
        run({kVecat, "exec", "-n", "2", "--report", xml, "--report-fail", "--", kProbe, "{iface}", "2"});
    EXPECT_EQ(ok.status, 0) << ok.output;
    EXPECT_NE(ok.output.find("11 of 11 checks passed"), std::string::npos) << ok.output;
    EXPECT_NE(read_file(xml).find("<testsuite name=\"vecat.master\" tests=\"11\" failures=\"0\""),
              std::string::npos)
        << read_file(xml);
    // A master that writes a read-only register: the command succeeds, the report fails the run.
    const auto bad = run({kVecat, "exec", "-n", "2", "--report", xml, "--report-fail", "--", kProbe,
                          "{iface}", "2", "--break-a-rule"});
    EXPECT_EQ(bad.status, 3) << bad.output;
    EXPECT_NE(bad.output.find("read-only-write"), std::string::npos) << bad.output;
    EXPECT_NE(read_file(xml).find("failures=\"1\""), std::string::npos) << read_file(xml);
    // Without --report-fail the report is only a report.
    EXPECT_EQ(
        run({kVecat, "exec", "-n", "2", "--report", xml, "--", kProbe, "{iface}", "2", "--break-a-rule"})
            .status,
        0);
    fs::remove(xml);
}

// Cable redundancy under vecat exec: a redundant master gets both ports ({iface} {iface2}, VECAT_IFACE2);
// a cable inside the ring breaks through the control socket and comes back, and no cycle is lost.
TEST(Exec, ARedundantMasterGetsBothPortsAndLosesNoCycleWhenTheRingBreaks) {
    SKIP_WITHOUT_NAMESPACES();
    const auto sock = temp_path("vecat-exec-ring.sock");
    const auto r = run({kVecat, "exec", "-n", "4", "--redundant", "--control", sock, "--", kProbe, "{iface}",
                        "4", "--redundant", "{iface2}"});
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("4 slaves, 300 of 300 cycles with the expected working counter"),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("through a broken one"), std::string::npos) << r.output;
    const auto env = run({kVecat, "exec", "--redundant", "--", "/bin/sh", "-c",
                          "test \"$VECAT_IFACE2\" = vecat-m2 && test \"$0\" = vecat-m2", "{iface2}"});
    EXPECT_EQ(env.status, 0) << env.output;
    // Without --redundant there is no second port: the placeholder stays as it is.
    const auto plain = run({kVecat, "exec", "--", "/bin/sh", "-c",
                            "test -z \"$VECAT_IFACE2\" && test \"$0\" = '{iface2}'", "{iface2}"});
    EXPECT_EQ(plain.status, 0) << plain.output;
}

TEST(Exec, TheExitStatusIsTheCommandsOrSaysWhyItDidNotRun) {
    SKIP_WITHOUT_NAMESPACES();
    EXPECT_EQ(run({kVecat, "exec", "--", "/bin/sh", "-c", "exit 7"}).status, 7);
    const auto missing = run({kVecat, "exec", "--", "vecat-no-such-command"});
    EXPECT_EQ(missing.status, 127);
    EXPECT_NE(missing.output.find("vecat-no-such-command: command not found"), std::string::npos)
        << missing.output;
    const auto not_exec = temp_path("vecat-not-executable");
    std::ofstream(not_exec) << "#!/bin/sh\n";
    fs::permissions(not_exec, fs::perms::owner_read | fs::perms::owner_write);
    EXPECT_EQ(run({kVecat, "exec", "--", not_exec}).status, 126);
    fs::remove(not_exec);
    // A line that cannot be served: vecat's own failure, and the command never runs.
    const auto bad = run({kVecat, "exec", "--esi", "/nonexistent.xml", "--", "/bin/sh", "-c", "echo ran"});
    EXPECT_EQ(bad.status, 125);
    EXPECT_EQ(bad.output.find("ran"), std::string::npos) << bad.output;
}

TEST(Exec, NothingTheCommandStartedOutlivesIt) {
    SKIP_WITHOUT_NAMESPACES();
    const std::string marker = "98765" + std::to_string(::getpid() % 10000);
    const auto r = run({kVecat, "exec", "--", "/bin/sh", "-c", "sleep " + marker + " & exit 3"});
    EXPECT_EQ(r.status, 3) << r.output;
    EXPECT_TRUE(eventually([&] { return sleepers(marker).empty(); }, 2s)) << "a background process survived";
}

TEST(Exec, KilledHalfWayItLeavesNoProcessBehind) {
    SKIP_WITHOUT_NAMESPACES();
    const std::string marker = "87654" + std::to_string(::getpid() % 10000);
    ChildProcess p({kVecat, "exec", "-n", "1", "--", "sleep", marker}, temp_path("vecat-exec-killed"));
    ASSERT_TRUE(eventually([&] { return !sleepers(marker).empty(); })) << "the command never started";
    ::kill(p.pid, SIGKILL);
    p.wait_for(5s);
    // The command, and with it the namespace's last process: the namespaces and the veth pair are gone.
    EXPECT_TRUE(eventually([&] { return sleepers(marker).empty(); }, 2s)) << "the command survived vecat";
    fs::remove(temp_path("vecat-exec-killed"));
}

TEST(Exec, ASignalToVecatGoesToTheCommand) {
    SKIP_WITHOUT_NAMESPACES();
    const std::string marker = "76543" + std::to_string(::getpid() % 10000);
    ChildProcess p({kVecat, "exec", "--", "sleep", marker}, temp_path("vecat-exec-term"));
    ASSERT_TRUE(eventually([&] { return !sleepers(marker).empty(); }));
    ::kill(p.pid, SIGTERM);
    const auto rc = p.wait_for(10s);
    ASSERT_TRUE(rc.has_value());
    EXPECT_EQ(*rc, 128 + SIGTERM);  // sleep ended by the signal; vecat returns its status
    EXPECT_TRUE(sleepers(marker).empty());
    fs::remove(temp_path("vecat-exec-term"));
}

// What issue 30 asks of CI: an ordinary user runs a master against vecat without root.
TEST(Exec, AnOrdinaryUserNeedsNoRoot) {
    if (::geteuid() != 0) {
        // Already an ordinary user: the other tests ran as one.
        SKIP_WITHOUT_NAMESPACES();
        EXPECT_EQ(run({kVecat, "exec", "-n", "2", "--", kProbe, "{iface}", "2"}).status, 0);
        return;
    }
    const char* user = "vecat-ci";
    const bool created = ::getpwnam(user) == nullptr;
    if (created) {
        ASSERT_EQ(run({"/usr/sbin/useradd", "--system", "--no-create-home", user}).status, 0);
    }
    // The build tree may sit where the user cannot reach (under /root): the two programs go to a directory
    // of their own.
    const fs::path dir = temp_path("vecat-exec-user");
    fs::create_directories(dir);
    fs::copy_file(kVecat, dir / "vecat", fs::copy_options::overwrite_existing);
    fs::copy_file(kProbe, dir / "probe", fs::copy_options::overwrite_existing);
    fs::permissions(dir, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                             fs::perms::others_read | fs::perms::others_exec);
    const auto who = run({"/usr/sbin/runuser", "-u", user, "--", "/usr/bin/id", "-u"});
    const auto uns = run({"/usr/sbin/runuser", "-u", user, "--", "/usr/bin/unshare", "-Urn", "true"});
    if (uns.status != 0) {
        fs::remove_all(dir);
        if (created) run({"/usr/sbin/userdel", user});
        GTEST_SKIP() << "unprivileged user namespaces are not allowed here: " << uns.output;
    }
    const auto r = run({"/usr/sbin/runuser", "-u", user, "--", (dir / "vecat").string(), "exec", "-n", "2",
                        "--", (dir / "probe").string(), "{iface}", "2"});
    EXPECT_NE(who.output, "0\n");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("2 slaves, 100 of 100 cycles"), std::string::npos) << r.output;
    // The Python kit's own tests (python/tests: the pytest fixture), as the same user.
    if (run({"/usr/bin/python3", "-c", "import pytest"}).status == 0) {
        fs::copy(fs::path(VECAT_SOURCE_DIR) / "python", dir / "python", fs::copy_options::recursive);
        fs::permissions(dir / "python", fs::perms::all, fs::perm_options::add);
        for (const auto& e : fs::recursive_directory_iterator(dir / "python"))
            fs::permissions(e.path(), fs::perms::others_read | fs::perms::others_exec, fs::perm_options::add);
        const auto py = run({"/usr/sbin/runuser", "-u", user, "--", (dir / "vecat").string(), "exec",
                             "--no-network", "--", "/usr/bin/python3", "-m", "pytest", "-q", "-p",
                             "no:cacheprovider", (dir / "python" / "tests").string()});
        EXPECT_EQ(py.status, 0) << py.output;
        // Every test of the kit ran (none skipped for want of a namespace) and passed.
        EXPECT_NE(py.output.find(" passed"), std::string::npos) << py.output;
        EXPECT_EQ(py.output.find("skipped"), std::string::npos) << py.output;
        EXPECT_EQ(py.output.find("failed"), std::string::npos) << py.output;
    }
    fs::remove_all(dir);
    if (created) run({"/usr/sbin/userdel", user});
}

}  // namespace
