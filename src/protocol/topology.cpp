#include "protocol/topology.hpp"

#include "protocol/registers.hpp"

namespace vecat::protocol {

std::uint8_t open_ports(std::uint16_t dl_status) noexcept {
    std::uint8_t open = 0;
    for (unsigned p = 0; p < 4; ++p)
        if ((dl_status & dl_status::communication(p)) && !(dl_status & dl_status::loop_closed(p)))
            open = static_cast<std::uint8_t>(open | (1u << p));
    return open;
}

std::vector<Upstream> topology_from_open_ports(std::span<const std::uint8_t> open) {
    std::vector<Upstream> up(open.size());
    // Per slave: the open ports after port 0 not yet given to a slave, in the frame's order.
    std::vector<std::vector<unsigned>> free(open.size());
    std::vector<std::size_t> path;  // slaves from the first to the current one that may have ports left
    for (std::size_t i = 0; i < open.size(); ++i) {
        for (unsigned p : kPortsAfterPort0)
            if ((open[i] >> p) & 1u) free[i].push_back(p);
        while (!path.empty() && free[path.back()].empty())
            path.pop_back();
        if (!path.empty()) {
            const std::size_t parent = path.back();
            up[i] = {static_cast<int>(parent), free[parent].front()};
            free[parent].erase(free[parent].begin());
        }
        path.push_back(i);
    }
    return up;
}

std::vector<std::size_t> frame_order(std::span<const std::array<int, 4>> children) {
    std::vector<std::size_t> order;
    if (children.empty()) return order;
    std::vector<bool> seen(children.size(), false);
    std::vector<std::size_t> todo{0};
    while (!todo.empty()) {
        const std::size_t at = todo.back();
        todo.pop_back();
        if (seen[at]) continue;
        seen[at] = true;
        order.push_back(at);
        for (auto p = kPortsAfterPort0.rbegin(); p != kPortsAfterPort0.rend(); ++p)
            if (const int c = children[at][*p]; c >= 0 && static_cast<std::size_t>(c) < children.size())
                todo.push_back(static_cast<std::size_t>(c));
    }
    return order;
}

}  // namespace vecat::protocol
