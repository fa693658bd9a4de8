// `vecat replay CAPTURE [--network FILE]`: a real capture's master frames sent to vecat, each reply held
// against the recorded one (src/replay). Exit 0 when the figures reach the thresholds, 1 below them, 2 for
// a capture or network file that cannot be used.
#pragma once

#include <CLI/CLI.hpp>

namespace vecat::cli {

CLI::App* add_replay_command(CLI::App& app);
int run_replay();

}  // namespace vecat::cli
