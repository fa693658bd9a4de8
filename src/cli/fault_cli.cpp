#include "cli/fault_cli.hpp"

#include <fmt/core.h>

#include "faults/fault.hpp"
#include "faults/scenario.hpp"

namespace vecat::cli {
namespace {

// Faults served outside the injector register their handlers here (the TWINsync port: its
// twinsync_cable_break, twinsync_crc_errors and twinsync_sync_loss handlers).
void register_fault_handlers(FaultSession& s, esc::Segment& seg) {
    s.twinsync = std::make_unique<faults::TwinsyncFaults>(seg);
    faults::register_twinsync_faults(*s.injector, *s.twinsync);
}

std::string kinds_help() {
    std::string s = "Faults (common keys: slave, probability, count, duration, id):\n";
    for (const auto& k : faults::fault_kinds())
        s += fmt::format("  {:<22} {}: {}\n", k.name, k.parameters, k.help);
    return s;
}

}  // namespace

void add_run_fault_options(CLI::App* run, RunFaultOptions& o) {
    run->add_option(
           "--scenario", o.scenario,
           "Fault scenario (YAML timeline, see src/faults/README.md); times count from the first frame")
        ->check(CLI::ExistingFile);
    run->add_option("--control", o.control,
                    "Unix socket for `vecat fault` commands while running (inject, clear, list, status)");
    run->add_option("--fault-seed", o.seed, "Seed of the fault probabilities (a scenario's seed: wins)");
}

std::unique_ptr<FaultSession> start_fault_session(esc::Segment& seg, const RunFaultOptions& o, bool& ok,
                                                  std::shared_ptr<io::IoBus> io) {
    ok = true;
    if (o.scenario.empty() && o.control.empty()) return nullptr;
    auto s = std::make_unique<FaultSession>();
    s->injector = std::make_unique<faults::FaultInjector>(seg, o.seed);
    s->injector->on_event = [](const std::string& line) { fmt::print("vecat: {}\n", line); };
    register_fault_handlers(*s, seg);
    if (io) {
        s->inputs = std::make_unique<io::InputForcing>(seg, std::move(io));
        s->injector->register_handler(io::InputForcing::kKind, *s->inputs);
    }
    try {
        if (!o.scenario.empty()) {
            const auto sc = faults::load_scenario(o.scenario);
            s->injector->load(sc);
            fmt::print("vecat: scenario {}: {} events\n", o.scenario, sc.events.size());
        }
        if (!o.control.empty()) {
            s->control = std::make_unique<faults::ControlServer>(o.control, *s->injector);
            fmt::print("vecat: fault control on {} (vecat fault --socket {} ...)\n", o.control, o.control);
        }
    } catch (const std::exception& e) {
        fmt::print(stderr, "vecat: {}\n", e.what());
        ok = false;
        return nullptr;
    }
    return s;
}

void print_fault_summary(const FaultSession& s) {
    const auto& c = s.injector->counters();
    fmt::print(
        "vecat: faults: {} started, {} ended; frames {} dropped, {} corrupted, {} delayed; {} SDO aborts, {} "
        "mailbox replies lost\n",
        c.faults_started, c.faults_ended, c.frames_dropped, c.frames_corrupted, c.replies_delayed,
        c.sdo_aborts, c.mailbox_replies_lost);
}

void add_fault_command(CLI::App& app, FaultCommand& f) {
    f.cmd = app.add_subcommand("fault", "Inject or clear faults in a running `vecat run --control SOCKET`");
    f.cmd->require_subcommand(1);
    f.cmd->footer(kinds_help());
    auto socket = [&](CLI::App* c) {
        c->add_option("-s,--socket", f.socket, "The control socket given to vecat run --control")->required();
    };
    f.inject = f.cmd->add_subcommand("inject", "Start a fault: KIND key=value... (prints its id)");
    f.inject->add_option("fault", f.words, "KIND key=value ... (e.g. link_down slave=1 port=1)")->required();
    socket(f.inject);
    f.clear = f.cmd->add_subcommand("clear", "End faults by id, by kind, or all");
    f.clear->add_option("what", f.words, "id | kind | all")->required();
    socket(f.clear);
    f.list = f.cmd->add_subcommand("list", "List the active faults");
    socket(f.list);
    f.status = f.cmd->add_subcommand("status",
                                     "What each slave shows now (AL state, counters, CiA 402 state and "
                                     "actual values), one line per slave");
    socket(f.status);
    f.kinds = f.cmd->add_subcommand("kinds", "Describe every fault and its parameters");
}

int run_fault_command(const FaultCommand& f) {
    if (f.kinds->parsed()) {
        fmt::print("{}", kinds_help());
        return 0;
    }
    std::string line = f.inject->parsed()   ? "inject"
                       : f.clear->parsed()  ? "clear"
                       : f.status->parsed() ? "status"
                                            : "list";
    for (const auto& w : f.words)
        line += " " + w;
    std::string reply;
    if (!faults::send_control_command(f.socket, line, reply)) {
        fmt::print(stderr, "vecat fault: {}\n", reply);
        return 1;
    }
    fmt::print("{}\n", reply);
    return reply.starts_with("ok") ? 0 : 1;
}

}  // namespace vecat::cli
