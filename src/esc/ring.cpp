// Cable redundancy: the line cabled back to the master's second port (a ring), and the way a frame takes
// through the ESCs' ports there. Kept apart from segment.cpp, whose depth-first route serves the open line
// and the tree (and chained segments), where a frame always comes back the way it went.
#include <algorithm>
#include <cstring>

#include "esc/segment.hpp"
#include "protocol/frame.hpp"
#include "protocol/registers.hpp"

namespace vecat::esc {

using protocol::FrameError;
using protocol::kMinEthFrame;
using protocol::ParsedFrame;

namespace {
// The port a frame goes on to after port p: 0 -> 3 -> 1 -> 2 -> 0 (ESC datasheet section I, frame
// processing). Only the way from port 0 to port 3 passes the processing unit.
constexpr unsigned next_port(unsigned p) {
    return p == 0 ? 3 : p == 3 ? 1 : p == 1 ? 2 : 0;
}
constexpr std::size_t kNobody = ~std::size_t{0};
}  // namespace

std::size_t Segment::cable_at(std::size_t slave, unsigned port) const {
    if (slave >= slaves_.size() || port > 3) return kNoCable;
    if (port == 0) return slave;
    if (const int c = child_[slave][port]; c >= 0) return static_cast<std::size_t>(c);
    if (slave == red_slave_ && port == red_port_) return slaves_.size();
    return kNoCable;
}

bool Segment::set_redundancy(std::size_t slave, unsigned port, std::string* why) {
    const auto fail = [&](const std::string& w) {
        if (why) *why = w;
        return false;
    };
    if (downstream_) return fail("a line chained to another segment has no redundancy cable");
    if (slave >= slaves_.size()) return fail("there is no slave " + std::to_string(slave));
    if (port < 1 || port > 3) return fail("the redundancy cable goes to port 1, 2 or 3");
    if (((slaves_[slave]->esc().config().port_descriptor >> (2 * port)) & 0x3) == 0)
        return fail("slave " + std::to_string(slave) + " has no port " + std::to_string(port));
    if (const int c = child_[slave][port]; c >= 0)
        return fail("port " + std::to_string(port) + " of slave " + std::to_string(slave) +
                    " is cabled to slave " + std::to_string(c) + " already");
    const std::size_t old = red_slave_;
    red_slave_ = slave;
    red_port_ = port;
    red_cable_up_ = true;
    ++port_epoch_;
    if (old < slaves_.size() && old != slave) update_links(old);
    update_links(slave);
    return true;
}

void Segment::set_secondary_link(bool up) {
    if (secondary_link_ == up) return;
    secondary_link_ = up;
    ++port_epoch_;
    if (redundant()) update_links(red_slave_);
}

Segment::WalkEnd Segment::walk(MasterPort from, const FrameDamage& damage) const {
    const std::size_t n = slaves_.size();
    ring_order_.clear();
    for (std::size_t k = 0; k < n; ++k) {
        ring_timing_[k] = FrameTiming{0, 0, 0, 0, 0};
        ring_seen_[k] = 0;
    }
    ring_damaged_receiver_ = kNobody;
    const bool damaged = damage.kind != FrameDamage::Kind::None;
    std::size_t s = 0;
    unsigned p = 0;
    const std::size_t entry = from == MasterPort::Primary ? 0 : n;
    if (from == MasterPort::Primary) {
        if (n == 0 || !cable(0)) return WalkEnd::Lost;
    } else {
        if (!redundant() || !red_cable_up_ || !secondary_link_) return WalkEnd::Lost;
        s = red_slave_;
        p = red_port_;
    }
    if (damaged && damage.cable == entry && !damage.returning) {
        ring_damaged_receiver_ = s;
        ring_damaged_port_ = p;
        return WalkEnd::Damaged;
    }
    std::uint64_t t = 0;
    const auto process = [&](std::size_t k) {
        if (ring_seen_[k]) return;  // once per frame, even on a way that loops
        ring_seen_[k] = 1;
        ring_order_.push_back(k);
    };
    // Each step crosses one cable; a frame still going after every cable twice circles for ever.
    for (std::size_t steps = 0; steps < 2 * (n + 1); ++steps) {
        // The frame arrives at port p of slave s from its cable.
        const Esc& e = slaves_[s]->esc();
        if (!e.port_open(p)) return WalkEnd::Lost;  // a closed port takes no frames from outside
        FrameTiming& ft = ring_timing_[s];
        if (p == 0) {
            ft.port0_ns = t;
            process(s);
        } else {
            (p == 1 ? ft.port1_ns : p == 2 ? ft.port2_ns : ft.port3_ns) = t;
            ft.returned_ports = static_cast<std::uint8_t>(ft.returned_ports | (1u << p));
        }
        // On to the next open port; a closed port 0 loops the frame into the processing unit.
        unsigned q = next_port(p);
        for (; !e.port_open(q); q = next_port(q))
            if (q == 0) process(s);
        const std::size_t c = cable_at(s, q);
        if (c == kNoCable || !cable(c) || (c == n && !secondary_link_))
            return WalkEnd::Lost;  // open without a device behind it
        const bool towards_master = q == 0;
        std::size_t to = kNobody;
        unsigned to_port = 0;
        if (q == 0 && parent_[s] >= 0) {
            to = static_cast<std::size_t>(parent_[s]);
            to_port = parent_port_[s];
        } else if (q != 0 && c < n) {
            to = c;
        }
        if (damaged && damage.cable == c && damage.returning == towards_master) {
            ring_damaged_receiver_ = to;
            ring_damaged_port_ = to_port;
            return WalkEnd::Damaged;
        }
        t += cable_delay(c);
        if (to == kNobody) return q == 0 ? WalkEnd::Primary : WalkEnd::Secondary;
        s = to;
        p = to_port;
    }
    return WalkEnd::Lost;
}

bool Segment::process_ring(Bytes frame, std::size_t& len, std::uint64_t now_ns, const FrameDamage& damage,
                           MasterPort from, const ParsedFrame& pf) {
    const WalkEnd end = walk(from, damage);
    if (pf.error == FrameError::NotCommands) {
        // Other EtherCAT frame types pass the ESCs unprocessed.
    } else if (pf.error != FrameError::None) {
        ++counters_.dropped;
        const std::size_t first = from == MasterPort::Primary ? 0 : red_slave_;
        if (cable(from == MasterPort::Primary ? 0 : slaves_.size()))
            slaves_[first]->esc().count_invalid_frame(from == MasterPort::Primary ? 0 : red_port_);
        return false;
    } else {
        // SYNC pulses and deadlines due before this frame arrived happen first, and the slaves' own
        // cycles catch up (see set_local_cycle_ns).
        catch_up(now_ns);
        for (const std::size_t k : ring_order_) {
            const FrameTiming& rel = ring_timing_[k];
            const FrameTiming t{now_ns + rel.port0_ns, now_ns + rel.port1_ns, now_ns + rel.port2_ns,
                                now_ns + rel.port3_ns, rel.returned_ports};
            Esc& esc = slaves_[k]->esc();
            for (std::size_t i = 0; i < pf.count; ++i)
                esc.process(pf.datagram(frame, i), t);
            if (esc.take_firmware_work()) mark_for_run(k);  // its firmware runs below
        }
        if (defer_firmware_) {
            defer_frame_firmware(now_ns);
        } else {
            run_due_firmware(now_ns);
        }
    }
    if (end == WalkEnd::Damaged && damage.kind == FrameDamage::Kind::Corrupted &&
        ring_damaged_receiver_ != kNobody)
        slaves_[ring_damaged_receiver_]->esc().count_invalid_frame(ring_damaged_port_);
    if (end == WalkEnd::Damaged || end == WalkEnd::Lost) {
        ++counters_.lost;
        return false;
    }
    if (!ring_order_.empty()) frame[6] |= 0x02;  // processed: marked in the source address
    if (len < kMinEthFrame && frame.size() >= kMinEthFrame) {
        std::memset(frame.data() + len, 0, kMinEthFrame - len);
        len = kMinEthFrame;
    }
    reply_port_ = end == WalkEnd::Primary ? MasterPort::Primary : MasterPort::Secondary;
    ++counters_.replies;
    return true;
}

}  // namespace vecat::esc
