// Cable redundancy end to end: `vecat run --iface A --redundant-iface B` in a private network namespace,
// the project's master behind a link over two raw sockets that does what a redundant master does (the
// frame out of the primary port, a BRD dummy of the same index out of the secondary one; with the ring
// broken, the primary's result again out of the secondary port). A cable break inside the ring (control
// socket, link_down) and the master's second cable pulled out (the veth end goes down) cost no cycle; the
// ring closes again. An interface in use is refused.
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "faults/control.hpp"
#include "master/master.hpp"
#include "net/netns.hpp"
#include "net/raw_socket.hpp"
#include "protocol/registers.hpp"

using namespace vecat;
using protocol::AlState;

namespace {

bool g_netns = false;

// `vecat run ARGS`, stopped with SIGINT at the end of its scope.
std::vector<std::string> vecat_run(std::vector<std::string> args) {
    args.insert(args.begin(), {VECAT_BINARY, "run"});
    return args;
}
constexpr std::chrono::seconds kRefusalWait{10};

// The dummy's source address: the frames are told apart by it, as a redundant master does.
constexpr std::array<std::uint8_t, 5> kDummySource = {0x04, 0x04, 0x04, 0x04, 0x04};

class RedundantRawLink final : public net::Link {
  public:
    RedundantRawLink(const std::string& a, const std::string& b) : prim_(a), sec_(b) {}
    bool send(ConstBytes frame) override {
        if (frame.size() > out_.size() || frame.size() < 18) return false;
        std::memcpy(out_.data(), frame.data(), frame.size());
        out_len_ = frame.size();
        std::array<std::uint8_t, 60> d{};
        std::memset(d.data(), 0xFF, 6);
        d[6] = 0x04;
        std::memcpy(d.data() + 7, kDummySource.data(), kDummySource.size());
        d[12] = 0x88, d[13] = 0xA4;
        st_le16(d.data() + 14, 0x1000 | 14);
        d[16] = static_cast<std::uint8_t>(protocol::Command::BRD);
        d[17] = frame[17];  // the index of the frame's first datagram
        st_le16(d.data() + 22, 2);
        return prim_.send(frame) && (sec_.send(ConstBytes(d.data(), d.size())) || true);
    }
    long receive(Bytes out, std::int64_t timeout_us) override {
        // Both frames, or whatever came until the timeout: each one where it arrived, and which it is.
        long at_a = 0, at_b = 0;
        bool a_is_dummy = false, b_is_dummy = false;
        const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(timeout_us);
        // Waiting in poll(), not spinning: on a veth pair the frames a process sends are delivered by the
        // kernel's softirq on its CPU, which a process spinning on recv() can hold off until it gives up
        // (seen with SOEM's redundant resend loop, see the report of this change).
        while ((at_a <= 0 || at_b <= 0) && std::chrono::steady_clock::now() < until) {
            wait_for(at_a <= 0, at_b <= 0, until);
            if (at_a <= 0)
                if ((at_a = prim_.try_receive(Bytes(rx_a_.data(), rx_a_.size()))) > 0)
                    a_is_dummy = dummy(rx_a_);
            if (at_b <= 0)
                if ((at_b = sec_.try_receive(Bytes(rx_b_.data(), rx_b_.size()))) > 0)
                    b_is_dummy = dummy(rx_b_);
        }
        if (at_b > 0 && !b_is_dummy && (at_a <= 0 || a_is_dummy)) {
            ++whole_;  // the primary frame went round the ring
            return give(rx_b_.data(), at_b, out);
        }
        if (at_b > 0 && b_is_dummy) {
            // Broken ring: the slaves behind the break get the primary's result (or the frame as sent).
            ++broken_;
            const std::uint8_t* f = at_a > 0 && !a_is_dummy ? rx_a_.data() : out_.data();
            const std::size_t n = at_a > 0 && !a_is_dummy ? static_cast<std::size_t>(at_a) : out_len_;
            std::memcpy(out_.data(), f, n);
            if (!sec_.send(ConstBytes(out_.data(), n))) return 0;
            const auto t2 = std::chrono::steady_clock::now() + std::chrono::microseconds(timeout_us);
            while (std::chrono::steady_clock::now() < t2) {
                wait_for(false, true, t2);
                if (const long r = sec_.try_receive(Bytes(rx_b_.data(), rx_b_.size())); r > 0)
                    return give(rx_b_.data(), r, out);
            }
            return 0;
        }
        if (at_a > 0 && !a_is_dummy) {
            ++primary_only_;
            return give(rx_a_.data(), at_a, out);
        }
        return 0;
    }
    unsigned whole_ = 0, broken_ = 0, primary_only_ = 0;

  private:
    void wait_for(bool a, bool b, std::chrono::steady_clock::time_point until) {
        pollfd p[2];
        nfds_t n = 0;
        if (a) p[n++] = {prim_.fd(), POLLIN, 0};
        if (b) p[n++] = {sec_.fd(), POLLIN, 0};
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(until - std::chrono::steady_clock::now());
        ::poll(p, n, static_cast<int>(std::max<std::int64_t>(left.count(), 0) + 1));
    }
    static bool dummy(const std::array<std::uint8_t, 1600>& f) {
        return std::memcmp(f.data() + 7, kDummySource.data(), kDummySource.size()) == 0;
    }
    static long give(const std::uint8_t* f, long n, Bytes out) {
        const std::size_t k = std::min(static_cast<std::size_t>(n), out.size());
        std::memcpy(out.data(), f, k);
        return static_cast<long>(k);
    }
    net::RawSocket prim_, sec_;
    std::array<std::uint8_t, 1600> out_{}, rx_a_{}, rx_b_{};
    std::size_t out_len_ = 0;
};

std::string control(const std::string& sock, const std::string& cmd) {
    std::string reply;
    if (!faults::send_control_command(sock, cmd, reply)) return "unreachable";
    return reply;
}

}  // namespace

TEST(RedundancyVeth, RingSurvivesABreakAndClosesAgain) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    std::string why;
    for (auto [x, y] : {std::pair{"rdm", "rds"}, std::pair{"rdm2", "rds2"}})
        ASSERT_TRUE(net::create_veth_pair(x, y, &why)) << why;
    const std::string sock = "/tmp/vecat-redundancy-" + std::to_string(getpid()) + ".sock";
    test::ChildProcess v(
        vecat_run({"--iface", "rds", "--redundant-iface", "rds2", "--slaves", "4", "--control", sock}));
    ASSERT_GT(v.pid, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(400));

    RedundantRawLink link("rdm", "rdm2");
    master::MasterOptions o;
    o.reply_timeout_us = 20'000;
    master::Master m(link, o);
    ASSERT_EQ(m.count_slaves(), 4);
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    const std::uint16_t expected = m.expected_wkc();
    const auto cycles = [&](int n) {
        int good = 0;
        for (int i = 0; i < n; ++i)
            good += m.exchange_process_data().value_or(0) == expected;
        return good;
    };
    const auto all_in_op = [&] {
        for (std::uint16_t st = 0x1001; st <= 0x1004; ++st) {
            const auto al = m.read16(st, protocol::addr(protocol::Reg::AlStatus));
            if (!al || (*al & 0x1F) != static_cast<std::uint16_t>(AlState::Op)) return false;
        }
        return true;
    };
    EXPECT_EQ(cycles(100), 100);
    EXPECT_GT(link.whole_, 0u);
    EXPECT_EQ(link.broken_, 0u);

    // The cable between slave 1 and slave 2 breaks.
    EXPECT_EQ(control(sock, "inject link_down slave=1 port=1 id=cut").rfind("ok", 0), 0u);
    const unsigned broken_before = link.broken_;
    EXPECT_EQ(cycles(200), 200);
    EXPECT_GE(link.broken_, broken_before + 200);
    EXPECT_TRUE(all_in_op());
    // Auto loop control closed the ports at the break; the lost link counters counted.
    EXPECT_EQ(m.read16(0x1002, protocol::addr(protocol::Reg::LostLinkCounter)).value_or(0) >> 8, 1);
    EXPECT_EQ(m.read16(0x1003, protocol::addr(protocol::Reg::LostLinkCounter)).value_or(0) & 0xFF, 1);

    // The cable is back: the ring is whole again.
    EXPECT_EQ(control(sock, "clear cut").rfind("ok", 0), 0u);
    const unsigned whole_before = link.whole_;
    EXPECT_EQ(cycles(200), 200);
    EXPECT_GE(link.whole_, whole_before + 200);
    EXPECT_TRUE(all_in_op());

    // The master's second cable pulled out: an open line from the primary port.
    ASSERT_EQ(system("ip link set rdm2 down"), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // vecat looks at the carrier every 10 ms
    EXPECT_EQ(cycles(20), 20);
    EXPECT_GT(link.primary_only_, 0u);
    ASSERT_EQ(system("ip link set rdm2 up"), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const unsigned whole_again = link.whole_;
    EXPECT_EQ(cycles(50), 50);
    EXPECT_GE(link.whole_, whole_again + 50);
    EXPECT_TRUE(m.request_state(AlState::Init));
    EXPECT_EQ(v.stop(), 0);
}

TEST(RedundancyVeth, AnInterfaceInUseIsRefused) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    std::string why;
    ASSERT_TRUE(net::create_veth_pair("rum", "rus", &why)) << why;
    ASSERT_TRUE(net::create_veth_pair("rum2", "rus2", &why)) << why;
    EXPECT_EQ(test::ChildProcess(vecat_run({"--iface", "rus", "--redundant-iface", "rus", "--slaves", "2"}))
                  .wait_for(kRefusalWait),
              2);
    EXPECT_EQ(test::ChildProcess(vecat_run({"--iface", "rus", "--redundant-iface", "rus2", "--downstream",
                                            "rum2", "--slaves", "2"}))
                  .wait_for(kRefusalWait),
              2);
}

int main(int argc, char** argv) {
    std::string why;
    g_netns = net::enter_private_netns(&why);
    if (!g_netns) std::fprintf(stderr, "veth tests skipped: %s\n", why.c_str());
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
