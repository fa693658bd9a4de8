#include "device/from_sii.hpp"

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
    d.objects.clear();
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
