#include "device/from_sii.hpp"

#include <map>

namespace vecat::device {

namespace {

std::vector<Pdo> pdos(const std::vector<protocol::SiiPdo>& in, const protocol::SiiInfo& sii) {
    std::vector<Pdo> out;
    for (const auto& p : in) {
        Pdo d;
        d.index = p.index;
        d.name = sii.string_at(p.name_idx);
        d.sm = p.sm;
        // ETG.2010 PDO flags: bit 4 fixed content, bit 0 mandatory; a PDO without SyncManager (0xFF) is
        // not in the default assignment.
        d.fixed = (p.flags & 0x0010) != 0;
        d.mandatory = (p.flags & 0x0001) != 0;
        d.assigned = p.sm != 0xFF;
        for (const auto& e : p.entries)
            d.entries.push_back({e.index, e.subindex, e.bit_length, static_cast<DataType>(e.data_type),
                                 sii.string_at(e.name_idx)});
        d.capacity = static_cast<std::uint8_t>(d.entries.size());
        out.push_back(std::move(d));
    }
    return out;
}

// A type of the SII entry's bit length when its data type is missing or of another length (an SII may leave
// the type 0 or name a BITn type this catalogue does not list).
DataType type_for(DataType t, unsigned bits) {
    if (fixed_bit_length(t) == bits) return t;
    switch (bits) {
        case 1:
            return DataType::Boolean;
        case 16:
            return DataType::Unsigned16;
        case 24:
            return DataType::Unsigned24;
        case 32:
            return DataType::Unsigned32;
        case 64:
            return DataType::Unsigned64;
        default:
            return DataType::Unsigned8;
    }
}

// The application objects the PDOs map (ETG.2010 PDO entries: index, subindex, type, bit length, name): a
// device emulated from its SII has no other description of them, and a mapping of an object the dictionary
// lacks is invalid (0x0024/0x0025 on SAFEOP). Outputs (RxPDO) are writable, inputs (TxPDO) read-only.
std::vector<ObjectDescription> mapped_objects(const DeviceDescription& d) {
    std::map<std::uint16_t, std::map<std::uint8_t, EntryDescription>> objects;
    std::map<std::uint16_t, std::string> names;
    const auto add = [&](const std::vector<Pdo>& pdos, std::uint16_t acc) {
        for (const auto& p : pdos)
            for (const auto& e : p.entries) {
                if (e.index == 0 || e.bit_length == 0) continue;  // a gap
                if (e.index < 0x2000) continue;                   // communication area: generated
                auto& subs = objects[e.index];
                if (auto it = subs.find(e.subindex); it != subs.end()) {  // mapped both ways
                    it->second.access |= acc & (access::RxPdoMappable | access::TxPdoMappable);
                    continue;
                }
                EntryDescription ed;
                ed.subindex = e.subindex;
                ed.name = e.name.empty() ? "SubIndex " + std::to_string(e.subindex) : e.name;
                ed.type = type_for(e.type, e.bit_length);
                ed.bit_length = e.bit_length;
                ed.access = acc;
                ed.default_value.assign((e.bit_length + 7) / 8, 0);
                subs[e.subindex] = std::move(ed);
                if (!names.count(e.index)) names[e.index] = e.name.empty() ? p.name : e.name;
            }
    };
    add(d.rx_pdos, access::RxMap);
    add(d.tx_pdos, access::TxMap);
    std::vector<ObjectDescription> out;
    for (auto& [index, subs] : objects) {
        ObjectDescription o;
        o.index = index;
        o.name = names[index];
        if (subs.size() == 1 && subs.begin()->first == 0) {
            o.code = ObjectCode::Var;
            o.type = subs.begin()->second.type;
            o.entries.push_back(std::move(subs.begin()->second));
        } else {
            std::vector<EntryDescription> entries;
            for (auto& [sub, e] : subs)
                if (sub != 0) entries.push_back(std::move(e));
            o = make_record(index, names[index], std::move(entries));
        }
        out.push_back(std::move(o));
    }
    return out;
}

}  // namespace

DeviceDescription description_from_sii(const protocol::SiiInfo& sii, std::vector<std::string>* notes) {
    DeviceDescription d;
    d.identity = sii.identity;
    d.vendor_name = "";
    d.name = sii.device_name().empty() ? "SII device" : sii.device_name();
    d.order_code = sii.string_at(sii.order_idx);
    d.group_type = sii.string_at(sii.group_idx);
    d.profile_no = 0;
    d.device_type = 0;
    d.pdi_control = sii.pdi_control;
    d.station_alias = sii.station_alias;
    d.mailbox_protocols = sii.mailbox_protocols;
    d.coe_details = sii.coe_details;
    d.foe_details = sii.foe_details;
    d.eoe_details = sii.eoe_details;
    d.bootstrap_supported = sii.boot_rx_mbx_size != 0 && sii.boot_tx_mbx_size != 0;
    d.boot_mailbox = {sii.boot_rx_mbx_offset, sii.boot_rx_mbx_size, sii.boot_tx_mbx_offset,
                      sii.boot_tx_mbx_size};
    d.general_flags = sii.flags;
    d.ebus_current_ma = sii.ebus_current;
    d.sync_managers.clear();
    for (const auto& s : sii.sync_managers)
        d.sync_managers.push_back(
            {s.start, s.length, s.control, s.enable, static_cast<SmType>(s.type <= 4 ? s.type : 0)});
    d.fmmus.clear();
    for (std::uint8_t f : sii.fmmus)
        d.fmmus.push_back(static_cast<FmmuUsage>(f <= 3 ? f : 0));
    d.rx_pdos = pdos(sii.rx_pdos, sii);
    d.tx_pdos = pdos(sii.tx_pdos, sii);
    d.dc_modes = sii.dc_modes;
    d.objects = mapped_objects(d);
    if (notes) {
        for (const auto& e : sii.errors)
            notes->push_back("SII: " + e);
        for (std::size_t i = 0; i < d.sync_managers.size(); ++i) {
            const auto t = d.sync_managers[i].type;
            if (t != SmType::Outputs && t != SmType::Inputs) continue;
            const auto& list = t == SmType::Outputs ? d.rx_pdos : d.tx_pdos;
            bool any = false;
            for (const auto& p : list)
                any |= p.sm == i;
            if (!any)
                notes->push_back(
                    "SM" + std::to_string(i) + " (" + (t == SmType::Outputs ? "outputs" : "inputs") +
                    ") has no PDO in the SII: its process data have the SyncManager's default length");
        }
    }
    return d;
}

}  // namespace vecat::device
