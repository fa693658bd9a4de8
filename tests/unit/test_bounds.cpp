// Bounded buffers and queues: the capture file stops at its limit; the mailbox reply queue of a slave
// drops (and counts) replies the master does not read instead of growing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "net/pcapng_writer.hpp"
#include "pcapng_reader.hpp"
#include "test_support.hpp"

using namespace vecat;

TEST(Bounds, CaptureFileStopsAtItsLimit) {
    const std::string path =
        (std::filesystem::temp_directory_path() / ("vecat-bounds-" + std::to_string(::getpid()) + ".pcapng"))
            .string();
    constexpr std::uint64_t kLimit = 4096;
    std::uint64_t written = 0;
    {
        net::PcapngWriter w(path, "test", kLimit);
        const std::vector<std::uint8_t> frame(60, 0xAB);
        for (int i = 0; i < 200; ++i)
            w.write(frame, 1'000'000'000ull * 1700000000ull + static_cast<std::uint64_t>(i), 1);
        EXPECT_EQ(w.frames() + w.dropped(), 200u);
        EXPECT_GT(w.dropped(), 0u);
        EXPECT_LE(w.bytes(), kLimit);
        written = w.frames();
    }
    EXPECT_LE(std::filesystem::file_size(path), kLimit);
    EXPECT_EQ(test::read_pcapng_frames(path).size(), written) << "the file stays readable";
    std::filesystem::remove(path);
}

TEST(Bounds, UnreadMailboxRepliesAreDroppedAndCounted) {
    test::Bench b(1);
    std::string why;
    ASSERT_TRUE(b.master.startup(protocol::AlState::PreOp, &why)) << why;
    const auto st = b.master.slaves()[0].station;
    const auto sm0 = b.desc.sync_managers[0];
    constexpr int kRequests = 20;
    for (int i = 0; i < kRequests; ++i) {
        // SDO upload 0x1000:00; counters 1..7 in turn so none is taken for a repeated request.
        std::vector<std::uint8_t> m(sm0.length, 0);
        m[0] = 10;
        m[5] = static_cast<std::uint8_t>(0x03 | ((i % 7 + 1) << 4));
        const std::uint8_t req[] = {0x00, 0x20, 0x40, 0x00, 0x10, 0x00};
        std::copy(std::begin(req), std::end(req), m.begin() + 6);
        ASSERT_EQ(b.master.fpwr(st, sm0.start, Bytes(m.data(), m.size())), 1);
        b.advance(100'000);
    }
    // One reply in SM1, eight queued, the rest dropped.
    const auto& c = b.slave().counters();
    EXPECT_EQ(c.mailbox_requests, static_cast<std::uint64_t>(kRequests));
    EXPECT_EQ(c.mailbox_replies_dropped, static_cast<std::uint64_t>(kRequests - 1 - 8));
}
