// EoE (ETG.1000.6 5.7): the wire layout of protocol/eoe.hpp (round trips and bytes as other stacks put
// them), and the EoE server of a slave driven by the project's master over an in-process link: reassembly
// of fragments (in order, overlapping, out of order, never completed, too large), frames fragmented to the
// master, set/get IP parameter and address filter with every result code the server answers, the device's
// ARP and ICMP echo answers, the address filter on frames to the master, and CoE and process data going on
// throughout. About 650 lines: one protocol, each case its own test.
#include <gtest/gtest.h>

#include <deque>

#include "eoe/eoe_server.hpp"
#include "eoe/ip_responder.hpp"
#include "master/coe_client.hpp"
#include "master/eoe_client.hpp"
#include "protocol/eoe.hpp"
#include "protocol/objects.hpp"
#include "test_support.hpp"

using namespace vecat;
using namespace vecat::test;
using protocol::AlState;
using protocol::EoeFrameType;
using protocol::EoeHeader;
using protocol::EoeResult;
using protocol::MacAddress;
using protocol::MailboxError;
using protocol::MailboxType;

namespace {

constexpr MacAddress kMasterMac = {0x02, 0x11, 0x22, 0x33, 0x44, 0x55};
constexpr MacAddress kOtherMac = {0x02, 0xAA, 0xBB, 0xCC, 0xDD, 0xEE};
constexpr protocol::Ip4 kDeviceIp = 0x0A000005;  // 10.0.0.5
constexpr protocol::Ip4 kMasterIp = 0x0A000001;  // 10.0.0.1

// An Ethernet frame dst, src, EtherType 0x88B5 (IEEE local experimental) and n bytes of a pattern.
std::vector<std::uint8_t> frame_to(const MacAddress& dst, std::size_t n, std::uint8_t seed = 1) {
    std::vector<std::uint8_t> f(dst.begin(), dst.end());
    f.insert(f.end(), kMasterMac.begin(), kMasterMac.end());
    f.push_back(0x88);
    f.push_back(0xB5);
    for (std::size_t i = 0; i < n; ++i)
        f.push_back(static_cast<std::uint8_t>(i * 13 + seed));
    return f;
}

// What the device sends out of its Ethernet side.
struct Wire final : eoe::EthernetPort {
    std::deque<std::vector<std::uint8_t>> frames;
    void send(ConstBytes f) override { frames.emplace_back(f.begin(), f.end()); }
};

// One drive with an EoE server behind the project's master, in PREOP.
struct EoeBench {
    explicit EoeBench(eoe::EoeOptions opt = {}) : b(1) {
        attached = eoe::attach_eoe(*b.seg, opt);
        std::string why;
        EXPECT_TRUE(b.master.startup(AlState::PreOp, &why)) << why;
        client.emplace(b.master, station());
        server().attach(&wire);
    }
    std::uint16_t station() { return b.master.slaves()[0].station; }
    eoe::EoeServer& server() { return *eoe::eoe_server(b.slave()); }
    // One raw EoE message: header and data.
    bool send(const EoeHeader& h, ConstBytes data = {}) {
        std::vector<std::uint8_t> p(protocol::kEoeHeaderSize);
        protocol::write_eoe_header(p, h);
        p.insert(p.end(), data.begin(), data.end());
        return client->mailbox().send(MailboxType::EoE, p, client->mailbox().next_counter());
    }
    std::optional<master::MailboxMessage> receive(int ms = 300) {
        return client->mailbox().receive(std::chrono::milliseconds(ms));
    }
    // The mailbox error the last message got (nullopt: another answer or none).
    std::optional<MailboxError> mailbox_error() {
        const auto m = receive();
        if (!m || m->header.type != static_cast<std::uint8_t>(MailboxType::Error) || m->payload.size() < 4)
            return std::nullopt;
        return static_cast<MailboxError>(ld_le16(m->payload.data() + 2));
    }
    Bench b;
    std::size_t attached = 0;
    Wire wire;
    std::optional<master::EoeClient> client;
};

EoeHeader fragment(std::uint8_t no, std::uint8_t blocks, std::uint8_t frame, bool last) {
    EoeHeader h;
    h.type = static_cast<std::uint8_t>(EoeFrameType::Fragment);
    h.fragment = no;
    h.blocks = blocks;
    h.frame = frame;
    h.last_fragment = last;
    return h;
}

EoeHeader request(EoeFrameType t, std::uint8_t port = 0) {
    EoeHeader h;
    h.type = static_cast<std::uint8_t>(t);
    h.port = port;
    h.last_fragment = true;
    return h;
}

std::vector<std::uint8_t> bytes(std::size_t n, std::uint8_t seed = 0) {
    std::vector<std::uint8_t> v(n);
    for (std::size_t i = 0; i < n; ++i)
        v[i] = static_cast<std::uint8_t>(i + seed);
    return v;
}

}  // namespace

// ---- The wire layout (ETG.1000.6 5.7)

TEST(EoeWire, HeaderBitsAsOnTheWire) {
    // Fragment 0 of frame 1, 1514 bytes (48 blocks), not the last: word 1 0x0000, word 2 0x1C00.
    EoeHeader h = fragment(0, protocol::eoe_size_blocks(1514), 1, false);
    std::array<std::uint8_t, 4> b{};
    h.pack(b);
    EXPECT_EQ(b, (std::array<std::uint8_t, 4>{0x00, 0x00, 0x00, 0x1C}));
    // Set IP parameter response on port 1, last fragment, result 0x0201: 0x0113, 0x0201.
    h = protocol::eoe_response_header(EoeFrameType::SetIpResponse, 1, EoeResult::NoIpSupport);
    h.pack(b);
    EXPECT_EQ(b, (std::array<std::uint8_t, 4>{0x13, 0x01, 0x01, 0x02}));
    EXPECT_EQ(EoeHeader::unpack(b), h);
    EXPECT_EQ(EoeHeader::unpack(b).result(), 0x0201);
}

TEST(EoeWire, HeaderRoundTripsEveryField) {
    EoeHeader h;
    h.type = 0x0F;
    h.port = 0x0A;
    h.last_fragment = true;
    h.time_appended = true;
    h.time_requested = true;
    h.fragment = 0x2A;
    h.blocks = 0x15;
    h.frame = 0x09;
    std::array<std::uint8_t, 4> b{};
    ASSERT_TRUE(protocol::write_eoe_header(b, h));
    EXPECT_EQ(ld_le16(b.data()), 0x07AF);
    EXPECT_EQ(protocol::parse_eoe_header(b), h);
    EXPECT_FALSE(protocol::parse_eoe_header(ConstBytes(b.data(), 3)));
    EXPECT_FALSE(protocol::write_eoe_header(Bytes(b.data(), 3), h));
}

TEST(EoeWire, IpParametersOnlyTheFlaggedFieldsLittleEndian) {
    protocol::EoeIpParameters p;
    p.ip = 0xC0A809C8;  // 192.168.9.200
    p.dns_name = "drive";
    std::array<std::uint8_t, protocol::kEoeIpBlockMaxSize> b{};
    const std::size_t n = protocol::write_eoe_ip(b, p);
    ASSERT_EQ(n, 4u + 4u + 32u);
    EXPECT_EQ(ld_le32(b.data()), protocol::eoe_ip_flag::Ip | protocol::eoe_ip_flag::DnsName);
    EXPECT_EQ(b[4], 0xC8);  // the number little-endian, as SOEM and SOES put it
    EXPECT_EQ(b[7], 0xC0);
    EXPECT_EQ(b[8], 'd');
    EXPECT_EQ(b[13], 0);
    EXPECT_EQ(protocol::parse_eoe_ip(ConstBytes(b.data(), n)), p);

    p.mac = kMasterMac;
    p.subnet = 0xFFFFFF00;
    p.gateway = 0xC0A80901;
    p.dns_server = 0x08080808;
    const std::size_t all = protocol::write_eoe_ip(b, p);
    EXPECT_EQ(all, protocol::kEoeIpBlockMaxSize);
    EXPECT_EQ(protocol::parse_eoe_ip(ConstBytes(b.data(), all)), p);
    // Shorter than its flags say: refused; a DNS name cut short at the end is taken as it is (SOES).
    EXPECT_FALSE(protocol::parse_eoe_ip(ConstBytes(b.data(), 4 + 6 + 4 * 4 - 1)));
    const auto cut = protocol::parse_eoe_ip(ConstBytes(b.data(), all - 29));
    ASSERT_TRUE(cut);
    EXPECT_EQ(cut->dns_name, "dri");
    EXPECT_FALSE(protocol::parse_eoe_ip(ConstBytes(b.data(), 3)));
    EXPECT_EQ(protocol::write_eoe_ip(Bytes(b.data(), 20), p), 0u);
}

TEST(EoeWire, AddressFilterBlockAndWhatItLetsPass) {
    protocol::EoeAddressFilter f;
    f.count = 2;
    f.macs[0] = kMasterMac;
    f.macs[1] = {0x01, 0x00, 0x5E, 0x00, 0x00, 0x00};  // IPv4 multicast ...
    f.mask_count = 2;
    f.masks[0] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
    f.masks[1] = {0xFF, 0xFF, 0xFF, 0x80, 0x00, 0x00};  // ... the whole 01:00:5E:00:00:00/25 range
    f.no_broadcasts = true;
    std::array<std::uint8_t, protocol::kEoeFilterBlockSize> b{};
    ASSERT_EQ(protocol::write_eoe_filter(b, f), 122u);
    EXPECT_EQ(ld_le16(b.data()), 0x0002 | 0x0020 | 0x0080);
    EXPECT_EQ(b[2], kMasterMac[0]);
    EXPECT_EQ(b[2 + 16 * 6 + 6 + 3], 0x80);  // mask 1 after the 16 filter slots
    EXPECT_EQ(protocol::parse_eoe_filter(b), f);

    EXPECT_TRUE(f.accepts(kMasterMac));
    EXPECT_TRUE(f.accepts({0x01, 0x00, 0x5E, 0x01, 0x02, 0x03}));
    EXPECT_FALSE(f.accepts({0x01, 0x00, 0x5E, 0x81, 0x02, 0x03}));
    EXPECT_FALSE(f.accepts(kOtherMac));
    EXPECT_FALSE(f.accepts(protocol::kBroadcastMac));
    f.no_broadcasts = false;
    EXPECT_TRUE(f.accepts(protocol::kBroadcastMac));
    // The filters in use must be there; masks in use too.
    EXPECT_FALSE(protocol::parse_eoe_filter(ConstBytes(b.data(), 2 + 6)));
    EXPECT_FALSE(protocol::parse_eoe_filter(ConstBytes(b.data(), 2 + 16 * 6 + 6)));
    EXPECT_FALSE(protocol::parse_eoe_filter(ConstBytes(b.data(), 1)));
}

TEST(EoeWire, FragmentSizesInBlocks) {
    EXPECT_EQ(protocol::eoe_fragment_capacity(240), 224u);  // (240 - 4) rounded down to 32
    EXPECT_EQ(protocol::eoe_fragment_capacity(35), 0u);
    EXPECT_EQ(protocol::eoe_size_blocks(1514), 48);
    EXPECT_EQ(protocol::eoe_size_blocks(64), 2);
    EXPECT_EQ(protocol::eoe_size_blocks(65), 3);
    EXPECT_EQ(protocol::parse_ip4("192.168.9.200"), 0xC0A809C8u);
    EXPECT_FALSE(protocol::parse_ip4("192.168.9"));
    EXPECT_FALSE(protocol::parse_ip4("192.168.9.256"));
    EXPECT_EQ(protocol::ip4_to_string(0xC0A809C8), "192.168.9.200");
}

// ---- The server: frames from the master

TEST(EoeServer, AttachedToTheDriveThatDeclaresEoe) {
    EoeBench e;
    EXPECT_EQ(e.attached, 1u);
    const auto& sii = e.b.master.slaves()[0].sii;
    EXPECT_TRUE(sii.mailbox_protocols & device::mbx_proto::EoE);
    EXPECT_EQ(sii.eoe_details, device::eoe_details::Enable);
    EXPECT_EQ(e.server().mac(), eoe::default_mac(0));

    auto d = device::default_drive();
    d.mailbox_protocols = device::mbx_proto::CoE;
    Bench plain(1, {}, d);
    EXPECT_EQ(eoe::attach_eoe(*plain.seg), 0u);
}

TEST(EoeServer, AFrameInFragmentsReachesTheEthernetSide) {
    EoeBench e;
    const auto f = frame_to(kOtherMac, 1500);
    ASSERT_TRUE(e.client->send_frame(f));
    e.b.advance(1'000'000);
    ASSERT_EQ(e.wire.frames.size(), 1u);
    EXPECT_EQ(e.wire.frames[0], f);
    const auto& c = e.server().counters();
    EXPECT_GT(c.fragments_in, 5u);  // a 246-byte mailbox: 224 bytes a fragment
    EXPECT_EQ(c.frames_in, 1u);
    EXPECT_EQ(c.to_ethernet, 1u);
    EXPECT_EQ(e.server().reassembling(), 0u);
}

TEST(EoeServer, AFrameForTheDeviceItselfStaysThere) {
    EoeBench e;
    ASSERT_TRUE(e.client->send_frame(frame_to(e.server().mac(), 100)));
    e.b.advance(1'000'000);
    EXPECT_TRUE(e.wire.frames.empty());
    EXPECT_EQ(e.server().counters().frames_in, 1u);
    // Without an Ethernet side, frames for others are counted and dropped.
    e.server().attach(nullptr);
    ASSERT_TRUE(e.client->send_frame(frame_to(kOtherMac, 100)));
    e.b.advance(1'000'000);
    EXPECT_EQ(e.server().counters().no_ethernet, 1u);
}

TEST(EoeServer, TimeAppendedIsNotPartOfTheFrame) {
    EoeBench e;
    auto f = frame_to(kOtherMac, 46);  // 60 bytes: one fragment
    auto data = f;
    for (const int t : {0x11, 0x22, 0x33, 0x44})
        data.push_back(static_cast<std::uint8_t>(t));
    auto h = fragment(0, protocol::eoe_size_blocks(f.size()), 3, true);
    h.time_appended = true;
    ASSERT_TRUE(e.send(h, data));
    e.b.advance(1'000'000);
    ASSERT_EQ(e.wire.frames.size(), 1u);
    EXPECT_EQ(e.wire.frames[0], f);
}

TEST(EoeServer, AFragmentWithoutItsFrameIsOutOfSequence) {
    EoeBench e;
    ASSERT_TRUE(e.send(fragment(1, 7, 2, true), bytes(40)));
    EXPECT_EQ(e.mailbox_error(), MailboxError::InvalidHeader);
    EXPECT_EQ(e.server().counters().out_of_sequence, 1u);
    EXPECT_TRUE(e.wire.frames.empty());
}

TEST(EoeServer, AnOverlappingFragmentGivesUpTheFrame) {
    EoeBench e;
    ASSERT_TRUE(e.send(fragment(0, 4, 5, false), bytes(64)));
    EXPECT_EQ(e.server().reassembling(), 64u);
    // Offset 1 block: overlaps the 2 blocks already there.
    ASSERT_TRUE(e.send(fragment(1, 1, 5, true), bytes(64)));
    EXPECT_EQ(e.mailbox_error(), MailboxError::InvalidHeader);
    EXPECT_EQ(e.server().counters().out_of_sequence, 1u);
    EXPECT_EQ(e.server().counters().incomplete, 1u);
    EXPECT_EQ(e.server().reassembling(), 0u);
    EXPECT_TRUE(e.wire.frames.empty());
}

TEST(EoeServer, AGapOrAnotherFrameNumberIsOutOfSequence) {
    EoeBench e;
    ASSERT_TRUE(e.send(fragment(0, 4, 5, false), bytes(32)));
    ASSERT_TRUE(e.send(fragment(2, 2, 5, true), bytes(32)));  // fragment 1 missing
    EXPECT_EQ(e.mailbox_error(), MailboxError::InvalidHeader);
    ASSERT_TRUE(e.send(fragment(0, 4, 6, false), bytes(32)));
    ASSERT_TRUE(e.send(fragment(1, 1, 7, true), bytes(32)));  // frame 7 in the middle of frame 6
    EXPECT_EQ(e.mailbox_error(), MailboxError::InvalidHeader);
    EXPECT_EQ(e.server().counters().out_of_sequence, 2u);
    EXPECT_EQ(e.server().counters().incomplete, 2u);
    EXPECT_TRUE(e.wire.frames.empty());
}

TEST(EoeServer, ANewFrameDiscardsTheHalfFrame) {
    EoeBench e;
    ASSERT_TRUE(e.send(fragment(0, 4, 1, false), bytes(64)));
    const auto f = frame_to(kOtherMac, 60);
    ASSERT_TRUE(e.send(fragment(0, protocol::eoe_size_blocks(f.size()), 2, true), f));
    e.b.advance(1'000'000);
    ASSERT_EQ(e.wire.frames.size(), 1u);
    EXPECT_EQ(e.wire.frames[0], f);
    EXPECT_EQ(e.server().counters().incomplete, 1u);
    EXPECT_FALSE(e.receive(50));  // given up silently: a new frame is what a master does after a loss
}

TEST(EoeServer, AFrameNeverCompletedIsDroppedWhenTheMailboxResets) {
    EoeBench e;
    ASSERT_TRUE(e.send(fragment(0, 40, 1, false), bytes(224)));
    EXPECT_EQ(e.server().reassembling(), 224u);
    ASSERT_TRUE(e.b.master.request_state(e.station(), AlState::Init));
    EXPECT_EQ(e.server().reassembling(), 0u);
    EXPECT_EQ(e.server().counters().incomplete, 1u);
}

TEST(EoeServer, AFrameLargerThanTheBufferIsRefused) {
    EoeBench e;
    // 63 blocks = 2016 bytes: more than any Ethernet frame.
    ASSERT_TRUE(e.send(fragment(0, 63, 1, false), bytes(224)));
    EXPECT_EQ(e.mailbox_error(), MailboxError::NoMoreMemory);
    EXPECT_EQ(e.server().counters().oversize, 1u);
    EXPECT_EQ(e.server().reassembling(), 0u);
    EXPECT_LE(eoe::EoeServer::kRxBufferSize, 1540u);
}

TEST(EoeServer, DataPastTheAnnouncedSizeIsRefused) {
    EoeBench e;
    ASSERT_TRUE(e.send(fragment(0, 2, 1, true), bytes(65)));  // 2 blocks announced, 65 bytes sent
    EXPECT_EQ(e.mailbox_error(), MailboxError::InvalidSize);
    ASSERT_TRUE(e.send(fragment(0, 4, 2, false), bytes(40)));  // not the last, not whole blocks
    EXPECT_EQ(e.mailbox_error(), MailboxError::InvalidSize);
    EXPECT_EQ(e.server().counters().oversize, 2u);
    EXPECT_TRUE(e.wire.frames.empty());
}

TEST(EoeServer, TooShortForAnEoeHeader) {
    EoeBench e;
    const std::uint8_t two[2] = {0, 0};
    ASSERT_TRUE(e.client->mailbox().send(MailboxType::EoE, two, e.client->mailbox().next_counter()));
    EXPECT_EQ(e.mailbox_error(), MailboxError::SizeTooShort);
    EXPECT_EQ(e.server().counters().mailbox_errors, 1u);
}

// ---- The server: frames to the master

TEST(EoeServer, AFrameFromTheEthernetSideReachesTheMasterInFragments) {
    EoeBench e;
    const auto f = frame_to(kMasterMac, 1500, 7);
    ASSERT_TRUE(e.server().from_ethernet(f));
    const auto got = e.client->receive_frame(std::chrono::milliseconds(1000));
    ASSERT_TRUE(got);
    EXPECT_EQ(*got, f);
    EXPECT_EQ(e.server().counters().fragments_out, 7u);  // 6 x 224 + 170
    EXPECT_EQ(e.server().counters().frames_out, 1u);
    EXPECT_EQ(e.client->bad_fragments(), 0u);
    // Several in a row keep their order.
    for (std::uint8_t k = 0; k < 3; ++k)
        ASSERT_TRUE(e.server().from_ethernet(frame_to(kMasterMac, 300 + k, k)));
    for (std::uint8_t k = 0; k < 3; ++k) {
        const auto g = e.client->receive_frame(std::chrono::milliseconds(1000));
        ASSERT_TRUE(g);
        EXPECT_EQ(*g, frame_to(kMasterMac, 300 + k, k));
    }
}

TEST(EoeServer, TheQueueToTheMasterIsBounded) {
    eoe::EoeOptions opt;
    opt.queue_frames = 4;
    EoeBench e(opt);
    for (int k = 0; k < 4; ++k)
        EXPECT_TRUE(e.server().from_ethernet(frame_to(kMasterMac, 100)));
    EXPECT_FALSE(e.server().from_ethernet(frame_to(kMasterMac, 100)));
    EXPECT_EQ(e.server().counters().queue_full, 1u);
    EXPECT_FALSE(e.server().from_ethernet(std::vector<std::uint8_t>(1600, 0xFF)));
    EXPECT_FALSE(e.server().from_ethernet(std::vector<std::uint8_t>(10, 0xFF)));
    EXPECT_EQ(e.server().counters().oversize, 2u);
    // Reset (INIT): what waited is gone; in INIT nothing is taken.
    ASSERT_TRUE(e.b.master.request_state(e.station(), AlState::Init));
    EXPECT_EQ(e.server().queued(), 0u);
    EXPECT_FALSE(e.server().from_ethernet(frame_to(kMasterMac, 100)));
    EXPECT_EQ(e.server().counters().not_running, 5u);
}

// ---- IP parameters

TEST(EoeServer, SetAndGetIpParameter) {
    EoeBench e;
    auto r = e.client->get_ip();
    ASSERT_TRUE(r.ok());
    ASSERT_TRUE(r.ip);
    EXPECT_EQ(r.ip->mac, eoe::default_mac(0));
    EXPECT_FALSE(r.ip->ip);

    protocol::EoeIpParameters p;
    p.mac = MacAddress{0x02, 0x01, 0x02, 0x03, 0x04, 0x05};
    p.ip = kDeviceIp;
    p.subnet = 0xFFFFFF00;
    p.gateway = kMasterIp;
    p.dns_server = 0x0A000002;
    p.dns_name = "vecat-drive";
    r = e.client->set_ip(p);
    EXPECT_TRUE(r.ok()) << (r.result ? *r.result : -1);
    r = e.client->get_ip();
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.ip, p);
    EXPECT_EQ(e.server().mac(), *p.mac);
    // A later set changes only what it carries.
    protocol::EoeIpParameters q;
    q.ip = 0x0A000006;
    ASSERT_TRUE(e.client->set_ip(q).ok());
    EXPECT_EQ(e.server().ip_parameters().ip, q.ip);
    EXPECT_EQ(e.server().ip_parameters().gateway, p.gateway);
}

TEST(EoeServer, NoIpSupport) {
    eoe::EoeOptions opt;
    opt.ip_support = false;
    EoeBench e(opt);
    protocol::EoeIpParameters p;
    p.ip = kDeviceIp;
    auto r = e.client->set_ip(p);
    EXPECT_EQ(r.result, 0x0201);
    r = e.client->get_ip();
    EXPECT_EQ(r.result, 0x0201);
    EXPECT_FALSE(r.ip);
    EXPECT_EQ(e.server().counters().results_sent, 2u);
}

TEST(EoeServer, AnAddressOfZeroAsksForDhcp) {
    EoeBench e;
    protocol::EoeIpParameters p;
    p.ip = 0;
    EXPECT_EQ(e.client->set_ip(p).result, 0x0202);
    EXPECT_FALSE(e.server().ip_parameters().ip);
}

TEST(EoeServer, UnspecifiedError) {
    EoeBench e;
    protocol::EoeIpParameters p;
    p.ip = kDeviceIp;
    EXPECT_EQ(e.client->set_ip(p, 2).result, 0x0001);  // the device has one port
    EXPECT_EQ(e.client->get_ip(5).result, 0x0001);
    EXPECT_EQ(e.client->get_filter(2).result, 0x0001);
    EXPECT_EQ(e.client->set_filter({}, 3).result, 0x0001);
    p.mac = MacAddress{0x01, 0, 0, 0, 0, 1};  // a multicast address as the device's own
    EXPECT_EQ(e.client->set_ip(p).result, 0x0001);
    // A block shorter than its flags say.
    std::vector<std::uint8_t> m(4 + 4 + 2);
    protocol::write_eoe_header(m, request(EoeFrameType::SetIpRequest));
    st_le32(m.data() + 4, protocol::eoe_ip_flag::Ip);
    EXPECT_EQ(e.client->service(m, EoeFrameType::SetIpResponse).result, 0x0001);
    std::vector<std::uint8_t> fm(4 + 2 + 6);
    protocol::write_eoe_header(fm, request(EoeFrameType::SetFilterRequest));
    st_le16(fm.data() + 4, 0x0003);  // three filters, one there
    EXPECT_EQ(e.client->service(fm, EoeFrameType::SetFilterResponse).result, 0x0001);
    EXPECT_FALSE(e.server().ip_parameters().ip);
    EXPECT_FALSE(e.server().filter());
    EXPECT_EQ(e.server().counters().results_sent, 7u);
}

TEST(EoeServer, UnsupportedFrameTypes) {
    EoeBench e;
    // Responses, the time stamp (slave to master) and the undefined types 10..15.
    for (const int t : {1, 3, 5, 7, 9, 10, 11, 12, 13, 14, 15}) {
        std::array<std::uint8_t, 4> m{};
        protocol::write_eoe_header(m, request(static_cast<EoeFrameType>(t)));
        const auto r = e.client->service(m, static_cast<EoeFrameType>(t));
        EXPECT_EQ(r.result, 0x0002) << "frame type " << int(t);
    }
}

// ---- Address filter

TEST(EoeServer, SetAndGetAddressFilterAndItIsHonoured) {
    EoeBench e;
    auto r = e.client->get_filter();
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.filter->count, 0);
    // No filter set: every frame goes to the master.
    EXPECT_TRUE(e.server().from_ethernet(frame_to(kOtherMac, 50)));

    protocol::EoeAddressFilter f;
    f.count = 1;
    f.macs[0] = kMasterMac;
    f.no_broadcasts = true;
    ASSERT_TRUE(e.client->set_filter(f).ok());
    r = e.client->get_filter();
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.filter, f);
    ASSERT_TRUE(e.client->receive_frame(std::chrono::milliseconds(500)));  // the one from before

    EXPECT_FALSE(e.server().from_ethernet(frame_to(kOtherMac, 50)));
    EXPECT_FALSE(e.server().from_ethernet(frame_to(protocol::kBroadcastMac, 50)));
    EXPECT_TRUE(e.server().from_ethernet(frame_to(kMasterMac, 50)));
    EXPECT_EQ(e.server().counters().filtered, 2u);
    const auto got = e.client->receive_frame(std::chrono::milliseconds(500));
    ASSERT_TRUE(got);
    EXPECT_EQ(*got, frame_to(kMasterMac, 50));
    EXPECT_FALSE(e.client->receive_frame(std::chrono::milliseconds(50)));

    f.no_broadcasts = false;
    ASSERT_TRUE(e.client->set_filter(f).ok());
    EXPECT_TRUE(e.server().from_ethernet(frame_to(protocol::kBroadcastMac, 50)));
}

TEST(EoeServer, NoFilterSupport) {
    eoe::EoeOptions opt;
    opt.filter_support = false;
    EoeBench e(opt);
    EXPECT_EQ(e.client->set_filter({}).result, 0x0401);
    EXPECT_EQ(e.client->get_filter().result, 0x0401);
}

// ---- The device's own IP stack

namespace {

std::vector<std::uint8_t> arp_request(protocol::Ip4 target) {
    std::vector<std::uint8_t> f(protocol::kBroadcastMac.begin(), protocol::kBroadcastMac.end());
    f.insert(f.end(), kMasterMac.begin(), kMasterMac.end());
    for (const int b : {0x08, 0x06, 0x00, 0x01, 0x08, 0x00, 0x06, 0x04, 0x00, 0x01})
        f.push_back(static_cast<std::uint8_t>(b));
    f.insert(f.end(), kMasterMac.begin(), kMasterMac.end());
    for (int i = 3; i >= 0; --i)
        f.push_back(static_cast<std::uint8_t>(kMasterIp >> (8 * i)));
    f.insert(f.end(), 6, 0);
    for (int i = 3; i >= 0; --i)
        f.push_back(static_cast<std::uint8_t>(target >> (8 * i)));
    f.resize(60, 0);
    return f;
}

std::vector<std::uint8_t> echo_request(const MacAddress& dst, protocol::Ip4 to, std::size_t payload) {
    std::vector<std::uint8_t> f(dst.begin(), dst.end());
    f.insert(f.end(), kMasterMac.begin(), kMasterMac.end());
    f.push_back(0x08);
    f.push_back(0x00);
    const std::size_t total = 20 + 8 + payload;
    std::vector<std::uint8_t> ip = {0x45,
                                    0,
                                    static_cast<std::uint8_t>(total >> 8),
                                    static_cast<std::uint8_t>(total),
                                    0x12,
                                    0x34,
                                    0x40,
                                    0,
                                    64,
                                    1,
                                    0,
                                    0};
    for (int i = 3; i >= 0; --i)
        ip.push_back(static_cast<std::uint8_t>(kMasterIp >> (8 * i)));
    for (int i = 3; i >= 0; --i)
        ip.push_back(static_cast<std::uint8_t>(to >> (8 * i)));
    const std::uint16_t hc = eoe::internet_checksum(ip);
    ip[10] = static_cast<std::uint8_t>(hc >> 8);
    ip[11] = static_cast<std::uint8_t>(hc);
    std::vector<std::uint8_t> icmp = {8, 0, 0, 0, 0xBE, 0xEF, 0x00, 0x01};
    for (std::size_t i = 0; i < payload; ++i)
        icmp.push_back(static_cast<std::uint8_t>(i));
    const std::uint16_t ic = eoe::internet_checksum(icmp);
    icmp[2] = static_cast<std::uint8_t>(ic >> 8);
    icmp[3] = static_cast<std::uint8_t>(ic);
    f.insert(f.end(), ip.begin(), ip.end());
    f.insert(f.end(), icmp.begin(), icmp.end());
    return f;
}

}  // namespace

TEST(EoeServer, AnswersArpAndPingForTheAddressTheMasterSet) {
    EoeBench e;
    // No address yet: nothing answered (the request goes to the Ethernet side, a broadcast).
    ASSERT_TRUE(e.client->send_frame(arp_request(kDeviceIp)));
    EXPECT_FALSE(e.client->receive_frame(std::chrono::milliseconds(50)));
    protocol::EoeIpParameters p;
    p.ip = kDeviceIp;
    ASSERT_TRUE(e.client->set_ip(p).ok());

    ASSERT_TRUE(e.client->send_frame(arp_request(kDeviceIp)));
    auto r = e.client->receive_frame(std::chrono::milliseconds(500));
    ASSERT_TRUE(r);
    const MacAddress mac = e.server().mac();
    ASSERT_GE(r->size(), 42u);
    EXPECT_TRUE(std::equal(kMasterMac.begin(), kMasterMac.end(), r->begin()));
    EXPECT_TRUE(std::equal(mac.begin(), mac.end(), r->begin() + 6));
    EXPECT_EQ((*r)[21], 2);                                            // ARP reply
    EXPECT_TRUE(std::equal(mac.begin(), mac.end(), r->begin() + 22));  // sender: the device
    EXPECT_EQ((*r)[31], 5);                                            // 10.0.0.5
    EXPECT_EQ((*r)[41], 1);                                            // target: 10.0.0.1
    EXPECT_EQ(e.wire.frames.size(), 2u);  // both broadcasts went to the Ethernet side too

    const auto ping = echo_request(mac, kDeviceIp, 1000);  // fragmented both ways
    ASSERT_TRUE(e.client->send_frame(ping));
    r = e.client->receive_frame(std::chrono::milliseconds(1000));
    ASSERT_TRUE(r);
    ASSERT_EQ(r->size(), ping.size());
    const ConstBytes ip(r->data() + 14, r->size() - 14);
    EXPECT_EQ(eoe::internet_checksum(ip.first(20)), 0);
    EXPECT_EQ(eoe::internet_checksum(ip.subspan(20)), 0);
    EXPECT_EQ(ip[20], 0);                                                // echo reply
    EXPECT_EQ(ld_le32(ip.data() + 12), ld_le32(ping.data() + 14 + 16));  // from the device's address
    EXPECT_TRUE(std::equal(ping.begin() + 14 + 24, ping.end(), r->begin() + 14 + 24));  // id, seq, data
    EXPECT_EQ(e.server().counters().echo_replies, 1u);
    EXPECT_EQ(e.wire.frames.size(), 2u);  // the ping was for the device alone

    // A ping with a bad checksum, or to another address, is not answered by the device.
    auto bad = echo_request(mac, kDeviceIp, 10);
    bad.back() ^= 0xFF;
    ASSERT_TRUE(e.client->send_frame(bad));
    ASSERT_TRUE(e.client->send_frame(echo_request(kOtherMac, 0x0A000009, 10)));
    EXPECT_FALSE(e.client->receive_frame(std::chrono::milliseconds(50)));
    EXPECT_EQ(e.server().counters().echo_replies, 1u);
    EXPECT_EQ(e.wire.frames.size(), 3u);
}

// ---- CoE and process data go on

TEST(EoeServer, CoeAndProcessDataGoOnThroughBadFragments) {
    EoeBench e;
    std::string why;
    ASSERT_TRUE(e.b.master.startup(AlState::Op, &why)) << why;
    master::CoeClient coe(e.b.master, e.station());
    for (int round = 0; round < 20; ++round) {
        // A frame that never completes, an overlapping fragment, an oversized one, half of a frame.
        ASSERT_TRUE(e.send(fragment(0, 10, 1, false), bytes(64)));
        ASSERT_TRUE(e.send(fragment(1, 1, 1, false), bytes(32)));
        EXPECT_EQ(e.mailbox_error(), MailboxError::InvalidHeader);
        ASSERT_TRUE(e.send(fragment(0, 60, 2, false), bytes(32)));
        EXPECT_EQ(e.mailbox_error(), MailboxError::NoMoreMemory);
        ASSERT_TRUE(e.send(fragment(0, 40, 3, false), bytes(224)));
        const auto wkc = e.b.master.exchange_process_data();
        ASSERT_TRUE(wkc);
        EXPECT_EQ(*wkc, e.b.master.expected_wkc());
        const auto sdo = coe.upload(protocol::obj::device_type.index, 0);
        ASSERT_TRUE(sdo.transport_ok);
        EXPECT_EQ(sdo.abort, protocol::SdoAbort::None);
        EXPECT_LE(e.server().reassembling(), eoe::EoeServer::kRxBufferSize);
    }
    EXPECT_EQ(e.b.slave().state(), AlState::Op);
    // And a whole frame still goes through.
    const auto f = frame_to(kOtherMac, 700);
    ASSERT_TRUE(e.client->send_frame(f));
    e.b.advance(1'000'000);
    ASSERT_FALSE(e.wire.frames.empty());
    EXPECT_EQ(e.wire.frames.back(), f);
}
