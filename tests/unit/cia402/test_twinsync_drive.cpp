// Two drives coupled by TWINsync, driven by the project's master in-process: the gantry (master drive in
// CSP, slave drive following through TWINsync), control of the slave through the TWINsync control word,
// the monitoring (40-00 on a cable break within P2613, 40-02 with two masters, sync loss), the coupling
// semantics of a position slave, and the refusal of what cannot work.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "cia402/drive.hpp"
#include "master/coe_client.hpp"
#include "protocol/cia402.hpp"
#include "protocol/cia402_objects.hpp"
#include "test_support.hpp"
#include "twinsync/parameters.hpp"
#include "unit/cia402/twin_bench.hpp"

namespace cia = vecat::protocol::cia402;

namespace obj = vecat::protocol::obj;

namespace vecat::cia402 {
namespace {

using namespace twinsync;
using namespace twin_test;

TEST_F(TwinBench, GantrySlaveFollowsTheMasterDriveInCsp) {
    // Before anything is enabled the link is up and the slave is synchronised to SYNC_OUT.
    for (int i = 0; i < 50; ++i)
        cycle(0, pos(0));
    ASSERT_NE(drive(0).twinsync_status(), nullptr);
    EXPECT_TRUE(drive(1).twinsync_status()->synchronised);
    EXPECT_TRUE(drive(0).twinsync_status()->link_ok);
    EXPECT_EQ(par(0, p::CommStatus).get<std::uint16_t>(), 0x0001);       // no error
    EXPECT_EQ(par(1, p::Statusword).get<std::uint16_t>() & 0x30, 0x20);  // the partner is a master

    enable_gantry();
    // The slave was switched on by the master's control word (it never got one over EtherCAT), and
    // reports state 5 "Control" back in P2612.
    EXPECT_EQ(par(1, p::SlaveCtrlWord).get<std::uint16_t>() & 0x0860, 0x0860);
    const std::uint16_t slave_status = par(0, p::SlaveStatus).get<std::uint16_t>();
    EXPECT_TRUE(slave_status & slave_status::OperationEnabled);
    EXPECT_EQ(slave_status >> 13, 5);

    // A jerk-limited move of two revolutions and back, generated like a master's NC does.
    const double start = pos(0);
    ProfileGenerator gen;
    gen.reset({start, 0, 0});
    const ProfileLimits limits{2.0 * (1 << 20), 20.0 * (1 << 20), 20.0 * (1 << 20), 400.0 * (1 << 20)};
    gen.move_to(start + 2.0 * (1 << 20), limits);
    double worst = 0, worst_twin = 0;
    int cycles = 0;
    for (int leg = 0; leg < 2; ++leg) {
        if (leg == 1) gen.move_to(start, limits);
        while (!gen.done() || cycles % 100 != 0) {
            const Kinematics k = gen.step(1e-3);
            cycle(0x0F, static_cast<std::int32_t>(std::lround(k.p)));
            worst = std::max(worst, std::abs(static_cast<double>(pos(0)) - pos(1)));
            worst_twin = std::max(worst_twin,
                                  std::abs(static_cast<double>(drive(0).twinsync_status()->tracking_error)));
            ++cycles;
        }
    }
    for (int i = 0; i < 100; ++i)
        cycle(0x0F, static_cast<std::int32_t>(start));
    std::printf(
        "gantry: %d cycles of 1 ms, 2 revolutions (2^21 units) at up to 2 rev/s; tracking error master-slave "
        "max %.0f units (%.3f %% of a revolution) read over EtherCAT, %.0f units in the master drive\n",
        cycles, worst, worst / (1 << 20) * 100.0, worst_twin);
    EXPECT_GT(worst, 0);
    EXPECT_LT(worst, 2000);  // 0.2 % of a revolution
    EXPECT_LE(std::abs(pos(0) - pos(1)), 5);
    EXPECT_EQ(drive(0).cia402_state(), State::OperationEnabled);
    EXPECT_EQ(drive(1).cia402_state(), State::OperationEnabled);
    EXPECT_GT(drive(1).twinsync_status()->frames_received, 4u * static_cast<unsigned>(cycles));
    EXPECT_EQ(drive(1).twinsync_status()->crc_errors, 0u);
}

TEST_F(TwinBench, CableBreakFaultsBothDrivesWithin40_00WithinTheMaxFaultTime) {
    enable_gantry();
    // Moving at constant speed.
    std::int32_t p = pos(0);
    for (int i = 0; i < 200; ++i)
        cycle(0x0F, p += 500);
    const double max_fault_ms = par(0, p::MaxFaultTime).get<float>();
    ASSERT_EQ(max_fault_ms, 10.0);
    e(0, 0x2104, 1).set<std::uint8_t>(1);  // cable break
    // Time from the break to the fault bit in each drive's statusword, at control cycle resolution.
    double t_fault[2] = {-1, -1};
    for (int k = 1; k <= 80 && (t_fault[0] < 0 || t_fault[1] < 0); ++k) {
        cycle(0x0F, p += 125, 0, 8, 0, kCycle);
        for (int d = 0; d < 2; ++d)
            if (t_fault[d] < 0 && (e(d, obj::statusword.index).get<std::uint16_t>() & cia::sw::Fault))
                t_fault[d] = k * kCycle / 1e6;
    }
    cycle(0x0F, p);
    EXPECT_TRUE(sw(0) & cia::sw::Fault);  // and the master sees it over EtherCAT
    EXPECT_TRUE(sw(1) & cia::sw::Fault);
    std::printf(
        "cable break: fault after %.2f ms (master drive) and %.2f ms (slave drive), P2613 = %.0f ms\n",
        t_fault[0], t_fault[1], max_fault_ms);
    for (int d = 0; d < 2; ++d) {
        SCOPED_TRACE(d);
        EXPECT_GT(t_fault[d], max_fault_ms);
        EXPECT_LE(t_fault[d], max_fault_ms + kCycle / 1e6);  // P2613 plus one control cycle
        EXPECT_EQ(drive(d).twinsync_error(), error::Communication);
        EXPECT_EQ(e(d, obj::error_code.index).get<std::uint16_t>(), 0x7520);
        EXPECT_TRUE(par(d, p::CommStatus).get<std::uint16_t>() & comm_status::CommunicationLost);
        // The emergency carries the MSD error 40-00.
        master::CoeClient c(b.master, static_cast<std::uint16_t>(0x1001 + d));
        c.upload(0x1000, 0);
        bool seen = false;
        for (const auto& em : c.emergencies())
            seen |= em.error_code == 0x7520 && em.data[0] == 40 && em.data[1] == 0;
        EXPECT_TRUE(seen);
    }
    // The fault reaction brakes both axes; a fault reset does not clear the fault while the cable is
    // broken; once repaired it does.
    for (int i = 0; i < 200 && drive(0).cia402_state() != State::Fault; ++i)
        cycle(0x0F, pos(0));
    for (int i = 0; i < 3; ++i)
        cycle(i % 2 ? 0x80 : 0x00, pos(0));
    EXPECT_EQ(drive(0).cia402_state(), State::Fault);
    e(0, 0x2104, 1).set<std::uint8_t>(0);
    for (int i = 0; i < 20; ++i)
        cycle(i % 2 ? 0x80 : 0x00, pos(0));
    EXPECT_EQ(drive(0).cia402_state(), State::SwitchOnDisabled);
    EXPECT_EQ(drive(1).cia402_state(), State::SwitchOnDisabled);
    EXPECT_EQ(e(0, obj::error_code.index).get<std::uint16_t>(), 0);
}

TEST_F(TwinBench, GantrySlaveBrakesFromWhereItIsWhenItsPartnerFaultsInMotion) {
    // Found by `vecat demo`: the slave's demand comes from TWINsync, not from its profile generator; its
    // fault reaction (quick stop ramp) once started from the profile left at its enable, so the axis ran
    // back to where it had been enabled.
    enable_gantry();
    const std::int32_t enabled_at = pos(1);
    std::int32_t p = pos(0);
    for (int i = 0; i < 300; ++i)
        cycle(0x0F, p += 500);  // 0.5 rev/s for 300 ms: the slave follows, 150000 increments away
    ASSERT_GT(pos(1) - enabled_at, 100'000);
    const std::int32_t at_fault = pos(1);
    e(0, 0x2101).set<std::uint16_t>(0x8611);  // drive 1: following error fault, in motion
    std::int32_t lowest = at_fault;
    for (int i = 0; i < 300 && drive(1).cia402_state() != State::Fault; ++i) {
        cycle(0x0F, p);
        lowest = std::min(lowest, pos(1));
    }
    EXPECT_EQ(drive(1).cia402_state(), State::Fault);
    // Braking from 0.5 rev/s goes on forward; it never heads back towards the enable position.
    EXPECT_GE(lowest, at_fault - 1000) << "enabled at " << enabled_at;
    e(0, 0x2101).set<std::uint16_t>(0);
}

TEST_F(TwinBench, TwoMastersGive40_02) {
    // Drive 2 parametrised as master too, and enabled over EtherCAT by its own controlword.
    master::CoeClient c(b.master, 0x1002);
    ASSERT_EQ(c.download_value<std::uint16_t>(object_index(p::ControlSelector), 0, 0).abort,
              protocol::SdoAbort::None);
    ASSERT_EQ(c.download_value<std::uint16_t>(object_index(p::SetpointSelector), 0, 0).abort,
              protocol::SdoAbort::None);
    ASSERT_EQ(c.download_value<std::uint8_t>(object_index(p::Setting), 0, 29).abort,
              protocol::SdoAbort::None);
    ASSERT_EQ(c.download_value<std::uint16_t>(object_index(p::Mode), 0, 2).abort, protocol::SdoAbort::None);
    const std::int32_t p0 = pos(0), p1 = pos(1);
    for (int i = 0; i < 10; ++i)
        cycle(0, p0, 0, 8, p1);
    EXPECT_TRUE(par(0, p::CommStatus).get<std::uint16_t>() & comm_status::ModeConflict);
    EXPECT_TRUE(par(1, p::CommStatus).get<std::uint16_t>() & comm_status::ModeConflict);
    // Errors are reported in state Control only.
    EXPECT_EQ(drive(0).cia402_state(), State::SwitchOnDisabled);
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        for (int i = 0; i < 3; ++i)
            cycle(cw, p0, cw, 8, p1);
    for (int d = 0; d < 2; ++d) {
        EXPECT_EQ(drive(d).cia402_state(), State::Fault) << d;
        EXPECT_EQ(drive(d).twinsync_error(), error::ModeConflict) << d;
        EXPECT_EQ(par(d, p::CurrentError, 1).get<std::uint16_t>(), 40);
        EXPECT_EQ(par(d, p::CurrentError, 2).get<std::uint16_t>(), 2);
        EXPECT_EQ(sw(d) & cia::sw::Fault, cia::sw::Fault);
    }
}

TEST_F(TwinBench, DifferentSwitchingFrequenciesGive40_01) {
    master::CoeClient c(b.master, 0x1002);
    ASSERT_EQ(c.download_value<std::uint16_t>(object_index(p::SwitchingFrequency), 0, 3).abort,
              protocol::SdoAbort::None);
    for (int i = 0; i < 5; ++i)
        cycle(0, pos(0));
    EXPECT_EQ(par(0, p::Statusword).get<std::uint16_t>() & 0x0E, 3 << 1);  // the slave's 8 kHz
    EXPECT_TRUE(par(0, p::CommStatus).get<std::uint16_t>() & comm_status::SwitchingFrequency);
    // The error comes as soon as the drives enter Control (the slave first, then the master's check).
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        for (int i = 0; i < 5; ++i)
            cycle(cw, pos(0));
    EXPECT_EQ(drive(1).twinsync_error(), error::SwitchingFrequency);
    EXPECT_EQ(drive(1).cia402_state(), State::Fault);
    EXPECT_EQ(sw(1) & cia::sw::Fault, cia::sw::Fault);
}

TEST_F(TwinBench, SlaveLeavingControlGives40_04AfterTheMaxFaultTime) {
    // The slave drive is switched by its own EtherCAT controlword; both are enabled, then the slave is
    // switched off: the master, still in Control, reports 40-04 once P2613 has passed.
    par(1, p::ControlSelector).set<std::uint16_t>(0);
    drive(1).twinsync_port().reconfigure();
    const std::int32_t p0 = pos(0), p1 = pos(1);
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        for (int i = 0; i < 5; ++i)
            cycle(cw, p0, cw, 8, p1);
    ASSERT_EQ(drive(0).cia402_state(), State::OperationEnabled);
    ASSERT_EQ(drive(1).cia402_state(), State::OperationEnabled);
    double t = -1;
    for (int k = 1; k <= 80 && t < 0; ++k) {
        cycle(0x0F, p0, 0x07, 8, p1, kCycle);
        if (drive(0).twinsync_error()) t = k * kCycle / 1e6;
    }
    EXPECT_EQ(drive(0).twinsync_error(), error::DriveComState);
    EXPECT_GT(t, 10.0);
    EXPECT_LE(t, 10.75);
    EXPECT_TRUE(par(0, p::CommStatus).get<std::uint16_t>() & comm_status::DriveComState);
    EXPECT_FALSE(drive(1).twinsync_error()) << "the slave is not in Control: it reports nothing";
}

TEST_F(TwinBench, SyncLossFaultsTheSlaveAndTheGantryMasterSeesTheOtherAxis) {
    enable_gantry();
    e(1, 0x2104, 2).set<std::uint8_t>(1);  // sync loss: data still passes, SYNC_OUT does not
    for (int i = 0; i < 20; ++i)
        cycle(0x0F, pos(0));
    EXPECT_FALSE(drive(1).twinsync_status()->synchronised);
    EXPECT_EQ(drive(1).twinsync_error(), error::Communication);
    // The master drive still gets valid frames; it sees the slave's error bit: 39-02 in gantry mode.
    EXPECT_EQ(drive(0).twinsync_error(), error::OtherAxis);
    EXPECT_EQ(drive(0).cia402_state(), State::Fault);
}

TEST_F(TwinBench, SlaveWithTooLittleSyncGainLosesSynchronisation) {
    // 40 ppm apart (10 ns per cycle); one tick (15 ns) still follows, zero ticks cannot.
    par(1, p::SyncTicks).set<std::int16_t>(1);
    for (int i = 0; i < 100; ++i)
        cycle(0, pos(0));
    EXPECT_TRUE(drive(1).twinsync_status()->synchronised);
    par(1, p::SyncTicks).set<std::int16_t>(0);
    for (int i = 0; i < 100; ++i)
        cycle(0, pos(0));
    EXPECT_FALSE(drive(1).twinsync_status()->synchronised);
    EXPECT_GT(std::abs(drive(1).twinsync_status()->sync_offset_ns), 2000);
    EXPECT_TRUE(par(1, p::CommStatus).get<std::uint16_t>() & comm_status::CommunicationLost);
}

TEST_F(TwinBench, RefusedConfigurationsSayWhy) {
    master::CoeClient c(b.master, 0x1002);
    // A mode that needs hardware vecat does not emulate.
    EXPECT_EQ(c.download_value<std::uint8_t>(object_index(p::Setting), 0, 14).abort,
              protocol::SdoAbort::CannotTransfer);
    auto msg = c.upload(0x2102, 0);
    ASSERT_TRUE(msg.ok());
    const std::string text(msg.data.begin(), msg.data.end());
    EXPECT_NE(text.find("dSPACE"), std::string::npos) << text;
    EXPECT_EQ(par(1, p::Setting).get<std::uint8_t>(), 30);  // unchanged
    // 250 kBaud cannot carry the 16-byte frame in 250 us.
    EXPECT_EQ(c.download_value<std::uint16_t>(object_index(p::PhyLinkConfig), 1, 6).abort,
              protocol::SdoAbort::ParameterIncompatible);
    msg = c.upload(0x2102, 0);
    EXPECT_NE(std::string(msg.data.begin(), msg.data.end()).find("640.0 us"), std::string::npos);
    // 250 kBaud with the 6-byte frame fits, but the gantry mapping (8 bytes) does not fit the frame.
    EXPECT_EQ(c.download_value<std::uint16_t>(object_index(p::PhyLinkConfig), 2, 5).abort,
              protocol::SdoAbort::ParameterIncompatible);
    // Automatic mappings are not edited by hand.
    EXPECT_EQ(c.download_value<std::uint32_t>(object_index(p::ProcessSendData), 1, 0).abort,
              protocol::SdoAbort::CannotTransfer);
    // The mapping follows P2580: PCON_SLAVE.
    EXPECT_EQ(c.download_value<std::uint8_t>(object_index(p::Setting), 0, 8).abort, protocol::SdoAbort::None);
    EXPECT_EQ(par(1, p::ProcessReceiveData, 2).get<std::uint32_t>(), 0x0A300020u);
    EXPECT_EQ(par(1, p::ProcessReceiveData, 3).get<std::uint32_t>(), 0x0A2E0010u);
    // Out of range.
    EXPECT_EQ(c.download_value<std::uint8_t>(object_index(p::Setting), 0, 35).abort,
              protocol::SdoAbort::ValueTooHigh);
}

struct TwinSpeed : TwinBench {
    TwinSpeed() : TwinBench(&speed_line) {}
};

TEST_F(TwinSpeed, SconSlaveRunsAtTheMasterSpeed) {
    enable_gantry();
    // The master drive ramps to 1 rev/s in CSP; the slave's speed set-point is the master's actual speed
    // (16-bit, scaled by P2602/P2609 = 5000 rpm).
    std::int32_t p = pos(0);
    for (int i = 0; i < 500; ++i)
        cycle(0x0F, p += std::min(i, 100) * (1 << 20) / 100000);
    const double v0 = drive(0).velocity_actual(), v1 = drive(1).velocity_actual();
    std::printf("SCON: master %.0f, slave %.0f units/s\n", v0, v1);
    EXPECT_NEAR(v0, 1 << 20, 0.02 * (1 << 20));
    EXPECT_NEAR(v1, v0, 0.01 * v0);  // the 16-bit speed resolution is 5000/32768 rpm
    EXPECT_EQ(par(1, p::RemoteActSpeed).get<std::int16_t>(), par(0, p::LocalActSpeed).get<std::int16_t>());
}

TEST_F(TwinBench, ExtendedMappingCarriesWhatTheUserMapped) {
    // EXT_MAP: the master sends its position set-point P2600, its speed P2599 and its control word P2611
    // (pppp.SS.tt, type 0); the slave takes them into P2607, P2605 and P2611 and follows by P0300 = 3
    // (position). Without a control word in the telegram, P2611 must be mapped for control via TWINsync.
    for (int d = 0; d < 2; ++d) {
        par(d, p::Setting).set<std::uint8_t>(d == 0 ? 31 : 32);
        for (std::uint8_t s = 1; s <= 8; ++s) {
            par(d, p::ProcessSendData, s).set<std::uint32_t>(0);
            par(d, p::ProcessReceiveData, s).set<std::uint32_t>(0);
        }
    }
    par(0, p::ProcessSendData, 1).set<std::uint32_t>(0x0A280000);
    par(0, p::ProcessSendData, 2).set<std::uint32_t>(0x0A270000);
    par(1, p::ProcessReceiveData, 1).set<std::uint32_t>(0x0A2F0000);
    par(1, p::ProcessReceiveData, 2).set<std::uint32_t>(0x0A2D0000);
    par(0, p::ProcessSendData, 3).set<std::uint32_t>(0x0A330000);
    par(1, p::ProcessReceiveData, 3).set<std::uint32_t>(0x0A330000);
    drive(0).twinsync_port().reconfigure();
    drive(1).twinsync_port().reconfigure();
    ASSERT_TRUE(drive(0).twinsync_port().mode()->extended);
    enable_gantry();
    std::int32_t p = pos(0);
    for (int i = 0; i < 300; ++i)
        cycle(0x0F, p += 200);
    for (int i = 0; i < 100; ++i)
        cycle(0x0F, p);
    EXPECT_EQ(par(1, p::RemoteRefPos).get<std::int32_t>(), par(0, p::LocalRefPos).get<std::int32_t>());
    // Both follow the same set-point; stiction leaves each up to ~0.01 % of a revolution off for a while.
    EXPECT_EQ(e(1, obj::position_demand_value.index).get<std::int32_t>(), p);
    EXPECT_NEAR(pos(1), p, 150);
    EXPECT_NEAR(pos(0), p, 150);
    // No status word in the extended layout, so no 40-xx monitoring: P2619 stays 0.
    EXPECT_EQ(par(1, p::CommStatus).get<std::uint16_t>(), 0x0001);
    // A scope signal (type 1) is refused.
    master::CoeClient c(b.master, 0x1002);
    EXPECT_EQ(c.download_value<std::uint32_t>(object_index(p::ProcessReceiveData), 4, 0x03F30001u).abort,
              protocol::SdoAbort::NotMappable);
}

struct TwinPosition : TwinBench {
    TwinPosition() : TwinBench(&position_line) {}
};

TEST_F(TwinPosition, GearedSlaveCouplesAtStandstillAndGoesOnWhenDecoupledInMotion) {
    // PCON: slave = 2 x master + offset. The slave is switched on by its own EtherCAT controlword here
    // (P0159 = 0) and takes its set-points from TWINsync (P0165 = 11).
    par(1, p::ControlSelector).set<std::uint16_t>(0);
    par(1, p::GearNumerator).set<std::int32_t>(2);
    // The master drive switches on without waiting for its slave (P2651 bit 2).
    par(0, p::Config).set<std::uint32_t>(kConfigNoSlaveStateCheck);
    drive(1).twinsync_port().reconfigure();
    std::int32_t p = pos(0);
    const std::int32_t s0 = pos(1);
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        for (int i = 0; i < 5; ++i)
            cycle(cw, p, 0, 3, 0);
    ASSERT_EQ(drive(0).cia402_state(), State::OperationEnabled);
    // The master moves; the slave is enabled meanwhile but does not couple while the master moves.
    for (int i = 0; i < 100; ++i)
        cycle(0x0F, p += 400, i < 10 ? 0x06 : i < 20 ? 0x07 : 0x0F, 3, 0);
    ASSERT_EQ(drive(1).cia402_state(), State::OperationEnabled);
    EXPECT_NEAR(pos(1), s0, 50) << "coupling waits for standstill";
    for (int i = 0; i < 50; ++i)
        cycle(0x0F, p, 0x0F, 3, 0);
    const std::int32_t m_couple = pos(0), s_couple = pos(1);
    // Coupled: the slave moves twice the master's way.
    for (int i = 0; i < 200; ++i)
        cycle(0x0F, p += 300, 0x0F, 3, 0);
    for (int i = 0; i < 50; ++i)
        cycle(0x0F, p, 0x0F, 3, 0);
    EXPECT_NEAR(pos(1) - s_couple, 2.0 * (pos(0) - m_couple), 150);  // the loops settle to ~0.01 %
    EXPECT_NEAR(pos(0) - m_couple, 60000, 100);
    // Decoupled in motion (set-points back to EtherCAT): the slave goes on at its speed although the
    // master stops, until it is halted.
    for (int i = 0; i < 100; ++i)
        cycle(0x0F, p += 300, 0x0F, 3, 0);
    par(1, p::SetpointSelector).set<std::uint16_t>(0);
    const std::int32_t s_decouple = pos(1);
    for (int i = 0; i < 100; ++i)
        cycle(0x0F, p, 0x0F, 3, 0);
    EXPECT_NEAR(pos(1) - s_decouple, 100 * 600, 1500) << "goes on at 600 units per ms";
    EXPECT_EQ(drive(1).cia402_state(), State::OperationEnabled);
    for (int i = 0; i < 300; ++i)
        cycle(0x0F, p, 0x10F, 3, 0);  // halt
    const std::int32_t s_halted = pos(1);
    for (int i = 0; i < 50; ++i)
        cycle(0x0F, p, 0x10F, 3, 0);
    EXPECT_NEAR(pos(1), s_halted, 5) << "stopped";
}

}  // namespace
}  // namespace vecat::cia402
