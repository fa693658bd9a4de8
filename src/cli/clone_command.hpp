// `vecat clone --iface IF -o DIR`: the line on a network interface (real hardware, or a veth to another
// vecat) read with the project's master and written as a network file that `vecat run --network` serves
// (src/clone, docs/clone.md). `--network FILE` clones a network file served in this process instead (no
// interface, no privileges: for tests and to see what a clone holds). Exit 0 when the copy is complete, 3
// when it was written with parts missing (listed on stderr), 1 when the line could not be read, 2 for bad
// arguments.
#pragma once

#include <CLI/CLI.hpp>

namespace vecat::cli {

CLI::App* add_clone_command(CLI::App& app);
int run_clone();

}  // namespace vecat::cli
