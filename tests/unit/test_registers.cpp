// Register semantics: information registers, read-only bits, write masks, side effects.
#include <gtest/gtest.h>

#include "test_support.hpp"

using namespace vecat;
using namespace vecat::test;

TEST(Registers, InformationRegisters) {
    esc::EscConfig cfg;
    cfg.ram_bytes = 16384;
    Bench b(1, cfg);
    auto r = raw_datagram(*b.seg, 1, phys(0, 0x0000), std::vector<std::uint8_t>(10, 0));
    EXPECT_EQ(r.data[0], 0x11);  // type
    EXPECT_EQ(r.data[4], 8);     // FMMUs
    EXPECT_EQ(r.data[5], 8);     // SyncManagers
    EXPECT_EQ(r.data[6], 16);    // RAM in KiB
    EXPECT_EQ(r.data[7], 0x0F);  // ports 0, 1 MII
    EXPECT_TRUE(ld_le16(&r.data[8]) & protocol::feature::DcAvailable);
}

TEST(Registers, ReadOnlyRegistersCountButKeepTheirValue) {
    Bench b(1);
    auto w = raw_datagram(*b.seg, 2, phys(0, 0x0000), {0x55, 0x55});
    EXPECT_EQ(w.wkc, 1);
    EXPECT_EQ(b.escx().peek(0x0000), 0x11);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0130), {0x08, 0}).wkc, 1);
    EXPECT_EQ(b.escx().peek(0x0130), 0x01);  // AL status is written by the slave only
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0012), {0x12, 0x34}).wkc, 1);
    EXPECT_EQ(b.escx().peek16(0x0012), 0);  // alias comes from the EEPROM
    raw_datagram(*b.seg, 2, phys(0, 0x0120), {0xFF, 0xFF});
    EXPECT_EQ(b.escx().peek16(0x0120), 0x003F);  // AL control write mask
}

TEST(Registers, DlStatusShowsTheLine) {
    Bench b(3);
    for (unsigned i = 0; i < 3; ++i) {
        const std::uint16_t dl = b.escx(i).peek16(0x0110);
        auto open_with_link = [&](unsigned p) { return ((dl >> (8 + 2 * p)) & 0x3) == 0x2; };
        EXPECT_TRUE(dl & 0x0001) << "PDI operational";
        EXPECT_TRUE(dl & 0x0010) << "link port 0";
        EXPECT_TRUE(open_with_link(0));
        EXPECT_EQ(open_with_link(1), i < 2) << i;
        EXPECT_FALSE(open_with_link(2));
        EXPECT_FALSE(open_with_link(3));
    }
}

TEST(Registers, ErrorCountersCountAndClearOnWrite) {
    Bench b(1);
    std::vector<std::uint8_t> bad(30, 0);
    bad[12] = 0x88;
    bad[13] = 0xA4;
    st_le16(bad.data() + 14, 0x1000 | 100);  // claims more than the frame holds
    std::size_t len = bad.size();
    bad.resize(64);
    EXPECT_FALSE(b.seg->process_frame(bad, len, 1));
    EXPECT_EQ(b.escx().peek(0x0300), 1);
    EXPECT_EQ(b.seg->counters().dropped, 1u);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0304), {0}).wkc, 1);  // a write anywhere clears 0x0300-0x030B
    EXPECT_EQ(b.escx().peek(0x0300), 0);
}

TEST(Registers, SyncManagerConfigurationLockedWhileEnabled) {
    Bench b(1);
    std::vector<std::uint8_t> sm{0x00, 0x1F, 0x10, 0x00, 0x64, 0x00, 0x01, 0x00};
    raw_datagram(*b.seg, 2, phys(0, 0x0820), sm);
    EXPECT_EQ(b.escx().peek16(0x0820), 0x1F00);
    std::vector<std::uint8_t> other{0x00, 0x1E, 0x08, 0x00, 0x64, 0x00, 0x01, 0x00};
    raw_datagram(*b.seg, 2, phys(0, 0x0820), other);
    EXPECT_EQ(b.escx().peek16(0x0820), 0x1F00);  // still enabled: start address unchanged
    other[6] = 0;
    raw_datagram(*b.seg, 2, phys(0, 0x0820), other);  // disables (start ignored in the same write)
    raw_datagram(*b.seg, 2, phys(0, 0x0820), other);
    EXPECT_EQ(b.escx().peek16(0x0820), 0x1E00);
    EXPECT_EQ(b.escx().peek(0x0825), 0);  // status is read-only
}

TEST(Registers, WatchdogDefaultsAndProcessRam) {
    Bench b(1);
    EXPECT_EQ(b.escx().peek16(0x0400), 2498);
    EXPECT_EQ(b.escx().peek16(0x0420), 1000);
    EXPECT_EQ(b.escx().peek(0x0440) & 1, 1);
    auto w = raw_datagram(*b.seg, 2, phys(0, 0x2F00), {1, 2, 3});
    EXPECT_EQ(w.wkc, 1);
    EXPECT_EQ(raw_datagram(*b.seg, 1, phys(0, 0x2F00), {0, 0, 0}).data, (std::vector<std::uint8_t>{1, 2, 3}));
}

TEST(Registers, DcReceiveTimesFollowThePositionOnTheLine) {
    Bench b(3);
    raw_datagram(*b.seg, 8, phys(0, 0x0900), {0, 0, 0, 0}, 5'000'000'000);
    std::uint32_t prev = 0;
    for (unsigned i = 0; i < 3; ++i) {
        const std::uint32_t p0 = b.escx(i).peek32(0x0900);
        EXPECT_GT(p0, prev);
        prev = p0;
        if (i < 2) {
            EXPECT_GT(b.escx(i).peek32(0x0904), p0);  // the frame comes back later on port 1
        }
    }
    // System time reads local time + offset.
    raw_datagram(*b.seg, 5, phys(0x0000, 0x0920), {0, 0, 0, 0, 0, 0, 0, 0});
    auto t1 = raw_datagram(*b.seg, 1, phys(0, 0x0910), std::vector<std::uint8_t>(8, 0), 6'000'000'000);
    auto t2 = raw_datagram(*b.seg, 1, phys(0, 0x0910), std::vector<std::uint8_t>(8, 0), 6'000'001'000);
    EXPECT_EQ(ld_le64(t2.data.data()) - ld_le64(t1.data.data()), 1000u);
}

// Firmware after the reply (what the serve loop does): the frame's ESC work happens in process_frame(), the
// firmware's reaction (here: the AL control request) only in run_deferred_firmware(), or before the next
// frame if the server has not run it. Without deferral the reaction is there when process_frame() returns.
TEST(Registers, DeferredFirmwareRunsAfterTheFrameAndBeforeTheNext) {
    for (const bool deferred : {false, true}) {
        SCOPED_TRACE(deferred ? "deferred" : "at once");
        Bench b(1);
        b.seg->set_deferred_firmware(deferred);
        EXPECT_EQ(b.escx().peek(0x0130) & 0x1F, 0x01);
        EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0120), {0x02, 0}).wkc, 1);  // APWR AL control: PREOP
        // The firmware has taken the request (PREOP, or the error bit for unconfigured mailboxes) only
        // when it ran.
        EXPECT_EQ((b.escx().peek(0x0130) & 0x1F) == 0x01, deferred);
        if (deferred) {
            // The next frame sees it: the firmware due runs before the frame.
            const auto r = raw_datagram(*b.seg, 1, phys(0, 0x0130), {0, 0});  // APRD AL status
            EXPECT_NE(r.data[0] & 0x1F, 0x01);
            b.seg->run_deferred_firmware();  // nothing due any more: a no-op
        }
        EXPECT_NE(b.escx().peek(0x0130) & 0x1F, 0x01);
    }
}
