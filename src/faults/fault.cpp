#include "faults/fault.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <stdexcept>

namespace vecat::faults {
namespace {

using K = FaultKind;

constexpr std::array kKinds{
    FaultKindInfo{"drop", K::Drop, "cable, direction",
                  "frames lost on a cable; slaves before it still process them, the master gets no reply"},
    FaultKindInfo{"corrupt", K::Corrupt, "cable, direction",
                  "frames with a wrong FCS on a cable: counted in the error counters 0x0300-0x030C of the "
                  "ESCs that see them, no reply"},
    FaultKindInfo{"delay", K::Delay, "delay", "replies held back by the given delay"},
    FaultKindInfo{"link_down", K::LinkDown, "slave, port",
                  "a port loses its link (DL status 0x0110, lost link counter 0x0310): frames turn back "
                  "before the break"},
    FaultKindInfo{"power_off", K::PowerOff, "slave",
                  "the slave loses power: the line ends before it; when the fault ends it restarts in INIT"},
    FaultKindInfo{"firmware_hang", K::FirmwareHang, "slave",
                  "the firmware stops: AL status, mailbox and inputs freeze; the ESC still forwards"},
    FaultKindInfo{"al_error", K::AlError, "slave, code, state",
                  "the application signals an AL error: AL status error bit, code in 0x0134, falls back"},
    FaultKindInfo{"sdo_abort", K::SdoAbort, "slave, code, index, subindex",
                  "SDO requests are answered with an abort code and not executed"},
    FaultKindInfo{"mailbox_lost_reply", K::MailboxLostReply, "slave",
                  "mailbox requests are executed but their replies never come"},
    FaultKindInfo{"encoder", K::EncoderFault, "slave", "drive fault 0x7305 (encoder) through 0x2101"},
    FaultKindInfo{"over_current", K::OverCurrent, "slave",
                  "drive fault 0x2310 (over-current) through 0x2101"},
    FaultKindInfo{"following_error", K::FollowingError, "slave",
                  "drive fault 0x8611 (following error) through 0x2101"},
    FaultKindInfo{"dc_drift", K::DcDrift, "slave, ppm | step_ppm",
                  "the slave's DC oscillator drift changes (restored when the fault ends)"},
    FaultKindInfo{
        "unplug", K::Unplug, "group | slave, to",
        "hot connect: the group (a device and everything downstream of it) is unplugged; when the "
        "fault ends it is plugged back (where it was, or with to=SLAVE:PORT into that free port) and "
        "starts in INIT, station address cleared"},
    FaultKindInfo{
        "set_input", K::External, "slave, channel, value",
        "an input of a built-in input terminal, or a touch probe input (channel 0/1) of a vecat drive, of a "
        "network file reads value until the fault ends (needs the I/O terminals' handler: vecat run "
        "--network)"},
    FaultKindInfo{"twinsync_cable_break", K::External, "slave",
                  "TWINsync: the drive-to-drive cable is cut (needs the TWINsync port's handler)"},
    FaultKindInfo{"twinsync_crc_errors", K::External, "slave",
                  "TWINsync: telegrams with a wrong CRC (needs the TWINsync port's handler)"},
    FaultKindInfo{"twinsync_sync_loss", K::External, "slave",
                  "TWINsync: the slave drive loses SYNC_OUT (needs the TWINsync port's handler)"},
};

template <class T>
T parse_int(std::string_view key, std::string_view v) {
    T out{};
    int base = 10;
    if (v.size() > 2 && v[0] == '0' && (v[1] == 'x' || v[1] == 'X')) {
        v.remove_prefix(2);
        base = 16;
    }
    const auto r = std::from_chars(v.data(), v.data() + v.size(), out, base);
    if (r.ec != std::errc() || r.ptr != v.data() + v.size())
        throw std::invalid_argument(std::string(key) + ": not a number: " + std::string(v));
    return out;
}

double parse_double(std::string_view key, std::string_view v) {
    try {
        std::size_t used = 0;
        const double d = std::stod(std::string(v), &used);
        if (used != v.size() || !std::isfinite(d)) throw std::invalid_argument("");
        return d;
    } catch (const std::exception&) {
        throw std::invalid_argument(std::string(key) + ": not a number: " + std::string(v));
    }
}

protocol::AlState parse_state(std::string_view v) {
    if (v == "init" || v == "INIT") return protocol::AlState::Init;
    if (v == "preop" || v == "PREOP") return protocol::AlState::PreOp;
    if (v == "safeop" || v == "SAFEOP") return protocol::AlState::SafeOp;
    if (v == "op" || v == "OP") return protocol::AlState::Op;
    throw std::invalid_argument("state: one of init, preop, safeop, op: " + std::string(v));
}

bool takes(const FaultKindInfo& k, std::string_view key) {
    // Whole words of the parameter list.
    std::string_view p = k.parameters;
    while (!p.empty()) {
        const auto end = p.find_first_of(",| ");
        const std::string_view w = p.substr(0, end);
        if (w == key) return true;
        if (end == std::string_view::npos) break;
        p.remove_prefix(end + 1);
    }
    return false;
}

}  // namespace

std::span<const FaultKindInfo> fault_kinds() {
    return kKinds;
}

const FaultKindInfo* find_kind(std::string_view name) {
    for (const auto& k : kKinds)
        if (k.name == name) return &k;
    return nullptr;
}

std::uint64_t parse_duration_ns(std::string_view v) {
    double scale = 1e9;
    std::string_view num = v;
    if (num.ends_with("ms")) {
        scale = 1e6;
        num.remove_suffix(2);
    } else if (num.ends_with("us")) {
        scale = 1e3;
        num.remove_suffix(2);
    } else if (num.ends_with("ns")) {
        scale = 1.0;
        num.remove_suffix(2);
    } else if (num.ends_with("s")) {
        num.remove_suffix(1);
    }
    const double d = parse_double("duration", num);
    if (d < 0 || d * scale > 1e18) throw std::invalid_argument("duration out of range: " + std::string(v));
    return static_cast<std::uint64_t>(std::llround(d * scale));
}

FaultSpec make_fault(std::string_view name, const KeyValues& kv) {
    FaultSpec f;
    f.name = std::string(name);
    const FaultKindInfo* info = find_kind(name);
    f.kind = info ? info->kind : FaultKind::External;
    if (name.empty()) throw std::invalid_argument("fault kind missing");
    // Defaults that differ per kind.
    if (f.kind == FaultKind::AlError)
        f.code = static_cast<std::uint32_t>(protocol::AlStatusCode::Unspecified);
    if (f.kind == FaultKind::SdoAbort) f.code = 0x08000000;  // general error
    for (const auto& [key, value] : kv) {
        f.params[key] = value;
        if (key == "id") {
            f.id = value;
        } else if (key == "slave") {
            f.slave = parse_int<std::size_t>(key, value);
        } else if (key == "probability") {
            f.probability = parse_double(key, value);
            if (f.probability < 0.0 || f.probability > 1.0)
                throw std::invalid_argument("probability: between 0 and 1");
        } else if (key == "count") {
            f.count = parse_int<std::uint64_t>(key, value);
        } else if (key == "duration") {
            f.duration_ns = parse_duration_ns(value);
        } else if (f.kind == FaultKind::External) {
            // the handler reads its own keys from params
        } else if (!takes(*info, key)) {
            throw std::invalid_argument(std::string(name) + " takes no parameter '" + key + "' (it takes " +
                                        std::string(info->parameters) +
                                        ", and id, probability, count, duration)");
        } else if (key == "cable") {
            f.cable = parse_int<std::size_t>(key, value);
        } else if (key == "direction") {
            if (value != "out" && value != "back") throw std::invalid_argument("direction: out or back");
            f.returning = value == "back";
        } else if (key == "port") {
            f.port = parse_int<unsigned>(key, value);
            if (f.port > 3) throw std::invalid_argument("port: 0 to 3");
        } else if (key == "group") {
            if (value.empty()) throw std::invalid_argument("group: the name of a hot connect group");
            f.group = value;
        } else if (key == "to") {
            const auto colon = value.find(':');
            if (colon == std::string::npos) throw std::invalid_argument("to: SLAVE:PORT (e.g. to=2:3)");
            f.elsewhere = true;
            f.to_slave = parse_int<std::size_t>(key, value.substr(0, colon));
            f.to_port = parse_int<unsigned>(key, value.substr(colon + 1));
            if (f.to_port < 1 || f.to_port > 3) throw std::invalid_argument("to: the port is 1, 2 or 3");
        } else if (key == "delay") {
            f.delay_ns = parse_duration_ns(value);
        } else if (key == "code") {
            f.code = parse_int<std::uint32_t>(key, value);
        } else if (key == "state") {
            f.state = parse_state(value);
        } else if (key == "index") {
            f.index = parse_int<std::uint16_t>(key, value);
        } else if (key == "subindex") {
            f.subindex = parse_int<std::uint8_t>(key, value);
        } else if (key == "ppm" || key == "step_ppm") {
            f.ppm = parse_double(key, value);
            f.ppm_is_step = key == "step_ppm";
            if (std::abs(f.ppm) > 1000.0) throw std::invalid_argument("ppm: at most 1000");
        }
    }
    if (f.kind == FaultKind::AlError && (f.code == 0 || f.code > 0xFFFF))
        throw std::invalid_argument("al_error: code must be an AL status code 0x0001-0xFFFF");
    if (f.kind == FaultKind::Delay && f.delay_ns == 0) throw std::invalid_argument("delay: give delay=...");
    if (f.kind == FaultKind::DcDrift && !f.params.contains("ppm") && !f.params.contains("step_ppm"))
        throw std::invalid_argument("dc_drift: give ppm=... or step_ppm=...");
    return f;
}

FaultSpec parse_fault(std::string_view line) {
    KeyValues kv;
    std::string name;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t'))
            ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t')
            ++i;
        const std::string_view word = line.substr(start, i - start);
        if (word.empty()) break;
        if (name.empty()) {
            name = std::string(word);
            continue;
        }
        const auto eq = word.find('=');
        if (eq == std::string_view::npos || eq == 0)
            throw std::invalid_argument("expected key=value: " + std::string(word));
        kv.emplace_back(std::string(word.substr(0, eq)), std::string(word.substr(eq + 1)));
    }
    return make_fault(name, kv);
}

std::string describe(const FaultSpec& f) {
    std::string s = f.id + " " + f.name;
    for (const auto& [k, v] : f.params)
        if (k != "id") s += " " + k + "=" + v;
    return s;
}

}  // namespace vecat::faults
