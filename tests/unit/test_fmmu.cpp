// FMMU mapping: bytes, bits, register space.
#include <gtest/gtest.h>

#include "test_support.hpp"

using namespace vecat;
using namespace vecat::test;

namespace {
std::vector<std::uint8_t> fmmu(std::uint32_t log, std::uint16_t len, std::uint8_t sbit, std::uint8_t ebit,
                               std::uint16_t phys_addr, std::uint8_t pbit, std::uint8_t type) {
    std::vector<std::uint8_t> f(16, 0);
    st_le32(f.data(), log);
    st_le16(f.data() + 4, len);
    f[6] = sbit;
    f[7] = ebit;
    st_le16(f.data() + 8, phys_addr);
    f[10] = pbit;
    f[11] = type;
    f[12] = 1;
    return f;
}
}  // namespace

TEST(Fmmu, ByteMappingReadAndWrite) {
    Bench b(1);
    raw_datagram(*b.seg, 2, phys(0, 0x0600), fmmu(0x1000, 4, 0, 7, 0x2000, 0, 2));
    raw_datagram(*b.seg, 2, phys(0, 0x0610), fmmu(0x1004, 2, 0, 7, 0x2100, 0, 1));
    raw_datagram(*b.seg, 2, phys(0, 0x2100), {0xAB, 0xCD});
    auto r = raw_datagram(*b.seg, 12, 0x0FFE, {9, 9, 1, 2, 3, 4, 0, 0, 7});
    EXPECT_EQ(r.wkc, 3);
    EXPECT_EQ(r.data, (std::vector<std::uint8_t>{9, 9, 1, 2, 3, 4, 0xAB, 0xCD, 7}));
    EXPECT_EQ(b.escx().peek32(0x2000), 0x04030201u);
}

TEST(Fmmu, BitGranularMapping) {
    Bench b(1);
    // Logical bits 0x300.3 .. 0x300.5 -> physical 0x2200.6 .. 0x2201.0
    raw_datagram(*b.seg, 2, phys(0, 0x0600), fmmu(0x300, 1, 3, 5, 0x2200, 6, 2));
    raw_datagram(*b.seg, 2, phys(0, 0x2200), {0x0F, 0xF0});
    auto w = raw_datagram(*b.seg, 11, 0x300, {0b00101000});  // bits 3 and 5 set, bit 4 clear
    EXPECT_EQ(w.wkc, 1);
    EXPECT_EQ(b.escx().peek(0x2200), 0x0F | 0x40);  // bit 6 <- bit 3, bit 7 <- bit 4 (0)
    EXPECT_EQ(b.escx().peek(0x2201), 0xF1);         // bit 0 <- bit 5, the other bits untouched
    // Read back through a read FMMU on the same bits.
    raw_datagram(*b.seg, 2, phys(0, 0x0610), fmmu(0x400, 1, 1, 3, 0x2200, 6, 1));
    auto r = raw_datagram(*b.seg, 10, 0x400, {0x00});
    EXPECT_EQ(r.wkc, 1);
    EXPECT_EQ(r.data[0], 0b00001010);  // bits 1..3 = 1,0,1
}

TEST(Fmmu, MapsRegisterSpaceLikeSoemMailboxStatus) {
    Bench b(1);
    ASSERT_TRUE(b.master.startup(protocol::AlState::PreOp));
    const auto st = b.master.slaves()[0].station;
    raw_datagram(*b.seg, 5, phys(st, 0x0620), fmmu(0x9000, 1, 0, 7, 0x080D, 0, 1));
    auto empty = raw_datagram(*b.seg, 10, 0x9000, {0});
    EXPECT_EQ(empty.wkc, 1);
    EXPECT_EQ(empty.data[0] & 0x08, 0);
    std::vector<std::uint8_t> reply(246, 0);
    ASSERT_TRUE(b.escx().pdi_mailbox_put(1, reply));
    auto full = raw_datagram(*b.seg, 10, 0x9000, {0});
    EXPECT_EQ(full.data[0] & 0x08, 0x08);
}

TEST(Fmmu, InactiveOrDisjointFmmuDoesNotCount) {
    Bench b(1);
    auto f = fmmu(0x100, 4, 0, 7, 0x2000, 0, 3);
    f[12] = 0;
    raw_datagram(*b.seg, 2, phys(0, 0x0600), f);
    EXPECT_EQ(raw_datagram(*b.seg, 12, 0x100, {1, 2, 3, 4}).wkc, 0);
    f[12] = 1;
    raw_datagram(*b.seg, 2, phys(0, 0x0600), f);
    EXPECT_EQ(raw_datagram(*b.seg, 12, 0x104, {1, 2}).wkc, 0);
    EXPECT_EQ(raw_datagram(*b.seg, 12, 0x102, {1, 2, 3, 4}).wkc, 3);  // partial overlap counts
    EXPECT_EQ(b.escx().peek16(0x2002), 0x0201);
}
