// The SoE benches of the unit tests (test_soe.cpp, test_soe_drive.cpp): a 128-byte reply sink, SoE request
// bytes, value encodings, the SoE drive alone with its server (DriveBench, its own time), and SoE drives
// behind the project's master over an in-process link (MasterBench).
#pragma once

#include <gtest/gtest.h>

#include "device/soe_drive.hpp"
#include "master/soe_client.hpp"
#include "protocol/soe.hpp"
#include "soe/soe_drive.hpp"
#include "soe/soe_server.hpp"
#include "test_support.hpp"

namespace vecat::test::soe_bench {

using protocol::AlState;
using protocol::Idn;
using protocol::MailboxType;
using protocol::SoeError;
using protocol::SoeMessage;
using protocol::SoeOpCode;
namespace el = protocol::soe_element;

// ---- The server alone: a reply sink of a 128-byte mailbox that keeps every message committed.
struct Sink final : esc::MailboxReplySink {
    std::array<std::uint8_t, 128 - protocol::kMailboxHeaderSize> buf{};
    std::vector<std::pair<MailboxType, std::vector<std::uint8_t>>> sent;
    std::size_t unread = 0;  // pending(): what the master has not read yet
    Bytes reply_buffer() override { return Bytes(buf.data(), buf.size()); }
    void commit(MailboxType t, std::size_t n) override {
        sent.emplace_back(t, std::vector<std::uint8_t>(buf.begin(), buf.begin() + static_cast<long>(n)));
    }
    bool can_commit() const override { return true; }
    std::size_t pending() const override { return unread; }
    SoeMessage last() const {
        EXPECT_FALSE(sent.empty());
        EXPECT_EQ(sent.back().first, MailboxType::SoE);
        return *protocol::parse_soe(sent.back().second);
    }
};

inline std::vector<std::uint8_t> request(SoeOpCode op, std::uint8_t drive, std::uint8_t elements,
                                         std::uint16_t idn_field, ConstBytes data = {},
                                         bool incomplete = false) {
    SoeMessage m;
    m.op = op;
    m.drive = drive;
    m.elements = elements;
    m.idn_or_fragments = idn_field;
    m.incomplete = incomplete;
    m.data = data;
    std::vector<std::uint8_t> b(protocol::kSoeHeaderSize + data.size());
    b.resize(protocol::write_soe(b, m));
    return b;
}

inline std::vector<std::uint8_t> u16(std::uint16_t v) {
    return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8)};
}
inline std::vector<std::uint8_t> u32(std::uint32_t v) {
    return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8),
            static_cast<std::uint8_t>(v >> 16), static_cast<std::uint8_t>(v >> 24)};
}
// A list value: current length, maximum length, the bytes.
inline std::vector<std::uint8_t> list(const std::vector<std::uint8_t>& bytes, std::uint16_t max = 0) {
    std::vector<std::uint8_t> v = u16(static_cast<std::uint16_t>(bytes.size()));
    const auto m = u16(max);
    v.insert(v.end(), m.begin(), m.end());
    v.insert(v.end(), bytes.begin(), bytes.end());
    return v;
}
inline std::vector<std::uint8_t> idns(std::initializer_list<Idn> l) {
    std::vector<std::uint8_t> v;
    for (Idn i : l) {
        v.push_back(static_cast<std::uint8_t>(i.raw));
        v.push_back(static_cast<std::uint8_t>(i.raw >> 8));
    }
    return list(v);
}

// The SoE drive alone, in a phase, with its server.
struct DriveBench {
    explicit DriveBench(AlState phase = AlState::PreOp, unsigned axes = 1)
        : drive(device::soe_drive(axes)), server(drive) {
        drive.on_state_change(AlState::Init, phase);
    }
    SoeMessage read(std::uint8_t elements, Idn i, std::uint8_t drive_no = 0) {
        server.handle({}, request(SoeOpCode::ReadRequest, drive_no, elements, i.raw), sink);
        return sink.last();
    }
    SoeMessage write(std::uint8_t elements, Idn i, ConstBytes data, std::uint8_t drive_no = 0) {
        server.handle({}, request(SoeOpCode::WriteRequest, drive_no, elements, i.raw, data), sink);
        return sink.last();
    }
    std::optional<std::uint16_t> write_error(Idn i, const std::vector<std::uint8_t>& data,
                                             std::uint8_t elements = el::Value) {
        const auto m = write(elements, i, data);
        EXPECT_EQ(m.op, SoeOpCode::WriteResponse);
        return m.error_code();
    }
    std::optional<std::uint16_t> read_error(Idn i, std::uint8_t elements) {
        const auto m = read(elements, i);
        EXPECT_EQ(m.op, SoeOpCode::ReadResponse);
        return m.error_code();
    }
    soe::SoeDrive drive;
    soe::SoeServer server;
    Sink sink;
};

inline constexpr std::uint16_t code(SoeError e) {
    return static_cast<std::uint16_t>(e);
}

// ---- The drive behind the project's master, over an in-process link.
struct MasterBench {
    explicit MasterBench(unsigned axes = 1) : b(1, {}, device::soe_drive(axes), &soe::make_soe_segment) {}
    std::uint16_t station() { return b.master.slaves()[0].station; }
    soe::SoeDrive& drive() { return dynamic_cast<soe::SoeDrive&>(b.slave().app()); }
    void startup(AlState s) {
        std::string why;
        ASSERT_TRUE(b.master.startup(s, &why)) << why;
    }
    master::SoeClient client() { return master::SoeClient(b.master, station()); }
    Bench b;
};

}  // namespace vecat::test::soe_bench
