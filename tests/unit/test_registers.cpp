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

// Writes to read-only or absent registers are not counted (ESC datasheet section I 2.4: counted is a
// successful access; section II 1: reserved addresses "are not writable"), as real ESCs answer.
TEST(Registers, WritesToReadOnlyOrAbsentRegistersAreNotCounted) {
    Bench b(1);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0000), {0x55, 0x55}).wkc, 0);
    EXPECT_EQ(b.escx().peek(0x0000), 0x11);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0130), {0x08, 0}).wkc, 0);
    EXPECT_EQ(b.escx().peek(0x0130), 0x01);  // AL status is written by the slave only
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0012), {0x12, 0x34}).wkc, 0);
    EXPECT_EQ(b.escx().peek16(0x0012), 0);                                     // alias comes from the EEPROM
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x092C), {1, 2, 3, 4}).wkc, 0);  // system time difference
    // The ESC has 8 FMMUs and 8 SyncManagers (0x0004, 0x0005): FMMU 8 and SyncManager 8 are absent.
    ASSERT_EQ(b.escx().peek(0x0004), 8);
    ASSERT_EQ(b.escx().peek(0x0005), 8);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, protocol::fmmu_addr(8)), std::vector<std::uint8_t>(16, 1)).wkc,
              0);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, protocol::sm_addr(8)), std::vector<std::uint8_t>(8, 1)).wkc, 0);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, protocol::fmmu_addr(7)), std::vector<std::uint8_t>(16, 0)).wkc,
              1);
    // Past the process RAM (8 KiB: 0x1000-0x2FFF) there is no memory to write.
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x3000), {1, 2}).wkc, 0);
    // Reads are counted, also of reserved or absent addresses (they read 0).
    EXPECT_EQ(raw_datagram(*b.seg, 1, phys(0, protocol::fmmu_addr(8)), std::vector<std::uint8_t>(16, 0)).wkc,
              1);
    EXPECT_EQ(raw_datagram(*b.seg, 1, phys(0, 0x3000), {0, 0}).wkc, 1);
    // A read-write of a read-only register: the read counts (+1), the write does not (+2).
    EXPECT_EQ(raw_datagram(*b.seg, 3, phys(0, 0x0130), {0, 0}).wkc, 1);
}

// A write counts when at least one of its bytes lies in a register the master may write (section I 2.4
// "at least one byte"), whatever the value or the other bytes; bits outside the register's write mask keep
// their value.
TEST(Registers, AWriteCountsWhenOneOfItsBytesIsWritable) {
    Bench b(1);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0120), {0xFF, 0xFF}).wkc, 1);
    EXPECT_EQ(b.escx().peek16(0x0120), 0x003F);                                // AL control write mask
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x012E), {1, 2, 3, 4}).wkc, 0);  // reserved + AL status
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x012E), std::vector<std::uint8_t>(12, 0)).wkc,
              1);  // ... + 0x0138 RUN LED override
    // TwinCAT writes 0x0910-0x092F at once: the system time is writable, the difference is not.
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0910), std::vector<std::uint8_t>(32, 0)).wkc, 1);
    // Registers whose write acts instead of storing: receive time latch, error counters, SII command.
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0900), {0, 0, 0, 0}).wkc, 1);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0310), {0}).wkc, 1);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0443), {0}).wkc, 1);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0503), {0}).wkc, 1);
    // Locked SyncManager configuration bytes (the SM is enabled) are still a writable register.
    std::vector<std::uint8_t> sm{0x00, 0x1F, 0x10, 0x00, 0x64, 0x00, 0x01, 0x00};
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0820), sm).wkc, 1);
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0820), {0x00, 0x1E}).wkc, 1);
    EXPECT_EQ(b.escx().peek16(0x0820), 0x1F00);
    // The user RAM 0x0F80-0x0FFF is read/write.
    EXPECT_EQ(raw_datagram(*b.seg, 2, phys(0, 0x0F80), {0x5A}).wkc, 1);
    EXPECT_EQ(b.escx().peek(0x0F80), 0x5A);
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
