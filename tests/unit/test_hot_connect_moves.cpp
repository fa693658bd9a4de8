// Segment::move_group (hot connect, a group plugged back into another port): after any sequence of moves on a
// tree of 4-port ESCs the slaves stay in the order a frame reaches them (set_topology, which checks it, takes
// the cabling as it is), every slave is reached, each group is one run of positions again, the slaves are the
// same objects in their new places, and refused moves change nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "device/device_description.hpp"
#include "esc/segment.hpp"
#include "protocol/frame.hpp"
#include "protocol/registers.hpp"
#include "test_support.hpp"

using namespace vecat;

namespace {

std::unique_ptr<esc::Segment> four_port_line(std::size_t n) {
    esc::EscConfig cfg;
    cfg.port_descriptor = 0xFF;  // ports 0-3
    return esc::make_segment(device::default_drive(), n, cfg);
}

// The cabling as it is, given back to set_topology: accepted only in depth-first order, ports 3, 1, 2.
bool order_is_the_frames(esc::Segment& seg, std::string& why) {
    std::vector<int> parents;
    std::vector<std::uint8_t> ports;
    for (std::size_t k = 0; k < seg.size(); ++k) {
        parents.push_back(seg.parent(k));
        ports.push_back(static_cast<std::uint8_t>(seg.parent_port(k)));
    }
    return seg.set_topology(parents, ports, std::vector<std::uint32_t>(seg.size(), 0), &why);
}

}  // namespace

TEST(HotConnectMoves, AnySequenceOfMovesKeepsTheFramesOrder) {
    constexpr std::size_t n = 12;
    auto seg = four_port_line(n);
    std::mt19937 rng(7);
    std::set<const esc::Slave*> slaves;
    for (std::size_t k = 0; k < n; ++k)
        slaves.insert(&seg->slave(k));
    unsigned moved = 0, refused = 0;
    for (int step = 0; step < 2000; ++step) {
        const std::size_t head = 1 + rng() % (n - 1);
        const std::size_t parent = rng() % n;
        const auto port = static_cast<unsigned>(1 + rng() % 3);
        const std::size_t end = seg->group_end(head);
        const esc::Slave* const head_slave = &seg->slave(head);
        std::vector<int> before;
        for (std::size_t k = 0; k < n; ++k)
            before.push_back(seg->parent(k));
        std::vector<std::size_t> order;
        std::string why;
        const bool allowed = seg->can_move_group(head, parent, port);
        const bool ok = seg->move_group(head, parent, port, order, &why);
        ASSERT_EQ(ok, allowed) << why;
        if (!ok) {
            ++refused;
            EXPECT_FALSE(why.empty());
            for (std::size_t k = 0; k < n; ++k)
                ASSERT_EQ(seg->parent(k), before[k]) << "a refused move changed the cabling: " << why;
            continue;
        }
        ++moved;
        ASSERT_EQ(order.size(), n);
        // The group's head now hangs at the port it was plugged into, and the group is one run again.
        const auto at = static_cast<std::size_t>(std::find(order.begin(), order.end(), head) - order.begin());
        ASSERT_EQ(&seg->slave(at), head_slave);
        ASSERT_EQ(seg->parent_port(at), port);
        ASSERT_EQ(order[static_cast<std::size_t>(seg->parent(at))], parent);
        ASSERT_EQ(seg->group_end(at) - at, end - head);
        ASSERT_TRUE(order_is_the_frames(*seg, why)) << why;
        ASSERT_EQ(seg->reachable(), n);
        std::set<const esc::Slave*> now;
        for (std::size_t k = 0; k < n; ++k)
            now.insert(&seg->slave(k));
        ASSERT_EQ(now, slaves);
    }
    // Both kinds happened many times (a move into the group itself, an occupied port, slave 0 as a head).
    EXPECT_GT(moved, 200u);
    EXPECT_GT(refused, 200u);
}

TEST(HotConnectMoves, RefusesWhatHardwareCannotDo) {
    auto seg = four_port_line(4);  // a line: 0 -1-> 1 -1-> 2 -1-> 3
    std::vector<std::size_t> order;
    std::string why;
    EXPECT_FALSE(seg->move_group(0, 1, 2, order, &why));  // the first slave's group is the whole line
    EXPECT_FALSE(seg->move_group(2, 3, 2, order, &why));  // into itself
    EXPECT_NE(why.find("belongs to the group"), std::string::npos) << why;
    EXPECT_FALSE(seg->move_group(3, 1, 1, order, &why));  // port 1 of slave 1 has slave 2
    EXPECT_NE(why.find("has a link already"), std::string::npos) << why;
    EXPECT_FALSE(seg->move_group(3, 0, 4, order, &why));
    auto two_ports = esc::make_segment(device::default_drive(), 3);  // ports 0 and 1 only
    EXPECT_FALSE(two_ports->move_group(2, 0, 3, order, &why));
    EXPECT_NE(why.find("has no port 3"), std::string::npos) << why;
    // Plugged back where it was: allowed, nothing moves.
    ASSERT_TRUE(seg->move_group(2, 1, 1, order, &why)) << why;
    EXPECT_EQ(order, (std::vector<std::size_t>{0, 1, 2, 3}));
    // Slave 3 to port 3 of slave 0: port 3 comes before port 1, so it is second now.
    ASSERT_TRUE(seg->move_group(3, 0, 3, order, &why)) << why;
    EXPECT_EQ(order, (std::vector<std::size_t>{0, 3, 1, 2}));
    EXPECT_EQ(seg->parent(1), 0);
    EXPECT_EQ(seg->parent_port(1), 3u);
}

// Each slave takes its own firmware schedule along when it moves (move_group permutes every per-slave entry):
// a frame that reads a moved slave whose own cycle is due finds it caught up, and one that reads a slave that
// is not due does not run it.
TEST(HotConnectMoves, EachSlaveKeepsItsFirmwareScheduleWhenItMoves) {
    auto seg = four_port_line(4);  // a line 0 -1-> 1 -1-> 2 -1-> 3 of plain process images
    constexpr std::uint64_t kMs = 1'000'000;
    const auto al_status_at = [](std::uint16_t position) {
        return test::phys(static_cast<std::uint16_t>(-position), test::reg(protocol::Reg::AlStatus));
    };
    const auto read_runs = [&](std::uint16_t position, std::uint64_t now) {
        const std::uint64_t before = seg->counters().firmware_runs;
        EXPECT_EQ(test::raw_datagram(*seg, static_cast<std::uint8_t>(protocol::Command::APRD),
                                     al_status_at(position), {0, 0}, now)
                      .wkc,
                  1);
        return seg->counters().firmware_runs - before;
    };
    seg->tick(1 * kMs);  // every slave runs: each is due again a local cycle (250 us) later
    // Slave 3 alone runs again at 2 ms (a read of its AL status finds it due).
    ASSERT_EQ(read_runs(3, 2 * kMs), 1u);
    // Slave 3 to port 3 of slave 0: the frame now reaches 0, 3, 1, 2.
    std::vector<std::size_t> order;
    std::string why;
    ASSERT_TRUE(seg->move_group(3, 0, 3, order, &why)) << why;
    ASSERT_EQ(order, (std::vector<std::size_t>{0, 3, 1, 2}));
    // At 2.1 ms slave 2 (position 3, last run at 1 ms) is due and runs before the read; slave 3 (position 1,
    // run at 2 ms) is not.
    EXPECT_EQ(read_runs(3, 2 * kMs + 100'000), 1u);
    EXPECT_EQ(read_runs(1, 2 * kMs + 100'000), 0u);
}
