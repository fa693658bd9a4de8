// The command line side of fault injection: `vecat run --scenario FILE --control SOCKET` and
// `vecat fault inject|clear|list|kinds`.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "esc/segment.hpp"
#include "faults/control.hpp"
#include "faults/injector.hpp"
#include "faults/twinsync_faults.hpp"
#include "io/terminals.hpp"

namespace vecat::cli {

struct RunFaultOptions {
    std::string scenario;  // YAML timeline
    std::string control;   // Unix socket for vecat fault
    std::uint64_t seed = 1;
};
void add_run_fault_options(CLI::App* run, RunFaultOptions& o);

// The injector of a `vecat run` with its control socket; nullptr from start_fault_session when neither a
// scenario nor a control socket was asked for (frames then go straight to the segment).
struct FaultSession {
    std::unique_ptr<faults::TwinsyncFaults> twinsync;  // outlives the injector that calls it
    std::unique_ptr<io::InputForcing> inputs;          // set_input, where the network has I/O terminals
    std::unique_ptr<faults::FaultInjector> injector;
    std::unique_ptr<faults::ControlServer> control;
};
// io: the I/O terminals of a network file (set_input), or null.
std::unique_ptr<FaultSession> start_fault_session(esc::Segment& seg, const RunFaultOptions& o, bool& ok,
                                                  std::shared_ptr<io::IoBus> io = {});
void print_fault_summary(const FaultSession& s);

// vecat fault ...: returns the subcommand; run_fault_command runs it when it was given.
struct FaultCommand {
    CLI::App* cmd = nullptr;
    CLI::App* inject = nullptr;
    CLI::App* clear = nullptr;
    CLI::App* list = nullptr;
    CLI::App* status = nullptr;
    CLI::App* kinds = nullptr;
    std::string socket;
    std::vector<std::string> words;  // inject: KIND key=value...; clear: WHAT
};
void add_fault_command(CLI::App& app, FaultCommand& f);
int run_fault_command(const FaultCommand& f);

}  // namespace vecat::cli
