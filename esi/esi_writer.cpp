#include "esi/esi_writer.hpp"

#include <fmt/core.h>

#include <map>
#include <pugixml.hpp>
#include <set>
#include <sstream>

#include "esc/sii_image.hpp"

namespace vecat::esi {
namespace {

using device::DataType;
using device::EntryDescription;
using device::ObjectCode;
using device::ObjectDescription;

std::string hex(std::uint32_t v, int digits) {
    return fmt::format("#x{:0{}X}", v, digits);
}

std::string hex_bytes(const std::vector<std::uint8_t>& b) {
    std::string s;
    for (auto c : b)
        s += fmt::format("{:02x}", c);
    return s;
}

void text(pugi::xml_node parent, const char* name, const std::string& value) {
    parent.append_child(name).text().set(value.c_str());
}

void text(pugi::xml_node parent, const char* name, long long value) {
    parent.append_child(name).text().set(value);
}

// Access bits of one AL state group (preop 1, safeop 2, op 4) as an ESI restriction; "" for all or none.
const char* restriction(unsigned states) {
    switch (states) {
        case 1:
            return "PreOP";
        case 2:
            return "SafeOP";
        case 4:
            return "OP";
        case 3:
            return "PreOP_SafeOP";
        case 5:
            return "PreOP_OP";
        case 6:
            return "SafeOP_OP";
        default:
            return "";
    }
}

void flags(pugi::xml_node parent, std::uint16_t acc) {
    auto f = parent.append_child("Flags");
    const unsigned r = acc & device::access::ReadAll;
    const unsigned w = (acc & device::access::WriteAll) >> 3;
    auto a = f.append_child("Access");
    a.text().set(w == 0 ? "ro" : (r == 0 ? "wo" : "rw"));
    if (*restriction(r)) a.append_attribute("ReadRestrictions").set_value(restriction(r));
    if (*restriction(w)) a.append_attribute("WriteRestrictions").set_value(restriction(w));
    const bool rx = acc & device::access::RxPdoMappable, tx = acc & device::access::TxPdoMappable;
    if (rx || tx) text(f, "PdoMapping", rx && tx ? "RT" : (rx ? "R" : "T"));
    if (acc & device::access::Backup) text(f, "Backup", 1);
    if (acc & device::access::Settings) text(f, "Setting", 1);
}

// Info of one entry: DefaultString for strings, else MinData/MaxData/DefaultData.
void entry_info(pugi::xml_node info, const EntryDescription& e) {
    if (e.type == DataType::VisibleString) {
        if (!e.default_value.empty())
            text(info, "DefaultString", std::string(e.default_value.begin(), e.default_value.end()));
        return;
    }
    if (!e.minimum.empty()) text(info, "MinData", hex_bytes(e.minimum));
    if (!e.maximum.empty()) text(info, "MaxData", hex_bytes(e.maximum));
    if (!e.default_value.empty()) text(info, "DefaultData", hex_bytes(e.default_value));
}

std::string complex_type_name(const ObjectDescription& o) {
    return fmt::format("DT{:04X}", o.index);
}

// Bit offset of each entry in the record/array layout: subindex 0 in the first byte, the rest from bit
// 16 on, entries of 8 bits and more aligned to their size (at most 16 bits), bits packed.
std::vector<unsigned> bit_offsets(const ObjectDescription& o, unsigned& total) {
    std::vector<unsigned> offs;
    unsigned pos = 0;
    for (const auto& e : o.entries) {
        if (e.subindex != 0 && pos < 16) pos = 16;
        const unsigned align = e.bit_length >= 16 ? 16 : (e.bit_length >= 8 ? 8 : 1);
        pos = (pos + align - 1) / align * align;
        offs.push_back(pos);
        pos += e.bit_length;
    }
    total = (pos + 15) / 16 * 16;
    return offs;
}

void data_types(pugi::xml_node dts, const std::vector<ObjectDescription>& objs) {
    std::map<std::string, unsigned> base;
    for (const auto& o : objs)
        for (const auto& e : o.entries)
            base.emplace(esi_type_name(e.type, e.bit_length), e.bit_length);
    for (const auto& [name, bits] : base) {
        auto dt = dts.append_child("DataType");
        text(dt, "Name", name);
        text(dt, "BitSize", bits);
    }
    for (const auto& o : objs) {
        if (o.code != ObjectCode::Array && o.code != ObjectCode::Record) continue;
        unsigned total = 0;
        const auto offs = bit_offsets(o, total);
        const std::string name = complex_type_name(o);
        if (o.code == ObjectCode::Array && o.entries.size() > 1) {
            const auto& el = o.entries[1];
            auto arr = dts.append_child("DataType");
            text(arr, "Name", name + "ARR");
            text(arr, "BaseType", esi_type_name(el.type, el.bit_length));
            text(arr, "BitSize", static_cast<long long>(el.bit_length * (o.entries.size() - 1)));
            auto ai = arr.append_child("ArrayInfo");
            text(ai, "LBound", 1);
            text(ai, "Elements", static_cast<long long>(o.entries.size() - 1));
        }
        auto dt = dts.append_child("DataType");
        text(dt, "Index", hex(static_cast<std::uint16_t>(o.type), 4));
        text(dt, "Name", name);
        text(dt, "BitSize", total);
        std::set<std::string> seen;  // SubItem names are a schema key: unique within the DataType
        for (std::size_t i = 0; i < o.entries.size(); ++i) {
            const auto& e = o.entries[i];
            const bool elements = o.code == ObjectCode::Array && i == 1;
            auto si = dt.append_child("SubItem");
            if (!elements) text(si, "SubIdx", e.subindex);
            std::string sname = elements ? std::string("Elements") : e.name;
            if (!seen.insert(sname).second) {
                sname = fmt::format("{} ({})", sname, e.subindex);
                seen.insert(sname);
            }
            text(si, "Name", sname);
            text(si, "Type", elements ? name + "ARR" : esi_type_name(e.type, e.bit_length));
            text(si, "BitSize",
                 elements ? static_cast<long long>(e.bit_length * (o.entries.size() - 1)) : e.bit_length);
            text(si, "BitOffs", offs[i]);
            flags(si, e.access);
            if (o.code == ObjectCode::Array && i >= 1) break;
        }
    }
}

void object(pugi::xml_node objs, const ObjectDescription& o) {
    auto x = objs.append_child("Object");
    text(x, "Index", hex(o.index, 4));
    text(x, "Name", o.name);
    if (o.code == ObjectCode::Array || o.code == ObjectCode::Record) {
        unsigned total = 0;
        bit_offsets(o, total);
        text(x, "Type", complex_type_name(o));
        text(x, "BitSize", total);
        auto info = x.append_child("Info");
        for (const auto& e : o.entries) {
            auto si = info.append_child("SubItem");
            text(si, "Name", e.name);
            entry_info(si.append_child("Info"), e);
        }
        if (!o.entries.empty()) flags(x, o.entries.front().access);
        return;
    }
    const auto* e = o.entry(0);
    if (!e) return;
    text(x, "Type", esi_type_name(e->type, e->bit_length));
    text(x, "BitSize", e->bit_length);
    auto info = x.append_child("Info");
    entry_info(info, *e);
    if (!info.first_child()) x.remove_child(info);
    flags(x, e->access);
}

void pdo(pugi::xml_node dev, const char* tag, const device::Pdo& p) {
    auto x = dev.append_child(tag);
    if (p.fixed) x.append_attribute("Fixed").set_value("true");
    if (p.mandatory) x.append_attribute("Mandatory").set_value("true");
    if (p.assigned) x.append_attribute("Sm").set_value(p.sm);
    text(x, "Index", hex(p.index, 4));
    text(x, "Name", p.name);
    for (auto ex : p.excludes)
        text(x, "Exclude", hex(ex, 4));
    for (const auto& e : p.entries) {
        auto en = x.append_child("Entry");
        text(en, "Index", hex(e.index, e.index ? 4 : 1));
        text(en, "SubIndex", e.subindex);
        text(en, "BitLen", e.bit_length);
        if (e.index != 0) {
            text(en, "Name", e.name);
            text(en, "DataType", esi_type_name(e.type, e.bit_length));
        }
    }
}

const char* sm_text(device::SmType t) {
    switch (t) {
        case device::SmType::MailboxOut:
            return "MBoxOut";
        case device::SmType::MailboxIn:
            return "MBoxIn";
        case device::SmType::Outputs:
            return "Outputs";
        case device::SmType::Inputs:
            return "Inputs";
        default:
            return "Unused";
    }
}

const char* fmmu_text(device::FmmuUsage u) {
    switch (u) {
        case device::FmmuUsage::Outputs:
            return "Outputs";
        case device::FmmuUsage::Inputs:
            return "Inputs";
        case device::FmmuUsage::MailboxState:
            return "MBoxState";
        default:
            return "Unused";
    }
}

}  // namespace

std::string esi_type_name(DataType t, unsigned bit_length) {
    if (device::is_variable_length(t)) return fmt::format("{}({})", device::type_name(t), bit_length / 8);
    return std::string(device::type_name(t));
}

std::string write_esi(const device::DeviceDescription& d) {
    namespace mp = device::mbx_proto;
    namespace cd = device::coe_details;
    pugi::xml_document doc;
    auto decl = doc.append_child(pugi::node_declaration);
    decl.append_attribute("version").set_value("1.0");
    decl.append_attribute("encoding").set_value("UTF-8");
    auto root = doc.append_child("EtherCATInfo");
    root.append_attribute("xmlns:xsi").set_value("http://www.w3.org/2001/XMLSchema-instance");
    root.append_attribute("xsi:noNamespaceSchemaLocation").set_value("EtherCATInfo.xsd");
    root.append_attribute("Version").set_value("1.17");

    auto vendor = root.append_child("Vendor");
    text(vendor, "Id", hex(d.identity.vendor_id, 8));
    text(vendor, "Name", d.vendor_name);

    auto descs = root.append_child("Descriptions");
    auto group = descs.append_child("Groups").append_child("Group");
    text(group, "Type", d.group_type);
    auto gname = group.append_child("Name");
    gname.append_attribute("LcId").set_value(1033);
    gname.text().set(d.group_name.c_str());

    auto dev = descs.append_child("Devices").append_child("Device");
    dev.append_attribute("Physics").set_value("YY");
    auto type = dev.append_child("Type");
    type.append_attribute("ProductCode").set_value(hex(d.identity.product_code, 8).c_str());
    type.append_attribute("RevisionNo").set_value(hex(d.identity.revision, 8).c_str());
    type.text().set(d.order_code.c_str());
    auto name = dev.append_child("Name");
    name.append_attribute("LcId").set_value(1033);
    name.text().set(d.name.c_str());
    if (d.ebus_current_ma != 0)
        text(dev.append_child("Info").append_child("Electrical"), "EBusCurrent", d.ebus_current_ma);
    text(dev, "GroupType", d.group_type);

    auto profile = dev.append_child("Profile");
    text(profile, "ProfileNo", d.profile_no);
    auto dict = profile.append_child("Dictionary");
    const auto objs = device::dictionary_objects(d);
    data_types(dict.append_child("DataTypes"), objs);
    auto objects = dict.append_child("Objects");
    for (const auto& o : objs)
        object(objects, o);

    for (auto f : d.fmmus)
        dev.append_child("Fmmu").text().set(fmmu_text(f));
    for (const auto& s : d.sync_managers) {
        auto sm = dev.append_child("Sm");
        sm.append_attribute("DefaultSize").set_value(s.length);
        sm.append_attribute("StartAddress").set_value(hex(s.start, 4).c_str());
        sm.append_attribute("ControlByte").set_value(hex(s.control, 2).c_str());
        namespace se = device::sm_enable;
        sm.append_attribute("Enable").set_value(s.enable & ~(se::Virtual | se::OpOnly));
        if (s.enable & se::Virtual) sm.append_attribute("Virtual").set_value("1");
        if (s.enable & se::OpOnly) sm.append_attribute("OpOnly").set_value("1");
        sm.text().set(sm_text(s.type));
    }
    for (const auto& p : d.rx_pdos)
        pdo(dev, "RxPdo", p);
    for (const auto& p : d.tx_pdos)
        pdo(dev, "TxPdo", p);

    if (d.mailbox_protocols != 0) {
        auto mbx = dev.append_child("Mailbox");
        if (d.mailbox_protocols & mp::AoE) mbx.append_child("AoE");
        if (d.mailbox_protocols & mp::EoE) mbx.append_child("EoE");
        if (d.mailbox_protocols & mp::CoE) {
            auto coe = mbx.append_child("CoE");
            auto flag = [&](const char* n, bool v) {
                coe.append_attribute(n).set_value(v ? "true" : "false");
            };
            flag("SdoInfo", d.coe_details & cd::SdoInfo);
            flag("PdoAssign", d.coe_details & cd::PdoAssign);
            flag("PdoConfig", d.coe_details & cd::PdoConfig);
            flag("PdoUpload", d.coe_details & cd::Upload);
            flag("CompleteAccess", d.coe_details & cd::CompleteAccess);
            flag("SegmentedSdo", true);  // the SDO server does segmented transfers in both directions
        }
        if (d.mailbox_protocols & mp::FoE) mbx.append_child("FoE");
        if (d.mailbox_protocols & mp::SoE) mbx.append_child("SoE");
        if (d.mailbox_protocols & mp::VoE) mbx.append_child("VoE");
    }

    if (!d.dc_modes.empty()) {
        auto dc = dev.append_child("Dc");
        for (const auto& m : d.dc_modes) {
            auto om = dc.append_child("OpMode");
            text(om, "Name", m.name);
            if (!m.description.empty()) text(om, "Desc", m.description);
            text(om, "AssignActivate", hex(m.assign_activate, 4));
            auto c0 = om.append_child("CycleTimeSync0");
            c0.append_attribute("Factor").set_value(m.sync0_cycle_factor);
            c0.text().set(m.cycle_time0);
            text(om, "ShiftTimeSync0", m.shift_time0);
            auto c1 = om.append_child("CycleTimeSync1");
            c1.append_attribute("Factor").set_value(m.sync1_cycle_factor);
            c1.text().set(0);
            text(om, "ShiftTimeSync1", m.shift_time1);
        }
    }

    auto ee = dev.append_child("Eeprom");
    text(ee, "ByteSize", d.eeprom_size_bytes);
    std::vector<std::uint8_t> cfg(14, 0);
    st_le16(cfg.data() + 2 * protocol::sii::PdiControl, d.pdi_control);
    st_le16(cfg.data() + 2 * protocol::sii::PdiConfig, d.pdi_config);
    st_le16(cfg.data() + 2 * protocol::sii::SyncImpulseLen, d.sync_impulse_len);
    st_le16(cfg.data() + 2 * protocol::sii::StationAlias, d.station_alias);
    text(ee, "ConfigData", hex_bytes(cfg));
    if (const auto boot = d.bootstrap_mailbox()) {
        std::vector<std::uint8_t> bs(8, 0);
        st_le16(bs.data(), boot->out_start);
        st_le16(bs.data() + 2, boot->out_length);
        st_le16(bs.data() + 4, boot->in_start);
        st_le16(bs.data() + 6, boot->in_length);
        text(ee, "BootStrap", hex_bytes(bs));
    }

    std::ostringstream os;
    doc.save(os, "\t", pugi::format_default, pugi::encoding_utf8);
    return os.str();
}

}  // namespace vecat::esi
