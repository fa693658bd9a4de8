#include "device/device_description.hpp"

#include "device/hiwin_d2.hpp"
#include "protocol/cia402_objects.hpp"

namespace vecat::device {
namespace {

unsigned assigned_bytes(const std::vector<Pdo>& pdos) {
    unsigned bits = 0;
    for (const auto& p : pdos)
        if (p.assigned) bits += p.bit_length();
    return (bits + 7) / 8;
}

}  // namespace

unsigned DeviceDescription::output_bytes() const {
    return assigned_bytes(rx_pdos);
}
unsigned DeviceDescription::input_bytes() const {
    return assigned_bytes(tx_pdos);
}

const SyncManagerConfig* DeviceDescription::sm_of_type(SmType t) const {
    for (const auto& s : sync_managers)
        if (s.type == t) return &s;
    return nullptr;
}

std::optional<BootMailbox> DeviceDescription::bootstrap_mailbox() const {
    const auto* out = sm_of_type(SmType::MailboxOut);
    const auto* in = sm_of_type(SmType::MailboxIn);
    if (!bootstrap_supported || !out || !in) return std::nullopt;
    BootMailbox b = boot_mailbox;
    if (b.out_length == 0) {
        b.out_start = out->start;
        b.out_length = out->length;
    }
    if (b.in_length == 0) {
        b.in_start = in->start;
        b.in_length = in->length;
    }
    return b;
}

std::optional<unsigned> DeviceDescription::sm_index_of_type(SmType t) const {
    for (unsigned i = 0; i < sync_managers.size(); ++i)
        if (sync_managers[i].type == t) return i;
    return std::nullopt;
}

DeviceDescription default_drive() {
    DeviceDescription d;
    // 0x00000A3C is not an ETG-assigned vendor ID of any real company we know of; it marks vecat devices.
    d.identity = {0x00000A3C, 0x00000402, 0x00010000, 0x00000001};
    d.vendor_name = "vecat";
    d.name = "vecat CiA402 servo drive";
    d.order_code = "VECAT-SD402";
    d.group_type = "ServoDrives";
    d.group_name = "Servo drives";
    // CoE, FoE with the BOOT state (firmware update, src/foe/README.md), and EoE (src/eoe/README.md): servo
    // drives of this class carry an Ethernet channel for their commissioning tools (the Elmo Gold and
    // Inovance SV660N ESIs in ../shared/data/esi declare <EoE>).
    d.mailbox_protocols = mbx_proto::CoE | mbx_proto::FoE | mbx_proto::EoE;
    d.foe_details = foe_details::Enable;
    d.eoe_details = eoe_details::Enable;
    d.bootstrap_supported = true;
    // The bootstrap mailbox is the standard one (boot_mailbox left 0). A master must disable SM0/SM1 before
    // it can move them (ESC datasheet: the SyncManager configuration is locked while enabled), which SOEM's
    // firm_update sample does not do (SOEM pull request #483): with the same mailbox it works unmodified.
    d.coe_details = coe_details::Sdo | coe_details::SdoInfo | coe_details::PdoAssign |
                    coe_details::PdoConfig | coe_details::CompleteAccess;
    d.ebus_current_ma = 0;

    // SyncManager layout of the HIWIN D2 (drive guide, section 4): mailbox at 0x1800/0x18F6, process
    // data at 0x1000/0x1100.
    d.sync_managers = hiwin::sync_managers();
    d.fmmus = {FmmuUsage::Outputs, FmmuUsage::Inputs, FmmuUsage::MailboxState};

    using DT = DataType;
    namespace obj = protocol::obj;
    d.rx_pdos = {Pdo{0x1600,
                     "RxPDO 1 (CSP/CSV/CST)",
                     2,
                     false,
                     false,
                     true,
                     {
                         pdo_entry(obj::controlword, "Controlword"),
                         pdo_entry(obj::modes_of_operation, "Modes of operation"),
                         {0x0000, 0, 8, DT::Unsigned8, ""},
                         pdo_entry(obj::target_position, "Target position"),
                         pdo_entry(obj::target_velocity, "Target velocity"),
                         pdo_entry(obj::target_torque, "Target torque"),
                         pdo_entry(obj::touch_probe_function, "Touch probe function"),
                     },
                     16,
                     {0x1601}},
                 Pdo{0x1601,
                     "RxPDO 2 (PP/PV)",
                     2,
                     false,
                     false,
                     false,
                     {
                         pdo_entry(obj::controlword, "Controlword"),
                         pdo_entry(obj::target_position, "Target position"),
                         pdo_entry(obj::profile_velocity, "Profile velocity"),
                     },
                     16,
                     {0x1600}},
                 Pdo{0x1602, "RxPDO 3", 2, false, false, false, {}, 16, {}},
                 Pdo{0x1603, "RxPDO 4", 2, false, false, false, {}, 16, {}}};
    d.tx_pdos = {Pdo{0x1A00,
                     "TxPDO 1 (CSP/CSV/CST)",
                     3,
                     false,
                     false,
                     true,
                     {
                         pdo_entry(obj::statusword, "Statusword"),
                         pdo_entry(obj::modes_of_operation_display, "Modes of operation display"),
                         {0x0000, 0, 8, DT::Unsigned8, ""},
                         pdo_entry(obj::position_actual_value, "Position actual value"),
                         pdo_entry(obj::velocity_actual_value, "Velocity actual value"),
                         pdo_entry(obj::torque_actual_value, "Torque actual value"),
                         pdo_entry(obj::following_error_actual_value, "Following error actual value"),
                         pdo_entry(obj::digital_inputs, "Digital inputs"),
                         pdo_entry(obj::touch_probe_status, "Touch probe status"),
                         pdo_entry(obj::touch_probe_1_positive_value, "Touch probe 1 positive value"),
                     },
                     16,
                     {0x1A01}},
                 Pdo{0x1A01,
                     "TxPDO 2 (PP/PV)",
                     3,
                     false,
                     false,
                     false,
                     {
                         pdo_entry(obj::statusword, "Statusword"),
                         pdo_entry(obj::position_actual_value, "Position actual value"),
                     },
                     16,
                     {0x1A00}},
                 Pdo{0x1A02, "TxPDO 3", 3, false, false, false, {}, 16, {}},
                 Pdo{0x1A03, "TxPDO 4", 3, false, false, false, {}, 16, {}}};
    d.sync_managers[2].length = static_cast<std::uint16_t>(d.output_bytes());
    d.sync_managers[3].length = static_cast<std::uint16_t>(d.input_bytes());

    d.dc_modes = {
        DcOpMode{"FreeRun", "Free run (no synchronisation)", 0x0000, 0, 0, 0, 0, 0},
        DcOpMode{"SM-Synchron", "SM-synchronous", 0x0000, 0, 0, 0, 0, 0},
        DcOpMode{"DC", "DC SYNC0", 0x0300, 1000000, 0, 0, 1, 0},
    };
    d.objects = cia402_drive_objects();
    for (auto& o : twinsync_objects())
        d.objects.push_back(std::move(o));
    return d;
}

std::optional<DeviceDescription> builtin_drive(std::string_view name) {
    if (name == "drive") return default_drive();
    if (name == "hiwin-d2") return hiwin_d2();
    return std::nullopt;
}

std::vector<std::string_view> builtin_drive_names() {
    return {"drive", "hiwin-d2"};
}

std::optional<std::string_view> adopt_builtin_rules(DeviceDescription& d) {
    for (std::string_view name : builtin_drive_names()) {
        const DeviceDescription b = *builtin_drive(name);
        // (The vecat drive's rules are every description's defaults.)
        if (b.drive_variant == DriveVariant::Vecat || b.identity.vendor_id != d.identity.vendor_id ||
            b.identity.product_code != d.identity.product_code)
            continue;
        d.drive_variant = b.drive_variant;
        d.pdo_remapping = b.pdo_remapping;
        d.pdo_assign_slots = b.pdo_assign_slots;
        for (auto* list : {&d.rx_pdos, &d.tx_pdos})
            for (auto& p : *list)
                for (const auto& q : list == &d.rx_pdos ? b.rx_pdos : b.tx_pdos)
                    if (q.index == p.index) p.max_entries = q.max_entries;
        return name;
    }
    return std::nullopt;
}

}  // namespace vecat::device
