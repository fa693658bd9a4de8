// The project master's start-up names the slave that kept the line from a state and why: the first slave that
// did not reach it, its state, error flag and AL status code (with its meaning), and how many more did not.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "coe/coe_application.hpp"
#include "device/device_description.hpp"
#include "master/master.hpp"
#include "serve/in_process_link.hpp"

using namespace vecat;

namespace {

// SYNC0 every 100 us: not a whole multiple of the vecat drive's 125 us, so each of the three slaves refuses
// SAFEOP with "Invalid SYNC0 cycle time" (ETG.1000.6 Table 11, 0x0036).
TEST(MasterStartup, ARefusedStateNamesTheFirstSlaveThatRefusedItAndWhy) {
    auto seg = coe::make_coe_segment(device::default_drive(), 3);
    net::InProcessLink link(*seg);
    link.set_time(1'000'000'000);
    master::MasterOptions o;
    o.dc.enable = true;
    o.dc.sync0_cycle_ns = 100'000;
    o.dc.static_drift_frames = 10;
    master::Master m(link, o);
    std::string why;
    ASSERT_FALSE(m.startup(protocol::AlState::Op, &why));
    char station[8];
    std::snprintf(station, sizeof station, "%04X", m.slaves().at(0).station);
    EXPECT_EQ(why, "SAFEOP refused: slave 0 (station 0x" + std::string(station) +
                       ") is in PREOP with the error flag, AL status code 0x0036 (" +
                       std::string(protocol::describe(protocol::AlStatusCode::DcInvalidSync0CycleTime)) +
                       ") (and 2 more)");
}

}  // namespace
