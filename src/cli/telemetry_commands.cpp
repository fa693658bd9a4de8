#include "cli/telemetry_commands.hpp"

#include <fmt/core.h>
#include <signal.h>

#include <atomic>
#include <fstream>

#include "telemetry/dds.hpp"
#include "telemetry/local_recorder.hpp"
#include "telemetry/plot.hpp"
#include "telemetry/recording.hpp"
#include "telemetry/sampler.hpp"

namespace vecat::cli {

namespace tm = vecat::telemetry;

void add_telemetry_options(CLI::App* run, TelemetryOptions& o) {
    run->add_flag("--telemetry", o.enabled,
                  "Publish telemetry over Cyclone DDS (axis samples, slave status, TWINsync, events; see "
                  "vecat scope)");
    run->add_option("--telemetry-decimation", o.decimation,
                    "One axis sample every N process data cycles (default 1: every cycle)")
        ->check(CLI::Range(1u, 1'000'000u));
    run->add_option("--dds-domain", o.domain, "DDS domain of the telemetry (default 0)")
        ->check(CLI::Range(0u, 232u));
}

struct RunTelemetry::Impl {
    tm::TelemetryQueue queue;
    std::unique_ptr<tm::Sampler> sampler;
    std::unique_ptr<tm::Publisher> publisher;
};

std::unique_ptr<RunTelemetry> RunTelemetry::start(esc::Segment& seg, const TelemetryOptions& o,
                                                  net::ServeOptions& serve) {
    auto t = std::unique_ptr<RunTelemetry>(new RunTelemetry);
    if (!o.enabled) return t;
    if (!tm::dds_built_in()) {
        fmt::print(stderr, "vecat: --telemetry: {}\n", tm::kNotBuiltIn);
        return nullptr;
    }
    t->impl_ = std::make_unique<Impl>();
    try {
        t->impl_->publisher = std::make_unique<tm::Publisher>(t->impl_->queue, o.domain);
    } catch (const std::exception& e) {
        fmt::print(stderr, "vecat: --telemetry: {}\n", e.what());
        return nullptr;
    }
    tm::SamplerOptions so;
    so.decimation = o.decimation;
    t->impl_->sampler = std::make_unique<tm::Sampler>(seg, t->impl_->queue, so);
    t->impl_->publisher->start();
    serve.after_frame = &tm::Sampler::after_frame;
    serve.after_frame_context = t->impl_->sampler.get();
    fmt::print("vecat: telemetry on DDS domain {} (topics {}, {}, {}, {}), one sample every {} cycle(s)\n",
               o.domain, tm::kAxisTopic, tm::kStatusTopic, tm::kTwinsyncTopic, tm::kEventTopic, o.decimation);
    return t;
}

RunTelemetry::~RunTelemetry() {
    if (!impl_) return;
    impl_->publisher->stop();
    const auto ps = impl_->publisher->stats();
    const auto& ss = impl_->sampler->stats();
    fmt::print(
        "vecat: telemetry: {} axis samples, {} events, {} records written to DDS ({} errors), {} lost "
        "to a full queue\n",
        ss.samples, ss.events, ps.written, ps.write_errors, impl_->queue.overflows());
}

namespace {

struct ScopeOptions {
    double duration = 0;
    std::string csv, svg, png, from_csv, title = "vecat scope", signals;
    std::vector<unsigned> slaves;
    std::uint32_t domain = 0;
    bool list = false;
};
ScopeOptions g_scope;
std::atomic<bool> g_scope_stop{false};

void on_scope_signal(int) {
    g_scope_stop.store(true);
}

}  // namespace

CLI::App* add_scope_command(CLI::App& app) {
    auto* s = app.add_subcommand(
        "scope",
        "Record the telemetry of `vecat run --telemetry` (CSV) and draw the chosen signals over time (SVG, "
        "PNG)");
    s->add_option("-d,--duration", g_scope.duration, "Seconds to record (default: until Ctrl-C)")
        ->check(CLI::Range(0.0, 1e6));
    s->add_option(
        "--csv", g_scope.csv,
        "Write the axis samples to this CSV file (status, TWINsync, events and I/O samples beside it "
        "as FILE-status.csv, FILE-twinsync.csv, FILE-events.csv, FILE-io.csv)");
    s->add_option("--svg", g_scope.svg, "Draw the signals into this SVG file");
    s->add_option("--png", g_scope.png, "Draw the signals into this PNG file (needs rsvg-convert)");
    s->add_option("--signals", g_scope.signals,
                  std::string("Panels separated by ',', signals of one panel joined by '+' (default ") +
                      tm::kDefaultSignals + ")");
    s->add_option("--slave", g_scope.slaves, "Only these slaves (positions on the line; repeatable)");
    s->add_option("--title", g_scope.title, "Title of the picture");
    s->add_option("--from-csv", g_scope.from_csv,
                  "Draw from a CSV file written by --csv instead of subscribing (no DDS needed)");
    s->add_option("--dds-domain", g_scope.domain, "DDS domain (default 0)")->check(CLI::Range(0u, 232u));
    s->add_flag("--list-signals", g_scope.list, "List the signal names and their units");
    return s;
}

int run_scope() {
    const ScopeOptions& o = g_scope;
    if (o.list) {
        for (const auto& s : tm::signal_list())
            fmt::print("{:34} {}{}\n", s.name, s.quantity, s.unit.empty() ? "" : " [" + s.unit + "]");
        return 0;
    }
    std::string why;
    const auto groups = tm::parse_signal_groups(o.signals, &why);
    if (groups.empty()) {
        fmt::print(stderr, "vecat scope: {}\n", why.empty() ? "no signals" : why);
        return 2;
    }
    tm::Recording rec;
    if (!o.from_csv.empty()) {
        if (!tm::read_csv(o.from_csv, rec, &why)) {
            fmt::print(stderr, "vecat scope: {}\n", why);
            return 1;
        }
    } else {
        if (!tm::dds_built_in()) {
            fmt::print(stderr, "vecat scope: {}\n", tm::kNotBuiltIn);
            return 2;
        }
        struct sigaction sa {};
        sa.sa_handler = on_scope_signal;
        sigemptyset(&sa.sa_mask);
        sigaction(SIGINT, &sa, nullptr);
        sigaction(SIGTERM, &sa, nullptr);
        try {
            tm::Subscriber sub(o.domain);
            fmt::print("vecat scope: subscribed on DDS domain {}{}\n", o.domain,
                       o.duration > 0 ? fmt::format(" for {} s", o.duration) : "; Ctrl-C stops");
            std::fflush(stdout);
            sub.record(rec, o.duration, g_scope_stop);
        } catch (const std::exception& e) {
            fmt::print(stderr, "vecat scope: {}\n", e.what());
            return 1;
        }
        fmt::print(
            "vecat scope: {} axis samples, {} slave status, {} TWINsync samples, {} events, {} I/O samples\n",
            rec.axes.size(), rec.status.size(), rec.twinsync.size(), rec.events.size(), rec.io.size());
        if (!o.csv.empty()) {
            if (!tm::write_csv(rec, o.csv, &why)) {
                fmt::print(stderr, "vecat scope: {}\n", why);
                return 1;
            }
            fmt::print("vecat scope: samples written to {}\n", o.csv);
        }
    }
    for (const auto& e : rec.events)
        if (e.kind == tm::EventKind::Fault || e.kind == tm::EventKind::Overflow)
            fmt::print("vecat scope: event {} slave {} code 0x{:04X} ({} -> {})\n", tm::to_string(e.kind),
                       e.slave, e.code, e.old_value, e.new_value);
    if (o.svg.empty() && o.png.empty()) return 0;
    const auto plot = tm::make_plot(rec, groups, o.title, o.slaves);
    const std::string svg = tm::render_svg(plot);
    const std::string svg_path = o.svg.empty() ? o.png + ".svg" : o.svg;
    if (!(std::ofstream(svg_path) << svg)) {
        fmt::print(stderr, "vecat scope: cannot write {}\n", svg_path);
        return 1;
    }
    if (!o.svg.empty()) fmt::print("vecat scope: picture written to {}\n", o.svg);
    if (!o.png.empty()) {
        const bool ok = tm::svg_to_png(svg_path, o.png, &why);
        if (o.svg.empty()) std::remove(svg_path.c_str());
        if (!ok) {
            fmt::print(stderr, "vecat scope: {}\n", why);
            return 1;
        }
        fmt::print("vecat scope: picture written to {}\n", o.png);
    }
    return 0;
}

struct DemoScope::Impl {
    tm::TelemetryQueue queue;
    tm::Sampler sampler;
    tm::LocalRecorder recorder{queue};
    Impl(esc::Segment& seg) : sampler(seg, queue) {}
};

DemoScope::DemoScope(esc::Segment& seg, net::ServeOptions& serve) : impl_(std::make_unique<Impl>(seg)) {
    serve.after_frame = &tm::Sampler::after_frame;
    serve.after_frame_context = &impl_->sampler;
}

DemoScope::~DemoScope() = default;

std::vector<std::string> DemoScope::write(const std::string& dir, const std::string& title,
                                          const std::string& signals) {
    const tm::Recording& rec = impl_->recorder.stop();
    std::string why;
    const std::string csv = dir + "/scope.csv", svg = dir + "/scope.svg", png = dir + "/scope.png";
    if (!tm::write_csv(rec, csv, &why)) {
        fmt::print(stderr, "vecat demo: {}\n", why);
        return {};
    }
    // The drives' panels, then one lane per channel of the I/O terminals (a network with terminals).
    auto groups = tm::parse_signal_groups(signals);
    for (auto& lane : tm::io_lanes(rec))
        groups.push_back(std::move(lane));
    const auto plot = tm::make_plot(rec, groups, title);
    std::ofstream(svg) << tm::render_svg(plot);
    std::vector<std::string> files{rec.io.empty() ? fmt::format("{} ({} samples)", csv, rec.axes.size())
                                                  : fmt::format("{} ({} axis samples, {} I/O samples)", csv,
                                                                rec.axes.size(), rec.io.size()),
                                   svg};
    if (tm::svg_to_png(svg, png, &why)) files.push_back(png);
    return files;
}

}  // namespace vecat::cli
