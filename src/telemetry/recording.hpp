// What a subscriber received, kept in memory: written to CSV (one file per topic), read back, and turned
// into scope pictures by signal name. Columns and signals are one table per record type, so the CSV
// header, the signal names of `vecat scope --signals` and the plot units cannot disagree.
#pragma once

#include <string>
#include <vector>

#include "telemetry/plot.hpp"
#include "telemetry/samples.hpp"

namespace vecat::telemetry {

struct Recording {
    std::vector<AxisSample> axes;
    std::vector<SlaveStatus> status;
    std::vector<TwinsyncSample> twinsync;
    std::vector<Event> events;
    std::vector<IoSample> io;
    void add(const Record& r);
};

// Writes the axis samples to path and, when any were received, the other topics beside it
// (FILE-status.csv, FILE-twinsync.csv, FILE-events.csv, FILE-io.csv for FILE.csv). False when a file cannot
// be written.
bool write_csv(const Recording& r, const std::string& path, std::string* why = nullptr);
// Reads what write_csv wrote (the files beside path are optional).
bool read_csv(const std::string& path, Recording& r, std::string* why = nullptr);
std::string csv_sibling(const std::string& path, const std::string& topic);

// A signal of `vecat scope`: "position_actual" (axis samples), "twinsync.tracking_error",
// "status.dc_time_difference_ns", "io.in3" / "io.out0" (channel 3 of an I/O terminal's inputs, channel 0 of
// its outputs, c < kIoChannels).
struct SignalInfo {
    std::string name;
    std::string quantity;  // y axis text
    std::string unit;
};
std::vector<SignalInfo> signal_list();
bool known_signal(const std::string& name);

// Signal groups: panels separated by ',' and signals of one panel joined by '+', e.g.
// "position_demand+position_actual,following_error". Empty: the default groups.
std::vector<std::vector<std::string>> parse_signal_groups(const std::string& spec,
                                                          std::string* why = nullptr);
inline constexpr const char* kDefaultSignals =
    "position_actual+position_demand,following_error,velocity_actual,torque_actual";

// One lane (group) per I/O channel the recording holds: io.in0.. up to the most input channels of any
// terminal, then io.out0..; empty without I/O samples. The demo adds them to its picture.
std::vector<std::vector<std::string>> io_lanes(const Recording& r);

// One panel per group, one series per signal and axis (slave) in the recording; time from the first sample.
// slaves: only these positions (empty: all).
Plot make_plot(const Recording& r, const std::vector<std::vector<std::string>>& groups,
               const std::string& title, const std::vector<unsigned>& slaves = {});

}  // namespace vecat::telemetry
