#include "cli/exec.hpp"

#include <fcntl.h>
#include <fmt/core.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <thread>

#include "net/netns.hpp"

extern char** environ;

namespace vecat::cli {
namespace {

// The process that runs COMMAND's process tree: the first child, PID 1 of the new PID namespace. When it
// ends, the kernel kills whatever COMMAND left behind in the namespace (pid_namespaces(7)).
std::atomic<pid_t> g_child{0};

void forward_to_child(int sig) {
    if (const pid_t c = g_child.load()) ::kill(c, sig);
}

constexpr int kForwarded[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2};

void handle(void (*h)(int)) {
    struct sigaction sa {};
    sa.sa_handler = h;
    sigemptyset(&sa.sa_mask);
    for (const int s : kForwarded)
        ::sigaction(s, &sa, nullptr);
}

int status_of(int st) {
    if (WIFEXITED(st)) return WEXITSTATUS(st);
    if (WIFSIGNALED(st)) return 128 + WTERMSIG(st);
    return kExecFailed;
}

// PATH search done before fork: the child only calls async-signal-safe functions.
std::string find_program(const std::string& name, int& error) {
    const auto usable = [&](const std::string& p) {
        struct stat sb {};
        if (::stat(p.c_str(), &sb) != 0 || S_ISDIR(sb.st_mode)) return false;
        if (::access(p.c_str(), X_OK) != 0) {
            error = kExecNotExecutable;
            return false;
        }
        return true;
    };
    error = kExecNotFound;
    if (name.find('/') != std::string::npos) return usable(name) ? name : "";
    const char* path = std::getenv("PATH");
    std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
    std::size_t b = 0;
    while (b <= dirs.size()) {
        const std::size_t e = std::min(dirs.find(':', b), dirs.size());
        const std::string dir = e > b ? dirs.substr(b, e - b) : ".";
        if (const std::string p = dir + "/" + name; usable(p)) return p;
        b = e + 1;
    }
    return "";
}

// The child after fork (PID 1 of the namespace): start COMMAND as its own child, pass signals on, reap
// orphans, and end with COMMAND's status. Only async-signal-safe calls from here on.
// alive: the read end of a pipe whose write end only vecat holds (it hangs up when vecat has ended).
[[noreturn]] void init_process(int alive, const char* path, char* const* argv, char* const* envp) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // vecat killed: the namespace goes with it
    // vecat may have ended before the line above: then nothing would kill this process.
    pollfd p{alive, POLLIN, 0};
    if (::poll(&p, 1, 0) != 0) ::_exit(kExecFailed);
    const pid_t cmd = ::fork();
    if (cmd < 0) ::_exit(kExecFailed);
    if (cmd == 0) {
        ::prctl(PR_SET_PDEATHSIG, SIGKILL);
        handle(SIG_DFL);
        sigset_t none;
        sigemptyset(&none);
        ::sigprocmask(SIG_SETMASK, &none, nullptr);
        ::execve(path, argv, envp);
        const int err = errno;
        const char msg[] = "vecat exec: cannot execute the command: ";
        [[maybe_unused]] auto w = ::write(2, msg, sizeof msg - 1);
        const char* why = ::strerrordesc_np(err);  // a constant string: safe after fork
        w = ::write(2, why, ::strlen(why));
        w = ::write(2, "\n", 1);
        ::_exit(err == ENOENT ? kExecNotFound : kExecNotExecutable);
    }
    g_child.store(cmd);
    handle(forward_to_child);
    while (true) {
        int st = 0;
        const pid_t reaped = ::waitpid(-1, &st, 0);
        if (reaped == cmd) ::_exit(status_of(st));
        if (reaped < 0 && errno == ECHILD) ::_exit(kExecFailed);
    }
}

// Replaces each key in arg by value.
std::string substitute(std::string arg, std::string_view key, const std::string& value) {
    for (std::size_t at = arg.find(key); at != std::string::npos; at = arg.find(key, at + value.size()))
        arg.replace(at, key.size(), value);
    return arg;
}

}  // namespace

int run_exec(const ExecOptions& o, const ServeFunction& serve) {
    if (o.command.empty()) {
        fmt::print(stderr, "vecat exec: no command given (vecat exec [options] -- COMMAND...)\n");
        return kExecFailed;
    }
    std::string why;
    if (!net::enter_private_netns(&why)) {
        fmt::print(stderr, "vecat exec: no private network namespace: {}\n", why);
        return kExecFailed;
    }
    if (!net::loopback_up(&why) ||
        (o.serve && !net::create_veth_pair(o.master_interface, o.slave_interface, &why)) ||
        (o.serve && o.redundant &&
         !net::create_veth_pair(o.redundant_master_interface, o.redundant_slave_interface, &why))) {
        fmt::print(stderr, "vecat exec: {}\n", why);
        return kExecFailed;
    }
    int error = 0;
    const std::string path = find_program(o.command[0], error);
    if (path.empty()) {
        fmt::print(stderr, "vecat exec: {}: {}\n", o.command[0],
                   error == kExecNotFound ? "command not found" : "not executable");
        return error;
    }

    // The slaves, served on a thread of this process until COMMAND has ended.
    std::atomic<bool> stop{false}, ready{!o.serve}, done{false};
    int serve_rc = 0;
    std::thread server;
    if (o.serve) {
        // The serving thread takes no signal: they are COMMAND's (see below).
        sigset_t all, old;
        sigfillset(&all);
        ::pthread_sigmask(SIG_BLOCK, &all, &old);
        server = std::thread([&] {
            serve_rc = serve(stop, ready, stderr);
            done = true;
        });
        ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
        while (!ready && !done && std::chrono::steady_clock::now() < deadline)
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        if (!ready) {
            stop = true;
            server.join();
            fmt::print(stderr, "vecat exec: the slaves could not be served (exit code {})\n", serve_rc);
            return kExecFailed;
        }
    }

    // Everything COMMAND's processes need, built before fork.
    std::vector<std::string> args, env;
    const bool redundant = o.serve && o.redundant;
    for (const auto& a : o.command) {
        std::string arg = redundant ? substitute(a, "{iface2}", o.redundant_master_interface) : a;
        args.push_back(substitute(std::move(arg), "{iface}", o.master_interface));
    }
    for (char** e = environ; *e; ++e)
        if (std::strncmp(*e, "VECAT_IFACE=", 12) != 0 && std::strncmp(*e, "VECAT_IFACE2=", 13) != 0 &&
            std::strncmp(*e, "VECAT_EXEC=", 11) != 0 && std::strncmp(*e, "VECAT_BIN=", 10) != 0)
            env.emplace_back(*e);
    if (o.serve) env.push_back("VECAT_IFACE=" + o.master_interface);
    if (redundant) env.push_back("VECAT_IFACE2=" + o.redundant_master_interface);
    // For test kits (python/vecat): they run inside a namespace of their own and may start more networks.
    env.emplace_back("VECAT_EXEC=1");
    char self[4096];
    if (const ssize_t n = ::readlink("/proc/self/exe", self, sizeof self); n > 0 && n < ssize_t{sizeof self})
        env.push_back("VECAT_BIN=" + std::string(self, static_cast<std::size_t>(n)));
    for (const auto& [k, v] : o.environment)
        env.push_back(k + "=" + v);
    std::vector<char*> argv, envp;
    for (auto& a : args)
        argv.push_back(a.data());
    argv.push_back(nullptr);
    for (auto& e : env)
        envp.push_back(e.data());
    envp.push_back(nullptr);

    // Signals for vecat go to COMMAND (through its init); vecat stops serving when COMMAND has ended.
    sigset_t all, old;
    sigfillset(&all);
    ::pthread_sigmask(SIG_BLOCK, &all, &old);  // no handler runs between fork and the child's set-up
    // The next child is PID 1 of a new PID namespace: when it ends, so does every process COMMAND left.
    // (No other child may be forked before it: a PID namespace whose init has ended takes no new process.)
    int alive[2] = {-1, -1};
    if (::pipe2(alive, O_CLOEXEC) != 0 || ::unshare(CLONE_NEWPID) != 0) {
        ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
        fmt::print(stderr, "vecat exec: no PID namespace for the command: {}\n", std::strerror(errno));
        stop = true;
        if (server.joinable()) server.join();
        return kExecFailed;
    }
    const pid_t child = ::fork();
    if (child == 0) {
        ::close(alive[1]);
        ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
        init_process(alive[0], path.c_str(), argv.data(), envp.data());
    }
    ::close(alive[0]);
    int status = kExecFailed;
    if (child < 0) {
        fmt::print(stderr, "vecat exec: fork: {}\n", std::strerror(errno));
    } else {
        g_child.store(child);
        handle(forward_to_child);
        ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
        int st = 0;
        pid_t p = 0;
        while ((p = ::waitpid(child, &st, 0)) < 0 && errno == EINTR) {
        }
        if (p == child) status = status_of(st);
        handle(SIG_DFL);
        g_child.store(0);
    }
    ::close(alive[1]);
    if (server.joinable()) {
        stop = true;
        server.join();
        // What serving found after COMMAND succeeded (vecat run --report-fail: the master broke a rule).
        if (status == 0 && serve_rc != 0) status = serve_rc;
    }
    return status;
}

}  // namespace vecat::cli
