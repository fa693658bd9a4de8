// The telemetry parts of the vecat program: `vecat run --telemetry ...` and `vecat scope`.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "esc/segment.hpp"
#include "serve/server.hpp"

namespace vecat::cli {

struct TelemetryOptions {
    bool enabled = false;
    unsigned decimation = 1;
    std::uint32_t domain = 0;
};
void add_telemetry_options(CLI::App* run, TelemetryOptions& o);

// Sampler, queue and DDS publisher of one `vecat run`, hooked into the serve options.
class RunTelemetry {
  public:
    // nullptr (and a message on stderr) when telemetry cannot start; a disabled option gives a no-op object.
    static std::unique_ptr<RunTelemetry> start(esc::Segment& seg, const TelemetryOptions& o,
                                               net::ServeOptions& serve);
    ~RunTelemetry();  // stops the publisher and prints what was published
    struct Impl;

  private:
    std::unique_ptr<Impl> impl_;
};

// `vecat scope`: registers the subcommand; run_scope() executes it after parsing.
CLI::App* add_scope_command(CLI::App& app);
int run_scope();

}  // namespace vecat::cli

namespace vecat::cli {

// The demo's scope: samples the segment in-process (no DDS) and draws the run into DIR/scope.svg (and
// scope.png when rsvg-convert is installed), the samples into DIR/scope.csv.
class DemoScope {
  public:
    DemoScope(esc::Segment& seg, net::ServeOptions& serve);
    ~DemoScope();
    // After the serve loop stopped. signals: as `vecat scope --signals`. Returns the files written (CSV, SVG,
    // and PNG when rsvg-convert exists); problems go to stderr.
    std::vector<std::string> write(const std::string& dir, const std::string& title,
                                   const std::string& signals);
    struct Impl;

  private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace vecat::cli
