// Frame parser: bounds and structure checks.
#include <gtest/gtest.h>

#include <vector>

#include "protocol/frame.hpp"

using namespace vecat;
using namespace vecat::protocol;

namespace {
std::vector<std::uint8_t> frame(std::initializer_list<std::uint16_t> lens, bool vlan = false) {
    std::vector<std::uint8_t> f(12, 0xFF);
    if (vlan) f.insert(f.end(), {0x81, 0x00, 0x00, 0x01});
    f.insert(f.end(), {0x88, 0xA4, 0, 0});
    const std::size_t hdr = f.size() - 2;
    std::size_t total = 0, i = 0;
    for (auto l : lens) {
        std::vector<std::uint8_t> d(10 + l + 2, 0);
        d[0] = 4;
        st_le16(d.data() + 6, static_cast<std::uint16_t>(l | (++i < lens.size() ? 0x8000 : 0)));
        f.insert(f.end(), d.begin(), d.end());
        total += d.size();
    }
    st_le16(f.data() + hdr, static_cast<std::uint16_t>(total | 0x1000));
    return f;
}
}  // namespace

TEST(Datagram, ParsesSeveralDatagrams) {
    auto f = frame({2, 4, 0});
    auto pf = parse_frame(f);
    ASSERT_EQ(pf.error, FrameError::None);
    ASSERT_EQ(pf.count, 3u);
    EXPECT_EQ(pf.datagram(f, 1).length(), 4);
    EXPECT_EQ(pf.datagram(f, 0).command(), Command::FPRD);
    EXPECT_FALSE(pf.datagram(f, 2).more());
}

TEST(Datagram, AcceptsVlanTag) {
    auto f = frame({2}, true);
    EXPECT_EQ(parse_frame(f).error, FrameError::None);
}

TEST(Datagram, RejectsEveryTruncation) {
    auto f = frame({8, 8});
    for (std::size_t n = 0; n < f.size(); ++n)
        EXPECT_NE(parse_frame(ConstBytes(f.data(), n)).error, FrameError::None) << n;
}

TEST(Datagram, RejectsDatagramLengthPastTheEnd) {
    auto f = frame({4});
    st_le16(f.data() + 16 + 6, 40);  // datagram claims 40 bytes
    EXPECT_EQ(parse_frame(f).error, FrameError::DatagramOverrun);
    auto g = frame({4});
    st_le16(g.data() + 14, 0x1000 | 200);  // header length past the frame
    EXPECT_EQ(parse_frame(g).error, FrameError::HeaderLength);
    auto h = frame({4});
    st_le16(h.data() + 16 + 6, 4 | 0x8000);  // "more" set but nothing follows
    EXPECT_EQ(parse_frame(h).error, FrameError::DatagramOverrun);
}

TEST(Datagram, OtherTypesAreRecognised) {
    auto f = frame({2});
    f[12] = 0x08;
    f[13] = 0x00;
    EXPECT_EQ(parse_frame(f).error, FrameError::NotEtherCat);
    auto g = frame({2});
    g[15] = 0x40;  // EtherCAT type 4 (network variables)
    EXPECT_EQ(parse_frame(g).error, FrameError::NotCommands);
}
