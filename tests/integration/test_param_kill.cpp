// A process storing parameters is killed (SIGKILL) at random moments, many times; after every kill the
// parameter file must hold a complete set (the old or the new one, never a mix, never corrupt), and a
// restart must apply it.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <random>
#include <string>
#include <thread>

#include "coe/coe_application.hpp"
#include "coe/parameter_store.hpp"

using namespace vecat;
namespace fs = std::filesystem;

namespace {

constexpr int kRounds = 150;

// Starts the writer and returns once it has loaded its set and begun storing (its first line of output),
// so the kill lands among the stores, not during the start-up.
pid_t start_writer(const std::string& dir) {
    int out[2];
    if (::pipe(out) != 0) return -1;
    const pid_t pid = ::fork();
    if (pid == 0) {
        ::dup2(out[1], STDOUT_FILENO);
        ::close(out[0]);
        ::close(out[1]);
        ::execl(VECAT_PARAM_WRITER, VECAT_PARAM_WRITER, dir.c_str(), static_cast<char*>(nullptr));
        ::_exit(127);
    }
    ::close(out[1]);
    char c = 0;
    while (::read(out[0], &c, 1) == 1 && c != '\n') {
    }
    ::close(out[0]);
    return pid;
}

TEST(ParameterKill, EveryRestartFindsACompleteSet) {
    const fs::path dir = fs::temp_directory_path() / ("vecat-param-kill-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string file = (dir / "slave-0.param").string();
    std::mt19937 rng(12345);
    std::uniform_int_distribution<int> delay_us(0, 10'000);
    std::uint32_t last_generation = 0;
    int progressed = 0, temp_left = 0;
    // At least kRounds rounds, and on until the set has advanced in kRounds / 4 of them (a loaded machine
    // gives the writer less time between start and kill), at most 10 x kRounds.
    int round = 0;
    for (; round < kRounds || (progressed <= kRounds / 4 && round < 10 * kRounds); ++round) {
        const pid_t pid = start_writer(dir.string());
        ASSERT_GT(pid, 0);
        std::this_thread::sleep_for(std::chrono::microseconds(delay_us(rng)));
        ::kill(pid, SIGKILL);
        int status = 0;
        ASSERT_EQ(::waitpid(pid, &status, 0), pid);
        ASSERT_TRUE(WIFSIGNALED(status))
            << "round " << round << ": the writer ended by itself, status " << status;
        if (fs::exists(file + ".tmp")) ++temp_left;

        const auto r = coe::load_parameter_file(file);
        if (r.status == coe::LoadStatus::Missing) {
            ASSERT_EQ(last_generation, 0u) << "round " << round << ": a stored set disappeared";
            continue;
        }
        ASSERT_EQ(r.status, coe::LoadStatus::Loaded) << "round " << round << ": " << r.detail;
        // All seven entries of 0x2000 from the same generation.
        std::uint32_t g = 0;
        int found = 0;
        for (const auto& rec : r.set.records) {
            if (rec.index != 0x2000 || rec.subindex == 0) continue;
            ASSERT_EQ(rec.value.size(), 4u);
            const std::uint32_t v = ld_le32(rec.value.data());
            if (found++ == 0) g = v;
            ASSERT_EQ(v, g) << "round " << round << ": mixed set at 0x2000:" << int(rec.subindex);
        }
        ASSERT_EQ(found, 7) << "round " << round;
        ASSERT_GE(g, last_generation) << "round " << round << ": an older set came back";
        if (g > last_generation) ++progressed;
        last_generation = g;

        // A restart applies it.
        coe::CoeApplication app(device::default_drive());
        const auto rep = app.attach_parameter_store(file);
        ASSERT_EQ(rep.load.status, coe::LoadStatus::Loaded);
        ASSERT_EQ(rep.refused, 0u);
        ASSERT_EQ(app.dictionary().find(0x2000, 7)->get<std::uint32_t>(), g);
    }
    std::printf(
        "%d kill rounds: the set advanced in %d, a temporary file was left by %d, last generation %u\n",
        round, progressed, temp_left, last_generation);
    EXPECT_GT(progressed, kRounds / 4) << "the writer hardly stored anything: the test proves little";
    fs::remove_all(dir);
}

}  // namespace
