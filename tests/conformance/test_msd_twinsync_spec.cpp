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
#include <cstring>
#include <ostream>
#include <string>
#include <vector>

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

// The issue-28 tests below drive the outputs of both drives themselves (mode, target torque), over the
// RxPDO 0x1600 of the vecat drive: controlword, mode, pad, target position, velocity, torque.
struct MsdTwinsyncIo : MsdTwinsync {
    void io(std::uint16_t cw0, std::int8_t mode0, std::int32_t pos0, std::int16_t torque0, std::uint16_t cw1,
            std::uint64_t ns = kMs) {
        auto o = b.master.outputs(kMaster);
        st_le16(o.data(), cw0);
        o[2] = static_cast<std::uint8_t>(mode0);
        st_le32(o.data() + 4, static_cast<std::uint32_t>(pos0));
        st_le16(o.data() + 12, static_cast<std::uint16_t>(torque0));
        auto o1 = b.master.outputs(kSlave);
        st_le16(o1.data(), cw1);
        o1[2] = 8;
        st_le32(o1.data() + 4, static_cast<std::uint32_t>(p1));
        ASSERT_EQ(b.master.exchange_process_data().value_or(0), b.master.expected_wkc());
        b.advance(ns);
    }
    // The times (ns) at which the slave's received P2607 changed while the master moves for `ms`.
    std::vector<std::uint64_t> remote_changes(int ms) {
        std::vector<std::uint64_t> at;
        std::int32_t last = par(kSlave, p::RemoteRefPos).get<std::int32_t>();
        for (int i = 0; i < ms; ++i) {
            p0 += 300;
            step(0x0F, 0x0F, 0);
            for (int k = 0; k < 40; ++k) {  // 25 us steps
                b.advance(25'000);
                const auto v = par(kSlave, p::RemoteRefPos).get<std::int32_t>();
                if (v != last) at.push_back(b.now);
                last = v;
            }
        }
        return at;
    }
    void set_switching_frequency(std::uint16_t code) {
        for (std::size_t d : {kMaster, kSlave})
            par(d, p::SwitchingFrequency).set<std::uint16_t>(code);
    }
};

// Chapter 2: "Data transfer takes place according to the speed control clock (dependent on the switching
// frequency; at 4 kHz, 250 us or at 8 kHz, 125 us)". Both drives at 8 kHz (P0302 = 3): the partner sees a
// new value every 125 us, and the drives' servo period (the speed control's sampling) is 125 us.
TEST_F(MsdTwinsyncIo, MsdTwinsync_2_At8kHzThePartnerSeesANewValueEvery125Us) {
    configure(kCouplings[7]);  // REFPOS: the master's position set-point P2600 -> the slave's P2607
    set_switching_frequency(3);
    enable_both();
    EXPECT_EQ(drive(kMaster).servo_period_ns(), 125'000u);
    EXPECT_EQ(drive(kSlave).servo_period_ns(), 125'000u);
    const auto frames = drive(kSlave).twinsync_status()->frames_received;
    const auto at = remote_changes(4);
    ASSERT_GE(at.size(), 30u);
    for (std::size_t i = 1; i < at.size(); ++i)
        EXPECT_EQ(at[i] - at[i - 1], 125'000u) << i;
    EXPECT_EQ(drive(kSlave).twinsync_status()->frames_received - frames, 32u) << "4 ms / 125 us";
    EXPECT_FALSE(drive(kSlave).twinsync_error());
}

TEST_F(MsdTwinsyncIo, MsdTwinsync_2_At4kHzThePartnerSeesANewValueEvery250Us) {
    configure(kCouplings[7]);
    set_switching_frequency(1);
    enable_both();
    EXPECT_EQ(drive(kMaster).servo_period_ns(), 250'000u);
    const auto frames = drive(kSlave).twinsync_status()->frames_received;
    const auto at = remote_changes(4);
    ASSERT_GE(at.size(), 14u);
    for (std::size_t i = 1; i < at.size(); ++i)
        EXPECT_EQ(at[i] - at[i - 1], 250'000u) << i;
    EXPECT_EQ(drive(kSlave).twinsync_status()->frames_received - frames, 16u) << "4 ms / 250 us";
}

// Chapter 2: "up to 30 bytes of usable data ... depending on the baud rate selected and the TWIN sampling
// time". A 32-byte frame (P2709[1] = 13) takes 160 us at 2 MBaud: it fits 250 us, not 125 us, so P0302 =
// 3 (8 kHz) is refused with the reason in 0x2102, and accepted again at 4 MBaud (80 us).
TEST_F(MsdTwinsyncIo, MsdTwinsync_2_TheTelegramMustFitTheSamplingTime) {
    configure(kCouplings[7]);
    master::CoeClient c(b.master, 0x1001);
    ASSERT_EQ(c.download_value<std::uint16_t>(object_index(p::PhyLinkConfig), 2, 13).abort,
              protocol::SdoAbort::None);
    ASSERT_EQ(c.download_value<std::uint16_t>(object_index(p::PhyLinkConfig), 1, 1).abort,
              protocol::SdoAbort::None);
    EXPECT_EQ(c.download_value<std::uint16_t>(object_index(p::SwitchingFrequency), 0, 3).abort,
              protocol::SdoAbort::ParameterIncompatible);
    const auto msg = c.upload(0x2102, 0);
    const std::string text(msg.data.begin(), msg.data.end());
    EXPECT_NE(text.find("125.0 us"), std::string::npos) << text;
    EXPECT_EQ(par(kMaster, p::SwitchingFrequency).get<std::uint16_t>(), 1) << "unchanged";
    step(0, 0);
    EXPECT_EQ(drive(kMaster).servo_period_ns(), 250'000u);
    ASSERT_EQ(c.download_value<std::uint16_t>(object_index(p::PhyLinkConfig), 1, 0).abort,
              protocol::SdoAbort::None);
    EXPECT_EQ(c.download_value<std::uint16_t>(object_index(p::SwitchingFrequency), 0, 3).abort,
              protocol::SdoAbort::None);
    step(0, 0);
    EXPECT_EQ(drive(kMaster).servo_period_ns(), 125'000u);
}

// 6.2.10: "The homing is controlled via the master and is also synchronized with the slave. The
// synchronization of the slave with the position of the master is absolute." The master homes (method 37,
// the current position is the home position, home offset 0x607C); its position now reads the home offset.
// The slave, controlled through TWINsync (P0159 = 10) and following the master's position set-point,
// takes the same reference: it reads the master's position, without moving, and reports itself homed to
// the master (P2612 HomePositionSet).
TEST_F(MsdTwinsyncIo, MsdTwinsync_6_2_10_HomingOnTheMasterCarriesOverToTheSlave) {
    configure(kCouplings[7]);
    par(kSlave, p::ControlSelector).set<std::uint16_t>(kControlByTwinsync);
    drive(kSlave).twinsync_port().reconfigure();
    enable_both();
    move(50);
    for (int i = 0; i < 20; ++i)
        step(0x0F, 0x0F);  // at rest
    ASSERT_NEAR(drive(kSlave).position_demand(), drive(kMaster).position_demand(), 1);
    ASSERT_FALSE(par(kMaster, p::SlaveStatus).get<std::uint16_t>() & slave_status::HomePositionSet);
    e(kMaster, obj::homing_method.index).set<std::int8_t>(37);
    e(kMaster, obj::home_offset.index).set<std::int32_t>(500'000);
    const double slave_machine = drive(kSlave).mechanics().position();
    for (int i = 0; i < 5; ++i)
        io(0x0F, 6, p0, 0, 0x0F);
    for (int i = 0; i < 20; ++i)
        io(0x1F, 6, p0, 0, 0x0F);
    EXPECT_NEAR(drive(kMaster).position_demand(), 500'000, 1);
    EXPECT_NEAR(drive(kSlave).position_demand(), 500'000, 1) << "the slave took the master's reference";
    EXPECT_NEAR(pos(kSlave), pos(kMaster), 1000);
    // (Without the common reference it would move 485,000 increments, 2.9 rad; it only settles.)
    EXPECT_NEAR(drive(kSlave).mechanics().position(), slave_machine, 0.01) << "without moving";
    EXPECT_EQ(drive(kSlave).cia402_state(), State::OperationEnabled);
    EXPECT_FALSE(drive(kSlave).twinsync_error());
    EXPECT_TRUE(par(kMaster, p::SlaveStatus).get<std::uint16_t>() & slave_status::HomePositionSet);
    // And it goes on following the master absolutely, in the new coordinates.
    p0 = static_cast<std::int32_t>(std::lround(drive(kMaster).position_demand()));
    for (int i = 0; i < 5; ++i)
        io(0x0F, 8, p0, 0, 0x0F);
    move(50);
    for (int i = 0; i < 20; ++i)
        step(0x0F, 0x0F);
    EXPECT_NEAR(drive(kSlave).position_demand(), drive(kMaster).position_demand(), 1);
    EXPECT_NEAR(drive(kMaster).position_demand(), 500'000 + 50 * 300, 1);
}

// 6.2.10 with a homing that moves (method 34, the index pulse in positive direction): the slave follows
// the master's homing motion and takes its reference where the master's coordinates change, in motion.
TEST_F(MsdTwinsyncIo, MsdTwinsync_6_2_10_SlaveFollowsTheMastersHomingMotionAndItsReference) {
    configure(kCouplings[7]);
    par(kSlave, p::ControlSelector).set<std::uint16_t>(kControlByTwinsync);
    drive(kSlave).twinsync_port().reconfigure();
    enable_both();
    e(kMaster, obj::homing_method.index).set<std::int8_t>(34);
    e(kMaster, obj::home_offset.index).set<std::int32_t>(-1'000'000);
    e(kMaster, obj::homing_speeds::search_for_switch.index, 1).set<std::uint32_t>(2'000'000);
    e(kMaster, obj::homing_speeds::search_for_zero.index, 2).set<std::uint32_t>(2'000'000);
    for (std::size_t d : {kMaster, kSlave})
        e(d, obj::homing_acceleration.index).set<std::uint32_t>(10'000'000);
    const double master_machine = drive(kMaster).mechanics().position();
    const double slave_machine = drive(kSlave).mechanics().position();
    for (int i = 0; i < 5; ++i)
        io(0x0F, 6, p0, 0, 0x0F);
    bool attained = false;
    for (int i = 0; i < 1500 && !attained; ++i) {
        io(0x1F, 6, p0, 0, 0x0F);
        attained = (sw(kMaster) & 0x1400) == 0x1400;  // target reached and homing attained
    }
    ASSERT_TRUE(attained);
    for (int i = 0; i < 20; ++i)
        io(0x1F, 6, p0, 0, 0x0F);
    const double master_moved = drive(kMaster).mechanics().position() - master_machine;
    const double slave_moved = drive(kSlave).mechanics().position() - slave_machine;
    EXPECT_GT(std::abs(master_moved), 0.1) << "the master moved to its index pulse (rad)";
    EXPECT_NEAR(slave_moved, master_moved, 0.01) << "the slave moved with it";
    EXPECT_NEAR(drive(kSlave).position_demand(), drive(kMaster).position_demand(), 1)
        << "and reads the master's position";
    EXPECT_LT(drive(kMaster).position_demand(), -500'000) << "in the coordinates of the home offset";
    EXPECT_EQ(drive(kSlave).cia402_state(), State::OperationEnabled);
    EXPECT_TRUE(par(kMaster, p::SlaveStatus).get<std::uint16_t>() & slave_status::HomePositionSet);
}

// Table 6.10 (VE, 12+13): P2581 MasterTorqueTF on the slave filters the master's torque set-point (a
// first-order lag of that time constant in ms); 0 passes it through.
TEST_F(MsdTwinsyncIo, MsdTwinsync_6_2_6_1_MasterTorqueTFFiltersTheMastersTorque) {
    configure(kCouplings[5]);  // VE
    enable_both();
    auto slave_torque = [&] { return e(kSlave, obj::torque_demand.index).get<std::int16_t>(); };
    // The master in CST; an external load (0x2100:5) as large as the torque keeps both axes near rest.
    auto torque = [&](std::int16_t t, int periods) {
        for (std::size_t d : {kMaster, kSlave})
            e(d, 0x2100, 5).set<std::int16_t>(t);
        for (int i = 0; i < periods; ++i)
            io(0x0F, 10, p0, t, 0x0F, kCycle);
    };
    torque(0, 12);
    torque(100, 12);
    EXPECT_NEAR(slave_torque(), 100, 2) << "P2581 = 0: the master's torque";
    torque(0, 40);
    EXPECT_NEAR(slave_torque(), 0, 2);
    par(kSlave, p::MasterTorqueTF).set<float>(5.0f);
    // The step reaches the slave two periods later (the master's period, then the telegram's): after 22
    // periods the filter has run 20 periods = 5 ms, one time constant.
    torque(100, 6);
    EXPECT_GT(slave_torque(), 10);
    EXPECT_LT(slave_torque(), 35) << "about 100 (1 - e^(-1/5))";
    torque(100, 16);
    EXPECT_NEAR(slave_torque(), 63, 3) << "one time constant";
    torque(100, 80);
    EXPECT_NEAR(slave_torque(), 100, 2) << "six time constants";
    EXPECT_EQ(e(kMaster, obj::torque_demand.index).get<std::int16_t>(), 100);
}

// 4.1.2: "it is therefore recommended that master and slave be configured and then an initialization be
// forced ... (P0149) MPRO_DRVCOM_Init". Writing 1 initialises the link again: the slave's synchronisation
// starts anew (unsynchronised until it has locked to SYNC_OUT again); P0149 reads 0 once done.
TEST_F(MsdTwinsyncIo, MsdTwinsync_4_1_2_P0149ForcesAnInitialisation) {
    configure(kCouplings[3]);  // SCON
    for (int i = 0; i < 20; ++i)
        step(0, 0);
    ASSERT_TRUE(drive(kSlave).twinsync_status()->synchronised);
    ASSERT_TRUE(drive(kSlave).twinsync_status()->link_ok);
    master::CoeClient c(b.master, 0x1002);
    ASSERT_EQ(c.download_value<std::uint16_t>(object_index(p::DriveComInit), 0, 1).abort,
              protocol::SdoAbort::None);
    EXPECT_EQ(par(kSlave, p::DriveComInit).get<std::uint16_t>(), 0);
    EXPECT_EQ(drive(kSlave).twinsync_status()->initialisations, 1u);
    step(0, 0);
    EXPECT_FALSE(drive(kSlave).twinsync_status()->synchronised) << "synchronising again";
    for (int i = 0; i < 20; ++i)
        step(0, 0);
    EXPECT_TRUE(drive(kSlave).twinsync_status()->synchronised);
    EXPECT_TRUE(drive(kSlave).twinsync_status()->link_ok);
    EXPECT_NE(c.download_value<std::uint16_t>(object_index(p::DriveComInit), 0, 2).abort,
              protocol::SdoAbort::None)
        << "0 or 1";
    EXPECT_EQ(drive(kSlave).twinsync_status()->initialisations, 1u);
}

// Tables 6.5-6.11, 6.14: the slave runs with P0301 setpoint mode = IP-Mode (1). With another setpoint
// mode it does not take TWINsync's set-points (like P0165 not TWINSYNC), and 0x2102 says why.
TEST_F(MsdTwinsyncIo, MsdTwinsync_6_2_SlaveFollowsOnlyInIpMode) {
    configure(kCouplings[4]);  // PCON
    EXPECT_EQ(par(kSlave, p::SetpointMode).get<std::uint16_t>(), kSetpointModeIp) << "default";
    master::CoeClient c(b.master, 0x1002);
    ASSERT_EQ(c.download_value<std::uint16_t>(object_index(p::SetpointMode), 0, 0).abort,
              protocol::SdoAbort::None);
    const auto msg = c.upload(0x2102, 0);
    const std::string text(msg.data.begin(), msg.data.end());
    EXPECT_NE(text.find("P0301"), std::string::npos) << text;
    enable_both();
    const std::int32_t before = pos(kSlave);
    move(50);
    EXPECT_NEAR(pos(kSlave), before, 50) << "not following";
    ASSERT_EQ(c.download_value<std::uint16_t>(object_index(p::SetpointMode), 0, 1).abort,
              protocol::SdoAbort::None);
    for (int i = 0; i < 20; ++i)
        step(0x0F, 0x0F);  // both at rest: the slave couples
    const std::int32_t coupled = pos(kSlave);
    move(50);
    EXPECT_GT(pos(kSlave) - coupled, 10'000) << "following";
}

// Tables 6.1 / 6.2 (virtual encoder: P0507 channel 3 = TWINSYNC(6), P0520 / P0521 = CH3(3)) and 4.7
// (P2697[2], the reference current behind P2609[2]): the parameters exist with their values and ranges.
TEST_F(MsdTwinsyncIo, MsdTwinsync_6_1_VirtualEncoderParametersAndReferenceCurrent) {
    master::CoeClient c(b.master, 0x1002);
    EXPECT_EQ(
        c.download_value<std::uint16_t>(object_index(p::EncoderChannel3), 0, kEncoderChannel3Twinsync).abort,
        protocol::SdoAbort::None);
    EXPECT_EQ(c.download_value<std::uint16_t>(object_index(p::CommutationEncoder), 0, kEncoderCh3).abort,
              protocol::SdoAbort::None);
    EXPECT_EQ(c.download_value<std::uint16_t>(object_index(p::SpeedEncoder), 0, kEncoderCh3).abort,
              protocol::SdoAbort::None);
    EXPECT_NE(c.download_value<std::uint16_t>(object_index(p::EncoderChannel3), 0, 7).abort,
              protocol::SdoAbort::None);
    EXPECT_NE(c.download_value<std::uint16_t>(object_index(p::CommutationEncoder), 0, 4).abort,
              protocol::SdoAbort::None);
    EXPECT_EQ(par(kSlave, p::EncoderChannel3).get<std::uint16_t>(), kEncoderChannel3Twinsync);
    const auto current = c.upload(object_index(p::ReferenceValues), 3);
    ASSERT_EQ(current.data.size(), 4u);
    float f = 0;
    std::memcpy(&f, current.data.data(), 4);
    EXPECT_EQ(f, 90.0f) << "P2697[2] (100 mA)";
    const auto tf = c.upload(object_index(p::MasterTorqueTF), 0);
    EXPECT_EQ(tf.data.size(), 4u) << "P2581 Float32";
}

}  // namespace
}  // namespace vecat::cia402::conformance
