// The wire layouts of src/protocol: each one packed and unpacked again (round trip), and unpacked from bytes
// written out by hand from the specification (so that both sides cannot agree on the same mistake).
#include <gtest/gtest.h>

#include <algorithm>

#include <array>
#include <vector>

#include "protocol/al_status.hpp"
#include "protocol/coe.hpp"
#include "protocol/fmmu.hpp"
#include "protocol/foe.hpp"
#include "protocol/frame.hpp"
#include "protocol/mailbox.hpp"
#include "protocol/registers.hpp"
#include "protocol/sdo_abort.hpp"
#include "protocol/sii.hpp"
#include "protocol/sync_manager.hpp"
#include "protocol/topology.hpp"

using namespace vecat;
using namespace vecat::protocol;

namespace {
template <std::size_t N>
using Raw = std::array<std::uint8_t, N>;
}  // namespace

// ---- Frame (ETG.1000.4 5.3, 5.4)

TEST(ProtocolFrame, EthernetHeaderRoundTripAndEtherTypeBigEndian) {
    const EthernetHeader h{kBroadcastMac, {0x02, 0x10, 0x20, 0x30, 0x40, 0x50}, kEtherTypeEtherCat};
    Raw<EthernetHeader::kSize> b{};
    h.pack(b);
    const Raw<14> spec = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x02, 0x10, 0x20, 0x30, 0x40, 0x50, 0x88, 0xA4};
    EXPECT_EQ(b, spec);
    const auto u = EthernetHeader::unpack(b);
    EXPECT_EQ(u.destination, h.destination);
    EXPECT_EQ(u.source, h.source);
    EXPECT_EQ(u.ether_type, 0x88A4);
}

TEST(ProtocolFrame, PhysicalCommandsThatReadAndWrite) {
    // ETG.1000.4 5.4: which physical commands read and which write at the slaves they address.
    using C = Command;
    const C reads[] = {C::APRD, C::APRW, C::FPRD, C::FPRW, C::BRD, C::BRW, C::ARMW, C::FRMW};
    const C writes[] = {C::APWR, C::APRW, C::FPWR, C::FPRW, C::BWR, C::BRW};
    for (unsigned c = 0; c <= static_cast<unsigned>(C::FRMW); ++c) {
        const auto cmd = static_cast<C>(c);
        EXPECT_EQ(physical_read(cmd), std::find(std::begin(reads), std::end(reads), cmd) != std::end(reads))
            << c;
        EXPECT_EQ(physical_write(cmd),
                  std::find(std::begin(writes), std::end(writes), cmd) != std::end(writes))
            << c;
    }
}

TEST(ProtocolFrame, EcatHeaderLengthAndType) {
    // 44 bytes of datagrams, type 1 (commands): 0x102C little-endian.
    const Raw<2> spec = {0x2C, 0x10};
    const auto h = EcatHeader::unpack(spec);
    EXPECT_EQ(h.length, 44);
    EXPECT_EQ(h.type, kEcatTypeCommands);
    Raw<2> b{};
    h.pack(b);
    EXPECT_EQ(b, spec);
    // The length has 11 bits; bit 11 is reserved and not part of it.
    EXPECT_EQ(EcatHeader::from_word(0x1FFF).length, 0x07FF);
}

TEST(ProtocolFrame, DatagramHeaderFromSpecificationBytes) {
    // FPRD, index 5, ADP 0x1001, ADO 0x0130 (AL status), 2 bytes, more datagrams follow.
    const Raw<10> spec = {0x04, 0x05, 0x01, 0x10, 0x30, 0x01, 0x02, 0x80, 0x00, 0x00};
    const auto h = DatagramHeader::unpack(spec);
    EXPECT_EQ(h.command, Command::FPRD);
    EXPECT_EQ(h.index, 5);
    EXPECT_EQ(h.address, datagram::address(0x1001, addr(Reg::AlStatus)));
    EXPECT_EQ(h.length, 2);
    EXPECT_TRUE(h.more);
    EXPECT_FALSE(h.circulating);
    EXPECT_EQ(h.irq, 0);
    Raw<10> b{};
    h.pack(b);
    EXPECT_EQ(b, spec);
}

TEST(ProtocolFrame, DatagramHeaderRoundTripEveryField) {
    for (const bool flag : {false, true}) {
        const DatagramHeader h{Command::LRW, 0xA5, 0x00010000, 0x07FF, flag, !flag, 0xBEEF};
        Raw<10> b{};
        h.pack(b);
        const auto u = DatagramHeader::unpack(b);
        EXPECT_EQ(u.command, h.command);
        EXPECT_EQ(u.index, h.index);
        EXPECT_EQ(u.address, h.address);
        EXPECT_EQ(u.length, h.length);
        EXPECT_EQ(u.circulating, h.circulating);
        EXPECT_EQ(u.more, h.more);
        EXPECT_EQ(u.irq, h.irq);
    }
}

TEST(ProtocolFrame, PackedFrameParsesBackWithTheSameDatagrams) {
    // A frame as the master builds it, from the layouts: Ethernet, EtherCAT header, two datagrams.
    std::vector<std::uint8_t> f(kMinEthFrame, 0);
    EthernetHeader{kBroadcastMac, {0x10, 0x10, 0x10, 0x10, 0x10, 0x10}}.pack(
        std::span(f).first<kEthHeaderSize>());
    std::size_t off = kEthHeaderSize + kEcatHeaderSize;
    const DatagramHeader d[2] = {{Command::BRD, 1, datagram::address(0, 0), 2, false, true, 0},
                                 {Command::LRW, 2, 0x00010000, 4, false, false, 0}};
    for (const auto& h : d) {
        h.pack(std::span(f).subspan(off).first<kDatagramHeaderSize>());
        off += kDatagramHeaderSize + h.length + kWkcSize;
    }
    EcatHeader{static_cast<std::uint16_t>(off - kEthHeaderSize - kEcatHeaderSize)}.pack(
        std::span(f).subspan<kEthHeaderSize, kEcatHeaderSize>());
    const auto pf = parse_frame(f);
    ASSERT_EQ(pf.error, FrameError::None);
    ASSERT_EQ(pf.count, 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        const auto v = pf.datagram(f, i);
        EXPECT_EQ(v.command(), d[i].command);
        EXPECT_EQ(v.index(), d[i].index);
        EXPECT_EQ(v.length(), d[i].length);
        EXPECT_EQ(v.more(), d[i].more);
        EXPECT_EQ(v.header().address, d[i].address);
    }
}

// ---- Register map (ETG.1000.4 clause 6)

TEST(ProtocolRegisters, RepeatedBlocksAreComputedFromTheirBase) {
    EXPECT_EQ(fmmu_addr(0), 0x0600);
    EXPECT_EQ(fmmu_addr(2), 0x0620);
    EXPECT_EQ(sm_addr(0), 0x0800);
    EXPECT_EQ(sm_addr(3), 0x0818);
    EXPECT_EQ(addr(Reg::AlStatusCode), 0x0134);
}

// ---- FMMU and SyncManager blocks (ETG.1000.4 6.6, 6.7)

TEST(ProtocolFmmu, OutputMappingFromDatasheetBytes) {
    // Logical 0x00010000, 4 bytes, bits 0..7, physical 0x1100 bit 0, write, active.
    const Raw<16> spec = {0x00, 0x00, 0x01, 0x00, 0x04, 0x00, 0x00, 0x07,
                          0x00, 0x11, 0x00, 0x02, 0x01, 0x00, 0x00, 0x00};
    const auto c = FmmuConfig::unpack(spec);
    EXPECT_EQ(c, FmmuConfig::bytes(0x00010000, 4, 0x1100, false, true));
    Raw<16> b{};
    c.pack(b);
    EXPECT_EQ(b, spec);
}

TEST(ProtocolFmmu, BitMappingRoundTrip) {
    const FmmuConfig c{0x12345678, 3, 5, 2, 0x1F00, 6, true, true, true};
    Raw<16> b{};
    c.pack(b);
    EXPECT_EQ(FmmuConfig::unpack(b), c);
    // Only bits 0..2 of the bit fields and bits 0..1 of the type count.
    b[fmmu::LogicalStartBit] |= 0xF8;
    b[fmmu::Type] |= 0xFC;
    EXPECT_EQ(FmmuConfig::unpack(b), c);
}

TEST(ProtocolSyncManager, MailboxOutFromDatasheetBytes) {
    // SM0 at 0x1000, 128 bytes, mailbox mode, ECAT writes, PDI interrupt (0x26), enabled.
    const Raw<8> spec = {0x00, 0x10, 0x80, 0x00, 0x26, 0x00, 0x01, 0x00};
    const auto c = SmConfig::unpack(spec);
    EXPECT_EQ(c, SmConfig::master(0x1000, 128, 0x26));
    EXPECT_TRUE(c.mailbox());
    EXPECT_TRUE(c.ecat_writes());
    EXPECT_TRUE(c.enabled());
    Raw<8> b{};
    c.pack(b);
    EXPECT_EQ(b, spec);
}

TEST(ProtocolSyncManager, RoundTripAndDisabledWithoutLength) {
    const SmConfig c{0x1180,           12, 0x20, sm::StatusIrqRead, sm::ActEnable | sm::ActRepeatRequest,
                     sm::PdiDeactivate};
    Raw<8> b{};
    c.pack(b);
    EXPECT_EQ(SmConfig::unpack(b), c);
    EXPECT_TRUE(c.repeat_request());
    EXPECT_TRUE(c.pdi_deactivated());
    EXPECT_FALSE(SmConfig::master(0x1100, 0, 0x64).enabled());
}

// ---- Mailbox (ETG.1000.4 5.6)

TEST(ProtocolMailbox, HeaderFromSpecificationBytes) {
    // 10 bytes of CoE, address 0, channel 0, priority 0, counter 2.
    const Raw<6> spec = {0x0A, 0x00, 0x00, 0x00, 0x00, 0x23};
    const auto h = MailboxHeader::unpack(spec);
    EXPECT_EQ(h.length, 10);
    EXPECT_EQ(h.type, static_cast<std::uint8_t>(MailboxType::CoE));
    EXPECT_EQ(h.counter, 2);
    Raw<6> b{};
    h.pack(b);
    EXPECT_EQ(b, spec);
}

TEST(ProtocolMailbox, HeaderRoundTripEveryField) {
    const MailboxHeader h{0x05C6, 0x1001, 0x3F, 3, 0x0F, 7};
    Raw<6> b{};
    h.pack(b);
    EXPECT_EQ(b[4], 0xFF);
    EXPECT_EQ(b[5], 0x7F);
    EXPECT_EQ(MailboxHeader::unpack(b), h);
    EXPECT_FALSE(parse_mailbox_header(ConstBytes(b.data(), 5)));
    EXPECT_EQ(*parse_mailbox_header(b), h);
}

TEST(ProtocolMailbox, ErrorReplyAndMessages) {
    Raw<4> b{};
    ASSERT_EQ(make_mailbox_error(b, MailboxError::UnsupportedProtocol), kMailboxErrorSize);
    EXPECT_EQ(b, (Raw<4>{0x01, 0x00, 0x02, 0x00}));
    EXPECT_EQ(describe(MailboxError::InvalidSize), "The length of data is inconsistent");
    EXPECT_EQ(make_mailbox_error(Bytes(b.data(), 3), MailboxError::Syntax), 0u);
}

// ---- FoE (ETG.1000.6 5.8)

TEST(ProtocolFoe, WriteRequestFromSpecificationBytes) {
    // Write request (opcode 2), reserved, password 0x12345678, file name "fw.efw".
    const Raw<12> spec = {0x02, 0x00, 0x78, 0x56, 0x34, 0x12, 'f', 'w', '.', 'e', 'f', 'w'};
    const auto m = parse_foe(spec);
    ASSERT_TRUE(m);
    EXPECT_EQ(m->op, FoeOpCode::Write);
    EXPECT_EQ(m->value, 0x12345678u);
    EXPECT_EQ(m->text(), "fw.efw");
    Raw<12> b{};
    ASSERT_EQ(write_foe_request(b, FoeOpCode::Write, 0x12345678, "fw.efw"), spec.size());
    EXPECT_EQ(b, spec);
}

TEST(ProtocolFoe, EveryMessageRoundTrips) {
    std::array<std::uint8_t, 32> b{};
    const Raw<3> data = {1, 2, 3};
    ASSERT_EQ(write_foe_data(b, 7, data), kFoeHeaderSize + 3);
    auto m = parse_foe(ConstBytes(b.data(), kFoeHeaderSize + 3));
    ASSERT_TRUE(m);
    EXPECT_EQ(m->op, FoeOpCode::Data);
    EXPECT_EQ(m->value, 7u);
    EXPECT_TRUE(std::equal(m->tail.begin(), m->tail.end(), data.begin(), data.end()));

    ASSERT_EQ(write_foe_ack(b, 0x01020304), kFoeHeaderSize);
    EXPECT_EQ((std::array<std::uint8_t, 6>{b[0], b[1], b[2], b[3], b[4], b[5]}),
              (std::array<std::uint8_t, 6>{0x04, 0x00, 0x04, 0x03, 0x02, 0x01}));
    m = parse_foe(ConstBytes(b.data(), kFoeHeaderSize));
    EXPECT_EQ(m->op, FoeOpCode::Ack);
    EXPECT_EQ(m->value, 0x01020304u);
    EXPECT_TRUE(m->tail.empty());

    // Error: code 0x8001 little-endian, then the text of Table 93.
    const std::size_t n = write_foe_error(b, FoeError::NotFound);
    ASSERT_EQ(n, kFoeHeaderSize + describe(FoeError::NotFound).size());
    EXPECT_EQ(b[0], 0x05);
    EXPECT_EQ(b[2], 0x01);
    EXPECT_EQ(b[3], 0x80);
    m = parse_foe(ConstBytes(b.data(), n));
    EXPECT_EQ(static_cast<FoeError>(m->value), FoeError::NotFound);
    EXPECT_EQ(m->text(), "Not found");

    // Busy: done and entire, two 16-bit fields in place of the packet number.
    const std::size_t nb = write_foe_busy(b, 3, 10, "erasing");
    m = parse_foe(ConstBytes(b.data(), nb));
    EXPECT_EQ(m->op, FoeOpCode::Busy);
    EXPECT_EQ(b[2], 3);
    EXPECT_EQ(b[4], 10);
    EXPECT_EQ(m->busy_done(), 3);
    EXPECT_EQ(m->busy_entire(), 10);
    EXPECT_EQ(m->text(), "erasing");
}

TEST(ProtocolFoe, TruncatedAndUnknownAreRefusedAndWritersAreBounded) {
    const Raw<6> unknown = {0x07, 0, 0, 0, 0, 0};
    EXPECT_FALSE(parse_foe(unknown));
    const Raw<5> shorter = {0x03, 0, 1, 0, 0};
    EXPECT_FALSE(parse_foe(shorter));
    const Raw<6> zero = {0x00, 0, 0, 0, 0, 0};
    EXPECT_FALSE(parse_foe(zero));
    std::array<std::uint8_t, 8> b{};
    EXPECT_EQ(write_foe_ack(Bytes(b.data(), 5), 1), 0u);
    EXPECT_EQ(write_foe_request(b, FoeOpCode::Read, 0, "longer than eight"), b.size());  // name cut
    EXPECT_EQ(foe_data_capacity(0xF6), 0xF6u - 12);
    EXPECT_EQ(foe_data_capacity(10), 0u);
    EXPECT_EQ(describe(FoeError::ProgramError), "Program error");
}

// ---- CoE (ETG.1000.6 5.6, CiA 301)

TEST(ProtocolCoe, HeaderAndInitiateUploadRequest) {
    // CoE SDO request, then "initiate upload 0x6041:00" (command 0x40).
    const Raw<10> spec = {0x00, 0x20, 0x40, 0x41, 0x60, 0x00, 0x00, 0x00, 0x00, 0x00};
    EXPECT_EQ(coe_service(ld_le16(spec.data())), CoeService::SdoRequest);
    EXPECT_EQ(coe_header(CoeService::SdoRequest), 0x2000);
    const auto h = SdoHeader::unpack(std::span(spec).subspan<kCoeHeaderSize, kSdoHeaderSize>());
    EXPECT_EQ(h, (SdoHeader{sdo::command(sdo::CcsInitiateUpload), 0x6041, 0, 0}));
    EXPECT_EQ(sdo::ccs(h.command), sdo::CcsInitiateUpload);
    Raw<8> b{};
    h.pack(b);
    EXPECT_TRUE(std::equal(b.begin(), b.end(), spec.begin() + kCoeHeaderSize));
}

TEST(ProtocolCoe, SdoHeaderRoundTrip) {
    const SdoHeader h{sdo::AbortCommand, 0x1C12, 0x01, static_cast<std::uint32_t>(SdoAbort::ReadOnly)};
    Raw<8> b{};
    h.pack(b);
    EXPECT_EQ(b, (Raw<8>{0x80, 0x12, 0x1C, 0x01, 0x02, 0x00, 0x01, 0x06}));
    EXPECT_EQ(SdoHeader::unpack(b), h);
}

TEST(ProtocolCoe, CommandBytesOfCiA301) {
    // Expedited download of 4, 2 and 1 bytes: 0x23, 0x2B, 0x2F; upload responses 0x43, 0x4B, 0x4F.
    EXPECT_EQ(sdo::command(sdo::CcsInitiateDownload, sdo::expedited_size(4)), 0x23);
    EXPECT_EQ(sdo::command(sdo::CcsInitiateDownload, sdo::expedited_size(2)), 0x2B);
    EXPECT_EQ(sdo::command(sdo::CcsInitiateDownload, sdo::expedited_size(1)), 0x2F);
    EXPECT_EQ(sdo::command(sdo::ScsInitiateUpload, sdo::expedited_size(2)), 0x4B);
    for (std::size_t n = 1; n <= 4; ++n)
        EXPECT_EQ(sdo::expedited_length(sdo::expedited_size(n)), n);
    EXPECT_EQ(sdo::expedited_length(sdo::Expedited), 4u);  // size not indicated
    // A last segment of 3 bytes: 4 unused, c = 1.
    EXPECT_EQ(sdo::command(sdo::CcsDownloadSegment, sdo::segment_unused(3) | sdo::LastSegment), 0x09);
    for (std::size_t n = 0; n <= 7; ++n)
        EXPECT_EQ(sdo::segment_length(sdo::segment_unused(n)), n);
    EXPECT_EQ(sdo::segment_unused(100), 0);
}

TEST(ProtocolCoe, SdoInformationHeaders) {
    // An OD list response fragment with more to come, 3 fragments left: opcode 0x02 | 0x80.
    const Raw<4> spec = {0x82, 0x00, 0x03, 0x00};
    const auto h = SdoInfoHeader::unpack(spec);
    EXPECT_EQ(h, (SdoInfoHeader{sdo_info::GetOdListResponse, true, 3}));
    Raw<4> b{};
    h.pack(b);
    EXPECT_EQ(b, spec);

    // Object description of 0x1018: RECORD (object code 9) of type 0x0023 (identity), 4 subindexes.
    const Raw<6> object = {0x18, 0x10, 0x23, 0x00, 0x04, 0x09};
    const auto o = SdoInfoObject::unpack(object);
    EXPECT_EQ(o, (SdoInfoObject{0x1018, 0x0023, 4, 9}));
    Raw<6> ob{};
    o.pack(ob);
    EXPECT_EQ(ob, object);

    // Entry description of 0x6041:00: UNSIGNED16 (0x0006), 16 bits, read in every state (0x0007), default
    // value asked for.
    const Raw<10> entry = {0x41, 0x60, 0x00, 0x10, 0x06, 0x00, 0x10, 0x00, 0x07, 0x00};
    const auto e = SdoInfoEntry::unpack(entry);
    EXPECT_EQ(e, (SdoInfoEntry{0x6041, 0, sdo_info::ValueDefault, 0x0006, 16, 0x0007}));
    Raw<10> eb{};
    e.pack(eb);
    EXPECT_EQ(eb, entry);
}

TEST(ProtocolCoe, EmergencyFromSpecificationBytes) {
    // Following error 0x8611, error register 0x80 (manufacturer), data 01 02 03 04 05.
    const Raw<8> spec = {0x11, 0x86, 0x80, 0x01, 0x02, 0x03, 0x04, 0x05};
    const auto e = Emergency::unpack(spec);
    EXPECT_EQ(e.error_code, 0x8611);
    EXPECT_EQ(e.error_register, 0x80);
    EXPECT_EQ(e.data, (std::array<std::uint8_t, 5>{1, 2, 3, 4, 5}));
    Raw<8> b{};
    e.pack(b);
    EXPECT_EQ(b, spec);
}

TEST(ProtocolCoe, AbortCodesWithMessages) {
    EXPECT_EQ(static_cast<std::uint32_t>(SdoAbort::ObjectDoesNotExist), 0x06020000u);
    EXPECT_EQ(describe(SdoAbort::ObjectDoesNotExist), "The object does not exist in the object dictionary");
    EXPECT_EQ(describe(SdoAbort::Timeout), "SDO protocol timeout");
    EXPECT_EQ(describe(static_cast<SdoAbort>(0x12345678)), "Unknown abort code");
}

// ---- AL (ETG.1000.6 5.3)

TEST(ProtocolAl, StatesAndStatusCodes) {
    for (const std::uint8_t s : std::initializer_list<std::uint8_t>{1, 2, 3, 4, 8})
        EXPECT_TRUE(is_valid_state(s)) << int(s);
    for (const std::uint8_t s : std::initializer_list<std::uint8_t>{0, 5, 6, 7, 9, 0x10, 0x18})
        EXPECT_FALSE(is_valid_state(s)) << int(s);
    EXPECT_EQ(to_string(AlState::SafeOp), "SAFEOP");
    EXPECT_EQ(static_cast<std::uint16_t>(AlStatusCode::SyncManagerWatchdog), 0x001B);
    EXPECT_EQ(describe(AlStatusCode::SyncManagerWatchdog), "Sync manager watchdog");
    EXPECT_EQ(describe(static_cast<AlStatusCode>(0x7777)), "Unknown AL status code");
}

// ---- SII (ETG.2010)

namespace {
// A minimal image written out by hand: the header words, a Strings, a General and a SyncM category, the end.
std::vector<std::uint8_t> hand_made_image() {
    std::vector<std::uint8_t> img(2 * sii::FirstCategory, 0);
    st_le32(img.data() + 2 * sii::VendorId, 0x00000ABC);
    st_le32(img.data() + 2 * sii::ProductCode, 0x12345678);
    st_le16(img.data() + 2 * sii::StdRxMailboxOffset, 0x1000);
    st_le16(img.data() + 2 * sii::StdRxMailboxSize, 128);
    st_le16(img.data() + 2 * sii::MailboxProtocol, sii::MailboxCoE);
    img[2 * sii::Checksum] = sii_config_crc(ConstBytes(img.data(), sii::kConfigAreaSize));
    auto put = [&](std::initializer_list<std::uint8_t> bytes) { img.insert(img.end(), bytes); };
    put({10, 0, 3, 0, 1, 4, 'D', 'r', 'v', '1'});  // Strings (3 words): 1 string of 4 characters
    put({30, 0, 16, 0});                           // General (16 words): the name is string 1
    std::vector<std::uint8_t> general(sii::kGeneralSize, 0);
    general[sii::general::NameIdx] = 1;
    img.insert(img.end(), general.begin(), general.end());
    put({41, 0, 8, 0});                                     // SyncM (8 words): 2 SyncManagers
    put({0x00, 0x10, 0x80, 0x00, 0x26, 0x00, 0x01, 0x01});  // mailbox out
    put({0x00, 0x11, 0x04, 0x00, 0x64, 0x00, 0x01, 0x03});  // outputs
    put({0xFF, 0xFF});                                      // end
    return img;
}
}  // namespace

TEST(ProtocolSii, ParsesAHandMadeImage) {
    const auto img = hand_made_image();
    const auto s = parse_sii(img);
    EXPECT_TRUE(s.errors.empty()) << s.errors.front();
    EXPECT_TRUE(s.checksum_ok);
    EXPECT_EQ(s.identity.vendor_id, 0xABCu);
    EXPECT_EQ(s.identity.product_code, 0x12345678u);
    EXPECT_EQ(s.std_rx_mbx_offset, 0x1000);
    EXPECT_EQ(s.std_rx_mbx_size, 128);
    EXPECT_EQ(s.mailbox_protocols, sii::MailboxCoE);
    ASSERT_TRUE(s.has_general);
    EXPECT_EQ(s.device_name(), "Drv1");
    ASSERT_EQ(s.sync_managers.size(), 2u);
    EXPECT_EQ(s.sync_managers[0].start, 0x1000);
    EXPECT_EQ(s.sync_managers[0].control, 0x26);
    EXPECT_EQ(s.sync_managers[0].type, sii::SmTypeMailboxOut);
    EXPECT_EQ(s.sync_managers[1].length, 4);
    EXPECT_EQ(s.sync_managers[1].type, sii::SmTypeOutputs);
}

TEST(ProtocolSii, TruncatedImageReportsAndNeverReadsPast) {
    auto img = hand_made_image();
    img.resize(img.size() - 4);  // the end marker and part of SM2 are cut off
    const auto s = parse_sii(img);
    EXPECT_FALSE(s.errors.empty());
    EXPECT_EQ(s.device_name(), "Drv1");  // what came before is kept
}

// The frame's order through a tree (ESC datasheet section I: ports 0 -> 3 -> 1 -> 2), depth first.
TEST(Topology, FrameOrderVisitsPort3ThenPort1ThenPort2DepthFirst) {
    // 0: port 1 -> 1, port 2 -> 4, port 3 -> 2; 2: port 1 -> 3.
    const std::vector<std::array<int, 4>> children = {
        {-1, 1, 4, 2}, {-1, -1, -1, -1}, {-1, 3, -1, -1}, {-1, -1, -1, -1}, {-1, -1, -1, -1}};
    EXPECT_EQ(protocol::frame_order(children), (std::vector<std::size_t>{0, 2, 3, 1, 4}));
    // Cables in a loop: each device once; a device not reached is not in the order.
    const std::vector<std::array<int, 4>> loop = {{-1, 1, -1, -1}, {-1, 0, -1, -1}, {-1, -1, -1, -1}};
    EXPECT_EQ(protocol::frame_order(loop), (std::vector<std::size_t>{0, 1}));
    EXPECT_TRUE(protocol::frame_order({}).empty());
}
