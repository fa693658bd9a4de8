// Cable redundancy: a line of drives cabled back to the master's second port (a ring). Raw frames show
// the way a frame takes from either side; the project's master behind a link that does what a redundant
// master does (SOEM's redundant mode: the frame out of the primary port, a dummy of the same index out of
// the secondary one, and with the ring broken the primary's result sent again out of the secondary port)
// keeps the line in OP through a break at every position and after the ring closes again.
#include <gtest/gtest.h>

#include <array>
#include <cstring>

#include "coe/coe_application.hpp"
#include "device/device_description.hpp"
#include "esc/segment.hpp"
#include "master/master.hpp"
#include "net/link.hpp"
#include "protocol/frame.hpp"
#include "protocol/registers.hpp"

using namespace vecat;
using esc::MasterPort;
using protocol::AlState;
using protocol::Reg;

namespace {

constexpr std::size_t kDrives = 4;

// One frame of one datagram, built by hand: cmd adp ado with len data bytes.
struct RawFrame {
    std::array<std::uint8_t, 1600> buf{};
    std::size_t len = 0;
    RawFrame(protocol::Command cmd, std::uint16_t adp, std::uint16_t ado, std::uint16_t dlen,
             std::uint8_t index = 0x42) {
        std::uint8_t* f = buf.data();
        std::memset(f, 0xFF, 6);  // destination: broadcast
        f[6] = 0x01;              // source 01:01:01:01:01:01
        std::memset(f + 7, 0x01, 5);
        f[12] = 0x88, f[13] = 0xA4;  // EtherType EtherCAT
        const std::uint16_t flen = static_cast<std::uint16_t>(10 + dlen + 2);
        st_le16(f + 14, static_cast<std::uint16_t>(flen | 0x1000));  // type 1: commands
        f[16] = static_cast<std::uint8_t>(cmd);
        f[17] = index;
        st_le16(f + 18, adp);
        st_le16(f + 20, ado);
        st_le16(f + 22, dlen);
        len = 14 + 2 + flen;
    }
    std::uint16_t wkc() const {
        const std::size_t at = 14 + 2 + 10 + ld_le16(buf.data() + 22);
        return ld_le16(buf.data() + at);
    }
};

struct Sent {
    bool back = false;
    MasterPort at = MasterPort::Primary;
    std::uint16_t wkc = 0;
};

Sent send(esc::Segment& seg, RawFrame f, MasterPort from, std::uint64_t now) {
    Sent s;
    s.back = seg.process_frame(Bytes(f.buf.data(), f.buf.size()), f.len, now, {}, from);
    s.at = seg.reply_port();
    s.wkc = f.wkc();
    return s;
}

// The master's two ports on the ring, as a redundant master uses them (SOEM 2.x ecx_outframe_red and
// ecx_waitinframe_red do the same; this is written from the way the frames go, not from their code).
class RedundantLink final : public net::Link {
  public:
    explicit RedundantLink(esc::Segment& seg) : seg_(seg) {}
    bool send(ConstBytes frame) override {
        if (frame.size() > prim_.size() || frame.size() < 18) return false;
        now_ += 100'000;
        // Out of the primary port: the frame itself; out of the secondary port: a BRD of the same index.
        std::memcpy(prim_.data(), frame.data(), frame.size());
        std::size_t plen = frame.size();
        const bool p_back =
            seg_.process_frame(Bytes(prim_.data(), prim_.size()), plen, now_, {}, MasterPort::Primary);
        const MasterPort p_at = seg_.reply_port();
        RawFrame dummy(protocol::Command::BRD, 0, 0, 2, frame[17]);
        const bool s_back = seg_.process_frame(Bytes(dummy.buf.data(), dummy.buf.size()), dummy.len, now_, {},
                                               MasterPort::Secondary);
        const MasterPort s_at = seg_.reply_port();
        pending_ = false;
        ++frames_;
        if (p_back && p_at == MasterPort::Secondary) {
            // The ring is whole: the primary frame went round, the dummy came back unprocessed.
            ++whole_;
            return keep(prim_.data(), plen);
        }
        if (s_back && s_at == MasterPort::Secondary) {
            // Broken: each side reached its part of the line. The primary's result (or, if it was lost,
            // the frame as sent) goes again out of the secondary port to the slaves behind the break.
            ++broken_;
            std::size_t len = p_back ? plen : frame.size();
            if (!p_back) std::memcpy(prim_.data(), frame.data(), frame.size());
            if (seg_.process_frame(Bytes(prim_.data(), prim_.size()), len, now_, {}, MasterPort::Secondary) &&
                seg_.reply_port() == MasterPort::Secondary)
                return keep(prim_.data(), len);
            return true;
        }
        if (p_back) {
            ++primary_only_;  // the redundancy cable is down: an open line from the primary port
            return keep(prim_.data(), plen);
        }
        return true;
    }
    long receive(Bytes out, std::int64_t) override {
        if (!pending_) return 0;
        pending_ = false;
        const std::size_t n = std::min(len_, out.size());
        std::memcpy(out.data(), reply_.data(), n);
        return static_cast<long>(n);
    }
    std::uint64_t now() const { return now_; }
    unsigned whole_ = 0;   // frames that went round the whole ring
    unsigned broken_ = 0;  // frames that needed both sides
    unsigned primary_only_ = 0;
    unsigned frames_ = 0;

  private:
    bool keep(const std::uint8_t* f, std::size_t n) {
        std::memcpy(reply_.data(), f, n);
        len_ = n;
        pending_ = true;
        return true;
    }
    esc::Segment& seg_;
    std::array<std::uint8_t, 1600> prim_{}, reply_{};
    std::size_t len_ = 0;
    bool pending_ = false;
    std::uint64_t now_ = 1'000'000'000;
};

std::unique_ptr<esc::Segment> ring(std::size_t n) {
    auto seg = coe::make_coe_segment(device::default_drive(), n, {});
    std::string why;
    EXPECT_TRUE(seg->set_redundancy(n - 1, 1, &why)) << why;
    return seg;
}

std::uint16_t reg16(esc::Segment& seg, std::size_t i, Reg r) {
    return seg.slave(i).esc().peek16(protocol::addr(r));
}
std::uint8_t lost_links(esc::Segment& seg, std::size_t i, unsigned port) {
    return seg.slave(i).esc().peek(static_cast<std::uint16_t>(protocol::addr(Reg::LostLinkCounter) + port));
}

}  // namespace

TEST(Redundancy, RefusesAPortThatIsTakenOrMissing) {
    auto seg = coe::make_coe_segment(device::default_drive(), 3, {});
    std::string why;
    EXPECT_FALSE(seg->set_redundancy(1, 1, &why));  // port 1 of slave 1 leads to slave 2
    EXPECT_NE(why.find("cabled to slave 2"), std::string::npos) << why;
    EXPECT_FALSE(seg->set_redundancy(3, 1, &why));
    EXPECT_FALSE(seg->set_redundancy(2, 0, &why));
    EXPECT_FALSE(seg->redundant());
    EXPECT_TRUE(seg->set_redundancy(2, 1, &why)) << why;
    EXPECT_TRUE(seg->redundant());
    EXPECT_EQ(seg->cables(), 4u);
    EXPECT_EQ(seg->cable_at(2, 1), 3u);
    EXPECT_EQ(seg->cable_at(1, 1), 2u);
    EXPECT_EQ(seg->cable_at(2, 2), esc::Segment::kNoCable);
    // The last slave's port 1 now has a link (to the master's secondary port).
    EXPECT_TRUE(seg->slave(2).esc().port_link(1));
}

TEST(Redundancy, WholeRingFramesGoRoundFromEitherSide) {
    auto seg = ring(kDrives);
    const Sent p = send(*seg, RawFrame(protocol::Command::BRD, 0, 0, 2), MasterPort::Primary, 1000);
    EXPECT_TRUE(p.back);
    EXPECT_EQ(p.at, MasterPort::Secondary);  // through every slave, out of the last one's port 1
    EXPECT_EQ(p.wkc, kDrives);
    const Sent s = send(*seg, RawFrame(protocol::Command::BRD, 0, 0, 2), MasterPort::Secondary, 2000);
    EXPECT_TRUE(s.back);
    EXPECT_EQ(s.at, MasterPort::Primary);  // enters at port 1: passes the ESCs unprocessed
    EXPECT_EQ(s.wkc, 0);
    EXPECT_EQ(seg->reachable(), kDrives);
}

TEST(Redundancy, BreakAtEachPositionSplitsTheRingAndClosesAgain) {
    for (std::size_t k = 0; k <= kDrives; ++k) {
        SCOPED_TRACE("cable " + std::to_string(k));
        auto seg = ring(kDrives);
        seg->set_cable(k, false);
        const Sent p = send(*seg, RawFrame(protocol::Command::BRD, 0, 0, 2), MasterPort::Primary, 1000);
        const Sent s = send(*seg, RawFrame(protocol::Command::BRD, 0, 0, 2), MasterPort::Secondary, 2000);
        // The primary side reaches the slaves before the break, the secondary side the ones after it, each
        // frame back at the port it left.
        EXPECT_EQ(p.back, k > 0);
        if (k > 0) {
            EXPECT_EQ(p.at, MasterPort::Primary);
            EXPECT_EQ(p.wkc, k);
        }
        EXPECT_EQ(s.back, k < kDrives);
        if (k < kDrives) {
            EXPECT_EQ(s.at, MasterPort::Secondary);
            EXPECT_EQ(s.wkc, kDrives - k);
        }
        EXPECT_EQ((k > 0 ? p.wkc : 0) + (k < kDrives ? s.wkc : 0), kDrives);
        // Auto loop control closed the ports at the break; their lost link counters counted.
        if (k > 0) {
            EXPECT_EQ(lost_links(*seg, k - 1, 1), 1) << "port 1 of slave " << k - 1;
            EXPECT_TRUE(reg16(*seg, k - 1, Reg::DlStatus) & protocol::dl_status::loop_closed(1));
        }
        if (k < kDrives) {
            EXPECT_EQ(lost_links(*seg, k, 0), 1) << "port 0 of slave " << k;
            EXPECT_TRUE(reg16(*seg, k, Reg::DlStatus) & protocol::dl_status::loop_closed(0));
        }
        EXPECT_EQ(seg->reachable(), kDrives);
        // The cable back: the ring closes, the frame goes round again.
        seg->set_cable(k, true);
        const Sent again = send(*seg, RawFrame(protocol::Command::BRD, 0, 0, 2), MasterPort::Primary, 3000);
        EXPECT_TRUE(again.back);
        EXPECT_EQ(again.at, MasterPort::Secondary);
        EXPECT_EQ(again.wkc, kDrives);
    }
}

TEST(Redundancy, TwoBreaksCutTheSlavesBetweenThemOff) {
    auto seg = ring(kDrives);
    seg->set_cable(1, false);
    seg->set_cable(3, false);
    const Sent p = send(*seg, RawFrame(protocol::Command::BRD, 0, 0, 2), MasterPort::Primary, 1000);
    const Sent s = send(*seg, RawFrame(protocol::Command::BRD, 0, 0, 2), MasterPort::Secondary, 2000);
    EXPECT_EQ(p.wkc, 1);  // slave 0
    EXPECT_EQ(s.wkc, 1);  // slave 3
    EXPECT_EQ(seg->reachable(), 2u);
    EXPECT_FALSE(seg->reached(1));
    EXPECT_FALSE(seg->reached(2));
}

TEST(Redundancy, ThePrimaryFrameDoesNotLatchPortsItNeverComesBackThrough) {
    auto seg = ring(2);
    // A receive-time latch going round: port 0 latches on the way out; port 1 of slave 0 sees the frame
    // go out, never come back, and keeps its time.
    const std::uint32_t old1 = seg->slave(0).esc().peek32(protocol::addr(Reg::DcRecvTimePort1));
    RawFrame latch(protocol::Command::BWR, 0, protocol::addr(Reg::DcRecvTimePort0), 4);
    std::size_t len = latch.len;
    ASSERT_TRUE(seg->process_frame(Bytes(latch.buf.data(), latch.buf.size()), len, 5'000'000, {},
                                   MasterPort::Primary));
    EXPECT_EQ(seg->slave(0).esc().peek32(protocol::addr(Reg::DcRecvTimePort1)), old1);
    EXPECT_NE(seg->slave(0).esc().peek32(protocol::addr(Reg::DcRecvTimePort0)), 0u);
    // With the ring open at the far end, the frame comes back through port 1 and latches it.
    seg->set_cable(2, false);
    len = latch.len;
    ASSERT_TRUE(seg->process_frame(Bytes(latch.buf.data(), latch.buf.size()), len, 6'000'000, {},
                                   MasterPort::Primary));
    EXPECT_EQ(seg->reply_port(), MasterPort::Primary);
    EXPECT_GT(seg->slave(0).esc().peek32(protocol::addr(Reg::DcRecvTimePort1)),
              seg->slave(0).esc().peek32(protocol::addr(Reg::DcRecvTimePort0)));
}

TEST(Redundancy, ProjectMasterKeepsTheLineInOpThroughABreakAtEachPosition) {
    for (std::size_t k = 0; k <= kDrives; ++k) {
        SCOPED_TRACE("cable " + std::to_string(k));
        auto seg = ring(kDrives);
        RedundantLink link(*seg);
        master::Master m(link);
        ASSERT_EQ(m.count_slaves(), static_cast<int>(kDrives));
        std::string why;
        ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
        const std::uint16_t expected = m.expected_wkc();
        for (int i = 0; i < 10; ++i)
            ASSERT_EQ(m.exchange_process_data().value_or(0), expected);
        EXPECT_GT(link.whole_, 0u);
        EXPECT_EQ(link.broken_, 0u);
        seg->set_cable(k, false);
        // Not one cycle lost: every exchange has the full working counter, the first one included.
        for (int i = 0; i < 20; ++i)
            EXPECT_EQ(m.exchange_process_data().value_or(0), expected) << "cycle " << i;
        EXPECT_GT(k < kDrives ? link.broken_ : link.primary_only_, 0u);
        for (std::size_t i = 0; i < kDrives; ++i) {
            const auto st = m.read16(static_cast<std::uint16_t>(0x1001 + i), protocol::addr(Reg::AlStatus));
            ASSERT_TRUE(st.has_value()) << "slave " << i;
            EXPECT_EQ(*st & 0x1F, static_cast<std::uint16_t>(AlState::Op)) << "slave " << i;
        }
        seg->set_cable(k, true);
        const unsigned whole_before = link.whole_;
        for (int i = 0; i < 20; ++i)
            EXPECT_EQ(m.exchange_process_data().value_or(0), expected) << "after, cycle " << i;
        EXPECT_EQ(link.whole_, whole_before + 20);  // the ring is whole again
    }
}
