// Replay of real traffic: the CoE mailbox requests SOEM sent to a Kollmorgen AKD servo drive
// (../shared/data/pcap/soem-slaveinfo-sdo-kollmorgen-akd.pcapng) are sent to vecat, and each reply must
// have the layout the real drive's reply had (mailbox type, length, CoE service, SDO command, index and
// subindex), and tshark must decode the whole replayed exchange without errors.
#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>

#include "master/coe_client.hpp"
#include "net/pcapng_writer.hpp"
#include "net/recording_link.hpp"
#include "pcapng_reader.hpp"
#include "shared_data.hpp"
#include "test_support.hpp"

using namespace vecat;

namespace {

struct Mailbox {
    std::vector<std::uint8_t> bytes;  // header + payload
};

// The mailbox content of single-datagram frames with the given source MAC, command and address.
std::vector<Mailbox> mailboxes(const std::vector<std::vector<std::uint8_t>>& frames, std::uint8_t src0,
                               std::uint8_t cmd, std::uint16_t ado) {
    std::vector<Mailbox> out;
    for (const auto& f : frames) {
        if (f.size() < 14 + 2 + 10 + 6 || f[6] != src0 || f[12] != 0x88 || f[13] != 0xA4) continue;
        const std::uint8_t* dg = f.data() + 16;
        if (dg[0] != cmd || ld_le16(dg + 4) != ado) continue;
        const std::size_t len = ld_le16(dg + 6) & 0x07FF;
        if (16 + 10 + len > f.size() || len < 6) continue;
        const std::uint8_t* mbx = dg + 10;
        const std::size_t mlen = ld_le16(mbx);
        if ((mbx[5] & 0x0F) != 0x03 || 6 + mlen > len) continue;  // CoE only
        out.push_back({std::vector<std::uint8_t>(mbx, mbx + 6 + mlen)});
    }
    return out;
}

}  // namespace

TEST(Replay, SoemRequestsToARealAkdGetRepliesOfTheSameLayout) {
    VECAT_REQUIRE_SHARED_DATA("pcap/soem-slaveinfo-sdo-kollmorgen-akd.pcapng");
    const std::string src = test::shared_data("pcap/soem-slaveinfo-sdo-kollmorgen-akd.pcapng");
    const auto frames = test::read_pcapng_frames(src);
    // Given: the requests SOEM wrote into the AKD's SM0 (0x1800) and the replies read from its SM1 (0x1C00).
    const auto requests = mailboxes(frames, 0x01, 0x05 /*FPWR*/, 0x1800);
    const auto replies = mailboxes(frames, 0x03, 0x04 /*FPRD*/, 0x1C00);
    ASSERT_EQ(requests.size(), 35u);
    ASSERT_EQ(replies.size(), requests.size());

    const std::string out = (std::filesystem::temp_directory_path() /
                             ("vecat-akd-replay-" + std::to_string(getpid()) + ".pcapng"))
                                .string();
    {
        test::Bench b(1);
        net::PcapngWriter w(out);
        net::RecordingLink rec(b.link, w);
        master::Master m(rec);
        std::string why;
        ASSERT_TRUE(m.startup(protocol::AlState::PreOp, &why)) << why;
        master::CoeClient c(m, m.slaves()[0].station);
        for (std::size_t i = 0; i < requests.size(); ++i) {
            const auto& rq = requests[i].bytes;
            const auto& real = replies[i].bytes;
            // When: the same CoE request, with the same mailbox counter, goes to vecat.
            ASSERT_TRUE(
                c.send(protocol::MailboxType::CoE, ConstBytes(rq.data() + 6, rq.size() - 6), rq[5] >> 4));
            auto rsp = c.receive();
            ASSERT_TRUE(rsp) << "request " << i << " got no reply";
            // Then: the reply is laid out like the real drive's.
            SCOPED_TRACE("request " + std::to_string(i) + " for 0x" + std::to_string(ld_le16(rq.data() + 9)));
            EXPECT_EQ(rsp->header.type, real[5] & 0x0F);
            EXPECT_EQ(rsp->header.length, ld_le16(real.data()));
            ASSERT_GE(rsp->payload.size(), 10u);
            EXPECT_EQ(ld_le16(rsp->payload.data()), ld_le16(real.data() + 6));  // CoE header: SDO response
            EXPECT_EQ(rsp->payload[2], real[8]);  // command: expedited, same size
            EXPECT_EQ(ld_le16(rsp->payload.data() + 3), ld_le16(real.data() + 9));
            EXPECT_EQ(rsp->payload[5], real[11]);
        }
        w.flush();
    }
    if (system("command -v tshark >/dev/null 2>&1") != 0) {
        std::filesystem::remove(out);
        GTEST_SKIP() << "tshark not installed";
    }
    const std::string verbose = test::run_capture("tshark -r " + out + " -V 2>/dev/null");
    EXPECT_EQ(verbose.find("Malformed"), std::string::npos);
    EXPECT_EQ(test::run_capture("tshark -r " + out + " -z expert,error -q 2>/dev/null").find("Error"),
              std::string::npos);
    // Every request and reply was decoded as CoE with an SDO index.
    const std::string sdo = test::run_capture(
        "tshark -r " + out + " -Y ecat_mailbox.coe.sdoidx -T fields -e frame.number 2>/dev/null");
    EXPECT_GE(std::count(sdo.begin(), sdo.end(), '\n'), 70);
    std::filesystem::remove(out);
}
