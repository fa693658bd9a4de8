// The CoE mailbox protocol of the default drive, driven directly through esc::MailboxProtocol: SDO upload
// and download (expedited, normal, segmented), abort codes, complete access, the PDO mapping rules of
// ETG.1020, SDO information and emergencies. Every reply is checked byte for byte.
// Long (about 1,380 lines): one mailbox fixture for every SDO service, each test a byte-exact exchange.
#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <string>
#include <vector>

#include "coe/coe_application.hpp"
#include "coe/sdo_server.hpp"
#include "device/device_description.hpp"
#include "esc/mailbox.hpp"
#include "master/coe_client.hpp"
#include "protocol/cia402_objects.hpp"
#include "protocol/coe.hpp"
#include "test_support.hpp"

namespace obj = vecat::protocol::obj;

using namespace vecat;
using namespace vecat::coe;
using protocol::AlState;
using protocol::MailboxType;

namespace {

using Buf = std::vector<std::uint8_t>;

constexpr std::size_t kMailboxPayload =
    0xF6 - protocol::kMailboxHeaderSize;  // SM1 length of the default drive

struct Reply {
    MailboxType type = MailboxType::Error;
    Buf bytes;
};

// The slave's side of the reply mailbox: one reply buffer of a fixed size and a bounded queue of what was
// committed, which the test reads (take) like a master would.
class FakeSink final : public esc::MailboxReplySink {
  public:
    explicit FakeSink(std::size_t payload = kMailboxPayload, std::size_t slots = 64)
        : buf_(payload, kFill), slots_(slots) {}

    Bytes reply_buffer() override { return Bytes(buf_.data(), buf_.size()); }
    void commit(MailboxType type, std::size_t len) override {
        if (len > buf_.size()) ADD_FAILURE() << "commit of " << len << " bytes, buffer " << buf_.size();
        if (queue_.size() >= slots_) ADD_FAILURE() << "commit while the queue is full";
        queue_.push_back(
            {type, Buf(buf_.begin(), buf_.begin() + static_cast<long>(std::min(len, buf_.size())))});
        // Fill the buffer again: a reply that does not write all its bytes shows 0xA5 instead of zeros.
        std::fill(buf_.begin(), buf_.end(), kFill);
    }
    bool can_commit() const override { return queue_.size() < slots_; }
    std::size_t pending() const override { return queue_.size() + unread_in_sm; }

    std::size_t queued() const { return queue_.size(); }
    Reply take() {
        if (queue_.empty()) {
            ADD_FAILURE() << "no reply";
            return {};
        }
        Reply r = std::move(queue_.front());
        queue_.pop_front();
        return r;
    }

    std::size_t unread_in_sm = 0;  // a reply already in the SyncManager the master has not read

  private:
    static constexpr std::uint8_t kFill = 0xA5;
    Buf buf_;
    std::size_t slots_;
    std::deque<Reply> queue_;
};

std::uint8_t lo(std::uint16_t v) {
    return static_cast<std::uint8_t>(v);
}
std::uint8_t hi(std::uint16_t v) {
    return static_cast<std::uint8_t>(v >> 8);
}
Buf le16(std::uint16_t v) {
    return {lo(v), hi(v)};
}
Buf le32(std::uint32_t v) {
    return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8),
            static_cast<std::uint8_t>(v >> 16), static_cast<std::uint8_t>(v >> 24)};
}
Buf cat(std::initializer_list<Buf> parts) {
    Buf out;
    for (const auto& p : parts)
        out.insert(out.end(), p.begin(), p.end());
    return out;
}
Buf text(const std::string& s) {
    return Buf(s.begin(), s.end());
}

// ---- requests (payload after the mailbox header, starting with the CoE header) ----

Buf sdo_req(std::uint8_t cmd, std::uint16_t index, std::uint8_t sub, Buf data4 = {}, const Buf& more = {}) {
    data4.resize(4, 0);
    return cat({{0x00, 0x20, cmd, lo(index), hi(index), sub}, data4, more});
}
Buf upload_req(std::uint16_t index, std::uint8_t sub, bool ca = false) {
    return sdo_req(static_cast<std::uint8_t>(0x40 | (ca ? 0x10 : 0)), index, sub);
}
// Expedited download with the size indicated (1..4 bytes).
Buf expedited_req(std::uint16_t index, std::uint8_t sub, const Buf& v, bool ca = false) {
    const auto cmd = static_cast<std::uint8_t>(0x23 | ((4 - v.size()) << 2) | (ca ? 0x10 : 0));
    return sdo_req(cmd, index, sub, v);
}
// Normal download: complete size, then as much data as given.
Buf normal_req(std::uint16_t index, std::uint8_t sub, std::uint32_t total, const Buf& data, bool ca = false) {
    return sdo_req(static_cast<std::uint8_t>(0x21 | (ca ? 0x10 : 0)), index, sub, le32(total), data);
}
// Download segment: at least 7 data bytes on the wire; fewer are announced in bits 1..3.
Buf segment_req(std::uint8_t toggle, Buf data, bool last) {
    std::uint8_t cmd = static_cast<std::uint8_t>(toggle | (last ? 1 : 0));
    if (data.size() < 7) {
        cmd = static_cast<std::uint8_t>(cmd | ((7 - data.size()) << 1));
        data.resize(7, 0);
    }
    return cat({{0x00, 0x20, cmd}, data});
}
Buf upload_segment_req(std::uint8_t toggle) {
    return {0x00, 0x20, static_cast<std::uint8_t>(0x60 | toggle), 0, 0, 0, 0, 0, 0, 0};
}
Buf info_req(std::uint8_t opcode, const Buf& data) {
    return cat({{0x00, 0x80, opcode, 0x00, 0x00, 0x00}, data});
}

// ---- expected replies ----

Buf abort_frame(std::uint16_t index, std::uint8_t sub, std::uint32_t code) {
    return cat({{0x00, 0x20, 0x80, lo(index), hi(index), sub}, le32(code)});
}
Buf download_ok(std::uint16_t index, std::uint8_t sub, bool ca = false) {
    return {0x00, 0x30, static_cast<std::uint8_t>(0x60 | (ca ? 0x10 : 0)), lo(index), hi(index), sub, 0, 0,
            0,    0};
}
Buf info_error(std::uint32_t code) {
    return cat({{0x00, 0x80, 0x07, 0x00, 0x00, 0x00}, le32(code)});
}

class Sdo : public ::testing::Test {
  protected:
    Sdo() : app(device::default_drive()) { app.on_state_change(AlState::Init, AlState::PreOp); }

    void handle(const Buf& p, FakeSink& s) {
        protocol::MailboxHeader h;
        h.length = static_cast<std::uint16_t>(p.size());
        h.type = static_cast<std::uint8_t>(MailboxType::CoE);
        app.sdo_server().handle(h, ConstBytes(p.data(), p.size()), s);
    }
    // One request, exactly one reply.
    Reply send(const Buf& p, FakeSink& s) {
        handle(p, s);
        EXPECT_EQ(s.queued(), 1u) << "replies to one request";
        Reply r = s.take();
        while (s.queued())
            s.take();
        return r;
    }
    Buf send(const Buf& p) {
        Reply r = send(p, sink);
        EXPECT_EQ(r.type, MailboxType::CoE);
        return r.bytes;
    }

    // SDO write by expedited (1..4 bytes) or normal transfer: 0 on success, else the abort code. The
    // reply layout is checked either way.
    std::uint32_t write(std::uint16_t index, std::uint8_t sub, const Buf& v, bool ca = false) {
        const Buf r = send(v.size() >= 1 && v.size() <= 4
                               ? expedited_req(index, sub, v, ca)
                               : normal_req(index, sub, static_cast<std::uint32_t>(v.size()), v, ca));
        if (r.size() == 10 && r[2] == 0x80) {
            const std::uint32_t code = ld_le32(r.data() + 6);
            EXPECT_EQ(r, abort_frame(index, sub, code));
            return code;
        }
        EXPECT_EQ(r, download_ok(index, sub, ca));
        return 0;
    }
    std::uint32_t write_u8(std::uint16_t index, std::uint8_t sub, std::uint8_t v) {
        return write(index, sub, {v});
    }
    std::uint32_t write_u16(std::uint16_t index, std::uint8_t sub, std::uint16_t v) {
        return write(index, sub, le16(v));
    }
    std::uint32_t write_u32(std::uint16_t index, std::uint8_t sub, std::uint32_t v) {
        return write(index, sub, le32(v));
    }
    // SDO read (expedited or normal, not segmented).
    Buf read(std::uint16_t index, std::uint8_t sub) {
        const Buf r = send(upload_req(index, sub));
        if (r.size() == 10 && r[2] == 0x80) {
            ADD_FAILURE() << "abort " << std::hex << ld_le32(r.data() + 6);
            return {};
        }
        if (r.size() < 10) {
            ADD_FAILURE() << "short reply";
            return {};
        }
        EXPECT_EQ(r[0], 0x00);
        EXPECT_EQ(r[1], 0x30);
        EXPECT_EQ(r[2] & 0xE0, 0x40);
        if (r[2] & 0x02) return Buf(r.begin() + 6, r.begin() + 6 + (4 - ((r[2] >> 2) & 3)));
        const std::uint32_t n = ld_le32(r.data() + 6);
        EXPECT_EQ(r.size(), 10u + n) << "segmented reply in read()";
        return Buf(r.begin() + 10, r.end());
    }
    std::uint32_t read_u32(std::uint16_t index, std::uint8_t sub) {
        const Buf v = read(index, sub);
        Buf w = v;
        w.resize(4, 0);
        return ld_le32(w.data());
    }
    // ETG.1020 sequence: subindex 0 := 0, the entries, subindex 0 := n.
    void remap(std::uint16_t pdo, const std::vector<std::uint32_t>& entries) {
        ASSERT_EQ(write_u8(pdo, 0, 0), 0u);
        for (std::size_t i = 0; i < entries.size(); ++i)
            ASSERT_EQ(write_u32(pdo, static_cast<std::uint8_t>(i + 1), entries[i]), 0u) << i;
        ASSERT_EQ(write_u8(pdo, 0, static_cast<std::uint8_t>(entries.size())), 0u);
    }
    ObjectDictionary& od() { return app.dictionary(); }

    CoeApplication app;
    FakeSink sink;
};

}  // namespace

// =========================================================================================================
// Upload

TEST_F(Sdo, ExpeditedUploadOfU8) {
    // 0x1C00:00 = 4 SyncManagers: 1 byte, 3 unused (size indicated, n = 3 -> 0x4F).
    EXPECT_EQ(send(upload_req(0x1C00, 0)), (Buf{0x00, 0x30, 0x4F, 0x00, 0x1C, 0x00, 0x04, 0x00, 0x00, 0x00}));
    EXPECT_EQ(send(upload_req(0x1C00, 3)), (Buf{0x00, 0x30, 0x4F, 0x00, 0x1C, 0x03, 0x03, 0x00, 0x00, 0x00}));
}

TEST_F(Sdo, ExpeditedUploadOfU16) {
    EXPECT_EQ(send(upload_req(0x1C12, 1)), (Buf{0x00, 0x30, 0x4B, 0x12, 0x1C, 0x01, 0x00, 0x16, 0x00, 0x00}));
}

TEST_F(Sdo, ExpeditedUploadOfU32) {
    EXPECT_EQ(send(upload_req(0x1600, 1)), (Buf{0x00, 0x30, 0x43, 0x00, 0x16, 0x01, 0x10, 0x00, 0x40, 0x60}));
    EXPECT_EQ(send(upload_req(0x1018, 1)), (Buf{0x00, 0x30, 0x43, 0x18, 0x10, 0x01, 0x3C, 0x0A, 0x00, 0x00}));
    EXPECT_EQ(app.sdo_server().counters().sdo_uploads, 2u);
}

TEST_F(Sdo, ExpeditedUploadOfSignedValue) {
    // 0x60C2:02 Interpolation time index, INTEGER8 default -3.
    EXPECT_EQ(send(upload_req(obj::interpolation_time_period::index, 2)),
              (Buf{0x00, 0x30, 0x4F, 0xC2, 0x60, 0x02, 0xFD, 0x00, 0x00, 0x00}));
}

TEST_F(Sdo, NormalUploadOfDeviceName) {
    const std::string name = "vecat CiA402 servo drive";
    EXPECT_EQ(send(upload_req(0x1008, 0)), cat({{0x00, 0x30, 0x41, 0x08, 0x10, 0x00},
                                                le32(static_cast<std::uint32_t>(name.size())),
                                                text(name)}));
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
}

TEST_F(Sdo, SegmentedUploadAlternatesToggleAndPadsTheLastSegment) {
    // Given a 16-byte reply mailbox, the 24-character device name needs an initiate reply with 6 bytes,
    // a full segment of 13 and a last segment of 5 bytes (padded to 7, 2 unused announced in bits 1..3).
    FakeSink small(16);
    Reply r = send(upload_req(0x1008, 0), small);
    EXPECT_EQ(r.bytes, cat({{0x00, 0x30, 0x41, 0x08, 0x10, 0x00, 24, 0, 0, 0}, text("vecat ")}));
    EXPECT_TRUE(app.sdo_server().transfer_in_progress());

    r = send(upload_segment_req(0x00), small);
    EXPECT_EQ(r.bytes, cat({{0x00, 0x30, 0x00}, text("CiA402 servo ")}));

    r = send(upload_segment_req(0x10), small);
    EXPECT_EQ(r.bytes, cat({{0x00, 0x30, 0x10 | (2 << 1) | 0x01}, text("drive"), {0x00, 0x00}}));
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());

    // The transfer is over: a further segment request is refused.
    r = send(upload_segment_req(0x00), small);
    EXPECT_EQ(r.bytes, abort_frame(0, 0, 0x05040001));
}

TEST_F(Sdo, SegmentedUploadOfLargeOctetString) {
    // 0x2020: 512 bytes. With a 240-byte mailbox: 230 in the initiate reply, 237 + 45 in segments.
    Buf pattern(512);
    for (std::size_t i = 0; i < pattern.size(); ++i)
        pattern[i] = static_cast<std::uint8_t>(i * 7 + 1);
    od().find(0x2020, 0)->assign(ConstBytes(pattern.data(), pattern.size()));

    Buf r = send(upload_req(0x2020, 0));
    ASSERT_EQ(r.size(), kMailboxPayload);
    EXPECT_EQ(Buf(r.begin(), r.begin() + 10),
              (Buf{0x00, 0x30, 0x41, 0x20, 0x20, 0x00, 0x00, 0x02, 0x00, 0x00}));
    Buf got(r.begin() + 10, r.end());

    r = send(upload_segment_req(0x00));
    ASSERT_EQ(r.size(), kMailboxPayload);
    EXPECT_EQ(r[2], 0x00);  // toggle 0, more to come
    got.insert(got.end(), r.begin() + 3, r.end());

    r = send(upload_segment_req(0x10));
    ASSERT_EQ(r.size(), 3u + 45u);
    EXPECT_EQ(r[2], 0x11);  // toggle 1, last; 45 >= 7 bytes so no size bits
    got.insert(got.end(), r.begin() + 3, r.end());
    EXPECT_EQ(got, pattern);
}

TEST_F(Sdo, SegmentedUploadLastSegmentSizeBits) {
    // A last segment of exactly 7 bytes has size bits 0; one of a single byte announces 6 unused.
    FakeSink s15(15);  // initiate carries 5, segments 12: 24 = 5 + 12 + 7
    EXPECT_EQ(send(upload_req(0x1008, 0), s15).bytes,
              cat({{0x00, 0x30, 0x41, 0x08, 0x10, 0x00, 24, 0, 0, 0}, text("vecat")}));
    EXPECT_EQ(send(upload_segment_req(0x00), s15).bytes, cat({{0x00, 0x30, 0x00}, text(" CiA402 serv")}));
    EXPECT_EQ(send(upload_segment_req(0x10), s15).bytes, cat({{0x00, 0x30, 0x11}, text("o drive")}));

    FakeSink s18(18);  // initiate carries 8, segments 15: 24 = 8 + 15 + 1
    EXPECT_EQ(send(upload_req(0x1008, 0), s18).bytes.size(), 18u);
    EXPECT_EQ(send(upload_segment_req(0x00), s18).bytes, cat({{0x00, 0x30, 0x00}, text("A402 servo driv")}));
    EXPECT_EQ(send(upload_segment_req(0x10), s18).bytes,
              cat({{0x00, 0x30, 0x10 | (6 << 1) | 0x01}, text("e"), Buf(6, 0)}));
}

TEST_F(Sdo, UploadSegmentToggleErrorAborts) {
    FakeSink small(20);
    send(upload_req(0x1008, 0), small);
    EXPECT_TRUE(app.sdo_server().transfer_in_progress());
    // The first segment must have toggle 0.
    EXPECT_EQ(send(upload_segment_req(0x10), small).bytes, abort_frame(0x1008, 0, 0x05030000));
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(send(upload_segment_req(0x00), small).bytes, abort_frame(0, 0, 0x05040001));
}

TEST_F(Sdo, SegmentedTransferLeftAloneTimesOut) {
    // Given a segmented upload in progress, with the slave's time running (the application's tick),
    FakeSink small(16);
    const std::uint64_t t0 = 5'000'000'000;
    app.tick(t0);
    send(upload_req(0x1008, 0), small);
    ASSERT_TRUE(app.sdo_server().transfer_in_progress());
    // a master that answers within the SDO timeout keeps the transfer going,
    app.tick(t0 + 1'000'000);
    app.tick(t0 + SdoServer::kSdoTimeoutNs - 1'000'000);
    EXPECT_TRUE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(send(upload_segment_req(0x00), small).bytes, cat({{0x00, 0x30, 0x00}, text("CiA402 servo ")}));
    // when it then stays silent for the timeout, the transfer is dropped
    const std::uint64_t t1 = t0 + SdoServer::kSdoTimeoutNs;
    app.tick(t1);
    EXPECT_TRUE(app.sdo_server().transfer_in_progress());  // the timeout counts from the last segment
    app.tick(t1 + SdoServer::kSdoTimeoutNs);
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    // and its late segment request hears "SDO protocol timeout" (0x05040000), once.
    EXPECT_EQ(send(upload_segment_req(0x10), small).bytes, abort_frame(0x1008, 0, 0x05040000));
    EXPECT_EQ(send(upload_segment_req(0x10), small).bytes, abort_frame(0, 0, 0x05040001));
}

TEST_F(Sdo, TimedOutDownloadStoresNothingAndANewTransferStartsClean) {
    // Given a normal download of 0x2010 (a visible string) with the first part sent,
    app.tick(1'000);
    const auto value = [&] {
        const auto v = od().find(0x2010, 0)->value();
        return Buf(v.begin(), v.end());
    };
    const Buf before = value();
    EXPECT_EQ(send(normal_req(0x2010, 0, 20, text("abc"))), download_ok(0x2010, 0));
    ASSERT_TRUE(app.sdo_server().transfer_in_progress());
    // when the master goes silent, the transfer is dropped without writing the entry,
    app.tick(2'000);
    app.tick(2'000 + SdoServer::kSdoTimeoutNs);
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(value(), before);
    // and a new request is served as usual.
    EXPECT_EQ(send(expedited_req(0x6060, 0, {8})), download_ok(0x6060, 0));
}

TEST_F(Sdo, UploadSegmentToggleMustAlternate) {
    FakeSink small(12);  // 2 data bytes in the initiate reply, 9 per segment
    send(upload_req(0x1008, 0), small);
    EXPECT_EQ(send(upload_segment_req(0x00), small).bytes[2], 0x00);
    // Repeating toggle 0 instead of 1.
    EXPECT_EQ(send(upload_segment_req(0x00), small).bytes, abort_frame(0x1008, 0, 0x05030000));
}

TEST_F(Sdo, UploadSegmentWithoutTransferAborts) {
    EXPECT_EQ(send(upload_segment_req(0x00)), abort_frame(0, 0, 0x05040001));
}

TEST_F(Sdo, NewRequestOrResetEndsASegmentedUpload) {
    FakeSink small(20);
    send(upload_req(0x1008, 0), small);
    ASSERT_TRUE(app.sdo_server().transfer_in_progress());
    send(upload_req(0x1000, 0), small);  // expedited: replaces the transfer
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(send(upload_segment_req(0x00), small).bytes, abort_frame(0, 0, 0x05040001));

    send(upload_req(0x1008, 0), small);
    ASSERT_TRUE(app.sdo_server().transfer_in_progress());
    app.sdo_server().reset();
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(send(upload_segment_req(0x00), small).bytes, abort_frame(0, 0, 0x05040001));
}

// =========================================================================================================
// Download

TEST_F(Sdo, ExpeditedDownloadOfI8AndReadBack) {
    // 0x6060 Modes of operation := -3 (INTEGER8): command 0x2F (size indicated, 3 bytes unused).
    EXPECT_EQ(send(sdo_req(0x2F, obj::modes_of_operation.index, 0, {0xFD})),
              download_ok(obj::modes_of_operation.index, 0));
    EXPECT_EQ(od().find(obj::modes_of_operation)->as_int64(), -3);
    EXPECT_EQ(send(upload_req(obj::modes_of_operation.index, 0)),
              (Buf{0x00, 0x30, 0x4F, 0x60, 0x60, 0x00, 0xFD, 0x00, 0x00, 0x00}));
    EXPECT_EQ(app.sdo_server().counters().sdo_downloads, 1u);
}

TEST_F(Sdo, ExpeditedDownloadOfI32AndReadBack) {
    EXPECT_EQ(send(sdo_req(0x23, obj::target_position.index, 0, le32(0xFFFE7960))),
              download_ok(obj::target_position.index, 0));  // -100000
    EXPECT_EQ(od().find(obj::target_position)->as_int64(), -100000);
    EXPECT_EQ(send(upload_req(obj::target_position.index, 0)),
              (Buf{0x00, 0x30, 0x43, 0x7A, 0x60, 0x00, 0x60, 0x79, 0xFE, 0xFF}));
}

TEST_F(Sdo, ExpeditedDownloadWithoutSizeUsesTheEntrySize) {
    // Command 0x22: expedited, size not indicated; the 1-byte entry takes the first data byte.
    EXPECT_EQ(send(sdo_req(0x22, obj::modes_of_operation.index, 0, {0x09, 0xEE, 0xEE, 0xEE})),
              download_ok(obj::modes_of_operation.index, 0));
    EXPECT_EQ(od().find(obj::modes_of_operation)->as_int64(), 9);
    EXPECT_EQ(send(sdo_req(0x22, obj::max_torque.index, 0, {0x34, 0x12, 0xEE, 0xEE})),
              download_ok(obj::max_torque.index, 0));
    EXPECT_EQ(od().find(obj::max_torque)->as_uint64(), 0x1234u);
}

TEST_F(Sdo, NormalDownloadOfString) {
    // 0x2010 User label (VISIBLE_STRING, RW, at most 32 characters), all data in the initiate request.
    EXPECT_EQ(send(normal_req(0x2010, 0, 9, text("left axis"))), download_ok(0x2010, 0));
    EXPECT_EQ(send(upload_req(0x2010, 0)),
              cat({{0x00, 0x30, 0x41, 0x10, 0x20, 0x00, 9, 0, 0, 0}, text("left axis")}));
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    // A shorter label replaces it entirely (3 characters: expedited reply).
    EXPECT_EQ(send(expedited_req(0x2010, 0, text("abc"))), download_ok(0x2010, 0));
    EXPECT_EQ(send(upload_req(0x2010, 0)), (Buf{0x00, 0x30, 0x47, 0x10, 0x20, 0x00, 'a', 'b', 'c', 0x00}));
}

TEST_F(Sdo, NormalDownloadIgnoresBytesBeyondTheAnnouncedSize) {
    EXPECT_EQ(send(normal_req(0x2010, 0, 5, text("motor-X-padding"))), download_ok(0x2010, 0));
    EXPECT_EQ(read(0x2010, 0), text("motor"));
}

TEST_F(Sdo, SegmentedDownloadWithTogglesAndShortLastSegment) {
    // Given 20 characters announced with 5 in the initiate request, when segments of 7 (toggle 0),
    // 5 (toggle 1, size bits 2) and 3 (toggle 0, last, size bits 4) follow, then each is confirmed with
    // its toggle and the whole label is stored once the last one arrived.
    const std::string label = "Axis 1 - main spindl";
    ASSERT_EQ(label.size(), 20u);
    EXPECT_EQ(send(normal_req(0x2010, 0, 20, text(label.substr(0, 5)))), download_ok(0x2010, 0));
    EXPECT_TRUE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(send(segment_req(0x00, text(label.substr(5, 7)), false)),
              (Buf{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
    Buf seg2 = segment_req(0x10, text(label.substr(12, 5)), false);
    EXPECT_EQ(seg2[2], 0x10 | (2 << 1));
    EXPECT_EQ(send(seg2), (Buf{0x00, 0x30, 0x30, 0, 0, 0, 0, 0, 0, 0}));
    EXPECT_EQ(od().find(0x2010, 0)->size(), 4u);  // not stored before the last segment
    Buf seg3 = segment_req(0x00, text(label.substr(17, 3)), true);
    EXPECT_EQ(seg3[2], (4 << 1) | 1);
    EXPECT_EQ(send(seg3), (Buf{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(read(0x2010, 0), text(label));
}

TEST_F(Sdo, UploadRequestEndsASegmentedDownload) {
    EXPECT_EQ(send(normal_req(0x2010, 0, 20, text("12345"))), download_ok(0x2010, 0));
    ASSERT_TRUE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(read(0x2010, 0), text("axis"));  // nothing stored yet
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(send(segment_req(0x00, text("6789012"), false)), abort_frame(0, 0, 0x05040001));
}

TEST_F(Sdo, SegmentedDownloadWithLongSegments) {
    // Segments longer than 7 bytes: the mailbox length gives the size, the size bits are ignored.
    const std::string label = "0123456789abcdefghijklmnopqrstuv";  // 32 = the maximum
    EXPECT_EQ(send(normal_req(0x2010, 0, 32, {})), download_ok(0x2010, 0));
    EXPECT_EQ(send(cat({{0x00, 0x20, 0x00}, text(label.substr(0, 20))})),
              (Buf{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
    EXPECT_EQ(send(cat({{0x00, 0x20, 0x11}, text(label.substr(20))})),
              (Buf{0x00, 0x30, 0x30, 0, 0, 0, 0, 0, 0, 0}));
    EXPECT_EQ(read(0x2010, 0), text(label));
}

TEST_F(Sdo, DownloadSegmentToggleErrorAborts) {
    EXPECT_EQ(send(normal_req(0x2010, 0, 20, {})), download_ok(0x2010, 0));
    EXPECT_EQ(send(segment_req(0x00, text("1234567"), false)), (Buf{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
    // Toggle 0 again instead of 1.
    EXPECT_EQ(send(segment_req(0x00, text("89ABCDE"), false)), abort_frame(0x2010, 0, 0x05030000));
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(send(segment_req(0x10, text("FGHIJK"), true)), abort_frame(0, 0, 0x05040001));
    EXPECT_EQ(read(0x2010, 0), text("axis"));
}

TEST_F(Sdo, DownloadOfOversizedValueIsRefusedAtInitiate) {
    // 100000 bytes announced for a 32-character label: refused before any segment is accepted.
    EXPECT_EQ(send(normal_req(0x2010, 0, 100000, text("abc"))), abort_frame(0x2010, 0, 0x06070012));
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(send(segment_req(0x00, text("defghij"), false)), abort_frame(0, 0, 0x05040001));
    // Just above the capacity of the entry.
    EXPECT_EQ(send(normal_req(0x2010, 0, 33, {})), abort_frame(0x2010, 0, 0x06070012));
    // Complete access: above the transfer buffer.
    EXPECT_EQ(send(normal_req(0x1C12, 0, 0x7FFFFFFF, {}, true)), abort_frame(0x1C12, 0, 0x06070012));
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(read(0x2010, 0), text("axis"));
}

TEST_F(Sdo, DownloadSegmentsBeyondTheAnnouncedSizeAbort) {
    EXPECT_EQ(send(normal_req(0x2010, 0, 10, {})), download_ok(0x2010, 0));
    EXPECT_EQ(send(segment_req(0x00, text("1234567"), false)), (Buf{0x00, 0x30, 0x20, 0, 0, 0, 0, 0, 0, 0}));
    EXPECT_EQ(send(segment_req(0x10, text("89ABCDE"), true)), abort_frame(0x2010, 0, 0x06070012));
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(read(0x2010, 0), text("axis"));
}

TEST_F(Sdo, DownloadEndingShortOfTheAnnouncedSizeAborts) {
    EXPECT_EQ(send(normal_req(0x2010, 0, 10, {})), download_ok(0x2010, 0));
    EXPECT_EQ(send(segment_req(0x00, text("1234"), true)), abort_frame(0x2010, 0, 0x06070013));
    EXPECT_EQ(read(0x2010, 0), text("axis"));
}

TEST_F(Sdo, DownloadSegmentWithoutTransferAborts) {
    EXPECT_EQ(send(segment_req(0x00, text("1234567"), false)), abort_frame(0, 0, 0x05040001));
}

TEST_F(Sdo, NormalDownloadOfFixedSizeValue) {
    // A U32 written by normal transfer, and one whose announced size is wrong.
    EXPECT_EQ(send(normal_req(obj::profile_velocity.index, 0, 4, le32(123456))),
              download_ok(obj::profile_velocity.index, 0));
    EXPECT_EQ(read_u32(obj::profile_velocity.index, 0), 123456u);
    EXPECT_EQ(send(normal_req(obj::profile_velocity.index, 0, 5, {1, 2, 3, 4, 5})),
              abort_frame(obj::profile_velocity.index, 0, 0x06070012));
    EXPECT_EQ(send(normal_req(obj::profile_velocity.index, 0, 3, {1, 2, 3})),
              abort_frame(obj::profile_velocity.index, 0, 0x06070013));
    EXPECT_EQ(read_u32(obj::profile_velocity.index, 0), 123456u);
}

// =========================================================================================================
// Abort codes

TEST_F(Sdo, AbortFrameLayout) {
    // CoE service 2 (an abort is an SDO request), command exactly 0x80, index, subindex, code LE.
    EXPECT_EQ(send(upload_req(0x1234, 0x56)),
              (Buf{0x00, 0x20, 0x80, 0x34, 0x12, 0x56, 0x00, 0x00, 0x02, 0x06}));
    EXPECT_EQ(app.sdo_server().counters().sdo_aborts_sent, 1u);
}

TEST_F(Sdo, UnknownObject) {
    EXPECT_EQ(send(upload_req(0x1234, 0)), abort_frame(0x1234, 0, 0x06020000));
    EXPECT_EQ(send(expedited_req(0x1234, 0, {1})), abort_frame(0x1234, 0, 0x06020000));
    EXPECT_EQ(send(normal_req(0x1234, 0, 8, Buf(8))), abort_frame(0x1234, 0, 0x06020000));
}

TEST_F(Sdo, UnknownSubindex) {
    EXPECT_EQ(send(upload_req(0x1018, 5)), abort_frame(0x1018, 5, 0x06090011));
    EXPECT_EQ(send(upload_req(0x1C32, 20)), abort_frame(0x1C32, 20, 0x06090011));
    EXPECT_EQ(send(expedited_req(obj::controlword.index, 1, {1, 0})),
              abort_frame(obj::controlword.index, 1, 0x06090011));
    EXPECT_EQ(send(normal_req(0x2010, 1, 5, text("hello"))), abort_frame(0x2010, 1, 0x06090011));
}

TEST_F(Sdo, WriteToReadOnly) {
    EXPECT_EQ(send(expedited_req(0x1018, 1, le32(0x12345678))), abort_frame(0x1018, 1, 0x06010002));
    EXPECT_EQ(send(normal_req(0x1008, 0, 5, text("hello"))), abort_frame(0x1008, 0, 0x06010002));
    EXPECT_EQ(send(expedited_req(obj::statusword.index, 0, {1, 0})),
              abort_frame(obj::statusword.index, 0, 0x06010002));
    EXPECT_EQ(read_u32(0x1018, 1), 0x00000A3Cu);
}

TEST_F(Sdo, LengthTooHighOrTooLow) {
    // 0x6066 Following error time out: UNSIGNED16.
    EXPECT_EQ(send(expedited_req(obj::following_error_time_out.index, 0, {1, 0, 0, 0})),
              abort_frame(obj::following_error_time_out.index, 0, 0x06070012));
    EXPECT_EQ(send(expedited_req(obj::following_error_time_out.index, 0, {1, 0, 0})),
              abort_frame(obj::following_error_time_out.index, 0, 0x06070012));
    EXPECT_EQ(send(expedited_req(obj::following_error_time_out.index, 0, {1})),
              abort_frame(obj::following_error_time_out.index, 0, 0x06070013));
    EXPECT_EQ(send(expedited_req(obj::target_position.index, 0, {1, 2})),
              abort_frame(obj::target_position.index, 0, 0x06070013));
    EXPECT_EQ(read(obj::following_error_time_out.index, 0), le16(10));
}

TEST_F(Sdo, ValueTooHighOrTooLow) {
    // 0x605A Quick stop option code: INTEGER16, 0..8.
    EXPECT_EQ(send(expedited_req(obj::quick_stop_option_code.index, 0, le16(9))),
              abort_frame(obj::quick_stop_option_code.index, 0, 0x06090031));
    EXPECT_EQ(send(expedited_req(obj::quick_stop_option_code.index, 0, le16(0xFFFF))),
              abort_frame(obj::quick_stop_option_code.index, 0, 0x06090032));
    EXPECT_EQ(write_u16(obj::quick_stop_option_code.index, 0, 8), 0u);
    EXPECT_EQ(write_u16(obj::quick_stop_option_code.index, 0, 0), 0u);
    // 0x60C2:02 Interpolation time index: INTEGER8, -6..63.
    EXPECT_EQ(send(expedited_req(obj::interpolation_time_period::index, 2, {64})),
              abort_frame(obj::interpolation_time_period::index, 2, 0x06090031));
    EXPECT_EQ(send(expedited_req(obj::interpolation_time_period::index, 2, {0xF9})),
              abort_frame(obj::interpolation_time_period::index, 2, 0x06090032));
    EXPECT_EQ(write_u8(obj::interpolation_time_period::index, 2, 0xFA), 0u);
    EXPECT_EQ(write_u8(obj::interpolation_time_period::index, 2, 63), 0u);
    EXPECT_EQ(read(obj::interpolation_time_period::index, 2), (Buf{63}));
}

TEST_F(Sdo, WrongState) {
    // 0x1C12:00 is writable in PREOP only.
    app.on_state_change(AlState::PreOp, AlState::SafeOp);
    EXPECT_EQ(send(expedited_req(0x1C12, 0, {0})), abort_frame(0x1C12, 0, 0x08000022));
    EXPECT_EQ(send(expedited_req(0x1600, 0, {0})), abort_frame(0x1600, 0, 0x08000022));
    app.on_state_change(AlState::SafeOp, AlState::Op);
    EXPECT_EQ(send(expedited_req(0x1C12, 0, {0})), abort_frame(0x1C12, 0, 0x08000022));
    EXPECT_EQ(read(0x1C12, 0), (Buf{1}));  // reading is fine
}

TEST_F(Sdo, UnknownCommandSpecifier) {
    for (int ccs : {5, 6, 7}) {
        SCOPED_TRACE(ccs);
        EXPECT_EQ(send(sdo_req(static_cast<std::uint8_t>(ccs << 5), 0x1018, 1)),
                  abort_frame(0x1018, 1, 0x05040001));
    }
}

TEST_F(Sdo, MasterAbortGetsNoReplyAndEndsTheTransfer) {
    FakeSink small(20);
    send(upload_req(0x1008, 0), small);
    ASSERT_TRUE(app.sdo_server().transfer_in_progress());
    handle(cat({{0x00, 0x20, 0x80, 0x08, 0x10, 0x00}, le32(0x05040000)}), small);
    EXPECT_EQ(small.queued(), 0u);
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    EXPECT_EQ(app.sdo_server().counters().sdo_aborts_received, 1u);

    send(normal_req(0x2010, 0, 20, {}), small);
    ASSERT_TRUE(app.sdo_server().transfer_in_progress());
    handle(cat({{0x00, 0x20, 0x80, 0x10, 0x20, 0x00}, le32(0x05040000)}), small);
    EXPECT_EQ(small.queued(), 0u);
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
}

TEST_F(Sdo, TooShortRequestsGetAMailboxError) {
    // Mailbox error reply: service 0x0001, detail 0x0006 (size too short).
    for (const Buf& p : {Buf{0x00}, Buf{0x00, 0x20, 0x40, 0x00, 0x10, 0x00, 0x00, 0x00, 0x00}}) {
        Reply r = send(p, sink);
        EXPECT_EQ(r.type, MailboxType::Error);
        EXPECT_EQ(r.bytes, (Buf{0x01, 0x00, 0x06, 0x00}));
    }
}

TEST_F(Sdo, UnsupportedCoeServiceGetsAMailboxError) {
    // An emergency or SDO response from the master, a PDO over the mailbox: detail 0x0004.
    for (int service : {1, 3, 4, 5, 6, 7, 9, 15}) {
        SCOPED_TRACE(service);
        Buf p = upload_req(0x1000, 0);
        p[1] = static_cast<std::uint8_t>(service << 4);
        const Reply r = send(p, sink);
        EXPECT_EQ(r.type, MailboxType::Error);
        EXPECT_EQ(r.bytes, (Buf{0x01, 0x00, 0x04, 0x00}));
    }
}

// =========================================================================================================
// Complete access

TEST_F(Sdo, CompleteAccessUploadOfAssignmentIsExpedited) {
    // 0x1C12 from subindex 0: count (U8 + pad) and the one assigned PDO = 4 bytes -> 0x53.
    EXPECT_EQ(send(upload_req(0x1C12, 0, true)),
              (Buf{0x00, 0x30, 0x53, 0x12, 0x1C, 0x00, 0x01, 0x00, 0x00, 0x16}));
}

TEST_F(Sdo, CompleteAccessUploadOfMappingIsNormal) {
    // 0x1600: 7 entries -> 2 + 28 bytes, command 0x51 (complete access, size indicated).
    Buf want = {0x00, 0x30, 0x51, 0x00, 0x16, 0x00, 30, 0, 0, 0, 0x07, 0x00};
    for (std::uint32_t v :
         {0x60400010u, 0x60600008u, 0x00000008u, 0x607A0020u, 0x60FF0020u, 0x60710010u, 0x60B80010u})
        want = cat({want, le32(v)});
    EXPECT_EQ(send(upload_req(0x1600, 0, true)), want);
}

TEST_F(Sdo, CompleteAccessUploadFromSubindexOne) {
    // No subindex 0 in the data: the 7 mapping entries only.
    Buf want = {0x00, 0x30, 0x51, 0x00, 0x16, 0x01, 28, 0, 0, 0};
    for (std::uint32_t v :
         {0x60400010u, 0x60600008u, 0x00000008u, 0x607A0020u, 0x60FF0020u, 0x60710010u, 0x60B80010u})
        want = cat({want, le32(v)});
    EXPECT_EQ(send(upload_req(0x1600, 1, true)), want);
    // 0x1C12 from subindex 1: just the PDO number (2 bytes, expedited).
    EXPECT_EQ(send(upload_req(0x1C12, 1, true)),
              (Buf{0x00, 0x30, 0x5B, 0x12, 0x1C, 0x01, 0x00, 0x16, 0x00, 0x00}));
}

TEST_F(Sdo, CompleteAccessUploadOfIdentity) {
    Buf want = cat({{0x00, 0x30, 0x51, 0x18, 0x10, 0x00, 18, 0, 0, 0, 0x04, 0x00},
                    le32(0x00000A3C),
                    le32(0x00000402),
                    le32(0x00010000),
                    le32(0x00000001)});
    EXPECT_EQ(send(upload_req(0x1018, 0, true)), want);
}

TEST_F(Sdo, CompleteAccessWithSubindexAboveOneIsRefused) {
    EXPECT_EQ(send(upload_req(0x1600, 2, true)), abort_frame(0x1600, 2, 0x06010000));
    EXPECT_EQ(send(expedited_req(0x1C12, 2, {0x01, 0x16}, true)), abort_frame(0x1C12, 2, 0x06010000));
}

TEST_F(Sdo, CompleteAccessOnVarObjectIsRefused) {
    EXPECT_EQ(send(upload_req(obj::controlword.index, 0, true)),
              abort_frame(obj::controlword.index, 0, 0x06010000));
    EXPECT_EQ(send(expedited_req(obj::controlword.index, 0, {0x06, 0x00}, true)),
              abort_frame(obj::controlword.index, 0, 0x06010000));
}

TEST_F(Sdo, CompleteAccessDownloadOfAssignment) {
    // Given PREOP and the default assignment {0x1600} (16 output bytes), when 0x1C12 is written
    // completely with 01 00 01 16, then 0x1601 is assigned and the output image follows (10 bytes).
    ASSERT_EQ(app.process_data().output_bytes(), 16u);
    EXPECT_EQ(send(sdo_req(0x33, 0x1C12, 0, {0x01, 0x00, 0x01, 0x16})), download_ok(0x1C12, 0, true));
    EXPECT_EQ(od().find(0x1C12, 1)->get<std::uint16_t>(), 0x1601);
    EXPECT_EQ(od().find(0x1C12, 0)->as_uint64(), 1u);
    EXPECT_EQ(app.process_data().output_bytes(), 10u);
    EXPECT_EQ(app.output_bytes(), 10u);
    EXPECT_EQ(send(upload_req(0x1C12, 0, true)),
              (Buf{0x00, 0x30, 0x53, 0x12, 0x1C, 0x00, 0x01, 0x00, 0x01, 0x16}));
}

TEST_F(Sdo, CompleteAccessDownloadOfTwoPdos) {
    // Normal transfer (6 bytes): both RxPDOs, 16 + 10 output bytes.
    EXPECT_EQ(send(normal_req(0x1C12, 0, 6, {0x02, 0x00, 0x00, 0x16, 0x01, 0x16}, true)),
              download_ok(0x1C12, 0, true));
    EXPECT_EQ(app.process_data().output_bytes(), 26u);
}

TEST_F(Sdo, CompleteAccessDownloadWithBadEntryIsRolledBack) {
    // 0x1A00 in the RxPDO assignment is out of range: the whole write is undone.
    EXPECT_EQ(send(normal_req(0x1C12, 0, 6, {0x02, 0x00, 0x01, 0x16, 0x00, 0x1A}, true)),
              abort_frame(0x1C12, 0, 0x06090030));
    EXPECT_EQ(od().find(0x1C12, 0)->as_uint64(), 1u);
    EXPECT_EQ(od().find(0x1C12, 1)->get<std::uint16_t>(), 0x1600);
    EXPECT_EQ(od().find(0x1C12, 2)->get<std::uint16_t>(), 0u);
    EXPECT_EQ(app.process_data().output_bytes(), 16u);
    EXPECT_EQ(app.process_data().validate(), protocol::AlStatusCode::NoError);
}

TEST_F(Sdo, CompleteAccessDownloadOfMapping) {
    // A whole mapping in one complete write: controlword and target position = 6 output bytes.
    const Buf data = cat({{0x02, 0x00}, le32(0x60400010), le32(0x607A0020)});
    EXPECT_EQ(send(normal_req(0x1600, 0, 10, data, true)), download_ok(0x1600, 0, true));
    EXPECT_EQ(od().find(0x1600, 0)->as_uint64(), 2u);
    EXPECT_EQ(app.process_data().output_bytes(), 6u);
    // An unmappable entry (the identity) is refused, the previous mapping stays.
    const Buf bad = cat({{0x02, 0x00}, le32(0x60400010), le32(0x10180120)});
    EXPECT_EQ(send(normal_req(0x1600, 0, 10, bad, true)), abort_frame(0x1600, 0, 0x06040041));
    EXPECT_EQ(od().find(0x1600, 0)->as_uint64(), 2u);
    EXPECT_EQ(od().find(0x1600, 2)->get<std::uint32_t>(), 0x607A0020u);
    EXPECT_EQ(app.process_data().output_bytes(), 6u);
}

TEST_F(Sdo, CompleteAccessDownloadOfAssignmentInSafeOpIsRefused) {
    app.on_state_change(AlState::PreOp, AlState::SafeOp);
    EXPECT_EQ(send(sdo_req(0x33, 0x1C12, 0, {0x01, 0x00, 0x01, 0x16})), abort_frame(0x1C12, 0, 0x08000022));
    EXPECT_EQ(od().find(0x1C12, 1)->get<std::uint16_t>(), 0x1600);
}

// =========================================================================================================
// PDO mapping and assignment (ETG.1020)

TEST_F(Sdo, MappingEntryWritableOnlyWhileSubindexZeroIsZero) {
    EXPECT_EQ(send(expedited_req(0x1600, 1, le32(0x60400010))), abort_frame(0x1600, 1, 0x06010003));
    EXPECT_EQ(send(expedited_req(0x1C12, 1, le16(0x1601))), abort_frame(0x1C12, 1, 0x06010003));
    EXPECT_EQ(write_u8(0x1600, 0, 0), 0u);
    EXPECT_EQ(write_u32(0x1600, 1, 0x60400010), 0u);
}

TEST_F(Sdo, RemapChangesTheOutputImage) {
    // Given 0x1600 := {controlword, 8-bit gap, target position}, the output image is 7 bytes and
    // copy_outputs stores the fields into the mapped objects (the gap is skipped).
    remap(0x1600, {0x60400010, 0x00000008, 0x607A0020});
    EXPECT_EQ(app.process_data().output_bytes(), 7u);
    EXPECT_EQ(app.process_data().validate(), protocol::AlStatusCode::NoError);
    EXPECT_EQ(send(upload_req(0x1600, 0)), (Buf{0x00, 0x30, 0x4F, 0x00, 0x16, 0x00, 0x03, 0x00, 0x00, 0x00}));
    const Buf image = {0x0F, 0x00, 0xEE, 0x78, 0x56, 0x34, 0x12};
    app.process_data().copy_outputs(ConstBytes(image.data(), image.size()));
    EXPECT_EQ(od().find(obj::controlword)->get<std::uint16_t>(), 0x000F);
    EXPECT_EQ(od().find(obj::target_position)->get<std::uint32_t>(), 0x12345678u);
    EXPECT_EQ(read(obj::controlword.index, 0), (Buf{0x0F, 0x00}));
    // The target velocity is no longer mapped.
    EXPECT_EQ(od().find(obj::target_velocity)->get<std::uint32_t>(), 0u);
}

TEST_F(Sdo, RemapChangesTheInputImage) {
    // 0x1A00 := {statusword, position actual value, sync error (1 bit)} = 49 bits -> 7 bytes.
    ASSERT_EQ(app.process_data().input_bytes(), 28u);
    remap(0x1A00, {0x60410010, 0x60640020, 0x1C322001});
    EXPECT_EQ(app.process_data().input_bytes(), 7u);
    od().find(obj::statusword)->set(std::uint16_t{0x0237});
    od().find(obj::position_actual_value)->set(std::int32_t{-2});
    od().find(0x1C32, 32)->set(std::uint8_t{1});
    Buf image(7, 0);
    app.process_data().copy_inputs(Bytes(image.data(), image.size()));
    EXPECT_EQ(image, (Buf{0x37, 0x02, 0xFE, 0xFF, 0xFF, 0xFF, 0x01}));
}

TEST_F(Sdo, DefaultImagesMoveValuesBothWays) {
    // Default RxPDO 0x1600: controlword, mode, gap, target position, target velocity, torque, probe.
    ASSERT_EQ(app.process_data().output_bytes(), 16u);
    const Buf out = {0x06, 0x00, 0x08, 0xEE, 0x01, 0x02, 0x03, 0x04,
                     0x05, 0x06, 0x07, 0x08, 0x09, 0x0A, 0x0B, 0x0C};
    app.process_data().copy_outputs(ConstBytes(out.data(), out.size()));
    EXPECT_EQ(od().find(obj::controlword)->get<std::uint16_t>(), 0x0006);
    EXPECT_EQ(od().find(obj::modes_of_operation)->as_int64(), 8);
    EXPECT_EQ(od().find(obj::target_position)->get<std::uint32_t>(), 0x04030201u);
    EXPECT_EQ(od().find(obj::target_velocity)->get<std::uint32_t>(), 0x08070605u);
    EXPECT_EQ(od().find(obj::target_torque)->get<std::uint16_t>(), 0x0A09);
    EXPECT_EQ(od().find(obj::touch_probe_function)->get<std::uint16_t>(), 0x0C0B);
    // Default TxPDO 0x1A00 starts with statusword, mode display, gap, position actual value.
    od().find(obj::statusword)->set(std::uint16_t{0x1237});
    od().find(obj::modes_of_operation_display)->set(std::int8_t{8});
    od().find(obj::position_actual_value)->set(std::int32_t{0x11223344});
    Buf in(app.process_data().input_bytes(), 0);
    app.process_data().copy_inputs(Bytes(in.data(), in.size()));
    EXPECT_EQ(Buf(in.begin(), in.begin() + 8), (Buf{0x37, 0x12, 0x08, 0x00, 0x44, 0x33, 0x22, 0x11}));
}

// The map counts the copies of the outputs that changed a mapped entry (ProcessDataMap::outputs_changed):
// a device that caches its entries' values reads them again only then. The same image twice counts once;
// one changed byte, or an entry written in between that the image writes back, counts again.
TEST_F(Sdo, OnlyOutputsThatChangeAnEntryCount) {
    coe::ProcessDataMap& pd = app.process_data();
    Buf out(pd.output_bytes(), 0);
    out[0] = 0x06;
    const auto copy = [&] { pd.copy_outputs(ConstBytes(out.data(), out.size())); };
    copy();
    const std::uint64_t first = pd.outputs_changed();
    copy();
    EXPECT_EQ(pd.outputs_changed(), first) << "the same outputs again";
    out[2] = 8;  // modes of operation, a 1-byte entry
    copy();
    EXPECT_EQ(pd.outputs_changed(), first + 1);
    out[7] = 0x40;  // the last byte of the target position
    copy();
    EXPECT_EQ(pd.outputs_changed(), first + 2);
    od().find(obj::controlword)->set(std::uint16_t{0x000F});
    copy();
    EXPECT_EQ(pd.outputs_changed(), first + 3) << "the image wrote the controlword back";
    EXPECT_EQ(od().find(obj::controlword)->get<std::uint16_t>(), 0x0006);
}

TEST_F(Sdo, NonMappableObjectsAreRefused) {
    ASSERT_EQ(write_u8(0x1600, 0, 0), 0u);
    EXPECT_EQ(send(expedited_req(0x1600, 1, le32(0x10180120))),
              abort_frame(0x1600, 1, 0x06040041));  // identity
    EXPECT_EQ(send(expedited_req(0x1600, 1, le32(0x60410010))),
              abort_frame(0x1600, 1, 0x06040041));  // TxPDO only
    EXPECT_EQ(send(expedited_req(0x1600, 1, le32(0x12340010))),
              abort_frame(0x1600, 1, 0x06040041));  // no object
    EXPECT_EQ(send(expedited_req(0x1600, 1, le32(0x60400110))),
              abort_frame(0x1600, 1, 0x06040041));  // no subindex
    ASSERT_EQ(write_u8(0x1A00, 0, 0), 0u);
    EXPECT_EQ(send(expedited_req(0x1A00, 1, le32(0x60400010))),
              abort_frame(0x1A00, 1, 0x06040041));                       // RxPDO only
    EXPECT_EQ(od().find(0x1600, 1)->get<std::uint32_t>(), 0x60400010u);  // unchanged
}

TEST_F(Sdo, MappingWithWrongBitLengthIsRefused) {
    ASSERT_EQ(write_u8(0x1600, 0, 0), 0u);
    EXPECT_EQ(send(expedited_req(0x1600, 1, le32(0x60400008))), abort_frame(0x1600, 1, 0x06040041));
    EXPECT_EQ(send(expedited_req(0x1600, 1, le32(0x60400020))), abort_frame(0x1600, 1, 0x06040041));
    EXPECT_EQ(send(expedited_req(0x1600, 1, le32(0x60400000))), abort_frame(0x1600, 1, 0x06040041));
    EXPECT_EQ(write_u32(0x1600, 1, 0x60400010), 0u);
}

TEST_F(Sdo, SubindexZeroAboveTheValidEntriesIsRefused) {
    // 0x1600:08 is empty (0): counting it in is not a valid mapping.
    ASSERT_EQ(write_u8(0x1600, 0, 0), 0u);
    EXPECT_EQ(send(expedited_req(0x1600, 0, {8})), abort_frame(0x1600, 0, 0x06040041));
    EXPECT_EQ(send(expedited_req(0x1600, 0, {17})), abort_frame(0x1600, 0, 0x06090031));  // above capacity 16
    EXPECT_EQ(od().find(0x1600, 0)->as_uint64(), 0u);
}

TEST_F(Sdo, ProcessImageBeyondTheSyncManagerIsRefused) {
    // The default layout leaves 85 bytes for three output buffers. 0x1600 with 16 x 32 bits (64 bytes)
    // plus 0x1601 with 21 bytes fits exactly; one more byte does not, whichever object grows.
    ASSERT_EQ(app.process_data().max_output_bytes(), 85u);
    remap(0x1600,
          {0x607A0020, 0x60FF0020, 0x60650020, 0x60670020, 0x607C0020, 0x607F0020, 0x60810020, 0x60820020,
           0x60830020, 0x60840020, 0x60850020, 0x60870020, 0x609A0020, 0x60B00020, 0x60B10020, 0x60FE0120});
    EXPECT_EQ(app.process_data().output_bytes(), 64u);
    // 0x1601 is not assigned yet: 22 bytes on its own are fine.
    remap(0x1601,
          {0x60400010, 0x607A0020, 0x60810020, 0x60FF0020, 0x60650020, 0x60710010, 0x60600008, 0x60980008});
    EXPECT_EQ(app.process_data().output_bytes(), 64u);
    // Assigning both: 86 bytes.
    ASSERT_EQ(write_u8(0x1C12, 0, 0), 0u);
    ASSERT_EQ(write_u16(0x1C12, 2, 0x1601), 0u);
    EXPECT_EQ(send(expedited_req(0x1C12, 0, {2})), abort_frame(0x1C12, 0, 0x06040042));
    // With 7 entries in 0x1601 (21 bytes) the assignment fits: 85 bytes.
    ASSERT_EQ(write_u8(0x1601, 0, 0), 0u);
    ASSERT_EQ(write_u8(0x1601, 0, 7), 0u);
    ASSERT_EQ(write_u8(0x1C12, 0, 2), 0u);
    EXPECT_EQ(app.process_data().output_bytes(), 85u);
    EXPECT_EQ(app.process_data().validate(), protocol::AlStatusCode::NoError);
    // Growing the assigned 0x1601 by its 8th entry: refused.
    ASSERT_EQ(write_u8(0x1601, 0, 0), 0u);
    EXPECT_EQ(send(expedited_req(0x1601, 0, {8})), abort_frame(0x1601, 0, 0x06040042));
    EXPECT_EQ(write_u8(0x1601, 0, 7), 0u);
    EXPECT_EQ(app.process_data().output_bytes(), 85u);
}

TEST_F(Sdo, AssigningATxPdoToTheOutputsIsRefused) {
    ASSERT_EQ(write_u8(0x1C12, 0, 0), 0u);
    EXPECT_EQ(send(expedited_req(0x1C12, 1, le16(0x1A00))), abort_frame(0x1C12, 1, 0x06090030));
    EXPECT_EQ(send(expedited_req(0x1C12, 1, le16(0x1604))), abort_frame(0x1C12, 1, 0x06090030));  // no object
    ASSERT_EQ(write_u8(0x1C13, 0, 0), 0u);
    EXPECT_EQ(send(expedited_req(0x1C13, 1, le16(0x1600))), abort_frame(0x1C13, 1, 0x06090030));
    EXPECT_EQ(od().find(0x1C12, 1)->get<std::uint16_t>(), 0x1600);
}

TEST_F(Sdo, AssignmentRulesForCountAndDuplicates) {
    ASSERT_EQ(write_u8(0x1C12, 0, 0), 0u);
    EXPECT_EQ(app.process_data().output_bytes(), 0u);
    EXPECT_EQ(send(expedited_req(0x1C12, 0, {5})), abort_frame(0x1C12, 0, 0x06090031));  // 4 slots
    ASSERT_EQ(write_u16(0x1C12, 2, 0x1600), 0u);
    EXPECT_EQ(send(expedited_req(0x1C12, 0, {2})), abort_frame(0x1C12, 0, 0x06040043));  // the same PDO twice
    ASSERT_EQ(write_u16(0x1C12, 2, 0x1601), 0u);
    EXPECT_EQ(write_u8(0x1C12, 0, 2), 0u);
    EXPECT_EQ(app.process_data().output_bytes(), 26u);
}

TEST_F(Sdo, RxMappedObjectCannotBeWrittenBySdoInSafeOp) {
    // Given SAFEOP, the controlword (mapped into the assigned RxPDO) is written by the outputs only;
    // an unmapped RW object still is writable.
    EXPECT_EQ(write_u16(obj::controlword.index, 0, 0x0006), 0u);  // PREOP: allowed
    app.on_state_change(AlState::PreOp, AlState::SafeOp);
    EXPECT_EQ(send(expedited_req(obj::controlword.index, 0, le16(0x000F))),
              abort_frame(obj::controlword.index, 0, 0x06010006));
    EXPECT_EQ(write_u32(obj::profile_velocity.index, 0, 5000), 0u);
    app.on_state_change(AlState::SafeOp, AlState::Op);
    EXPECT_EQ(send(expedited_req(obj::target_position.index, 0, le32(1))),
              abort_frame(obj::target_position.index, 0, 0x06010006));
    EXPECT_EQ(od().find(obj::controlword)->get<std::uint16_t>(), 0x0006);
    EXPECT_EQ(read(obj::controlword.index, 0), (Buf{0x06, 0x00}));
}

TEST_F(Sdo, ExchangeMovesProcessDataThroughTheMappedObjects) {
    // Outputs are stored only when applied; inputs are always produced.
    const Buf out = {0x0F, 0x00, 0x09, 0x00, 0x10, 0x00, 0x00, 0x00, 0, 0, 0, 0, 0, 0, 0, 0};
    od().find(obj::statusword)->set(std::uint16_t{0x0637});
    Buf in(app.input_bytes(), 0);
    app.exchange(1000, ConstBytes(out.data(), out.size()), false, Bytes(in.data(), in.size()));
    EXPECT_EQ(od().find(obj::controlword)->get<std::uint16_t>(), 0u);
    EXPECT_EQ(in[0], 0x37);
    EXPECT_EQ(in[1], 0x06);
    app.exchange(2000, ConstBytes(out.data(), out.size()), true, Bytes(in.data(), in.size()));
    EXPECT_EQ(od().find(obj::controlword)->get<std::uint16_t>(), 0x000F);
    EXPECT_EQ(od().find(obj::modes_of_operation)->as_int64(), 9);
    EXPECT_EQ(od().find(obj::target_position)->get<std::uint32_t>(), 0x10u);
    EXPECT_EQ(app.exchanges(), 2u);
    // Safe state: every RxPDO-mapped object back to zero, others untouched.
    od().find(obj::profile_velocity)->set(std::uint32_t{777});
    app.outputs_safe_state();
    EXPECT_EQ(od().find(obj::controlword)->get<std::uint16_t>(), 0u);
    EXPECT_EQ(od().find(obj::modes_of_operation)->as_int64(), 0);
    EXPECT_EQ(od().find(obj::target_position)->get<std::uint32_t>(), 0u);
    EXPECT_EQ(od().find(obj::profile_velocity)->get<std::uint32_t>(), 777u);
}

TEST_F(Sdo, ApplicationServesCoeOnly) {
    EXPECT_EQ(app.mailbox_protocol(MailboxType::CoE), &app.sdo_server());
    EXPECT_EQ(app.sdo_server().type(), MailboxType::CoE);
    EXPECT_EQ(app.mailbox_protocol(MailboxType::FoE), nullptr);
    EXPECT_EQ(app.mailbox_protocol(MailboxType::EoE), nullptr);
}

TEST_F(Sdo, InvalidMappingFailsTheTransitionToSafeOp) {
    // A mapping that became invalid behind the SDO checks (the application's own write) is reported by
    // check_transition as "invalid output mapping" (0x0025).
    EXPECT_EQ(app.check_transition(AlState::PreOp, AlState::SafeOp), protocol::AlStatusCode::NoError);
    od().find(0x1600, 1)->set(std::uint32_t{0x10180120});
    app.process_data().rebuild();
    EXPECT_EQ(app.check_transition(AlState::PreOp, AlState::SafeOp),
              protocol::AlStatusCode::InvalidOutputMapping);
    od().find(0x1600, 1)->set(std::uint32_t{0x60400010});
    od().find(0x1A00, 2)->set(std::uint32_t{0x60400010});
    app.process_data().rebuild();
    EXPECT_EQ(app.check_transition(AlState::PreOp, AlState::SafeOp),
              protocol::AlStatusCode::InvalidInputMapping);
}

// =========================================================================================================
// SDO information

namespace {
struct InfoReply {
    std::uint8_t opcode = 0;
    std::uint16_t fragments_left = 0;
    Buf data;
};
InfoReply info_of(const Buf& r) {
    InfoReply i;
    if (r.size() < 6) {
        ADD_FAILURE() << "short SDO information reply";
        return i;
    }
    EXPECT_EQ(r[0], 0x00);
    EXPECT_EQ(r[1], 0x80);  // CoE service 8
    EXPECT_EQ(r[3], 0x00);
    i.opcode = r[2];
    i.fragments_left = ld_le16(r.data() + 4);
    i.data.assign(r.begin() + 6, r.end());
    return i;
}
std::vector<std::uint16_t> indexes_of(const Buf& list_data) {
    std::vector<std::uint16_t> v;
    for (std::size_t i = 2; i + 1 < list_data.size(); i += 2)
        v.push_back(ld_le16(list_data.data() + i));
    return v;
}
}  // namespace

TEST_F(Sdo, OdListOfAllObjects) {
    // The whole list, in as many fragments as the default mailbox needs (all queued at once).
    handle(info_req(0x01, le16(1)), sink);
    ASSERT_GE(sink.queued(), 1u);
    Buf list;
    std::size_t left = sink.queued();
    while (sink.queued()) {
        const InfoReply r = info_of(sink.take().bytes);
        --left;
        EXPECT_EQ(r.opcode, left == 0 ? 0x02 : 0x82);
        EXPECT_EQ(r.fragments_left, left);
        list.insert(list.end(), r.data.begin(), r.data.end());
    }
    ASSERT_GE(list.size(), 2u);
    EXPECT_EQ(ld_le16(list.data()), 1);
    std::vector<std::uint16_t> want;
    for (const auto& o : od().objects())
        want.push_back(o.index());
    const auto got = indexes_of(list);
    EXPECT_EQ(got, want);
    EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
    EXPECT_EQ(got.size(), device::dictionary_objects(device::default_drive()).size());
    EXPECT_EQ(list.size(), 2 + 2 * want.size());
}

TEST_F(Sdo, OdListLengths) {
    // Type 0: the number of objects in the lists 1..5.
    const InfoReply r = info_of(send(info_req(0x01, le16(0))));
    EXPECT_EQ(r.opcode, 0x02);
    ASSERT_EQ(r.data.size(), 12u);
    EXPECT_EQ(ld_le16(r.data.data()), 0);
    auto count = [&](std::uint16_t bit) {
        std::uint16_t n = 0;
        for (const auto& o : od().objects())
            if (std::any_of(o.entries().begin(), o.entries().end(),
                            [&](const Entry& e) { return e.access() & bit; }))
                ++n;
        return n;
    };
    EXPECT_EQ(ld_le16(r.data.data() + 2), od().objects().size());
    EXPECT_EQ(ld_le16(r.data.data() + 4), count(device::access::RxPdoMappable));
    EXPECT_EQ(ld_le16(r.data.data() + 6), count(device::access::TxPdoMappable));
    EXPECT_EQ(ld_le16(r.data.data() + 8), count(device::access::Backup));
    EXPECT_EQ(ld_le16(r.data.data() + 10), count(device::access::Settings));
    // The default drive: 170 objects (61 of them TWINsync, 0x1010/0x1011, the TX1250 objects
    // 0x2112-0x2115 and 0x60F2), 29 RxPDO-mappable (the gear numerator P2653 among them, TX1250 3.3), 50
    // TxPDO-mappable (26 of them TWINsync values), none backup/settings.
    EXPECT_EQ(r.data, cat({le16(0), le16(170), le16(29), le16(50), le16(0), le16(0)}));
}

TEST_F(Sdo, OdListOfPdoMappableObjects) {
    const InfoReply tx = info_of(send(info_req(0x01, le16(3))));
    EXPECT_EQ(ld_le16(tx.data.data()), 3);
    const auto t = indexes_of(tx.data);
    EXPECT_NE(std::find(t.begin(), t.end(), obj::statusword.index), t.end());
    EXPECT_NE(std::find(t.begin(), t.end(), obj::position_actual_value.index), t.end());
    EXPECT_NE(std::find(t.begin(), t.end(), 0x1C32), t.end());  // sync error
    EXPECT_EQ(std::find(t.begin(), t.end(), obj::controlword.index), t.end());
    EXPECT_EQ(std::find(t.begin(), t.end(), 0x1018), t.end());
    EXPECT_TRUE(std::is_sorted(t.begin(), t.end()));

    const InfoReply rx = info_of(send(info_req(0x01, le16(2))));
    const auto x = indexes_of(rx.data);
    EXPECT_NE(std::find(x.begin(), x.end(), obj::controlword.index), x.end());
    EXPECT_NE(std::find(x.begin(), x.end(), obj::target_position.index), x.end());
    EXPECT_EQ(std::find(x.begin(), x.end(), obj::statusword.index), x.end());
}

TEST_F(Sdo, OdListOfUnknownTypeIsAnInfoError) {
    const Buf r = send(info_req(0x01, le16(6)));
    ASSERT_EQ(r.size(), 10u);
    EXPECT_EQ(Buf(r.begin(), r.begin() + 6), (Buf{0x00, 0x80, 0x07, 0x00, 0x00, 0x00}));
    EXPECT_NE(ld_le32(r.data() + 6), 0u);
    EXPECT_EQ(send(info_req(0x01, le16(0xFFFF))), r);
}

TEST_F(Sdo, OdListIsFragmentedForASmallMailbox) {
    // Given a 40-byte reply mailbox (34 bytes of list per fragment) with room for one reply at a time,
    // the list comes in fragments: opcode 0x82 with fragments left counting down, the last one 0x02 with
    // 0 left; handle() sends the first, poll() the others once the mailbox is read.
    FakeSink small(40, 1);
    const std::size_t total = 2 + 2 * od().objects().size();
    const std::size_t fragments = (total + 33) / 34;
    ASSERT_GT(fragments, 2u);
    handle(info_req(0x01, le16(1)), small);
    Buf list;
    for (std::size_t k = 0; k < fragments; ++k) {
        SCOPED_TRACE(k);
        if (k > 0) {
            EXPECT_EQ(small.queued(), 0u);
            app.sdo_server().poll(small);
        }
        ASSERT_EQ(small.queued(), 1u);
        const InfoReply r = info_of(small.take().bytes);
        const bool last = k + 1 == fragments;
        EXPECT_EQ(r.opcode, last ? 0x02 : 0x82);
        EXPECT_EQ(r.fragments_left, fragments - 1 - k);
        EXPECT_EQ(r.data.size(), last ? total - 34 * k : 34u);
        list.insert(list.end(), r.data.begin(), r.data.end());
    }
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
    app.sdo_server().poll(small);
    EXPECT_EQ(small.queued(), 0u);
    std::vector<std::uint16_t> want;
    for (const auto& o : od().objects())
        want.push_back(o.index());
    EXPECT_EQ(ld_le16(list.data()), 1);
    EXPECT_EQ(indexes_of(list), want);
}

TEST_F(Sdo, OdListFragmentsAllQueuedWhenThereIsRoom) {
    FakeSink small(40, 64);
    handle(info_req(0x01, le16(1)), small);
    const std::size_t fragments = (2 + 2 * od().objects().size() + 33) / 34;
    EXPECT_EQ(small.queued(), fragments);
    EXPECT_EQ(info_of(small.take().bytes).fragments_left, fragments - 1);
}

TEST_F(Sdo, NewInfoRequestEndsAFragmentedList) {
    FakeSink small(40, 1);
    handle(info_req(0x01, le16(1)), small);
    small.take();
    EXPECT_TRUE(app.sdo_server().transfer_in_progress());
    handle(info_req(0x03, le16(0x1000)), small);
    const InfoReply r = info_of(small.take().bytes);
    EXPECT_EQ(r.opcode, 0x04);
    app.sdo_server().poll(small);
    EXPECT_EQ(small.queued(), 0u);
    EXPECT_FALSE(app.sdo_server().transfer_in_progress());
}

TEST_F(Sdo, ObjectDescription) {
    // 0x1018: data type 0x0023 (identity), max subindex 4, object code 9 (RECORD), name.
    EXPECT_EQ(
        send(info_req(0x03, le16(0x1018))),
        cat({{0x00, 0x80, 0x04, 0x00, 0x00, 0x00, 0x18, 0x10, 0x23, 0x00, 0x04, 0x09}, text("Identity")}));
    // A VAR: 0x6040 UNSIGNED16, code 7.
    EXPECT_EQ(
        send(info_req(0x03, le16(obj::controlword.index))),
        cat({{0x00, 0x80, 0x04, 0x00, 0x00, 0x00, 0x40, 0x60, 0x06, 0x00, 0x00, 0x07}, text("Controlword")}));
    // An ARRAY: 0x1C12 of UNSIGNED16, 4 slots, code 8.
    EXPECT_EQ(send(info_req(0x03, le16(0x1C12))),
              cat({{0x00, 0x80, 0x04, 0x00, 0x00, 0x00, 0x12, 0x1C, 0x06, 0x00, 0x04, 0x08},
                   text("RxPDO assign")}));
}

TEST_F(Sdo, EntryDescriptionWithoutValues) {
    // Value info 0x07: no default/min/max; the name follows the 10-byte fixed part (payload offset 16).
    const Buf r = send(info_req(0x05, {0x18, 0x10, 0x01, 0x07}));
    EXPECT_EQ(
        r,
        cat({{0x00, 0x80, 0x06, 0x00, 0x00, 0x00, 0x18, 0x10, 0x01, 0x07, 0x07, 0x00, 0x20, 0x00, 0x07, 0x00},
             text("Vendor ID")}));
    ASSERT_GE(r.size(), 16u);
    EXPECT_EQ(std::string(r.begin() + 16, r.end()), "Vendor ID");
}

TEST_F(Sdo, EntryDescriptionWithDefaultMinimumAndMaximum) {
    // 0x605A: INTEGER16, 16 bits, RW (0x3F); default 2, minimum 0, maximum 8, then the name.
    EXPECT_EQ(
        send(info_req(0x05, {0x5A, 0x60, 0x00, 0x70})),
        cat({{0x00, 0x80, 0x06, 0x00, 0x00, 0x00, 0x5A, 0x60, 0x00, 0x70, 0x03, 0x00, 0x10, 0x00, 0x3F, 0x00},
             le16(2),
             le16(0),
             le16(8),
             text("Quick stop option code")}));
}

TEST_F(Sdo, EntryDescriptionReportsTypeLimitsWithoutDeclaredRange) {
    // 0x6071 Target torque: INTEGER16, RxPDO-mappable RW (0x7F); min/max of the type.
    EXPECT_EQ(
        send(info_req(0x05, {0x71, 0x60, 0x00, 0x60})),
        cat({{0x00, 0x80, 0x06, 0x00, 0x00, 0x00, 0x71, 0x60, 0x00, 0x60, 0x03, 0x00, 0x10, 0x00, 0x7F, 0x00},
             {0x00, 0x80, 0xFF, 0x7F},
             text("Target torque")}));
    // 0x6041 Statusword: UNSIGNED16, TxPDO-mappable RO (0x87); default 0.
    EXPECT_EQ(
        send(info_req(0x05, {0x41, 0x60, 0x00, 0x10})),
        cat({{0x00, 0x80, 0x06, 0x00, 0x00, 0x00, 0x41, 0x60, 0x00, 0x10, 0x06, 0x00, 0x10, 0x00, 0x87, 0x00},
             {0x00, 0x00},
             text("Statusword")}));
}

TEST_F(Sdo, EntryDescriptionOfUnknownObjectOrSubindex) {
    EXPECT_EQ(send(info_req(0x03, le16(0x1234))), info_error(0x06020000));
    EXPECT_EQ(send(info_req(0x05, {0x34, 0x12, 0x00, 0x00})), info_error(0x06020000));
    EXPECT_EQ(send(info_req(0x05, {0x18, 0x10, 0x05, 0x00})), info_error(0x06090011));
    EXPECT_EQ(send(info_req(0x05, {0x32, 0x1C, 0x14, 0x00})), info_error(0x06090011));
}

TEST_F(Sdo, UnknownInfoOpcodeIsAnInfoError) {
    EXPECT_EQ(send(info_req(0x09, le16(0))), info_error(0x05040001));
    EXPECT_EQ(send(info_req(0x02, le16(1))), info_error(0x05040001));  // a response opcode
}

TEST_F(Sdo, TooShortInfoRequestsGetAMailboxError) {
    for (const Buf& p : {Buf{0x00, 0x80, 0x01}, info_req(0x01, {}), info_req(0x01, {0x01}),
                         info_req(0x03, {0x18}), info_req(0x05, {0x18, 0x10, 0x01})}) {
        Reply r = send(p, sink);
        EXPECT_EQ(r.type, MailboxType::Error);
        EXPECT_EQ(r.bytes, (Buf{0x01, 0x00, 0x06, 0x00}));
    }
}

// =========================================================================================================
// Emergencies

TEST_F(Sdo, RaisedFaultIsSentAsEmergency) {
    // Given a fault 0x2310 with the current bit, when the mailbox is free, then poll() sends the
    // emergency: CoE service 1, error code, error register (current + generic), 5 data bytes.
    app.raise_fault(0x2310, error_register::Current, {0xA1, 0xA2, 0xA3, 0xA4, 0xA5});
    EXPECT_EQ(od().find(0x1001, 0)->as_uint64(), 0x03u);
    EXPECT_EQ(od().find(obj::error_code)->as_uint64(), 0x2310u);
    EXPECT_EQ(sink.queued(), 0u);
    app.sdo_server().poll(sink);
    ASSERT_EQ(sink.queued(), 1u);
    const Reply r = sink.take();
    EXPECT_EQ(r.type, MailboxType::CoE);
    EXPECT_EQ(r.bytes, (Buf{0x00, 0x10, 0x10, 0x23, 0x03, 0xA1, 0xA2, 0xA3, 0xA4, 0xA5}));
    EXPECT_EQ(app.sdo_server().counters().emergencies_sent, 1u);
    app.sdo_server().poll(sink);
    EXPECT_EQ(sink.queued(), 0u);
    // The registers are readable by SDO.
    EXPECT_EQ(read(0x1001, 0), (Buf{0x03}));
    EXPECT_EQ(read(obj::error_code.index, 0), (Buf{0x10, 0x23}));
}

TEST_F(Sdo, EmergencyWaitsForTheMailbox) {
    app.raise_fault(0x2310, error_register::Current);
    sink.unread_in_sm = 1;  // the master has not read the last reply
    app.sdo_server().poll(sink);
    EXPECT_EQ(sink.queued(), 0u);
    sink.unread_in_sm = 0;
    app.sdo_server().poll(sink);
    ASSERT_EQ(sink.queued(), 1u);
    EXPECT_EQ(sink.take().bytes, (Buf{0x00, 0x10, 0x10, 0x23, 0x03, 0, 0, 0, 0, 0}));
}

TEST_F(Sdo, ClearFaultsSendsErrorReset) {
    app.raise_fault(0x2310, error_register::Current);
    app.clear_faults();
    EXPECT_EQ(od().find(0x1001, 0)->as_uint64(), 0u);
    EXPECT_EQ(od().find(obj::error_code)->as_uint64(), 0u);
    app.sdo_server().poll(sink);  // the fault first, then the reset
    ASSERT_EQ(sink.queued(), 1u);
    EXPECT_EQ(sink.take().bytes, (Buf{0x00, 0x10, 0x10, 0x23, 0x03, 0, 0, 0, 0, 0}));
    app.sdo_server().poll(sink);
    ASSERT_EQ(sink.queued(), 1u);
    EXPECT_EQ(sink.take().bytes, (Buf{0x00, 0x10, 0x00, 0x00, 0x00, 0, 0, 0, 0, 0}));
}

TEST_F(Sdo, AlErrorDuringPreOpToSafeOpIsReported) {
    // The AL status code 0x001D goes into the first data bytes of emergency 0xA000.
    EXPECT_EQ(app.check_transition(AlState::PreOp, AlState::SafeOp), protocol::AlStatusCode::NoError);
    app.on_al_error(protocol::AlStatusCode::InvalidOutputConfig);
    EXPECT_EQ(od().find(0x1001, 0)->as_uint64(), 0x11u);     // communication + generic
    EXPECT_EQ(od().find(obj::error_code)->as_uint64(), 0u);  // not a device fault
    app.sdo_server().poll(sink);
    ASSERT_EQ(sink.queued(), 1u);
    EXPECT_EQ(sink.take().bytes, (Buf{0x00, 0x10, 0x00, 0xA0, 0x11, 0x1D, 0x00, 0x00, 0x00, 0x00}));
    // Acknowledged: the error register clears and an error reset follows.
    app.on_al_error(protocol::AlStatusCode::NoError);
    EXPECT_EQ(od().find(0x1001, 0)->as_uint64(), 0u);
    app.sdo_server().poll(sink);
    ASSERT_EQ(sink.queued(), 1u);
    EXPECT_EQ(sink.take().bytes, (Buf{0x00, 0x10, 0x00, 0x00, 0x00, 0, 0, 0, 0, 0}));
}

TEST_F(Sdo, AlErrorDuringSafeOpToOpAndWatchdog) {
    app.check_transition(AlState::SafeOp, AlState::Op);
    app.on_al_error(protocol::AlStatusCode::NoValidOutputs);
    app.on_al_error(protocol::AlStatusCode::SyncManagerWatchdog);
    app.sdo_server().poll(sink);
    ASSERT_EQ(sink.queued(), 1u);  // one at a time: the next waits until this one is read
    EXPECT_EQ(sink.take().bytes, (Buf{0x00, 0x10, 0x01, 0xA0, 0x11, 0x19, 0x00, 0x00, 0x00, 0x00}));
    app.sdo_server().poll(sink);
    ASSERT_EQ(sink.queued(), 1u);
    EXPECT_EQ(sink.take().bytes, (Buf{0x00, 0x10, 0x30, 0x81, 0x11, 0x1B, 0x00, 0x00, 0x00, 0x00}));
}

TEST_F(Sdo, RefusalWithoutACheckedTransitionIsAGenericCommunicationError) {
    // Given a PREOP->SAFEOP check that was refused and reported ...
    app.check_transition(AlState::PreOp, AlState::SafeOp);
    app.on_al_error(protocol::AlStatusCode::InvalidOutputConfig);
    app.sdo_server().poll(sink);
    ASSERT_EQ(sink.queued(), 1u);
    EXPECT_EQ(ld_le16(sink.take().bytes.data() + 2), 0xA000);
    // ... a later refusal that runs no check (0x0011) does not reuse that transition's code.
    app.on_al_error(protocol::AlStatusCode::InvalidRequestedStateChange);
    app.sdo_server().poll(sink);
    ASSERT_EQ(sink.queued(), 1u);
    const Buf e = sink.take().bytes;
    EXPECT_EQ(ld_le16(e.data() + 2), 0x8100);
    EXPECT_EQ(ld_le16(e.data() + 5), 0x0011);
}

TEST_F(Sdo, EmergencyQueueIsBounded) {
    for (std::size_t i = 0; i < SdoServer::kEmergencySlots; ++i)
        EXPECT_TRUE(app.sdo_server().emergency({static_cast<std::uint16_t>(0x5000 + i), 0x01, {}}));
    EXPECT_FALSE(app.sdo_server().emergency({0x5FFF, 0x01, {}}));
    EXPECT_EQ(app.sdo_server().counters().emergencies_dropped, 1u);
    for (std::size_t i = 0; i < SdoServer::kEmergencySlots; ++i) {
        app.sdo_server().poll(sink);
        ASSERT_EQ(sink.queued(), 1u) << i;
        EXPECT_EQ(ld_le16(sink.take().bytes.data() + 2), 0x5000 + i);
    }
    app.sdo_server().poll(sink);
    EXPECT_EQ(sink.queued(), 0u);
    EXPECT_EQ(app.sdo_server().counters().emergencies_sent, SdoServer::kEmergencySlots);
}

TEST_F(Sdo, EmergencyNeverSitsBetweenRequestAndReply) {
    // A queued emergency is not sent by handle(): the reply to the request comes alone.
    app.raise_fault(0x2310, error_register::Current);
    EXPECT_EQ(send(upload_req(0x1000, 0)), (Buf{0x00, 0x30, 0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00}));
    app.sdo_server().poll(sink);
    ASSERT_EQ(sink.queued(), 1u);
    EXPECT_EQ(sink.take().bytes[1], 0x10);
}

// The master side (master::CoeClient) against a whole slave: the SDO information answers it assembles
// agree with the dictionary, and a segmented round trip through SM0/SM1 keeps every byte.
TEST(CoeClientThroughTheSlave, SdoInformationAndSegmentedTransfers) {
    vecat::test::Bench b(1);
    std::string why;
    ASSERT_TRUE(b.master.startup(AlState::PreOp, &why)) << why;
    vecat::master::CoeClient c(b.master, b.master.slaves()[0].station);
    auto all = c.od_list(vecat::protocol::sdo_info::ListAll);
    ASSERT_TRUE(all);
    ASSERT_EQ(all->size(), b.od().objects().size());
    for (std::size_t i = 0; i < all->size(); ++i)
        EXPECT_EQ((*all)[i], b.od().objects()[i].index());
    EXPECT_FALSE(c.od_list(77));
    EXPECT_EQ(c.last_abort(), SdoAbort::UnsupportedAccess);
    auto o = c.object_description(0x1018);
    ASSERT_TRUE(o);
    EXPECT_EQ(o->name, "Identity");
    EXPECT_EQ(o->max_subindex, 4);
    auto e = c.entry_description(obj::quick_stop_option_code.index, 0, 0x70);
    ASSERT_TRUE(e);
    EXPECT_EQ(e->values, (Buf{0x02, 0x00, 0x00, 0x00, 0x08, 0x00}));
    EXPECT_EQ(e->name, "Quick stop option code");
    // 0x2020 (512 bytes) needs segments both ways through a 246-byte mailbox.
    Buf pattern(512);
    for (std::size_t i = 0; i < pattern.size(); ++i)
        pattern[i] = static_cast<std::uint8_t>(i * 7);
    b.od().find(0x2020, 0)->assign(ConstBytes(pattern.data(), pattern.size()));
    auto up = c.upload(0x2020, 0);
    ASSERT_TRUE(up.ok());
    EXPECT_EQ(up.data, pattern);
    const std::string label = "a label of thirty-two characters";
    auto down =
        c.download(0x2010, 0, ConstBytes(reinterpret_cast<const std::uint8_t*>(label.data()), label.size()),
                   false, vecat::master::CoeClient::Transfer::Segmented);
    ASSERT_TRUE(down.ok());
    auto back = c.upload(0x2010, 0);
    EXPECT_EQ(std::string(back.data.begin(), back.data.end()), label);
}
