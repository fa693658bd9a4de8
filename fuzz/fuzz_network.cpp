// Fuzz target: the network file reader (network::parse_network: YAML, the devices' keys, the cabling
// checks, the order of the tree). Input: the text of a file.
// Invariants: the text is accepted or refused with a NetworkFileError that names a line ("NAME:LINE: ...")
// or the file; nothing else is thrown. An accepted file is a tree: one device on the master, every other one
// with a parent before it in the order, its port cabled to it and to nothing else. A redundancy port is a
// free port of a device; hot connect group names are unique. The inputs of I/O terminals name channels the
// terminal has, and wires name output terminals or drives of the file (a channel), or devices of ESI files or
// SII dumps (a channel or an output PDO entry). Quirks hold values within their ranges. modules:
// is on esi: devices only, each entry with its line. The same
// text read as a signal's CSV table (io::parse_table) is refused with std::invalid_argument naming a line, or
// gives rows at rising times with finite values.
#include <cctype>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_support.hpp"
#include "io/signal.hpp"
#include "network/network_file.hpp"

using namespace vecat;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const auto rows = io::parse_table(text);
        VECAT_FUZZ_CHECK(!rows.empty());
        for (std::size_t i = 0; i < rows.size(); ++i) {
            VECAT_FUZZ_CHECK(std::isfinite(rows[i].second));
            VECAT_FUZZ_CHECK(i == 0 || rows[i].first > rows[i - 1].first);
        }
    } catch (const std::invalid_argument& e) {
        VECAT_FUZZ_CHECK(std::isdigit(static_cast<unsigned char>(e.what()[0])));
    }
    network::NetworkFile f;
    try {
        f = network::parse_network(text, "fuzz.yaml", "/nonexistent");
    } catch (const network::NetworkFileError& e) {
        VECAT_FUZZ_CHECK(std::string(e.what()).rfind("fuzz.yaml:", 0) == 0);
        return 0;
    }
    const std::size_t n = f.devices.size();
    VECAT_FUZZ_CHECK(n > 0 && f.parent.size() == n && f.children.size() == n);
    VECAT_FUZZ_CHECK(f.parent[0] == -1);
    for (std::size_t i = 1; i < n; ++i) {
        const int p = f.parent[i];
        VECAT_FUZZ_CHECK(p >= 0 && static_cast<std::size_t>(p) < i);
        const unsigned port = f.devices[i].upstream_port;
        VECAT_FUZZ_CHECK(port >= 1 && port < network::kPorts);
        VECAT_FUZZ_CHECK(f.children[static_cast<std::size_t>(p)][port] == static_cast<int>(i));
    }
    if (f.redundancy_device >= 0) {
        VECAT_FUZZ_CHECK(static_cast<std::size_t>(f.redundancy_device) < n);
        VECAT_FUZZ_CHECK(f.redundancy_port >= 1 && f.redundancy_port < network::kPorts);
        VECAT_FUZZ_CHECK(f.children[static_cast<std::size_t>(f.redundancy_device)][f.redundancy_port] < 0);
    }
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j)
            VECAT_FUZZ_CHECK(f.devices[i].hot_connect.empty() ||
                             f.devices[i].hot_connect != f.devices[j].hot_connect);
    for (const auto& d : f.devices) {
        // Quirks (device::parse_quirk): only values within their ranges are accepted.
        const auto& q = d.quirks;
        VECAT_FUZZ_CHECK(q.max_pdo_entries <= 254);
        VECAT_FUZZ_CHECK(q.mailbox_drop_every == 0 ||
                         (q.mailbox_drop_every >= 2 && q.mailbox_drop_every <= 1000));
        VECAT_FUZZ_CHECK(q.mailbox_delay_ns <= 500'000'000ull);
        VECAT_FUZZ_CHECK(q.sii_without <= 0x07 && (q.sii_without == 0 || d.source != network::Source::Sii));
        VECAT_FUZZ_CHECK(!q.any() || d.quirks_line > 0);
        VECAT_FUZZ_CHECK(d.modules.empty() || (d.source == network::Source::Esi && d.modules_line > 0));
        for (const auto& m : d.modules)
            VECAT_FUZZ_CHECK(m.line > 0 && (!m.module || !m.module->empty()));
    }
    for (const auto& d : f.devices)
        for (const auto& in : d.inputs) {
            VECAT_FUZZ_CHECK(d.source == network::Source::DigitalIn ||
                             d.source == network::Source::AnalogIn || d.source == network::Source::Drive);
            VECAT_FUZZ_CHECK(in.channel < network::kMaxChannels);
            if (in.signal.kind != io::SignalKind::Wire) continue;
            // A wire names an output terminal or a vecat drive (a channel), or a device of an ESI file or SII
            // dump (a channel or an output PDO entry 0xINDEX:SUB, checked when the device is made).
            bool output = false;
            for (const auto& o : f.devices) {
                if (o.name != in.signal.device) continue;
                const bool from_file = o.source == network::Source::Esi || o.source == network::Source::Sii;
                output = from_file || (!in.signal.wire_entry && (o.source == network::Source::DigitalOut ||
                                                                 o.source == network::Source::AnalogOut ||
                                                                 o.source == network::Source::Drive));
            }
            VECAT_FUZZ_CHECK(output);
        }
    return 0;
}
