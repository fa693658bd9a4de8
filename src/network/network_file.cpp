// The network file's reader (about 620 lines): every key of a device entry, the cabling, the inputs and
// quirks, each checked with the line it is on, so that a refusal names where the file is wrong.
#include "network/network_file.hpp"
#include "network/yaml_reader.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <system_error>

#include "common/file.hpp"
#include "protocol/registers.hpp"
#include "protocol/topology.hpp"

namespace vecat::network {

namespace {

struct Kind {
    std::string_view name;
    Source source;
};
// The values of device: (built-in devices).
constexpr Kind kBuiltIn[] = {
    {"drive", Source::Drive},           {"coupler", Source::Coupler},        {"junction", Source::Junction},
    {"digital-in", Source::DigitalIn},  {"digital-out", Source::DigitalOut}, {"analog-in", Source::AnalogIn},
    {"analog-out", Source::AnalogOut},  {"hiwin-d2", Source::HiwinD2},       {"soe-drive", Source::SoeDrive},
    {"soe-drive-2", Source::SoeDrive2},
};

bool is_io(Source s) {
    return s == Source::DigitalIn || s == Source::DigitalOut || s == Source::AnalogIn ||
           s == Source::AnalogOut;
}

using Reader = YamlReader<NetworkFileError>;

double real(const Reader& r, const YAML::Node& n, const std::string& key) {
    const std::string s = r.scalar(n, key);
    double v = 0;
    const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || res.ec != std::errc{} || res.ptr != s.data() + s.size() || !std::isfinite(v))
        r.fail(n, key + ": \"" + s + "\" is not a number");
    return v;
}

std::uint64_t milliseconds(const Reader& r, const YAML::Node& n, const std::string& key) {
    const double ms = real(r, n, key);
    if (ms < 0 || ms > 1e9) r.fail(n, key + ": from 0 to 1e9 ms");
    return static_cast<std::uint64_t>(ms * 1e6);
}

// wire: DEVICE:CHANNEL (a channel number), or DEVICE:0xINDEX:SUB (an output PDO entry of a device of an ESI
// file or SII dump: index in hexadecimal, subindex decimal or 0x). Device names hold no ':'.
void parse_wire(const Reader& r, const YAML::Node& v, io::Signal& sig) {
    const std::string w = r.scalar(v, "wire");
    const auto colon = w.find(':');
    if (colon == std::string::npos || colon == 0)
        r.fail(v, "wire: DEVICE:CHANNEL (an output channel) or DEVICE:0xINDEX:SUB (an output PDO entry)");
    sig.kind = io::SignalKind::Wire;
    sig.device = w.substr(0, colon);
    const std::string rest = w.substr(colon + 1);
    const auto digits = [](const std::string& t, bool hex) {
        return !t.empty() && std::all_of(t.begin(), t.end(), [&](char c) {
            return hex ? std::isxdigit(static_cast<unsigned char>(c)) != 0
                       : std::isdigit(static_cast<unsigned char>(c)) != 0;
        });
    };
    if (const auto second = rest.find(':'); second != std::string::npos) {
        const std::string index = rest.substr(0, second);
        std::string sub = rest.substr(second + 1);
        const bool hex_index = index.size() > 2 && index[0] == '0' && (index[1] == 'x' || index[1] == 'X');
        if (!hex_index || index.size() > 6 || !digits(index.substr(2), true))
            r.fail(v, "wire: DEVICE:0xINDEX:SUB, the entry's index in hexadecimal (0x7000)");
        const bool hex_sub = sub.size() > 2 && sub[0] == '0' && (sub[1] == 'x' || sub[1] == 'X');
        if (hex_sub) sub = sub.substr(2);
        if (!digits(sub, hex_sub) || sub.size() > 3 || std::stoul(sub, nullptr, hex_sub ? 16 : 10) > 255)
            r.fail(v, "wire: DEVICE:0xINDEX:SUB, the subindex 0-255 after the index");
        sig.wire_entry = true;
        sig.wire_index = static_cast<std::uint16_t>(std::stoul(index.substr(2), nullptr, 16));
        sig.wire_subindex = static_cast<std::uint8_t>(std::stoul(sub, nullptr, hex_sub ? 16 : 10));
        return;
    }
    if (!digits(rest, false) || rest.size() > 3)
        r.fail(v, "wire: the channel after ':' is a number (or 0xINDEX:SUB, an output PDO entry)");
    sig.channel = static_cast<unsigned>(std::stoul(rest));
}

// inputs: of an input terminal: CHANNEL: {signal: KIND, parameters...} or CHANNEL: {wire: DEVICE:CHANNEL}.
void parse_inputs(const Reader& r, const YAML::Node& n, DeviceEntry& d, const std::string& folder) {
    if (!n.IsMap()) r.fail(n, "inputs: a map of channel: {signal: ...} or channel: {wire: DEVICE:CHANNEL}");
    d.inputs_line = Reader::line(n);
    for (const auto& item : n) {
        DeviceEntry::Input in;
        in.line = Reader::line(item.first);
        in.channel = static_cast<unsigned>(r.number(item.first, "inputs: channel", kMaxChannels - 1));
        for (const auto& other : d.inputs)
            if (other.channel == in.channel)
                r.fail(item.first, "inputs: channel " + std::to_string(in.channel) + " is given twice");
        const YAML::Node& spec = item.second;
        if (!spec.IsMap()) r.fail(spec, "inputs: a channel takes {signal: ...} or {wire: DEVICE:CHANNEL}");
        io::Signal& sig = in.signal;
        bool kind_given = false;
        std::uint64_t period = 0;
        bool period_given = false;
        for (const auto& kv : spec) {
            const std::string key = r.scalar(kv.first, "key");
            const YAML::Node& v = kv.second;
            if (key == "signal") {
                const std::string k = r.scalar(v, key);
                static constexpr std::pair<std::string_view, io::SignalKind> kinds[] = {
                    {"constant", io::SignalKind::Constant},
                    {"square", io::SignalKind::Square},
                    {"sine", io::SignalKind::Sine},
                    {"ramp", io::SignalKind::Ramp},
                    {"table", io::SignalKind::Table}};
                const auto* it = std::find_if(std::begin(kinds), std::end(kinds),
                                              [&](const auto& p) { return p.first == k; });
                if (it == std::end(kinds))
                    r.fail(v, "signal: unknown signal " + k + " (constant, square, sine, ramp, table)");
                sig.kind = it->second;
                kind_given = true;
            } else if (key == "wire") {
                parse_wire(r, v, sig);
                kind_given = true;
            } else if (key == "value") {
                sig.value = real(r, v, key);
            } else if (key == "low") {
                sig.low = real(r, v, key);
            } else if (key == "high") {
                sig.high = real(r, v, key);
            } else if (key == "amplitude") {
                sig.amplitude = real(r, v, key);
            } else if (key == "offset") {
                sig.offset = real(r, v, key);
            } else if (key == "from") {
                sig.from = real(r, v, key);
            } else if (key == "to") {
                sig.to = real(r, v, key);
            } else if (key == "period_ms") {
                period = milliseconds(r, v, key);
                if (period == 0) r.fail(v, "period_ms: more than 0");
                period_given = true;
            } else if (key == "phase_ms") {
                sig.phase_ns = milliseconds(r, v, key);
            } else if (key == "file") {
                std::string path = r.scalar(v, key);
                if (std::filesystem::path(path).is_relative())
                    path = (std::filesystem::path(folder) / path).string();
                std::string why;
                const auto text = read_whole_file(path, kMaxTextFileBytes, why);
                if (!text) r.fail(v, "file: " + path + " " + why);
                try {
                    sig.table = io::parse_table(*text);
                } catch (const std::invalid_argument& e) {
                    r.fail(v, "file: " + path + ":" + e.what());
                }
            } else {
                r.fail(kv.first,
                       "inputs: unknown key " + key +
                           " (signal, wire, value, low, high, amplitude, offset, from, to, period_ms, "
                           "phase_ms, file)");
            }
        }
        if (!kind_given)
            r.fail(in.line, "inputs: channel " + std::to_string(in.channel) + ": give signal: or wire:");
        if (sig.kind == io::SignalKind::Table && sig.table.empty())
            r.fail(in.line, "inputs: a table signal takes file: (CSV rows time_ms,value)");
        if (period_given)
            sig.period_ns = period;
        else if (sig.kind == io::SignalKind::Table)
            sig.period_ns = 0;  // holds its last value
        d.inputs.push_back(std::move(in));
    }
}

void parse_upstream(const Reader& r, const YAML::Node& n, DeviceEntry& d) {
    const std::string s = r.scalar(n, "upstream");
    const auto colon = s.rfind(':');
    d.upstream = s.substr(0, colon);
    if (colon != std::string::npos) {
        const std::string port = s.substr(colon + 1);
        if (port.size() != 1 || port[0] < '1' || port[0] > '3')
            r.fail(n, "upstream: the port after ':' is 1, 2 or 3 (port 0 of a device leads to the master)");
        d.upstream_port = static_cast<unsigned>(port[0] - '0');
    }
    if (d.upstream.empty()) r.fail(n, "upstream: the name of a device, optionally :PORT");
}

void parse_identity(const Reader& r, const YAML::Node& n, IdentityOverride& id) {
    if (!n.IsMap()) r.fail(n, "identity: a map of vendor, product, revision, serial");
    for (const auto& item : n) {
        const std::string key = r.scalar(item.first, "identity key");
        const auto v = static_cast<std::uint32_t>(r.number(item.second, key, 0xFFFFFFFFu));
        if (key == "vendor")
            id.vendor_id = v;
        else if (key == "product")
            id.product_code = v;
        else if (key == "revision")
            id.revision = v;
        else if (key == "serial")
            id.serial = v;
        else
            r.fail(item.first, "identity: unknown key " + key + " (vendor, product, revision, serial)");
    }
}

void parse_esc(const Reader& r, const YAML::Node& n, EscOverride& esc) {
    if (!n.IsMap())
        r.fail(
            n,
            "esc: a map of type, revision, build, fmmus, syncmanagers, ram_kib, port_descriptor, features, "
            "sii_read_bytes");
    for (const auto& item : n) {
        const std::string key = r.scalar(item.first, "esc key");
        const YAML::Node& v = item.second;
        const auto u8 = [&] { return static_cast<std::uint8_t>(r.number(v, "esc: " + key, 0xFF)); };
        const auto u16 = [&] { return static_cast<std::uint16_t>(r.number(v, "esc: " + key, 0xFFFF)); };
        if (key == "type")
            esc.type = u8();
        else if (key == "revision")
            esc.revision = u8();
        else if (key == "build")
            esc.build = u16();
        else if (key == "fmmus")
            esc.fmmus = u8();
        else if (key == "syncmanagers")
            esc.syncmanagers = u8();
        else if (key == "ram_kib")
            esc.ram_kib = u8();
        else if (key == "port_descriptor")
            esc.port_descriptor = u8();
        else if (key == "features")
            esc.features = u16();
        else if (key == "sii_read_bytes") {
            esc.sii_read_bytes = static_cast<unsigned>(r.number(v, "esc: sii_read_bytes", 8));
            if (*esc.sii_read_bytes != 4 && *esc.sii_read_bytes != 8)
                r.fail(v, "esc: sii_read_bytes: 4 or 8");
        } else
            r.fail(item.first, "esc: unknown key " + key +
                                   " (type, revision, build, fmmus, syncmanagers, ram_kib, port_descriptor, "
                                   "features, sii_read_bytes)");
    }
}

// quirks: a list of quirks (device::parse_quirk), or one of them; each refusal names its line.
void parse_quirks(const Reader& r, const YAML::Node& n, DeviceEntry& d) {
    d.quirks_line = Reader::line(n);
    const auto one = [&](const YAML::Node& q) {
        const std::string why = device::parse_quirk(r.scalar(q, "quirks"), d.quirks);
        if (!why.empty()) r.fail(q, "quirks: " + why);
    };
    if (n.IsSequence()) {
        for (const auto& q : n)
            one(q);
    } else if (n.IsScalar()) {
        one(n);
    } else {
        r.fail(n, "quirks: a list of quirks (" + std::string(device::kQuirkNames) + ")");
    }
}

// modules: of an esi: device: a list, one entry per slot, each a module Type, a ModuleIdent, or empty / null
// for an empty slot. Whether the ESI has such modules and slots is checked when the device is built.
void parse_modules(const Reader& r, const YAML::Node& n, DeviceEntry& d) {
    constexpr const char* what =
        "modules: a list, one entry per slot: a module Type or ModuleIdent, or empty for an empty slot";
    if (!n.IsSequence()) r.fail(n, what);
    if (n.size() == 0) r.fail(n, "modules: an empty list (leave modules: out for the default modules)");
    d.modules_line = Reader::line(n);
    for (const auto& item : n) {
        DeviceEntry::SlotModule m;
        m.line = Reader::line(item);
        if (!item.IsNull()) {
            if (!item.IsScalar()) r.fail(item, what);
            const std::string s = item.as<std::string>();
            if (s.empty()) r.fail(item, "modules: an empty name; write empty for an empty slot");
            if (s != "empty") m.module = s;
        }
        d.modules.push_back(std::move(m));
    }
}

DeviceEntry parse_device(const Reader& r, const YAML::Node& n, const std::string& folder) {
    if (!n.IsMap()) r.fail(n, "a device is a map (name:, and device:, esi: or sii:)");
    DeviceEntry d;
    d.line = Reader::line(n);
    int sources = 0;
    std::optional<unsigned> channels_line, esi_keys_line;
    for (const auto& item : n) {
        const std::string key = r.scalar(item.first, "key");
        const YAML::Node& v = item.second;
        if (key == "name") {
            d.name = r.scalar(v, key);
            const bool ok = !d.name.empty() && std::all_of(d.name.begin(), d.name.end(), [](char c) {
                return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
            });
            if (!ok) r.fail(v, "name: letters, digits, '_', '-' and '.' only");
        } else if (key == "device") {
            ++sources;
            const std::string k = r.scalar(v, key);
            const auto* it = std::find_if(std::begin(kBuiltIn), std::end(kBuiltIn),
                                          [&](const Kind& b) { return b.name == k; });
            if (it == std::end(kBuiltIn)) {
                std::string names;  // every kind of the table (the list once missed hiwin-d2)
                for (const Kind& b : kBuiltIn)
                    names += (names.empty() ? "" : ", ") + std::string(b.name);
                r.fail(v, "device: unknown device " + k + " (" + names + ")");
            }
            d.source = it->source;
        } else if (key == "esi" || key == "sii") {
            ++sources;
            d.source = key == "esi" ? Source::Esi : Source::Sii;
            d.path = r.scalar(v, key);
            if (d.path.empty()) r.fail(v, key + ": the path of a file");
            if (std::filesystem::path(d.path).is_relative())
                d.path = (std::filesystem::path(folder) / d.path).string();
        } else if (key == "type") {
            d.esi_type = r.scalar(v, key);
            esi_keys_line = Reader::line(v);
        } else if (key == "product") {
            d.esi_product = static_cast<std::uint32_t>(r.number(v, key, 0xFFFFFFFFu));
            esi_keys_line = Reader::line(v);
        } else if (key == "revision") {
            d.esi_revision = static_cast<std::uint32_t>(r.number(v, key, 0xFFFFFFFFu));
            esi_keys_line = Reader::line(v);
        } else if (key == "modules") {
            parse_modules(r, v, d);
        } else if (key == "channels") {
            d.channels = static_cast<unsigned>(r.number(v, key, kMaxChannels));
            if (d.channels == 0) r.fail(v, "channels: at least 1");
            channels_line = Reader::line(v);
        } else if (key == "upstream") {
            parse_upstream(r, v, d);
        } else if (key == "cable_delay_ns") {
            d.cable_delay_ns = static_cast<std::uint32_t>(r.number(v, key, 1'000'000));
        } else if (key == "alias") {
            d.station_alias = static_cast<std::uint16_t>(r.number(v, key, 0xFFFF));
        } else if (key == "identity") {
            parse_identity(r, v, d.identity);
        } else if (key == "dictionary") {
            d.dictionary = r.scalar(v, key);
            d.dictionary_line = Reader::line(v);
            if (d.dictionary.empty()) r.fail(v, "dictionary: the path of a dictionary file");
            if (std::filesystem::path(d.dictionary).is_relative())
                d.dictionary = (std::filesystem::path(folder) / d.dictionary).string();
        } else if (key == "esc") {
            parse_esc(r, v, d.esc);
        } else if (key == "inputs") {
            parse_inputs(r, v, d, folder);
        } else if (key == "quirks") {
            parse_quirks(r, v, d);
        } else if (key == "hot_connect") {
            d.hot_connect = r.scalar(v, key);
            d.hot_connect_line = Reader::line(v);
            if (d.hot_connect.empty()) r.fail(v, "hot_connect: the name of the group");
        } else {
            r.fail(item.first,
                   "unknown key " + key +
                       " (name, device, esi, sii, type, product, revision, modules, channels, upstream, "
                       "cable_delay_ns, alias, identity, dictionary, esc, hot_connect, inputs, quirks)");
        }
    }
    if (d.name.empty()) r.fail(d.line, "a device without name:");
    if (sources != 1) r.fail(d.line, d.name + ": give exactly one of device:, esi: and sii:");
    if (esi_keys_line && d.source != Source::Esi)
        r.fail(*esi_keys_line, d.name + ": type:, product: and revision: select a device of an esi: file");
    if (d.modules_line && d.source != Source::Esi)
        r.fail(d.modules_line, d.name + ": modules: chooses the modules of a modular device of an esi: file");
    if (d.dictionary_line && d.source != Source::Sii)
        r.fail(d.dictionary_line, d.name + ": dictionary: is for an sii: device");
    if (d.quirks.sii_without && d.source == Source::Sii)
        r.fail(d.quirks_line, d.name + ": quirks: sii_without: an sii: device serves its dump as it is");
    if (channels_line && !is_io(d.source))
        r.fail(*channels_line, d.name + ": channels: is for the built-in I/O terminals");
    if (d.inputs_line && d.source != Source::DigitalIn && d.source != Source::AnalogIn &&
        d.source != Source::Drive)
        r.fail(d.inputs_line, d.name +
                                  ": inputs: is for the built-in input terminals (digital-in, analog-in) and "
                                  "the touch probe inputs of the vecat drive (device: drive)");
    for (const auto& in : d.inputs)
        if (in.channel >= input_channels(d))
            r.fail(in.line, d.name + ": inputs: channel " + std::to_string(in.channel) +
                                ": it has channels 0-" + std::to_string(input_channels(d) - 1) +
                                (d.source == Source::Drive ? " (touch probe inputs 1 and 2)" : ""));
    return d;
}

}  // namespace

std::string_view to_string(Source s) noexcept {
    switch (s) {
        case Source::Drive:
            return "drive";
        case Source::HiwinD2:
            return "hiwin-d2";
        case Source::SoeDrive:
            return "soe-drive";
        case Source::SoeDrive2:
            return "soe-drive-2";
        case Source::Esi:
            return "esi";
        case Source::Sii:
            return "sii";
        case Source::Coupler:
            return "coupler";
        case Source::Junction:
            return "junction";
        case Source::DigitalIn:
            return "digital-in";
        case Source::DigitalOut:
            return "digital-out";
        case Source::AnalogIn:
            return "analog-in";
        case Source::AnalogOut:
            return "analog-out";
    }
    return "?";
}

std::uint8_t default_ports(Source s) noexcept {
    switch (s) {
        case Source::Coupler:
            return 0b1011;
        case Source::Junction:
        case Source::Esi:
        case Source::Sii:
            return 0b1111;
        default:
            return 0b0011;
    }
}

NetworkFile parse_network(const std::string& yaml_text, const std::string& name, const std::string& folder) {
    const Reader r(name);
    YAML::Node root;
    try {
        root = YAML::Load(yaml_text);
    } catch (const YAML::ParserException& x) {
        r.fail(static_cast<unsigned>(x.mark.line + 1), x.msg);
    } catch (const YAML::Exception& x) {
        throw NetworkFileError(name + ": " + x.what());
    }
    if (!root.IsMap()) throw NetworkFileError(name + ": a network file is a map with devices:");
    YAML::Node list, redundancy;
    bool has_redundancy = false;
    for (const auto& item : root) {
        const std::string key = r.scalar(item.first, "key");
        if (key == "devices")
            list = item.second;
        else if (key == "redundancy")
            redundancy = item.second, has_redundancy = true;
        else
            r.fail(item.first, "unknown key " + key + " (devices, redundancy)");
    }
    if (!list || !list.IsSequence() || list.size() == 0)
        throw NetworkFileError(name + ": devices: a list of at least one device");
    std::vector<bool> explicit_upstream;
    std::vector<DeviceEntry> devices;
    for (const auto& n : list) {
        devices.push_back(parse_device(r, n, folder));
        explicit_upstream.push_back(n["upstream"].IsDefined());
    }
    NetworkFile f = arrange_network(std::move(devices), explicit_upstream, name, folder);
    // Hot connect groups: each name heads one group (the device and everything downstream of it).
    std::map<std::string, const DeviceEntry*> groups;
    for (const DeviceEntry& d : f.devices) {
        if (d.hot_connect.empty()) continue;
        const auto [it, fresh] = groups.emplace(d.hot_connect, &d);
        if (!fresh)
            r.fail(d.hot_connect_line, d.name + ": hot_connect: " + d.hot_connect + " heads the group of " +
                                           it->second->name + " (line " +
                                           std::to_string(it->second->hot_connect_line) +
                                           "); a group is a device and everything downstream of it");
    }
    // Wires: each names an output terminal of the file, or a vecat drive (its digital outputs), and one of
    // its channels; or a device of an ESI file or SII dump (its outputs, checked when it is made).
    for (const DeviceEntry& d : f.devices)
        for (const auto& in : d.inputs) {
            if (in.signal.kind != io::SignalKind::Wire) continue;
            const auto it = std::find_if(f.devices.begin(), f.devices.end(),
                                         [&](const DeviceEntry& o) { return o.name == in.signal.device; });
            if (it == f.devices.end())
                r.fail(in.line, d.name + ": wire: no device named " + in.signal.device);
            // A device of an ESI file or SII dump: its output PDO entries are checked when it is made.
            if (it->source == Source::Esi || it->source == Source::Sii) continue;
            if (in.signal.wire_entry)
                r.fail(in.line, d.name + ": wire: " + it->name +
                                    " is a built-in device: a wire names its channel (DEVICE:CHANNEL); "
                                    "DEVICE:0xINDEX:SUB is for devices of ESI files and SII dumps");
            if (output_channels(*it) == 0)
                r.fail(in.line, d.name + ": wire: " + it->name +
                                    " is no output terminal (digital-out, analog-out) and no vecat drive "
                                    "(device: drive, its digital outputs 0x60FE)");
            if (in.signal.channel >= output_channels(*it))
                r.fail(in.line, d.name + ": wire: " + it->name + " has channels 0-" +
                                    std::to_string(output_channels(*it) - 1));
        }
    if (has_redundancy) {
        // The same NAME:PORT as upstream:, for the port the redundancy cable leaves the line at.
        DeviceEntry at;
        parse_upstream(r, redundancy, at);
        const std::string key = "redundancy: ";
        const auto it = std::find_if(f.devices.begin(), f.devices.end(),
                                     [&](const DeviceEntry& d) { return d.name == at.upstream; });
        if (it == f.devices.end()) r.fail(redundancy, key + "no device named " + at.upstream);
        const auto i = static_cast<std::size_t>(it - f.devices.begin());
        if (!((default_ports(it->source) >> at.upstream_port) & 1u))
            r.fail(redundancy, key + it->name + " (" + std::string(to_string(it->source)) + ") has no port " +
                                   std::to_string(at.upstream_port));
        if (const int c = f.children[i][at.upstream_port]; c >= 0)
            r.fail(redundancy, key + "port " + std::to_string(at.upstream_port) + " of " + it->name +
                                   " is already cabled to " + f.devices[static_cast<std::size_t>(c)].name);
        f.redundancy_device = static_cast<int>(i);
        f.redundancy_port = at.upstream_port;
        f.redundancy_line = Reader::line(redundancy);
    }
    return f;
}

NetworkFile arrange_network(std::vector<DeviceEntry> devices, const std::vector<bool>& explicit_upstream,
                            const std::string& name, const std::string& folder) {
    const Reader r(name);
    NetworkFile f;
    f.folder = folder;
    f.devices = std::move(devices);
    // Names, then each device's upstream: the device before it in the list (port 1) unless given.
    std::map<std::string, std::size_t> by_name;
    for (std::size_t i = 0; i < f.devices.size(); ++i) {
        const auto [it, fresh] = by_name.emplace(f.devices[i].name, i);
        if (!fresh)
            r.fail(f.devices[i].line, "a second device named " + f.devices[i].name +
                                          " (the first is on line " +
                                          std::to_string(f.devices[it->second].line) + ")");
    }
    const std::size_t n = f.devices.size();
    f.parent.assign(n, -1);
    f.children.assign(n, {-1, -1, -1, -1});
    if (explicit_upstream[0])
        r.fail(f.devices[0].line,
               f.devices[0].name + ": the first device is cabled to the master: no upstream:");
    for (std::size_t i = 1; i < n; ++i) {
        DeviceEntry& d = f.devices[i];
        if (!explicit_upstream[i]) d.upstream = f.devices[i - 1].name;
        const auto it = by_name.find(d.upstream);
        if (it == by_name.end()) r.fail(d.line, d.name + ": upstream: no device named " + d.upstream);
        if (it->second == i) r.fail(d.line, d.name + ": cabled to itself");
        const DeviceEntry& up = f.devices[it->second];
        if (!((default_ports(up.source) >> d.upstream_port) & 1u))
            r.fail(d.line, d.name + ": " + up.name + " (" + std::string(to_string(up.source)) +
                               ") has no port " + std::to_string(d.upstream_port));
        int& slot = f.children[it->second][d.upstream_port];
        if (slot >= 0)
            r.fail(d.line, d.name + ": port " + std::to_string(d.upstream_port) + " of " + up.name +
                               " is already cabled to " + f.devices[static_cast<std::size_t>(slot)].name +
                               " (line " + std::to_string(f.devices[static_cast<std::size_t>(slot)].line) +
                               (explicit_upstream[i] ? ")" : "); give upstream: NAME:PORT"));
        slot = static_cast<int>(i);
        f.parent[i] = static_cast<int>(it->second);
    }
    // A tree: every device leads to the first one (the master's) through its upstream devices.
    for (std::size_t i = 0; i < n; ++i) {
        std::size_t at = i, steps = 0;
        while (f.parent[at] >= 0 && steps <= n) {
            at = static_cast<std::size_t>(f.parent[at]);
            ++steps;
        }
        if (steps > n) r.fail(f.devices[i].line, f.devices[i].name + ": its upstream cables form a loop");
    }

    // The order the frame reaches them: depth first from the master, ports 3, 1, 2 of each device.
    const std::vector<std::size_t> order = protocol::frame_order(f.children);
    std::vector<int> position(n, -1);
    for (std::size_t k = 0; k < order.size(); ++k)
        position[order[k]] = static_cast<int>(k);
    NetworkFile out;
    out.folder = f.folder;
    for (std::size_t k = 0; k < order.size(); ++k) {
        const std::size_t i = order[k];
        out.devices.push_back(f.devices[i]);
        out.parent.push_back(f.parent[i] < 0 ? -1 : position[static_cast<std::size_t>(f.parent[i])]);
        std::array<int, kPorts> ch{-1, -1, -1, -1};
        for (unsigned p = 0; p < kPorts; ++p)
            if (f.children[i][p] >= 0) ch[p] = position[static_cast<std::size_t>(f.children[i][p])];
        out.children.push_back(ch);
    }
    return out;
}

unsigned channels_of(const DeviceEntry& d) noexcept {
    if (d.channels) return d.channels;
    return d.source == Source::DigitalIn || d.source == Source::DigitalOut ? 8u : 4u;
}

unsigned input_channels(const DeviceEntry& d) noexcept {
    if (d.source == Source::Drive) return kDriveProbeInputs;
    return d.source == Source::DigitalIn || d.source == Source::AnalogIn ? channels_of(d) : 0;
}

unsigned output_channels(const DeviceEntry& d) noexcept {
    if (d.source == Source::Drive) return kDriveDigitalOutputs;
    return d.source == Source::DigitalOut || d.source == Source::AnalogOut ? channels_of(d) : 0;
}

NetworkFile read_network_file(const std::string& path) {
    std::string why;
    const auto text = read_whole_file(path, kMaxTextFileBytes, why);
    if (!text) throw NetworkFileError(path + ": " + why);
    const auto folder = std::filesystem::path(path).parent_path();
    return parse_network(*text, path, folder.empty() ? "." : folder.string());
}

}  // namespace vecat::network
