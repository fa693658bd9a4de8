// SoE (ETG.1000.6 5.6) (about 670 lines: one protocol, each error code its own test): the wire layout of
// protocol/soe.hpp (round trips, bytes written by hand from the header layout), the SoE server's cases
// (read and write of elements, segmented transfers both ways, notifications) with every SoE error code and
// mailbox error it answers, and the SoE drive behind the project's master: the AT/MDT mapping through
// S-0-0015/0016/0024 as SOEM's ecx_readIDNmap reads it, the process data, the procedure commands. The
// drive's motion, its two axes and the commands' timing: test_soe_drive.cpp.
#include <gtest/gtest.h>

#include <map>

#include "esc/sii_image.hpp"
#include "soe_bench.hpp"

using namespace vecat;
using namespace vecat::test;
using namespace vecat::test::soe_bench;  // and its names of the protocol (AlState, Idn, SoeError, el...)
namespace idn = soe::idn;

// ---- Wire layout

TEST(SoeProtocol, ReadRequestFromTheHeaderLayout) {
    // opcode 1, drive 2 (bits 5-7), value element, S-0-0024.
    const std::vector<std::uint8_t> wire = {0x41, 0x40, 0x18, 0x00};
    const auto m = protocol::parse_soe(wire);
    ASSERT_TRUE(m);
    EXPECT_EQ(m->op, SoeOpCode::ReadRequest);
    EXPECT_EQ(m->drive, 2);
    EXPECT_FALSE(m->incomplete);
    EXPECT_FALSE(m->error);
    EXPECT_EQ(m->elements, el::Value);
    EXPECT_EQ(m->idn(), protocol::s_idn(24));
    EXPECT_EQ(request(SoeOpCode::ReadRequest, 2, el::Value, 24), wire);
}

TEST(SoeProtocol, EveryFieldRoundTrips) {
    for (unsigned op = 0; op < 8; ++op)
        for (unsigned drive = 0; drive < 8; ++drive)
            for (bool inc : {false, true})
                for (bool err : {false, true}) {
                    SoeMessage m;
                    m.op = static_cast<SoeOpCode>(op);
                    m.drive = static_cast<std::uint8_t>(drive);
                    m.incomplete = inc;
                    m.error = err;
                    m.elements = static_cast<std::uint8_t>(0x5A ^ op);
                    m.idn_or_fragments = static_cast<std::uint16_t>(0x8064 + drive);
                    const std::uint8_t data[3] = {1, 2, 3};
                    m.data = ConstBytes(data, 3);
                    std::uint8_t b[16];
                    ASSERT_EQ(protocol::write_soe(b, m), 7u);
                    const auto p = protocol::parse_soe(ConstBytes(b, 7));
                    ASSERT_TRUE(p);
                    EXPECT_EQ(p->op, m.op);
                    EXPECT_EQ(p->drive, m.drive);
                    EXPECT_EQ(p->incomplete, inc);
                    EXPECT_EQ(p->error, err);
                    EXPECT_EQ(p->elements, m.elements);
                    EXPECT_EQ(p->idn_or_fragments, m.idn_or_fragments);
                    EXPECT_EQ(p->data.size(), 3u);
                }
    EXPECT_FALSE(protocol::parse_soe(std::vector<std::uint8_t>{1, 2, 3}));
}

TEST(SoeProtocol, ErrorResponseCarriesTheCodeAfterTheHeader) {
    std::uint8_t b[16];
    const auto n = protocol::write_soe_error(b, SoeOpCode::WriteResponse, 1, el::Value, protocol::s_idn(47),
                                             SoeError::DataTooLong);
    ASSERT_EQ(n, 6u);
    // opcode 4 | error (bit 4) | drive 1 (bits 5-7); elements; IDN 47; code 0x7003.
    EXPECT_EQ(std::vector<std::uint8_t>(b, b + 6),
              (std::vector<std::uint8_t>{0x34, 0x40, 47, 0, 0x03, 0x70}));
    EXPECT_EQ(protocol::parse_soe(ConstBytes(b, n))->error_code(), 0x7003);
}

TEST(SoeProtocol, AttributeBitsAndIdnNumbers) {
    protocol::SoeAttribute a;
    a.conversion = 1;
    a.length_code = 2;
    a.type = protocol::SoeDataType::Signed;
    a.wp_safeop = true;
    a.wp_op = true;
    EXPECT_EQ(a.pack(), 0x60220001u);
    EXPECT_EQ(protocol::SoeAttribute::unpack(a.pack()), a);
    a.list = true;
    a.command = true;
    a.decimals = 9;
    a.wp_preop = true;
    EXPECT_EQ(protocol::SoeAttribute::unpack(a.pack()), a);
    EXPECT_EQ(a.element_size(), 4u);
    EXPECT_EQ(protocol::s_idn(24).raw, 24);
    EXPECT_EQ(protocol::p_idn(100).raw, 0x8064);
    EXPECT_EQ(protocol::idn_name(protocol::p_idn(100, 1)), "P-1-0100");
    EXPECT_EQ(protocol::idn_name(protocol::s_idn(24)), "S-0-0024");
    EXPECT_EQ(protocol::describe(SoeError::NoIdn), "No IDN");
}

// ---- The server: reads

TEST(SoeRead, ElementsComeInWireOrder) {
    DriveBench d;
    const auto m = d.read(el::Name | el::Attribute | el::Unit | el::Value, idn::PositionCommand);
    ASSERT_FALSE(m.error);
    const std::string name = "Position command value";
    std::vector<std::uint8_t> want =
        list({name.begin(), name.end()}, static_cast<std::uint16_t>(name.size()));
    const auto a = u32(d.drive.table(0).find(idn::PositionCommand)->attribute.pack());
    want.insert(want.end(), a.begin(), a.end());
    const auto unit = list({'i', 'n', 'c'}, 3);
    want.insert(want.end(), unit.begin(), unit.end());
    const auto v = u32(0);
    want.insert(want.end(), v.begin(), v.end());
    EXPECT_EQ(std::vector<std::uint8_t>(m.data.begin(), m.data.end()), want);
    EXPECT_EQ(m.elements, el::Name | el::Attribute | el::Unit | el::Value);
}

TEST(SoeRead, MinMaxDefaultAndDataState) {
    DriveBench d;
    auto m = d.read(el::Min | el::Max | el::Default, idn::TelegramType);
    ASSERT_FALSE(m.error);
    EXPECT_EQ(std::vector<std::uint8_t>(m.data.begin(), m.data.end()),
              (std::vector<std::uint8_t>{0, 0, 7, 0, 4, 0}));
    m = d.read(el::DataState, idn::ResetClass1Diagnostic);
    EXPECT_EQ(ld_le16(m.data.data()), soe::command_state::NotSet);
}

TEST(SoeRead, TheMdtAndAtConfigurationAsSoemReadsIt) {
    DriveBench d;
    auto m = d.read(el::Value, idn::MdtConfiguration);
    EXPECT_EQ(std::vector<std::uint8_t>(m.data.begin(), m.data.end()),
              (std::vector<std::uint8_t>{2, 0, 16, 0, 47, 0}));
    m = d.read(el::Value, idn::AtConfiguration);
    EXPECT_EQ(std::vector<std::uint8_t>(m.data.begin(), m.data.end()),
              (std::vector<std::uint8_t>{2, 0, 16, 0, 51, 0}));
    // The attribute's length (bits 16-17: 2 = 4 bytes), not a list: SOEM adds 8 << 2 bits.
    m = d.read(el::Attribute, idn::PositionFeedback);
    const auto a = protocol::SoeAttribute::unpack(ld_le32(m.data.data()));
    EXPECT_EQ(a.length_code, 2);
    EXPECT_FALSE(a.list);
}

TEST(SoeRead, LongValueGoesInFragmentsOneAtATime) {
    DriveBench d;
    std::vector<std::uint8_t> bytes(400);
    for (std::size_t i = 0; i < bytes.size(); ++i)
        bytes[i] = static_cast<std::uint8_t>(i * 3);
    ASSERT_FALSE(d.write(el::Value, idn::DataContainer, list(bytes, 0)).error);
    d.sink.sent.clear();
    d.server.handle({}, request(SoeOpCode::ReadRequest, 0, el::Value, idn::DataContainer.raw), d.sink);
    const std::size_t cap = d.sink.buf.size() - protocol::kSoeHeaderSize;  // 118
    const std::size_t total = 4 + bytes.size();
    const std::size_t n = (total + cap - 1) / cap;
    ASSERT_EQ(d.sink.sent.size(), 1u);
    d.sink.unread = 1;  // the master has not read it: nothing more
    d.server.poll(d.sink);
    EXPECT_EQ(d.sink.sent.size(), 1u);
    d.sink.unread = 0;
    while (d.server.has_output() && d.sink.sent.size() < 10)
        d.server.poll(d.sink);
    ASSERT_EQ(d.sink.sent.size(), n);
    std::vector<std::uint8_t> got;
    for (std::size_t i = 0; i < n; ++i) {
        const auto m = *protocol::parse_soe(d.sink.sent[i].second);
        EXPECT_EQ(m.incomplete, i + 1 < n);
        EXPECT_EQ(m.idn_or_fragments,
                  i + 1 < n ? n - 1 - i : idn::DataContainer.raw);  // fragments left, then IDN
        got.insert(got.end(), m.data.begin(), m.data.end());
    }
    EXPECT_EQ(got, list(bytes, 1024));
    EXPECT_EQ(d.server.buffered(), 0u);
    EXPECT_EQ(d.server.counters().fragments_sent, n - 1);
}

TEST(SoeRead, ANewRequestEndsASegmentedRead) {
    DriveBench d;
    ASSERT_FALSE(d.write(el::Value, idn::DataContainer, list(std::vector<std::uint8_t>(400, 1))).error);
    d.server.handle({}, request(SoeOpCode::ReadRequest, 0, el::Value, idn::DataContainer.raw), d.sink);
    EXPECT_TRUE(d.server.fragments_pending());
    EXPECT_FALSE(d.read(el::Value, idn::TelegramType).error);
    EXPECT_FALSE(d.server.fragments_pending());
    EXPECT_EQ(d.server.counters().transfers_abandoned, 1u);
}

// ---- The server: writes

TEST(SoeWrite, ValueIsStoredAndAnsweredWithoutData) {
    DriveBench d;
    const auto m = d.write(el::Value, idn::MonitoringWindow, u32(5000));
    EXPECT_FALSE(m.error);
    EXPECT_EQ(m.op, SoeOpCode::WriteResponse);
    EXPECT_TRUE(m.data.empty());
    EXPECT_EQ(d.drive.table(0).find(idn::MonitoringWindow)->number(), 5000u);
}

TEST(SoeWrite, FragmentsAreHeldUnansweredUntilTheLastNamesTheIdn) {
    DriveBench d;
    std::vector<std::uint8_t> bytes(300);
    for (std::size_t i = 0; i < bytes.size(); ++i)
        bytes[i] = static_cast<std::uint8_t>(i);
    const auto v = list(bytes, 0);
    // Three fragments of at most 118 bytes; the count of the first two is not checked (masters differ).
    const std::size_t cap = 118;
    d.server.handle({}, request(SoeOpCode::WriteRequest, 0, el::Value, 2, ConstBytes(v.data(), cap), true),
                    d.sink);
    d.server.handle(
        {}, request(SoeOpCode::WriteRequest, 0, el::Value, 7, ConstBytes(v.data() + cap, cap), true), d.sink);
    EXPECT_TRUE(d.sink.sent.empty());
    EXPECT_EQ(d.server.buffered(), 2 * cap);
    d.server.handle({},
                    request(SoeOpCode::WriteRequest, 0, el::Value, idn::DataContainer.raw,
                            ConstBytes(v.data() + 2 * cap, v.size() - 2 * cap)),
                    d.sink);
    ASSERT_EQ(d.sink.sent.size(), 1u);
    EXPECT_FALSE(d.sink.last().error);
    EXPECT_EQ(d.drive.table(0).find(idn::DataContainer)->value, bytes);
    EXPECT_EQ(d.server.buffered(), 0u);
    EXPECT_EQ(d.server.counters().fragments_received, 2u);
}

TEST(SoeWrite, TooManyFragmentsAreAnswered0x7003WithBoundedMemory) {
    DriveBench d;
    const std::vector<std::uint8_t> chunk(118, 0xAA);
    for (int i = 0; i < 60; ++i) {
        d.server.handle({}, request(SoeOpCode::WriteRequest, 0, el::Value, 1, chunk, true), d.sink);
        EXPECT_LE(d.server.buffered(), soe::SoeServer::kMaxTransfer);
    }
    EXPECT_TRUE(d.sink.sent.empty());
    EXPECT_EQ(d.write_error(idn::DataContainer, chunk), code(SoeError::DataTooLong));
    EXPECT_EQ(d.server.buffered(), 0u);
}

TEST(SoeWrite, AnotherRequestOrTheMailboxResetEndsAFragmentedWrite) {
    DriveBench d;
    const std::vector<std::uint8_t> chunk(100, 7);
    d.server.handle({}, request(SoeOpCode::WriteRequest, 0, el::Value, 1, chunk, true), d.sink);
    EXPECT_EQ(d.server.buffered(), 100u);
    // A fragment of other elements starts a transfer of its own: the first one is dropped.
    d.server.handle({}, request(SoeOpCode::WriteRequest, 0, el::Name, 1, chunk, true), d.sink);
    EXPECT_EQ(d.server.buffered(), 100u);
    EXPECT_EQ(d.server.counters().transfers_abandoned, 1u);
    // INIT (esc::MailboxProtocol::reset) drops it too, without an answer.
    d.server.reset();
    EXPECT_EQ(d.server.buffered(), 0u);
    EXPECT_EQ(d.server.counters().transfers_abandoned, 2u);
    EXPECT_TRUE(d.sink.sent.empty());
    // Nothing is left of it: the next write is a plain one.
    EXPECT_EQ(d.write_error(idn::DataContainer, list(std::vector<std::uint8_t>(8, 1))), std::nullopt);
}

// ---- Every SoE error code the server answers

TEST(SoeErrors, NoIdn0x1001OnReadAndWrite) {
    DriveBench d;
    EXPECT_EQ(d.read_error(protocol::s_idn(999), el::Value), code(SoeError::NoIdn));
    EXPECT_EQ(d.write_error(protocol::p_idn(7), u16(1)), code(SoeError::NoIdn));
    // The error response repeats the request's IDN, drive and elements.
    EXPECT_EQ(d.sink.last().idn(), protocol::p_idn(7));
    EXPECT_EQ(d.sink.last().elements, el::Value);
}

TEST(SoeErrors, InvalidDriveNumber0x800A) {
    DriveBench d;
    const auto m = d.read(el::Value, idn::TelegramType, 1);
    EXPECT_EQ(m.error_code(), code(SoeError::InvalidDriveNumber));
    EXPECT_EQ(m.drive, 1);
    EXPECT_EQ(d.write(el::Value, idn::TelegramType, u16(4), 7).error_code(),
              code(SoeError::InvalidDriveNumber));
}

TEST(SoeErrors, NoElementAddressed0x800C) {
    DriveBench d;
    EXPECT_EQ(d.read_error(idn::TelegramType, 0), code(SoeError::NoElementAddressed));
    EXPECT_EQ(d.write_error(idn::TelegramType, u16(4), 0), code(SoeError::NoElementAddressed));
}

TEST(SoeErrors, GeneralError0x800BForAReadRequestInFragments) {
    DriveBench d;
    d.server.handle({}, request(SoeOpCode::ReadRequest, 0, el::Value, 3, {}, true), d.sink);
    EXPECT_EQ(d.sink.last().error_code(), code(SoeError::GeneralError));
}

TEST(SoeErrors, MissingElementsOnRead0x2001_0x4001_0x5001_0x6001_0x8001) {
    // A table of one bare IDN: no name, unit, limits or default.
    struct Bare final : soe::SoeDevice {
        soe::IdnTable t{[] {
            soe::IdnEntry e;
            e.idn = protocol::p_idn(1);
            e.value = {0, 0};
            return std::vector<soe::IdnEntry>{e};
        }()};
        unsigned drives() const override { return 1; }
        soe::IdnTable& table(unsigned) override { return t; }
        AlState phase() const override { return AlState::PreOp; }
        std::optional<SoeError> write_value(unsigned, soe::IdnEntry&, ConstBytes) override {
            return std::nullopt;
        }
    } bare;
    soe::SoeServer s(bare);
    Sink sink;
    auto err = [&](std::uint8_t elements, SoeOpCode op = SoeOpCode::ReadRequest) {
        s.handle({}, request(op, 0, elements, protocol::p_idn(1).raw, u16(1)), sink);
        return sink.last().error_code();
    };
    EXPECT_EQ(err(el::Name), code(SoeError::NoName));
    EXPECT_EQ(err(el::Unit), code(SoeError::NoUnit));
    EXPECT_EQ(err(el::Min), code(SoeError::NoMin));
    EXPECT_EQ(err(el::Max), code(SoeError::NoMax));
    EXPECT_EQ(err(el::Default), code(SoeError::NoDefault));
    // The same elements written: "no ...".
    EXPECT_EQ(err(el::Name, SoeOpCode::WriteRequest), code(SoeError::NoName));
    EXPECT_EQ(err(el::Unit, SoeOpCode::WriteRequest), code(SoeError::NoUnit));
    EXPECT_EQ(err(el::Min, SoeOpCode::WriteRequest), code(SoeError::NoMin));
    EXPECT_EQ(err(el::Max, SoeOpCode::WriteRequest), code(SoeError::NoMax));
    EXPECT_EQ(err(el::Default, SoeOpCode::WriteRequest), code(SoeError::NoDefault));
    EXPECT_FALSE(err(el::Value | el::DataState | el::Attribute, SoeOpCode::ReadRequest));
}

TEST(SoeErrors, ElementsOtherThanTheValueAreReadOnly) {
    DriveBench d;
    const auto v = u32(1);
    EXPECT_EQ(d.write_error(idn::MonitoringWindow, v, el::DataState), code(SoeError::InvalidAccessElement1));
    EXPECT_EQ(d.write_error(idn::MonitoringWindow, v, el::Name), code(SoeError::NameReadOnly));
    EXPECT_EQ(d.write_error(idn::MonitoringWindow, v, el::Attribute), code(SoeError::AttributeReadOnly));
    EXPECT_EQ(d.write_error(idn::MonitoringWindow, v, el::Unit), code(SoeError::UnitReadOnly));
    EXPECT_EQ(d.write_error(idn::MonitoringWindow, v, el::Min), code(SoeError::MinReadOnly));
    EXPECT_EQ(d.write_error(idn::MonitoringWindow, v, el::Max), code(SoeError::MaxReadOnly));
    EXPECT_EQ(d.write_error(idn::MonitoringWindow, v, el::Default), code(SoeError::DefaultReadOnly));
    // Value and another element: the other's error.
    EXPECT_EQ(d.write_error(idn::MonitoringWindow, v, el::Value | el::Unit), code(SoeError::UnitReadOnly));
}

TEST(SoeErrors, DataTooShort0x7002AndTooLong0x7003) {
    DriveBench d;
    EXPECT_EQ(d.write_error(idn::MonitoringWindow, u16(1)), code(SoeError::DataTooShort));
    EXPECT_EQ(d.write_error(idn::MonitoringWindow, {1, 2, 3, 4, 5}), code(SoeError::DataTooLong));
    // A list: its current length against the data carried and its maximum.
    EXPECT_EQ(d.write_error(idn::DataContainer, {8, 0, 0, 0, 1, 2, 3, 4}), code(SoeError::DataTooShort));
    EXPECT_EQ(d.write_error(idn::DataContainer, {4, 0, 0, 0, 1, 2, 3, 4, 5}), code(SoeError::DataTooLong));
    EXPECT_EQ(d.write_error(idn::DataContainer, {0x10, 0x04}), code(SoeError::DataTooShort));
    EXPECT_EQ(d.write_error(idn::DataContainer, list(std::vector<std::uint8_t>(1028, 0))),
              code(SoeError::DataTooLong));
}

TEST(SoeErrors, DataReadOnly0x7004) {
    DriveBench d;
    EXPECT_EQ(d.write_error(idn::PositionFeedback, u32(1)), code(SoeError::DataReadOnly));
    EXPECT_EQ(d.write_error(idn::AllOperationData, idns({idn::TelegramType})), code(SoeError::DataReadOnly));
}

TEST(SoeErrors, WriteProtectedInThisPhase0x7005) {
    DriveBench d(AlState::SafeOp);
    EXPECT_EQ(d.write_error(idn::TelegramType, u16(4)), code(SoeError::DataWriteProtected));
    EXPECT_EQ(d.write_error(idn::MdtConfiguration, idns({idn::PositionCommand})),
              code(SoeError::DataWriteProtected));
    DriveBench p(AlState::PreOp);
    EXPECT_EQ(p.write_error(idn::TelegramType, u16(4)), std::nullopt);
}

TEST(SoeErrors, BelowMinimum0x7006AboveMaximum0x7007) {
    DriveBench d;
    EXPECT_EQ(d.write_error(idn::NcCycleTime, u16(100)), code(SoeError::DataBelowMin));
    EXPECT_EQ(d.write_error(idn::TelegramType, u16(8)), code(SoeError::DataAboveMax));
    EXPECT_EQ(d.write_error(idn::MonitoringWindow, u32(0x80000000u)), code(SoeError::DataAboveMax));
}

TEST(SoeErrors, InvalidData0x7008) {
    DriveBench d;
    ASSERT_EQ(d.write_error(idn::TelegramType, u16(soe::kApplicationTelegram)), std::nullopt);
    // S-0-0051 is configurable in the AT, not in the MDT; a list of 4-byte values takes whole elements.
    EXPECT_EQ(d.write_error(idn::MdtConfiguration, idns({idn::PositionFeedback})),
              code(SoeError::DataInvalid));
    EXPECT_EQ(d.write_error(idn::DataContainer, list({1, 2, 3})), code(SoeError::DataInvalid));
    // A procedure command takes 0, 1 or 3.
    EXPECT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(2)), code(SoeError::DataInvalid));
}

TEST(SoeErrors, ConfiguredCyclically0x700A) {
    DriveBench d(AlState::SafeOp);
    EXPECT_EQ(d.write_error(idn::PositionCommand, u32(5)), code(SoeError::DataCyclic));
    EXPECT_EQ(d.write_error(idn::VelocityCommand, u32(5)), std::nullopt);  // not in the MDT of telegram 4
}

TEST(SoeErrors, ListsOfAStandardTelegram0x700C) {
    DriveBench d;
    EXPECT_EQ(d.write_error(idn::AtConfiguration, idns({idn::VelocityFeedback})),
              code(SoeError::DataProtectedBySettings));
}

TEST(SoeErrors, CommandAlreadyActive0x7010AndNotInterruptible0x7011) {
    DriveBench d;
    ASSERT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::SetAndEnable)), std::nullopt);
    // In progress (P-0-0101, 2 ms by default): started again, 0x7010.
    EXPECT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::SetAndEnable)),
              code(SoeError::CommandActive));
    d.drive.tick(1'000'000'000);  // the drive's first time: past the command's end, it is executed
    EXPECT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::SetAndEnable)),
              code(SoeError::CommandActive));
    EXPECT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::SetNotEnabled)),
              code(SoeError::CommandNotInterruptible));
    ASSERT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::Cancel)), std::nullopt);
    EXPECT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::SetAndEnable)), std::nullopt);
}

TEST(SoeErrors, TransitionCheckOutsideItsPhase0x7012) {
    DriveBench safeop(AlState::SafeOp);
    EXPECT_EQ(safeop.write_error(idn::Cp3TransitionCheck, u16(3)), code(SoeError::CommandNotNow));
    DriveBench preop(AlState::PreOp);
    EXPECT_EQ(preop.write_error(idn::Cp4TransitionCheck, u16(3)), code(SoeError::CommandNotNow));
    EXPECT_EQ(preop.write_error(idn::Cp3TransitionCheck, u16(3)), std::nullopt);
}

TEST(SoeErrors, TruncatedPayloadAndServicesOfTheSlaveGetMailboxErrors) {
    DriveBench d;
    d.server.handle({}, std::vector<std::uint8_t>{0x01, 0x40, 0x18}, d.sink);
    ASSERT_EQ(d.sink.sent.back().first, MailboxType::Error);
    EXPECT_EQ(ld_le16(d.sink.sent.back().second.data() + 2),
              static_cast<std::uint16_t>(protocol::MailboxError::SizeTooShort));
    for (SoeOpCode op : {SoeOpCode::ReadResponse, SoeOpCode::WriteResponse, SoeOpCode::Notification,
                         SoeOpCode::SlaveInfo, SoeOpCode::Reserved, static_cast<SoeOpCode>(0)}) {
        d.server.handle({}, request(op, 0, el::Value, 24), d.sink);
        ASSERT_EQ(d.sink.sent.back().first, MailboxType::Error);
        EXPECT_EQ(ld_le16(d.sink.sent.back().second.data() + 2),
                  static_cast<std::uint16_t>(protocol::MailboxError::ServiceNotSupported));
    }
}

// ---- Procedure commands and notifications

TEST(SoeCommands, ExecutionIsNotifiedWithItsDataState) {
    DriveBench d;
    d.drive.tick(1'000'000'000);
    ASSERT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(soe::command_input::SetAndEnable)), std::nullopt);
    // In progress first (set, enabled, not yet executed): no notification, no command change yet.
    EXPECT_EQ(ld_le16(d.read(el::DataState, idn::ResetClass1Diagnostic).data.data()),
              soe::command_state::InProgress);
    EXPECT_FALSE(d.server.has_output());
    EXPECT_EQ(d.drive.status_word() & soe::status::CommandChange, 0);
    d.drive.tick(1'000'000'000 + soe::kDefaultCommandDurationUs * 1000ull);
    EXPECT_TRUE(d.server.has_output());
    d.server.poll(d.sink);
    const auto n = d.sink.last();
    EXPECT_EQ(n.op, SoeOpCode::Notification);
    EXPECT_EQ(n.elements, el::DataState);
    EXPECT_EQ(n.idn(), idn::ResetClass1Diagnostic);
    EXPECT_EQ(ld_le16(n.data.data()), soe::command_state::Executed);
    EXPECT_FALSE(d.server.has_output());
    EXPECT_EQ(d.drive.status_word() & soe::status::CommandChange, soe::status::CommandChange);
    EXPECT_EQ(ld_le16(d.read(el::DataState, idn::ResetClass1Diagnostic).data.data()),
              soe::command_state::Executed);
    // Cleared by the master: not set, the change bit goes.
    ASSERT_EQ(d.write_error(idn::ResetClass1Diagnostic, u16(0)), std::nullopt);
    EXPECT_EQ(d.drive.status_word() & soe::status::CommandChange, 0);
}

TEST(SoeCommands, Cp3CheckFailsWhenTheSyncManagersDoNotFitTheTelegrams) {
    MasterBench m;
    m.startup(AlState::PreOp);  // SM2/SM3 are still off in PREOP: the check fails
    auto c = m.client();
    ASSERT_TRUE(c.write(0, el::Value, idn::Cp3TransitionCheck, u16(3)).ok());
    // A master polling the data state sees it in progress until the command's time has passed.
    const auto r = c.read(0, el::DataState, idn::Cp3TransitionCheck);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(ld_le16(r.data.data()), soe::command_state::InProgress);
    m.b.advance(soe::kDefaultCommandDurationUs * 1000ull);
    const auto n = c.notification(std::chrono::milliseconds(200));
    ASSERT_TRUE(n);
    EXPECT_EQ(n->idn, idn::Cp3TransitionCheck);
    EXPECT_EQ(n->data_state, soe::command_state::Error);
}

// ---- The drive behind the project's master

TEST(SoeDriveDevice, SiiDeclaresSoeAndOneChannel) {
    const auto d = device::soe_drive();
    const auto img = esc::build_sii_image(d);
    const auto sii = protocol::parse_sii(img);
    EXPECT_EQ(sii.mailbox_protocols, 0x0010);
    EXPECT_EQ(sii.identity.vendor_id, 0x00000A3Cu);
    EXPECT_EQ(sii.identity.product_code, device::kSoeDriveProduct);
}

TEST(SoeDriveDevice, ApplicationTelegramChangesTheProcessDataLengths) {
    MasterBench m;
    m.startup(AlState::PreOp);
    auto c = m.client();
    ASSERT_TRUE(c.write(0, el::Value, idn::TelegramType, u16(soe::kApplicationTelegram)).ok());
    ASSERT_TRUE(
        c.write(0, el::Value, idn::MdtConfiguration, idns({idn::PositionCommand, idn::TorqueCommand})).ok());
    ASSERT_TRUE(c.write(0, el::Value, idn::AtConfiguration,
                        idns({idn::PositionFeedback, idn::VelocityFeedback, idn::TorqueFeedback}))
                    .ok());
    m.startup(AlState::Op);
    EXPECT_EQ(m.b.master.slaves()[0].out_bytes, 2u + 4 + 2);
    EXPECT_EQ(m.b.master.slaves()[0].in_bytes, 2u + 4 + 4 + 2);
    EXPECT_EQ(m.b.master.exchange_process_data(), m.b.master.expected_wkc());
}

TEST(SoeDriveDevice, SegmentedTransfersThroughTheMailbox) {
    MasterBench m;
    m.startup(AlState::PreOp);
    auto c = m.client();
    std::vector<std::uint8_t> bytes(1024);
    for (std::size_t i = 0; i < bytes.size(); ++i)
        bytes[i] = static_cast<std::uint8_t>(i * 13 + 1);
    const auto w = c.write(0, el::Value, idn::DataContainer, list(bytes));
    ASSERT_TRUE(w.ok());
    EXPECT_GE(w.fragments, 8u);
    const auto r = c.read(0, el::Value, idn::DataContainer);
    ASSERT_TRUE(r.ok());
    EXPECT_GE(r.fragments, 8u);
    EXPECT_EQ(r.data, list(bytes, 1024));
}

TEST(SoeDriveDevice, BadRequestsLeaveProcessDataRunning) {
    MasterBench m;
    m.startup(AlState::Op);
    const auto wkc = m.b.master.expected_wkc();
    auto c = m.client();
    for (std::uint16_t i = 0; i < 40; ++i) {
        const auto r = c.read(static_cast<std::uint8_t>(i % 9), static_cast<std::uint8_t>(i * 37),
                              Idn{static_cast<std::uint16_t>(i * 977)});
        EXPECT_TRUE(r.transport_ok);
        EXPECT_EQ(m.b.master.exchange_process_data(), wkc);
    }
    // A write whose fragments never end, then a read: answered, the fragments dropped.
    master::CoeClient raw(m.b.master, m.station());
    for (int i = 0; i < 5; ++i)
        ASSERT_TRUE(raw.send(
            MailboxType::SoE,
            request(SoeOpCode::WriteRequest, 0, el::Value, 3, std::vector<std::uint8_t>(100, 1), true),
            raw.next_counter()));
    EXPECT_TRUE(c.read(0, el::Value, idn::TelegramType).ok());
    EXPECT_EQ(m.b.master.exchange_process_data(), wkc);
    EXPECT_EQ(m.b.master.read_al_status(m.station()).state(), AlState::Op);
}
