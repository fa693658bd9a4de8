// `vecat demo`: virtual drives and the project's master on a private veth pair, run as a list of named
// phases (scan, PREOP, PDO mapping, DC, SAFEOP, OP, enable, CSP move, homing, fault and recovery, disable,
// INIT) with a live status line, then the ESI file, the SII image, the capture and the scope plot.
#pragma once

#include <string>

namespace vecat::cli {

struct DemoOptions {
    unsigned slaves = 2;     // drives 1 and 2 form a TWINsync gantry when there are two or more
    unsigned cycles = 3000;  // 1 ms cycles of the CSP move (out for the first half, back for the second)
    std::string outdir = "vecat-demo";
    // A network file (docs/network-file.md) instead of the line of drives: the CiA 402 drives found in it
    // are enabled and moved, the I/O devices' outputs written and their inputs read back.
    std::string network;
};

// Exit codes of run_demo (and of `vecat demo`).
inline constexpr int kDemoOk = 0;
inline constexpr int kDemoFailed = 1;      // a phase failed, or the namespace / veth pair could not be made
inline constexpr int kDemoBadNetwork = 2;  // the network file was refused (the message names its line)
// Interrupted by a signal: 128 + its number (130 for Ctrl-C / SIGINT, 143 for SIGTERM). The drives are
// disabled, the line goes back to INIT and the files are written all the same.
inline constexpr int kDemoInterruptedBase = 128;

int run_demo(const DemoOptions& o);

}  // namespace vecat::cli
