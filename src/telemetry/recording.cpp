#include "telemetry/recording.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>

namespace vecat::telemetry {

void Recording::add(const Record& r) {
    std::visit(
        [this](const auto& v) {
            using T = std::decay_t<decltype(v)>;
            if constexpr (std::is_same_v<T, AxisSample>)
                axes.push_back(v);
            else if constexpr (std::is_same_v<T, SlaveStatus>)
                status.push_back(v);
            else if constexpr (std::is_same_v<T, TwinsyncSample>)
                twinsync.push_back(v);
            else if constexpr (std::is_same_v<T, IoSample>)
                io.push_back(v);
            else
                events.push_back(v);
        },
        r);
}

namespace {

// One column of a record type: CSV header, plot text, and access (long double holds every 64-bit value).
template <class T>
struct Column {
    const char* name;
    const char* quantity;
    const char* unit;
    bool integer;
    long double (*get)(const T&);
    void (*set)(T&, long double);
};

#define VECAT_COLUMN(T, field, quantity, unit)                                     \
    Column<T> {                                                                    \
#field, quantity, unit, std::is_integral_v<decltype(T::field)>,                  \
            [](const T& s) -> long double { return static_cast<long double>(s.field); }, \
            [](T& s, long double v) { s.field = static_cast<decltype(T::field)>(v); } \
    }

const std::vector<Column<AxisSample>>& axis_columns() {
    using A = AxisSample;
    static const std::vector<Column<A>> c{
        VECAT_COLUMN(A, time_ns, "time", "ns"),
        VECAT_COLUMN(A, cycle, "cycle", ""),
        VECAT_COLUMN(A, slave, "slave", ""),
        VECAT_COLUMN(A, axis, "axis", ""),
        VECAT_COLUMN(A, cia402_state, "CiA 402 state", ""),
        VECAT_COLUMN(A, mode, "mode of operation", ""),
        VECAT_COLUMN(A, controlword, "controlword", ""),
        VECAT_COLUMN(A, statusword, "statusword", ""),
        VECAT_COLUMN(A, error_code, "error code", ""),
        VECAT_COLUMN(A, position_demand, "position", "inc"),
        VECAT_COLUMN(A, position_actual, "position", "inc"),
        VECAT_COLUMN(A, velocity_actual, "velocity", "inc/s"),
        VECAT_COLUMN(A, torque_actual, "torque", "\u2030 rated"),
        VECAT_COLUMN(A, following_error, "following error", "inc"),
    };
    return c;
}

const std::vector<Column<SlaveStatus>>& status_columns() {
    using S = SlaveStatus;
    static const std::vector<Column<S>> c{
        VECAT_COLUMN(S, time_ns, "time", "ns"),
        VECAT_COLUMN(S, slave, "slave", ""),
        VECAT_COLUMN(S, al_status, "AL status", ""),
        VECAT_COLUMN(S, al_status_code, "AL status code", ""),
        VECAT_COLUMN(S, dc_time_difference_ns, "DC system time difference", "ns"),
        VECAT_COLUMN(S, watchdog_pd_expiries, "PD watchdog expiries", ""),
        VECAT_COLUMN(S, watchdog_pdi_expiries, "PDI watchdog expiries", ""),
        VECAT_COLUMN(S, rx_errors, "RX errors", ""),
        VECAT_COLUMN(S, lost_links, "lost links", ""),
        VECAT_COLUMN(S, frames, "process data exchanges", ""),
        VECAT_COLUMN(S, mailbox_errors, "mailbox errors", ""),
        VECAT_COLUMN(S, emergencies, "emergencies", ""),
    };
    return c;
}

const std::vector<Column<TwinsyncSample>>& twinsync_columns() {
    using T = TwinsyncSample;
    static const std::vector<Column<T>> c{
        VECAT_COLUMN(T, time_ns, "time", "ns"),
        VECAT_COLUMN(T, slave, "slave", ""),
        VECAT_COLUMN(T, axis, "axis", ""),
        VECAT_COLUMN(T, mode, "TWINsync mode", ""),
        VECAT_COLUMN(T, tx_statusword, "TWINsync statusword sent", ""),
        VECAT_COLUMN(T, rx_statusword, "TWINsync statusword received", ""),
        VECAT_COLUMN(T, comm_status, "TWINsync communication status", ""),
        VECAT_COLUMN(T, synchronised, "synchronised", ""),
        VECAT_COLUMN(T, link_ok, "link ok", ""),
        VECAT_COLUMN(T, error_number, "error number", ""),
        VECAT_COLUMN(T, frames_sent, "frames sent", ""),
        VECAT_COLUMN(T, frames_received, "frames received", ""),
        VECAT_COLUMN(T, crc_errors, "CRC errors", ""),
        VECAT_COLUMN(T, frames_missing, "frames missing", ""),
        VECAT_COLUMN(T, sync_offset_ns, "sync offset", "ns"),
        VECAT_COLUMN(T, tracking_error, "tracking error", "inc"),
    };
    return c;
}

const std::vector<Column<Event>>& event_columns() {
    using E = Event;
    static const std::vector<Column<E>> c{
        VECAT_COLUMN(E, time_ns, "time", "ns"),
        VECAT_COLUMN(E, slave, "slave", ""),
        VECAT_COLUMN(E, axis, "axis", ""),
        Column<E>{
            "kind", "event", "", true,
            [](const E& e) -> long double { return static_cast<long double>(static_cast<int>(e.kind)); },
            [](E& e, long double v) { e.kind = static_cast<EventKind>(static_cast<int>(v)); }},
        VECAT_COLUMN(E, code, "code", ""),
        VECAT_COLUMN(E, old_value, "old value", ""),
        VECAT_COLUMN(E, new_value, "new value", ""),
    };
    return c;
}

// The I/O sample: its header fields, then one column per channel and direction (in0..in15, out0..out15).
// A channel's quantity and unit depend on the terminal (bits or raw 16-bit counts): "I/O channel", no unit.
template <unsigned I, bool Out>
Column<IoSample> io_channel_column() {
    static const std::string name = (Out ? "out" : "in") + std::to_string(I);
    return Column<IoSample>{
        name.c_str(),
        "I/O channel",
        "",
        true,
        [](const IoSample& s) -> long double { return static_cast<long double>(Out ? s.out[I] : s.in[I]); },
        [](IoSample& s, long double v) { (Out ? s.out[I] : s.in[I]) = static_cast<std::int16_t>(v); }};
}

template <unsigned... I>
void add_io_channels(std::vector<Column<IoSample>>& c, std::integer_sequence<unsigned, I...>) {
    (c.push_back(io_channel_column<I, false>()), ...);
    (c.push_back(io_channel_column<I, true>()), ...);
}

const std::vector<Column<IoSample>>& io_columns() {
    using S = IoSample;
    static const std::vector<Column<S>> c = [] {
        std::vector<Column<S>> cols{
            VECAT_COLUMN(S, time_ns, "time", "ns"),
            VECAT_COLUMN(S, cycle, "cycle", ""),
            VECAT_COLUMN(S, slave, "slave", ""),
            VECAT_COLUMN(S, analog, "analog", ""),
            VECAT_COLUMN(S, in_channels, "input channels", ""),
            VECAT_COLUMN(S, out_channels, "output channels", ""),
        };
        add_io_channels(cols, std::make_integer_sequence<unsigned, kIoChannels>{});
        return cols;
    }();
    return c;
}

// Whether column i of io_columns() is a channel the sample holds (in_channels / out_channels).
bool io_channel_valid(const IoSample& s, std::size_t column) {
    constexpr std::size_t first = 6;  // the header fields above
    if (column < first) return true;
    const std::size_t k = column - first;
    return k < kIoChannels ? k < s.in_channels : k - kIoChannels < s.out_channels;
}

#undef VECAT_COLUMN

template <class T>
bool write_table(const std::string& path, const std::vector<Column<T>>& cols, const std::vector<T>& rows,
                 std::string* why, bool event_names = false) {
    std::ofstream f(path);
    if (!f) {
        if (why) *why = "cannot write " + path;
        return false;
    }
    std::string line;
    for (std::size_t i = 0; i < cols.size(); ++i)
        line += (i ? "," : "") + std::string(cols[i].name);
    if (event_names) line += ",what";
    f << line << '\n';
    for (const T& r : rows) {
        line.clear();
        for (std::size_t i = 0; i < cols.size(); ++i) {
            if (i) line += ',';
            const long double v = cols[i].get(r);
            if (cols[i].integer)
                line += v < 0 ? fmt::format("{}", static_cast<long long>(v))
                              : fmt::format("{}", static_cast<unsigned long long>(v));
            else
                line += fmt::format("{}", static_cast<double>(v));
        }
        if constexpr (std::is_same_v<T, Event>)
            if (event_names) line += std::string(",") + to_string(r.kind);
        f << line << '\n';
    }
    return static_cast<bool>(f);
}

std::vector<std::string> split(const std::string& s, char c) {
    std::vector<std::string> v;
    std::string item;
    std::stringstream ss(s);
    while (std::getline(ss, item, c))
        v.push_back(item);
    return v;
}

// Reads a table by its header: unknown columns are ignored, missing ones stay at their defaults.
template <class T>
bool read_table(const std::string& path, const std::vector<Column<T>>& cols, std::vector<T>& rows,
                std::string* why) {
    std::ifstream f(path);
    if (!f) {
        if (why) *why = "cannot read " + path;
        return false;
    }
    std::string line;
    if (!std::getline(f, line)) return true;
    std::vector<int> which;  // column of the table for each CSV column, -1: unknown
    for (const auto& h : split(line, ',')) {
        int idx = -1;
        for (std::size_t i = 0; i < cols.size(); ++i)
            if (h == cols[i].name) idx = static_cast<int>(i);
        which.push_back(idx);
    }
    while (std::getline(f, line)) {
        if (line.empty()) continue;
        T r{};
        const auto fields = split(line, ',');
        for (std::size_t i = 0; i < fields.size() && i < which.size(); ++i) {
            if (which[i] < 0) continue;
            const auto& c = cols[static_cast<std::size_t>(which[i])];
            const char* s = fields[i].c_str();
            char* end = nullptr;
            long double v;
            if (c.integer)
                v = fields[i][0] == '-' ? static_cast<long double>(std::strtoll(s, &end, 10))
                                        : static_cast<long double>(std::strtoull(s, &end, 10));
            else
                v = std::strtold(s, &end);
            if (end == s) {
                if (why) *why = fmt::format("{}: bad value \"{}\" in column {}", path, fields[i], c.name);
                return false;
            }
            c.set(r, v);
        }
        rows.push_back(r);
    }
    return true;
}

struct SignalRef {
    enum Topic { Axis, Status, Twinsync, Io } topic;
    std::size_t column;
};

bool find_signal(const std::string& name, SignalRef& ref) {
    auto look = [&](const auto& cols, SignalRef::Topic t, const std::string& n) {
        for (std::size_t i = 0; i < cols.size(); ++i)
            if (n == cols[i].name && std::string(cols[i].name) != "time_ns") {
                ref = {t, i};
                return true;
            }
        return false;
    };
    if (name.rfind("twinsync.", 0) == 0) return look(twinsync_columns(), SignalRef::Twinsync, name.substr(9));
    if (name.rfind("status.", 0) == 0) return look(status_columns(), SignalRef::Status, name.substr(7));
    if (name.rfind("io.", 0) == 0) {
        const std::string ch = name.substr(3);
        if (ch.rfind("in", 0) != 0 && ch.rfind("out", 0) != 0) return false;  // only the channels
        return look(io_columns(), SignalRef::Io, ch);
    }
    return look(axis_columns(), SignalRef::Axis, name);
}

bool step_like(const std::string& name) {
    static const char* kWords[] = {"state", "word", "mode", "status", "code", "synchronised", "link_ok"};
    for (const char* w : kWords)
        if (name.find(w) != std::string::npos) return true;
    return false;
}

}  // namespace

std::string csv_sibling(const std::string& path, const std::string& topic) {
    const auto dot = path.rfind('.');
    const auto slash = path.rfind('/');
    const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash);
    return (has_ext ? path.substr(0, dot) : path) + "-" + topic + (has_ext ? path.substr(dot) : ".csv");
}

bool write_csv(const Recording& r, const std::string& path, std::string* why) {
    if (!write_table(path, axis_columns(), r.axes, why)) return false;
    if (!r.status.empty() && !write_table(csv_sibling(path, "status"), status_columns(), r.status, why))
        return false;
    if (!r.twinsync.empty() &&
        !write_table(csv_sibling(path, "twinsync"), twinsync_columns(), r.twinsync, why))
        return false;
    if (!r.events.empty() && !write_table(csv_sibling(path, "events"), event_columns(), r.events, why, true))
        return false;
    if (!r.io.empty() && !write_table(csv_sibling(path, "io"), io_columns(), r.io, why)) return false;
    return true;
}

bool read_csv(const std::string& path, Recording& r, std::string* why) {
    if (!read_table(path, axis_columns(), r.axes, why)) return false;
    auto optional = [&](const std::string& topic, const auto& cols, auto& rows) {
        const std::string p = csv_sibling(path, topic);
        if (!std::ifstream(p)) return true;
        return read_table(p, cols, rows, why);
    };
    return optional("status", status_columns(), r.status) &&
           optional("twinsync", twinsync_columns(), r.twinsync) &&
           optional("events", event_columns(), r.events) && optional("io", io_columns(), r.io);
}

std::vector<SignalInfo> signal_list() {
    std::vector<SignalInfo> v;
    auto add = [&](const auto& cols, const std::string& prefix) {
        for (const auto& c : cols) {
            const std::string n = c.name;
            if (n == "time_ns" || n == "slave" || n == "axis") continue;
            v.push_back({prefix + n, c.quantity, c.unit});
        }
    };
    add(axis_columns(), "");
    add(twinsync_columns(), "twinsync.");
    add(status_columns(), "status.");
    for (const auto& c : io_columns()) {
        const std::string n = c.name;
        if (n.rfind("in", 0) == 0 && n != "in_channels") v.push_back({"io." + n, "I/O input", "0/1 or raw"});
        if (n.rfind("out", 0) == 0 && n != "out_channels")
            v.push_back({"io." + n, "I/O output", "0/1 or raw"});
    }
    return v;
}

bool known_signal(const std::string& name) {
    SignalRef ref{};
    return find_signal(name, ref);
}

std::vector<std::vector<std::string>> parse_signal_groups(const std::string& spec, std::string* why) {
    std::vector<std::vector<std::string>> groups;
    for (const auto& g : split(spec.empty() ? std::string(kDefaultSignals) : spec, ',')) {
        std::vector<std::string> names;
        for (const auto& n : split(g, '+')) {
            if (n.empty()) continue;
            if (!known_signal(n)) {
                if (why) *why = "unknown signal \"" + n + "\" (vecat scope --list-signals lists them)";
                return {};
            }
            names.push_back(n);
        }
        if (!names.empty()) groups.push_back(std::move(names));
    }
    return groups;
}

std::vector<std::vector<std::string>> io_lanes(const Recording& r) {
    unsigned in = 0, out = 0;
    for (const auto& s : r.io) {
        in = std::max<unsigned>(in, s.in_channels);
        out = std::max<unsigned>(out, s.out_channels);
    }
    std::vector<std::vector<std::string>> lanes;
    for (unsigned c = 0; c < in; ++c)
        lanes.push_back({fmt::format("io.in{}", c)});
    for (unsigned c = 0; c < out; ++c)
        lanes.push_back({fmt::format("io.out{}", c)});
    return lanes;
}

Plot make_plot(const Recording& r, const std::vector<std::vector<std::string>>& groups,
               const std::string& title, const std::vector<unsigned>& slaves) {
    Plot p;
    p.title = title;
    // Time zero: the first record of any topic.
    std::uint64_t t0 = UINT64_MAX;
    for (const auto& a : r.axes)
        t0 = std::min(t0, a.time_ns);
    for (const auto& s : r.status)
        t0 = std::min(t0, s.time_ns);
    for (const auto& t : r.twinsync)
        t0 = std::min(t0, t.time_ns);
    for (const auto& s : r.io)
        t0 = std::min(t0, s.time_ns);
    if (t0 == UINT64_MAX) t0 = 0;
    auto wanted = [&](unsigned slave) {
        return slaves.empty() || std::find(slaves.begin(), slaves.end(), slave) != slaves.end();
    };
    std::size_t several_slaves = 0;  // label series by slave only when more than one is shown
    {
        std::map<unsigned, int> seen;
        for (const auto& a : r.axes)
            if (wanted(a.slave)) seen[a.slave] = 1;
        for (const auto& t : r.twinsync)
            if (wanted(t.slave)) seen[t.slave] = 1;
        for (const auto& s : r.io)
            if (wanted(s.slave)) seen[s.slave] = 1;
        several_slaves = seen.size();
    }

    for (const auto& group : groups) {
        Panel pan;
        for (const auto& name : group) {
            SignalRef ref{};
            if (!find_signal(name, ref)) continue;
            std::map<unsigned, Series> by_slave;  // keyed by slave << 8 | axis
            std::map<unsigned, bool> digital;     // series of a digital terminal's channel: drawn as steps
            auto add_rows = [&](const auto& rows, const auto& cols) {
                const auto& c = cols[ref.column];
                if (pan.quantity.empty()) {
                    pan.quantity = c.quantity;
                    pan.unit = c.unit;
                } else if (pan.quantity != c.quantity) {
                    // A panel of different quantities keeps the unit of the first; name them all.
                    if (pan.quantity.find(c.quantity) == std::string::npos)
                        pan.quantity += ", " + std::string(c.quantity);
                }
                for (const auto& row : rows) {
                    if (!wanted(row.slave)) continue;
                    if constexpr (std::is_same_v<std::decay_t<decltype(row)>, IoSample>) {
                        if (!io_channel_valid(row, ref.column)) continue;  // the terminal lacks it
                        if (!row.analog) digital[row.slave << 8] = true;
                    }
                    unsigned axis = 0;
                    if constexpr (requires { row.axis; }) axis = row.axis;
                    Series& s = by_slave[static_cast<unsigned>(row.slave) << 8 | axis];
                    s.t.push_back(static_cast<double>(row.time_ns - t0) * 1e-9);
                    s.y.push_back(static_cast<double>(c.get(row)));
                }
            };
            if (ref.topic == SignalRef::Axis) add_rows(r.axes, axis_columns());
            if (ref.topic == SignalRef::Status) add_rows(r.status, status_columns());
            if (ref.topic == SignalRef::Twinsync) add_rows(r.twinsync, twinsync_columns());
            if (ref.topic == SignalRef::Io) add_rows(r.io, io_columns());
            for (auto& [key, s] : by_slave) {
                const unsigned slave = key >> 8, axis = key & 0xFF;
                s.label = name;
                if (several_slaves > 1 || axis != 0)
                    s.label = fmt::format("slave {}{} {}", slave, axis ? fmt::format(".{}", axis) : "", name);
                s.step = digital[key] || step_like(name);
                s.dashed = name.find("demand") != std::string::npos;
                pan.series.push_back(std::move(s));
            }
        }
        p.panels.push_back(std::move(pan));
    }
    return p;
}

}  // namespace vecat::telemetry
