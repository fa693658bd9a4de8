// The ESI reader (about 1,000 lines): one vendor file to one DeviceDescription, element by element of the
// ETG.2000 schema (identity, SyncManagers, PDOs, Dictionary, Modules/Slots and the modules chosen for them,
// DC), each with its bad-input messages; the elements share the reading helpers of this file.
#include "esi/esi_reader.hpp"

#include <fmt/core.h>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <pugixml.hpp>
#include <set>
#include <sstream>

#include "common/file.hpp"
#include "esc/sii_image.hpp"
#include "protocol/objects.hpp"
#include "protocol/registers.hpp"

namespace vecat::esi {
namespace {

using device::DataType;
using device::EntryDescription;
using device::ObjectCode;
using device::ObjectDescription;
namespace acc = device::access;

std::string trim(std::string s) {
    const auto b = s.find_first_not_of(" \t\r\n");
    if (b == std::string::npos) return {};
    const auto e = s.find_last_not_of(" \t\r\n");
    return s.substr(b, e - b + 1);
}

std::string txt(pugi::xml_node n) {
    return trim(n.text().as_string());
}

std::optional<std::int64_t> hexdec_child(pugi::xml_node n, const char* child) {
    auto c = n.child(child);
    if (!c) return std::nullopt;
    return parse_hexdec(txt(c));
}

std::int64_t hexdec_or(pugi::xml_node n, const char* child, std::int64_t dflt) {
    return hexdec_child(n, child).value_or(dflt);
}

std::int64_t attr_or(pugi::xml_node n, const char* a, std::int64_t dflt) {
    auto at = n.attribute(a);
    if (!at) return dflt;
    return parse_hexdec(trim(at.as_string())).value_or(dflt);
}

bool bool_attr(pugi::xml_node n, const char* a) {
    const std::string v = trim(n.attribute(a).as_string());
    return v == "1" || v == "true";
}

// The Name child in English (LcId 1033), else the first one.
std::string name_of(pugi::xml_node n) {
    for (auto c : n.children("Name"))
        if (c.attribute("LcId").as_int(1033) == 1033) return txt(c);
    return txt(n.child("Name"));
}

std::vector<std::uint8_t> parse_hex_bytes(const std::string& s) {
    std::vector<std::uint8_t> out;
    for (std::size_t i = 0; i + 1 < s.size(); i += 2)
        out.push_back(static_cast<std::uint8_t>(std::stoul(s.substr(i, 2), nullptr, 16)));
    return out;
}

unsigned states_of(const std::string& r) {
    if (r == "PreOP" || r == "PreOp") return 1;
    if (r == "SafeOP") return 2;
    if (r == "OP") return 4;
    if (r == "PreOP_SafeOP") return 3;
    if (r == "PreOP_OP") return 5;
    if (r == "SafeOP_OP") return 6;
    return 7;
}

std::uint16_t access_of(pugi::xml_node flags, std::uint16_t dflt) {
    if (!flags) return dflt;
    std::uint16_t a = 0;
    auto ac = flags.child("Access");
    const std::string mode = ac ? txt(ac) : "ro";
    const unsigned r = states_of(trim(ac.attribute("ReadRestrictions").as_string()));
    const unsigned w = states_of(trim(ac.attribute("WriteRestrictions").as_string()));
    if (mode != "wo") a |= static_cast<std::uint16_t>(r);
    if (mode == "rw" || mode == "wo") a |= static_cast<std::uint16_t>(w << 3);
    std::string pm = txt(flags.child("PdoMapping"));
    std::transform(pm.begin(), pm.end(), pm.begin(),
                   [](char c) { return static_cast<char>(std::toupper(c)); });
    if (pm.find('R') != std::string::npos) a |= acc::RxPdoMappable;
    if (pm.find('T') != std::string::npos) a |= acc::TxPdoMappable;
    if (flags.child("Backup").text().as_int() != 0) a |= acc::Backup;
    if (flags.child("Setting").text().as_int() != 0) a |= acc::Settings;
    return a;
}

// A value of an entry's Info: DefaultString / *Data (hex bytes) / *Value (number).
void apply_info(pugi::xml_node info, EntryDescription& e) {
    if (!info) return;
    const unsigned bytes = device::fixed_bit_length(e.type) ? (device::fixed_bit_length(e.type) + 7) / 8 : 0;
    auto fit = [&](std::vector<std::uint8_t> v) {
        if (bytes) v.resize(bytes, 0);
        return v;
    };
    auto number = [&](const char* tag, std::vector<std::uint8_t>& out) {
        if (auto v = hexdec_child(info, tag)) out = device::encode_integer(e.type, *v);
    };
    if (auto s = info.child("DefaultString")) {
        const std::string t = s.text().as_string();
        e.default_value.assign(t.begin(), t.end());
    }
    if (auto d = info.child("DefaultData")) e.default_value = fit(parse_hex_bytes(txt(d)));
    if (auto d = info.child("MinData")) e.minimum = fit(parse_hex_bytes(txt(d)));
    if (auto d = info.child("MaxData")) e.maximum = fit(parse_hex_bytes(txt(d)));
    number("DefaultValue", e.default_value);
    number("MinValue", e.minimum);
    number("MaxValue", e.maximum);
}

DataType record_type_guess(std::uint16_t index) {
    if ((index >= 0x1600 && index < 0x1800) || (index >= 0x1A00 && index < 0x1C00))
        return DataType::PdoMapping;
    if (index == 0x1018) return DataType::Identity;
    if (index == 0x1C32 || index == 0x1C33) return DataType::SyncParameter;
    return DataType::Unsigned8;
}

struct Dictionary {
    std::map<std::string, pugi::xml_node> types;
    std::vector<ObjectDescription> objects;
};

std::optional<ObjectDescription> read_object(const Dictionary& dict, pugi::xml_node x,
                                             std::vector<std::string>& notes) {
    ObjectDescription o;
    const auto idx = hexdec_child(x, "Index");
    if (!idx) return std::nullopt;
    o.index = static_cast<std::uint16_t>(*idx);
    o.name = name_of(x);
    const std::string tname = txt(x.child("Type"));
    const auto obj_flags = x.child("Flags");
    auto dt_it = dict.types.find(tname);
    const pugi::xml_node dt = dt_it == dict.types.end() ? pugi::xml_node() : dt_it->second;
    if (!dt || !dt.child("SubItem")) {
        const auto t = parse_esi_type(dt && dt.child("BaseType") ? txt(dt.child("BaseType")) : tname);
        if (!t) {
            notes.push_back(
                fmt::format("object 0x{:04X} \"{}\": unknown type \"{}\", left out", o.index, o.name, tname));
            return std::nullopt;
        }
        EntryDescription e;
        e.subindex = 0;
        e.name = o.name;
        e.type = *t;
        e.bit_length =
            static_cast<std::uint16_t>(x.child("BitSize").text().as_uint(device::fixed_bit_length(*t)));
        e.access = access_of(obj_flags, acc::RO);
        apply_info(x.child("Info"), e);
        o.code = ObjectCode::Var;
        o.type = *t;
        o.entries.push_back(std::move(e));
        return o;
    }
    o.code = ObjectCode::Record;
    int next_sub = 0;
    for (auto si : dt.children("SubItem")) {
        const std::string st = txt(si.child("Type"));
        auto sub_dt = dict.types.find(st);
        const std::uint16_t a = access_of(si.child("Flags"), access_of(obj_flags, acc::RO));
        if (sub_dt != dict.types.end() && sub_dt->second.child("ArrayInfo")) {
            const auto arr = sub_dt->second;
            const auto base = parse_esi_type(txt(arr.child("BaseType")));
            if (!base) {
                notes.push_back(
                    fmt::format("object 0x{:04X}: unknown array element type, left out", o.index));
                return std::nullopt;
            }
            const int lb = arr.child("ArrayInfo").child("LBound").text().as_int(1);
            const int n = arr.child("ArrayInfo").child("Elements").text().as_int(0);
            // The elements are subindexes lb .. lb+n-1, all of them in 1..255 (subindex 0 is the count).
            if (lb < 1 || lb > 255 || n < 0 || n > 256 - lb) {
                notes.push_back(fmt::format(
                    "object 0x{:04X}: array bounds LBound {} Elements {} outside subindexes 1..255, left out",
                    o.index, lb, n));
                return std::nullopt;
            }
            unsigned bits = device::fixed_bit_length(*base);
            if (bits == 0 && n > 0) bits = arr.child("BitSize").text().as_uint() / static_cast<unsigned>(n);
            for (int k = 0; k < n; ++k) {
                EntryDescription e;
                e.subindex = static_cast<std::uint8_t>(lb + k);
                e.name = device::subindex_name(e.subindex);
                e.type = *base;
                e.bit_length = static_cast<std::uint16_t>(bits);
                e.access = a;
                o.entries.push_back(std::move(e));
            }
            o.code = ObjectCode::Array;
            o.type = *base;
            next_sub = lb + n;
            continue;
        }
        EntryDescription e;
        e.subindex = static_cast<std::uint8_t>(hexdec_or(si, "SubIdx", next_sub));
        next_sub = e.subindex + 1;
        e.name = txt(si.child("Name"));
        const auto t = parse_esi_type(st);
        if (!t) {
            notes.push_back(fmt::format("object 0x{:04X}:{} type \"{}\" unknown, read as bytes", o.index,
                                        e.subindex, st));
        }
        e.type = t.value_or(DataType::OctetString);
        e.bit_length = static_cast<std::uint16_t>(si.child("BitSize").text().as_uint());
        e.access = a;
        o.entries.push_back(std::move(e));
    }
    if (o.code == ObjectCode::Record)
        o.type =
            dt.child("Index") ? static_cast<DataType>(hexdec_or(dt, "Index", 0)) : record_type_guess(o.index);
    else if (dt.child("Index"))
        o.type = static_cast<DataType>(hexdec_or(dt, "Index", 0));
    // Defaults and names of the subindexes, in order.
    std::size_t i = 0;
    for (auto si : x.child("Info").children("SubItem")) {
        if (i >= o.entries.size()) break;
        auto& e = o.entries[i++];
        const std::string n = txt(si.child("Name"));
        if (!n.empty()) e.name = n;
        apply_info(si.child("Info"), e);
    }
    return o;
}

Dictionary read_dictionary(pugi::xml_node d, std::vector<std::string>& notes) {
    Dictionary dict;
    for (auto dt : d.child("DataTypes").children("DataType"))
        dict.types.emplace(txt(dt.child("Name")), dt);
    for (auto x : d.child("Objects").children("Object"))
        if (auto o = read_object(dict, x, notes)) dict.objects.push_back(std::move(*o));
    return dict;
}

device::SmType sm_type(const std::string& t, std::uint8_t control) {
    if (t == "MBoxOut") return device::SmType::MailboxOut;
    if (t == "MBoxIn") return device::SmType::MailboxIn;
    if (t == "Outputs") return device::SmType::Outputs;
    if (t == "Inputs") return device::SmType::Inputs;
    const bool mailbox = (control & 0x03) == 0x02;
    const bool write = (control & 0x0C) == 0x04;
    if (mailbox) return write ? device::SmType::MailboxOut : device::SmType::MailboxIn;
    return write ? device::SmType::Outputs : device::SmType::Inputs;
}

// How far the indexes of a module in one slot move (ETG.2000 Slots): an Index marked DependOnSlot by the
// slot's increment times its slot number, one marked DependOnSlotGroup by the group increment times its
// slot group number; PDO indexes and excludes by the PDO increments, entries and objects by the index ones.
struct SlotShift {
    std::int64_t pdo = 0;
    std::int64_t index = 0;
    std::int64_t group_pdo = 0;
    std::int64_t group_index = 0;
    std::uint16_t pdo_index(pugi::xml_node idx) const {
        return static_cast<std::uint16_t>(parse_hexdec(txt(idx)).value_or(0) +
                                          (bool_attr(idx, "DependOnSlot") ? pdo : 0) +
                                          (bool_attr(idx, "DependOnSlotGroup") ? group_pdo : 0));
    }
    std::uint16_t object_index(pugi::xml_node idx, std::int64_t base) const {
        return static_cast<std::uint16_t>(base + (bool_attr(idx, "DependOnSlot") ? index : 0) +
                                          (bool_attr(idx, "DependOnSlotGroup") ? group_index : 0));
    }
};

device::Pdo read_pdo(pugi::xml_node x, const device::DeviceDescription& d, bool rx, const SlotShift& shift) {
    device::Pdo p;
    p.index = shift.pdo_index(x.child("Index"));
    p.name = name_of(x);
    p.fixed = bool_attr(x, "Fixed");
    p.mandatory = bool_attr(x, "Mandatory");
    p.assigned = static_cast<bool>(x.attribute("Sm"));
    const auto own_sm = d.sm_index_of_type(rx ? device::SmType::Outputs : device::SmType::Inputs);
    p.sm = static_cast<std::uint8_t>(attr_or(x, "Sm", own_sm.value_or(rx ? 2 : 3)));
    for (auto ex : x.children("Exclude"))
        p.excludes.push_back(shift.pdo_index(ex));
    for (auto en : x.children("Entry")) {
        device::PdoEntry e;
        auto ei = en.child("Index");
        e.index = static_cast<std::uint16_t>(parse_hexdec(txt(ei)).value_or(0));
        if (e.index != 0) e.index = shift.object_index(ei, e.index);  // index 0: a gap, never moved
        e.subindex = static_cast<std::uint8_t>(hexdec_or(en, "SubIndex", 0));
        e.bit_length = static_cast<std::uint8_t>(en.child("BitLen").text().as_uint());
        e.name = e.index ? name_of(en) : "";
        e.type = e.index ? parse_esi_type(txt(en.child("DataType"))).value_or(DataType::Unsigned8)
                         : DataType::Unsigned8;
        p.entries.push_back(std::move(e));
    }
    p.capacity = static_cast<std::uint8_t>(p.entries.size());
    return p;
}

pugi::xml_node select_device(pugi::xml_node devices, const DeviceSelector& sel) {
    for (auto dev : devices.children("Device")) {
        auto t = dev.child("Type");
        if (sel.type && txt(t) != *sel.type) continue;
        if (sel.product_code && attr_or(t, "ProductCode", -1) != *sel.product_code) continue;
        if (sel.revision && attr_or(t, "RevisionNo", -1) != *sel.revision) continue;
        return dev;
    }
    return {};
}

// What the file has of the asked device, so that the message names what could be picked: the devices of
// the asked type or product code (all revisions), or every device when none of them matches.
std::string no_match_message(pugi::xml_node devices, const DeviceSelector& sel) {
    std::string asked;
    if (sel.type) asked += fmt::format(" type {}", *sel.type);
    if (sel.product_code) asked += fmt::format(" product code 0x{:08X}", *sel.product_code);
    if (sel.revision) asked += fmt::format(" revision 0x{:08X}", *sel.revision);
    auto line = [](pugi::xml_node t) {
        return fmt::format("{} (product code 0x{:08X}, revision 0x{:08X})", txt(t),
                           static_cast<std::uint32_t>(attr_or(t, "ProductCode", 0)),
                           static_cast<std::uint32_t>(attr_or(t, "RevisionNo", 0)));
    };
    std::vector<std::string> same, all;
    for (auto dev : devices.children("Device")) {
        auto t = dev.child("Type");
        all.push_back(line(t));
        const bool type_ok = !sel.type || txt(t) == *sel.type;
        const bool product_ok = !sel.product_code || attr_or(t, "ProductCode", -1) == *sel.product_code;
        if (type_ok && product_ok) same.push_back(line(t));
    }
    if (all.empty()) return "no Device in the ESI file";
    const bool revisions = sel.revision && !same.empty();
    return fmt::format("no Device with{} in the ESI file; {}: {}", asked,
                       revisions ? "its revisions are" : "it has", fmt::join(revisions ? same : all, ", "));
}

void load(pugi::xml_document& doc, const std::string& xml) {
    const auto r = doc.load_buffer(xml.data(), xml.size());
    if (!r) throw EsiError(fmt::format("not an XML document: {} at byte {}", r.description(), r.offset));
    if (!doc.child("EtherCATInfo")) throw EsiError("no EtherCATInfo root element");
}

const EntryDescription* find_entry(const std::vector<ObjectDescription>& objs, std::uint16_t index,
                                   std::uint8_t sub) {
    for (const auto& o : objs)
        if (o.index == index) return o.entry(sub);
    return nullptr;
}

std::uint32_t u32_of(const EntryDescription* e, std::uint32_t dflt) {
    if (!e || e->default_value.empty()) return dflt;
    std::uint32_t v = 0;
    for (std::size_t i = 0; i < e->default_value.size() && i < 4; ++i)
        v |= static_cast<std::uint32_t>(e->default_value[i]) << (8 * i);
    return v;
}

std::string string_of(const EntryDescription* e, const std::string& dflt) {
    if (!e || e->default_value.empty()) return dflt;
    return std::string(e->default_value.begin(), e->default_value.end());
}

// Modular devices (ETG.2000 Slots / Modules) ---------------------------------------------------------------

std::uint32_t module_ident(pugi::xml_node module) {
    return static_cast<std::uint32_t>(attr_or(module.child("Type"), "ModuleIdent", 0));
}

std::string module_label(pugi::xml_node module) {
    return fmt::format("\"{}\" (ModuleIdent 0x{:X})", txt(module.child("Type")), module_ident(module));
}

// "0x110", "#x110", "272": a ModuleIdent as a network file or an ESI file writes it.
std::optional<std::int64_t> parse_ident(const std::string& s) {
    const auto v = s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')
                       ? parse_hexdec("#x" + s.substr(2))
                       : parse_hexdec(s);
    if (!v || *v < 0 || *v > 0xFFFFFFFF) return std::nullopt;  // a ModuleIdent is an UDINT (0xF050)
    return v;
}

// The Module of the file a choice names: by its Type text (which must be unique), else by its ModuleIdent.
pugi::xml_node find_module(pugi::xml_node modules, const std::string& choice, std::size_t entry) {
    std::vector<pugi::xml_node> by_type;
    for (auto m : modules.children("Module"))
        if (txt(m.child("Type")) == choice) by_type.push_back(m);
    if (by_type.size() == 1) return by_type.front();
    if (by_type.size() > 1) {
        std::vector<std::string> idents;
        for (auto m : by_type)
            idents.push_back(fmt::format("0x{:X}", module_ident(m)));
        throw ModuleError(entry, fmt::format("{} modules have the Type \"{}\" (ModuleIdent {}): give the "
                                             "ModuleIdent",
                                             by_type.size(), choice, fmt::join(idents, ", ")));
    }
    if (const auto ident = parse_ident(choice))
        for (auto m : modules.children("Module"))
            if (attr_or(m.child("Type"), "ModuleIdent", -1) == *ident) return m;
    std::vector<std::string> all;
    for (auto m : modules.children("Module"))
        all.push_back(module_label(m));
    throw ModuleError(
        entry, fmt::format("unknown module \"{}\"; the file has {}", choice,
                           all.empty() ? std::string("no Module") : fmt::format("{}", fmt::join(all, ", "))));
}

// ETG.2000 SlotType: a slot lists the modules it takes by ModuleIdent or by ModuleClass (the Class the
// Module's Type names).
bool slot_accepts(pugi::xml_node slot, pugi::xml_node module) {
    bool listed = false;
    for (auto mi : slot.children("ModuleIdent")) {
        listed = true;
        if (parse_hexdec(txt(mi)) == static_cast<std::int64_t>(module_ident(module))) return true;
    }
    const std::string cls = trim(module.child("Type").attribute("ModuleClass").as_string());
    for (auto mc : slot.children("ModuleClass")) {
        listed = true;
        if (!cls.empty() && txt(mc.child("Class")) == cls) return true;
    }
    return !listed;
}

std::string slot_offer(pugi::xml_node slot) {
    std::vector<std::string> what;
    for (auto mi : slot.children("ModuleIdent"))
        what.push_back(fmt::format("ModuleIdent {}", txt(mi)));
    for (auto mc : slot.children("ModuleClass"))
        what.push_back(fmt::format("ModuleClass {}", txt(mc.child("Class"))));
    return fmt::format("{}", fmt::join(what, ", "));
}

std::string slot_label(pugi::xml_node slot, int no) {
    const std::string n = name_of(slot);
    return n.empty() ? fmt::format("slot {}", no + 1) : fmt::format("slot {} \"{}\"", no + 1, n);
}

// The Module of the file whose Type has this ModuleIdent text (none: no such Module, or no number).
pugi::xml_node module_with_ident(pugi::xml_node modules, const std::string& ident_text) {
    const auto want = parse_hexdec(ident_text);
    for (auto m : modules.children("Module"))
        if (want && attr_or(m.child("Type"), "ModuleIdent", -1) == *want) return m;
    return {};
}

// The default module of a slot (ETG.2000 SlotType): the ModuleIdent of the Slot's Default attribute (a slot
// of ModuleClass entries names its default so), else its ModuleIdent with Default, else its first one.
pugi::xml_node default_module(pugi::xml_node slot, pugi::xml_node modules, std::string& ident_text) {
    if (const auto a = slot.attribute("Default")) {
        ident_text = trim(a.as_string());
        return module_with_ident(modules, ident_text);
    }
    pugi::xml_node ident;
    for (auto mi : slot.children("ModuleIdent"))
        if (bool_attr(mi, "Default")) ident = mi;
    if (!ident) ident = slot.child("ModuleIdent");
    ident_text = txt(ident);
    return module_with_ident(modules, ident_text);
}

// ETG.2000 SlotType Fallback: the module "automatically plugged when no other module is plugged to this
// slot" (none: the slot can stay empty). A Fallback that names no Module of the file refuses the file.
pugi::xml_node fallback_module(pugi::xml_node slot, pugi::xml_node modules) {
    const auto a = slot.attribute("Fallback");
    if (!a) return {};
    const auto m = module_with_ident(modules, trim(a.as_string()));
    if (!m)
        throw EsiError(fmt::format("Slot \"{}\": Fallback {} names no Module of the file", name_of(slot),
                                   trim(a.as_string())));
    return m;
}

// The objects of a module's own dictionary (Module/Profile/Dictionary), their DependOnSlot and
// DependOnSlotGroup indexes moved by the slot's shift. Data types come from the module's dictionary, then the
// device's.
void read_module_objects(pugi::xml_node module, pugi::xml_node device_dict, const SlotShift& shift,
                         std::vector<ObjectDescription>& out, std::vector<std::string>& notes) {
    pugi::xml_node md;
    for (auto p : module.children("Profile"))
        if (!md) md = p.child("Dictionary");
    if (!md) return;
    Dictionary dict;
    for (auto src : {md, device_dict})
        for (auto dt : src.child("DataTypes").children("DataType"))
            dict.types.emplace(txt(dt.child("Name")), dt);
    for (auto x : md.child("Objects").children("Object")) {
        auto o = read_object(dict, x, notes);
        if (!o) continue;
        o->index = shift.object_index(x.child("Index"), o->index);
        out.push_back(std::move(*o));
    }
}

// One slot of the device: a Slot element repeats from MinInstances to MaxInstances times (ETG.2000 SlotType),
// each instance one slot with its number (from 0, in the order of the Slot elements and their instances).
struct SlotPosition {
    pugi::xml_node slot;    // its Slot element
    pugi::xml_node module;  // none: empty
    bool chosen = false;    // from DeviceSelector::modules, not the Slot's default
    std::string why_empty;  // a Slot without its default module: what it lacks (with a Fallback: why it
                            // took that instead)
    bool fallback = false;  // the Slot's Fallback module, in a slot that would be empty
};

// A Slot's own increment, else the one of Slots (ETG.2000: the Slot's attribute overrides Slots').
std::int64_t increment(pugi::xml_node slot, pugi::xml_node slots, const char* name) {
    return attr_or(slot, name, attr_or(slots, name, 0));
}

// The entries of DeviceSelector::modules a Slot element takes, from `entry` on: the modules it takes while it
// has fewer than MaxInstances; `empty` as its first entry plugs the Slot's Fallback module, or without one
// leaves it empty (one empty slot, MinInstances 0).
// Appends its slots to `out` and moves `entry` past the entries taken. full_note: why the previous Slot took
// no more (it is full), for the message of a refused entry.
void take_entries(pugi::xml_node slot, pugi::xml_node modules,
                  const std::vector<std::optional<std::string>>& list, std::size_t& entry,
                  std::vector<SlotPosition>& out, std::string& full_note) {
    const auto min = attr_or(slot, "MinInstances", 1);
    const auto max = attr_or(slot, "MaxInstances", 1);
    const auto label = [&](std::size_t n) { return slot_label(slot, static_cast<int>(n)); };
    std::int64_t taken = 0;
    while (entry < list.size() && taken < max) {
        const std::size_t no = out.size();
        if (!list[entry]) {
            if (taken > 0) break;  // the next Slot's entry
            if (const auto fb = fallback_module(slot, modules)) {
                // Not empty after all: the Fallback module is plugged (an instance like any other).
                out.push_back({slot, fb, true, "the list leaves it empty", true});
                ++entry;
                ++taken;
                full_note.clear();
                continue;
            }
            if (min != 0)
                throw ModuleError(entry, fmt::format("{} cannot stay empty (MinInstances {})", label(no),
                                                     trim(slot.attribute("MinInstances").as_string("1"))));
            out.push_back({slot, {}, true, {}});
            ++entry;
            full_note.clear();
            return;
        }
        const auto module = find_module(modules, *list[entry], entry);
        if (!slot_accepts(slot, module)) {
            if (taken > 0 && taken >= min) break;  // the next Slot's entry
            std::string why = taken > 0 ? fmt::format(
                                              "{} does not take module {} and the Slot has {} of at "
                                              "least {} instances (MinInstances); it takes {}",
                                              label(no), module_label(module), taken, min, slot_offer(slot))
                                        : fmt::format("{} does not take module {}; it takes {}", label(no),
                                                      module_label(module), slot_offer(slot));
            throw ModuleError(entry, why + full_note);
        }
        out.push_back({slot, module, true, {}});
        ++entry;
        ++taken;
        full_note.clear();
    }
    if (taken < min)
        throw ModuleError(entry - 1, fmt::format("{} module{} for the Slot \"{}\", which takes at least {} "
                                                 "(MinInstances)",
                                                 taken, taken == 1 ? "" : "s", name_of(slot), min));
    full_note = taken == max && max > 1
                    ? fmt::format("; the Slot \"{}\" takes at most {} (MaxInstances)", name_of(slot), max)
                    : std::string();
}

// The slots of a modular device: each its chosen (or default) module's PDOs and objects, their DependOnSlot
// indexes moved by slot number n (from 0) times the increments (the Slot's SlotPdoIncrement and
// SlotIndexIncrement, else those of Slots), their DependOnSlotGroup indexes by the Slot's SlotGroup number
// times the group increments (SlotGroupPdoIncrement, SlotGroupIndexIncrement, the Slot's else Slots'), and
// its ModuleIdent in d.module_idents. Returns the modules' objects. A refused choice throws ModuleError.
std::vector<ObjectDescription> read_slots(pugi::xml_node dev, pugi::xml_node modules,
                                          pugi::xml_node device_dict, const DeviceSelector& sel,
                                          device::DeviceDescription& d, std::vector<std::string>& notes) {
    std::vector<ObjectDescription> objects;
    const auto slots = dev.child("Slots");
    std::vector<pugi::xml_node> slot_nodes;
    for (auto slot : slots.children("Slot"))
        slot_nodes.push_back(slot);
    if (sel.modules && slot_nodes.empty())
        throw ModuleError(std::nullopt,
                          "the device has no slots (no Slots element): modules: is for modular devices");
    std::int64_t most = 0;  // the slots the Slot elements can make
    for (auto slot : slot_nodes) {
        const auto min = attr_or(slot, "MinInstances", 1);
        const auto max = attr_or(slot, "MaxInstances", 1);
        if (min < 0 || max < 1 || max < min)
            throw EsiError(
                fmt::format("Slot \"{}\": MinInstances {} and MaxInstances {} (ETG.2000: 0 <= "
                            "MinInstances <= MaxInstances, MaxInstances >= 1)",
                            name_of(slot), min, max));
        most += max;
        fallback_module(slot, modules);  // a Fallback that names no Module refuses the file, used or not
    }
    // The slots: the Slot elements in order, each taking entries of the list; after the list (or without
    // one) each Slot its default module MinInstances times (at least once; the Slot's Default, else the
    // first ModuleIdent or the Default one; none: its Fallback module, else one empty slot).
    std::vector<SlotPosition> positions;
    std::size_t entry = 0;
    std::string full_note;
    for (auto slot : slot_nodes) {
        if (sel.modules && entry < sel.modules->size()) {
            take_entries(slot, modules, *sel.modules, entry, positions, full_note);
            continue;
        }
        std::string ident;
        const auto module = default_module(slot, modules, ident);
        const auto n = std::max<std::int64_t>(1, attr_or(slot, "MinInstances", 1));
        for (std::int64_t k = 0; k < n; ++k) {
            if (!module) {
                const std::string why = ident.empty()
                                            ? fmt::format("no default module (it takes {})", slot_offer(slot))
                                            : fmt::format("default module {} not found", ident);
                if (const auto fb = fallback_module(slot, modules)) {
                    positions.push_back({slot, fb, false, why, true});
                    if (positions.size() > protocol::obj::modular_device::max_slots) break;
                    continue;
                }
                positions.push_back({slot, {}, false, why});
                break;  // one empty slot stands for the Slot
            }
            positions.push_back({slot, module, false, {}});
            if (positions.size() > protocol::obj::modular_device::max_slots) break;
        }
    }
    if (sel.modules && entry < sel.modules->size())
        throw ModuleError(entry, fmt::format("{} modules for {} slot{}{}{}", sel.modules->size(),
                                             slot_nodes.size(), slot_nodes.size() == 1 ? "" : "s",
                                             most > static_cast<std::int64_t>(slot_nodes.size())
                                                 ? fmt::format(", which take at most {} (MaxInstances)", most)
                                                 : std::string(),
                                             full_note));
    const auto max_count = attr_or(slots, "MaxSlotCount", 0);
    if (max_count > 0 && static_cast<std::int64_t>(positions.size()) > max_count) {
        const auto why = fmt::format("{} slots: the device has at most {} (Slots MaxSlotCount)",
                                     positions.size(), max_count);
        if (!sel.modules) throw EsiError(why);  // its default modules alone are too many
        // The entry of the first slot too many, or the last one when the defaults after the list are.
        throw ModuleError(std::min(static_cast<std::size_t>(max_count), sel.modules->size() - 1), why);
    }
    if (positions.size() > protocol::obj::modular_device::max_slots)
        throw EsiError(fmt::format("{} slots: the module ident lists have room for {}", positions.size(),
                                   protocol::obj::modular_device::max_slots));
    for (std::size_t i = 0; i < positions.size(); ++i) {
        const auto& pos = positions[i];
        const int no = static_cast<int>(i);
        if (!pos.module) {
            notes.push_back(pos.chosen
                                ? fmt::format("{}: empty", slot_label(pos.slot, no))
                                : fmt::format("{}: {}, empty", slot_label(pos.slot, no), pos.why_empty));
            d.module_idents.push_back(0);
            continue;
        }
        const auto group = attr_or(pos.slot, "SlotGroup", 0);
        SlotShift shift;
        shift.pdo = increment(pos.slot, slots, "SlotPdoIncrement") * no;
        shift.index = increment(pos.slot, slots, "SlotIndexIncrement") * no;
        shift.group_pdo = increment(pos.slot, slots, "SlotGroupPdoIncrement") * group;
        shift.group_index = increment(pos.slot, slots, "SlotGroupIndexIncrement") * group;
        for (auto p : pos.module.children("RxPdo"))
            d.rx_pdos.push_back(read_pdo(p, d, true, shift));
        for (auto p : pos.module.children("TxPdo"))
            d.tx_pdos.push_back(read_pdo(p, d, false, shift));
        read_module_objects(pos.module, device_dict, shift, objects, notes);
        d.module_idents.push_back(module_ident(pos.module));
        if (pos.fallback)
            notes.push_back(fmt::format("{}: {}, fallback module {} (Slot Fallback)",
                                        slot_label(pos.slot, no), pos.why_empty, module_label(pos.module)));
        else
            notes.push_back(fmt::format("{}: {} module {}", slot_label(pos.slot, no),
                                        pos.chosen ? "chosen" : "default", module_label(pos.module)));
    }
    return objects;
}

}  // namespace

std::optional<std::int64_t> parse_hexdec(const std::string& s0) {
    const std::string s = trim(s0);
    if (s.empty()) return std::nullopt;
    try {
        std::size_t used = 0;
        std::int64_t v;
        if (s.size() > 2 && s[0] == '#' && (s[1] == 'x' || s[1] == 'X')) {
            v = static_cast<std::int64_t>(std::stoull(s.substr(2), &used, 16));
            used += 2;
        } else {
            v = std::stoll(s, &used, 10);
        }
        if (used != s.size()) return std::nullopt;
        return v;
    } catch (const std::exception&) {
        return std::nullopt;
    }
}

std::optional<DataType> parse_esi_type(const std::string& name0) {
    const std::string name = trim(name0);
    static const std::map<std::string, DataType> names = {
        {"BOOL", DataType::Boolean},
        {"BIT", DataType::Boolean},
        {"BIT1", DataType::Boolean},
        {"SINT", DataType::Integer8},
        {"INT", DataType::Integer16},
        {"INT24", DataType::Integer24},
        {"DINT", DataType::Integer32},
        {"LINT", DataType::Integer64},
        {"USINT", DataType::Unsigned8},
        {"BYTE", DataType::Unsigned8},
        {"UINT", DataType::Unsigned16},
        {"WORD", DataType::Unsigned16},
        {"UINT24", DataType::Unsigned24},
        {"UDINT", DataType::Unsigned32},
        {"DWORD", DataType::Unsigned32},
        {"ULINT", DataType::Unsigned64},
        {"REAL", DataType::Real32},
        {"LREAL", DataType::Real64},
        {"STRING", DataType::VisibleString},
        {"OCTET_STRING", DataType::OctetString},
        {"UNICODE_STRING", DataType::UnicodeString},
        {"DOMAIN", DataType::Domain},
    };
    std::string base = name;
    if (auto p = name.find('('); p != std::string::npos) base = name.substr(0, p);
    if (auto it = names.find(base); it != names.end()) return it->second;
    if (base.rfind("BIT", 0) == 0 || base.rfind("BITARR", 0) == 0) return DataType::Unsigned8;
    if (base.rfind("ARRAY [", 0) == 0 && base.find("OF BYTE") != std::string::npos)
        return DataType::OctetString;
    return std::nullopt;
}

std::vector<DeviceSummary> list_devices_text(const std::string& xml) {
    pugi::xml_document doc;
    load(doc, xml);
    std::vector<DeviceSummary> out;
    for (auto dev : doc.child("EtherCATInfo").child("Descriptions").child("Devices").children("Device")) {
        auto t = dev.child("Type");
        out.push_back({txt(t), name_of(dev), static_cast<std::uint32_t>(attr_or(t, "ProductCode", 0)),
                       static_cast<std::uint32_t>(attr_or(t, "RevisionNo", 0))});
    }
    return out;
}

ImportResult import_esi_text(const std::string& xml, const DeviceSelector& sel) {
    namespace mp = device::mbx_proto;
    namespace cd = device::coe_details;
    pugi::xml_document doc;
    load(doc, xml);
    const auto root = doc.child("EtherCATInfo");
    const auto descs = root.child("Descriptions");
    const auto dev = select_device(descs.child("Devices"), sel);
    if (!dev) throw EsiError(no_match_message(descs.child("Devices"), sel));

    ImportResult r;
    auto& d = r.desc;
    auto& notes = r.notes;
    d.identity.vendor_id = static_cast<std::uint32_t>(hexdec_or(root.child("Vendor"), "Id", 0));
    d.vendor_name = name_of(root.child("Vendor"));
    const auto type = dev.child("Type");
    d.identity.product_code = static_cast<std::uint32_t>(attr_or(type, "ProductCode", 0));
    d.identity.revision = static_cast<std::uint32_t>(attr_or(type, "RevisionNo", 0));
    d.identity.serial = 0;
    d.order_code = txt(type);
    d.name = name_of(dev);
    d.group_type = txt(dev.child("GroupType"));
    for (auto g : descs.child("Groups").children("Group"))
        if (txt(g.child("Type")) == d.group_type) d.group_name = name_of(g);
    d.ebus_current_ma =
        static_cast<std::int16_t>(hexdec_or(dev.child("Info").child("Electrical"), "EBusCurrent", 0));

    pugi::xml_node dict_node;
    d.profile_no = 0;
    for (auto p : dev.children("Profile")) {
        if (d.profile_no == 0) {
            if (p.child("ProfileNo"))
                d.profile_no = p.child("ProfileNo").text().as_uint();
            else if (p.child("ChannelInfo"))
                d.profile_no = p.child("ChannelInfo").child("ProfileNo").text().as_uint();
        }
        if (!dict_node && p.child("Dictionary")) dict_node = p.child("Dictionary");
        if (p.child("DictionaryFile"))
            notes.push_back("Profile refers to a DictionaryFile, which is not read");
    }

    for (auto f : dev.children("Fmmu")) {
        const std::string t = txt(f);
        d.fmmus.push_back(t == "Outputs"     ? device::FmmuUsage::Outputs
                          : t == "Inputs"    ? device::FmmuUsage::Inputs
                          : t == "MBoxState" ? device::FmmuUsage::MailboxState
                                             : device::FmmuUsage::Unused);
    }
    for (auto s : dev.children("Sm")) {
        device::SyncManagerConfig c;
        c.start = static_cast<std::uint16_t>(attr_or(s, "StartAddress", 0));
        c.control = static_cast<std::uint8_t>(attr_or(s, "ControlByte", 0));
        // Enable is the SII byte; Virtual and OpOnly are its bits 2 and 3 (ETG.2000 Sm, ETG.2010 SyncM).
        c.enable = static_cast<std::uint8_t>(attr_or(s, "Enable", 0));
        if (bool_attr(s, "Virtual")) c.enable |= device::sm_enable::Virtual;
        if (bool_attr(s, "OpOnly")) c.enable |= device::sm_enable::OpOnly;
        c.length = static_cast<std::uint16_t>(
            attr_or(s, "DefaultSize", attr_or(s, "MaxSize", attr_or(s, "MinSize", 0))));
        c.type = sm_type(txt(s), c.control);
        d.sync_managers.push_back(c);
    }
    // An ESC has at most 16 SyncManagers and 16 FMMUs: the rest of a longer list does not exist.
    if (d.sync_managers.size() > protocol::kMaxSms) {
        notes.push_back(fmt::format("{} Sm elements: an ESC has {} SyncManagers, the rest is left out",
                                    d.sync_managers.size(), protocol::kMaxSms));
        d.sync_managers.resize(protocol::kMaxSms);
    }
    if (d.fmmus.size() > protocol::kMaxFmmus) {
        notes.push_back(fmt::format("{} Fmmu elements: an ESC has {} FMMUs, the rest is left out",
                                    d.fmmus.size(), protocol::kMaxFmmus));
        d.fmmus.resize(protocol::kMaxFmmus);
    }

    for (auto p : dev.children("RxPdo"))
        d.rx_pdos.push_back(read_pdo(p, d, true, {}));
    for (auto p : dev.children("TxPdo"))
        d.tx_pdos.push_back(read_pdo(p, d, false, {}));
    // Modular devices: the module in each slot brings its PDOs and objects.
    auto module_objects = read_slots(dev, descs.child("Modules"), dict_node, sel, d, notes);

    d.mailbox_protocols = 0;
    d.coe_details = 0;
    if (auto mbx = dev.child("Mailbox")) {
        if (mbx.child("AoE")) d.mailbox_protocols |= mp::AoE;
        if (mbx.child("EoE")) {
            d.mailbox_protocols |= mp::EoE;
            d.eoe_details = device::eoe_details::Enable;  // ETG.2000: the SII General EoE details of <EoE>
        }
        if (mbx.child("FoE")) {
            d.mailbox_protocols |= mp::FoE;
            d.foe_details = device::foe_details::Enable;  // ETG.2000: the SII General FoE details of <FoE>
        }
        if (mbx.child("SoE")) d.mailbox_protocols |= mp::SoE;
        if (mbx.child("VoE")) d.mailbox_protocols |= mp::VoE;
        if (auto coe = mbx.child("CoE")) {
            d.mailbox_protocols |= mp::CoE;
            d.coe_details = cd::Sdo;
            if (bool_attr(coe, "SdoInfo")) d.coe_details |= cd::SdoInfo;
            if (bool_attr(coe, "PdoAssign")) d.coe_details |= cd::PdoAssign;
            if (bool_attr(coe, "PdoConfig")) d.coe_details |= cd::PdoConfig;
            if (bool_attr(coe, "PdoUpload")) d.coe_details |= cd::Upload;
            if (bool_attr(coe, "CompleteAccess")) d.coe_details |= cd::CompleteAccess;
        }
    }

    for (auto om : dev.child("Dc").children("OpMode")) {
        device::DcOpMode m;
        m.name = txt(om.child("Name"));
        m.description = txt(om.child("Desc"));
        m.assign_activate = static_cast<std::uint16_t>(hexdec_or(om, "AssignActivate", 0));
        m.cycle_time0 = static_cast<std::uint32_t>(hexdec_or(om, "CycleTimeSync0", 0));
        m.sync0_cycle_factor = static_cast<std::int16_t>(attr_or(om.child("CycleTimeSync0"), "Factor", 1));
        m.shift_time0 = static_cast<std::uint32_t>(hexdec_or(om, "ShiftTimeSync0", 0));
        m.sync1_cycle_factor = static_cast<std::int16_t>(attr_or(om.child("CycleTimeSync1"), "Factor", 0));
        m.shift_time1 = static_cast<std::uint32_t>(hexdec_or(om, "ShiftTimeSync1", 0));
        d.dc_modes.push_back(m);
    }

    if (auto ee = dev.child("Eeprom")) {
        // ESC register 0x0502 bit 7: 1 or 2 address bytes, EEPROMs of 1 kbit up to 4 Mbit.
        constexpr std::int64_t kMaxEepromBytes = 4 * 1024 * 1024 / 8;
        const std::int64_t bytes = hexdec_or(ee, "ByteSize", d.eeprom_size_bytes);
        if (bytes <= 0 || bytes > kMaxEepromBytes)
            throw EsiError(
                fmt::format("Eeprom ByteSize {}: an ESC addresses EEPROMs of 1 to {} bytes (4 Mbit)", bytes,
                            kMaxEepromBytes));
        d.eeprom_size_bytes = static_cast<std::uint32_t>(bytes);
        const auto cfg = parse_hex_bytes(txt(ee.child("ConfigData")));
        auto w = [&](unsigned i) -> std::uint16_t {
            return 2 * i + 1 < cfg.size() ? static_cast<std::uint16_t>(cfg[2 * i] | cfg[2 * i + 1] << 8) : 0;
        };
        if (cfg.size() >= 2) d.pdi_control = w(0);
        if (cfg.size() >= 4) d.pdi_config = w(1);
        if (cfg.size() >= 6) d.sync_impulse_len = w(2);
        if (cfg.size() >= 10) d.station_alias = w(4);
        if (w(3) != 0)
            notes.push_back(fmt::format("ConfigData word 3 (PDI config 2) 0x{:04X} is not kept", w(3)));
        d.bootstrap_supported = static_cast<bool>(ee.child("BootStrap"));
        // BootStrap: 8 bytes, the SII words 0x14-0x17 (receive mailbox offset and size, send mailbox offset
        // and size).
        const auto bs = parse_hex_bytes(txt(ee.child("BootStrap")));
        if (bs.size() >= 8)
            d.boot_mailbox = {ld_le16(&bs[0]), ld_le16(&bs[2]), ld_le16(&bs[4]), ld_le16(&bs[6])};
        if (ee.child("Data"))
            notes.push_back("Eeprom Data (a complete image) is not used; the SII is generated");
    }

    // The dictionary: the communication area is generated from the fields above; values the file gives
    // for it (device type, versions, serial, mapping capacity, cycle times) are taken over.
    if (dict_node) {
        auto dict = read_dictionary(dict_node, notes);
        const auto& objs = dict.objects;
        d.device_type = u32_of(find_entry(objs, 0x1000, 0), d.profile_no);
        d.hardware_version = string_of(find_entry(objs, 0x1009, 0), "");
        d.software_version = string_of(find_entry(objs, 0x100A, 0), "");
        d.identity.serial = u32_of(find_entry(objs, 0x1018, 4), 0);
        if (auto* e = find_entry(objs, 0x1C32, 5)) d.min_cycle_time_ns = u32_of(e, d.min_cycle_time_ns);
        if (auto* e = find_entry(objs, 0x1C32, 6)) d.calc_copy_time_ns = u32_of(e, d.calc_copy_time_ns);
        for (auto* list : {&d.rx_pdos, &d.tx_pdos})
            for (auto& p : *list)
                for (const auto& o : objs)
                    if (o.index == p.index) p.capacity = std::max<std::uint8_t>(p.capacity, o.max_subindex());
        device::DeviceDescription bare = d;
        bare.objects.clear();
        std::set<std::uint16_t> generated;
        for (const auto& o : device::dictionary_objects(bare))
            generated.insert(o.index);
        for (const auto& o : objs) {
            const bool comm_generated = generated.count(o.index) || (o.index >= 0x1600 && o.index < 0x1800) ||
                                        (o.index >= 0x1A00 && o.index < 0x1C00) ||
                                        (o.index >= 0x1C00 && o.index < 0x1C40);
            if (!comm_generated) d.objects.push_back(o);
        }
    } else {
        d.device_type = d.profile_no;
        notes.push_back("no Dictionary: only the communication area is emulated");
    }
    // The modules' own objects: one of the index of a device object replaces it (ETG.2000 Object Index
    // OverwrittenByModule); the communication area stays generated.
    for (auto& o : module_objects) {
        if (protocol::obj::communication_area.contains(o.index)) {
            notes.push_back(fmt::format(
                "module object 0x{:04X}: in the communication area, which is generated", o.index));
            continue;
        }
        auto it = std::find_if(d.objects.begin(), d.objects.end(),
                               [&](const ObjectDescription& x) { return x.index == o.index; });
        if (it != d.objects.end())
            *it = std::move(o);
        else
            d.objects.push_back(std::move(o));
    }
    if (d.profile_no == 0) d.profile_no = d.device_type & 0xFFFF;

    // Process data SyncManager lengths follow the default PDO assignment.
    for (auto& s : d.sync_managers) {
        unsigned want = 0;
        if (s.type == device::SmType::Outputs)
            want = d.output_bytes();
        else if (s.type == device::SmType::Inputs)
            want = d.input_bytes();
        else
            continue;
        if (s.length != want)
            notes.push_back(
                fmt::format("Sm at 0x{:04X}: DefaultSize {} replaced by {} bytes of the default PDOs",
                            s.start, s.length, want));
        s.length = static_cast<std::uint16_t>(want);
    }
    // The generated SII must fit the EEPROM: a too small ByteSize grows to the next power of two.
    for (;;) {
        try {
            (void)esc::build_sii_image(d);
            break;
        } catch (const std::length_error&) {
            if (d.eeprom_size_bytes >= 65536) throw EsiError("the SII image does not fit 64 KiB");
            const auto grown = std::max<std::uint32_t>(128, d.eeprom_size_bytes * 2);
            notes.push_back(fmt::format("Eeprom ByteSize {} too small for the generated SII; {} used",
                                        d.eeprom_size_bytes, grown));
            d.eeprom_size_bytes = grown;
        }
    }
    return r;
}

std::vector<std::string> complete_for_emulation(device::DeviceDescription& d) {
    std::vector<std::string> out;
    for (bool rx : {true, false}) {
        const std::uint16_t map_bit = rx ? acc::RxPdoMappable : acc::TxPdoMappable;
        for (const auto& p : rx ? d.rx_pdos : d.tx_pdos) {
            for (const auto& pe : p.entries) {
                if (pe.index == 0) continue;
                auto it = std::find_if(d.objects.begin(), d.objects.end(),
                                       [&](const ObjectDescription& o) { return o.index == pe.index; });
                if (it == d.objects.end()) {
                    ObjectDescription o;
                    o.index = pe.index;
                    o.name = pe.name.empty() ? fmt::format("Object 0x{:04X}", pe.index) : pe.name;
                    o.type = pe.type;
                    o.code = pe.subindex == 0 ? ObjectCode::Var : ObjectCode::Record;
                    if (pe.subindex != 0)
                        o.entries.push_back(
                            device::make_entry(0, "Number of entries", DataType::Unsigned8, acc::RO, 0));
                    d.objects.push_back(std::move(o));
                    it = std::prev(d.objects.end());
                    out.push_back(fmt::format("object 0x{:04X} added: {} maps it", pe.index,
                                              fmt::format("PDO 0x{:04X}", p.index)));
                }
                auto& o = *it;
                auto* e = const_cast<EntryDescription*>(o.entry(pe.subindex));
                if (!e) {
                    EntryDescription ne;
                    ne.subindex = pe.subindex;
                    ne.name = pe.name;
                    ne.type = pe.type;
                    ne.bit_length = pe.bit_length;
                    ne.access = rx ? acc::RxMap : acc::TxMap;
                    ne.default_value = device::encode_integer(pe.type, 0);
                    ne.default_value.resize((pe.bit_length + 7) / 8, 0);
                    o.entries.push_back(std::move(ne));
                    std::sort(o.entries.begin(), o.entries.end(),
                              [](const EntryDescription& a, const EntryDescription& b) {
                                  return a.subindex < b.subindex;
                              });
                    if (o.code != ObjectCode::Var && !o.entries.empty() && o.entries.front().subindex == 0)
                        o.entries.front().default_value = {o.max_subindex()};
                    out.push_back(fmt::format("0x{:04X}:{} added: PDO 0x{:04X} maps it", pe.index,
                                              pe.subindex, p.index));
                    continue;
                }
                if (!(e->access & map_bit)) {
                    e->access |= map_bit;
                    if (rx) e->access |= acc::WriteAll;
                    out.push_back(fmt::format("0x{:04X}:{} marked {}-mappable: PDO 0x{:04X} maps it",
                                              pe.index, pe.subindex, rx ? "Rx" : "Tx", p.index));
                }
                if (e->bit_length != pe.bit_length)
                    out.push_back(fmt::format("0x{:04X}:{} has {} bits, PDO 0x{:04X} maps {}", pe.index,
                                              pe.subindex, e->bit_length, p.index, pe.bit_length));
            }
        }
    }
    return out;
}

ImportResult import_esi_file(const std::string& path, const DeviceSelector& sel) {
    std::string why;
    const auto text = read_whole_file(path, kMaxXmlFileBytes, why);
    if (!text) throw EsiError(why);  // the callers name the file
    return import_esi_text(*text, sel);
}

}  // namespace vecat::esi
