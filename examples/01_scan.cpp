// 01_scan: bring a line up and list its slaves with their identity.
//
// The wiring every other example hides behind vecat::testing: a segment of virtual drives, an in-process
// link into it (frames are processed as they are sent), and the project's master on the link. On a real
// network the link would be a net::RawSocket on one end of a veth pair instead.
#include <cstdio>
#include <string>

#include "cia402/drive.hpp"
#include "master/master.hpp"
#include "serve/in_process_link.hpp"

using namespace vecat;

int main() {
    const device::DeviceDescription desc = device::default_drive();
    auto segment = cia402::make_drive_segment(desc, 3);  // three CiA 402 drives on a line
    net::InProcessLink link(*segment);
    link.set_time(1'000'000'000);  // simulated time: the segment sees only what we set
    master::Master master(link);

    // What a master does first: count the slaves with a broadcast read (its working counter).
    const int n = master.count_slaves();
    std::printf("broadcast read: %d slaves answered\n", n);
    if (n != 3) return 1;

    // The whole start-up sequence: station addresses, SII, mailboxes, PDO sizes over CoE, INIT -> OP.
    std::string why;
    if (!master.startup(protocol::AlState::Op, &why)) {
        std::printf("start-up failed: %s\n", why.c_str());
        return 1;
    }
    for (const auto& s : master.slaves()) {
        const auto& id = s.sii.identity;
        std::printf(
            "slave %u at 0x%04X: %s vendor 0x%08X product 0x%08X revision 0x%08X serial %u, "
            "%u output and %u input bytes, AL state 0x%02X\n",
            s.position, s.station, s.sii.device_name().c_str(), id.vendor_id, id.product_code, id.revision,
            id.serial, s.out_bytes, s.in_bytes, master.read_al_status(s.station).status);
        if (id.vendor_id != desc.identity.vendor_id) return 1;
    }
    // One process data frame through all three: the working counter of an LRW is 3 per slave.
    const auto wkc = master.exchange_process_data();
    std::printf("LRW working counter %u (expected %u)\n", wkc.value_or(0), master.expected_wkc());
    return wkc == master.expected_wkc() ? 0 : 1;
}
