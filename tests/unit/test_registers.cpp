// Register semantics: information registers, read-only bits, write masks, side effects.
#include <gtest/gtest.h>

#include <random>

#include "esc/sii_image.hpp"
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

// One datagram writing a run of registers against the rules of src/esc/README.md applied byte by byte (the
// model below: the write mask of the register table, AL control refused while unread, SyncManager
// configuration locked while enabled, an absent DC unit, a single-byte SyncManager on the digital output
// register, AL status set by device emulation). The ESC handles a run that touches none of the registers
// with rules of their own as one masked copy, the others byte by byte: runs of 1 to 24 bytes at every
// address of the register space (into the process RAM at its end), with random data, cross every border
// between the two. Bytes that the write's side effects change afterwards (DL status, AL events, error and
// watchdog counters, the SII interface, SM status, the DC unit) are not compared here; their tests are
// above and in test_dc.cpp.
TEST(Registers, AWriteRunStoresAndCountsAsItsBytesOneByOne) {
    struct Scenario {
        const char* name;
        bool al_control_unread = false;
        bool dc_system_time_unit = true;
        bool digital_io = false;
    };
    const Scenario scenarios[] = {{"plain ESC", false, true, false},
                                  {"AL control unread", true, true, false},
                                  {"no DC system time unit", false, false, false},
                                  {"digital I/O with SM2 on 0x0F00", false, true, true}};
    auto excluded = [](unsigned a) {
        return (a >= 0x0110 && a < 0x0112) || (a >= 0x0220 && a < 0x0224) || (a >= 0x0300 && a < 0x0314) ||
               a == 0x0442 || a == 0x0443 || (a >= 0x0500 && a < 0x0510) ||
               (a >= 0x0800 && a < 0x0880 && (a & 7) == 5) || (a >= 0x0900 && a < 0x0A00);
    };
    std::mt19937 rng(24);
    for (const Scenario& sc : scenarios) {
        auto dev = device::default_drive();
        if (sc.digital_io) dev.pdi_control = 0x0104;
        const std::vector<std::uint8_t> sii = esc::build_sii_image(dev);
        esc::EscConfig cfg;
        cfg.dc_system_time_unit = sc.dc_system_time_unit;
        const auto table = protocol::make_write_mask_table(cfg.fmmu_count, cfg.sm_count);
        for (unsigned a = 0; a < protocol::kRegisterSpaceSize; ++a) {
            const unsigned len = 1 + (a * 7 + (a >> 4)) % 24;
            esc::Esc esc(cfg, sii);
            // SM0 enabled (its configuration locked); SM2 on the digital output register where there is one.
            std::vector<std::uint8_t> sm0{0x00, 0x18, 0x80, 0x00, 0x26, 0x00, 0x01, 0x00};
            ASSERT_EQ(esc_datagram(esc, protocol::Command::APWR, protocol::sm_addr(0), sm0), 1);
            if (sc.digital_io) {
                std::vector<std::uint8_t> sm2{0x00, 0x0F, 0x01, 0x00, 0x44, 0x00, 0x01, 0x00};
                ASSERT_EQ(esc_datagram(esc, protocol::Command::APWR, protocol::sm_addr(2), sm2), 1);
            }
            if (sc.al_control_unread) {
                std::vector<std::uint8_t> al{0x02, 0x00};
                ASSERT_EQ(esc_datagram(esc, protocol::Command::APWR, 0x0120, al), 1);
            }
            std::vector<std::uint8_t> before(protocol::kRegisterSpaceSize + 24), data(len);
            for (unsigned k = 0; k < before.size(); ++k)
                before[k] = esc.peek(static_cast<std::uint16_t>(k));
            for (auto& v : data)
                v = static_cast<std::uint8_t>(rng());
            // The model, byte by byte on the memory before the write.
            std::vector<std::uint8_t> expected(before);
            bool counted = false;
            for (unsigned k = 0; k < len; ++k) {
                const unsigned ad = a + k;
                const std::uint8_t v = data[k];
                if (ad >= protocol::kRegisterSpaceSize) {  // process RAM without SyncManager
                    expected[ad] = v;
                    counted = true;
                    continue;
                }
                if (!sc.dc_system_time_unit && ad >= 0x0910 && ad < 0x0A00) continue;
                if ((ad == 0x0120 || ad == 0x0121) && sc.al_control_unread) continue;
                const bool dout = ad >= 0x0F00 && ad < 0x0F04;  // the digital output register
                if (dout && !sc.digital_io) continue;           // absent
                if (dout) {  // 0x0F00 through SM2 (one byte: no buffer), the rest as plain registers
                    expected[ad] = v;
                    counted = true;
                    continue;
                }
                std::uint8_t m = table.mask[ad];
                if (ad >= 0x0800 && ad < protocol::sm_addr(cfg.sm_count) && (ad & 7) < 5 &&
                    (before[(ad & ~7u) + 6] & 1))
                    m = 0;
                expected[ad] = static_cast<std::uint8_t>((before[ad] & ~m) | (v & m));
                counted |= table.writable(static_cast<std::uint16_t>(ad));
            }
            // Device emulation (the digital I/O ESC's SII): AL status takes what AL control holds after a
            // write.
            if (esc.device_emulation() && a <= 0x0121 && a + len > 0x0120) {
                expected[0x0130] = expected[0x0120];
                expected[0x0131] = expected[0x0121];
            }
            std::vector<std::uint8_t> frame_data(data);
            const std::uint16_t wkc =
                esc_datagram(esc, protocol::Command::APWR, static_cast<std::uint16_t>(a), frame_data);
            ASSERT_EQ(wkc, counted ? 1 : 0)
                << sc.name << " at 0x" << std::hex << a << " length " << std::dec << len;
            for (unsigned k = a; k < a + len; ++k) {
                if (excluded(k)) continue;
                ASSERT_EQ(esc.peek(static_cast<std::uint16_t>(k)), expected[k])
                    << sc.name << ": byte 0x" << std::hex << k << " of the write at 0x" << a << std::dec
                    << " length " << len;
            }
        }
    }
}

// A write that covers part of the system time (0x0910-0x0917) and read-only registers around it feeds the
// time control loop with exactly the bytes of the system time it covers, the others being the ESC's own
// (ETG.1000.4 9.1.3.4: a 32-bit write is compared in 32 bits). With the filter depth 0, the system time
// difference 0x092C shows what the loop received less the ESC's time: |diff|, bit 31 when the local copy is
// smaller.
TEST(Registers, APartialSystemTimeWriteFeedsTheLoopWithItsBytes) {
    const std::vector<std::uint8_t> sii = esc::build_sii_image(device::default_drive());
    struct Case {
        std::uint16_t at;
        std::size_t len;
        std::int64_t delta;  // the received time less the ESC's, put into the bytes written
    };
    for (const Case c : {Case{0x090C, 8, 0x1234}, Case{0x090E, 4, -0x0567}, Case{0x0900, 0x20, 0x345678},
                         Case{0x0913, 2, 0x05000000}, Case{0x0910, 8, -77}}) {
        esc::Esc esc(esc::EscConfig{}, sii);
        std::vector<std::uint8_t> depth{0x00};
        ASSERT_EQ(esc_datagram(esc, protocol::Command::APWR, 0x0934, depth), 1);
        std::vector<std::uint8_t> mine(8);
        ASSERT_EQ(esc_datagram(esc, protocol::Command::APRD, 0x0910, mine), 1);
        std::vector<std::uint8_t> sent(8);
        st_le64(sent.data(), ld_le64(mine.data()) + static_cast<std::uint64_t>(c.delta));
        std::vector<std::uint8_t> w(c.len, 0xA5), received(mine);
        bool upper = false;
        for (std::size_t k = 0; k < c.len; ++k) {
            const std::size_t b = c.at + k - 0x0910;
            if (c.at + k < 0x0910 || b >= 8) continue;
            w[k] = received[b] = sent[b];
            upper |= b >= 4;
        }
        EXPECT_EQ(esc_datagram(esc, protocol::Command::APWR, c.at, w), 1);
        EXPECT_EQ(esc.dc().counters().system_time_writes, 1u) << std::hex << c.at;
        const std::uint64_t r = ld_le64(received.data()), m = ld_le64(mine.data());
        const std::int64_t diff =
            upper ? static_cast<std::int64_t>(r - m)
                  : static_cast<std::int32_t>(static_cast<std::uint32_t>(r) - static_cast<std::uint32_t>(m));
        ASSERT_LT(diff < 0 ? -diff : diff, 0x7FFFFFFF) << std::hex << c.at;
        const auto mag = static_cast<std::uint32_t>(diff < 0 ? -diff : diff);
        EXPECT_EQ(esc.peek32(0x092C), mag | (diff > 0 ? 0x80000000u : 0u)) << std::hex << c.at;
    }
}
