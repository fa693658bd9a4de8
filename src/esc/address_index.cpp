#include "esc/address_index.hpp"

#include <algorithm>

namespace vecat::esc {

void AddressIndex::rebuild(std::span<const Esc::Addressing> table) {
    by_address_.clear();
    by_first_bit_.clear();
    by_address_.reserve(2 * table.size());
    by_first_bit_.reserve(2 * table.size());
    for (std::size_t k = 0; k < table.size(); ++k) {
        const Esc::Addressing& a = table[k];
        const auto slave = static_cast<std::uint32_t>(k);
        by_address_.emplace_back(a.station, slave);
        if (a.alias_enabled && a.alias != a.station) by_address_.emplace_back(a.alias, slave);
        // One span for the FMMUs that read and one for those that write, or one for both where they overlap
        // or touch.
        const bool reads = a.log_read_first_bit <= a.log_read_last_bit;
        const bool writes = a.log_write_first_bit <= a.log_write_last_bit;
        if (reads && writes && a.log_read_first_bit <= a.log_write_last_bit + 1 &&
            a.log_write_first_bit <= a.log_read_last_bit + 1) {
            by_first_bit_.push_back({std::min(a.log_read_first_bit, a.log_write_first_bit),
                                     std::max(a.log_read_last_bit, a.log_write_last_bit), 0, slave});
        } else {
            if (reads) by_first_bit_.push_back({a.log_read_first_bit, a.log_read_last_bit, 0, slave});
            if (writes) by_first_bit_.push_back({a.log_write_first_bit, a.log_write_last_bit, 0, slave});
        }
    }
    std::sort(by_address_.begin(), by_address_.end());
    std::sort(by_first_bit_.begin(), by_first_bit_.end(),
              [](const Span& x, const Span& y) { return x.first_bit < y.first_bit; });
    std::uint64_t max_last = 0;
    for (Span& s : by_first_bit_) {
        max_last = std::max(max_last, s.last_bit);
        s.max_last_bit = max_last;
    }
}

void AddressIndex::fixed(std::uint16_t adp, std::vector<std::uint32_t>& out) const {
    auto it = std::lower_bound(by_address_.begin(), by_address_.end(),
                               std::pair<std::uint16_t, std::uint32_t>{adp, 0});
    for (; it != by_address_.end() && it->first == adp; ++it)
        out.push_back(it->second);
}

void AddressIndex::logical(std::uint64_t first_bit, std::uint64_t last_bit,
                           std::vector<std::uint32_t>& out) const {
    // The spans that start at or before last_bit; of those, walking back, the ones that reach first_bit. The
    // walk stops where no span before reaches it (max_last_bit), so disjoint spans in order cost one more.
    auto end = std::upper_bound(by_first_bit_.begin(), by_first_bit_.end(), last_bit,
                                [](std::uint64_t bit, const Span& s) { return bit < s.first_bit; });
    const std::size_t from = out.size();
    for (auto it = end; it != by_first_bit_.begin();) {
        --it;
        if (it->max_last_bit < first_bit) break;
        if (it->last_bit >= first_bit) out.push_back(it->slave);
    }
    // In the order of the logical addresses: on a line mapped in its order, the slaves' order (which spares
    // the caller its sort).
    std::reverse(out.begin() + static_cast<std::ptrdiff_t>(from), out.end());
}

}  // namespace vecat::esc
