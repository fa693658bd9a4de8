// The project master's cyclic frames: a cycle whose process data needs several frames sends them back to
// back before it waits for the first reply (as SOEM's ecx_send_processdata and IgH's ecrt_master_send do),
// and matches each reply to its frame by the datagrams' indexes, whatever order the replies come in.
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "master/master.hpp"
#include "test_support.hpp"

using namespace vecat;

namespace {

// The link between the master and an in-process segment, with a log of what the master did: S for a frame
// sent, R for a reply received. The replies of the frames sent since the last receive can be handed out
// last first, and a frame can be lost on the wire.
class LoggingLink final : public net::Link {
  public:
    explicit LoggingLink(esc::Segment& seg) : inner_(seg) { inner_.set_time(1'000'000'000); }
    bool send(ConstBytes frame) override {
        log += 'S';
        ++sent_;
        if (sent_ == lose_) return true;  // lost on the wire
        return inner_.send(frame);
    }
    long receive(Bytes out, std::int64_t timeout_us) override {
        if (stall_next_receive) {
            // The master's thread kept from running for longer than its whole timeout, the replies arriving
            // meanwhile: this look finds nothing, and the time is up when it returns.
            stall_next_receive = false;
            std::this_thread::sleep_for(std::chrono::microseconds(timeout_us) + std::chrono::milliseconds(1));
            return 0;
        }
        if (reverse && held_.empty()) {
            std::array<std::uint8_t, 1600> b{};
            while (const long n = inner_.receive(Bytes(b.data(), b.size()), 0))
                held_.emplace_back(b.begin(), b.begin() + n);
        }
        long n = 0;
        if (reverse && !held_.empty()) {
            n = static_cast<long>(held_.back().size());
            std::copy(held_.back().begin(), held_.back().end(), out.begin());
            held_.pop_back();
        } else if (!reverse) {
            n = inner_.receive(out, timeout_us);
        }
        if (n > 0) log += 'R';
        return n;
    }
    std::string log;
    bool reverse = false;
    bool stall_next_receive = false;
    // Loses the n-th frame sent from now on (1: the next one; 0: none).
    void lose_frame(unsigned n) {
        sent_ = 0;
        lose_ = n;
    }

  private:
    net::InProcessLink inner_;
    std::vector<std::vector<std::uint8_t>> held_;
    unsigned sent_ = 0, lose_ = 0;
};

struct MasterCyclicFrames : ::testing::Test {
    // Enough slaves that the process image needs more than one frame.
    std::unique_ptr<esc::Segment> seg = coe::make_coe_segment(device::default_drive(), 80, {});
    LoggingLink link{*seg};
    master::Master m{link};
    void SetUp() override {
        std::string why;
        ASSERT_TRUE(m.startup(protocol::AlState::Op, &why)) << why;
        ASSERT_GE(m.process_data_frames(), 2u);
        m.options().retries = 0;
        m.options().reply_timeout_us = 2'000;
        link.log.clear();
    }
};

}  // namespace

TEST_F(MasterCyclicFrames, ACyclesFramesGoOutBeforeTheFirstReplyIsAwaited) {
    ASSERT_EQ(m.exchange_process_data(), m.expected_wkc());
    const std::size_t n = m.process_data_frames();
    EXPECT_EQ(link.log, std::string(n, 'S') + std::string(n, 'R'));
}

TEST_F(MasterCyclicFrames, RepliesAreMatchedToTheirFramesInAnyOrder) {
    ASSERT_EQ(m.exchange_process_data(), m.expected_wkc());
    std::vector<std::vector<std::uint8_t>> in_order;
    for (std::size_t i = 0; i < m.slaves().size(); ++i)
        in_order.emplace_back(m.inputs(i).begin(), m.inputs(i).end());
    // Clear the inputs in the master's image, so that only the replies can bring them back.
    for (std::size_t i = 0; i < m.slaves().size(); ++i) {
        auto in = m.inputs(i);
        std::fill(const_cast<std::uint8_t*>(in.data()), const_cast<std::uint8_t*>(in.data()) + in.size(), 0);
    }
    link.reverse = true;
    ASSERT_EQ(m.exchange_process_data(), m.expected_wkc());
    for (std::size_t i = 0; i < m.slaves().size(); ++i)
        EXPECT_EQ(std::vector<std::uint8_t>(m.inputs(i).begin(), m.inputs(i).end()), in_order[i]) << i;
}

TEST_F(MasterCyclicFrames, ALostFrameFailsTheCycleAndLeavesTheNextOneWhole) {
    link.lose_frame(2);
    EXPECT_FALSE(m.exchange_process_data().has_value());
    link.lose_frame(0);
    EXPECT_EQ(m.exchange_process_data(), m.expected_wkc());
}

// Replies that came in time are taken even when the master's thread first looks after its deadline (a
// scheduler that kept it from running): the cycle is whole, and no frame goes out again.
TEST_F(MasterCyclicFrames, RepliesThereAtTheDeadlineAreTakenNotSentAgain) {
    m.options().retries = 1;
    link.stall_next_receive = true;
    EXPECT_EQ(m.exchange_process_data(), m.expected_wkc());
    const std::size_t n = m.process_data_frames();
    EXPECT_EQ(link.log, std::string(n, 'S') + std::string(n, 'R'));
}
