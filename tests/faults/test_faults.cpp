// Fault injection: every fault class started on a line of drives, and what the project's master observes
// (lost replies, working counters, DL status, error counters, AL status codes, SDO aborts, emergencies,
// statusword and 0x603F, DC time). In-process: the injector sits between the link and the segment.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <thread>

#include "cia402/drive.hpp"
#include "faults/control.hpp"
#include "faults/injector.hpp"
#include "faults/twinsync_faults.hpp"
#include "master/coe_client.hpp"
#include "protocol/cia402.hpp"
#include "protocol/cia402_objects.hpp"
#include "test_support.hpp"
#include "twinsync/parameters.hpp"

namespace cia = vecat::protocol::cia402;

namespace obj = vecat::protocol::obj;

namespace vecat::faults {
namespace {

using protocol::AlState;
constexpr std::uint64_t kMs = 1'000'000;

master::MasterOptions quick_master() {
    master::MasterOptions o;
    o.reply_timeout_us = 2000;  // lost frames cost little test time
    return o;
}

// n drives behind an in-process link, the injector between link and segment, the project's master.
struct FaultBench {
    explicit FaultBench(std::size_t n)
        : seg(cia402::make_drive_segment(desc, n, {})), link(*seg), inj(*seg), master(link, quick_master()) {
        link.set_time(now);
        link.set_filter(&inj);
    }
    void advance(std::uint64_t ns) {
        now += ns;
        link.set_time(now);
        seg->tick(now);
        inj.tick(now);
    }
    std::uint16_t station(std::size_t i) const { return static_cast<std::uint16_t>(0x1001 + i); }
    std::optional<std::uint16_t> reg16(std::size_t i, protocol::Reg r) {
        return master.read16(station(i), protocol::addr(r));
    }
    std::uint8_t reg8(std::size_t i, std::uint16_t a) {
        std::uint8_t v = 0xEE;
        const auto w = master.fprd(station(i), a, Bytes(&v, 1));
        EXPECT_TRUE(w && *w == 1) << "register 0x" << std::hex << a << " of slave " << i;
        return v;
    }
    // A frame the master sends once (no retry): its working counter, nullopt if no reply.
    std::optional<std::uint16_t> once(protocol::Command cmd, std::uint16_t adp, std::uint16_t ado, Bytes d) {
        master::MasterOptions o = quick_master();
        o.retries = 0;
        master::Master single(link, o);
        return single.transact(cmd, adp, ado, d);
    }
    std::string inject(const std::string& line) { return inj.execute("inject " + line, now); }
    coe::ObjectDictionary& od0() {
        return dynamic_cast<coe::CoeApplication&>(seg->slave(0).app()).dictionary();
    }

    device::DeviceDescription desc = device::default_drive();
    std::unique_ptr<esc::Segment> seg;
    net::InProcessLink link;
    FaultInjector inj;
    master::Master master;
    std::uint64_t now = 1'000'000'000;
};

struct FaultTest : ::testing::Test {
    void up(std::size_t n, AlState target = AlState::PreOp) {
        b = std::make_unique<FaultBench>(n);
        std::string why;
        ASSERT_TRUE(b->master.startup(target, &why)) << why;
    }
    std::unique_ptr<FaultBench> b;
};

// ---- Fault model and scenario files

TEST(FaultSpec, ParsesKeysAndRefusesUnknownOnes) {
    const FaultSpec f =
        parse_fault("corrupt cable=2 direction=back probability=0.25 count=3 duration=1.5s id=x");
    EXPECT_EQ(f.kind, FaultKind::Corrupt);
    EXPECT_EQ(f.cable, 2u);
    EXPECT_TRUE(f.returning);
    EXPECT_DOUBLE_EQ(f.probability, 0.25);
    EXPECT_EQ(f.count, 3u);
    EXPECT_EQ(f.duration_ns, 1'500'000'000u);
    EXPECT_EQ(f.id, "x");
    EXPECT_EQ(parse_fault("al_error slave=1 code=0x001A state=preop").code, 0x001Au);
    EXPECT_EQ(parse_fault("delay delay=250us").delay_ns, 250'000u);
    EXPECT_THROW(parse_fault("drop port=1"), std::invalid_argument);         // drop has no port
    EXPECT_THROW(parse_fault("drop probability=2"), std::invalid_argument);  // out of range
    EXPECT_THROW(parse_fault("link_down slave=x"), std::invalid_argument);   // not a number
    EXPECT_THROW(parse_fault("delay"), std::invalid_argument);               // no delay given
    EXPECT_THROW(parse_fault("link_down port=4"), std::invalid_argument);    // ports 0-3
    EXPECT_EQ(parse_fault("unplug group=tail").group, "tail");
    EXPECT_THROW(parse_fault("unplug group="), std::invalid_argument);
    EXPECT_EQ(parse_fault("twinsync_crc_errors slave=1 rate=0.1").params.at("rate"), "0.1");
}

TEST(Scenario, ReadsATimelineAndNamesTheLineOfAnError) {
    const Scenario s = parse_scenario(R"(
seed: 42
events:
  - at: 20ms
    start: link_down
    slave: 0
    port: 1
    id: cut
  - at_cycle: 7
    start: drop
    count: 1
  - at: 1.5
    stop: cut
)");
    EXPECT_EQ(s.seed, 42u);
    ASSERT_EQ(s.events.size(), 3u);
    EXPECT_EQ(s.events[0].at, 20 * kMs);
    EXPECT_EQ(s.events[0].fault.kind, FaultKind::LinkDown);
    EXPECT_EQ(s.events[0].fault.id, "cut");
    EXPECT_TRUE(s.events[1].by_cycle);
    EXPECT_EQ(s.events[1].at, 7u);
    EXPECT_FALSE(s.events[2].start);
    EXPECT_EQ(s.events[2].target, "cut");
    EXPECT_EQ(s.events[2].at, 1'500'000'000u);
    try {
        parse_scenario(
            "events:\n  - at: 1s\n    start: drop\n  - at: 2s\n    start: link_down\n    cable: 1\n");
        FAIL() << "link_down takes no cable";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("line 4"), std::string::npos) << e.what();
    }
    EXPECT_THROW(parse_scenario("events:\n  - start: drop\n"), std::invalid_argument);  // no time
    EXPECT_THROW(parse_scenario("evnts: []\n"), std::invalid_argument);
}

TEST(Scenario, ExampleFilesParse) {
    const std::filesystem::path dir = std::filesystem::path(VECAT_SOURCE_DIR) / "examples" / "faults";
    int n = 0;
    for (const auto& f : std::filesystem::directory_iterator(dir)) {
        if (f.path().extension() != ".yaml") continue;
        EXPECT_NO_THROW(load_scenario(f.path().string())) << f.path();
        ++n;
    }
    EXPECT_GT(n, 0);
}

// ---- Frames: drop, corrupt, delay

TEST_F(FaultTest, DroppedFrameNeverComesBackButSlavesBeforeTheCableProcessedIt) {
    up(3);
    // ECAT event mask 0x0200: a register the master may write.
    std::uint16_t mask = 0x1234;
    auto write_mask = [&] {
        return b->once(protocol::Command::FPWR, b->station(0), 0x0200,
                       Bytes(reinterpret_cast<std::uint8_t*>(&mask), 2));
    };
    // Lost on cable 2 (between slave 1 and 2) on the way out: slave 0 has executed the write.
    ASSERT_EQ(b->inject("drop cable=2 count=1"), "ok drop#1");
    EXPECT_FALSE(write_mask());
    EXPECT_EQ(b->seg->slave(0).esc().peek16(0x0200), 0x1234u);
    // Lost before the first slave: nothing happened.
    mask = 0x00FF;
    ASSERT_EQ(b->inject("drop count=1").substr(0, 2), "ok");
    EXPECT_FALSE(write_mask());
    EXPECT_EQ(b->seg->slave(0).esc().peek16(0x0200), 0x1234u);
    EXPECT_EQ(write_mask(), 1);
    EXPECT_EQ(b->seg->slave(0).esc().peek16(0x0200), 0x00FFu);
    // Count reached: the line works again, the master's retries hide nothing any more.
    EXPECT_EQ(b->master.count_slaves(), 3);
    EXPECT_EQ(b->inj.counters().frames_dropped, 2u);
    EXPECT_TRUE(b->inj.active().empty());
}

TEST_F(FaultTest, ProbabilisticDropLosesAboutThatShareOfFrames) {
    up(1);
    ASSERT_EQ(b->inject("drop probability=0.3").substr(0, 2), "ok");
    int lost = 0;
    std::uint16_t v = 0;
    for (int i = 0; i < 200; ++i)
        if (!b->once(protocol::Command::BRD, 0, 0x0000, Bytes(reinterpret_cast<std::uint8_t*>(&v), 2)))
            ++lost;
    EXPECT_GT(lost, 35);
    EXPECT_LT(lost, 85);
}

TEST_F(FaultTest, CorruptedFrameIsCountedInTheErrorCountersOfTheEscsThatSawIt) {
    up(3);
    ASSERT_EQ(b->inject("corrupt cable=1 count=1").substr(0, 2), "ok");
    std::uint16_t v = 0;
    EXPECT_FALSE(b->once(protocol::Command::BRD, 0, 0x0000, Bytes(reinterpret_cast<std::uint8_t*>(&v), 2)));
    // Slave 1 received the bad FCS on port 0 (invalid frame, processing unit), slave 2 the marked frame
    // (forwarded error); on the way back slaves 0 and 1 got the marked frame on port 1.
    EXPECT_EQ(b->reg8(0, 0x0300), 0);
    EXPECT_EQ(b->reg8(0, 0x0309), 1);
    EXPECT_EQ(b->reg8(0, 0x030C), 0);
    EXPECT_EQ(b->reg8(1, 0x0300), 1);
    EXPECT_EQ(b->reg8(1, 0x0308), 0);
    EXPECT_EQ(b->reg8(1, 0x0309), 1);
    EXPECT_EQ(b->reg8(1, 0x030C), 1);
    EXPECT_EQ(b->reg8(2, 0x0300), 0);
    EXPECT_EQ(b->reg8(2, 0x0308), 1);
    EXPECT_EQ(b->reg8(2, 0x030C), 1);
    // On the way back on cable 2: slave 1 sees it first at port 1, slave 0 forwarded.
    ASSERT_EQ(b->inject("corrupt cable=2 direction=back count=1").substr(0, 2), "ok");
    EXPECT_FALSE(b->once(protocol::Command::BRD, 0, 0x0000, Bytes(reinterpret_cast<std::uint8_t*>(&v), 2)));
    EXPECT_EQ(b->reg8(1, 0x0302), 1);
    EXPECT_EQ(b->reg8(0, 0x0309), 2);
    EXPECT_EQ(b->reg8(2, 0x0308), 1);  // it had processed the frame intact
    EXPECT_EQ(b->inj.counters().frames_corrupted, 2u);
}

TEST_F(FaultTest, DelayedReplyComesTooLateAndTheMasterDiscardsIt) {
    up(1);
    ASSERT_EQ(b->inject("delay delay=5ms count=1").substr(0, 2), "ok");
    std::uint16_t v = 0;
    EXPECT_FALSE(b->once(protocol::Command::BRD, 0, 0x0000, Bytes(reinterpret_cast<std::uint8_t*>(&v), 2)));
    EXPECT_EQ(b->inj.counters().replies_delayed, 1u);
    EXPECT_NE(b->inj.next_due_ns(), ~std::uint64_t{0});
    b->advance(5 * kMs);
    // The late reply is waiting in the link; the master matches replies by index and takes its own.
    EXPECT_EQ(b->master.count_slaves(), 1);
    EXPECT_EQ(b->inj.next_due_ns(), ~std::uint64_t{0});
}

// ---- The line: link down, power off, firmware hang

TEST_F(FaultTest, LinkDownCutsTheLineAndShowsInDlStatusAndLostLinkCounter) {
    up(3, AlState::Op);
    const std::uint16_t wkc_ok = b->master.expected_wkc();
    ASSERT_EQ(b->master.exchange_process_data(), wkc_ok);
    ASSERT_EQ(b->inject("link_down slave=1 port=1 id=cut"), "ok cut");
    EXPECT_EQ(b->master.count_slaves(), 2);
    const auto w = b->master.exchange_process_data();
    ASSERT_TRUE(w);
    EXPECT_LT(*w, wkc_ok);
    const auto dl = b->reg16(1, protocol::Reg::DlStatus);
    ASSERT_TRUE(dl);
    EXPECT_FALSE(*dl & protocol::dl_status::link(1));
    EXPECT_TRUE(*dl & protocol::dl_status::loop_closed(1));
    EXPECT_EQ(b->reg8(1, 0x0311), 1);                    // lost link counter port 1
    EXPECT_FALSE(b->reg16(2, protocol::Reg::DlStatus));  // slave 2 is gone
    ASSERT_EQ(b->inj.execute("clear cut", b->now), "ok 1 cleared");
    EXPECT_EQ(b->master.count_slaves(), 3);
    const auto dl2 = b->reg16(1, protocol::Reg::DlStatus);
    ASSERT_TRUE(dl2);
    EXPECT_TRUE(*dl2 & protocol::dl_status::link(1));
}

TEST_F(FaultTest, PoweredOffSlaveBreaksTheLineAndRestartsInInit) {
    up(3, AlState::PreOp);
    ASSERT_EQ(b->inject("power_off slave=1").substr(0, 2), "ok");
    EXPECT_EQ(b->master.count_slaves(), 1);
    const auto dl = b->reg16(0, protocol::Reg::DlStatus);
    ASSERT_TRUE(dl);
    EXPECT_FALSE(*dl & protocol::dl_status::link(1));
    b->advance(10 * kMs);
    ASSERT_EQ(b->inj.execute("clear power_off", b->now), "ok 1 cleared");
    EXPECT_EQ(b->master.count_slaves(), 3);
    // A fresh device: no station address, INIT; its neighbours kept theirs.
    std::uint16_t st = 0xFFFF;
    ASSERT_EQ(b->master.aprd(1, protocol::addr(protocol::Reg::StationAddress),
                             Bytes(reinterpret_cast<std::uint8_t*>(&st), 2)),
              1);
    EXPECT_EQ(st, 0);
    std::uint8_t al = 0;
    ASSERT_EQ(b->master.aprd(1, protocol::addr(protocol::Reg::AlStatus), Bytes(&al, 1)), 1);
    EXPECT_EQ(al, static_cast<std::uint8_t>(AlState::Init));
    EXPECT_EQ(b->master.read_al_status(b->station(2)).state(), AlState::PreOp);
    // Slave 1 was drive 0's TWINsync partner: the rebuilt drive is not on the cable, and drive 0 keeps
    // running without touching the old one (ASan would see it).
    b->advance(10 * kMs);
    auto& d0 = dynamic_cast<cia402::Drive&>(b->seg->slave(0).app());
    EXPECT_GT(d0.servo_steps(), 0u);
}

TEST_F(FaultTest, HungFirmwareLeavesTheAlStateWhileTheEscAnswers) {
    up(1, AlState::PreOp);
    ASSERT_EQ(b->inject("firmware_hang slave=0").substr(0, 2), "ok");
    EXPECT_FALSE(b->master.request_state(b->station(0), AlState::Init, std::chrono::milliseconds(30)));
    const auto s = b->master.read_al_status(b->station(0));
    ASSERT_TRUE(s.ok);  // the ESC still answers (working counter 1)
    EXPECT_EQ(s.state(), AlState::PreOp);
    EXPECT_FALSE(s.error());
    // The firmware comes back and handles the request that waited in AL control.
    b->inj.execute("clear all", b->now);
    b->advance(kMs);
    EXPECT_EQ(b->master.read_al_status(b->station(0)).state(), AlState::Init);
}

// ---- Application layer: AL error, mailbox, drive faults, DC

TEST_F(FaultTest, ForcedAlErrorShowsTheCodeAndAnEmergency) {
    up(2, AlState::Op);
    ASSERT_EQ(b->inject("al_error slave=1 code=0x001A state=safeop").substr(0, 2), "ok");
    const auto s = b->master.read_al_status(b->station(1));
    ASSERT_TRUE(s.ok);
    EXPECT_EQ(s.state(), AlState::SafeOp);
    EXPECT_TRUE(s.error());
    EXPECT_EQ(s.code, 0x001A);
    EXPECT_EQ(b->master.read_al_status(b->station(0)).state(), AlState::Op);
    master::CoeClient c(b->master, b->station(1));
    const auto r = c.upload(0x1001, 0);
    ASSERT_TRUE(r.ok());
    EXPECT_TRUE(r.data.at(0) & coe::error_register::Communication);
    ASSERT_FALSE(c.emergencies().empty());
    // The AL status code travels in the emergency's manufacturer bytes.
    EXPECT_EQ(c.emergencies().back().error_register & coe::error_register::Communication,
              coe::error_register::Communication);
    EXPECT_EQ(c.emergencies().back().data[0], 0x1A);
    EXPECT_EQ(c.emergencies().back().data[1], 0x00);
    // The master acknowledges it like a real one.
    EXPECT_TRUE(b->master.acknowledge_error(b->station(1), AlState::SafeOp));
    EXPECT_FALSE(b->master.read_al_status(b->station(1)).error());
}

TEST_F(FaultTest, SdoAbortWithTheChosenCodeOnTheChosenObject) {
    up(1);
    master::CoeClient c(b->master, b->station(0));
    ASSERT_EQ(b->inject("sdo_abort slave=0 index=0x6060 code=0x08000022 count=1").substr(0, 2), "ok");
    EXPECT_TRUE(c.upload(obj::statusword.index, 0).ok());  // another object: unaffected
    ASSERT_NE(b->od0().find(obj::modes_of_operation)->get<std::int8_t>(), 10);
    const auto r = c.download_value<std::int8_t>(obj::modes_of_operation.index, 0, 10);
    EXPECT_TRUE(r.transport_ok);
    EXPECT_EQ(static_cast<std::uint32_t>(r.abort), 0x08000022u);
    EXPECT_NE(b->od0().find(obj::modes_of_operation)->get<std::int8_t>(), 10);              // not executed
    EXPECT_TRUE(c.download_value<std::int8_t>(obj::modes_of_operation.index, 0, 10).ok());  // count reached
    EXPECT_EQ(b->od0().find(obj::modes_of_operation)->get<std::int8_t>(), 10);
    EXPECT_EQ(b->inj.counters().sdo_aborts, 1u);
}

TEST_F(FaultTest, LostMailboxReplyTimesOutThoughTheRequestWasExecuted) {
    up(1);
    master::CoeClient c(b->master, b->station(0));
    ASSERT_EQ(b->inject("mailbox_lost_reply slave=0 count=1").substr(0, 2), "ok");
    const auto r = c.download_value<std::int8_t>(obj::modes_of_operation.index, 0, 9);
    EXPECT_FALSE(r.transport_ok);
    EXPECT_EQ(b->od0().find(obj::modes_of_operation)->get<std::int8_t>(), 9);
    EXPECT_EQ(b->inj.counters().mailbox_replies_lost, 1u);
    EXPECT_TRUE(c.upload(obj::modes_of_operation.index, 0).ok());
}

struct DriveFaultCase {
    const char* kind;
    std::uint16_t code;
};
struct DriveFaultTest : FaultTest, ::testing::WithParamInterface<DriveFaultCase> {};

TEST_P(DriveFaultTest, StatuswordFaultBitErrorCodeAndEmergency) {
    up(1);
    auto& od = b->od0();
    od.find(obj::modes_of_operation)->set(std::int8_t{8});  // CSP: the drive holds its position
    for (int cw : {0x06, 0x07, 0x0F}) {
        od.find(obj::controlword)->set(static_cast<std::uint16_t>(cw));
        b->advance(kMs);
    }
    master::CoeClient c(b->master, b->station(0));
    auto sw = c.upload(obj::statusword.index, 0);
    ASSERT_TRUE(sw.ok());
    ASSERT_EQ(ld_le16(sw.data.data()) & 0x6F, 0x27);
    ASSERT_EQ(b->inject(std::string(GetParam().kind) + " slave=0 id=f"), "ok f");
    b->advance(2 * kMs);
    sw = c.upload(obj::statusword.index, 0);
    ASSERT_TRUE(sw.ok());
    EXPECT_TRUE(ld_le16(sw.data.data()) & cia::sw::Fault) << std::hex << ld_le16(sw.data.data());
    const auto err = c.upload(obj::error_code.index, 0);
    ASSERT_TRUE(err.ok());
    EXPECT_EQ(ld_le16(err.data.data()), GetParam().code);
    bool seen = false;
    for (const auto& e : c.emergencies())
        seen |= e.error_code == GetParam().code;
    EXPECT_TRUE(seen);
    // Cause removed, fault reset by the master: the drive leaves the fault state.
    b->inj.execute("clear f", b->now);
    od.find(obj::controlword)->set(std::uint16_t{0x80});
    b->advance(2 * kMs);
    sw = c.upload(obj::statusword.index, 0);
    ASSERT_TRUE(sw.ok());
    EXPECT_FALSE(ld_le16(sw.data.data()) & cia::sw::Fault);
}

INSTANTIATE_TEST_SUITE_P(Kinds, DriveFaultTest,
                         ::testing::Values(DriveFaultCase{"encoder", 0x7305},
                                           DriveFaultCase{"over_current", 0x2310},
                                           DriveFaultCase{"following_error", 0x8611}),
                         [](const auto& i) { return std::string(i.param.kind); });

TEST_F(FaultTest, DcDriftStepShowsInTheLocalTime) {
    up(1);
    auto local = [&] {
        std::uint64_t t = 0;
        EXPECT_EQ(b->master.fprd(b->station(0), 0x0910, Bytes(reinterpret_cast<std::uint8_t*>(&t), 8)), 1);
        return t;
    };
    const std::uint64_t t0 = local();
    b->advance(1'000 * kMs);
    const std::uint64_t t1 = local();
    EXPECT_NEAR(static_cast<double>(t1 - t0), 1e9, 10.0);
    ASSERT_EQ(b->inject("dc_drift slave=0 ppm=100 id=d"), "ok d");
    b->advance(1'000 * kMs);
    const std::uint64_t t2 = local();
    EXPECT_NEAR(static_cast<double>(t2 - t1), 1e9 + 100'000, 10.0);
    b->inj.execute("clear d", b->now);  // back to the old oscillator
    b->advance(1'000 * kMs);
    EXPECT_NEAR(static_cast<double>(local() - t2), 1e9, 10.0);
}

// ---- Timeline, external handlers, control channel

TEST_F(FaultTest, TimelineStartsAndStopsFaultsAtTimesAndCycles) {
    up(2);
    b->inj.load(parse_scenario(R"(
events:
  - at_cycle: 3
    start: drop
    count: 1
  - at: 10ms
    start: link_down
    slave: 0
    port: 1
    id: cut
  - at: 20ms
    stop: cut
)"));
    std::uint16_t v = 0;
    auto brd = [&] {
        return b->once(protocol::Command::BRD, 0, 0x0000, Bytes(reinterpret_cast<std::uint8_t*>(&v), 2));
    };
    EXPECT_EQ(brd(), 2);  // frame 0 sets the time origin
    EXPECT_EQ(brd(), 2);
    EXPECT_EQ(brd(), 2);
    EXPECT_FALSE(brd());  // frame 3
    EXPECT_EQ(brd(), 2);
    b->advance(10 * kMs);
    EXPECT_EQ(brd(), 1);
    b->advance(10 * kMs);
    EXPECT_EQ(brd(), 2);
}

struct RecordingHandler final : FaultHandler {
    void start(const FaultSpec& f, std::uint64_t) override {
        if (f.params.contains("refuse")) throw std::invalid_argument("refused");
        started.push_back(f.name + "/" + std::to_string(f.slave) + "/" + f.params.at("rate"));
    }
    void stop(const FaultSpec& f, std::uint64_t) override { stopped.push_back(f.name); }
    std::vector<std::string> started, stopped;
};

TEST_F(FaultTest, ExternalFaultsGoToTheirRegisteredHandler) {
    up(2);
    EXPECT_EQ(b->inject("twinsync_crc_errors slave=1 rate=0.1").substr(0, 5), "error");  // no handler yet
    RecordingHandler h;
    b->inj.register_handler("twinsync_crc_errors", h);
    ASSERT_EQ(b->inject("twinsync_crc_errors slave=1 rate=0.1 duration=5ms id=t"), "ok t");
    EXPECT_EQ(b->inject("twinsync_crc_errors slave=1 rate=0 refuse=1").substr(0, 5), "error");
    ASSERT_EQ(h.started, std::vector<std::string>{"twinsync_crc_errors/1/0.1"});
    EXPECT_TRUE(h.stopped.empty());
    b->advance(5 * kMs);
    EXPECT_EQ(h.stopped, std::vector<std::string>{"twinsync_crc_errors"});
}

TEST_F(FaultTest, TwinsyncFaultsReachTheDrivesThroughTheirPort) {
    up(2);
    TwinsyncFaults h(*b->seg);
    register_twinsync_faults(b->inj, h);
    // The injector (in b) stops its faults through h when it goes: it must go first.
    struct ResetFirst {
        std::unique_ptr<FaultBench>& bench;
        ~ResetFirst() { bench.reset(); }
    } reset_first{b};
    auto& d0 = dynamic_cast<cia402::Drive&>(b->seg->slave(0).app());
    auto& d1 = dynamic_cast<cia402::Drive&>(b->seg->slave(1).app());
    // TWINsync on between the two drives (master drive 1, slave drive 2).
    cia402::apply_twinsync_preset(d0, d1, cia402::TwinsyncPreset::Position);
    b->advance(20 * kMs);
    ASSERT_TRUE(d1.twinsync_status()->link_ok);
    ASSERT_EQ(b->inject("twinsync_crc_errors slave=0 count=3 id=crc"), "ok crc");
    b->advance(5 * kMs);
    EXPECT_EQ(d0.twinsync_status()->crc_errors + d1.twinsync_status()->crc_errors, 3u);
    EXPECT_TRUE(d1.twinsync_status()->link_ok);  // three bad frames are far below P2613
    ASSERT_EQ(b->inject("twinsync_sync_loss slave=1 id=sync"), "ok sync");
    b->advance(2 * kMs);
    EXPECT_FALSE(d1.twinsync_status()->synchronised);
    EXPECT_EQ(b->inj.execute("clear sync", b->now).substr(0, 2), "ok");
    b->advance(20 * kMs);
    EXPECT_TRUE(d1.twinsync_status()->synchronised);
    ASSERT_EQ(b->inject("twinsync_cable_break slave=1 duration=20ms"), "ok twinsync_cable_break#1");
    b->advance(15 * kMs);
    EXPECT_FALSE(d0.twinsync_status()->link_ok);
    EXPECT_FALSE(d1.twinsync_status()->link_ok);
    EXPECT_TRUE(b->od0().find(twinsync::object_index(twinsync::p::CommStatus), 0)->get<std::uint16_t>() &
                0x0002);
    b->advance(10 * kMs);  // the break ends after its 20 ms
    b->advance(kMs);
    EXPECT_TRUE(d0.twinsync_status()->link_ok);
    EXPECT_EQ(b->inject("twinsync_cable_break slave=5").substr(0, 5), "error");
}

TEST_F(FaultTest, ControlSocketInjectsListsAndClears) {
    up(2);
    const std::string path =
        (std::filesystem::temp_directory_path() / ("vecat-faults-" + std::to_string(getpid()) + ".sock"))
            .string();
    ControlServer server(path, b->inj);
    // The serving thread: ticks the injector, which takes the commands.
    std::atomic<bool> stop{false};
    std::thread serving([&] {
        while (!stop) {
            b->inj.tick(b->now);
            std::this_thread::sleep_for(std::chrono::microseconds(200));
        }
    });
    std::string reply;
    ASSERT_TRUE(send_control_command(path, "inject link_down slave=0 port=1 id=cut", reply));
    EXPECT_EQ(reply, "ok cut");
    ASSERT_TRUE(send_control_command(path, "list", reply));
    EXPECT_EQ(reply, "ok 1 active\ncut link_down port=1 slave=0");
    ASSERT_TRUE(send_control_command(path, "inject link_down slave=9", reply));
    EXPECT_EQ(reply.substr(0, 5), "error");
    ASSERT_TRUE(send_control_command(path, "reboot", reply));
    EXPECT_EQ(reply.substr(0, 5), "error");
    stop = true;
    serving.join();
    EXPECT_FALSE(b->seg->cable(1));
    // Without a serving thread the command times out instead of hanging.
    EXPECT_EQ(b->inj.submit("clear all", std::chrono::milliseconds(20)).substr(0, 5), "error");
    EXPECT_EQ(b->inj.execute("clear all", b->now), "ok 1 cleared");
    EXPECT_TRUE(b->seg->cable(1));
}

}  // namespace
}  // namespace vecat::faults
