// The report on the master (src/report): silent for the project master's normal start-up and cycles, and
// each rule flagged by a master that breaks it (the project master driven step by step, or raw datagrams).
#include <gtest/gtest.h>

#include <fstream>
#include <pugixml.hpp>
#include <sstream>
#include <thread>

#include "coe/coe_application.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "network/build.hpp"
#include "network/network_file.hpp"
#include "protocol/mailbox.hpp"
#include "protocol/registers.hpp"
#include "report/master_checks.hpp"
#include "serve/in_process_link.hpp"

namespace vecat {
namespace {

using protocol::addr;
using protocol::AlState;
using protocol::Reg;
using report::Rule;

master::MasterOptions with_dc(std::uint32_t sync0_cycle_ns) {
    master::MasterOptions o;
    o.dc.enable = true;
    o.dc.sync0_cycle_ns = sync0_cycle_ns;
    o.dc.static_drift_frames = 100;
    return o;
}

// A line of CoE slaves behind an in-process link (real time), watched by the checks, and the project
// master.
struct Line {
    explicit Line(std::size_t n = 2, master::MasterOptions o = {})
        : seg(coe::make_coe_segment(device::default_drive(), n, {})),
          link(*seg),
          checks(*seg),
          master(link, o) {
        link.set_observer(&checks);
    }
    bool failed(Rule r) const { return checks.failed(r); }
    std::string report() const { return report::summary(checks); }
    std::uint16_t station(std::size_t i = 0) { return master.slaves()[i].station; }
    // PREOP with the process data SyncManagers and FMMUs written, SAFEOP not yet requested.
    void preop_with_process_data() {
        std::string why;
        ASSERT_TRUE(master.startup(AlState::PreOp, &why)) << why;
        ASSERT_TRUE(master.configure_process_data());
    }
    void wait_for(std::uint16_t st, AlState s) {
        for (int i = 0; i < 2000 && master.read_al_status(st).state() != s; ++i)
            std::this_thread::sleep_for(std::chrono::microseconds(200));
        ASSERT_EQ(master.read_al_status(st).state(), s);
    }

    std::unique_ptr<esc::Segment> seg;
    net::InProcessLink link;
    report::MasterChecks checks;
    master::Master master;
};

TEST(MasterReport, SilentForTheProjectMastersStartUpMailboxAndCycles) {
    // Given the project master with distributed clocks (offsets, drift compensation, SYNC0), SDO traffic
    // past one round of mailbox counters and 200 cycles in OP.
    Line l(2, with_dc(1'000'000));
    std::string why;
    ASSERT_TRUE(l.master.startup(AlState::Op, &why)) << why;
    master::CoeClient c(l.master, l.station(1));
    for (int i = 0; i < 10; ++i)
        ASSERT_TRUE(c.upload(0x1018, 1).ok());
    for (int i = 0; i < 200; ++i)
        ASSERT_EQ(l.master.exchange_process_data().value_or(0), l.master.expected_wkc());
    // A slave that shows an error by now is acknowledged, as the rule al-error-ack asks of a master: the
    // cycles stopped above, and on a loaded machine (sanitizers) they can stop long enough for the slaves'
    // SYNC supervision to leave OP (0x002C) before the INIT request.
    for (std::size_t i = 0; i < l.master.slaves().size(); ++i)
        if (l.master.read_al_status(l.station(i)).error()) {
            ASSERT_TRUE(l.master.acknowledge_error(l.station(i), AlState::Init));
            l.wait_for(l.station(i), AlState::Init);
        }
    ASSERT_TRUE(l.master.request_state(AlState::Init));
    // Then: every check passed, and the report says so.
    EXPECT_TRUE(l.checks.findings().empty()) << l.report();
    EXPECT_GT(l.checks.frames(), 200u);
    EXPECT_NE(l.report().find("11 of 11 checks passed"), std::string::npos) << l.report();
}

// The checks follow the slaves when they change places (hot connect: a group plugged back into another port)
// or start again: a master that configures the devices at their new positions breaks no rule, although what
// the checks knew of position 1 (a drive's SII) now belongs to position 2.
TEST(MasterReport, SilentWhenAHotConnectGroupComesBackAtAnotherPort) {
    const auto file = network::parse_network(R"(
devices:
  - name: j
    device: junction
  - name: drive
    device: drive
    upstream: j:3
    hot_connect: g
  - name: outputs
    device: digital-out
    upstream: j:1
)",
                                             "moves.yaml");
    auto seg = network::build_network(file, "moves.yaml").segment;
    net::InProcessLink link(*seg);
    report::MasterChecks checks(*seg);
    link.set_observer(&checks);
    std::string why;
    {
        master::Master m(link);
        ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
        for (int i = 0; i < 20; ++i)
            ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
    }
    // The drive's group goes from port 3 of the junction to port 1 of the output terminal, and starts again.
    std::vector<std::size_t> order;
    ASSERT_TRUE(seg->move_group(1, 2, 1, order, &why)) << why;
    ASSERT_TRUE(seg->restart_slave(2));
    ASSERT_EQ(seg->slave(1).esc().eeprom(),
              network::build_network(file, "moves.yaml").segment->slave(2).esc().eeprom());
    master::Master m(link);
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    for (int i = 0; i < 20; ++i)
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
    EXPECT_TRUE(checks.findings().empty()) << report::summary(checks);
}

TEST(MasterReport, SyncManagerLengthOtherThanThePdoAssignmentThenAStateRequestWithoutAcknowledge) {
    Line l;
    l.preop_with_process_data();
    const std::uint16_t st = l.station();
    const std::uint16_t len = l.seg->slave(0).esc().sm_block(2).length;
    ASSERT_GT(len, 0);
    // When: SM2 is one byte longer than the PDO assignment, and SAFEOP is requested (the slave refuses it).
    // (An ESC takes a SyncManager's configuration only while the SyncManager is disabled.)
    ASSERT_TRUE(l.master.write8(st, protocol::sm_addr(2) + protocol::sm::Activate, 0));
    ASSERT_TRUE(l.master.write16(st, protocol::sm_addr(2) + protocol::sm::Length, len + 1));
    ASSERT_TRUE(l.master.write8(st, protocol::sm_addr(2) + protocol::sm::Activate, protocol::sm::ActEnable));
    EXPECT_FALSE(l.master.request_state(st, AlState::SafeOp));
    EXPECT_TRUE(l.failed(Rule::SmConfiguration)) << l.report();
    EXPECT_NE(l.report().find("the PDO assignment has"), std::string::npos) << l.report();
    EXPECT_FALSE(l.failed(Rule::AlErrorNotAcknowledged)) << l.report();
    // When: the master asks again without acknowledging the error.
    ASSERT_TRUE(l.master.write16(st, addr(Reg::AlControl), static_cast<std::uint16_t>(AlState::SafeOp)));
    EXPECT_TRUE(l.failed(Rule::AlErrorNotAcknowledged)) << l.report();
    // Acknowledging is what the rule asks for: the next request with Error Ind Ack adds no finding.
    l.master.read_al_status(st);
    const auto before = l.checks.findings().size();
    EXPECT_TRUE(l.master.acknowledge_error(st, AlState::PreOp));
    EXPECT_EQ(l.checks.findings().size(), before) << l.report();
}

TEST(MasterReport, ProcessDataSyncManagerWithoutAnFmmu) {
    Line l;
    l.preop_with_process_data();
    const std::uint16_t st = l.station();
    for (unsigned f = 0; f < 3; ++f)
        ASSERT_TRUE(l.master.write8(st, protocol::fmmu_addr(f) + protocol::fmmu::Activate, 0));
    l.master.request_state(st, AlState::SafeOp);
    EXPECT_TRUE(l.failed(Rule::FmmuConfiguration)) << l.report();
    EXPECT_FALSE(l.failed(Rule::SmConfiguration)) << l.report();
}

TEST(MasterReport, StateRequestedAgainBeforeTheAlStatusWasRead) {
    Line l;
    l.preop_with_process_data();
    std::uint8_t safeop[2] = {static_cast<std::uint8_t>(AlState::SafeOp), 0};
    ASSERT_TRUE(l.master.bwr(addr(Reg::AlControl), safeop));
    ASSERT_TRUE(l.master.bwr(addr(Reg::AlControl), safeop));  // the same request again: allowed
    EXPECT_FALSE(l.failed(Rule::AlStatusNotRead)) << l.report();
    std::uint8_t preop[2] = {static_cast<std::uint8_t>(AlState::PreOp), 0};
    ASSERT_TRUE(l.master.bwr(addr(Reg::AlControl), preop));
    EXPECT_TRUE(l.failed(Rule::AlStatusNotRead)) << l.report();
}

TEST(MasterReport, OpRequestedBeforeAnyOutputsWereSentInSafeOp) {
    Line l;
    l.preop_with_process_data();
    const std::uint16_t st = l.station();
    ASSERT_TRUE(l.master.write16(st, addr(Reg::AlControl), static_cast<std::uint16_t>(AlState::SafeOp)));
    l.wait_for(st, AlState::SafeOp);
    ASSERT_TRUE(l.master.write16(st, addr(Reg::AlControl), static_cast<std::uint16_t>(AlState::Op)));
    EXPECT_TRUE(l.failed(Rule::OpWithoutOutputs)) << l.report();
    // The second slave got its outputs first: no finding for it.
    const std::uint16_t st2 = l.station(1);
    ASSERT_TRUE(l.master.write16(st2, addr(Reg::AlControl), static_cast<std::uint16_t>(AlState::SafeOp)));
    l.wait_for(st2, AlState::SafeOp);
    l.master.exchange_process_data();
    ASSERT_TRUE(l.master.write16(st2, addr(Reg::AlControl), static_cast<std::uint16_t>(AlState::Op)));
    for (const auto& f : l.checks.findings())
        EXPECT_NE(f.slave, 1u) << l.report();
}

TEST(MasterReport, Sync0StartTimeInThePast) {
    Line l(2, with_dc(0));  // offsets, delays and drift compensation; no SYNC0
    std::string why;
    ASSERT_TRUE(l.master.startup(AlState::PreOp, &why)) << why;
    ASSERT_TRUE(l.master.configure_dc());
    ASSERT_TRUE(l.master.compensate_static_drift(10));
    const std::uint16_t st = l.station();
    std::uint8_t start[8] = {1, 0, 0, 0, 0, 0, 0, 0};  // 1 ns after 2000-01-01
    ASSERT_TRUE(l.master.fpwr(st, addr(Reg::DcStartTimeCyclic), start));
    ASSERT_TRUE(l.master.write32(st, addr(Reg::DcSync0CycleTime), 1'000'000));
    ASSERT_TRUE(l.master.write8(st, addr(Reg::DcActivation), 0x03));
    EXPECT_TRUE(l.failed(Rule::Sync0StartInThePast)) << l.report();
    EXPECT_FALSE(l.failed(Rule::Sync0BeforeDriftCompensation)) << l.report();
}

TEST(MasterReport, Sync0ActivatedBeforeAnyDriftCompensation) {
    Line l;
    std::string why;
    ASSERT_TRUE(l.master.startup(AlState::PreOp, &why)) << why;
    ASSERT_TRUE(l.master.configure_dc());
    ASSERT_TRUE(l.master.start_sync(l.station(), 1'000'000, 0));
    EXPECT_TRUE(l.failed(Rule::Sync0BeforeDriftCompensation)) << l.report();
    EXPECT_FALSE(l.failed(Rule::Sync0StartInThePast)) << l.report();
}

TEST(MasterReport, MailboxCounterThatSkipsAhead) {
    Line l;
    std::string why;
    ASSERT_TRUE(l.master.startup(AlState::PreOp, &why)) << why;
    const std::uint16_t st = l.station();
    master::CoeClient c(l.master, st);
    ASSERT_TRUE(c.upload(0x1018, 1).ok());
    ASSERT_TRUE(c.upload(0x1018, 2).ok());
    EXPECT_FALSE(l.failed(Rule::MailboxCounter)) << l.report();
    // An SDO upload request of 0x1000:00 with counter 6 where the next is 3 (ETG.1000.4 mailbox header).
    const auto& sii = l.master.slaves()[0].sii;
    std::vector<std::uint8_t> mbx(sii.std_rx_mbx_size, 0);
    const std::uint8_t request[] = {10, 0, 0, 0, 0, 0x03 | (6 << 4), 0x00, 0x20, 0x40, 0x00, 0x10, 0x00};
    std::copy(std::begin(request), std::end(request), mbx.begin());
    ASSERT_EQ(l.master.fpwr(st, sii.std_rx_mbx_offset, mbx).value_or(0), 1);
    EXPECT_TRUE(l.failed(Rule::MailboxCounter)) << l.report();
    EXPECT_NE(l.report().find("counter 6 after 2 (expected 3"), std::string::npos) << l.report();
}

TEST(MasterReport, CycleLongerThanTheProcessDataWatchdog) {
    Line l;
    std::string why;
    ASSERT_TRUE(l.master.startup(AlState::Op, &why)) << why;
    ASSERT_NE(l.seg->slave(0).esc().sm_block(2).control & protocol::sm::CtrlWatchdog, 0)
        << "the device's SII enables the watchdog of its outputs";
    for (int i = 0; i < 10; ++i)
        l.master.exchange_process_data();
    EXPECT_FALSE(l.failed(Rule::WatchdogShorterThanCycle)) << l.report();
    // When: the watchdog is 1 ms (10 x 2500 x 40 ns) and the next cycle comes 20 ms later.
    for (std::size_t i = 0; i < 2; ++i)
        ASSERT_TRUE(l.master.write16(l.station(i), addr(Reg::WatchdogTimeProcessData), 10));
    l.master.exchange_process_data();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    l.master.exchange_process_data();
    EXPECT_TRUE(l.failed(Rule::WatchdogShorterThanCycle)) << l.report();
}

TEST(MasterReport, WriteToAReadOnlyRegister) {
    Line l;
    std::string why;
    ASSERT_TRUE(l.master.startup(AlState::Init, &why)) << why;
    std::uint8_t v[2] = {0x02, 0};
    l.master.fpwr(l.station(), addr(Reg::AlStatus), v);  // AL status instead of AL control
    EXPECT_TRUE(l.failed(Rule::ReadOnlyRegisterWrite)) << l.report();
    EXPECT_NE(l.report().find("FPWR of 2 bytes at 0x0130"), std::string::npos) << l.report();
}

TEST(MasterReport, EepromCommandWithoutAssigningTheEepromFirst) {
    Line l;
    ASSERT_EQ(l.master.count_slaves(), 2);
    // A read of SII word 0 straight away (SOEM and the project master write 0x0500 first).
    std::uint8_t cmd[6] = {0x00, 0x01, 0x00, 0x00, 0x00, 0x00};
    ASSERT_EQ(l.master.apwr(0, addr(Reg::SiiControl), cmd).value_or(0), 1);
    EXPECT_TRUE(l.failed(Rule::EepromNotAssigned)) << l.report();
    EXPECT_EQ(l.checks.findings().size(), 1u) << l.report();  // the other slave was not addressed
}

TEST(MasterReport, JunitXmlHasOneTestCasePerRuleAndAFailureForEachBrokenRule) {
    Line l;
    std::string why;
    ASSERT_TRUE(l.master.startup(AlState::Init, &why)) << why;
    std::uint8_t v[2] = {0x02, 0};
    l.master.fpwr(l.station(), addr(Reg::AlStatus), v);
    pugi::xml_document doc;
    ASSERT_TRUE(doc.load_string(report::junit_xml(l.checks).c_str()));
    const auto suite = doc.child("testsuites").child("testsuite");
    EXPECT_EQ(suite.attribute("tests").as_uint(), report::kRuleCount);
    EXPECT_EQ(suite.attribute("failures").as_uint(), 1u);
    unsigned cases = 0, failures = 0;
    for (auto tc : suite.children("testcase")) {
        ++cases;
        if (auto f = tc.child("failure")) {
            ++failures;
            EXPECT_EQ(std::string(tc.attribute("name").as_string()).rfind("read-only-write:", 0), 0u);
            EXPECT_STREQ(f.attribute("type").as_string(), "warning");
            EXPECT_NE(std::string(f.text().as_string()).find("ESC datasheet section II"), std::string::npos);
        }
    }
    EXPECT_EQ(cases, report::kRuleCount);
    EXPECT_EQ(failures, 1u);
}

TEST(MasterReport, EveryRuleIsDocumented) {
    std::ifstream f(std::string(VECAT_SOURCE_DIR) + "/docs/master-report.md");
    ASSERT_TRUE(f) << "docs/master-report.md";
    std::stringstream doc;
    doc << f.rdbuf();
    for (const report::RuleInfo& r : report::kRules)
        EXPECT_NE(
            doc.str().find("| `" + std::string(r.id) + "` | " + std::string(report::to_string(r.severity))),
            std::string::npos)
            << r.id;
}

}  // namespace
}  // namespace vecat
