// Chained segments in one process: several segments cabled port 1 -> port 0 as separate vecat processes
// would be, each with its own notion of time, against one segment with all the slaves.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstring>

#include "coe/coe_application.hpp"
#include "device/device_description.hpp"
#include "esc/segment.hpp"
#include "master/master.hpp"
#include "net/link.hpp"
#include "protocol/frame.hpp"
#include "protocol/registers.hpp"

using namespace vecat;
using protocol::AlState;

namespace {

std::uint64_t steady_ns() {
    return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                          std::chrono::steady_clock::now().time_since_epoch())
                                          .count());
}

// The master's cable into the first segment. A frame goes out through each segment while it passes it
// on, and back through return_frame() of the segments before the one that closed the line. Segment i sees
// the time shifted by i * skew_ns (its own clock, and the transit time of a real link).
class ChainLink final : public net::Link {
  public:
    explicit ChainLink(std::vector<esc::Segment*> segs, std::uint64_t skew_ns = 0)
        : segs_(std::move(segs)), skew_ns_(skew_ns) {}
    bool send(ConstBytes frame) override {
        if (frame.size() > buf_.size()) return false;
        std::memcpy(buf_.data(), frame.data(), frame.size());
        len_ = frame.size();
        pending_ = false;
        std::size_t i = 0;
        for (; i < segs_.size(); ++i) {
            if (!segs_[i]->process_frame(Bytes(buf_.data(), buf_.size()), len_, now(i))) return true;
            if (!segs_[i]->frame_goes_downstream()) break;
        }
        if (i == segs_.size()) return true;  // passed on out of the last segment: nobody there
        while (i-- > 0)
            if (!segs_[i]->return_frame(Bytes(buf_.data(), buf_.size()), len_, now(i))) return true;
        pending_ = true;
        return true;
    }
    long receive(Bytes out, std::int64_t) override {
        if (!pending_) return 0;
        pending_ = false;
        const std::size_t n = std::min(len_, out.size());
        std::memcpy(out.data(), buf_.data(), n);
        return static_cast<long>(n);
    }

  private:
    std::uint64_t now(std::size_t i) const { return steady_ns() + i * skew_ns_; }
    std::vector<esc::Segment*> segs_;
    std::uint64_t skew_ns_;
    std::array<std::uint8_t, 1600> buf_{};
    std::size_t len_ = 0;
    bool pending_ = false;
};

master::MasterOptions dc_options() {
    master::MasterOptions o;
    o.dc.enable = true;
    o.dc.sync0_cycle_ns = 0;  // delays, offsets and drift compensation only
    o.dc.static_drift_frames = 100;
    return o;
}

struct LineResult {
    int count = 0;
    std::vector<master::SlaveInfo> slaves;
    std::uint16_t expected_wkc = 0;
    std::vector<std::uint16_t> wkcs;
};

LineResult bring_up(net::Link& link) {
    LineResult r;
    master::Master m(link, dc_options());
    r.count = m.count_slaves();
    std::string why;
    EXPECT_TRUE(m.startup(AlState::Op, &why)) << why;
    r.slaves = m.slaves();
    r.expected_wkc = m.expected_wkc();
    for (int i = 0; i < 20; ++i)
        r.wkcs.push_back(m.exchange_process_data().value_or(0));
    return r;
}

std::unique_ptr<esc::Segment> segment(std::size_t n) {
    return coe::make_coe_segment(device::default_drive(), n, {});
}

}  // namespace

TEST(ChainedSegments, ThreeSegmentsFormTheSameLineAsOne) {
    auto one = segment(5);
    ChainLink single({one.get()});
    const LineResult ref = bring_up(single);

    auto a = segment(2), b = segment(1), c = segment(2);
    a->set_downstream_link(true);
    b->set_downstream_link(true);
    // Each segment runs on another clock and sees the frame tens of microseconds after the previous one.
    ChainLink chain({a.get(), b.get(), c.get()}, 37'000);
    const LineResult r = bring_up(chain);

    EXPECT_EQ(ref.count, 5);
    EXPECT_EQ(r.count, ref.count);
    ASSERT_EQ(r.slaves.size(), ref.slaves.size());
    for (std::size_t i = 0; i < r.slaves.size(); ++i) {
        const auto &s = r.slaves[i], &x = ref.slaves[i];
        EXPECT_EQ(s.position, x.position) << i;
        EXPECT_EQ(s.station, x.station) << i;
        EXPECT_EQ(s.sii.identity.vendor_id, x.sii.identity.vendor_id) << i;
        EXPECT_EQ(s.sii.identity.product_code, x.sii.identity.product_code) << i;
        EXPECT_EQ(s.dl_status, x.dl_status) << i;  // port 1 open on all but the last
        EXPECT_EQ(s.dc_delay_ns, x.dc_delay_ns) << i;
        EXPECT_EQ(s.dc_delay_ns, 500u * i) << i;  // the cable between two segments is a hop like any other
    }
    EXPECT_EQ(r.expected_wkc, ref.expected_wkc);
    EXPECT_EQ(r.wkcs, ref.wkcs);
    for (auto w : r.wkcs)
        EXPECT_EQ(w, r.expected_wkc);
    // The slaves of each segment are where the line puts them.
    EXPECT_EQ(a->slave(1).esc().station_address(), r.slaves[1].station);
    EXPECT_EQ(b->slave(0).esc().station_address(), r.slaves[2].station);
    EXPECT_EQ(c->slave(1).esc().station_address(), r.slaves[4].station);
    // Frames went on from A and B and came back; C closed the line.
    EXPECT_GT(a->counters().onward, 0u);
    EXPECT_EQ(a->counters().onward, a->counters().returned);
    EXPECT_EQ(a->counters().replies, 0u);
    EXPECT_EQ(b->counters().onward, b->counters().returned);
    EXPECT_EQ(c->counters().onward, 0u);
    EXPECT_EQ(c->counters().replies, a->counters().frames);
}

TEST(ChainedSegments, WithoutDownstreamLinkTheLineClosesAtTheLastSlave) {
    auto a = segment(2), b = segment(1);
    ChainLink chain({a.get(), b.get()});
    master::Master m(chain);
    EXPECT_EQ(m.count_slaves(), 2);
    EXPECT_EQ(a->slave(1).esc().port_link(1), false);
    // Cable plugged in: the line now reaches b.
    a->set_downstream_link(true);
    EXPECT_EQ(a->slave(1).esc().port_link(1), true);
    EXPECT_EQ(m.count_slaves(), 3);
    a->set_downstream_link(false);
    EXPECT_EQ(m.count_slaves(), 2);
}

TEST(ChainedSegments, ReturnLatchesPort1FromTheSlavesBehind) {
    // Driven by hand: a BWR 0x0900 goes out through a (2 slaves) with 3 slaves behind it.
    auto a = segment(2);
    a->set_downstream_link(true);
    std::array<std::uint8_t, 128> f{};
    std::memset(f.data(), 0xFF, 6);
    f[12] = 0x88;
    f[13] = 0xA4;
    const std::size_t dlen = 4;
    st_le16(f.data() + 14,
            static_cast<std::uint16_t>((protocol::kDatagramHeaderSize + dlen + protocol::kWkcSize) | 0x1000));
    std::uint8_t* d = f.data() + 16;
    d[0] = static_cast<std::uint8_t>(protocol::Command::BWR);
    d[1] = 0x42;
    st_le16(d + 4, protocol::addr(protocol::Reg::DcRecvTimePort0));
    st_le16(d + 6, dlen);
    std::size_t len = 16 + protocol::kDatagramHeaderSize + dlen + protocol::kWkcSize;
    const std::uint64_t t0 = 5'000'000'000;
    ASSERT_TRUE(a->process_frame(Bytes(f.data(), f.size()), len, t0));
    ASSERT_TRUE(a->frame_goes_downstream());
    protocol::DatagramView v(d);
    EXPECT_EQ(v.wkc(), 2);
    v.set_wkc(5);  // three more slaves downstream
    ASSERT_TRUE(a->return_frame(Bytes(f.data(), f.size()), len, t0 + 80'000));
    auto port_time = [&](std::size_t k, unsigned p) {
        return a->slave(k).esc().peek32(
            static_cast<std::uint16_t>(protocol::addr(protocol::Reg::DcRecvTimePort0) + 4 * p));
    };
    // Slave 0: 4 slaves behind it, 8 hops out and back; slave 1: 3 behind, 6 hops.
    EXPECT_EQ(port_time(0, 1) - port_time(0, 0), 8u * 500u);
    EXPECT_EQ(port_time(1, 1) - port_time(1, 0), 6u * 500u);
    // A frame of another index does not touch the latched times.
    d[1] = 0x43;
    v.set_wkc(9);
    ASSERT_TRUE(a->return_frame(Bytes(f.data(), f.size()), len, t0 + 90'000));
    EXPECT_EQ(port_time(0, 1) - port_time(0, 0), 8u * 500u);
}
