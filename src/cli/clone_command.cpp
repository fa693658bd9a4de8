#include "cli/clone_command.hpp"

#include <fmt/format.h>

#include <memory>
#include <string>

#include "clone/clone.hpp"
#include "master/master.hpp"
#include "net/raw_socket.hpp"
#include "network/build.hpp"
#include "serve/in_process_link.hpp"

namespace vecat::cli {

namespace {

struct CloneArgs {
    std::string iface;
    std::string network;
    std::string out;
    bool quiet = false;
} g_args;

int clone_through(net::Link& link, const CloneArgs& a) {
    master::Master m(link);
    clone::CloneOptions opt;
    if (!a.quiet)
        opt.progress = [](const std::string& line) { fmt::print(stderr, "vecat clone: {}\n", line); };
    clone::CloneResult r;
    try {
        r = clone::read_line(m, opt);
    } catch (const std::exception& e) {
        fmt::print(stderr, "vecat clone: {}\n", e.what());
        return 1;
    }
    std::string file;
    try {
        file = clone::write_clone(r, a.out);
    } catch (const std::exception& e) {
        fmt::print(stderr, "vecat clone: {}\n", e.what());
        return 1;
    }
    std::size_t missing = 0;
    for (const auto& n : r.notes)
        fmt::print(stderr, "vecat clone: {}\n", n);
    for (const auto& d : r.devices)
        for (const auto& x : d.missing) {
            fmt::print(stderr, "vecat clone: {}: missing: {}\n", d.name, x);
            ++missing;
        }
    fmt::print(
        "{}: {} devices{}\n", file, r.devices.size(),
        missing ? fmt::format(", {} things missing (listed on stderr and in the files)", missing) : "");
    return missing ? 3 : 0;
}

}  // namespace

CLI::App* add_clone_command(CLI::App& app) {
    auto* c = app.add_subcommand("clone",
                                 "Read a line with the project's master and write it as a network file that "
                                 "vecat run --network serves as a copy");
    auto* iface = c->add_option("--iface", g_args.iface, "Network interface of the line (needs CAP_NET_RAW)");
    auto* network = c->add_option("--network", g_args.network,
                                  "Clone a network file served in this process instead of an interface");
    iface->excludes(network);
    c->add_option("-o,--output", g_args.out, "Folder for network.yaml, NAME.sii.bin, NAME.dictionary.yaml")
        ->required();
    c->add_flag("-q,--quiet", g_args.quiet, "No progress lines");
    return c;
}

int run_clone() {
    const CloneArgs& a = g_args;
    if (a.iface.empty() == a.network.empty()) {
        fmt::print(stderr, "vecat clone: give --iface IF or --network FILE\n");
        return 2;
    }
    if (!a.network.empty()) {
        network::BuiltNetwork built;
        try {
            built = network::build_network(network::read_network_file(a.network), a.network);
        } catch (const network::NetworkFileError& e) {
            fmt::print(stderr, "vecat clone: {}\n", e.what());
            return 2;
        }
        net::InProcessLink link(*built.segment);
        return clone_through(link, a);
    }
    std::unique_ptr<net::RawSocket> sock;
    try {
        sock = std::make_unique<net::RawSocket>(a.iface);
    } catch (const std::exception& e) {
        fmt::print(stderr, "vecat clone: {}\n", e.what());
        return 1;
    }
    return clone_through(*sock, a);
}

}  // namespace vecat::cli
