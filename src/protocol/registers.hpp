// The ESC register map (ETG.1000.4 clause 6 and the ESC datasheets, section II), as one typed table.
// Each register carries its address, width, name and the bits the EtherCAT side may write.
// Repeated blocks (FMMUs, SyncManagers) are computed from their base.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "protocol/fmmu.hpp"
#include "protocol/sync_manager.hpp"

namespace vecat::protocol {

enum class Reg : std::uint16_t {
    Type = 0x0000,
    Revision = 0x0001,
    Build = 0x0002,
    FmmuCount = 0x0004,
    SmCount = 0x0005,
    RamSize = 0x0006,
    PortDescriptor = 0x0007,
    Features = 0x0008,
    StationAddress = 0x0010,
    StationAlias = 0x0012,
    WriteRegEnable = 0x0020,
    WriteRegProtection = 0x0021,
    EscWriteEnable = 0x0030,
    EscWriteProtection = 0x0031,
    EscResetEcat = 0x0040,
    EscResetPdi = 0x0041,
    DlControl = 0x0100,
    PhysicalRwOffset = 0x0108,
    DlStatus = 0x0110,
    AlControl = 0x0120,
    AlStatus = 0x0130,
    AlStatusCode = 0x0134,
    RunLedOverride = 0x0138,
    ErrLedOverride = 0x0139,
    PdiControl = 0x0140,
    EscConfiguration = 0x0141,
    PdiConfiguration = 0x0150,
    SyncLatchConfig = 0x0151,
    ExtendedPdiConfiguration = 0x0152,
    EcatEventMask = 0x0200,
    AlEventMask = 0x0204,
    EcatEventRequest = 0x0210,
    AlEventRequest = 0x0220,
    RxErrorCounter = 0x0300,     // 4 ports x {invalid frame, RX error}
    FwdRxErrorCounter = 0x0308,  // 4 ports
    EcatProcessingUnitErrorCounter = 0x030C,
    PdiErrorCounter = 0x030D,
    PdiErrorCode = 0x030E,
    LostLinkCounter = 0x0310,  // 4 ports
    WatchdogDivider = 0x0400,
    WatchdogTimePdi = 0x0410,
    WatchdogTimeProcessData = 0x0420,
    WatchdogStatusProcessData = 0x0440,
    WatchdogCounterProcessData = 0x0442,
    WatchdogCounterPdi = 0x0443,
    SiiConfig = 0x0500,
    SiiPdiAccess = 0x0501,
    SiiControl = 0x0502,
    SiiAddress = 0x0504,
    SiiData = 0x0508,
    MiiControl = 0x0510,
    Fmmu0 = 0x0600,
    Sm0 = 0x0800,
    DcRecvTimePort0 = 0x0900,
    DcRecvTimePort1 = 0x0904,
    DcRecvTimePort2 = 0x0908,
    DcRecvTimePort3 = 0x090C,
    DcSystemTime = 0x0910,
    DcRecvTimeEcatPu = 0x0918,
    DcSystemTimeOffset = 0x0920,
    DcSystemTimeDelay = 0x0928,
    DcSystemTimeDifference = 0x092C,
    DcSpeedCounterStart = 0x0930,
    DcSpeedCounterDiff = 0x0932,
    DcSystemTimeDiffFilterDepth = 0x0934,
    DcSpeedCounterFilterDepth = 0x0935,
    DcCyclicUnitControl = 0x0980,
    DcActivation = 0x0981,
    DcPulseLength = 0x0982,
    DcActivationStatus = 0x0984,
    DcSync0Status = 0x098E,
    DcSync1Status = 0x098F,
    DcStartTimeCyclic = 0x0990,
    DcNextSync1Pulse = 0x0998,
    DcSync0CycleTime = 0x09A0,
    DcSync1CycleTime = 0x09A4,
    DcLatch0Control = 0x09A8,
    DcLatch1Control = 0x09A9,
    DcLatch0Status = 0x09AE,
    DcLatch1Status = 0x09AF,
    DcLatch0PositiveEdge = 0x09B0,
    DcLatch0NegativeEdge = 0x09B8,
    DcLatch1PositiveEdge = 0x09C0,
    DcLatch1NegativeEdge = 0x09C8,
    DigitalOutputData = 0x0F00,  // 4 bytes, ESCs with a digital I/O PDI
    UserRam = 0x0F80,
    ProcessRam = 0x1000,
};

constexpr std::uint16_t addr(Reg r) noexcept {
    return static_cast<std::uint16_t>(r);
}

inline constexpr std::uint16_t kRegisterSpaceSize = 0x1000;

// The repeated blocks: FMMU i at 0x0600 + 16 i (protocol/fmmu.hpp), SyncManager i at 0x0800 + 8 i
// (protocol/sync_manager.hpp).
constexpr std::uint16_t fmmu_addr(unsigned i) noexcept {
    return static_cast<std::uint16_t>(addr(Reg::Fmmu0) + kFmmuSize * i);
}
constexpr std::uint16_t sm_addr(unsigned i) noexcept {
    return static_cast<std::uint16_t>(addr(Reg::Sm0) + kSmSize * i);
}

// DL status bits (0x0110).
// The ports after port 0 in the order a frame passes them (ESC datasheet section I, frame processing order
// 0 -> 3 -> 1 -> 2): devices on port 3 (a coupler's E-bus) come before those on port 1, then port 2.
inline constexpr std::array<unsigned, 3> kPortsAfterPort0 = {3, 1, 2};

namespace dl_status {
inline constexpr std::uint16_t PdiOperational = 0x0001;
inline constexpr std::uint16_t PdiWatchdogOk = 0x0002;
inline constexpr std::uint16_t EnhancedLinkDetection = 0x0004;
constexpr std::uint16_t link(unsigned port) {
    return static_cast<std::uint16_t>(0x0010u << port);
}
constexpr std::uint16_t loop_closed(unsigned port) {
    return static_cast<std::uint16_t>(0x0100u << (2 * port));
}
constexpr std::uint16_t communication(unsigned port) {
    return static_cast<std::uint16_t>(0x0200u << (2 * port));
}
}  // namespace dl_status

inline constexpr std::uint16_t kDigitalOutputSize = 4;

// PDI types (0x0140, loaded from the low byte of SII word 0; ESC datasheet section II 0x0140) that drive
// the digital I/O: 0x01 4 digital inputs, 0x02 4 digital outputs, 0x03 2 in/2 out, 0x04 digital I/O. The
// ESC then has the digital output register 0x0F00-0x0F03.
constexpr bool pdi_is_digital_io(std::uint8_t pdi_control) noexcept {
    return pdi_control >= 0x01 && pdi_control <= 0x04;
}

// ESC configuration bits (0x0141, loaded from the high byte of SII word 0).
namespace esc_config {
// The ESC itself copies AL control to AL status (simple devices without a µController); off, AL control
// behaves as a mailbox towards the PDI (ESC datasheet section II 0x0120).
inline constexpr std::uint8_t DeviceEmulation = 0x01;
// Enhanced link detection: bit 1 for all ports, bits 4-7 for port 0-3 (DL status 0x0110 bit 2 shows it).
inline constexpr std::uint8_t EnhancedLinkDetection = 0xF2;
}  // namespace esc_config

// SII control/status bits (0x0502).
namespace sii_ctrl {
inline constexpr std::uint16_t WriteEnable = 0x0001;
// Bit 4 is reserved in the datasheet. The ESCs of the EL1004, EL2828 and EL3004 read it as 1 from power-up
// until their PDI first had the EEPROM interface (esc::Esc::pdi_use_eeprom); an EK1100 or EL2889 reads 0.
inline constexpr std::uint16_t ReservedUntilPdiAccess = 0x0010;
inline constexpr std::uint16_t Emulation = 0x0020;
inline constexpr std::uint16_t Read8Bytes = 0x0040;
inline constexpr std::uint16_t TwoAddressBytes = 0x0080;
inline constexpr std::uint16_t CmdMask = 0x0700;
inline constexpr std::uint16_t CmdRead = 0x0100;
inline constexpr std::uint16_t CmdWrite = 0x0200;
inline constexpr std::uint16_t CmdReload = 0x0400;
inline constexpr std::uint16_t ChecksumError = 0x0800;
inline constexpr std::uint16_t NotLoaded = 0x1000;
inline constexpr std::uint16_t ErrorAck = 0x2000;  // missing acknowledge or invalid command
inline constexpr std::uint16_t ErrorWriteEnable = 0x4000;
inline constexpr std::uint16_t Busy = 0x8000;
}  // namespace sii_ctrl

// AL event request bits (0x0220), the ESC's interrupt lines towards the slave application.
namespace al_event {
inline constexpr std::uint32_t AlControl = 0x0001;
inline constexpr std::uint32_t DcLatch = 0x0002;
inline constexpr std::uint32_t Sync0 = 0x0004;
inline constexpr std::uint32_t Sync1 = 0x0008;
inline constexpr std::uint32_t SmActivation = 0x0010;
inline constexpr std::uint32_t EepromEmulation = 0x0020;
inline constexpr std::uint32_t WatchdogProcessData = 0x0040;
constexpr std::uint32_t sm(unsigned i) {
    return 0x0100u << i;
}
}  // namespace al_event

// Feature bits (0x0008).
namespace feature {
inline constexpr std::uint16_t FmmuBytewise = 0x0001;
inline constexpr std::uint16_t DcAvailable = 0x0004;
inline constexpr std::uint16_t Dc64Bit = 0x0008;
inline constexpr std::uint16_t EnhancedLinkMii = 0x0040;
inline constexpr std::uint16_t SeparateFcsErrors = 0x0080;
inline constexpr std::uint16_t EnhancedDcSyncActivation = 0x0100;
}  // namespace feature

// One row of the register table: what the EtherCAT side may write.
struct RegisterInfo {
    std::uint16_t address;
    std::uint8_t width;  // bytes
    std::string_view name;
    std::array<std::uint8_t, 8> ecat_write_mask;  // per byte, up to 8 bytes
};

// Registers the EtherCAT master can write, with their per-byte write masks. Every register not listed is
// read-only from the EtherCAT side or reserved (ESC datasheet section II 1: "not writable"): a write to it
// has no effect and, when no byte of the datagram is writable, is not counted (section I 2.4: only a
// successful access counts). Bits not set in a mask of a listed register keep their value.
inline constexpr RegisterInfo kWritableRegisters[] = {
    {0x0010, 2, "Configured Station Address", {0xFF, 0xFF}},
    {0x0020, 1, "Write Register Enable", {0x01}},
    {0x0021, 1, "Write Register Protection", {0x01}},
    {0x0030, 1, "ESC Write Enable", {0x01}},
    {0x0031, 1, "ESC Write Protection", {0x01}},
    {0x0040, 1, "ESC Reset ECAT", {0xFF}},
    {0x0100, 4, "ESC DL Control", {0x03, 0xFF, 0x07, 0x01}},
    {0x0108, 2, "Physical Read/Write Offset", {0xFF, 0xFF}},
    {0x0120, 2, "AL Control", {0x3F, 0x00}},
    {0x0138, 1, "RUN LED Override", {0x1F}},
    {0x0139, 1, "ERR LED Override", {0x1F}},
    {0x0200, 2, "ECAT Event Mask", {0xFF, 0xFF}},
    {0x0400, 2, "Watchdog Divider", {0xFF, 0xFF}},
    {0x0410, 2, "Watchdog Time PDI", {0xFF, 0xFF}},
    {0x0420, 2, "Watchdog Time Process Data", {0xFF, 0xFF}},
    {0x0500, 1, "SII EEPROM Configuration", {0x03}},
    {0x0502, 2, "SII EEPROM Control/Status", {0x01, 0x00}},  // command bits handled as a side effect
    {0x0504, 4, "SII EEPROM Address", {0xFF, 0xFF, 0xFF, 0xFF}},
    {0x0508, 8, "SII EEPROM Data", {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}},
    {0x0510, 2, "MII Management Control/Status", {0x01, 0x03}},  // no PHY behind: stored only
    {0x0512, 1, "PHY Address", {0x1F}},
    {0x0513, 1, "PHY Register Address", {0x1F}},
    {0x0514, 2, "PHY Data", {0xFF, 0xFF}},
    {0x0516, 1, "MII Management ECAT Access State", {0x01}},
    {0x0920, 8, "System Time Offset", {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}},
    {0x0928, 4, "System Time Delay", {0xFF, 0xFF, 0xFF, 0xFF}},
    {0x0930, 2, "Speed Counter Start", {0xFF, 0x7F}},
    {0x0934, 1, "System Time Difference Filter Depth", {0x0F}},
    {0x0935, 1, "Speed Counter Filter Depth", {0x0F}},
    {0x0980, 1, "Cyclic Unit Control", {0x31}},
    {0x0981, 1, "Activation Register", {0xFF}},
    {0x0990, 8, "Start Time Cyclic Operation", {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}},
    {0x09A0, 4, "SYNC0 Cycle Time", {0xFF, 0xFF, 0xFF, 0xFF}},
    {0x09A4, 4, "SYNC1 Cycle Time", {0xFF, 0xFF, 0xFF, 0xFF}},
    {0x09A8, 1, "Latch0 Control", {0x03}},
    {0x09A9, 1, "Latch1 Control", {0x03}},
};

// Register areas the master may write whose written value is not stored as such: the write acts (the
// ESC code does it), and it counts like any write. Areas stored byte for byte are listed with mask 0xFF.
struct WritableArea {
    std::uint16_t address;
    std::uint16_t length;  // bytes
    std::string_view name;
    std::uint8_t ecat_write_mask;  // for every byte
};

inline constexpr WritableArea kWritableAreas[] = {
    {0x0300, 14, "RX/forwarded RX/processing unit/PDI error counters: a write clears", 0x00},
    {0x0310, 4, "Lost link counters: a write clears", 0x00},
    {0x0442, 2, "Watchdog counters process data/PDI: a write clears", 0x00},
    {0x0503, 1, "SII EEPROM command", 0x00},
    {0x0900, 4, "Receive time port 0: a write latches the receive times", 0x00},
    {0x0910, 8, "System time: a write feeds the time control loop", 0x00},
    {addr(Reg::UserRam), 128, "User RAM", 0xFF},
};

// Per-byte ECAT write masks for the whole register space, and which bytes the master may write at all,
// computed once from the tables above plus the FMMU and SyncManager blocks the ESC has.
struct WriteMaskTable {
    std::array<std::uint8_t, kRegisterSpaceSize> mask{};
    std::array<std::uint8_t, kRegisterSpaceSize / 8> writable_bits{};  // one bit per address

    constexpr bool writable(std::uint16_t a) const {
        return a < kRegisterSpaceSize && ((writable_bits[a / 8] >> (a % 8)) & 1u) != 0;
    }
    constexpr void set(unsigned a, std::uint8_t m, bool is_writable = true) {
        mask[a] = is_writable ? m : 0;
        const auto bit = static_cast<std::uint8_t>(1u << (a % 8));
        writable_bits[a / 8] =
            static_cast<std::uint8_t>(is_writable ? writable_bits[a / 8] | bit : writable_bits[a / 8] & ~bit);
    }
};

constexpr WriteMaskTable make_write_mask_table(unsigned fmmu_count, unsigned sm_count) {
    WriteMaskTable t{};
    for (const auto& r : kWritableRegisters)
        for (unsigned i = 0; i < r.width; ++i)
            t.set(r.address + i, r.ecat_write_mask[i]);
    for (const auto& r : kWritableAreas)
        for (unsigned i = 0; i < r.length; ++i)
            t.set(r.address + i, r.ecat_write_mask);
    for (unsigned f = 0; f < fmmu_count && f < kMaxFmmus; ++f) {
        const unsigned b = fmmu_addr(f);
        for (unsigned i = 0; i < fmmu::LogicalStartBit; ++i)  // logical start and length
            t.set(b + i, 0xFF);
        t.set(b + fmmu::LogicalStartBit, 0x07);
        t.set(b + fmmu::LogicalStopBit, 0x07);
        t.set(b + fmmu::PhysicalStart, 0xFF);
        t.set(b + fmmu::PhysicalStart + 1, 0xFF);
        t.set(b + fmmu::PhysicalStartBit, 0x07);
        t.set(b + fmmu::Type, 0x03);
        t.set(b + fmmu::Activate, 0x01);
    }
    for (unsigned s = 0; s < sm_count && s < kMaxSms; ++s) {
        const unsigned b = sm_addr(s);
        for (unsigned i = 0; i < sm::Control; ++i)  // physical start and length
            t.set(b + i, 0xFF);
        t.set(b + sm::Control, 0x7F);
        t.set(b + sm::Activate, 0xC3);
    }
    return t;
}

}  // namespace vecat::protocol
