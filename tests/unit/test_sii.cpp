// SII EEPROM: the image built from the device description, and the 0x0500-0x050F interface.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "esc/sii_image.hpp"
#include "shared_data.hpp"
#include "test_support.hpp"

using namespace vecat;
using namespace vecat::test;
using namespace vecat::esc;
using namespace vecat::protocol;

namespace {
std::vector<std::uint8_t> load(const std::string& rel) {
    std::ifstream f(shared_data(rel), std::ios::binary);
    return {std::istreambuf_iterator<char>(f), {}};
}
std::uint16_t sii_status(Bench& b) {
    return b.escx().peek16(0x0502);
}
void command(Bench& b, std::uint16_t cmd, std::uint32_t word) {
    std::vector<std::uint8_t> c(6);
    st_le16(c.data(), cmd);
    st_le32(c.data() + 2, word);
    ASSERT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0502), c).wkc, 1);
}
}  // namespace

TEST(SiiImage, DefaultDriveImageIsCompleteAndConsistent) {
    const auto d = device::default_drive();
    const auto img = build_sii_image(d);
    const auto s = parse_sii(img);
    EXPECT_TRUE(s.errors.empty()) << s.errors.front();
    EXPECT_TRUE(s.checksum_ok);
    EXPECT_EQ(s.identity.vendor_id, d.identity.vendor_id);
    EXPECT_EQ(s.identity.product_code, d.identity.product_code);
    EXPECT_EQ(s.string_at(1), d.name);  // SOEM shows string #1
    EXPECT_EQ(s.device_name(), d.name);
    ASSERT_TRUE(s.has_general);
    for (unsigned w = sii::BootRxMailboxOffset; w <= sii::StdTxMailboxSize; ++w)
        EXPECT_NE(ld_le16(&img[2 * w]), 0xFFFF) << "word " << w;
    EXPECT_EQ(s.std_rx_mbx_offset, 0x1800);
    EXPECT_EQ(s.std_tx_mbx_size, 0x00F6);
    ASSERT_EQ(s.sync_managers.size(), 4u);
    for (std::size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(s.sync_managers[i].start, d.sync_managers[i].start);
        EXPECT_EQ(s.sync_managers[i].length, d.sync_managers[i].length);
        EXPECT_EQ(s.sync_managers[i].control, d.sync_managers[i].control);
        EXPECT_EQ(s.sync_managers[i].type, static_cast<std::uint8_t>(d.sync_managers[i].type));
    }
    EXPECT_EQ(s.fmmus, (std::vector<std::uint8_t>{1, 2, 3, 0xFF}));
    ASSERT_EQ(s.rx_pdos.size(), d.rx_pdos.size());
    ASSERT_EQ(s.tx_pdos.size(), d.tx_pdos.size());
    // Only the assigned PDOs carry their SyncManager; the others say 0xFF (not assigned).
    for (std::size_t i = 1; i < s.rx_pdos.size(); ++i)
        EXPECT_EQ(s.rx_pdos[i].sm, 0xFF);
    unsigned bits = 0;
    for (const auto& e : s.tx_pdos[0].entries)
        bits += e.bit_length;
    EXPECT_EQ(bits / 8, d.sync_managers[3].length);
    EXPECT_EQ(s.rx_pdos[0].sm, 2);
    ASSERT_EQ(s.dc_modes.size(), 3u);
    EXPECT_EQ(s.dc_modes[2].assign_activate, 0x0300);
    EXPECT_EQ(img.size(), d.eeprom_size_bytes);
}

TEST(SiiImage, ChecksumMatchesRealEeproms) {
    VECAT_REQUIRE_SHARED_DATA("sii");
    for (const char* f : {"sii/kollmorgen-akd.bin", "sii/beckhoff-el2004.bin", "sii/soes-dynpdo.bin",
                          "sii/soes-lan9252.bin"}) {
        const auto img = load(f);
        ASSERT_GE(img.size(), 16u) << f;
        EXPECT_EQ(sii_config_crc(ConstBytes(img.data(), 14)), img[14]) << f;
        const auto s = parse_sii(img);
        EXPECT_TRUE(s.checksum_ok) << f;
        EXPECT_NE(s.identity.vendor_id, 0u) << f;
        EXPECT_FALSE(s.strings.empty()) << f;
    }
}

// SII text is ISO 8859-1 (the EL2262's "1 µs" is the byte 0xB5); vecat's text is UTF-8. The parser converts
// one way, the writer the other, and an image written from a description reads back as its text.
TEST(SiiImage, StringsAreIso8859OneInTheImageAndUtf8InVecat) {
    EXPECT_EQ(protocol::sii_text_to_utf8("1\xB5s, \xE4"), "1\xC2\xB5s, \xC3\xA4");
    EXPECT_EQ(protocol::utf8_to_sii_text("1\xC2\xB5s, \xC3\xA4"), "1\xB5s, \xE4");
    EXPECT_EQ(protocol::utf8_to_sii_text("20 \xE2\x82\xAC"), "20 ?");  // the euro sign has no ISO 8859-1 code
    EXPECT_EQ(protocol::utf8_to_sii_text("raw \xB5 byte"), "raw \xB5 byte");  // no UTF-8: kept as it is
    for (unsigned c = 0; c < 256; ++c) {
        const std::string one(1, static_cast<char>(c));
        EXPECT_EQ(protocol::utf8_to_sii_text(protocol::sii_text_to_utf8(one)), one) << c;
    }
    auto d = device::default_drive();
    d.name = "Ausgang 24V, 1\xC2\xB5s";
    const auto img = build_sii_image(d);
    const std::string text = "Ausgang 24V, 1\xB5s";
    const std::vector<std::uint8_t> latin1(text.begin(), text.end());
    EXPECT_NE(std::search(img.begin(), img.end(), latin1.begin(), latin1.end()), img.end());
    EXPECT_EQ(parse_sii(img).device_name(), d.name);
}

TEST(SiiImage, TheNameOfARealDeviceReadsAsUtf8) {
    VECAT_REQUIRE_SHARED_DATA("sii/beckhoff-el2262.bin");
    const auto s = parse_sii(load("sii/beckhoff-el2262.bin"));
    EXPECT_NE(s.device_name().find("1\xC2\xB5s"), std::string::npos) << s.device_name();
}

TEST(SiiImage, ParserSurvivesTruncation) {
    const auto img = build_sii_image(device::default_drive());
    for (std::size_t n = 0; n < 400; n += 3) {
        const auto s = parse_sii(ConstBytes(img.data(), n));
        EXPECT_FALSE(s.errors.empty()) << n;
    }
}

TEST(SiiInterface, ReadsEightBytesAndClearsTheCommand) {
    Bench b(1);
    EXPECT_TRUE(sii_status(b) & sii_ctrl::Read8Bytes);
    command(b, sii_ctrl::CmdRead, sii::VendorId);
    EXPECT_EQ(sii_status(b) & (sii_ctrl::CmdMask | sii_ctrl::Busy | sii_ctrl::ErrorAck), 0);
    EXPECT_EQ(b.escx().peek32(0x0508), b.desc.identity.vendor_id);
    EXPECT_EQ(b.escx().peek32(0x050C), b.desc.identity.product_code);
}

TEST(SiiInterface, FourByteMode) {
    esc::EscConfig cfg;
    cfg.sii_read_8_bytes = false;
    Bench b(1, cfg);
    EXPECT_FALSE(sii_status(b) & sii_ctrl::Read8Bytes);
    command(b, sii_ctrl::CmdRead, sii::VendorId);
    EXPECT_EQ(b.escx().peek32(0x0508), b.desc.identity.vendor_id);
    EXPECT_EQ(b.escx().peek32(0x050C), 0u);
}

TEST(SiiInterface, CapabilityBitsAreReadOnly) {
    Bench b(1);
    const auto before = sii_status(b) & 0x00FF;
    raw_datagram(*b.seg, 2, phys(0, 0x0502), {0x00});  // SOEM writes 0x00
    EXPECT_EQ(sii_status(b) & 0x00FE, before & 0xFE);
    raw_datagram(*b.seg, 2, phys(0, 0x0502), {0x80});  // IgH writes 0x80
    EXPECT_EQ(sii_status(b) & 0x00FE, before & 0xFE);
}

TEST(SiiInterface, ErrorsAndTheirAcknowledge) {
    Bench b(1);
    command(b, sii_ctrl::CmdRead, 0x4000);  // past the 4 KiB EEPROM
    EXPECT_TRUE(sii_status(b) & sii_ctrl::ErrorAck);
    raw_datagram(*b.seg, 2, phys(0, 0x0502), {0, 0});
    EXPECT_FALSE(sii_status(b) & sii_ctrl::ErrorAck);
    command(b, 0x0300, 0);  // invalid command
    EXPECT_TRUE(sii_status(b) & sii_ctrl::ErrorAck);
    command(b, sii_ctrl::CmdWrite, 0x20);  // write without write enable
    EXPECT_TRUE(sii_status(b) & sii_ctrl::ErrorWriteEnable);
}

TEST(SiiInterface, WriteWithEnableThenReload) {
    Bench b(1);
    raw_datagram(*b.seg, 2, phys(0, 0x0508), {0x34, 0x12});
    command(b, sii_ctrl::CmdWrite | sii_ctrl::WriteEnable, sii::StationAlias);
    EXPECT_EQ(sii_status(b) & (sii_ctrl::WriteEnable | sii_ctrl::ErrorWriteEnable), 0);
    EXPECT_EQ(ld_le16(&b.escx().eeprom()[2 * sii::StationAlias]), 0x1234);
    // The configuration area checksum no longer matches: the reload reports it and keeps the old values.
    command(b, sii_ctrl::CmdReload, 0);
    EXPECT_TRUE(sii_status(b) & sii_ctrl::ChecksumError);
    EXPECT_EQ(b.escx().peek16(0x0012), 0);
    const auto& e = b.escx().eeprom();
    const std::uint8_t crc = sii_config_crc(ConstBytes(e.data(), 14));
    raw_datagram(*b.seg, 2, phys(0, 0x0508), {crc, 0});
    command(b, sii_ctrl::CmdWrite | sii_ctrl::WriteEnable, sii::Checksum);
    command(b, sii_ctrl::CmdReload, 0);
    EXPECT_FALSE(sii_status(b) & sii_ctrl::ChecksumError);
    EXPECT_EQ(b.escx().peek16(0x0012), 0x1234);
}

TEST(SiiInterface, MasterReadsTheImageTheSlaveServes) {
    Bench b(1);
    ASSERT_TRUE(b.master.startup(AlState::Init));
    const auto& img = b.master.slaves()[0].sii_image;
    const auto full = build_sii_image(b.desc);
    ASSERT_GT(img.size(), 128u);
    EXPECT_TRUE(std::equal(img.begin(), img.end(), full.begin()));
    EXPECT_EQ(b.master.slaves()[0].sii.device_name(), b.desc.name);
}
