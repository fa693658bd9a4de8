#include "network/dictionary_file.hpp"
#include "common/file.hpp"
#include "network/yaml_reader.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

namespace vecat::network {

namespace {

using device::DataType;
using device::ObjectCode;

// The object codes by name (ETG.1000.6 Table 46).
struct CodeName {
    std::string_view name;
    ObjectCode code;
};
constexpr CodeName kCodes[] = {
    {"domain", ObjectCode::Domain}, {"deftype", ObjectCode::DefType}, {"defstruct", ObjectCode::DefStruct},
    {"var", ObjectCode::Var},       {"array", ObjectCode::Array},     {"record", ObjectCode::Record},
};

std::string_view code_name(ObjectCode c) {
    for (const auto& k : kCodes)
        if (k.code == c) return k.name;
    return {};
}

// The highest data type index type_name() knows (ETG.1000.6 Table 64 and the ETG.1020 structures).
constexpr unsigned kLastNamedType = 0x0030;

class Reader : public YamlReader<DictionaryFileError> {
  public:
    using YamlReader::YamlReader;
    bool boolean(const YAML::Node& n, const std::string& key) const {
        const std::string s = scalar(n, key);
        if (s == "true") return true;
        if (s == "false") return false;
        fail(n, key + ": true or false");
    }
    std::vector<std::uint8_t> bytes(const YAML::Node& n, const std::string& key) const {
        std::vector<std::uint8_t> out;
        if (!parse_hex(scalar(n, key), out))
            fail(n, key + ": bytes in hexadecimal separated by spaces (\"9a 00\"), or \"\" for none");
        return out;
    }
    DataType type(const YAML::Node& n) const {
        const std::string s = scalar(n, "type");
        for (unsigned t = 1; t <= kLastNamedType; ++t)
            if (device::type_name(static_cast<DataType>(t)) == s) return static_cast<DataType>(t);
        return static_cast<DataType>(number(n, "type", 0xFFFF));
    }
};

device::EntryDescription parse_entry(const Reader& r, const YAML::Node& n, std::uint16_t index,
                                     DeviceDictionary& out) {
    if (!n.IsMap()) r.fail(n, "an entry is a map (subindex:, name:, type:, bits:, access:, value:)");
    device::EntryDescription e;
    bool have_sub = false, have_type = false, have_bits = false, have_access = false;
    std::optional<std::vector<std::uint8_t>> value;
    unsigned value_line = 0;
    for (const auto& item : n) {
        const std::string key = r.scalar(item.first, "key");
        const YAML::Node& v = item.second;
        if (key == "subindex") {
            e.subindex = static_cast<std::uint8_t>(r.number(v, key, 0xFF));
            have_sub = true;
        } else if (key == "name") {
            e.name = r.scalar(v, key);
        } else if (key == "type") {
            e.type = r.type(v);
            have_type = true;
        } else if (key == "bits") {
            e.bit_length = static_cast<std::uint16_t>(r.number(v, key, 0xFFFF));
            have_bits = true;
        } else if (key == "access") {
            e.access = static_cast<std::uint16_t>(r.number(v, key, 0xFFFF));
            have_access = true;
        } else if (key == "value") {
            value = r.bytes(v, key);
            value_line = Reader::line(v);
        } else if (key == "default") {
            e.default_value = r.bytes(v, key);
        } else if (key == "minimum") {
            e.minimum = r.bytes(v, key);
        } else if (key == "maximum") {
            e.maximum = r.bytes(v, key);
        } else {
            r.fail(item.first, "unknown key " + key +
                                   " (subindex, name, type, bits, access, value, default, minimum, maximum)");
        }
    }
    const unsigned line = Reader::line(n);
    if (!have_sub || !have_type || !have_bits || !have_access)
        r.fail(line, "an entry needs subindex:, type:, bits: and access:");
    // A value holds at most the entry's bits; a string or domain may be shorter (its current length).
    const std::size_t room = (e.bit_length + 7u) / 8u;
    const auto check = [&](const std::vector<std::uint8_t>& b, const char* what, unsigned at) {
        if (b.size() > std::max<std::size_t>(room, 1))
            r.fail(at, std::string(what) + ": " + std::to_string(b.size()) +
                           " bytes, more than the entry's " + std::to_string(e.bit_length) + " bits");
        if (!device::is_variable_length(e.type) && !b.empty() && b.size() != room)
            r.fail(at, std::string(what) + ": " + std::to_string(b.size()) + " bytes for an entry of " +
                           std::to_string(e.bit_length) + " bits");
    };
    check(e.default_value, "default", line);
    check(e.minimum, "minimum", line);
    check(e.maximum, "maximum", line);
    if (value) {
        check(*value, "value", value_line);
        out.values[{index, e.subindex}] = std::move(*value);
    }
    return e;
}

device::ObjectDescription parse_object(const Reader& r, const YAML::Node& n, DeviceDictionary& out) {
    if (!n.IsMap()) r.fail(n, "an object is a map (index:, name:, code:, type:, max_subindex:, entries:)");
    device::ObjectDescription o;
    bool have_index = false, have_code = false, have_type = false;
    std::optional<std::uint8_t> max_sub;
    YAML::Node entries;
    unsigned entries_line = Reader::line(n);
    // The index first: the entries' values are kept under it.
    if (const YAML::Node i = n["index"]; i) {
        o.index = static_cast<std::uint16_t>(r.number(i, "index", 0xFFFF));
        have_index = true;
    }
    for (const auto& item : n) {
        const std::string key = r.scalar(item.first, "key");
        const YAML::Node& v = item.second;
        if (key == "index") {
            continue;
        } else if (key == "name") {
            o.name = r.scalar(v, key);
        } else if (key == "code") {
            const std::string s = r.scalar(v, key);
            const auto* it = std::find_if(std::begin(kCodes), std::end(kCodes),
                                          [&](const CodeName& c) { return c.name == s; });
            if (it == std::end(kCodes))
                r.fail(v, "code: var, array, record, domain, deftype or defstruct, not " + s);
            o.code = it->code;
            have_code = true;
        } else if (key == "type") {
            o.type = r.type(v);
            have_type = true;
        } else if (key == "max_subindex") {
            max_sub = static_cast<std::uint8_t>(r.number(v, key, 0xFF));
        } else if (key == "entries") {
            entries = v;
            entries_line = Reader::line(v);
        } else {
            r.fail(item.first, "unknown key " + key + " (index, name, code, type, max_subindex, entries)");
        }
    }
    const unsigned line = Reader::line(n);
    if (!have_index || !have_code || !have_type) r.fail(line, "an object needs index:, code: and type:");
    if (!entries || !entries.IsSequence() || entries.size() == 0)
        r.fail(entries_line, "object " + std::to_string(o.index) + ": entries: a list of at least one entry");
    std::set<unsigned> subs;
    for (const auto& e : entries) {
        o.entries.push_back(parse_entry(r, e, o.index, out));
        if (!subs.insert(o.entries.back().subindex).second)
            r.fail(e, "a second entry of subindex " + std::to_string(o.entries.back().subindex));
    }
    std::sort(o.entries.begin(), o.entries.end(),
              [](const auto& a, const auto& b) { return a.subindex < b.subindex; });
    if (max_sub) {
        if (*max_sub < o.entries.back().subindex)
            r.fail(line, "max_subindex " + std::to_string(*max_sub) + " is below the entry of subindex " +
                             std::to_string(o.entries.back().subindex));
        if (*max_sub != o.entries.back().subindex) o.declared_max_subindex = max_sub;
    }
    return o;
}

std::string quoted(const std::string& s) {
    std::string out = "\"";
    for (const char ch : s) {
        const auto c = static_cast<unsigned char>(ch);
        if (c == '"' || c == '\\') {
            out += '\\';
            out += ch;
        } else if (c < 0x20 || c == 0x7F) {  // UTF-8 (bytes from 0x80) stays as it is
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", c);
            out += buf;
        } else {
            out += ch;
        }
    }
    return out + "\"";
}

// Text on one comment line: a line break or other control character in it would end the comment.
std::string comment(std::string s) {
    for (char& c : s)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) c = ' ';
    return s;
}

std::string hex_number(unsigned v, int digits) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "0x%0*x", digits, v);
    return buf;
}

std::string type_text(DataType t) {
    const auto v = static_cast<unsigned>(t);
    const std::string_view n = device::type_name(t);
    return hex_number(v, 4) + (v <= kLastNamedType && n != "UNKNOWN" ? "    # " + std::string(n) : "");
}

}  // namespace

std::string to_hex(const std::vector<std::uint8_t>& bytes) {
    std::string s;
    char buf[4];
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        std::snprintf(buf, sizeof buf, "%02x", bytes[i]);
        if (i) s += ' ';
        s += buf;
    }
    return s;
}

bool parse_hex(const std::string& text, std::vector<std::uint8_t>& out) {
    out.clear();
    const auto digit = [](char c) -> int {
        if (c >= '0' && c <= '9') return c - '0';
        if (c >= 'a' && c <= 'f') return c - 'a' + 10;
        if (c >= 'A' && c <= 'F') return c - 'A' + 10;
        return -1;
    };
    std::size_t i = 0;
    while (i < text.size()) {
        if (text[i] == ' ') {
            ++i;
            continue;
        }
        if (i + 1 >= text.size()) return false;
        const int hi = digit(text[i]), lo = digit(text[i + 1]);
        if (hi < 0 || lo < 0) return false;
        out.push_back(static_cast<std::uint8_t>(hi * 16 + lo));
        i += 2;
        if (i < text.size() && text[i] != ' ') return false;
    }
    return true;
}

DeviceDictionary parse_dictionary(const std::string& text, const std::string& name) {
    const Reader r(name);
    YAML::Node root;
    try {
        root = YAML::Load(text);
    } catch (const YAML::ParserException& x) {
        r.fail(static_cast<unsigned>(x.mark.line + 1), x.msg);
    } catch (const YAML::Exception& x) {
        throw DictionaryFileError(name + ": " + x.what());
    }
    if (!root.IsMap()) throw DictionaryFileError(name + ": a dictionary file is a map with objects:");
    DeviceDictionary d;
    YAML::Node objects;
    for (const auto& item : root) {
        const std::string key = r.scalar(item.first, "key");
        const YAML::Node& v = item.second;
        if (key == "objects") {
            objects = v;
        } else if (key == "sdo_information") {
            d.sdo_information = r.boolean(v, key);
        } else if (key == "missing") {
            if (!v.IsSequence()) r.fail(v, "missing: a list of lines");
            for (const auto& m : v)
                d.missing.push_back(r.scalar(m, "missing"));
        } else {
            r.fail(item.first, "unknown key " + key + " (objects, sdo_information, missing)");
        }
    }
    if (!objects || !objects.IsSequence() || objects.size() == 0)
        throw DictionaryFileError(name + ": objects: a list of at least one object");
    std::set<unsigned> seen;
    for (const auto& n : objects) {
        d.objects.push_back(parse_object(r, n, d));
        if (!seen.insert(d.objects.back().index).second)
            r.fail(n, "a second object of index " + hex_number(d.objects.back().index, 4));
    }
    std::sort(d.objects.begin(), d.objects.end(),
              [](const auto& a, const auto& b) { return a.index < b.index; });
    return d;
}

DeviceDictionary read_dictionary_file(const std::string& path) {
    std::string why;
    const auto text = read_whole_file(path, kMaxTextFileBytes, why);
    if (!text) throw DictionaryFileError(path + ": " + why);
    return parse_dictionary(*text, path);
}

std::string write_dictionary(const DeviceDictionary& d, const std::vector<std::string>& header) {
    std::ostringstream o;
    for (const auto& h : header)
        o << "# " << comment(h) << "\n";
    if (!d.missing.empty()) {
        o << "# Not read from the device (" << d.missing.size() << "):\n";
        for (const auto& m : d.missing)
            o << "#   " << comment(m) << "\n";
    }
    o << "sdo_information: " << (d.sdo_information ? "true" : "false") << "\n";
    if (!d.missing.empty()) {
        o << "missing:\n";
        for (const auto& m : d.missing)
            o << "  - " << quoted(m) << "\n";
    }
    o << "objects:\n";
    for (const auto& ob : d.objects) {
        o << "  - index: " << hex_number(ob.index, 4) << "\n";
        o << "    name: " << quoted(ob.name) << "\n";
        o << "    code: " << code_name(ob.code) << "\n";
        o << "    type: " << type_text(ob.type) << "\n";
        o << "    max_subindex: " << static_cast<unsigned>(ob.max_subindex()) << "\n";
        o << "    entries:\n";
        for (const auto& e : ob.entries) {
            o << "      - subindex: " << static_cast<unsigned>(e.subindex) << "\n";
            o << "        name: " << quoted(e.name) << "\n";
            o << "        type: " << type_text(e.type) << "\n";
            o << "        bits: " << e.bit_length << "\n";
            o << "        access: " << hex_number(e.access, 4) << "\n";
            if (auto it = d.values.find({ob.index, e.subindex}); it != d.values.end())
                o << "        value: \"" << to_hex(it->second) << "\"\n";
            if (!e.default_value.empty()) o << "        default: \"" << to_hex(e.default_value) << "\"\n";
            if (!e.minimum.empty()) o << "        minimum: \"" << to_hex(e.minimum) << "\"\n";
            if (!e.maximum.empty()) o << "        maximum: \"" << to_hex(e.maximum) << "\"\n";
        }
    }
    return o.str();
}

}  // namespace vecat::network
