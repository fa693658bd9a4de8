#include <gtest/gtest.h>

#include <vector>

#include "common/bytes.hpp"

using namespace vecat;

TEST(Bytes, LittleEndianRoundTrip) {
    std::uint8_t b[8] = {};
    st_le16(b, 0x1234);
    EXPECT_EQ(b[0], 0x34);
    EXPECT_EQ(b[1], 0x12);
    st_le32(b, 0xA1B2C3D4);
    EXPECT_EQ(ld_le32(b), 0xA1B2C3D4u);
    EXPECT_EQ(b[0], 0xD4);
    st_le64(b, 0x0102030405060708ull);
    EXPECT_EQ(ld_le64(b), 0x0102030405060708ull);
    EXPECT_EQ(b[7], 0x01);
}

TEST(Bytes, CheckedReadsRefusePastTheEnd) {
    const std::uint8_t b[3] = {1, 2, 3};
    EXPECT_EQ(read_le16(b, 1).value(), 0x0302);
    EXPECT_FALSE(read_le16(b, 2).has_value());
    EXPECT_FALSE(read_le32(b, 0).has_value());
    EXPECT_FALSE(read_u8(b, 3).has_value());
    EXPECT_FALSE(read_le64(b, SIZE_MAX).has_value());
    std::uint8_t w[3] = {};
    EXPECT_FALSE(write_le32(w, 0, 1));
    EXPECT_TRUE(write_le16(w, 1, 0xBEEF));
    EXPECT_EQ(w[2], 0xBE);
}

TEST(Bytes, WriterAppendsLittleEndian) {
    std::vector<std::uint8_t> v;
    LeWriter w(v);
    w.u8(1);
    w.u16(0x0302);
    w.u32(0x07060504);
    EXPECT_EQ(v, (std::vector<std::uint8_t>{1, 2, 3, 4, 5, 6, 7}));
}
