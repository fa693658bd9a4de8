// Working counter and addressing rules of every command (ETG.1000.4 Table 13), on a line of 3 slaves.
#include <gtest/gtest.h>

#include "test_support.hpp"

using namespace vecat;
using namespace vecat::test;
using protocol::Command;

namespace {
constexpr std::uint8_t c(Command x) {
    return static_cast<std::uint8_t>(x);
}

struct Line : ::testing::Test {
    Bench b{3};
    void SetUp() override {
        for (std::uint16_t i = 0; i < 3; ++i) {
            std::vector<std::uint8_t> a{static_cast<std::uint8_t>(0x01 + i), 0x10};
            ASSERT_EQ(
                raw_datagram(*b.seg, c(Command::APWR), phys(static_cast<std::uint16_t>(-i), 0x0010), a).wkc,
                1);
        }
    }
};
}  // namespace

TEST_F(Line, BroadcastReadCountsEverySlaveAndIncrementsAdp) {
    auto r = raw_datagram(*b.seg, c(Command::BRD), phys(0, 0x0000), {0, 0});
    EXPECT_EQ(r.wkc, 3);
    EXPECT_EQ(r.adp, 3);
    EXPECT_EQ(r.data[0], 0x11);  // ESC type
}

TEST_F(Line, BroadcastReadOrsTheData) {
    // Station addresses 0x1001..0x1003: the low bytes OR together.
    auto r = raw_datagram(*b.seg, c(Command::BRD), phys(0, 0x0010), {0, 0});
    EXPECT_EQ(r.data[0], 0x01 | 0x02 | 0x03);
    EXPECT_EQ(r.data[1], 0x10);
}

TEST_F(Line, BroadcastWriteAndReadWrite) {
    EXPECT_EQ(raw_datagram(*b.seg, c(Command::BWR), phys(0, 0x0138), {0x05}).wkc, 3);
    EXPECT_EQ(b.escx(2).peek(0x0138), 0x05);
    auto r = raw_datagram(*b.seg, c(Command::BRW), phys(0, 0x0138), {0x02});
    EXPECT_EQ(r.wkc, 9);
    EXPECT_EQ(r.data[0], 0x05 | 0x02);  // OR of the old contents with the incoming data
    EXPECT_EQ(b.escx(0).peek(0x0138), 0x02);
    EXPECT_EQ(b.escx(1).peek(0x0138), 0x07);  // each slave writes the data as its predecessor left it
}

TEST_F(Line, AutoIncrementAddressesOneSlaveByPosition) {
    for (int pos = 0; pos < 4; ++pos) {
        auto r =
            raw_datagram(*b.seg, c(Command::APRD), phys(static_cast<std::uint16_t>(-pos), 0x0010), {0, 0});
        EXPECT_EQ(r.wkc, pos < 3 ? 1 : 0) << pos;
        EXPECT_EQ(r.adp, static_cast<std::uint16_t>(-pos + 3));
        if (pos < 3) {
            EXPECT_EQ(r.data[0], 0x01 + pos);
        }
    }
    EXPECT_EQ(raw_datagram(*b.seg, c(Command::APWR), phys(0xFFFF, 0x0138), {0x07}).wkc, 1);
    EXPECT_EQ(b.escx(1).peek(0x0138), 0x07);
    auto rw = raw_datagram(*b.seg, c(Command::APRW), phys(0xFFFF, 0x0138), {0x03});
    EXPECT_EQ(rw.wkc, 3);
    EXPECT_EQ(rw.data[0], 0x07);
    EXPECT_EQ(b.escx(1).peek(0x0138), 0x03);
}

TEST_F(Line, FixedAddressing) {
    EXPECT_EQ(raw_datagram(*b.seg, c(Command::FPRD), phys(0x1002, 0x0010), {0, 0}).wkc, 1);
    EXPECT_EQ(raw_datagram(*b.seg, c(Command::FPRD), phys(0x1009, 0x0010), {0, 0}).wkc, 0);
    EXPECT_EQ(raw_datagram(*b.seg, c(Command::FPWR), phys(0x1003, 0x0138), {0x09}).wkc, 1);
    EXPECT_EQ(b.escx(2).peek(0x0138), 0x09);
    auto r = raw_datagram(*b.seg, c(Command::FPRW), phys(0x1003, 0x0138), {0x01});
    EXPECT_EQ(r.wkc, 3);
    EXPECT_EQ(r.data[0], 0x09);
    EXPECT_EQ(r.adp, 0x1003);  // FP commands never change ADP
}

TEST(AliasAddressing, OnlyWhenEnabledInDlControl) {
    auto dev = device::default_drive();
    dev.station_alias = 0x0777;
    Bench b(1, {}, dev);
    EXPECT_EQ(b.escx().peek16(0x0012), 0x0777);
    EXPECT_EQ(raw_datagram(*b.seg, 4, phys(0x0777, 0x0012), {0, 0}).wkc, 0);
    EXPECT_EQ(raw_datagram(*b.seg, 8, phys(0, 0x0103), {0x01}).wkc, 1);
    auto r = raw_datagram(*b.seg, 4, phys(0x0777, 0x0012), {0, 0});
    EXPECT_EQ(r.wkc, 1);
    EXPECT_EQ(r.data[0], 0x77);
}

TEST_F(Line, ReadMultipleWrite) {
    // ARMW: the slave at position 0 reads, all others write (reference clock distribution).
    raw_datagram(*b.seg, c(Command::APWR), phys(0, 0x0108), {0x34, 0x12});
    auto r = raw_datagram(*b.seg, c(Command::ARMW), phys(0, 0x0108), {0, 0});
    EXPECT_EQ(r.wkc, 3);
    EXPECT_EQ(r.adp, 3);
    EXPECT_EQ(ld_le16(r.data.data()), 0x1234);
    EXPECT_EQ(b.escx(2).peek16(0x0108), 0x1234);
    // FRMW: the addressed slave reads, the others write.
    raw_datagram(*b.seg, c(Command::FPWR), phys(0x1002, 0x0108), {0x78, 0x56});
    auto f = raw_datagram(*b.seg, c(Command::FRMW), phys(0x1002, 0x0108), {0, 0});
    EXPECT_EQ(f.wkc, 3);
    EXPECT_EQ(ld_le16(f.data.data()), 0x5678);
    EXPECT_EQ(b.escx(0).peek16(0x0108),
              0x0000);  // slave 0 comes before the reader: it writes the incoming data
    EXPECT_EQ(b.escx(2).peek16(0x0108), 0x5678);
}

TEST_F(Line, NopAndUnknownCommandsPassUntouched) {
    auto n = raw_datagram(*b.seg, c(Command::NOP), phys(0, 0x0000), {0xAA, 0xBB});
    EXPECT_EQ(n.wkc, 0);
    EXPECT_EQ(n.data[0], 0xAA);
    auto u = raw_datagram(*b.seg, 0x0F, phys(0, 0x0000), {0xAA});
    EXPECT_TRUE(u.replied);
    EXPECT_EQ(u.wkc, 0);
    EXPECT_EQ(u.data[0], 0xAA);
    EXPECT_EQ(u.adp, 0);
}

TEST(LogicalCommands, WorkingCounterPerFmmuDirection) {
    Bench b(3);
    std::string why;
    ASSERT_TRUE(b.master.startup(protocol::AlState::SafeOp, &why)) << why;
    EXPECT_EQ(b.master.expected_wkc(), 9);
    EXPECT_EQ(b.master.exchange_process_data().value(), 9);  // LRW: 3 x (1 read + 2 write)
    const std::uint32_t base = 0x00010000;
    std::vector<std::uint8_t> img(3 * 16 + 3 * 28, 0);
    EXPECT_EQ(b.master.transact_logical(Command::LRD, base, img).value(), 3);
    EXPECT_EQ(b.master.transact_logical(Command::LWR, base, img).value(), 3);
    std::vector<std::uint8_t> outs(3 * 16, 0);
    EXPECT_EQ(b.master.transact_logical(Command::LRW, base, outs).value(), 6);  // only write FMMUs match
    std::vector<std::uint8_t> none(8, 0);
    EXPECT_EQ(b.master.transact_logical(Command::LRW, 0x00F00000, none).value(), 0);
}

TEST(Frames, SeveralDatagramsEachGetTheirOwnCounter) {
    Bench b(2);
    std::uint8_t d0[2] = {}, d1[2] = {}, d2[1] = {0x3};
    master::DatagramRequest dg[3] = {{Command::BRD, 0, Bytes(d0, 2)},
                                     {Command::APRD, 0xFFFF, Bytes(d1, 2)},
                                     {Command::BWR, 0x01380000, Bytes(d2, 1)}};
    ASSERT_TRUE(b.master.transact_frame(dg));
    EXPECT_EQ(dg[0].wkc, 2);
    EXPECT_EQ(dg[1].wkc, 1);
    EXPECT_EQ(dg[2].wkc, 2);
}

TEST(Frames, ReplyIsMarkedAndPadded) {
    Bench b(1);
    auto r = raw_datagram(*b.seg, 7, phys(0, 0), {0, 0});
    ASSERT_TRUE(r.replied);
    EXPECT_EQ(r.frame.size(), 60u);
    EXPECT_EQ(r.frame[6], 0x12);  // 0x10 | 0x02
    EXPECT_EQ(r.frame[7], 0x10);
}
