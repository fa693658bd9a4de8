// 06_fault_injection: faults injected with the text commands of `vecat fault`, and what the master sees:
// a cable break on the EtherCAT line (link_down), then a broken TWINsync cable between two gantry drives.
#include <cstdio>

#include "protocol/cia402.hpp"
#include "testing/virtual_segment.hpp"

using namespace vecat;

int main() {
    testing::VirtualSegment vs({.drives = 3, .twinsync = cia402::TwinsyncPreset::Gantry});
    vs.cycles(50);
    std::printf("3 slaves, LRW working counter %u\n", vs.last_wkc());

    // 1. The cable behind slave 1 breaks: slave 2 disappears, the slaves before it close the loop.
    std::printf("> inject link_down slave=1 port=1 id=cut: %s\n",
                vs.fault("inject link_down slave=1 port=1 id=cut").c_str());
    const bool full = vs.cycle();
    const auto dl = vs.master().read16(vs.station(1), 0x0110);
    std::printf("LRW working counter %u of %u, BRD counts %d slaves, slave 1 DL status 0x%04X\n",
                vs.last_wkc(), vs.master().expected_wkc(), vs.master().count_slaves(), dl.value_or(0));
    if (full || vs.master().count_slaves() != 2) return 1;
    std::printf("> clear cut: %s\n", vs.fault("clear cut").c_str());
    if (!vs.cycle() || vs.master().count_slaves() != 3) return 1;
    std::printf("line whole again: LRW working counter %u\n", vs.last_wkc());

    // 2. The TWINsync cable between drives 1 and 2 breaks while they are enabled: both fault (TWINsync
    //    error 40-00) within the monitoring time; the master sees the fault bit in the statusword.
    if (!vs.enable(0)) return 1;
    std::printf("> inject twinsync_cable_break slave=0: %s\n",
                vs.fault("inject twinsync_cable_break slave=0").c_str());
    bool faulted = false;
    for (int k = 0; k < 200 && !faulted; ++k) {
        vs.cycle();
        faulted = (vs.statusword(0) & protocol::cia402::sw::Fault) &&
                  (vs.statusword(1) & protocol::cia402::sw::Fault);
    }
    std::printf("statuswords 0x%04X 0x%04X: %s\n", vs.statusword(0), vs.statusword(1),
                faulted ? "both drives in FAULT" : "no fault seen");
    std::printf("> list: %s\n", vs.fault("list").c_str());
    return faulted ? 0 : 1;
}
