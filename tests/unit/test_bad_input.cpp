// Bad input never crashes, hangs or reads out of bounds (run under ASan/UBSan with VECAT_SANITIZE=ON).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "common/file.hpp"
#include "master/coe_client.hpp"
#include "test_support.hpp"

using namespace vecat;
using namespace vecat::test;

TEST(BadInput, TruncatedFramesAreDroppedAndCounted) {
    Bench b(2);
    auto good = raw_datagram(*b.seg, 7, phys(0, 0), std::vector<std::uint8_t>(20, 0)).frame;
    std::uint64_t dropped = 0;
    for (std::size_t n = 0; n < 16 + 10 + 20 + 2; ++n) {
        std::vector<std::uint8_t> f(good.begin(), good.begin() + static_cast<long>(n));
        f.resize(std::max<std::size_t>(n, 64));  // the EtherCAT header still claims the whole datagram
        std::size_t len = n;
        EXPECT_FALSE(b.seg->process_frame(f, len, 1)) << n;
        if (n >= 14) ++dropped;
    }
    EXPECT_EQ(b.seg->counters().dropped, dropped);
    EXPECT_EQ(b.escx(0).peek(0x0300), std::min<std::uint64_t>(dropped, 255));
    EXPECT_EQ(b.escx(1).peek(0x0300), 0);  // dropped at the first slave
}

TEST(BadInput, AddressesAtTheEndOfTheSpaces) {
    Bench b(1);
    auto r = raw_datagram(*b.seg, 1, phys(0, 0xFFF0), std::vector<std::uint8_t>(64, 0xEE));
    EXPECT_EQ(r.wkc, 1);
    auto w = raw_datagram(*b.seg, 2, phys(0, 0xFFFF), std::vector<std::uint8_t>(300, 1));
    EXPECT_EQ(w.wkc, 0);  // no memory there: nothing written, not counted
    auto w2 = raw_datagram(*b.seg, 2, phys(0, 0x2FFF), std::vector<std::uint8_t>(300, 1));
    EXPECT_EQ(w2.wkc, 1);  // the last byte of the process RAM is
    auto l = raw_datagram(*b.seg, 12, 0xFFFFFFF0, std::vector<std::uint8_t>(64, 0));
    EXPECT_EQ(l.wkc, 0);
    // An FMMU ending at the top of the logical space.
    std::vector<std::uint8_t> f(16, 0);
    st_le32(f.data(), 0xFFFFFFF0);
    st_le16(f.data() + 4, 0xFFFF);
    f[7] = 7;
    st_le16(f.data() + 8, 0xFFF0);
    f[10] = 3;
    f[11] = 3;
    f[12] = 1;
    raw_datagram(*b.seg, 2, phys(0, 0x0600), f);
    raw_datagram(*b.seg, 12, 0xFFFFFFF0, std::vector<std::uint8_t>(16, 0xA5));
    SUCCEED();
}

TEST(BadInput, RandomFramesNeverCrash) {
    Bench b(3);
    ASSERT_TRUE(b.master.startup(protocol::AlState::Op));
    std::mt19937 rng(20261122);
    std::vector<std::uint8_t> f(1600);
    std::uint64_t replies = 0;
    for (int i = 0; i < 20000; ++i) {
        const std::size_t n = 14 + rng() % 600;
        for (std::size_t k = 0; k < n; ++k)
            f[k] = static_cast<std::uint8_t>(rng());
        f[6] &= 0xFD;
        f[12] = 0x88;
        f[13] = 0xA4;
        if (rng() % 2) st_le16(f.data() + 14, static_cast<std::uint16_t>(0x1000 | ((n - 16) & 0x7FF)));
        std::size_t len = n;
        replies += b.seg->process_frame(f, len, 1'000'000'000 + static_cast<std::uint64_t>(i) * 1000);
        ASSERT_LE(len, f.size());
    }
    EXPECT_GT(replies, 0u);
    EXPECT_GT(b.seg->counters().dropped, 0u);
    // The slaves still answer a well-formed frame afterwards.
    EXPECT_EQ(raw_datagram(*b.seg, 7, phys(0, 0), {0, 0}).wkc, 3);
}

TEST(BadInput, NonsenseAlRequestsGetAStatusCode) {
    Bench b(1);
    ASSERT_TRUE(b.master.startup(protocol::AlState::Init));
    const auto st = b.master.slaves()[0].station;
    ASSERT_TRUE(b.master.write16(st, 0x0120, 0x00FF));
    const auto r = b.master.read_al_status(st);
    EXPECT_TRUE(r.error());
    EXPECT_EQ(r.code, 0x0012);
}

// Random CoE mailbox messages through the real slave: each is answered (data, SDO abort, SDO info error
// or mailbox error), except a master's own abort request, which by CiA 301 gets no answer. Nothing
// crashes and the slave keeps serving valid requests afterwards.
TEST(BadInput, RandomCoeMessagesAlwaysGetAnAnswer) {
    Bench b(1);
    std::string why;
    ASSERT_TRUE(b.master.startup(protocol::AlState::PreOp, &why)) << why;
    const auto st = b.master.slaves()[0].station;
    master::CoeClient c(b.master, st);
    std::mt19937 rng(20261122);
    std::uniform_int_distribution<int> byte(0, 255);
    std::uniform_int_distribution<int> len(0, 240);
    unsigned answered = 0, silent_by_spec = 0;
    for (int i = 0; i < 3000; ++i) {
        std::vector<std::uint8_t> p(static_cast<std::size_t>(len(rng)));
        for (auto& x : p)
            x = static_cast<std::uint8_t>(byte(rng));
        // Bias towards the services that exist, so the SDO and SDO info code is exercised deeply.
        if (p.size() >= 2 && i % 3 != 0)
            p[1] = static_cast<std::uint8_t>((i % 2 ? 0x20 : 0x80) | (p[1] & 0x01));
        const bool master_abort = p.size() >= 3 && (p[1] >> 4) == 2 && (p[2] >> 5) == 4;
        ASSERT_TRUE(c.send(protocol::MailboxType::CoE, p, c.next_counter()));
        auto r = c.receive(std::chrono::milliseconds(master_abort ? 1 : 50));
        if (master_abort && p.size() >= 10) {
            EXPECT_FALSE(r) << "a master abort request is not answered";
            ++silent_by_spec;
            continue;
        }
        ASSERT_TRUE(r) << "message " << i << " of " << p.size() << " bytes got no answer";
        ++answered;
        // Drain fragments of SDO information lists.
        while (r && r->payload.size() >= 3 && (r->payload[1] >> 4) == 8 && (r->payload[2] & 0x80))
            r = c.receive(std::chrono::milliseconds(50));
    }
    EXPECT_GT(answered, 2500u);
    (void)silent_by_spec;
    // Still serving.
    auto v = c.upload(0x1018, 1);
    ASSERT_TRUE(v.ok());
    EXPECT_EQ(ld_le32(v.data.data()), b.desc.identity.vendor_id);
}

// A mailbox protocol that reads every byte it is given: answers with their sum (32 bits) and count.
class SummingProtocol final : public esc::MailboxProtocol {
  public:
    protocol::MailboxType type() const override { return protocol::MailboxType::CoE; }
    void handle(const protocol::MailboxHeader&, ConstBytes payload, esc::MailboxReplySink& out) override {
        std::uint32_t sum = 0;
        for (auto x : payload)
            sum += x;
        auto r = out.reply_buffer();
        st_le32(r.data(), sum);
        st_le32(r.data() + 4, static_cast<std::uint32_t>(payload.size()));
        out.commit(protocol::MailboxType::CoE, 8);
    }
};
class SummingApplication final : public esc::ProcessImageApplication {
  public:
    using ProcessImageApplication::ProcessImageApplication;
    esc::MailboxProtocol* mailbox_protocol(protocol::MailboxType t) override {
        return t == protocol::MailboxType::CoE ? &proto_ : nullptr;
    }

  private:
    SummingProtocol proto_;
};
std::unique_ptr<esc::Segment> summing_segment(const device::DeviceDescription& d, std::size_t n,
                                              const esc::EscConfig& cfg) {
    return esc::make_segment(
        d, n, cfg, [](const device::DeviceDescription& dd) -> std::unique_ptr<esc::Application> {
            return std::make_unique<SummingApplication>(dd.output_bytes(), dd.input_bytes());
        });
}

// A device (from an ESI file) whose mailbox is larger than the usual 1486 bytes: a message filling it
// reaches the protocol whole (the mailbox layer used to hand over 2000 bytes of a 1486-byte buffer).
TEST(BadInput, MailboxLargerThanAnEthernetFrame) {
    auto dev = device::default_drive();
    dev.sync_managers[0] = {0x1000, 2048, 0x26, 0x01, device::SmType::MailboxOut};
    dev.sync_managers[1] = {0x1800, 2048, 0x22, 0x01, device::SmType::MailboxIn};
    dev.sync_managers[2].start = 0x2000;
    dev.sync_managers[3].start = 0x2100;
    Bench b(1, {}, dev, &summing_segment);
    std::string why;
    ASSERT_TRUE(b.master.startup(protocol::AlState::PreOp, &why)) << why;
    const auto st = b.master.slaves()[0].station;
    // 2000 bytes of 0x01 after the header, written in two datagrams (no frame holds 2048 bytes).
    std::vector<std::uint8_t> m(2048, 0x01);
    st_le16(&m[0], 2000);
    st_le16(&m[2], 0);
    m[4] = 0;
    m[5] = 0x13;  // CoE, counter 1
    ASSERT_EQ(b.master.fpwr(st, 0x1000, Bytes(m.data(), 1024)), 1);
    ASSERT_EQ(b.master.fpwr(st, 0x1000 + 1024, Bytes(m.data() + 1024, 1024)), 1);
    b.advance(1'000'000);
    std::vector<std::uint8_t> r(1024);
    ASSERT_EQ(b.master.fprd(st, 0x1800, Bytes(r.data(), r.size())), 1);
    EXPECT_EQ(r[5] & 0x0F, 0x03);
    EXPECT_EQ(ld_le32(&r[10]), 2000u) << "payload bytes handed over";
    EXPECT_EQ(ld_le32(&r[6]), 2000u) << "sum of the payload";
}

// Input files are read with a limit: a device that never ends (/dev/zero) or a file past it is refused, not
// read for ever; what can be read comes back whole.
TEST(BadInput, InputFilesAreReadWithALimit) {
    std::string why;
    EXPECT_FALSE(read_whole_file("/dev/zero", 1u << 20, why).has_value());
    EXPECT_EQ(why, "is larger than 1 MiB");
    EXPECT_FALSE(read_whole_file("/nonexistent/vecat-file", 1u << 20, why).has_value());
    EXPECT_EQ(why, "cannot be read");
    const auto path = (std::filesystem::temp_directory_path() / "vecat-read-whole-file").string();
    std::string text(200'000, 'x');
    text[123'456] = '\0';
    std::ofstream(path, std::ios::binary) << text;
    EXPECT_EQ(read_whole_file(path, text.size(), why).value_or(""), text);
    EXPECT_FALSE(read_whole_file(path, text.size() - 1, why).has_value());
    std::filesystem::remove(path);
}
