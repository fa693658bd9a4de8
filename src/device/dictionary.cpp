// The communication area of the object dictionary (CiA 301, ETG.1000.6 5.6.7, ETG.1020), generated from
// the device description so that it always agrees with the SII and the ESI file.
#include <algorithm>

#include "device/device_description.hpp"

namespace vecat::device {
namespace {

namespace obj = protocol::obj;

std::uint32_t mapping_value(const PdoEntry& e) {
    return (static_cast<std::uint32_t>(e.index) << 16) | (static_cast<std::uint32_t>(e.subindex) << 8) |
           e.bit_length;
}

ObjectDescription pdo_mapping_object(const Pdo& p, bool rx) {
    ObjectDescription o;
    o.index = p.index;
    o.name = p.name.empty() ? (rx ? "RxPDO mapping" : "TxPDO mapping") : p.name;
    o.code = ObjectCode::Record;
    o.type = DataType::PdoMapping;
    const std::uint16_t acc = p.fixed ? access::RO : access::RWPreop;
    const auto capacity = std::max<std::size_t>(p.entries.size(), p.capacity);
    o.entries.push_back(make_entry(0, "Number of entries", DataType::Unsigned8, acc,
                                   static_cast<std::int64_t>(p.entries.size())));
    auto& sub0 = o.entries.back();
    set_range(
        sub0, 0,
        static_cast<std::int64_t>(p.max_entries ? std::min<std::size_t>(p.max_entries, capacity) : capacity));
    for (std::size_t i = 0; i < capacity; ++i) {
        const std::uint32_t v = i < p.entries.size() ? mapping_value(p.entries[i]) : 0;
        o.entries.push_back(make_entry(static_cast<std::uint8_t>(i + 1),
                                       subindex_name(static_cast<unsigned>(i + 1)), DataType::Unsigned32, acc,
                                       v));
    }
    return o;
}

// slots: its subindexes (0: one per PDO).
ObjectDescription pdo_assign_object(std::uint16_t index, const std::vector<Pdo>& pdos, const char* name,
                                    std::size_t slots) {
    ObjectDescription o;
    o.index = index;
    o.name = name;
    o.code = ObjectCode::Array;
    o.type = DataType::Unsigned16;
    bool any_free = false;
    std::vector<std::uint16_t> assigned;
    for (const auto& p : pdos) {
        if (p.assigned) assigned.push_back(p.index);
        if (!p.fixed || !p.mandatory) any_free = true;
    }
    const std::uint16_t acc = any_free ? access::RWPreop : access::RO;
    o.entries.push_back(make_entry(0, "Number of assigned PDOs", DataType::Unsigned8, acc,
                                   static_cast<std::int64_t>(assigned.size())));
    const std::size_t n = slots ? std::max(slots, assigned.size()) : pdos.size();
    set_range(o.entries.back(), 0, static_cast<std::int64_t>(n));
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint16_t v = i < assigned.size() ? assigned[i] : 0;
        o.entries.push_back(make_entry(static_cast<std::uint8_t>(i + 1),
                                       subindex_name(static_cast<unsigned>(i + 1)), DataType::Unsigned16, acc,
                                       v));
    }
    return o;
}

// 0x1C32 / 0x1C33: SM output / input parameter (ETG.1020 21.1).
ObjectDescription sync_parameter_object(std::uint16_t index, const DeviceDescription& d, bool outputs) {
    using DT = DataType;
    bool dc = false;
    for (const auto& m : d.dc_modes)
        if (m.assign_activate != 0) dc = true;
    // Bit 0 free run, bit 1 SM-synchronous, bits 2..4 = 001: DC SYNC0 (ETG.1020 Table 80).
    const std::uint16_t supported = static_cast<std::uint16_t>(0x0003 | (dc ? 0x0004 : 0));
    // Default synchronisation: with the SM2 event (0x1C33 reports 0x22 "synchronous with SM2 event").
    const std::int64_t mode = outputs ? 0x0001 : 0x0022;
    namespace sp = obj::sync_parameter;
    std::vector<EntryDescription> subs;
    subs.push_back(make_entry(sp::sync_mode, "Sync mode", DT::Unsigned16, access::RWPreop, mode));
    subs.push_back(make_entry(sp::cycle_time, "Cycle time", DT::Unsigned32, access::RWPreop, 1'000'000));
    subs.push_back(make_entry(sp::shift_time, "Shift time", DT::Unsigned32, access::RO, 0));
    subs.push_back(
        make_entry(sp::sync_modes_supported, "Sync modes supported", DT::Unsigned16, access::RO, supported));
    subs.push_back(make_entry(sp::minimum_cycle_time, "Minimum cycle time", DT::Unsigned32, access::RO,
                              d.min_cycle_time_ns));
    subs.push_back(make_entry(sp::calc_and_copy_time, "Calc and copy time", DT::Unsigned32, access::RO,
                              d.calc_copy_time_ns));
    subs.push_back(make_entry(sp::minimum_delay_time, "Minimum delay time", DT::Unsigned32, access::RO, 0));
    subs.push_back(make_entry(sp::get_cycle_time, "Get cycle time", DT::Unsigned16, access::RW, 0));
    subs.push_back(make_entry(sp::delay_time, "Delay time", DT::Unsigned32, access::RO, 0));
    subs.push_back(make_entry(sp::sync0_cycle_time, "Sync0 cycle time", DT::Unsigned32, access::RW, 0));
    subs.push_back(make_entry(sp::sm_event_missed, "SM event missed", DT::Unsigned16, access::RO, 0));
    subs.push_back(
        make_entry(sp::cycle_time_too_small, "Cycle time too small", DT::Unsigned16, access::RO, 0));
    subs.push_back(
        make_entry(sp::shift_time_too_short, "Shift time too short", DT::Unsigned16, access::RO, 0));
    subs.push_back(
        make_entry(sp::sync_error, "Sync error", DT::Boolean, access::RO | access::TxPdoMappable, 0));
    return make_record(index, outputs ? "SM output parameter" : "SM input parameter", std::move(subs),
                       DT::SyncParameter);
}

}  // namespace

std::vector<ObjectDescription> dictionary_objects(const DeviceDescription& d) {
    using DT = DataType;
    std::vector<ObjectDescription> objs;
    objs.push_back(make_var(obj::device_type, "Device type", access::RO, d.device_type));
    objs.push_back(make_var(obj::error_register, "Error register", access::RO | access::TxPdoMappable, 0));
    objs.push_back(make_string_var(obj::device_name.index, "Device name", d.name));
    objs.push_back(make_string_var(obj::hardware_version.index, "Hardware version", d.hardware_version));
    objs.push_back(make_string_var(obj::software_version.index, "Software version", d.software_version));
    // CiA 301 store parameters / restore default parameters: sub 1 all, 2 communication, 3 application,
    // 4 manufacturer area. A read gives the capability (bit 0: on command); "save" / "load" act.
    const std::vector<std::int64_t> groups = {1, 1, 1, 1};
    objs.push_back(
        make_array(obj::store_parameters::index, "Store parameters", DT::Unsigned32, access::RW, groups));
    objs.push_back(make_array(obj::restore_default_parameters::index, "Restore default parameters",
                              DT::Unsigned32, access::RW, groups));
    for (auto* o : {&objs[objs.size() - 2], &objs.back()}) {
        const char* names[] = {"All parameters", "Communication parameters", "Application parameters",
                               "Manufacturer parameters"};
        for (std::size_t i = 1; i < o->entries.size(); ++i)
            o->entries[i].name = names[i - 1];
    }
    objs.push_back(make_record(
        obj::identity::index, "Identity",
        {make_entry(obj::identity::vendor_id, "Vendor ID", access::RO, d.identity.vendor_id),
         make_entry(obj::identity::product_code, "Product code", access::RO, d.identity.product_code),
         make_entry(obj::identity::revision, "Revision", access::RO, d.identity.revision),
         make_entry(obj::identity::serial_number, "Serial number", access::RO, d.identity.serial)},
        DT::Identity));
    objs.push_back(make_record(
        obj::error_settings::index, "Error settings",
        {make_entry(obj::error_settings::local_error_reaction, "Local error reaction", access::RW, 1),
         make_entry(obj::error_settings::sync_error_counter_limit, "Sync error counter limit", access::RW,
                    4)}));
    for (const auto& p : d.rx_pdos)
        objs.push_back(pdo_mapping_object(p, true));
    for (const auto& p : d.tx_pdos)
        objs.push_back(pdo_mapping_object(p, false));

    std::vector<std::int64_t> sm_types;
    for (const auto& s : d.sync_managers)
        sm_types.push_back(static_cast<std::int64_t>(s.type));
    objs.push_back(
        make_array(obj::sync_manager_type, "Sync manager type", DT::Unsigned8, access::RO, sm_types));
    if (auto sm = d.sm_index_of_type(SmType::Outputs))
        objs.push_back(pdo_assign_object(static_cast<std::uint16_t>(obj::sm_pdo_assign_first + *sm),
                                         d.rx_pdos, "RxPDO assign", d.pdo_assign_slots));
    if (auto sm = d.sm_index_of_type(SmType::Inputs))
        objs.push_back(pdo_assign_object(static_cast<std::uint16_t>(obj::sm_pdo_assign_first + *sm),
                                         d.tx_pdos, "TxPDO assign", d.pdo_assign_slots));
    if (d.sm_index_of_type(SmType::Outputs))
        objs.push_back(sync_parameter_object(obj::sync_parameter::outputs, d, true));
    if (d.sm_index_of_type(SmType::Inputs))
        objs.push_back(sync_parameter_object(obj::sync_parameter::inputs, d, false));

    // A modular device (ETG.5001.1 device area): the ModuleIdent of each slot as it is (0xF050, read-only)
    // and as the master configures it (0xF030, writable in PREOP, subindex 0 too: 0 entries is "nothing
    // configured"). 0xF030 starts equal to 0xF050, as a device that was never configured otherwise.
    if (!d.module_idents.empty()) {
        std::vector<std::int64_t> idents(d.module_idents.begin(), d.module_idents.end());
        idents.resize(std::min(idents.size(), obj::modular_device::max_slots));
        objs.push_back(make_array(obj::modular_device::configured_module_ident_list,
                                  "Configured module ident list", DT::Unsigned32, access::RWPreop, idents,
                                  access::RWPreop));
        set_range(objs.back().entries.front(), 0, static_cast<std::int64_t>(idents.size()));
        objs.push_back(make_array(obj::modular_device::detected_module_ident_list,
                                  "Detected module ident list", DT::Unsigned32, access::RO, idents));
    }

    // Application objects; one with the index of a generated object replaces it.
    for (const auto& o : d.objects) {
        auto it = std::find_if(objs.begin(), objs.end(),
                               [&](const ObjectDescription& x) { return x.index == o.index; });
        if (it != objs.end())
            *it = o;
        else
            objs.push_back(o);
    }
    std::sort(objs.begin(), objs.end(),
              [](const ObjectDescription& a, const ObjectDescription& b) { return a.index < b.index; });
    return objs;
}

}  // namespace vecat::device
