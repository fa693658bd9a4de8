#include "cli/replay_command.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <fstream>
#include <string>

#include "network/build.hpp"
#include "replay/replay.hpp"

namespace vecat::cli {

namespace {

struct ReplayArgs {
    std::string capture;
    std::string network;
    double min_wkc = 99.9;
    double min_data = 99.9;
    bool differences = false;
    std::size_t max_differences = 200;
    std::string save_sii;
} g_args;

}  // namespace

CLI::App* add_replay_command(CLI::App& app) {
    auto* r = app.add_subcommand("replay",
                                 "Send a capture's master frames to vecat and compare each reply with the "
                                 "recorded one");
    r->add_option("capture", g_args.capture, "pcap or pcapng file of a master talking to slaves")->required();
    r->add_option("--network", g_args.network,
                  "The line as a network file (default: rebuilt from the capture's SII reads and registers)");
    r->add_option("--min-wkc", g_args.min_wkc,
                  "Exit 1 below this percentage of datagrams with the recorded "
                  "working counter (default 99.9)");
    r->add_option("--min-data", g_args.min_data,
                  "Exit 1 below this percentage of register and memory reads with the recorded data, "
                  "time-dependent values and counters excepted (default 99.9)");
    r->add_flag("--differences", g_args.differences, "List the differences (the first --max-differences)");
    r->add_option("--max-differences", g_args.max_differences,
                  "How many differences --differences lists (default 200)");
    r->add_option("--save-sii", g_args.save_sii,
                  "Write the SII image of each slave rebuilt from the capture to DIR/slave-N.bin (words the "
                  "master did not read are 0xFFFF)");
    return r;
}

int run_replay() {
    const ReplayArgs& a = g_args;
    replay::Capture cap;
    try {
        cap = replay::read_capture(a.capture);
    } catch (const replay::CaptureError& e) {
        fmt::print(stderr, "vecat replay: {}\n", e.what());
        return 2;
    }
    const replay::Pairing pairing = replay::pair_frames(cap);
    fmt::print("{}: {} frames, {} EtherCAT, {} of other protocols\n", a.capture, cap.total, cap.frames.size(),
               cap.other_protocol);
    if (!cap.problem.empty()) fmt::print("{}: {}\n", a.capture, cap.problem);
    if (pairing.exchanges.empty()) {
        fmt::print(stderr, "vecat replay: {}: no master frame with its reply: nothing to replay\n",
                   a.capture);
        return 2;
    }
    std::unique_ptr<esc::Segment> line;
    std::vector<std::string> notes;
    if (!a.network.empty()) {
        try {
            auto built = network::build_network(network::read_network_file(a.network), a.network);
            line = std::move(built.segment);
            notes = std::move(built.notes);
        } catch (const network::NetworkFileError& e) {
            fmt::print(stderr, "{}\n", e.what());
            return 2;
        }
    } else {
        const replay::RecoveredLine rec = replay::recover_line(cap, pairing);
        line = replay::build_recovered_line(rec, notes);
        fmt::print("line rebuilt from the capture: {} slaves\n", rec.slave_count);
        for (std::size_t i = 0; !a.save_sii.empty() && i < rec.slaves.size(); ++i) {
            const std::string path = fmt::format("{}/slave-{}.bin", a.save_sii, i);
            const auto img = replay::recovered_sii_image(rec.slaves[i]);
            std::ofstream out(path, std::ios::binary);
            out.write(reinterpret_cast<const char*>(img.data()), static_cast<std::streamsize>(img.size()));
            if (!out) {
                fmt::print(stderr, "vecat replay: cannot write {}\n", path);
                return 2;
            }
        }
    }
    for (const auto& n : notes)
        fmt::print("note: {}\n", n);
    replay::ReplayOptions options;
    options.max_differences = a.max_differences;
    const replay::ReplayReport r = replay::replay(cap, pairing, *line, options);
    fmt::print("{}", replay::format_report(r));
    if (a.differences)
        for (const auto& d : r.differences)
            fmt::print("  frame {} datagram {}: {} adp 0x{:04X} ado 0x{:04X}: {}\n", d.frame, d.datagram,
                       protocol::to_string(static_cast<protocol::Command>(d.command)), d.adp, d.ado,
                       d.no_reply ? std::string("no reply")
                       : d.working_counter
                           ? fmt::format("working counter {} (recorded {})", d.replayed_wkc, d.recorded_wkc)
                           : fmt::format("data from 0x{:04X} {}: {:02X} recorded, {:02X} replayed",
                                         d.first_byte, replay::to_string(d.verdict),
                                         fmt::join(d.recorded, " "), fmt::join(d.replayed, " ")));
    const bool ok = r.wkc_percent() >= a.min_wkc && r.data_percent() >= a.min_data;
    if (!ok)
        fmt::print("below the thresholds (working counter {:.1f} %, data {:.1f} %)\n", a.min_wkc, a.min_data);
    return ok ? 0 : 1;
}

}  // namespace vecat::cli
