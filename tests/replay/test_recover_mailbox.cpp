// The CoE dictionary recovered from a capture's mailbox traffic (src/replay/recover_mailbox.*): the
// messages are the ones real devices of ../shared/data/pcap sent, written out byte by byte, so that these
// tests run without ../shared.
#include <gtest/gtest.h>

#include <initializer_list>

#include "common/bytes.hpp"
#include "device/object_description.hpp"
#include "replay/recover_mailbox.hpp"

using namespace vecat;
using replay::MailboxRecoverer;
using replay::RecoveredDictionary;

namespace {

std::vector<std::uint8_t> hex(const std::string& s) {
    std::vector<std::uint8_t> v;
    for (std::size_t i = 0; i + 1 < s.size(); i += 2)
        v.push_back(static_cast<std::uint8_t>(std::stoul(s.substr(i, 2), nullptr, 16)));
    return v;
}

// SM0 at 0x1000, SM1 at 0x1080 (as SOEM writes both blocks in one datagram).
MailboxRecoverer with_mailboxes() {
    MailboxRecoverer m;
    const auto sm = hex("00108000260001008010800022000100");
    m.wrote(0x0800, sm.data(), sm.size());
    return m;
}
void request(MailboxRecoverer& m, const std::string& h) {
    auto b = hex(h);
    b.resize(128);
    m.wrote(0x1000, b.data(), b.size());
}
void reply(MailboxRecoverer& m, const std::string& h) {
    auto b = hex(h);
    b.resize(128, 0xAE);  // the rest of the area holds whatever the device's memory held
    m.read(0x1080, b.data(), b.size());
}
std::vector<std::uint8_t> value(const RecoveredDictionary& d, std::uint16_t i, std::uint8_t s) {
    auto it = d.values.find({i, s});
    return it == d.values.end() ? std::vector<std::uint8_t>{} : it->second;
}

}  // namespace

// Expedited upload (EL3004 of ek1914-el3004-mailbox: 0x100A "08").
TEST(RecoverMailbox, ExpeditedUpload) {
    auto m = with_mailboxes();
    request(m, "0a00000000130020400a1000000000000000");
    reply(m, "0a000000001300304b0a1000303800000000");
    EXPECT_EQ(value(m.result(), 0x100A, 0), hex("3038"));
}

// A reply read from another address (not the mailbox-in area) is not taken.
TEST(RecoverMailbox, OnlyTheMailboxInAreaIsAReply) {
    auto m = with_mailboxes();
    request(m, "0a00000000130020400a1000000000000000");
    auto b = hex("0a000000001300304b0a1000303800000000");
    m.read(0x1100, b.data(), b.size());
    EXPECT_TRUE(m.result().values.empty());
}

// Complete access (SOES behind a LAN9252, soem-lan9252): subindex 0 in 16 bits, then the entries of the
// object's fixed layout (0x1C00: U8, 0x1C12: U16).
TEST(RecoverMailbox, CompleteAccessUploadIsSplitIntoEntries) {
    auto m = with_mailboxes();
    request(m, "0a0000000013002050001c000000000000000000");
    reply(m, "100000000013003051001c00060000000400010203040000");
    request(m, "0a0000000023002050121c000000000000000000");
    reply(m, "0a0000000023003053121c0001000116");
    const auto& d = m.result();
    EXPECT_EQ(value(d, 0x1C00, 0), hex("04"));
    EXPECT_EQ(value(d, 0x1C00, 3), hex("03"));
    EXPECT_EQ(value(d, 0x1C12, 0), hex("01"));
    EXPECT_EQ(value(d, 0x1C12, 1), hex("0116"));
}

// A normal upload followed by segments (ETG.1000.6 5.6.2.3): the value is the concatenation, taken when the
// last segment makes the size the initiate response announced.
TEST(RecoverMailbox, SegmentedUpload) {
    const auto start = [](MailboxRecoverer& m) {
        request(m, "0a000000001300204008100000000000");
        reply(m,
              "0d0000000013003041081000"
              "0a000000"
              "414243");                                 // size 10, 3 bytes here
        request(m, "0a000000002300206000000000000000");  // upload segment request
    };
    auto m = with_mailboxes();
    start(m);
    reply(m,
          "0a0000000023003001"
          "44454647484950");  // last segment, 7 bytes: 3 + 7 = 10
    EXPECT_EQ(value(m.result(), 0x1008, 0), hex("41424344454647484950"));
    auto short_one = with_mailboxes();
    start(short_one);
    reply(short_one,
          "0a0000000023003009"
          "44454647484950");  // last, 7 - 4 unused = 3 bytes: 6 != 10
    EXPECT_TRUE(short_one.result().values.empty());
}

// SDO information: the object list (in fragments), an object and an entry description.
TEST(RecoverMailbox, SdoInformation) {
    auto m = with_mailboxes();
    request(m, "0800000000130080010000000100");
    reply(m,
          "0c000000001300808200010001000010"
          "0810");                             // incomplete, 1 fragment left: list 1000 1008
    reply(m, "0800000000230080020000001810");  // last fragment: 1018
    // Object description of 0x1018: RECORD, type 0x0023, max subindex 4, "Identity".
    reply(m, "1400000000330080040000001810230004094964656e74697479");
    // Entry description of 0x1018:01: U32 (0x0007), 32 bits, read in all states, with a default.
    reply(m, "1a0000000043008006000000181001100700200007000200000056656e646f72");
    const auto& d = m.result();
    ASSERT_TRUE(d.all_objects);
    EXPECT_EQ(*d.all_objects, (std::vector<std::uint16_t>{0x1000, 0x1008, 0x1018}));
    ASSERT_TRUE(d.objects.contains(0x1018));
    const auto& o = d.objects.at(0x1018);
    EXPECT_EQ(o.name, "Identity");
    EXPECT_EQ(o.code, device::ObjectCode::Record);
    EXPECT_EQ(o.max_subindex(), 4);
    ASSERT_NE(o.entry(1), nullptr);
    EXPECT_EQ(o.entry(1)->name, "Vendor");
    EXPECT_EQ(o.entry(1)->bit_length, 32);
    EXPECT_EQ(o.entry(1)->default_value, hex("02000000"));
}

// Aborts say what does not exist; a confirmed download says what is writable.
TEST(RecoverMailbox, AbortsAndConfirmedDownloads) {
    auto m = with_mailboxes();
    request(m, "0a0000000013002040322200000000000");
    reply(m, "0a000000001300208032220000000206");      // 0x2232:00: object does not exist
    request(m, "0a000000002300202f131c000000000000");  // download 0x1C13:00 = 0
    reply(m, "0a00000000230030601313000000000000");    // a response for another index: not taken
    request(m, "0a000000003300202f131c000000000000");
    reply(m, "0a0000000033003060131c000000000000");
    const auto& d = m.result();
    EXPECT_TRUE(d.absent_objects.contains(0x2232));
    EXPECT_EQ(d.written.size(), 1u);
    EXPECT_TRUE(d.written.contains({0x1C13, 0}));
}

// A download response repeating the request's data field in its reserved bytes (the EL3004 of
// ek1914-el3004-configure: 0x1C13:01 = 0x1A00) is the device's quirk sdo_download_echo; zeros are not.
TEST(RecoverMailbox, DownloadResponseEchoingTheRequestData) {
    auto m = with_mailboxes();
    request(m, "0a000000003300202b131c01001a00000000");
    reply(m, "0a0000000033003060131c01000000000000");
    EXPECT_FALSE(m.result().download_echo);
    request(m, "0a000000004300202b131c01001a00000000");
    reply(m, "0a0000000043003060131c01001a00000000");
    EXPECT_TRUE(m.result().download_echo);
}

// The SM1 status read first after the master read a message: 0x80 (write buffer in use, not interrupt read)
// after most of them, as the EL3004 of the ek1914 captures shows, is the device's quirk mailbox_open_early;
// 0x02 after most of them is an ESC whose firmware writes each message at once.
TEST(RecoverMailbox, Sm1OpenedAfterMostReadsIsTheQuirkMailboxOpenEarly) {
    const auto sm1_status = [](MailboxRecoverer& m, std::uint8_t st) { m.read(0x080D, &st, 1); };
    for (const std::uint8_t after : std::initializer_list<std::uint8_t>{0x02, 0x80}) {
        auto m = with_mailboxes();
        sm1_status(m, 0x80);  // not after a read: not counted
        sm1_status(m, 0x80);
        for (int i = 0; i < 3; ++i) {
            request(m, "0a00000000130020400a1000000000000000");
            reply(m, "0a000000001300304b0a1000303800000000");
            sm1_status(m, after);
            sm1_status(m, 0x09);  // the next read after it: not counted either
        }
        EXPECT_EQ(m.result().open_early, after == 0x80) << int{after};
    }
}

// The merge: described objects replace generated ones, values become entries, absent objects go, the
// objects a PDO mapping maps exist and are mappable, a confirmed assignment names PDOs that exist.
TEST(RecoverMailbox, MergeOverTheGeneratedDictionary) {
    std::vector<device::ObjectDescription> generated;
    generated.push_back(
        device::make_var(0x1000, "Device type", device::DataType::Unsigned32, device::access::RO));
    generated.push_back(
        device::make_var(0x2232, "Generated", device::DataType::Unsigned8, device::access::RO));
    generated.push_back(device::make_record(
        0x1C13, "TxPDO assign",
        {device::make_entry(1, "PDO 1", device::DataType::Unsigned16, device::access::RW)}));
    generated.back().entries.front().maximum = {1};
    RecoveredDictionary r;
    r.absent_objects.insert(0x2232);
    r.values[{0x1A00, 0}] = {2};
    r.values[{0x1A00, 1}] = hex("08010060");  // 0x6000:01, 8 bits
    r.values[{0x1A00, 2}] = hex("01070218");  // 0x1802:07, 1 bit
    r.written[{0x1C13, 2}] = hex("021a");     // 0x1C13:02 = 0x1A02
    std::map<std::pair<std::uint16_t, std::uint8_t>, std::vector<std::uint8_t>> values;
    const auto merged = replay::merge_dictionary(generated, r, values);
    const auto find = [&](std::uint16_t i) -> const device::ObjectDescription* {
        for (const auto& o : merged)
            if (o.index == i) return &o;
        return nullptr;
    };
    EXPECT_NE(find(0x1000), nullptr);
    EXPECT_EQ(find(0x2232), nullptr);
    ASSERT_NE(find(0x1A00), nullptr);
    EXPECT_EQ(find(0x1A00)->code, device::ObjectCode::Record);
    ASSERT_NE(find(0x6000), nullptr);
    ASSERT_NE(find(0x6000)->entry(1), nullptr);
    EXPECT_EQ(find(0x6000)->entry(1)->bit_length, 8);
    EXPECT_TRUE(find(0x6000)->entry(1)->access & device::access::TxPdoMappable);
    ASSERT_NE(find(0x1802), nullptr);
    ASSERT_NE(find(0x1802)->entry(7), nullptr);
    EXPECT_EQ(find(0x1802)->entry(7)->type, device::DataType::Boolean);
    ASSERT_NE(find(0x1C13), nullptr);
    ASSERT_NE(find(0x1C13)->entry(2), nullptr);
    EXPECT_TRUE(find(0x1C13)->entry(2)->access & device::access::WritePreop);
    EXPECT_EQ(find(0x1C13)->entries.front().maximum, std::vector<std::uint8_t>{2});
    EXPECT_NE(find(0x1A02), nullptr);
    EXPECT_EQ(values.at({0x1A00, 1}), hex("08010060"));
}
