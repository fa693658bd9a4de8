// FoE (ETG.1000.6 5.8) and the BOOT state (about 600 lines: one protocol, each error code its own test):
// the FoE server's state machine (read, write, packet numbers, busy, every FoE error code the device
// produces), the INIT <-> BOOT transitions with their AL status codes, and the firmware update that changes
// the revision in the SII and in 0x1018:03. Driven by the project's master over an in-process link, on the
// wire layout of protocol/foe.hpp.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "device/device_description.hpp"
#include "esc/sii_image.hpp"
#include "foe/foe_server.hpp"
#include "master/coe_client.hpp"
#include "master/foe_client.hpp"
#include "protocol/foe.hpp"
#include "protocol/objects.hpp"
#include "protocol/sync_manager.hpp"
#include "test_support.hpp"

using namespace vecat;
using namespace vecat::test;
using protocol::AlState;
using protocol::AlStatusCode;
using protocol::FoeError;
using protocol::FoeOpCode;
using protocol::MailboxType;

namespace {

constexpr std::uint32_t kNewRevision = 0x00020000;

std::vector<std::uint8_t> bytes_of(std::string_view s) {
    return {s.begin(), s.end()};
}

std::vector<std::uint8_t> firmware(std::uint32_t revision, std::optional<std::uint32_t> product = {},
                                   std::size_t image = 1500) {
    auto f = bytes_of(foe::firmware_header_line(revision, product));
    for (std::size_t i = 0; i < image; ++i)
        f.push_back(static_cast<std::uint8_t>(i * 7));
    return f;
}

std::vector<std::uint8_t> pattern(std::size_t n) {
    std::vector<std::uint8_t> v(n);
    for (std::size_t i = 0; i < n; ++i)
        v[i] = static_cast<std::uint8_t>(i ^ (i >> 8));
    return v;
}

// A drive whose bootstrap mailbox is larger than its standard one (as many real devices): 512 bytes each way.
device::DeviceDescription big_boot_mailbox() {
    auto d = device::default_drive();
    d.boot_mailbox = {0x1800, 0x0200, 0x1A00, 0x0200};
    return d;
}

// One drive with an FoE server behind the project's master.
struct FoeBench {
    explicit FoeBench(foe::FoeOptions opt = {}, device::DeviceDescription dev = device::default_drive(),
                      SegmentFactory make = &coe::make_coe_segment)
        : b(1, {}, std::move(dev), make) {
        attached = foe::attach_foe(*b.seg, opt);
    }
    std::uint16_t station() { return b.master.slaves()[0].station; }
    foe::FoeServer& server() { return *foe::foe_server(b.slave()); }
    void startup(AlState s) {
        std::string why;
        ASSERT_TRUE(b.master.startup(s, &why)) << why;
    }
    // INIT, SM0/SM1 as the SII's bootstrap mailbox, then BOOT: what SOEM's firm_update does.
    void to_boot() {
        startup(AlState::PreOp);
        ASSERT_TRUE(b.master.request_state(station(), AlState::Init));
        ASSERT_TRUE(master::configure_boot_mailbox(b.master, b.master.slaves()[0]));
        ASSERT_TRUE(b.master.request_state(station(), AlState::Boot));
    }
    master::AlStatusReading request(AlState s) {
        EXPECT_TRUE(
            b.master.write16(station(), reg(protocol::Reg::AlControl), static_cast<std::uint16_t>(s)));
        return b.master.read_al_status(station());
    }
    master::FoeClient client() { return master::FoeClient(b.master, station()); }
    // One raw FoE message and the answer.
    std::optional<master::MailboxMessage> raw(ConstBytes payload) {
        master::CoeClient c(b.master, station());
        return c.request(MailboxType::FoE, payload);
    }
    std::optional<master::MailboxMessage> raw_op(FoeOpCode op, std::uint32_t value,
                                                 std::string_view tail = {}) {
        std::vector<std::uint8_t> p(protocol::kFoeHeaderSize + tail.size());
        const auto n = protocol::write_foe(
            p, op, value, ConstBytes(reinterpret_cast<const std::uint8_t*>(tail.data()), tail.size()));
        return raw(ConstBytes(p.data(), n));
    }
    std::uint32_t sii_revision() { return *b.master.read_sii_dword(station(), protocol::sii::RevisionNo); }

    Bench b;
    std::size_t attached = 0;
};

// The FoE error of an answer (nullopt when it is none).
std::optional<FoeError> foe_error(const std::optional<master::MailboxMessage>& m) {
    if (!m || m->header.type != static_cast<std::uint8_t>(MailboxType::FoE)) return std::nullopt;
    const auto f = protocol::parse_foe(m->payload);
    if (!f || f->op != FoeOpCode::Error) return std::nullopt;
    return static_cast<FoeError>(f->value);
}

}  // namespace

// ---- The device declares FoE and bootstrap: one description feeds SII and ESI.

TEST(FoeDevice, DriveDeclaresFoeAndTheBootstrapMailboxInTheSii) {
    const auto d = device::default_drive();
    const auto sii = protocol::parse_sii(esc::build_sii_image(d));
    EXPECT_TRUE(sii.mailbox_protocols & device::mbx_proto::FoE);
    EXPECT_TRUE(sii.mailbox_protocols & device::mbx_proto::CoE);
    EXPECT_EQ(sii.foe_details, device::foe_details::Enable);
    // The drive's bootstrap mailbox is its standard mailbox.
    EXPECT_EQ(sii.boot_rx_mbx_offset, 0x1800);
    EXPECT_EQ(sii.boot_rx_mbx_size, 0x00F6);
    EXPECT_EQ(sii.boot_tx_mbx_offset, 0x18F6);
    EXPECT_EQ(sii.boot_tx_mbx_size, 0x00F6);
    // A bootstrap mailbox of its own goes to words 0x0014-0x0017.
    const auto big = protocol::parse_sii(esc::build_sii_image(big_boot_mailbox()));
    EXPECT_EQ(big.boot_rx_mbx_size, 0x0200);
    EXPECT_EQ(big.boot_tx_mbx_offset, 0x1A00);
    EXPECT_EQ(big.std_rx_mbx_size, 0x00F6);
    // A device without bootstrap has no bootstrap mailbox words.
    auto plain = d;
    plain.bootstrap_supported = false;
    const auto sii2 = protocol::parse_sii(esc::build_sii_image(plain));
    EXPECT_EQ(sii2.boot_rx_mbx_size, 0);
    EXPECT_EQ(sii2.boot_tx_mbx_size, 0);
}

TEST(FoeDevice, OnlyDevicesDeclaringFoeGetAServer) {
    FoeBench with;
    EXPECT_EQ(with.attached, 1u);
    auto d = device::default_drive();
    d.mailbox_protocols = device::mbx_proto::CoE;
    FoeBench without({}, d);
    EXPECT_EQ(without.attached, 0u);
    EXPECT_EQ(foe::foe_server(without.b.slave()), nullptr);
}

// A device of a network file without CoE (a process image only) but with FoE and bootstrap.
std::unique_ptr<esc::Segment> plain_segment(const device::DeviceDescription& d, std::size_t n,
                                            const esc::EscConfig& cfg) {
    auto seg = std::make_unique<esc::Segment>();
    for (std::size_t i = 0; i < n; ++i)
        seg->add(std::make_unique<esc::Slave>(d, cfg, std::make_unique<esc::ProcessImageApplication>(0, 0)));
    return seg;
}

TEST(FoeDevice, ADeviceWithoutCoeUpdatesItsSii) {
    auto d = device::default_drive();
    d.mailbox_protocols = device::mbx_proto::FoE;
    d.rx_pdos.clear();
    d.tx_pdos.clear();
    FoeBench f({}, d, &plain_segment);
    ASSERT_EQ(f.attached, 1u);
    f.to_boot();
    const auto w = f.client().write("io.efw", firmware(0x00000005));
    ASSERT_TRUE(w.ok()) << w.error_text;
    ASSERT_TRUE(f.b.master.request_state(f.station(), AlState::Init));
    EXPECT_EQ(f.sii_revision(), 5u);
}

// ---- BOOT transitions (ETG.1000.6 6.4, Table 9; AL status codes of Table 11)

TEST(BootState, InitToBootWithTheBootstrapMailboxAndBack) {
    FoeBench f;
    f.to_boot();
    EXPECT_EQ(f.b.slave().state(), AlState::Boot);
    EXPECT_FALSE(f.b.slave().error());
    const auto r = f.request(AlState::Init);
    EXPECT_EQ(r.state(), AlState::Init);
    EXPECT_FALSE(r.error());
}

TEST(BootState, StandardMailboxIsTheWrongConfigurationForADeviceWithItsOwnBootMailbox) {
    FoeBench f({}, big_boot_mailbox());
    f.startup(AlState::Init);
    ASSERT_TRUE(f.b.master.configure_mailboxes());
    const auto r = f.request(AlState::Boot);
    EXPECT_EQ(r.state(), AlState::Init);
    EXPECT_TRUE(r.error());
    EXPECT_EQ(r.code, static_cast<std::uint16_t>(AlStatusCode::InvalidMailboxConfigBoot));
}

TEST(BootState, TheBootMailboxIsWrittenIntoDisabledSyncManagersOnly) {
    // SOEM's firm_update (before its pull request #483) writes the bootstrap mailbox over the enabled
    // standard one: the ESC keeps the old configuration and BOOT is refused, as on real hardware.
    FoeBench f({}, big_boot_mailbox());
    f.startup(AlState::PreOp);
    ASSERT_TRUE(f.b.master.request_state(f.station(), AlState::Init));
    for (unsigned i = 0; i < 2; ++i) {
        std::uint8_t b[protocol::SmConfig::kSize];
        protocol::SmConfig::master(i == 0 ? 0x1800 : 0x1A00, 0x0200, i == 0 ? 0x26 : 0x22).pack(b);
        ASSERT_TRUE(f.b.master.fpwr(f.station(), protocol::sm_addr(i), b));
    }
    auto r = f.request(AlState::Boot);
    EXPECT_EQ(r.state(), AlState::Init);
    EXPECT_EQ(r.code, static_cast<std::uint16_t>(AlStatusCode::InvalidMailboxConfigBoot));
    // Disabled first (configure_boot_mailbox), the same configuration is taken.
    ASSERT_TRUE(master::configure_boot_mailbox(f.b.master, f.b.master.slaves()[0]));
    f.request(AlState::Init);  // acknowledge the error (INIT is obeyed without acknowledge)
    r = f.request(AlState::Boot);
    EXPECT_EQ(r.state(), AlState::Boot);
    EXPECT_FALSE(r.error());
    // FoE runs on the larger mailbox: 500 bytes a packet.
    auto c = f.client();
    EXPECT_EQ(c.mailbox().mailbox_size_out(), 0x200u);
    const auto w = c.write("big.efw", firmware(kNewRevision, {}, 1200));
    ASSERT_TRUE(w.ok()) << w.error_text;
    EXPECT_EQ(w.packets, 3u);
}

TEST(BootState, WithoutAnyMailboxConfigurationBootIsRefused) {
    FoeBench f;
    f.startup(AlState::Init);
    const auto r = f.request(AlState::Boot);
    EXPECT_EQ(r.state(), AlState::Init);
    EXPECT_EQ(r.code, static_cast<std::uint16_t>(AlStatusCode::InvalidMailboxConfigBoot));
}

TEST(BootState, DeviceWithoutBootstrapAnswers0x0013) {
    auto d = device::default_drive();
    d.bootstrap_supported = false;
    FoeBench f({}, d);
    f.startup(AlState::Init);
    ASSERT_TRUE(f.b.master.configure_mailboxes());
    const auto r = f.request(AlState::Boot);
    EXPECT_EQ(r.state(), AlState::Init);
    EXPECT_EQ(r.code, static_cast<std::uint16_t>(AlStatusCode::BootstrapNotSupported));
}

TEST(BootState, BootToPreOpSafeOpOpIsRefused) {
    for (AlState to : {AlState::PreOp, AlState::SafeOp, AlState::Op}) {
        FoeBench f;
        f.to_boot();
        const auto r = f.request(to);
        EXPECT_EQ(r.state(), AlState::Boot) << static_cast<int>(to);
        EXPECT_TRUE(r.error());
        EXPECT_EQ(r.code, static_cast<std::uint16_t>(AlStatusCode::InvalidRequestedStateChange));
        // INIT is obeyed without acknowledge.
        EXPECT_EQ(f.request(AlState::Init).state(), AlState::Init);
    }
}

TEST(BootState, OpToBootIsRefused) {
    FoeBench f;
    f.startup(AlState::Op);
    const auto r = f.request(AlState::Boot);
    EXPECT_EQ(r.state(), AlState::SafeOp);
    EXPECT_EQ(r.code, static_cast<std::uint16_t>(AlStatusCode::InvalidRequestedStateChange));
}

TEST(BootState, CoeInBootIsAnUnsupportedProtocol) {
    FoeBench f;
    f.to_boot();
    master::CoeClient c(f.b.master, f.station());
    const std::uint8_t upload[10] = {0x00, 0x20, 0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0};  // 0x1018:01
    const auto m = c.request(MailboxType::CoE, upload);
    ASSERT_TRUE(m);
    EXPECT_EQ(m->header.type, static_cast<std::uint8_t>(MailboxType::Error));
    ASSERT_GE(m->payload.size(), 4u);
    EXPECT_EQ(ld_le16(m->payload.data() + 2),
              static_cast<std::uint16_t>(protocol::MailboxError::UnsupportedProtocol));
}

// ---- The firmware update

TEST(FoeFirmware, UpdateInBootChangesTheRevisionInSiiAnd0x1018OnBootToInit) {
    FoeBench f;
    const std::uint32_t old_rev = f.b.desc.identity.revision;
    f.to_boot();
    ASSERT_EQ(f.sii_revision(), old_rev);
    auto c = f.client();
    const auto fw = firmware(kNewRevision, 0x402);
    const auto r = c.write("drive.efw", fw);
    ASSERT_TRUE(r.ok()) << r.error_text;
    EXPECT_EQ(r.busy, 1u);  // the first data packet: "erasing flash", sent again
    EXPECT_EQ(f.server().counters().busy_sent, 1u);
    EXPECT_EQ(f.server().pending_revision(), kNewRevision);
    // Still the old revision while in BOOT.
    EXPECT_EQ(f.sii_revision(), old_rev);
    ASSERT_TRUE(f.b.master.request_state(f.station(), AlState::Init));
    EXPECT_EQ(f.sii_revision(), kNewRevision);
    EXPECT_EQ(f.b.slave().sii_revision(), kNewRevision);
    EXPECT_EQ(f.server().counters().firmware_updates, 1u);
    // A master starting again sees the new revision in the SII and in 0x1018:03.
    f.startup(AlState::PreOp);
    EXPECT_EQ(f.b.master.slaves()[0].sii.identity.revision, kNewRevision);
    master::CoeClient coe(f.b.master, f.station());
    const auto up = coe.upload(protocol::obj::identity::index, 3);
    ASSERT_TRUE(up.ok());
    EXPECT_EQ(ld_le32(up.data.data()), kNewRevision);
}

TEST(FoeFirmware, NotAFirmwareFileIsAProgramErrorAndChangesNothing) {
    FoeBench f;
    const std::uint32_t old_rev = f.b.desc.identity.revision;
    f.to_boot();
    auto c = f.client();
    const auto bad = bytes_of("MZ this is not a vecat firmware\n");
    auto r = c.write("drive.efw", bad);
    ASSERT_EQ(r.error, FoeError::ProgramError);
    EXPECT_NE(r.error_text.find("not a vecat firmware"), std::string::npos) << r.error_text;
    // Firmware for another product.
    r = f.client().write("drive.efw", firmware(kNewRevision, 0x1234));
    ASSERT_EQ(r.error, FoeError::ProgramError);
    EXPECT_NE(r.error_text.find("0x00001234"), std::string::npos) << r.error_text;
    // No header line at all, and a header without revision.
    EXPECT_EQ(f.client().write("drive.efw", bytes_of("vecat-firmware product=1")).error,
              FoeError::ProgramError);
    EXPECT_EQ(f.client().write("drive.efw", bytes_of("vecat-firmware product=1\n")).error,
              FoeError::ProgramError);
    EXPECT_FALSE(f.server().pending_revision());
    ASSERT_TRUE(f.b.master.request_state(f.station(), AlState::Init));
    EXPECT_EQ(f.sii_revision(), old_rev);
}

TEST(FoeFirmware, FirmwareOutsideBootIsBootstrapOnly) {
    FoeBench f;
    f.startup(AlState::PreOp);
    const auto r = f.client().write("drive.efw", firmware(kNewRevision));
    EXPECT_EQ(r.error, FoeError::BootstrapOnly);
    EXPECT_EQ(r.error_text, "Bootstrap only");
    EXPECT_EQ(f.client().read("DRIVE.EFW").error, FoeError::BootstrapOnly);
}

TEST(FoeFirmware, OtherFilesInBootAreNotInBootstrapAndFirmwareIsNotReadBack) {
    FoeBench f;
    f.to_boot();
    EXPECT_EQ(f.client().write("config.txt", bytes_of("x")).error, FoeError::NotInBootstrap);
    EXPECT_EQ(f.client().read("config.txt").error, FoeError::NotInBootstrap);
    ASSERT_TRUE(f.client().write("drive.efw", firmware(kNewRevision)).ok());
    EXPECT_EQ(f.client().read("drive.efw").error, FoeError::AccessDenied);
}

TEST(FoeFirmware, LeavingBootWithoutAFirmwareKeepsTheRevision) {
    FoeBench f;
    f.to_boot();
    ASSERT_TRUE(f.b.master.request_state(f.station(), AlState::Init));
    EXPECT_EQ(f.sii_revision(), f.b.desc.identity.revision);
    EXPECT_EQ(f.server().counters().firmware_updates, 0u);
}

// ---- Read and write of ordinary files

TEST(FoeFiles, WriteThenReadBackManyPackets) {
    FoeBench f;
    f.startup(AlState::PreOp);
    const auto data = pattern(1000);  // the standard mailbox carries 234 bytes a packet: 5 packets
    const auto w = f.client().write("log.bin", data);
    ASSERT_TRUE(w.ok()) << w.error_text;
    EXPECT_EQ(w.packets, 5u);
    EXPECT_EQ(w.busy, 0u);  // busy only while the bootloader erases
    const auto r = f.client().read("log.bin");
    ASSERT_TRUE(r.ok()) << r.error_text;
    EXPECT_EQ(r.data, data);
    EXPECT_EQ(r.packets, 5u);
    EXPECT_EQ(f.server().counters().files_written, 1u);
    EXPECT_EQ(f.server().counters().files_read, 1u);
    EXPECT_EQ(f.server().state(), foe::FoeState::Idle);
}

TEST(FoeFiles, AFileOfWholePacketsEndsWithAnEmptyPacket) {
    FoeBench f;
    f.startup(AlState::PreOp);
    const std::size_t full = protocol::foe_data_capacity(0xF6);
    const auto data = pattern(2 * full);
    const auto w = f.client().write("two.bin", data);
    ASSERT_TRUE(w.ok());
    EXPECT_EQ(w.packets, 3u);
    const auto r = f.client().read("two.bin");
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.packets, 3u);
    EXPECT_EQ(r.data, data);
    // An empty file: one empty packet.
    ASSERT_TRUE(f.client().write("empty", {}).ok());
    const auto e = f.client().read("empty");
    ASSERT_TRUE(e.ok());
    EXPECT_TRUE(e.data.empty());
    EXPECT_EQ(e.packets, 1u);
}

TEST(FoeFiles, FilesLiveInTheDirectoryOfTheSlave) {
    const auto dir = std::filesystem::temp_directory_path() / ("vecat_foe_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    {
        FoeBench f({.dir = dir.string()});
        f.startup(AlState::SafeOp);
        const auto data = pattern(600);
        ASSERT_TRUE(f.client().write("cfg.bin", data).ok());
        std::ifstream in(dir / "slave-0" / "cfg.bin", std::ios::binary);
        const std::vector<std::uint8_t> on_disk((std::istreambuf_iterator<char>(in)), {});
        EXPECT_EQ(on_disk, data);
        // A file put there from outside is read.
        std::ofstream(dir / "slave-0" / "hello.txt") << "hello";
        const auto r = f.client().read("hello.txt");
        ASSERT_TRUE(r.ok());
        EXPECT_EQ(std::string(r.data.begin(), r.data.end()), "hello");
        // A directory is not a file: access denied.
        std::filesystem::create_directories(dir / "slave-0" / "sub");
        EXPECT_EQ(f.client().read("sub").error, FoeError::AccessDenied);
    }
    std::filesystem::remove_all(dir);
}

TEST(FoeFiles, FoeRunsBesideProcessDataInOp) {
    FoeBench f;
    f.startup(AlState::Op);
    const auto expected = f.b.master.expected_wkc();
    ASSERT_EQ(f.b.master.exchange_process_data(), expected);
    ASSERT_TRUE(f.client().write("op.bin", pattern(700)).ok());
    EXPECT_EQ(f.b.master.exchange_process_data(), expected);
    EXPECT_EQ(f.b.master.read_al_status(f.station()).state(), AlState::Op);
}

// ---- Every FoE error code the device produces (ETG.1000.6 Table 93)

TEST(FoeErrors, NotFound0x8001) {
    FoeBench f;
    f.startup(AlState::PreOp);
    const auto r = f.client().read("missing.bin");
    EXPECT_EQ(r.error, FoeError::NotFound);
    EXPECT_EQ(r.error_text, "Not found");
}

TEST(FoeErrors, NoRights0x800AForAWrongPassword) {
    FoeBench f({.dir = {}, .password = 0x1234});
    f.startup(AlState::PreOp);
    EXPECT_EQ(f.client().write("a.bin", pattern(10), 0x9999).error, FoeError::NoRights);
    EXPECT_EQ(f.client().read("a.bin", 0).error, FoeError::NoRights);
    ASSERT_TRUE(f.client().write("a.bin", pattern(10), 0x1234).ok());
    EXPECT_TRUE(f.client().read("a.bin", 0x1234).ok());
}

TEST(FoeErrors, DiskFull0x8003ForAFileOverTheLimitWithBoundedMemory) {
    FoeBench f({.dir = {}, .max_file_size = 500});
    f.startup(AlState::PreOp);
    EXPECT_TRUE(f.client().write("fits.bin", pattern(500)).ok());
    const auto r = f.client().write("big.bin", pattern(501));
    EXPECT_EQ(r.error, FoeError::DiskFull);
    EXPECT_EQ(r.packets, 2u);  // the third packet went over the limit
    EXPECT_EQ(f.server().state(), foe::FoeState::Idle);
    EXPECT_EQ(f.client().read("big.bin").error, FoeError::NotFound);
}

TEST(FoeErrors, DiskFull0x8003WhenMemoryHoldsNoMoreFiles) {
    FoeBench f;
    f.startup(AlState::PreOp);
    for (std::size_t i = 0; i < foe::FileStore::kMaxMemoryFiles; ++i)
        ASSERT_TRUE(f.client().write("f" + std::to_string(i), pattern(3)).ok());
    EXPECT_EQ(f.client().write("one-more", pattern(3)).error, FoeError::DiskFull);
    EXPECT_TRUE(f.client().write("f0", pattern(4)).ok());  // replacing one is fine
}

TEST(FoeErrors, Illegal0x8004ForBadNames) {
    FoeBench f;
    f.startup(AlState::PreOp);
    const std::vector<std::string> names = {"../etc/passwd", "a/b", "..", ".", "a\\b", "", "tab\tname"};
    for (const auto& name : names) {
        EXPECT_EQ(f.client().write(name, pattern(3)).error, FoeError::Illegal) << name;
        EXPECT_EQ(f.client().read(name).error, FoeError::Illegal) << name;
    }
    // Trailing NULs (some masters send a C string) are not part of the name.
    ASSERT_TRUE(f.client().write(std::string("nul.bin\0\0", 9), pattern(3)).ok());
    EXPECT_TRUE(f.client().read("nul.bin").ok());
}

TEST(FoeErrors, Illegal0x8004ForANameOver255Bytes) {
    // The standard mailbox (246 bytes) carries at most 234 name bytes; the 512-byte bootstrap mailbox more.
    FoeBench f({}, big_boot_mailbox());
    f.startup(AlState::PreOp);
    ASSERT_TRUE(f.b.master.request_state(f.station(), AlState::Init));
    ASSERT_TRUE(master::configure_boot_mailbox(f.b.master, f.b.master.slaves()[0]));
    ASSERT_TRUE(f.b.master.request_state(f.station(), AlState::Boot));
    EXPECT_EQ(foe_error(f.raw_op(FoeOpCode::Write, 0, std::string(252, 'x') + ".efw")), FoeError::Illegal);
    const auto ok = f.raw_op(FoeOpCode::Write, 0, std::string(251, 'y') + ".efw");
    ASSERT_TRUE(ok);
    EXPECT_EQ(protocol::parse_foe(ok->payload)->op, FoeOpCode::Ack);
}

TEST(FoeErrors, Illegal0x8004ForOpcodesOutOfTurn) {
    FoeBench f;
    f.startup(AlState::PreOp);
    EXPECT_EQ(foe_error(f.raw_op(FoeOpCode::Data, 1, "abc")), FoeError::Illegal);  // no write in progress
    EXPECT_EQ(foe_error(f.raw_op(FoeOpCode::Ack, 1)), FoeError::Illegal);          // no read in progress
    EXPECT_EQ(foe_error(f.raw_op(FoeOpCode::Busy, 0)), FoeError::Illegal);         // masters are never busy
    const std::uint8_t unknown[6] = {0x09, 0, 0, 0, 0, 0};
    EXPECT_EQ(foe_error(f.raw(unknown)), FoeError::Illegal);
    // An acknowledge during a write ends it.
    ASSERT_EQ(protocol::parse_foe(f.raw_op(FoeOpCode::Write, 0, "w.bin")->payload)->op, FoeOpCode::Ack);
    EXPECT_EQ(foe_error(f.raw_op(FoeOpCode::Ack, 0)), FoeError::Illegal);
    EXPECT_EQ(f.server().state(), foe::FoeState::Idle);
}

TEST(FoeErrors, PacketNumberWrong0x8005OnWriteAndRead) {
    FoeBench f;
    f.startup(AlState::PreOp);
    // Write: ACK 0, then packet 2 instead of 1.
    auto a = f.raw_op(FoeOpCode::Write, 0, "w.bin");
    ASSERT_TRUE(a);
    EXPECT_EQ(protocol::parse_foe(a->payload)->value, 0u);
    EXPECT_EQ(foe_error(f.raw_op(FoeOpCode::Data, 2, "xyz")), FoeError::PacketNumberWrong);
    EXPECT_EQ(f.server().state(), foe::FoeState::Idle);
    // The same packet twice.
    ASSERT_TRUE(f.raw_op(FoeOpCode::Write, 0, "w.bin"));
    const std::string full(protocol::foe_data_capacity(0xF6), 'a');
    ASSERT_EQ(protocol::parse_foe(f.raw_op(FoeOpCode::Data, 1, full)->payload)->op, FoeOpCode::Ack);
    EXPECT_EQ(foe_error(f.raw_op(FoeOpCode::Data, 1, full)), FoeError::PacketNumberWrong);
    // Read: the acknowledge of a packet not sent.
    ASSERT_TRUE(f.client().write("r.bin", pattern(1000)).ok());
    auto d = f.raw_op(FoeOpCode::Read, 0, "r.bin");
    ASSERT_TRUE(d);
    EXPECT_EQ(protocol::parse_foe(d->payload)->op, FoeOpCode::Data);
    EXPECT_EQ(protocol::parse_foe(d->payload)->value, 1u);
    const auto e = f.raw_op(FoeOpCode::Ack, 5);
    EXPECT_EQ(foe_error(e), FoeError::PacketNumberWrong);
    EXPECT_NE(protocol::parse_foe(e->payload)->text().find("acknowledge of packet 5"),
              std::string_view::npos);
}

TEST(FoeErrors, NotDefined0x8000WhenTheHostCannotStoreTheFile) {
    // The directory is a regular file: the store cannot create the slave's folder.
    const auto file =
        std::filesystem::temp_directory_path() / ("vecat_foe_file_" + std::to_string(::getpid()));
    std::ofstream(file) << "in the way";
    {
        FoeBench f({.dir = file.string()});
        f.startup(AlState::PreOp);
        const auto r = f.client().write("x.bin", pattern(10));
        EXPECT_EQ(r.error, FoeError::NotDefined);
        EXPECT_NE(r.error_text.find("cannot write"), std::string::npos) << r.error_text;
    }
    std::filesystem::remove(file);
}

TEST(FoeErrors, TruncatedPayloadGetsTheMailboxErrorAndEndsTheTransfer) {
    FoeBench f;
    f.startup(AlState::PreOp);
    ASSERT_TRUE(f.raw_op(FoeOpCode::Write, 0, "t.bin"));
    const std::uint8_t cut[3] = {0x03, 0x00, 0x01};
    const auto m = f.raw(cut);
    ASSERT_TRUE(m);
    EXPECT_EQ(m->header.type, static_cast<std::uint8_t>(MailboxType::Error));
    EXPECT_EQ(ld_le16(m->payload.data() + 2),
              static_cast<std::uint16_t>(protocol::MailboxError::SizeTooShort));
    EXPECT_EQ(f.server().state(), foe::FoeState::Idle);
}

TEST(FoeErrors, TheMastersErrorRequestCancelsQuietly) {
    FoeBench f;
    f.startup(AlState::PreOp);
    ASSERT_TRUE(f.raw_op(FoeOpCode::Write, 0, "c.bin"));
    EXPECT_EQ(f.server().state(), foe::FoeState::Writing);
    master::CoeClient c(f.b.master, f.station());
    std::uint8_t p[protocol::kFoeHeaderSize + 8];
    const auto n = protocol::write_foe_error(p, FoeError::NotDefined, "cancel");
    ASSERT_TRUE(c.send(MailboxType::FoE, ConstBytes(p, n), c.next_counter()));
    EXPECT_FALSE(c.receive(std::chrono::milliseconds(20)));  // not answered
    EXPECT_EQ(f.server().state(), foe::FoeState::Idle);
    EXPECT_EQ(foe_error(f.raw_op(FoeOpCode::Data, 1, "x")), FoeError::Illegal);
}

TEST(FoeErrors, ANewRequestReplacesATransferInProgress) {
    FoeBench f;
    f.startup(AlState::PreOp);
    ASSERT_TRUE(f.raw_op(FoeOpCode::Write, 0, "abandoned.bin"));
    ASSERT_TRUE(f.client().write("new.bin", pattern(300)).ok());
    EXPECT_EQ(f.client().read("abandoned.bin").error, FoeError::NotFound);
    EXPECT_EQ(f.client().read("new.bin").data, pattern(300));
}

TEST(FoeErrors, InitEndsATransfer) {
    FoeBench f;
    f.startup(AlState::PreOp);
    ASSERT_TRUE(f.raw_op(FoeOpCode::Write, 0, "i.bin"));
    ASSERT_TRUE(f.b.master.request_state(f.station(), AlState::Init));
    EXPECT_EQ(f.server().state(), foe::FoeState::Idle);
}

// ---- The firmware file format

TEST(FoeFirmwareFormat, HeaderLine) {
    auto h = foe::parse_firmware(bytes_of("vecat-firmware revision=0x00020000 product=1026\nimage"));
    ASSERT_TRUE(h);
    EXPECT_EQ(h->revision, 0x00020000u);
    EXPECT_EQ(h->product, 1026u);
    h = foe::parse_firmware(bytes_of(foe::firmware_header_line(7)));
    ASSERT_TRUE(h);
    EXPECT_EQ(h->revision, 7u);
    EXPECT_FALSE(h->product);
    std::string why;
    EXPECT_FALSE(foe::parse_firmware(bytes_of("vecat-firmwarex revision=1\n"), &why));
    EXPECT_FALSE(foe::parse_firmware(bytes_of("vecat-firmware revision=zz\n"), &why));
    EXPECT_NE(why.find("revision=zz"), std::string::npos);
    EXPECT_FALSE(foe::parse_firmware(bytes_of("vecat-firmware revision=1 color=2\n"), &why));
    EXPECT_FALSE(foe::parse_firmware(bytes_of("vecat-firmware revision=99999999999\n"), &why));
    EXPECT_TRUE(foe::is_firmware_name("X.EFW"));
    EXPECT_FALSE(foe::is_firmware_name("efw"));
    EXPECT_FALSE(foe::is_firmware_name("x.efw.txt"));
}
