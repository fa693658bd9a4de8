// Device quirks (device/quirks.hpp): each one as a master sees it through the wire, with the project's
// master on an in-process link: what the SII it reads says, and what the slave answers over the mailbox.
// Each test also shows the same device without the quirk answering normally, so that it fails when the
// quirk does nothing.
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <vector>

#include "device/device_description.hpp"
#include "device/quirks.hpp"
#include "device/simple_devices.hpp"
#include "master/coe_client.hpp"
#include "protocol/coe.hpp"
#include "protocol/mailbox.hpp"
#include "protocol/registers.hpp"
#include "protocol/sync_manager.hpp"
#include "test_support.hpp"

using namespace vecat;
using protocol::AlState;
using protocol::MailboxType;
using protocol::SdoAbort;
using namespace std::chrono_literals;
namespace cd = device::coe_details;

namespace {

// The default drive with the quirks of text (each one as in a network file's list).
device::DeviceDescription with_quirks(const std::vector<std::string>& text) {
    device::DeviceDescription d = device::default_drive();
    device::Quirks q;
    for (const auto& t : text)
        EXPECT_EQ(device::parse_quirk(t, q), "") << t;
    EXPECT_EQ(device::apply_quirks(d, q), "");
    return d;
}

// One slave of the device in PREOP behind the project master.
struct Preop {
    explicit Preop(device::DeviceDescription d) : b(1, {}, std::move(d)) {
        std::string why;
        EXPECT_TRUE(b.master.startup(AlState::PreOp, &why)) << why;
        c = std::make_unique<master::CoeClient>(b.master, station());
    }
    std::uint16_t station() { return b.master.slaves()[0].station; }
    const protocol::SiiInfo& sii() { return b.master.slaves()[0].sii; }
    test::Bench b;
    std::unique_ptr<master::CoeClient> c;
};

// The CoE payload of an SDO information "get OD list" request (ETG.1000.6 5.6.3.3) of all objects.
std::vector<std::uint8_t> od_list_request() {
    std::vector<std::uint8_t> p(protocol::kCoeHeaderSize + protocol::kSdoInfoHeaderSize + 2, 0);
    st_le16(p.data(), protocol::coe_header(protocol::CoeService::SdoInformation));
    p[2] = protocol::sdo_info::GetOdListRequest;
    st_le16(p.data() + protocol::kCoeHeaderSize + protocol::kSdoInfoHeaderSize, protocol::sdo_info::ListAll);
    return p;
}

// The CoE payload of an expedited-size SDO upload request of index:sub.
std::vector<std::uint8_t> upload_request(std::uint16_t index, std::uint8_t sub) {
    std::vector<std::uint8_t> p(protocol::kCoeHeaderSize + protocol::kSdoHeaderSize, 0);
    st_le16(p.data(), protocol::coe_header(protocol::CoeService::SdoRequest));
    p[2] = protocol::sdo::command(protocol::sdo::CcsInitiateUpload, 0);
    st_le16(p.data() + 3, index);
    p[5] = sub;
    return p;
}

// The value of an expedited upload response (4 data bytes from byte 6 of the CoE payload).
std::uint32_t expedited_value(const master::MailboxMessage& m) {
    return m.payload.size() >= 10 ? ld_le32(m.payload.data() + 6) : 0xFFFFFFFF;
}

TEST(Quirks, ParsedAsWrittenAndRefusedWithTheReason) {
    device::Quirks q;
    EXPECT_EQ(device::parse_quirk("no_sdo_info", q), "");
    EXPECT_EQ(device::parse_quirk(" max_pdo_entries=8 ", q), "");
    EXPECT_EQ(device::parse_quirk("mailbox_delay_ms=2.5", q), "");
    EXPECT_EQ(device::parse_quirk("mailbox_drop_every=4", q), "");
    EXPECT_EQ(device::parse_quirk("sii_without=strings+dc", q), "");
    EXPECT_TRUE(q.no_sdo_info);
    EXPECT_FALSE(q.no_complete_access);
    EXPECT_EQ(q.max_pdo_entries, 8u);
    EXPECT_EQ(q.mailbox_delay_ns, 2'500'000u);
    EXPECT_EQ(q.mailbox_drop_every, 4u);
    EXPECT_EQ(q.sii_without, device::sii_optional::Strings | device::sii_optional::Dc);
    // Written back as read, and read again to the same quirks.
    const std::string text = device::to_string(q);
    EXPECT_EQ(text,
              "no_sdo_info, max_pdo_entries=8, mailbox_delay_ms=2.5, mailbox_drop_every=4, "
              "sii_without=strings+dc");
    device::Quirks again;
    for (std::size_t at = 0; at < text.size();) {
        const auto comma = std::min(text.find(',', at), text.size());
        EXPECT_EQ(device::parse_quirk(text.substr(at, comma - at), again), "");
        at = comma + 1;
    }
    EXPECT_EQ(again, q);
    EXPECT_EQ(device::to_string({}), "");
    const std::pair<const char*, const char*> bad[] = {
        {"no_sdo_info=1", "no_sdo_info: takes no value"},
        {"max_pdo_entries", "max_pdo_entries: needs a value"},
        {"max_pdo_entries=0", "is not 1..254"},
        {"max_pdo_entries=255", "is not 1..254"},
        {"max_pdo_entries=4x", "is not 1..254"},
        {"mailbox_drop_every=1", "is not 2..1000"},
        {"mailbox_delay_ms=-1", "is not 0..500"},
        {"mailbox_delay_ms=501", "is not 0..500"},
        {"mailbox_delay_ms=nan", "is not 0..500"},
        {"sii_without=general", "sii_without: unknown category \"general\""},
        {"sii_without=strings+", "a category after '+'"},
        {"slow", "unknown quirk \"slow\""},
    };
    for (const auto& [option, why] : bad) {
        device::Quirks x;
        EXPECT_NE(device::parse_quirk(option, x).find(why), std::string::npos)
            << option << ": " << device::parse_quirk(option, x);
    }
}

// A device whose default mapping is longer than the limit, or a CoE quirk on a device without CoE, cannot
// be made.
TEST(Quirks, ADeviceThatCannotHaveThemIsRefused) {
    device::Quirks q;
    q.max_pdo_entries = 4;
    auto d = device::default_drive();
    EXPECT_EQ(device::apply_quirks(d, q), "max_pdo_entries=4: the default mapping of 0x1600 has 7 entries");
    device::Quirks info;
    info.no_sdo_info = true;
    auto coupler = device::DeviceDescription{};
    coupler.mailbox_protocols = 0;
    EXPECT_NE(device::apply_quirks(coupler, info).find("no CoE mailbox"), std::string::npos);
}

// no_sdo_info: the SII's CoE details lack SDO information (ETG.2010 General category), and an SDO
// information request gets the mailbox error "service not supported" (ETG.1000.4 Table 30); SDO
// uploads still work. Like many drives and gateways with a small CoE stack (SDO only).
TEST(Quirks, NoSdoInformation) {
    Preop plain(device::default_drive());
    EXPECT_TRUE(plain.sii().coe_details & cd::SdoInfo);
    EXPECT_TRUE(plain.c->od_list(protocol::sdo_info::ListAll));

    Preop p(with_quirks({"no_sdo_info"}));
    EXPECT_FALSE(p.sii().coe_details & cd::SdoInfo);
    EXPECT_TRUE(p.sii().coe_details & cd::Sdo);
    const auto reply = p.c->request(MailboxType::CoE, od_list_request());
    ASSERT_TRUE(reply);
    EXPECT_EQ(reply->header.type, static_cast<std::uint8_t>(MailboxType::Error));
    ASSERT_EQ(reply->payload.size(), protocol::kMailboxErrorSize);
    EXPECT_EQ(ld_le16(reply->payload.data() + 2),
              static_cast<std::uint16_t>(protocol::MailboxError::ServiceNotSupported));
    EXPECT_FALSE(p.c->object_description(0x1018));
    const auto up = p.c->upload(0x1018, 1);
    ASSERT_TRUE(up.ok());
    EXPECT_EQ(ld_le32(up.data.data()), p.b.desc.identity.vendor_id);
}

// no_complete_access: complete access uploads and downloads are aborted with 0x06010000 "unsupported
// access to an object" (ETG.1000.6 Table 41) and the SII's CoE details say so; access by subindex works.
// Like simple CoE devices whose SDO server knows single entries only.
TEST(Quirks, NoCompleteAccess) {
    Preop plain(device::default_drive());
    EXPECT_TRUE(plain.sii().coe_details & cd::CompleteAccess);
    EXPECT_TRUE(plain.c->upload(0x1C12, 0, true).ok());

    Preop p(with_quirks({"no_complete_access"}));
    EXPECT_FALSE(p.sii().coe_details & cd::CompleteAccess);
    const auto up = p.c->upload(0x1C12, 0, true);
    EXPECT_TRUE(up.transport_ok);
    EXPECT_EQ(up.abort, SdoAbort::UnsupportedAccess);
    const std::vector<std::uint8_t> assign = {1, 0, 0x00, 0x16};  // 1 PDO: 0x1600
    const auto down = p.c->download(0x1C12, 0, ConstBytes(assign.data(), assign.size()), true);
    EXPECT_TRUE(down.transport_ok);
    EXPECT_EQ(down.abort, SdoAbort::UnsupportedAccess);
    const auto single = p.c->upload(0x1C12, 1);
    ASSERT_TRUE(single.ok());
    EXPECT_EQ(ld_le16(single.data.data()), 0x1600);
}

// sdo_download_echo: the initiate download response repeats the request's data field (bytes 4-7 of the SDO
// header, reserved in ETG.1000.6 5.6.2) instead of zeros, as the EL3004 of ../shared/data/pcap answers.
TEST(Quirks, SdoDownloadResponseEchoesTheRequestData) {
    // An expedited download of 0x1C12:00 = 0 with the bytes past the value non-zero, as a master may send.
    std::vector<std::uint8_t> rq(protocol::kCoeHeaderSize + protocol::kSdoHeaderSize, 0);
    st_le16(rq.data(), protocol::coe_header(protocol::CoeService::SdoRequest));
    rq[2] = static_cast<std::uint8_t>(
        protocol::sdo::command(protocol::sdo::CcsInitiateDownload,
                               protocol::sdo::Expedited | protocol::sdo::SizeIndicated) |
        (3u << protocol::sdo::ExpeditedUnusedShift));  // one byte
    st_le16(rq.data() + 3, 0x1C12);
    rq[5] = 0;
    st_le32(rq.data() + 6, 0x1A2B3C00);
    for (const bool echo : {false, true}) {
        Preop p(echo ? with_quirks({"sdo_download_echo"}) : device::default_drive());
        const auto reply = p.c->request(MailboxType::CoE, rq);
        ASSERT_TRUE(reply);
        ASSERT_GE(reply->payload.size(), rq.size());
        EXPECT_EQ(reply->payload[2], protocol::sdo::command(protocol::sdo::ScsInitiateDownload, 0));
        EXPECT_EQ(ld_le32(reply->payload.data() + 6), echo ? 0x1A2B3C00u : 0u) << "echo " << echo;
    }
    device::Quirks q;
    EXPECT_EQ(device::parse_quirk("sdo_download_echo", q), "");
    EXPECT_EQ(device::to_string(q), "sdo_download_echo");
    device::DeviceDescription io = device::default_drive();
    io.mailbox_protocols = 0;
    EXPECT_NE(device::apply_quirks(io, q), "");  // a CoE quirk
}

// mailbox_open_early: once the master has read a message from SM1, the firmware opens the buffer for the next
// one at once: the SM1 status reads 0x80 (write buffer in use, ESC datasheet section II 0x0805 bit 7), not
// 0x02 (interrupt read), until the next message is there (0x09), as the EL3004 of ../shared/data/pcap shows.
TEST(Quirks, MailboxInOpenedAsSoonAsTheMasterReadIt) {
    constexpr std::uint16_t kSm1Status = protocol::sm_addr(1) + protocol::sm::Status;
    for (const bool early : {false, true}) {
        SCOPED_TRACE(early ? "mailbox_open_early" : "plain");
        Preop p(early ? with_quirks({"mailbox_open_early"}) : device::default_drive());
        const auto status = [&] {
            std::uint8_t st = 0xFF;
            EXPECT_EQ(p.b.master.fprd(p.station(), kSm1Status, Bytes(&st, 1)), 1);
            return st;
        };
        EXPECT_EQ(status(), 0x00);  // nothing read yet: not opened
        for (int i = 0; i < 3; ++i) {
            const auto reply = p.c->request(MailboxType::CoE, upload_request(0x1000, 0));
            ASSERT_TRUE(reply);
            EXPECT_EQ(expedited_value(*reply), device::default_drive().device_type);
            p.b.advance(1'000'000);  // the firmware's run after the read
            EXPECT_EQ(status(), early ? 0x80 : 0x02);
            // An opened buffer is not a message: the master's read of SM1 is not counted.
            std::vector<std::uint8_t> in(p.b.master.slaves()[0].sii.std_tx_mbx_size);
            EXPECT_EQ(p.b.master.fprd(p.station(), p.b.master.slaves()[0].sii.std_tx_mbx_offset, Bytes(in)),
                      0);
        }
    }
    device::Quirks q;
    EXPECT_EQ(device::parse_quirk("mailbox_open_early", q), "");
    EXPECT_EQ(device::to_string(q), "mailbox_open_early");
    device::DeviceDescription io = device::digital_output_terminal(8);
    EXPECT_NE(device::apply_quirks(io, q), "");  // no mailbox
}

// max_pdo_entries=N: each mapping object has N entry subindexes; subindex 0 beyond N is refused with
// 0x06090031 "value too high", subindex N + 1 does not exist (0x06090011), and SDO information reports N
// as the object's largest subindex. Like drives whose firmware keeps a fixed-size table per PDO.
TEST(Quirks, AtMostNEntriesPerMappingObject) {
    Preop plain(device::default_drive());
    EXPECT_TRUE(plain.c->download_value(0x1600, 0, std::uint8_t{0}).ok());
    EXPECT_TRUE(plain.c->download_value(0x1600, 11, std::uint32_t{0}).ok());

    Preop p(with_quirks({"max_pdo_entries=10"}));
    const auto o = p.c->object_description(0x1600);
    ASSERT_TRUE(o);
    EXPECT_EQ(o->max_subindex, 10);
    ASSERT_TRUE(p.c->download_value(0x1600, 0, std::uint8_t{0}).ok());
    EXPECT_EQ(p.c->download_value(0x1600, 11, std::uint32_t{0}).abort, SdoAbort::SubindexDoesNotExist);
    EXPECT_EQ(p.c->download_value(0x1600, 0, std::uint8_t{11}).abort, SdoAbort::ValueTooHigh);
    // Within the limit the mapping is written as before: the default 7 entries again.
    EXPECT_TRUE(p.c->download_value(0x1600, 0, std::uint8_t{7}).ok());
    EXPECT_TRUE(p.c->download_value(0x1A00, 0, std::uint8_t{10}).ok());
}

// fixed_pdos: the mapping and the assignment are read-only (0x06010002 "attempt to write a read only
// object"), the PDOs that were not assigned are gone, the SII marks the PDOs fixed and mandatory and its CoE
// details lack PdoAssign/PdoConfig; the device reaches SAFEOP with its one mapping. Like I/O terminals and
// low-cost drives with one fixed process image.
TEST(Quirks, FixedPdos) {
    Preop plain(device::default_drive());
    EXPECT_TRUE(plain.c->download_value(0x1600, 0, std::uint8_t{0}).ok());
    EXPECT_TRUE(plain.c->upload(0x1601, 0).ok());

    Preop p(with_quirks({"fixed_pdos"}));
    EXPECT_FALSE(p.sii().coe_details & (cd::PdoAssign | cd::PdoConfig));
    ASSERT_EQ(p.sii().rx_pdos.size(), 1u);
    ASSERT_EQ(p.sii().tx_pdos.size(), 1u);
    for (const auto* pdo : {&p.sii().rx_pdos[0], &p.sii().tx_pdos[0]})
        EXPECT_EQ(pdo->flags & 0x0011, 0x0011) << "SII PDO flags: mandatory (bit 0) and fixed (bit 4)";
    EXPECT_EQ(p.c->download_value(0x1600, 0, std::uint8_t{0}).abort, SdoAbort::ReadOnly);
    EXPECT_EQ(p.c->download_value(0x1A00, 1, std::uint32_t{0x60410010}).abort, SdoAbort::ReadOnly);
    EXPECT_EQ(p.c->download_value(0x1C12, 0, std::uint8_t{0}).abort, SdoAbort::ReadOnly);
    EXPECT_EQ(p.c->download_value(0x1C13, 1, std::uint16_t{0x1A00}).abort, SdoAbort::ReadOnly);
    EXPECT_EQ(p.c->upload(0x1601, 0).abort, SdoAbort::ObjectDoesNotExist);
    const auto n = p.c->upload(0x1600, 0);
    ASSERT_TRUE(n.ok());
    EXPECT_EQ(n.data.at(0), 7);
    std::string why;
    EXPECT_TRUE(p.b.master.startup(AlState::SafeOp, &why)) << why;
}

// mailbox_delay_ms: the reply is in the mailbox-in SyncManager (SM1 status "mailbox full", ESC datasheet
// 0x080D bit 3) only when the delay has passed since the request; until then a master polling SM1 sees it
// empty. Like gateways and drives whose mailbox runs in a slow background task.
TEST(Quirks, MailboxRepliesAfterADelay) {
    // (3 ms: shorter than the segment's lag bound, Segment::kMaxLagCycles local cycles, so that the held
    // reply is the earliest deadline.)
    Preop p(with_quirks({"mailbox_delay_ms=3"}));
    const auto sm1_full = [&] {
        const auto st = p.b.master.read16(p.station(), protocol::sm_addr(1) + protocol::sm::Status);
        return st && (*st & protocol::sm::StatusMailboxFull);
    };
    ASSERT_TRUE(p.c->send(MailboxType::CoE, upload_request(0x1018, 2), p.c->next_counter()));
    EXPECT_FALSE(p.c->receive(20ms)) << "the reply came before its delay";
    // The held reply is a deadline of the firmware: a serve loop without frames wakes up for it.
    EXPECT_EQ(p.b.seg->next_firmware_ns(), p.b.now + 3'000'000);
    p.b.advance(2'900'000);
    EXPECT_FALSE(sm1_full());
    EXPECT_FALSE(p.c->receive(5ms));
    p.b.advance(100'000);
    const auto r = p.c->receive(20ms);
    ASSERT_TRUE(r) << "no reply once the delay passed";
    EXPECT_EQ(expedited_value(*r), p.b.desc.identity.product_code);
    // The same device without the quirk answers at once.
    Preop plain(device::default_drive());
    ASSERT_TRUE(plain.c->send(MailboxType::CoE, upload_request(0x1018, 2), plain.c->next_counter()));
    EXPECT_TRUE(plain.c->receive(20ms));
}

// mailbox_drop_every=K: every Kth reply does not reach SM1; the master's repeat request (ETG.1000.4 5.6.3:
// it toggles SM1's repeat bit 0x0806.1, the slave writes the last reply again and acknowledges in 0x0807.1)
// brings it back. Like devices on a noisy line whose reply read got lost, or firmware that loses one.
TEST(Quirks, AMailboxThatLosesEveryKthReplyAndTheRepeatRequestBringsItBack) {
    Preop p(with_quirks({"mailbox_drop_every=3"}));
    const std::uint8_t subs[] = {1, 2, 3, 4, 1, 2};
    const std::uint32_t expect[] = {p.b.desc.identity.vendor_id, p.b.desc.identity.product_code,
                                    p.b.desc.identity.revision, p.b.desc.identity.serial};
    unsigned lost = 0;
    for (unsigned i = 0; i < 6; ++i) {
        ASSERT_TRUE(p.c->send(MailboxType::CoE, upload_request(0x1018, subs[i]), p.c->next_counter()));
        auto r = p.c->receive(30ms);
        if ((i + 1) % 3 == 0) {
            EXPECT_FALSE(r) << "reply " << i + 1 << " was not lost";
            ++lost;
            ASSERT_TRUE(p.c->repeat()) << "no repeat acknowledge";
            r = p.c->receive(30ms);
        }
        ASSERT_TRUE(r) << "reply " << i + 1;
        EXPECT_EQ(expedited_value(*r), expect[subs[i] - 1]) << "reply " << i + 1;
    }
    EXPECT_EQ(lost, 2u);
    EXPECT_EQ(p.b.slave().counters().mailbox_replies_lost, 2u);
    EXPECT_EQ(p.b.slave().counters().mailbox_repeats, 2u);
}

// sii_without=strings+pdo+dc: the SII the master reads has no Strings, TxPDO, RxPDO and DC categories (the
// General category's name index is 0); the master takes the process data sizes from CoE and reaches SAFEOP.
// Like devices with a small EEPROM written by their vendor's own tool.
TEST(Quirks, SiiWithoutOptionalCategories) {
    Preop plain(device::default_drive());
    EXPECT_FALSE(plain.sii().strings.empty());
    EXPECT_FALSE(plain.sii().tx_pdos.empty());
    EXPECT_FALSE(plain.sii().dc_modes.empty());

    Preop p(with_quirks({"sii_without=strings+pdo+dc"}));
    const auto& sii = p.sii();
    EXPECT_TRUE(sii.errors.empty()) << sii.errors.front();
    EXPECT_TRUE(sii.has_general);
    EXPECT_TRUE(sii.strings.empty());
    EXPECT_EQ(sii.name_idx, 0);
    EXPECT_EQ(sii.device_name(), "");
    EXPECT_TRUE(sii.tx_pdos.empty());
    EXPECT_TRUE(sii.rx_pdos.empty());
    EXPECT_TRUE(sii.dc_modes.empty());
    EXPECT_EQ(sii.sync_managers.size(), 4u);
    std::string why;
    ASSERT_TRUE(p.b.master.startup(AlState::SafeOp, &why)) << why;
    EXPECT_EQ(p.b.master.slaves()[0].out_bytes, p.b.desc.output_bytes());
    EXPECT_EQ(p.b.master.slaves()[0].in_bytes, p.b.desc.input_bytes());
}

}  // namespace
