// Hot connect: a group of devices (a device and everything downstream of it, network file hot_connect:)
// unplugged and plugged back at run time through the injector (control socket commands, scenario
// timeline). The project's master sees it as on hardware: the group gone, then back in INIT with its
// station address cleared and its identity (station alias, the ID through AL control bit 5), while the
// rest of the line answers every cycle in OP.
#include <gtest/gtest.h>

#include "faults/injector.hpp"
#include "faults/scenario.hpp"
#include "master/master.hpp"
#include "network/build.hpp"
#include "network/network_file.hpp"
#include "protocol/registers.hpp"
#include "serve/in_process_link.hpp"

namespace vecat::faults {
namespace {

using protocol::AlState;
using protocol::Reg;

constexpr const char* kLine = R"(
devices:
  - name: a1
    device: drive
  - name: a2
    device: drive
  - name: a3
    device: drive
    alias: 0x0033
    hot_connect: tail
  - name: a4
    device: drive
    alias: 0x0044
)";

struct HotConnectBench {
    HotConnectBench()
        : seg(network::build_network(network::parse_network(kLine, "line.yaml"), "line.yaml").segment),
          link(*seg),
          inj(*seg) {
        link.set_time(now);
        link.set_filter(&inj);
    }
    std::string execute(const std::string& cmd) { return inj.execute(cmd, now); }
    // The master's own cycle: the time moves 1 ms per exchange.
    std::optional<std::uint16_t> cycle(master::Master& m) {
        now += 1'000'000;
        link.set_time(now);
        return m.exchange_process_data();
    }
    std::uint16_t al_status(master::Master& m, std::uint16_t station) {
        return m.read16(station, protocol::addr(Reg::AlStatus)).value_or(0xFFFF);
    }
    std::unique_ptr<esc::Segment> seg;
    net::InProcessLink link;
    FaultInjector inj;
    std::uint64_t now = 1'000'000'000;
};

std::optional<std::uint16_t> aprd16(master::Master& m, std::uint16_t pos, Reg r) {
    std::array<std::uint8_t, 2> v{};
    const auto w = m.aprd(pos, protocol::addr(r), Bytes(v.data(), v.size()));
    if (!w || *w != 1) return std::nullopt;
    return ld_le16(v.data());
}

TEST(HotConnect, AGroupUnpluggedAndPluggedBackIsSeenAsOnHardware) {
    HotConnectBench b;
    ASSERT_EQ(b.seg->hot_connect_head("tail"), 2u);
    EXPECT_EQ(b.seg->group_end(2), 4u);
    master::Master m(b.link);
    std::string why;
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    const std::uint16_t full = m.expected_wkc();
    for (int i = 0; i < 10; ++i)
        ASSERT_EQ(b.cycle(m).value_or(0), full);

    EXPECT_EQ(b.execute("inject unplug group=tail id=u").rfind("ok", 0), 0u);
    // Gone: two slaves answer a broadcast, a3 and a4 do not answer their addresses; a1 and a2 keep
    // exchanging their process data every cycle (the LRW has their part of the working counter) in OP.
    EXPECT_EQ(m.count_slaves(), 2);
    EXPECT_FALSE(m.read16(0x1003, protocol::addr(Reg::AlStatus)).has_value());
    const std::uint16_t rest = static_cast<std::uint16_t>(full / 2);  // two drives of four, same mapping
    for (int i = 0; i < 20; ++i)
        EXPECT_EQ(b.cycle(m).value_or(0), rest) << "cycle " << i;
    EXPECT_EQ(b.al_status(m, 0x1001) & 0x1F, static_cast<std::uint16_t>(AlState::Op));
    EXPECT_EQ(b.al_status(m, 0x1002) & 0x1F, static_cast<std::uint16_t>(AlState::Op));
    // Unplugging it again is refused; so is a group that does not exist.
    EXPECT_EQ(b.execute("inject unplug group=tail").rfind("error", 0), 0u);
    EXPECT_EQ(b.execute("inject unplug slave=3").rfind("error", 0), 0u);  // inside the unplugged group
    EXPECT_EQ(b.execute("inject unplug group=nope").rfind("error", 0), 0u);

    // Plugged back: four slaves; the two of the group in INIT, station address 0, alias from their SII.
    EXPECT_EQ(b.execute("clear u").rfind("ok", 0), 0u);
    EXPECT_EQ(m.count_slaves(), 4);
    for (std::uint16_t pos = 2; pos < 4; ++pos) {
        SCOPED_TRACE("position " + std::to_string(pos));
        EXPECT_EQ(aprd16(m, pos, Reg::AlStatus).value_or(0xFF) & 0x1F,
                  static_cast<std::uint16_t>(AlState::Init));
        EXPECT_EQ(aprd16(m, pos, Reg::StationAddress), 0);
        EXPECT_EQ(aprd16(m, pos, Reg::StationAlias), pos == 2 ? 0x0033 : 0x0044);
    }
    // Its identity on request (AL control bit 5): AL status bit 5, the ID in the AL status code register.
    std::array<std::uint8_t, 2> ctl{static_cast<std::uint8_t>(AlState::Init) | 0x20, 0};
    ASSERT_EQ(m.apwr(2, protocol::addr(Reg::AlControl), Bytes(ctl.data(), ctl.size())).value_or(0), 1);
    b.now += 1'000'000;
    b.link.set_time(b.now);
    b.seg->tick(b.now);
    EXPECT_TRUE(aprd16(m, 2, Reg::AlStatus).value_or(0) & 0x20);
    EXPECT_EQ(aprd16(m, 2, Reg::AlStatusCode), 0x0033);
    // The rest of the line never left OP, and its process data went on all along.
    EXPECT_EQ(b.al_status(m, 0x1001) & 0x1F, static_cast<std::uint16_t>(AlState::Op));
    EXPECT_EQ(b.cycle(m).value_or(0), rest);  // the group is not configured again yet: its part is missing
}

TEST(HotConnect, TheScenarioTimelineUnplugsAndPlugs) {
    HotConnectBench b;
    master::Master m(b.link);
    std::string why;
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    const std::uint16_t full = m.expected_wkc();
    std::vector<std::string> events;
    b.inj.on_event = [&](const std::string& e) { events.push_back(e); };
    // Frames counted from the first one after load(): one exchange per cycle.
    b.inj.load(parse_scenario(R"(
events:
  - at_cycle: 5
    start: unplug
    group: tail
    id: u
  - at_cycle: 15
    stop: u
)"));
    std::vector<std::uint16_t> wkc;
    for (int i = 0; i < 20; ++i)
        wkc.push_back(b.cycle(m).value_or(0));
    for (int i = 0; i < 20; ++i) {
        // Every cycle answered: the whole line before the unplug, a1 and a2 while the group is out and
        // after it is back (in INIT, not configured again).
        EXPECT_EQ(wkc[static_cast<std::size_t>(i)], i < 5 ? full : full / 2) << "cycle " << i;
    }
    ASSERT_EQ(events.size(), 2u);
    EXPECT_NE(events[0].find("unplug"), std::string::npos) << events[0];
    EXPECT_EQ(b.seg->reachable(), 4u);
    EXPECT_EQ(aprd16(m, 3, Reg::AlStatus).value_or(0xFF) & 0x1F, static_cast<std::uint16_t>(AlState::Init));
    EXPECT_EQ(b.al_status(m, 0x1001) & 0x1F, static_cast<std::uint16_t>(AlState::Op));
}

// A tree: a junction with a drive at port 3 (a hot connect group) and a line of two drives at port 1.
constexpr const char* kTree = R"(
devices:
  - name: j
    device: junction
  - name: g1
    device: drive
    alias: 0x0071
    upstream: j:3
    hot_connect: moving
  - name: l1
    device: drive
    upstream: j:1
  - name: l2
    device: drive
)";

// Plugged back into another port the group takes its place in the order the frame reaches the slaves
// (0 -> 3 -> 1 -> 2), as on hardware: the master finds it there, with its identity, and computes the new
// topology from the DL status; the faults that name slaves follow them.
TEST(HotConnect, AGroupPluggedBackIntoAnotherPortTakesItsPlaceInTheLine) {
    auto seg = network::build_network(network::parse_network(kTree, "tree.yaml"), "tree.yaml").segment;
    net::InProcessLink link(*seg);
    FaultInjector inj(*seg);
    std::uint64_t now = 1'000'000'000;
    link.set_time(now);
    link.set_filter(&inj);
    const auto execute = [&](const std::string& cmd) { return inj.execute(cmd, now); };
    ASSERT_EQ(seg->hot_connect_head("moving"), 1u);
    ASSERT_EQ(seg->parent(1), 0);
    ASSERT_EQ(seg->parent_port(1), 3u);
    master::Master m(link);
    std::string why;
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    // Refused at once: a port with a device, a port of the group itself, a port the junction lacks.
    EXPECT_EQ(execute("inject unplug group=moving to=0:1").rfind("error", 0), 0u) << execute("active");
    EXPECT_EQ(execute("inject unplug group=moving to=1:1").rfind("error", 0), 0u);
    EXPECT_EQ(execute("inject unplug group=moving to=4:3").rfind("error", 0), 0u);  // no slave 4
    // A fault on l2 (position 3) before the move: it follows l2 to its new position.
    ASSERT_EQ(execute("inject dc_drift slave=3 step_ppm=1 id=d").rfind("ok", 0), 0u);
    ASSERT_EQ(execute("inject unplug group=moving to=3:1 id=u").rfind("ok", 0), 0u);
    EXPECT_EQ(m.count_slaves(), 3);
    esc::Slave* const moved = &seg->slave(1);
    const esc::Slave* const l2 = &seg->slave(3);
    ASSERT_EQ(execute("clear u").rfind("ok", 0), 0u);
    // Now: junction, l1, l2, and the group behind port 1 of l2.
    ASSERT_EQ(seg->size(), 4u);
    EXPECT_EQ(&seg->slave(2), l2);
    EXPECT_EQ(seg->parent(2), 1);
    EXPECT_EQ(seg->parent(3), 2);
    EXPECT_EQ(seg->parent_port(3), 1u);
    EXPECT_EQ(seg->hot_connect_head("moving"), 3u);
    EXPECT_EQ(seg->group_end(3), 4u);
    EXPECT_NE(&seg->slave(3), moved);  // plugged back: a new start of the device
    EXPECT_EQ(seg->reachable(), 4u);
    EXPECT_EQ(m.count_slaves(), 4);
    EXPECT_EQ(aprd16(m, 3, Reg::AlStatus).value_or(0xFF) & 0x1F, static_cast<std::uint16_t>(AlState::Init));
    EXPECT_EQ(aprd16(m, 3, Reg::StationAlias), 0x0071);
    EXPECT_EQ(aprd16(m, 3, Reg::StationAddress), 0);
    // The rest kept their station addresses and OP: l1 and l2 moved up one position.
    EXPECT_EQ(aprd16(m, 1, Reg::StationAddress), 0x1003);
    EXPECT_EQ(aprd16(m, 2, Reg::StationAddress), 0x1004);
    EXPECT_EQ(m.read16(0x1004, protocol::addr(Reg::AlStatus)).value_or(0) & 0x1F,
              static_cast<std::uint16_t>(AlState::Op));
    // The drift fault named l2 by its position then; it ends on l2 where it is now.
    const double drift = seg->slave(2).esc().dc().drift_ppm();
    ASSERT_EQ(execute("clear d").rfind("ok", 0), 0u);
    EXPECT_NE(seg->slave(2).esc().dc().drift_ppm(), drift);
    // A new scan finds the tree as it is now: the group's drive behind port 1 of l2.
    master::Master again(link);
    ASSERT_TRUE(again.startup(AlState::PreOp, &why)) << why;
    ASSERT_EQ(again.slaves().size(), 4u);
    EXPECT_EQ(again.slaves()[3].parent, 2);
    EXPECT_EQ(again.slaves()[3].parent_port, 1u);
}

// The control socket's status: what each slave shows, for a test to read while the line runs.
TEST(ControlStatus, EachSlaveWithItsAlStateCountersAndCia402State) {
    HotConnectBench b;
    master::Master m(b.link);
    std::string why;
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    b.cycle(m);
    std::string s = b.execute("status");
    EXPECT_EQ(s.rfind("ok 4 slaves\nslave=0 al=OP al_code=0x0000 lost_links=0,0,0,0", 0), 0u) << s;
    EXPECT_NE(s.find("slave=3 al=OP"), std::string::npos) << s;
    EXPECT_NE(s.find("state=SWITCH_ON_DISABLED mode="), std::string::npos) << s;
    // A group unplugged and plugged back: its devices in INIT, the cable's loss counted at the port before.
    ASSERT_EQ(b.execute("inject unplug group=tail id=u").rfind("ok", 0), 0u);
    b.cycle(m);
    ASSERT_EQ(b.execute("clear u").rfind("ok", 0), 0u);
    b.cycle(m);
    s = b.execute("status");
    EXPECT_NE(s.find("slave=2 al=INIT"), std::string::npos) << s;
    EXPECT_NE(s.find("slave=1 al=OP al_code=0x0000 lost_links=0,1,0,0"), std::string::npos) << s;
}

TEST(HotConnect, LinkDownNeedsACableAtThePort) {
    HotConnectBench b;
    EXPECT_EQ(b.execute("inject link_down slave=0 port=3").rfind("error", 0), 0u);  // nothing cabled there
    EXPECT_EQ(b.execute("inject link_down slave=3 port=1").rfind("error", 0), 0u);  // the end of the line
    EXPECT_EQ(b.execute("inject link_down slave=2 port=0").rfind("ok", 0), 0u);
    EXPECT_FALSE(b.seg->cable(2));
}

TEST(HotConnect, TheNetworkFileRefusesAGroupNameTwice) {
    try {
        network::parse_network(
            "devices:\n  - name: a\n    device: drive\n    hot_connect: g\n  - name: b\n"
            "    device: drive\n    hot_connect: g\n",
            "net.yaml");
        FAIL() << "accepted";
    } catch (const network::NetworkFileError& e) {
        EXPECT_NE(std::string(e.what()).find("net.yaml:7: b: hot_connect: g heads the group of a (line 4)"),
                  std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace vecat::faults
