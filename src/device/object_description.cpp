#include "device/object_description.hpp"

#include <cstdio>
#include <cstring>

namespace vecat::device {

std::vector<std::uint8_t> encode_integer(DataType t, std::int64_t v) {
    unsigned bits = fixed_bit_length(t);
    if (bits == 0 || is_real(t)) bits = 32;
    std::vector<std::uint8_t> out((bits + 7) / 8);
    const auto u = static_cast<std::uint64_t>(v);
    for (std::size_t i = 0; i < out.size(); ++i)
        out[i] = static_cast<std::uint8_t>(u >> (8 * i));
    if (t == DataType::Boolean) out[0] &= 1;
    return out;
}

std::vector<std::uint8_t> encode_real(DataType t, double v) {
    if (t == DataType::Real64) {
        std::vector<std::uint8_t> out(8);
        std::uint64_t u = 0;
        std::memcpy(&u, &v, 8);
        for (int i = 0; i < 8; ++i)
            out[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(u >> (8 * i));
        return out;
    }
    const auto f = static_cast<float>(v);
    std::uint32_t u = 0;
    std::memcpy(&u, &f, 4);
    std::vector<std::uint8_t> out(4);
    for (int i = 0; i < 4; ++i)
        out[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(u >> (8 * i));
    return out;
}

EntryDescription make_entry(std::uint8_t sub, std::string name, DataType t, std::uint16_t acc,
                            std::int64_t default_value) {
    EntryDescription e;
    e.subindex = sub;
    e.name = std::move(name);
    e.type = t;
    e.bit_length = static_cast<std::uint16_t>(fixed_bit_length(t));
    e.access = acc;
    e.default_value = encode_integer(t, default_value);
    return e;
}

EntryDescription make_string_entry(std::uint8_t sub, std::string name, std::string_view text,
                                   std::uint16_t acc) {
    EntryDescription e;
    e.subindex = sub;
    e.name = std::move(name);
    e.type = DataType::VisibleString;
    e.bit_length = static_cast<std::uint16_t>(8 * text.size());
    e.access = acc;
    e.default_value.assign(text.begin(), text.end());
    return e;
}

ObjectDescription make_var(std::uint16_t index, std::string name, DataType t, std::uint16_t acc,
                           std::int64_t default_value) {
    ObjectDescription o;
    o.index = index;
    o.code = ObjectCode::Var;
    o.type = t;
    o.entries.push_back(make_entry(0, name, t, acc, default_value));
    o.name = std::move(name);
    return o;
}

ObjectDescription make_string_var(std::uint16_t index, std::string name, std::string_view text) {
    ObjectDescription o;
    o.index = index;
    o.code = ObjectCode::Var;
    o.type = DataType::VisibleString;
    o.entries.push_back(make_string_entry(0, name, text));
    o.name = std::move(name);
    return o;
}

ObjectDescription make_record(std::uint16_t index, std::string name, std::vector<EntryDescription> subs,
                              DataType struct_type) {
    ObjectDescription o;
    o.index = index;
    o.name = std::move(name);
    o.code = ObjectCode::Record;
    o.type = struct_type;
    const std::uint8_t highest = subs.empty() ? 0 : subs.back().subindex;
    o.entries.push_back(make_entry(0, "Number of entries", DataType::Unsigned8, access::RO, highest));
    for (auto& s : subs)
        o.entries.push_back(std::move(s));
    return o;
}

ObjectDescription make_array(std::uint16_t index, std::string name, DataType element, std::uint16_t acc,
                             std::vector<std::int64_t> defaults, std::uint16_t sub0_access) {
    ObjectDescription o;
    o.index = index;
    o.name = std::move(name);
    o.code = ObjectCode::Array;
    o.type = element;
    o.entries.push_back(make_entry(0, "Number of entries", DataType::Unsigned8, sub0_access,
                                   static_cast<std::int64_t>(defaults.size())));
    for (std::size_t i = 0; i < defaults.size(); ++i)
        o.entries.push_back(make_entry(static_cast<std::uint8_t>(i + 1),
                                       subindex_name(static_cast<unsigned>(i + 1)), element, acc,
                                       defaults[i]));
    return o;
}

std::string subindex_name(unsigned sub) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "SubIndex %03u", sub & 0xFFu);
    return buf;
}

void set_range(EntryDescription& e, std::int64_t min, std::int64_t max) {
    e.minimum = encode_integer(e.type, min);
    e.maximum = encode_integer(e.type, max);
}

}  // namespace vecat::device
