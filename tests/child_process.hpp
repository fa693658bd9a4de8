// A program the tests start (usually `vecat run`), stopped with SIGINT like a user's Ctrl-C.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <optional>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace vecat::test {

class ChildProcess {
  public:
    // stdout_path: the child's standard output (and error) go to this file instead of the test's.
    explicit ChildProcess(std::vector<std::string> args, const std::string& stdout_path = {}) {
        std::vector<char*> argv;
        for (auto& a : args)
            argv.push_back(a.data());
        argv.push_back(nullptr);
        posix_spawn_file_actions_t fa;
        posix_spawn_file_actions_init(&fa);
        if (!stdout_path.empty()) {
            posix_spawn_file_actions_addopen(&fa, 1, stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            posix_spawn_file_actions_adddup2(&fa, 1, 2);
        }
        if (posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ) != 0) pid = -1;
        posix_spawn_file_actions_destroy(&fa);
    }
    ChildProcess(const ChildProcess&) = delete;
    ChildProcess& operator=(const ChildProcess&) = delete;
    ~ChildProcess() { stop(); }

    // SIGINT, then waits; the exit code, or -1 if it did not exit normally (or never ran).
    int stop() {
        if (pid <= 0) return -1;
        kill(pid, SIGINT);
        int st = 0;
        waitpid(pid, &st, 0);
        pid = -1;
        return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    }

    // Waits at most timeout for the child to end by itself: its exit code, -1 if it did not exit normally,
    // or nullopt when it is still running (then stop() or the destructor ends it).
    std::optional<int> wait_for(std::chrono::milliseconds timeout) {
        if (pid <= 0) return -1;
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        int st = 0;
        while (waitpid(pid, &st, WNOHANG) == 0) {
            if (std::chrono::steady_clock::now() > deadline) return std::nullopt;
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        pid = -1;
        return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    }

    pid_t pid = -1;
};

}  // namespace vecat::test
