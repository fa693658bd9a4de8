// The master side of cable redundancy for the tests: the project's master behind a link over two raw
// sockets that does what a redundant master (SOEM's ecx_init_redundant) does. Each frame goes out of the
// primary port, and a BRD dummy of the same index out of the secondary one; the frame that went round the
// ring whole arrives at the secondary port. With the ring broken, the primary's result is sent again out of
// the secondary port, so that the slaves behind the break process it too. Counts which way each frame took.
#pragma once

#include <poll.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <string>

#include "common/bytes.hpp"
#include "net/link.hpp"
#include "net/raw_socket.hpp"
#include "protocol/frame.hpp"

namespace vecat::test {

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

}  // namespace vecat::test
