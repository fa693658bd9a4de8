// ESC variants that real lines show and vecat's own drive does not have: device emulation (the ESC sets AL
// status itself), no PDI, an ESC without the DC system time unit, further read-only bits of 0x0502. Each
// was found by replaying ../shared/data/pcap (docs/replay.md) and follows the ESC datasheet section II.
#include <gtest/gtest.h>

#include "device/simple_devices.hpp"
#include "esc/esc.hpp"
#include "esc/sii_image.hpp"
#include "esc/slave.hpp"
#include "test_support.hpp"

using namespace vecat;
using namespace vecat::esc;
using namespace vecat::protocol;

namespace {

std::uint16_t write(Esc& esc, std::uint16_t ado, std::vector<std::uint8_t> data,
                    Command cmd = Command::APWR) {
    return test::esc_datagram(esc, cmd, ado, data);
}
std::uint16_t read(Esc& esc, std::uint16_t ado, std::vector<std::uint8_t>& data,
                   Command cmd = Command::APRD) {
    return test::esc_datagram(esc, cmd, ado, data);
}

}  // namespace

// Section II 0x0130: with device emulation the ESC sets AL status to the value written to AL control, at
// once and without any check; an acknowledge shows as the error indication (an EK1100 reads 0x11 after a
// master wrote INIT + acknowledge). The slave follows the state and never writes AL status.
TEST(DeviceEmulation, AlStatusIsTheValueWrittenToAlControl) {
    Slave slave(device::coupler(), EscConfig{}, std::make_unique<ProcessImageApplication>(0, 0));
    Esc& esc = slave.esc();
    ASSERT_TRUE(esc.device_emulation());
    EXPECT_EQ(esc.al_status(), 0x01);  // INIT at power-up
    EXPECT_EQ(write(esc, addr(Reg::AlControl), {0x11, 0x00}), 1);
    EXPECT_EQ(esc.peek16(addr(Reg::AlStatus)), 0x0011);  // before any firmware ran
    slave.run(1'000'000);
    EXPECT_EQ(esc.peek16(addr(Reg::AlStatus)), 0x0011);
    EXPECT_EQ(esc.al_status_code(), 0);
    // OP straight from INIT: no check refuses it.
    EXPECT_EQ(write(esc, addr(Reg::AlControl), {0x08, 0x00}), 1);
    slave.run(2'000'000);
    EXPECT_EQ(esc.peek16(addr(Reg::AlStatus)), 0x0008);
    EXPECT_EQ(slave.state(), AlState::Op);
    EXPECT_EQ(esc.al_status_code(), 0);
}

// Without device emulation the firmware answers, with its checks: INIT -> OP is refused.
TEST(DeviceEmulation, WithoutItTheFirmwareChecksTheRequest) {
    auto dev = device::coupler();
    dev.pdi_control = 0x0005;
    Slave slave(dev, EscConfig{}, std::make_unique<ProcessImageApplication>(0, 0));
    Esc& esc = slave.esc();
    ASSERT_FALSE(esc.device_emulation());
    EXPECT_EQ(write(esc, addr(Reg::AlControl), {0x08, 0x00}), 1);
    slave.run(1'000'000);
    EXPECT_EQ(esc.al_status(), 0x11);
    EXPECT_EQ(esc.al_status_code(), static_cast<std::uint16_t>(AlStatusCode::InvalidRequestedStateChange));
}

// Section II 0x0110 bit 1: without a PDI nothing reloads the PDI watchdog (an EK1100 reads 0x..31); with
// one it shows reloaded.
TEST(NoPdi, DlStatusShowsThePdiWatchdogExpired) {
    Esc coupler{EscConfig{}, build_sii_image(device::coupler())};
    EXPECT_EQ(coupler.peek16(addr(Reg::DlStatus)) & dl_status::PdiWatchdogOk, 0);
    EXPECT_NE(coupler.peek16(addr(Reg::DlStatus)) & dl_status::PdiOperational, 0);
    Esc drive{EscConfig{}, build_sii_image(device::default_drive())};
    EXPECT_NE(drive.peek16(addr(Reg::DlStatus)) & dl_status::PdiWatchdogOk, 0);
}

// An ESC that reports DC (0x0008) but has the receive times only: reads and writes of 0x0910-0x09FF are
// not counted and leave the frame's data as it was (EL2828/EL1004/EK1914/EL3004 of ../shared/data/pcap).
TEST(NoDcSystemTimeUnit, CountsNoAccessPastTheReceiveTimes) {
    EscConfig cfg;
    cfg.dc_system_time_unit = false;
    Esc esc{cfg, build_sii_image(device::coupler())};
    Esc full{EscConfig{}, build_sii_image(device::coupler())};
    std::vector<std::uint8_t> d(8, 0xAA);
    EXPECT_EQ(read(esc, addr(Reg::DcRecvTimeEcatPu), d), 0);
    EXPECT_EQ(d, std::vector<std::uint8_t>(8, 0xAA));
    EXPECT_EQ(read(full, addr(Reg::DcRecvTimeEcatPu), d), 1);
    EXPECT_EQ(write(esc, addr(Reg::DcSystemTimeOffset), std::vector<std::uint8_t>(8, 1)), 0);
    EXPECT_EQ(write(esc, addr(Reg::DcSystemTime), std::vector<std::uint8_t>(4, 1), Command::BWR), 0);
    EXPECT_EQ(write(esc, addr(Reg::DcActivation), {0x03}), 0);
    EXPECT_EQ(write(full, addr(Reg::DcActivation), {0x03}), 1);
    // The receive times are there: a write of port 0's latches them, reads count.
    EXPECT_EQ(write(esc, addr(Reg::DcRecvTimePort0), {0, 0, 0, 0}), 1);
    std::vector<std::uint8_t> rt(16, 0);
    EXPECT_EQ(read(esc, addr(Reg::DcRecvTimePort0), rt), 1);
    // A read that covers both counts for the receive times; the bytes past them keep the frame's data.
    std::vector<std::uint8_t> both(24, 0xAA);
    EXPECT_EQ(read(esc, addr(Reg::DcRecvTimePort0), both), 1);
    EXPECT_EQ(std::vector<std::uint8_t>(both.begin() + 16, both.end()), std::vector<std::uint8_t>(8, 0xAA));
}

// Section II 0x0502: bits 1-5 are read-only (bit 5 EEPROM emulation, 1-4 reserved); an ESC shows what it
// has there (an EL2828 reads 0x50), and a write of the register does not change them.
TEST(SiiStatusBits, ShownAndKeptAcrossCommands) {
    EscConfig cfg;
    cfg.sii_status_bits = 0x10;
    Esc esc{cfg, build_sii_image(device::coupler())};
    EXPECT_EQ(esc.peek(addr(Reg::SiiControl)), 0x50);
    EXPECT_EQ(write(esc, addr(Reg::SiiAddress), {0, 0, 0, 0}), 1);
    EXPECT_EQ(write(esc, addr(Reg::SiiControl), {0x00, 0x01}), 1);  // read word 0
    EXPECT_EQ(esc.peek(addr(Reg::SiiControl)) & 0x3E, 0x10);
}

// Bit 4 of 0x0502 (reserved in section II) reads 1 on some ESCs until their PDI had the EEPROM interface:
// only while the master offers it (0x0500 bit 0, section I 11.2) may the PDI take it; an ECAT command keeps
// the bit (above).
TEST(SiiStatusBits, Bit4ClearedOnlyWhenThePdiUsesTheOfferedEeprom) {
    EscConfig cfg;
    cfg.sii_status_bits = 0x10;
    Esc esc{cfg, build_sii_image(device::coupler())};
    EXPECT_FALSE(esc.pdi_use_eeprom());
    EXPECT_EQ(esc.peek(addr(Reg::SiiControl)), 0x50);
    EXPECT_EQ(write(esc, addr(Reg::SiiConfig), {0x01}), 1);
    EXPECT_TRUE(esc.pdi_use_eeprom());
    EXPECT_EQ(esc.peek(addr(Reg::SiiControl)), 0x40);
}

// A firmware with a mailbox reads the mailbox SyncManagers of its SII at INIT -> PREOP, if the master offered
// it the EEPROM: the EL3004 of ../shared/data/pcap reads 0x50 before, 0x40 after (0x0500 = 1 around the
// request), and keeps 0x50 when the master did not offer it.
TEST(SiiStatusBits, TheFirmwareReadsItsSiiAtInitToPreOp) {
    auto dev = device::default_drive();
    dev.rx_pdos.clear();
    dev.tx_pdos.clear();
    EscConfig cfg;
    cfg.sii_status_bits = 0x10;
    for (const bool offered : {false, true}) {
        Slave slave(dev, cfg, std::make_unique<ProcessImageApplication>(0, 0));
        Esc& esc = slave.esc();
        ASSERT_FALSE(esc.device_emulation());
        if (offered) {
            EXPECT_EQ(write(esc, addr(Reg::SiiConfig), {0x01}), 1);
        }
        EXPECT_EQ(write(esc, addr(Reg::AlControl), {0x02, 0x00}), 1);
        slave.run(1'000'000);
        EXPECT_EQ(esc.peek(addr(Reg::SiiControl)) & sii_ctrl::ReservedUntilPdiAccess, offered ? 0 : 0x10)
            << "offered " << offered;
    }
}

// With device emulation the bit goes at PREOP -> SAFEOP with the EEPROM offered to the PDI, not at INIT ->
// PREOP (the EL1004 of ../shared/data/pcap: 0x50 in PREOP, 0x40 after SAFEOP; its SII word 0 is 0x0104).
TEST(SiiStatusBits, DeviceEmulationClearsBit4AtSafeOp) {
    EscConfig cfg;
    cfg.sii_status_bits = 0x10;
    Slave slave(device::coupler(), cfg, std::make_unique<ProcessImageApplication>(0, 0));
    Esc& esc = slave.esc();
    ASSERT_TRUE(esc.device_emulation());
    EXPECT_EQ(write(esc, addr(Reg::SiiConfig), {0x01}), 1);
    EXPECT_EQ(write(esc, addr(Reg::AlControl), {0x02, 0x00}), 1);
    slave.run(1'000'000);
    EXPECT_EQ(esc.peek(addr(Reg::SiiControl)), 0x50);
    EXPECT_EQ(write(esc, addr(Reg::AlControl), {0x04, 0x00}), 1);
    slave.run(2'000'000);
    EXPECT_EQ(esc.al_status(), 0x04);
    EXPECT_EQ(esc.peek(addr(Reg::SiiControl)), 0x40);
}

// Section II 0x0120 without device emulation: AL control is a mailbox the firmware empties by reading it.
// A firmware that takes its time (Slave::set_al_control_latency, recovered by the replay from real devices
// that refused a second write 0.56 ms after the first) refuses a second write until it has read the first.
TEST(AlControlLatency, ASecondWriteIsRefusedUntilTheFirmwareReadTheFirst) {
    auto dev = device::coupler();
    dev.pdi_control = 0x0005;  // a µController on SPI: no device emulation
    Slave slave(dev, EscConfig{}, std::make_unique<ProcessImageApplication>(0, 0));
    slave.set_al_control_latency(1'000'000);
    Esc& esc = slave.esc();
    EXPECT_EQ(write(esc, addr(Reg::AlControl), {0x11, 0x00}), 1);  // at 1000 ns (the helper's frame time)
    slave.run(500'000);
    EXPECT_EQ(write(esc, addr(Reg::AlControl), {0x11, 0x00}), 0);  // not read yet
    slave.run(1'001'000);
    EXPECT_EQ(write(esc, addr(Reg::AlControl), {0x02, 0x00}), 1);  // PREOP, again at 1000 ns
    slave.run(500'000);
    EXPECT_EQ(esc.al_status(), 0x01);  // not read yet
    slave.run(1'002'000);
    EXPECT_EQ(esc.al_status(), 0x02);  // read and answered
}

// Under device emulation nothing but the master's writes changes AL status: an error the application
// raises (fault injection) does not show.
TEST(DeviceEmulation, TheFirmwareNeverWritesAlStatus) {
    Slave slave(device::coupler(), EscConfig{}, std::make_unique<ProcessImageApplication>(0, 0));
    Esc& esc = slave.esc();
    EXPECT_EQ(write(esc, addr(Reg::AlControl), {0x02, 0x00}), 1);
    slave.run(1'000'000);
    slave.raise_error(AlStatusCode::SyncManagerWatchdog, AlState::Init);
    EXPECT_EQ(esc.peek16(addr(Reg::AlStatus)), 0x0002);
    EXPECT_EQ(esc.al_status_code(), 0);
    EXPECT_EQ(slave.state(), AlState::PreOp);
}

// Section II 0x0006: the process RAM size in KiB. An ET1200 (the EL terminals of ../shared/data/pcap) has
// 1 KiB, 0x1000-0x13FF, and reports 1. The DL control register starts at its configured value (a line
// rebuilt from a capture takes what the ESC showed), 0x00070001 by default.
TEST(EscRam, AnEscReportsItsRamAndDlControlAsConfigured) {
    EscConfig cfg;
    cfg.ram_bytes = 1024;
    cfg.dl_control = 0x00C70001;
    Esc esc(cfg, {});
    std::vector<std::uint8_t> b(1);
    EXPECT_EQ(read(esc, 0x0006, b), 1);
    EXPECT_EQ(b[0], 1);
    EXPECT_EQ(esc.config().ram_bytes, 1024u);
    EXPECT_EQ(write(esc, 0x13FF, {0x55}), 1);
    EXPECT_EQ(read(esc, 0x13FF, b), 1);
    EXPECT_EQ(b[0], 0x55);
    EXPECT_EQ(esc.peek(0x0102), 0xC7);
    Esc standard(EscConfig{}, {});
    EXPECT_EQ(standard.peek(0x0006), 8);
    EXPECT_EQ(standard.peek(0x0102), 0x07);
}
