// Hot connect groups (as TwinCAT's): a device and everything downstream of it, unplugged from the line and
// plugged back at run time, at the port it left or at another free port. Plugged back elsewhere, the slaves
// take the order in which the frame now reaches them (depth first, ports 0 -> 3 -> 1 -> 2).
#include <algorithm>
#include <string>

#include "esc/segment.hpp"
#include "protocol/topology.hpp"

namespace vecat::esc {

void Segment::add_hot_connect_group(std::string name, std::size_t head) {
    groups_.emplace_back(std::move(name), head);
}

std::size_t Segment::hot_connect_head(std::string_view name) const {
    for (const auto& [n, head] : groups_)
        if (n == name) return head;
    return slaves_.size();
}

std::size_t Segment::group_end(std::size_t head) const {
    // Depth first: the slaves downstream of head follow it; the first one that does not lead back to head
    // ends the group.
    std::size_t k = head + 1;
    for (; k < slaves_.size(); ++k) {
        int at = parent_[k];
        while (at >= 0 && static_cast<std::size_t>(at) > head)
            at = parent_[static_cast<std::size_t>(at)];
        if (at < 0 || static_cast<std::size_t>(at) != head) break;
    }
    return k;
}

bool Segment::can_move_group(std::size_t head, std::size_t parent, unsigned port, std::string* why) const {
    const auto fail = [&](const std::string& w) {
        if (why) *why = w;
        return false;
    };
    const std::size_t n = slaves_.size();
    if (head == 0 || head >= n)
        return fail("slave " + std::to_string(head) + " heads no group that can move");
    if (downstream_) return fail("a line chained to another segment keeps its order");
    const std::size_t end = group_end(head);
    if (parent >= n) return fail("there is no slave " + std::to_string(parent));
    if (parent >= head && parent < end)
        return fail("slave " + std::to_string(parent) + " belongs to the group itself");
    if (port < 1 || port > 3) return fail("a group is plugged into port 1, 2 or 3");
    if (((slaves_[parent]->esc().config().port_descriptor >> (2 * port)) & 0x3) == 0)
        return fail("slave " + std::to_string(parent) + " has no port " + std::to_string(port));
    if (const int c = child_[parent][port]; c >= 0 && static_cast<std::size_t>(c) != head)
        return fail("port " + std::to_string(port) + " of slave " + std::to_string(parent) +
                    " has a link already (slave " + std::to_string(c) + ")");
    if (parent == red_slave_ && port == red_port_)
        return fail("port " + std::to_string(port) + " of slave " + std::to_string(parent) +
                    " has the redundancy cable");
    return true;
}

bool Segment::move_group(std::size_t head, std::size_t parent, unsigned port, std::vector<std::size_t>& order,
                         std::string* why) {
    if (!can_move_group(head, parent, port, why)) return false;
    finish_background_firmware();
    const std::size_t n = slaves_.size();
    // The new cabling, by the slaves' present numbers.
    std::vector<std::array<int, 4>> child = child_;
    child[static_cast<std::size_t>(parent_[head])][parent_port_[head]] = -1;
    child[parent][port] = static_cast<int>(head);
    // The order the frame reaches them now: order[new] = old.
    order = protocol::frame_order(child);
    if (order.size() != n) {  // cannot happen: the parent lies outside the group
        if (why) *why = "the cabling would leave slaves without a way to the master";
        return false;
    }
    std::vector<std::size_t> now(n);  // now[old] = new
    for (std::size_t k = 0; k < n; ++k)
        now[order[k]] = k;
    const auto permute = [&](auto& v) {
        auto old = std::move(v);
        v.clear();
        v.reserve(old.size());
        for (std::size_t k = 0; k < n; ++k)
            v.push_back(std::move(old[order[k]]));
    };
    std::vector<int> parents(n);
    std::vector<std::uint8_t> ports(n);
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t o = order[k];
        const int p = o == head ? static_cast<int>(parent) : parent_[o];
        parents[k] = p < 0 ? -1 : static_cast<int>(now[static_cast<std::size_t>(p)]);
        ports[k] = static_cast<std::uint8_t>(o == head ? port : parent_port_[o]);
    }
    permute(slaves_);
    permute(own_factory_);
    permute(cable_up_);
    permute(halted_);
    permute(last_run_ns_);
    marks_valid_ = false;  // marked_ names the old places
    permute(deadline_ns_);
    permute(pulse_ns_);
    permute(cycle_ns_);
    permute(latched_);
    permute(delay_);
    parent_ = std::move(parents);
    parent_port_ = std::move(ports);
    for (auto& c : child_)
        c = {-1, -1, -1, -1};
    for (std::size_t k = 1; k < n; ++k)
        child_[static_cast<std::size_t>(parent_[k])][parent_port_[k]] = static_cast<int>(k);
    for (auto& g : groups_)
        g.second = now[g.second];
    if (red_slave_ < n) red_slave_ = now[red_slave_];
    pending_latch_ = PendingLatch{};
    ++slaves_epoch_;
    ++port_epoch_;
    for (std::size_t k = 0; k < n; ++k)
        update_links(k);
    return true;
}

}  // namespace vecat::esc
