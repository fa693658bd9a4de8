#include "soe/idn_table.hpp"

#include <algorithm>

namespace vecat::soe {

namespace el = protocol::soe_element;
using protocol::AlState;
using protocol::kSoeListHeaderSize;

std::uint64_t IdnEntry::number() const noexcept {
    if (attribute.list) return 0;
    std::uint64_t v = 0;
    const std::size_t n = std::min<std::size_t>(value.size(), 8);
    for (std::size_t i = 0; i < n; ++i)
        v |= static_cast<std::uint64_t>(value[i]) << (8 * i);
    return v;
}

void IdnEntry::set_number(std::uint64_t v) noexcept {
    if (attribute.list) return;
    for (std::size_t i = 0; i < value.size() && i < 8; ++i)
        value[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

std::vector<std::uint16_t> IdnEntry::words() const {
    std::vector<std::uint16_t> w;
    for (std::size_t i = 0; i + 1 < value.size(); i += 2)
        w.push_back(ld_le16(value.data() + i));
    return w;
}

void IdnEntry::set_words(const std::vector<std::uint16_t>& w) {
    value.assign(w.size() * 2, 0);
    for (std::size_t i = 0; i < w.size(); ++i)
        st_le16(value.data() + 2 * i, w[i]);
}

IdnTable::IdnTable(std::vector<IdnEntry> entries) : entries_(std::move(entries)) {
    std::sort(entries_.begin(), entries_.end(),
              [](const IdnEntry& a, const IdnEntry& b) { return a.idn < b.idn; });
}

IdnEntry* IdnTable::find(Idn idn) {
    auto it = std::lower_bound(entries_.begin(), entries_.end(), idn,
                               [](const IdnEntry& e, Idn i) { return e.idn < i; });
    return it != entries_.end() && it->idn == idn ? &*it : nullptr;
}

const IdnEntry* IdnTable::find(Idn idn) const {
    return const_cast<IdnTable*>(this)->find(idn);
}

std::vector<std::uint16_t> IdnTable::all_idns() const {
    std::vector<std::uint16_t> v;
    v.reserve(entries_.size());
    for (const auto& e : entries_)
        v.push_back(e.idn.raw);
    return v;
}

namespace {

void put_u16(std::vector<std::uint8_t>& out, std::uint16_t v) {
    LeWriter w(out);
    w.u16(v);
}

// A text or list element: current length, maximum length, the bytes.
void put_list(std::vector<std::uint8_t>& out, ConstBytes bytes, std::size_t max_bytes) {
    put_u16(out, static_cast<std::uint16_t>(bytes.size()));
    put_u16(out, static_cast<std::uint16_t>(std::max(bytes.size(), max_bytes)));
    out.insert(out.end(), bytes.begin(), bytes.end());
}

void put_text(std::vector<std::uint8_t>& out, const std::string& s) {
    put_list(out, ConstBytes(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()), s.size());
}

void put_fixed(std::vector<std::uint8_t>& out, std::uint64_t v, std::size_t size) {
    for (std::size_t i = 0; i < size; ++i)
        out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

void put_value(std::vector<std::uint8_t>& out, const IdnEntry& e, const std::vector<std::uint8_t>& v) {
    if (e.attribute.list)
        put_list(out, v, e.max_list_bytes);
    else
        out.insert(out.end(), v.begin(), v.end());
}

// The error a write of an element other than the value gets (IEC 61800-7-204 error codes: "no ..." when
// the IDN lacks it, "... cannot be changed" when it has it).
SoeError not_writable(const IdnEntry& e, std::uint8_t element) {
    switch (element) {
        case el::DataState:
            return SoeError::InvalidAccessElement1;
        case el::Name:
            return e.name.empty() ? SoeError::NoName : SoeError::NameReadOnly;
        case el::Attribute:
            return SoeError::AttributeReadOnly;
        case el::Unit:
            return e.unit.empty() ? SoeError::NoUnit : SoeError::UnitReadOnly;
        case el::Min:
            return e.min && !e.attribute.list ? SoeError::MinReadOnly : SoeError::NoMin;
        case el::Max:
            return e.max && !e.attribute.list ? SoeError::MaxReadOnly : SoeError::NoMax;
        default:
            return e.default_value ? SoeError::DefaultReadOnly : SoeError::NoDefault;
    }
}

// a < b for the bit patterns of a value, signed when the attribute says so.
bool less(const IdnEntry& e, std::uint64_t a, std::uint64_t b) {
    if (e.attribute.type != protocol::SoeDataType::Signed) return a < b;
    const unsigned bits = static_cast<unsigned>(e.attribute.element_size() * 8);
    auto sext = [bits](std::uint64_t v) {
        if (bits >= 64) return static_cast<std::int64_t>(v);
        const std::uint64_t sign = std::uint64_t{1} << (bits - 1);
        v &= (sign << 1) - 1;
        return static_cast<std::int64_t>((v ^ sign) - sign);
    };
    return sext(a) < sext(b);
}

}  // namespace

std::optional<SoeError> IdnTable::read(const IdnEntry& e, std::uint8_t elements,
                                       std::vector<std::uint8_t>& out) {
    if (elements == 0) return SoeError::NoElementAddressed;
    const std::size_t size = e.attribute.element_size();
    if (elements & el::DataState) put_u16(out, e.data_state);
    if (elements & el::Name) {
        if (e.name.empty()) return SoeError::NoName;
        put_text(out, e.name);
    }
    if (elements & el::Attribute) {
        LeWriter w(out);
        w.u32(e.attribute.pack());
    }
    if (elements & el::Unit) {
        if (e.unit.empty()) return SoeError::NoUnit;
        put_text(out, e.unit);
    }
    if (elements & el::Min) {
        if (!e.min || e.attribute.list) return SoeError::NoMin;
        put_fixed(out, *e.min, size);
    }
    if (elements & el::Max) {
        if (!e.max || e.attribute.list) return SoeError::NoMax;
        put_fixed(out, *e.max, size);
    }
    if (elements & el::Value) put_value(out, e, e.value);
    if (elements & el::Default) {
        if (!e.default_value) return SoeError::NoDefault;
        put_value(out, e, *e.default_value);
    }
    return std::nullopt;
}

std::optional<SoeError> IdnTable::check_write(const IdnEntry& e, std::uint8_t elements, ConstBytes data,
                                              AlState phase) {
    if (elements == 0) return SoeError::NoElementAddressed;
    // Only the operation data can be written; the lowest other element requested gives the error.
    for (unsigned bit = el::DataState; bit <= el::Default; bit <<= 1)
        if (bit != el::Value && (elements & bit) != 0) return not_writable(e, static_cast<std::uint8_t>(bit));
    if (e.read_only) return SoeError::DataReadOnly;
    const auto& a = e.attribute;
    if ((phase == AlState::PreOp && a.wp_preop) || (phase == AlState::SafeOp && a.wp_safeop) ||
        (phase == AlState::Op && a.wp_op))
        return SoeError::DataWriteProtected;
    const std::size_t size = a.element_size();
    if (a.list) {
        if (data.size() < kSoeListHeaderSize) return SoeError::DataTooShort;
        const std::size_t current = ld_le16(data.data());
        const std::size_t carried = data.size() - kSoeListHeaderSize;
        if (current > e.max_list_bytes) return SoeError::DataTooLong;
        if (carried < current) return SoeError::DataTooShort;
        if (carried > current) return SoeError::DataTooLong;
        if (current % size != 0) return SoeError::DataInvalid;
        return std::nullopt;
    }
    if (data.size() < size) return SoeError::DataTooShort;
    if (data.size() > size) return SoeError::DataTooLong;
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < size; ++i)
        v |= static_cast<std::uint64_t>(data[i]) << (8 * i);
    if (e.min && less(e, v, *e.min)) return SoeError::DataBelowMin;
    if (e.max && less(e, *e.max, v)) return SoeError::DataAboveMax;
    return std::nullopt;
}

ConstBytes IdnTable::value_of(const IdnEntry& e, ConstBytes data) {
    if (!e.attribute.list) return data;
    return data.size() >= kSoeListHeaderSize ? data.subspan(kSoeListHeaderSize) : ConstBytes{};
}

}  // namespace vecat::soe
