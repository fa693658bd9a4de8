// A program the tests start (usually `vecat run`), stopped with SIGINT like a user's Ctrl-C.
#pragma once

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <string>
#include <vector>

extern char** environ;

namespace vecat::test {

class ChildProcess {
  public:
    explicit ChildProcess(std::vector<std::string> args) {
        std::vector<char*> argv;
        for (auto& a : args)
            argv.push_back(a.data());
        argv.push_back(nullptr);
        if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) pid = -1;
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

    pid_t pid = -1;
};

}  // namespace vecat::test
