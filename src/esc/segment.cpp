// The line's frame path: the frame's way through the ports and its timing, which slaves' firmware a frame
// needs. The datagrams' way to the ESCs they concern is in segment_datagrams.cpp, the firmware runs in
// segment_firmware.cpp, the ring's path in ring.cpp, hot connect in hot_connect.cpp.
#include "esc/segment.hpp"

#include <algorithm>
#include <cstring>

#include "protocol/frame.hpp"
#include "protocol/registers.hpp"
#include "protocol/topology.hpp"

namespace vecat::esc {

using protocol::addr;
using protocol::Command;
using protocol::DatagramView;
using protocol::FrameError;
using protocol::kEthHeaderSize;
using protocol::kMinEthFrame;
using protocol::parse_frame;
using protocol::ParsedFrame;
using protocol::Reg;

void Segment::add(std::unique_ptr<Slave> s) {
    add(std::move(s), {});
}

void Segment::add(std::unique_ptr<Slave> s, ApplicationFactory own) {
    finish_background_firmware();
    const std::size_t i = slaves_.size();
    slaves_.push_back(std::move(s));
    ++slaves_epoch_;
    own_factory_.push_back(std::move(own));
    cable_up_.push_back(1);
    halted_.push_back(0);
    last_run_ns_.push_back(0);
    deadline_ns_.push_back(0);
    pulse_ns_.push_back(0);
    cycle_ns_.push_back(0);
    picked_.push_back(0);
    run_at_ns_.push_back(0);
    picked_list_.reserve(slaves_.size());
    background_list_.reserve(slaves_.size());
    marked_.reserve(slaves_.size());
    marks_valid_ = false;
    earliest_deadline_ns_ = 0;
    latched_.push_back(0);
    // A line: port 0 of the new slave to port 1 of the one before.
    parent_.push_back(static_cast<int>(i) - 1);
    parent_port_.push_back(i ? 1 : 0);
    delay_.push_back(0);
    child_.push_back({-1, -1, -1, -1});
    if (i) child_[i - 1][1] = static_cast<int>(i);
    reached_.push_back(0);
    timing_.push_back({});
    stack_.reserve(slaves_.size());
    ring_order_.reserve(2 * slaves_.size());
    ring_timing_.push_back({});
    ring_seen_.push_back(0);
    slaves_.back()->esc().set_port_change_counter(&port_epoch_);
    slaves_.back()->esc().set_address_change_counter(&address_epoch_);
    ++port_epoch_;
    for (std::size_t k = 0; k < slaves_.size(); ++k)
        update_links(k);
}

bool Segment::set_topology(const std::vector<int>& parents, const std::vector<std::uint8_t>& ports,
                           const std::vector<std::uint32_t>& delays_ns, std::string* why) {
    const std::size_t n = slaves_.size();
    const auto fail = [&](const std::string& w) {
        if (why) *why = w;
        return false;
    };
    if (parents.size() != n || ports.size() != n || delays_ns.size() != n) return fail("one entry per slave");
    std::vector<std::array<int, 4>> child(n, {-1, -1, -1, -1});
    for (std::size_t k = 0; k < n; ++k) {
        const int p = parents[k];
        if ((k == 0) != (p < 0)) return fail("slave 0, and only it, is cabled to the master");
        if (p < 0) continue;
        if (static_cast<std::size_t>(p) >= k || ports[k] < 1 || ports[k] > 3)
            return fail("slave " + std::to_string(k) + ": bad parent or port");
        int& slot = child[static_cast<std::size_t>(p)][ports[k]];
        if (slot >= 0) return fail("slave " + std::to_string(k) + ": port cabled twice");
        slot = static_cast<int>(k);
    }
    // The order the frame reaches them must be the slaves' own.
    const std::vector<std::size_t> order = protocol::frame_order(child);
    for (std::size_t k = 0; k < order.size(); ++k)
        if (order[k] != k) return fail("the slaves are not in the order the frame reaches them");
    if (redundant() && child[red_slave_][red_port_] >= 0) return fail("the redundancy port is cabled twice");
    parent_ = parents;
    parent_port_.assign(ports.begin(), ports.end());
    if (n) parent_port_[0] = 0;  // the master's side
    delay_ = delays_ns;
    child_ = std::move(child);
    ++port_epoch_;
    for (std::size_t k = 0; k < n; ++k)
        update_links(k);
    return true;
}

void Segment::update_links(std::size_t i) {
    Esc& e = slaves_[i]->esc();
    e.set_port_link(0, cable(i));
    for (unsigned p = 1; p < 4; ++p) {
        const int c = child_[i][p];
        // The last slave's free port 1 leads to the next segment (chained segments), if anywhere.
        const bool up = c >= 0 ? cable(static_cast<std::size_t>(c))
                        : (i == red_slave_ && p == red_port_)
                            ? red_cable_up_ && secondary_link_
                            : (p == 1 && i + 1 == slaves_.size() && downstream_);
        if (up || e.port_link(p)) e.set_port_link(p, up);
    }
}

void Segment::refresh_route() const {
    if (routed_epoch_ == port_epoch_ && routed_hop_ns_ == hop_delay_ns) return;
    routed_epoch_ = port_epoch_;
    routed_hop_ns_ = hop_delay_ns;
    reached_count_ = 0;
    if (redundant()) {
        // Reached from either master port.
        std::fill(reached_.begin(), reached_.end(), std::uint8_t{0});
        for (const MasterPort from : {MasterPort::Primary, MasterPort::Secondary}) {
            walk(from, FrameDamage{});
            for (const std::size_t k : ring_order_)
                reached_[k] = 1;
        }
        reached_count_ = static_cast<std::size_t>(std::count(reached_.begin(), reached_.end(), 1));
        return;
    }
    for (std::size_t k = 0; k < slaves_.size(); ++k) {
        const int p = parent_[k];
        const bool r =
            cable(k) && (p < 0 || (reached_[static_cast<std::size_t>(p)] &&
                                   slaves_[static_cast<std::size_t>(p)]->esc().port_open(parent_port_[k])));
        reached_[k] = r ? 1 : 0;
        reached_count_ += r;
    }
    route();
}

void Segment::route() const {
    passed_ = slaves_.size();
    stack_.clear();
    if (slaves_.empty() || !reached_[0]) return;
    timing_[0] = FrameTiming{};
    stack_.push_back({0, 0, 0});
    std::size_t visited = 1;  // slaves the frame has passed (depth first: positions 0..visited-1)
    while (!stack_.empty()) {
        Visit& v = stack_.back();
        if (v.next < 3) {
            const unsigned p = protocol::kPortsAfterPort0[v.next++];
            if (!slaves_[v.slave]->esc().port_open(p)) continue;  // the port loops the frame back at once
            const int c = child_[v.slave][p];
            if (c < 0 || !reached_[static_cast<std::size_t>(c)]) {
                // Open without a device behind it (a port forced open without link): the frame is gone. A
                // free port 1 of the last slave leads to the next segment instead.
                if (!(p == 1 && v.slave + 1 == slaves_.size() && downstream_)) {
                    passed_ = visited;
                    return;
                }
                continue;
            }
            const auto k = static_cast<std::size_t>(c);
            const std::uint64_t at = v.t + cable_delay(k);
            timing_[k] = FrameTiming{at, 0, 0, 0};
            stack_.push_back({k, 0, at});  // capacity reserved in add(): v stays valid until here
            ++visited;
        } else {
            const std::size_t k = v.slave;
            const std::uint64_t out = v.t;
            stack_.pop_back();
            if (stack_.empty()) break;
            Visit& up = stack_.back();
            up.t = out + cable_delay(k);
            FrameTiming& t = timing_[up.slave];
            (parent_port_[k] == 1 ? t.port1_ns : parent_port_[k] == 2 ? t.port2_ns : t.port3_ns) = up.t;
        }
    }
}

void Segment::set_downstream_link(bool up) {
    downstream_ = up;
    ++port_epoch_;
    pending_latch_.valid = false;
    if (!slaves_.empty()) update_links(slaves_.size() - 1);
}

namespace {
// A write of 0x0900 (receive time port 0) makes every port latch the time the frame passes it.
bool latches_receive_times(DatagramView d) {
    return protocol::physical_write(d.command()) && d.ado() <= addr(Reg::DcRecvTimePort0) + 3u &&
           d.ado() + d.length() > addr(Reg::DcRecvTimePort0);
}
}  // namespace

bool Segment::return_frame(Bytes frame, std::size_t len, std::uint64_t /*now_ns*/) {
    if (len > frame.size()) len = frame.size();
    const ParsedFrame pf = parse_frame(ConstBytes(frame.data(), len));
    if (pf.error == FrameError::NotEtherCat || (pf.error == FrameError::TooShort && len < kEthHeaderSize)) {
        ++counters_.ignored;
        return false;
    }
    // On the way back an ESC forwards whatever comes (errors were counted on the way out).
    if (pf.error == FrameError::None) return_receive_times(pf, frame);
    ++counters_.returned;
    return true;
}

void Segment::return_receive_times(const ParsedFrame& pf, Bytes frame) {
    const PendingLatch p = pending_latch_;
    if (!p.valid || p.position >= pf.count) return;
    const DatagramView d = pf.datagram(frame, p.position);
    if (d.index() != p.index || !latches_receive_times(d) || d.wkc() < p.wkc_after) return;
    pending_latch_.valid = false;
    // Slaves behind this segment: what the latch added downstream (one per slave for a broadcast, the way
    // masters latch). The frame was back at port 1 of slave k after 2 (n - 1 + behind) - k hops from the
    // arrival at slave 0, as in one segment: only per-slave differences of these times matter to a master,
    // so the processes' different clocks and the real transit time between them do not.
    const std::size_t behind = static_cast<std::size_t>(d.wkc() - p.wkc_after);
    const std::size_t n = slaves_.size();
    for (std::size_t k = 0; k < n; ++k)
        if (latched_[k])
            slaves_[k]->esc().dc().latch_port1_receive_time(p.port0_ns +
                                                            (2 * (n - 1 + behind) - k) * hop_delay_ns);
}

void Segment::set_cable(std::size_t k, bool connected) {
    finish_background_firmware();
    if (redundant() && k == slaves_.size()) {
        red_cable_up_ = connected;
        ++port_epoch_;
        update_links(red_slave_);
        return;
    }
    if (k >= cable_up_.size()) return;
    cable_up_[k] = connected ? 1 : 0;
    ++port_epoch_;
    update_links(k);
    if (parent_[k] >= 0) update_links(static_cast<std::size_t>(parent_[k]));
}

std::size_t Segment::reachable() const {
    refresh_route();
    return reached_count_;
}

void Segment::set_firmware_halted(std::size_t i, bool halted) {
    finish_background_firmware();
    // (Unchanged: the slave keeps its schedule. The fault injector states every slave's halt whenever a
    // fault starts or ends.)
    if (i >= halted_.size() || halted_[i] == (halted ? 1 : 0)) return;
    halted_[i] = halted ? 1 : 0;
    deadline_ns_[i] = 0;
    earliest_deadline_ns_ = 0;
    pulse_ns_[i] = 0;
    cycle_ns_[i] = 0;
}

bool Segment::restart_slave(std::size_t i) {
    finish_background_firmware();
    if (i >= slaves_.size()) return false;
    const ApplicationFactory& factory = own_factory_[i] ? own_factory_[i] : factory_;
    if (!factory) return false;
    const Slave& old = *slaves_[i];
    EscConfig cfg = old.esc().config();
    cfg.dc_drift_ppm = old.esc().dc().drift_ppm();  // the same oscillator after the restart
    const DeviceModel model = old.model();
    auto fresh = std::make_unique<Slave>(model, cfg, factory(*model.description));
    slaves_[i] = std::move(fresh);
    deadline_ns_[i] = 0;
    earliest_deadline_ns_ = 0;
    pulse_ns_[i] = 0;
    cycle_ns_[i] = 0;
    ++slaves_epoch_;
    slaves_[i]->esc().set_port_change_counter(&port_epoch_);
    slaves_[i]->esc().set_address_change_counter(&address_epoch_);
    ++port_epoch_;
    update_links(i);
    return true;
}

bool Segment::process_frame(Bytes frame, std::size_t& len, std::uint64_t now_ns) {
    return process_frame(frame, len, now_ns, FrameDamage{});
}

bool Segment::process_frame(Bytes frame, std::size_t& len, std::uint64_t now_ns, const FrameDamage& damage) {
    return process_frame(frame, len, now_ns, damage, MasterPort::Primary);
}

bool Segment::process_frame(Bytes frame, std::size_t& len, std::uint64_t now_ns, const FrameDamage& damage,
                            MasterPort from) {
    // The firmware of the frames before, if the server has not run it yet and this frame may see it.
    if (deferred_count_ != 0 && !keep_deferred(now_ns, damage)) run_deferred_firmware();
    onward_ = false;
    if (len > frame.size()) len = frame.size();
    ConstBytes in(frame.data(), len);
    const ParsedFrame pf = parse_frame(in);
    if (pf.error == FrameError::NotEtherCat || (pf.error == FrameError::TooShort && len < kEthHeaderSize)) {
        ++counters_.ignored;
        return false;
    }
    ++counters_.frames;
    reply_port_ = MasterPort::Primary;
    if (redundant()) return process_ring(frame, len, now_ns, damage, from, pf);
    if (from != MasterPort::Primary) {
        ++counters_.lost;  // no cable at the master's secondary port
        return false;
    }
    // Slaves the frame reaches, and whether it crosses the damaged cable on its way.
    const std::size_t m = reachable();
    const bool hit =
        damage.kind != FrameDamage::Kind::None && damage.cable < slaves_.size() && reached_[damage.cable];
    if (m == 0) {
        ++counters_.lost;  // no link at the master's cable: the frame goes nowhere
        return false;
    }
    bool gone = false;  // left through an open port without a device behind it
    if (pf.error == FrameError::NotCommands) {
        // Other EtherCAT frame types pass the ESCs unprocessed.
    } else if (pf.error != FrameError::None) {
        ++counters_.dropped;
        slaves_.front()->esc().count_invalid_frame(0);
        return false;
    } else {
        // The frame's way through the ports: the slaves it passes, and when (same delay per cable both
        // ways; a closed port loops it back at once), so masters compute exact delays and topology.
        const std::size_t passed = passed_;  // reachable() above worked the route out
        gone = passed < slaves_.size();
        // An outbound frame damaged on the cable into slave c is processed by the slaves before c only.
        const std::size_t intact = std::min(hit && !damage.returning ? damage.cable : slaves_.size(), passed);
        // SYNC pulses that fell due before this frame arrived happen first, and the deadlines due; the
        // slaves the frame reads catch up with their own cycles as it reaches them (process_datagrams).
        catch_up_deadlines(now_ns);
        // A latch that goes on downstream: remembered until it returns (see return_frame()).
        const bool onward = downstream_ && m == slaves_.size() && !hit;
        std::size_t latch_pos = pf.count;
        if (onward) {
            for (std::size_t i = 0; i < pf.count && latch_pos == pf.count; ++i)
                if (latches_receive_times(pf.datagram(frame, i))) latch_pos = i;
            if (latch_pos < pf.count) std::fill(latched_.begin(), latched_.end(), std::uint8_t{0});
        }
        process_datagrams(frame, pf, intact, latch_pos, now_ns);
        if (latch_pos < pf.count) {
            const DatagramView d = pf.datagram(frame, latch_pos);
            pending_latch_ = PendingLatch{true, d.index(), latch_pos, d.wkc(), now_ns};
        }
        if (defer_firmware_)
            defer_frame_firmware(now_ns);
        else
            run_due_firmware(now_ns);
    }
    if (hit) {
        if (damage.kind == FrameDamage::Kind::Corrupted) count_corruption(damage, m);
        ++counters_.lost;
        return false;
    }
    if (gone) {
        ++counters_.lost;
        return false;
    }
    frame[6] |= 0x02;  // the ESC marks the frame as processed in the source address
    if (len < kMinEthFrame && frame.size() >= kMinEthFrame) {
        std::memset(frame.data() + len, 0, kMinEthFrame - len);
        len = kMinEthFrame;
    }
    onward_ = downstream_ && m == slaves_.size();
    if (onward_)
        ++counters_.onward;
    else
        ++counters_.replies;
    return true;
}

void Segment::count_corruption(const FrameDamage& d, std::size_t m) {
    // The first ESC to receive the bad FCS counts an invalid frame and marks the frame; the ESCs after it
    // count a forwarded error (ESC datasheet section I, error counters). Only port 0 leads through the
    // processing unit (0x030C).
    if (!d.returning) {
        for (std::size_t k = d.cable; k < m; ++k) {
            Esc& e = slaves_[k]->esc();
            if (k == d.cable)
                e.count_invalid_frame(0);
            else
                e.count_forwarded_error(0);
            e.count_processing_unit_error();
        }
        // On its way back the marked frame enters each ESC before the last through port 1.
        for (std::size_t k = 0; k + 1 < m; ++k)
            slaves_[k]->esc().count_forwarded_error(1);
    } else if (d.cable > 0) {
        slaves_[d.cable - 1]->esc().count_invalid_frame(1);
        for (std::size_t k = 0; k + 1 < d.cable; ++k)
            slaves_[k]->esc().count_forwarded_error(1);
    }
    // Damage on the returning cable 0 reaches the master's NIC, which drops the frame: no ESC sees it.
}

std::unique_ptr<Segment> make_segment(const device::DeviceDescription& d, std::size_t n, const EscConfig& cfg,
                                      const ApplicationFactory& factory) {
    return make_segment(DeviceModel::of(d), n, cfg, factory);
}

std::unique_ptr<Segment> make_segment(const DeviceModel& model, std::size_t n, const EscConfig& cfg,
                                      const ApplicationFactory& factory) {
    const device::DeviceDescription& d = *model.description;
    auto seg = std::make_unique<Segment>();
    for (std::size_t i = 0; i < n; ++i) {
        std::unique_ptr<Application> app;
        if (factory)
            app = factory(d);
        else
            app = std::make_unique<ProcessImageApplication>(d.output_bytes(), d.input_bytes());
        seg->add(std::make_unique<Slave>(model, cfg, std::move(app)));
    }
    if (factory)
        seg->set_application_factory(factory);
    else
        seg->set_application_factory([](const device::DeviceDescription& dd) -> std::unique_ptr<Application> {
            return std::make_unique<ProcessImageApplication>(dd.output_bytes(), dd.input_bytes());
        });
    return seg;
}

}  // namespace vecat::esc
