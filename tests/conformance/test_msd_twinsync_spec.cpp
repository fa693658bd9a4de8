// Conformance to the MSD Servo Drive TWINsync option specification (CB08759-001 Rev. 1.2,
// ../shared/seeds/000_95da6662442c2afb.txt): one test per behaviour, named after the section it checks.
// The monitoring of 40-00/40-01/40-02/40-04 and the gantry's 39-00 are tested in
// tests/unit/cia402/test_twinsync_drive.cpp (tests/conformance/README.md lists them by section).
//
// Chapter 7, 39-02 "Error detected on the other axis (master or slave)", in every operation mode of
// chapter 6 that vecat emulates, both directions: two drives, each switched by its own EtherCAT
// controlword, the slave on TWINsync's set-points (P0165 = 11), both in state Control and moving; a fault
// of one drive reaches the other as the mode prescribes (src/cia402/README.md, "TWINsync fault
// propagation").
#include <gtest/gtest.h>

#include <cmath>
#include <ostream>
#include <string>

#include "master/coe_client.hpp"
#include "protocol/cia402.hpp"
#include "protocol/cia402_objects.hpp"
#include "unit/cia402/twin_bench.hpp"

namespace vecat::cia402::conformance {
namespace {

using namespace twin_test;
using namespace twinsync;
namespace obj = protocol::obj;

// One emulated operation mode pair of P2580 (chapter 6) and where its description is.
struct Coupling {
    const char* name;
    const char* section;
    Setting master;
    Setting slave;
};

const Coupling kCouplings[] = {
    {"User", "6.2.1.1", Setting::User, Setting::User},
    {"TwdV1", "6.2.2.1", Setting::TwdMasterV1, Setting::TwdSlaveV1},
    {"TwdV2", "6.2.2.2", Setting::TwdMasterV2, Setting::TwdSlaveV2},
    {"Scon", "6.2.3.1", Setting::SconMaster, Setting::SconSlave},
    {"Pcon", "6.2.3.2", Setting::PconMaster, Setting::PconSlave},
    {"VeTcon", "6.2.6.1", Setting::VeTconMaster, Setting::VeTconSlave},
    {"PconIp", "6.2.8.1", Setting::PconMaster, Setting::PconIpSlave},
    {"Refpos", "6.2.10.1", Setting::PconRefposMaster, Setting::PconRefposSlave},
    {"Gantry", "6.2.12.1", Setting::PconGantryMaster, Setting::PconGantrySlave},
    {"ExtMap", "6.2.13.1", Setting::ExtMapMaster, Setting::ExtMapSlave},
};

void PrintTo(const Coupling& c, std::ostream* os) {
    *os << c.name << " (section " << c.section << ")";
}

// The modes whose tables 6.5-6.10 have the slave send its P2650 (current error) to the master.
bool slave_sends_its_error(Setting s) {
    switch (s) {
        case Setting::TwdSlaveV1:
        case Setting::TwdSlaveV2:
        case Setting::SconSlave:
        case Setting::PconSlave:
        case Setting::VeTconSlave:
        case Setting::PconIpSlave:
            return true;
        default:
            return false;
    }
}

struct MsdTwinsync : TwinBench, ::testing::WithParamInterface<Coupling> {
    MsdTwinsync() : TwinBench(&connected_line) {}
    static constexpr std::size_t kMaster = 0, kSlave = 1;
    std::int32_t p0 = 0, p1 = 0;  // the CSP targets

    void configure(const Coupling& c) {
        par(kMaster, p::Mode).set<std::uint16_t>(static_cast<std::uint16_t>(Role::Master));
        par(kSlave, p::Mode).set<std::uint16_t>(static_cast<std::uint16_t>(Role::Slave));
        par(kMaster, p::Setting).set<std::uint8_t>(static_cast<std::uint8_t>(c.master));
        par(kSlave, p::Setting).set<std::uint8_t>(static_cast<std::uint8_t>(c.slave));
        par(kSlave, p::SetpointSelector).set<std::uint16_t>(kSetpointByTwinsync);
        if (c.master == Setting::User || c.master == Setting::ExtMapMaster) {
            // The user's mapping: the master's position set-point P2600 to the slave's P2607 (and in the
            // extended mapping its speed P2599 to P2605), the slave following in position (P0300 = 3).
            const bool ext = c.master == Setting::ExtMapMaster;
            for (std::uint8_t s = 1; s <= 8; ++s) {
                par(kMaster, p::ProcessSendData, s).set<std::uint32_t>(0);
                par(kSlave, p::ProcessReceiveData, s).set<std::uint32_t>(0);
            }
            if (ext) {
                par(kMaster, p::ProcessSendData, 1).set<std::uint32_t>(mapping_word(p::LocalRefPos, 0, 0));
                par(kMaster, p::ProcessSendData, 2).set<std::uint32_t>(mapping_word(p::LocalActSpeed, 0, 0));
                par(kSlave, p::ProcessReceiveData, 1).set<std::uint32_t>(mapping_word(p::RemoteRefPos, 0, 0));
                par(kSlave, p::ProcessReceiveData, 2)
                    .set<std::uint32_t>(mapping_word(p::RemoteRefSpeed, 0, 0));
            } else {
                par(kMaster, p::ProcessSendData, 1).set<std::uint32_t>(1);
                par(kMaster, p::ProcessSendData, 2).set<std::uint32_t>(mapping_word(p::LocalRefPos, 0, 0x20));
                par(kSlave, p::ProcessReceiveData, 1).set<std::uint32_t>(1);
                par(kSlave, p::ProcessReceiveData, 2)
                    .set<std::uint32_t>(mapping_word(p::RemoteRefPos, 0, 0x20));
            }
            par(kSlave, p::ControlMode).set<std::uint16_t>(3);
        }
        drive(kMaster).twinsync_port().reconfigure();
        drive(kSlave).twinsync_port().reconfigure();
    }
    void step(std::uint16_t cw0, std::uint16_t cw1, std::uint64_t ns = kMs) {
        cycle(cw0, p0, cw1, 8, p1, ns);
    }
    // Both drives switched on by their own controlword; the master switches on its control once its slave
    // is in Control (P2651 bit 2 clear, section 4.1).
    void enable_both() {
        p0 = pos(kMaster);
        p1 = pos(kSlave);
        for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
            for (int i = 0; i < 5; ++i)
                step(cw, cw);
        ASSERT_EQ(drive(kMaster).cia402_state(), State::OperationEnabled);
        ASSERT_EQ(drive(kSlave).cia402_state(), State::OperationEnabled);
        ASSERT_TRUE(drive(kSlave).twinsync_status()->link_ok);
    }
    // The master drive moves at 0.3 units per us in CSP (about 0.29 rev/s), the slave coupled to it.
    void move(int ms) {
        for (int i = 0; i < ms; ++i) {
            p0 += 300;
            step(0x0F, 0x0F);
        }
    }
    // The emergency with the MSD error number and location in its manufacturer bytes.
    bool emergency_seen(std::size_t d, std::uint16_t code, ErrorId e) {
        master::CoeClient c(b.master, static_cast<std::uint16_t>(0x1001 + d));
        c.upload(0x1000, 0);
        for (const auto& em : c.emergencies())
            if (em.error_code == code && em.data[0] == e.number && em.data[1] == e.location) return true;
        return false;
    }
    // Injects a following error fault (0x2101 = 0x8611) into `faulty` in motion; returns after the other
    // drive faulted or 20 ms.
    void fault_in_motion(std::size_t faulty) {
        enable_both();
        const std::int32_t slave_before = pos(kSlave);
        move(100);
        ASSERT_GT(std::abs(pos(kSlave) - slave_before), 10'000) << "the slave follows its master";
        ASSERT_EQ(drive(1 - faulty).cia402_state(), State::OperationEnabled);
        e(faulty, 0x2101).set<std::uint16_t>(fault::FollowingError);
        for (int i = 0; i < 80 && drive(1 - faulty).cia402_state() == State::OperationEnabled; ++i)
            step(0x0F, 0x0F, kCycle);
    }
    // The other drive faulted with 39-02, the emergency carrying it, and both come to rest in FAULT; a
    // fault reset of both clears it once the cause is gone.
    void expect_partner_error(std::size_t faulty) {
        const std::size_t other = 1 - faulty;
        EXPECT_EQ(drive(other).twinsync_error(), error::OtherAxis);
        for (int i = 0;
             i < 300 && (drive(0).cia402_state() != State::Fault || drive(1).cia402_state() != State::Fault);
             ++i)
            step(0x0F, 0x0F);
        EXPECT_EQ(drive(faulty).cia402_state(), State::Fault);
        EXPECT_EQ(drive(other).cia402_state(), State::Fault);
        EXPECT_TRUE(sw(other) & protocol::cia402::sw::Fault);  // as the EtherCAT master sees it
        EXPECT_EQ(e(other, obj::error_code.index).get<std::uint16_t>(), 0x7520);
        EXPECT_TRUE(emergency_seen(other, 0x7520, error::OtherAxis));
        e(faulty, 0x2101).set<std::uint16_t>(0);
        for (int i = 0; i < 6; ++i)
            step(i % 2 ? 0x80 : 0x00, i % 2 ? 0x80 : 0x00);
        EXPECT_EQ(drive(0).cia402_state(), State::SwitchOnDisabled);
        EXPECT_EQ(drive(1).cia402_state(), State::SwitchOnDisabled);
        EXPECT_FALSE(drive(other).twinsync_error());
    }
};

// Chapter 7, 39-02, and TwinCAT NC's error propagation (TX1250 3.1, INSTANTANEOUS: an error of one axis
// halts every axis of its master/slave group): the master drive's fault reaches its slave. In the
// extended mapping (6.2.13) the telegram has no status word and the link is not monitored (4.1.2): the
// slave does not fault, it stops with the set-points it follows, those of the master's fault reaction.
TEST_P(MsdTwinsync, MsdTwinsync_7_39_02_MasterFaultReachesTheSlave) {
    const Coupling& c = GetParam();
    configure(c);
    fault_in_motion(kMaster);
    if (c.master == Setting::ExtMapMaster) {
        for (int i = 0; i < 300 && drive(kMaster).cia402_state() != State::Fault; ++i)
            step(0x0F, 0x0F);
        ASSERT_EQ(drive(kMaster).cia402_state(), State::Fault);
        const std::int32_t stopped = pos(kSlave);
        for (int i = 0; i < 100; ++i)
            step(0x0F, 0x0F);
        EXPECT_EQ(drive(kSlave).cia402_state(), State::OperationEnabled);
        EXPECT_FALSE(drive(kSlave).twinsync_error());
        EXPECT_NEAR(pos(kSlave), stopped, 200) << "the slave stopped with its master";
        EXPECT_LT(std::abs(drive(kSlave).velocity_actual()), 1000);
        return;
    }
    expect_partner_error(kMaster);
}

// Chapter 7, 39-02, the other way: the slave's fault reaches the master drive, which then stops the group
// (TX1250 3.1). The modes of tables 6.5-6.10 also carry the slave's current error P2650 to the master
// (6.2.2.1: "the received data ... are interpreted as current error number and location of the slave").
// In the extended mapping nothing reaches the master (4.1.2): it goes on with its set-points.
TEST_P(MsdTwinsync, MsdTwinsync_7_39_02_SlaveFaultReachesTheMaster) {
    const Coupling& c = GetParam();
    configure(c);
    fault_in_motion(kSlave);
    if (c.master == Setting::ExtMapMaster) {
        const std::int32_t before = pos(kMaster);
        move(100);
        EXPECT_EQ(drive(kMaster).cia402_state(), State::OperationEnabled);
        EXPECT_FALSE(drive(kMaster).twinsync_error());
        EXPECT_NEAR(pos(kMaster) - before, 100 * 300, 1000) << "the master goes on";
        return;
    }
    if (slave_sends_its_error(c.slave)) {
        EXPECT_EQ(par(kMaster, p::CurrentError, 1).get<std::uint16_t>(), fault::FollowingError >> 8);
        EXPECT_EQ(par(kMaster, p::CurrentError, 2).get<std::uint16_t>(), fault::FollowingError & 0xFF);
    }
    expect_partner_error(kSlave);
}

INSTANTIATE_TEST_SUITE_P(Coupling, MsdTwinsync, ::testing::ValuesIn(kCouplings),
                         [](const ::testing::TestParamInfo<Coupling>& i) {
                             return std::string(i.param.name);
                         });

// Chapter 7: "errors are only reported when the MSD Servo Drive is in the Control state": a slave that is
// switched on but not in Control does not fault when its master does, and can be enabled once the master
// is reset.
TEST_F(MsdTwinsync, MsdTwinsync_7_ErrorsOnlyInControl) {
    configure(kCouplings[8]);  // gantry
    p0 = pos(kMaster);
    p1 = pos(kSlave);
    par(kMaster, p::Config).set<std::uint32_t>(kConfigNoSlaveStateCheck);
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x0F}})
        for (int i = 0; i < 5; ++i)
            step(cw, cw == 0x06 ? 0x06 : 0x07);
    ASSERT_EQ(drive(kMaster).cia402_state(), State::OperationEnabled);
    ASSERT_EQ(drive(kSlave).cia402_state(), State::SwitchedOn);
    e(kMaster, 0x2101).set<std::uint16_t>(fault::FollowingError);
    for (int i = 0; i < 50; ++i)
        step(0x0F, 0x07);
    EXPECT_EQ(drive(kMaster).cia402_state(), State::Fault);
    EXPECT_EQ(drive(kSlave).cia402_state(), State::SwitchedOn);
    EXPECT_FALSE(drive(kSlave).twinsync_error());
}

// 4.1, table 4.1, P2619 TOPT_TWIN_CommStatus "bit 0: no error": it reads "no error" whenever no error
// bit is set: at power-on and with TWINsync OFF (nothing monitored, nothing wrong) as well as with a
// working link; with a fault it shows the error bit alone.
TEST_F(MsdTwinsync, MsdTwinsync_4_1_P2619ReadsNoError) {
    for (std::size_t d : {kMaster, kSlave}) {
        SCOPED_TRACE(d);
        EXPECT_EQ(par(d, p::CommStatus).get<std::uint16_t>(), comm_status::NoError)
            << "power-on, TWINsync OFF";
        master::CoeClient c(b.master, static_cast<std::uint16_t>(0x1001 + d));
        const auto r = c.upload(object_index(p::CommStatus), 0);
        ASSERT_EQ(r.data.size(), 2u);
        EXPECT_EQ(ld_le16(r.data.data()), comm_status::NoError) << "read by SDO";
    }
    for (int i = 0; i < 10; ++i)
        step(0, 0);
    EXPECT_EQ(par(kMaster, p::CommStatus).get<std::uint16_t>(), comm_status::NoError) << "still OFF";
    configure(kCouplings[3]);  // SCON
    for (int i = 0; i < 10; ++i)
        step(0, 0);
    EXPECT_EQ(par(kMaster, p::CommStatus).get<std::uint16_t>(), comm_status::NoError) << "link up";
    e(kMaster, 0x2104, 1).set<std::uint8_t>(1);  // cable break
    for (int i = 0; i < 20; ++i)
        step(0, 0);
    EXPECT_EQ(par(kSlave, p::CommStatus).get<std::uint16_t>(), comm_status::CommunicationLost);
    e(kMaster, 0x2104, 1).set<std::uint8_t>(0);
    par(kSlave, p::Mode).set<std::uint16_t>(0);  // OFF again
    drive(kSlave).twinsync_port().reconfigure();
    step(0, 0);
    EXPECT_EQ(par(kSlave, p::CommStatus).get<std::uint16_t>(), comm_status::NoError) << "OFF again";
}

}  // namespace
}  // namespace vecat::cia402::conformance
