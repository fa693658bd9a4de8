// `vecat exec [run options] -- COMMAND...`: COMMAND runs in a private network namespace (and, for an
// ordinary user, a private user namespace: no root, no setuid helper) in which vecat serves the slaves on
// one end of a veth pair; COMMAND gets the other end (environment VECAT_IFACE, and "{iface}" in its
// arguments). With cable redundancy a second pair is the master's second port (VECAT_IFACE2, "{iface2}"). The
// exit status is COMMAND's (or, when COMMAND succeeded, what serving returned: 3 for a failed report with
// --report-fail); the namespaces, the interfaces and every process COMMAND started disappear with it, also
// when vecat itself is killed.
#pragma once

#include <atomic>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

namespace vecat::cli {

struct ExecOptions {
    std::vector<std::string> command;  // COMMAND and its arguments
    std::string master_interface = "vecat-m";
    std::string slave_interface = "vecat-s";
    // Cable redundancy (--redundant): a second veth pair, the master's second port; the far end of the line
    // is cabled back to redundant_slave_interface.
    bool redundant = false;
    std::string redundant_master_interface = "vecat-m2";
    std::string redundant_slave_interface = "vecat-s2";
    bool serve = true;  // false (--no-network): only the namespaces, for a runner that starts networks
    std::vector<std::pair<std::string, std::string>> environment;  // set for COMMAND besides VECAT_IFACE
};

// Serves the slaves on ExecOptions::slave_interface until stop; sets ready once frames are answered; writes
// its messages to log. Returns its exit code (not 0: it could not serve).
using ServeFunction = std::function<int(std::atomic<bool>& stop, std::atomic<bool>& ready, std::FILE* log)>;

// Exit codes of vecat itself, as env(1) and container runners use them: 125 vecat failed (no namespace,
// no veth pair, the slaves could not be served), 126 COMMAND cannot be executed, 127 COMMAND not found.
// Otherwise COMMAND's status; 128 + N when a signal N ended it.
inline constexpr int kExecFailed = 125;
inline constexpr int kExecNotExecutable = 126;
inline constexpr int kExecNotFound = 127;

// Call before any thread is started (user namespaces need a single-threaded process).
int run_exec(const ExecOptions& o, const ServeFunction& serve);

}  // namespace vecat::cli
