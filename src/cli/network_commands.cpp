#include "cli/network_commands.hpp"

#include <fmt/core.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <vector>

#include "network/build.hpp"
#include "network/eni.hpp"
#include "network/eni_network.hpp"

namespace vecat::cli {

namespace {

// The network of a network file, or of an ENI (a file whose first character is '<': XML); an ENI's notes go
// to notes, or to stderr.
network::NetworkFile read_network(const std::string& file, const std::string& esi_dir,
                                  std::vector<std::string>* notes = nullptr) {
    std::ifstream in(file);
    char first = 0;
    while (in.get(first) && std::isspace(static_cast<unsigned char>(first))) {
    }
    if (first != '<') return network::read_network_file(file);
    auto n = network::network_from_eni(network::read_eni_file(file), {esi_dir});
    for (const auto& x : n.notes)
        if (notes)
            notes->push_back(x);
        else
            fmt::print(stderr, "vecat: {}\n", x);
    return std::move(n.file);
}

}  // namespace

// vecat network from-eni: the network file of an ENI, and the SII images of the devices made from the ENI
// alone beside it.
int cmd_network_from_eni(const std::string& eni_file, const std::string& out, const std::string& esi_dir) {
    namespace fs = std::filesystem;
    try {
        const auto eni = network::read_eni_file(eni_file);
        const auto n = network::network_from_eni(eni, {esi_dir});
        const fs::path folder =
            fs::path(out).parent_path().empty() ? fs::path(".") : fs::path(out).parent_path();
        const auto text = network::network_file_from_eni(eni, n, folder.string());
        for (const auto& [name, bytes] : text.files) {
            std::ofstream f(folder / name, std::ios::binary);
            f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
            if (!f) {
                fmt::print(stderr, "vecat: cannot write {}\n", (folder / name).string());
                return 1;
            }
        }
        std::ofstream y(out);
        y << text.yaml;
        if (!y) {
            fmt::print(stderr, "vecat: cannot write {}\n", out);
            return 1;
        }
        for (const auto& x : n.notes)
            fmt::print("note: {}\n", x);
        fmt::print("{}: {} devices ({} SII images beside it)\n", out, n.file.devices.size(),
                   text.files.size());
        return 0;
    } catch (const network::NetworkFileError& e) {
        fmt::print(stderr, "{}\n", e.what());
        return 1;
    }
}

// vecat network check: the devices in the order the frame reaches them, where each is cabled, what was
// guessed; exit 1 with the file's line when something is wrong. An ENI (XML) is read as vecat run --eni.
int cmd_network_check(const std::string& file, const std::string& esi_dir) {
    try {
        std::vector<std::string> eni_notes;
        const auto f = read_network(file, esi_dir, &eni_notes);
        auto built = network::build_network(f, file);
        built.notes.insert(built.notes.begin(), eni_notes.begin(), eni_notes.end());
        fmt::print("{}: {} devices\n", file, f.devices.size());
        for (std::size_t i = 0; i < f.devices.size(); ++i) {
            const auto& d = f.devices[i];
            const auto& desc = built.segment->slave(i).description();
            const std::string up =
                f.parent[i] < 0
                    ? "the master"
                    : fmt::format("{} port {}", f.devices[static_cast<std::size_t>(f.parent[i])].name,
                                  d.upstream_port);
            fmt::print(
                "  {:>3}  {:<16} {:<11} vendor 0x{:08X} product 0x{:08X} rev 0x{:08X}  \"{}\"  port 0 to "
                "{}\n",
                i, d.name, network::to_string(d.source), desc.identity.vendor_id, desc.identity.product_code,
                desc.identity.revision, desc.name, up);
            if (desc.quirks.any()) fmt::print("       quirks: {}\n", device::to_string(desc.quirks));
        }
        if (f.redundancy_device >= 0)
            fmt::print("  redundancy: port {} of {} cabled back to the master's second port\n",
                       f.redundancy_port, f.devices[static_cast<std::size_t>(f.redundancy_device)].name);
        for (const auto& [group, head] : built.segment->hot_connect_groups())
            fmt::print("  hot connect group {}: {} to {}\n", group, f.devices[head].name,
                       f.devices[built.segment->group_end(head) - 1].name);
        for (const auto& n : built.notes)
            fmt::print("note: {}\n", n);
        return 0;
    } catch (const network::NetworkFileError& e) {
        fmt::print(stderr, "{}\n", e.what());
        return 1;
    }
}

}  // namespace vecat::cli
