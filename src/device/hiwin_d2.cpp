// The HIWIN D2 CoE drive as data (HIWIN Drive User Guide with EtherCAT (CoE) Interface, sections cited
// below). Where the guide's value column says "—" it gives no default: those take the vecat drive's.
// Where two of its tables disagree, the object dictionary tables of chapter 3 win over the mode chapters
// (0x6075 UINT32 RW in 3.5, REAL32 RO in 9.3; 0x6078 INT16 in 3.5, UINT16 in 9.3), and chapter 7's default
// layout wins over 3.3's example for 0x1600 (Mode of operation is its third entry, as appendix B step 5
// forces it through RxPDO 1).
#include "device/hiwin_d2.hpp"

#include "protocol/cia402_objects.hpp"

namespace vecat::device {

namespace hiwin {

bool homing_method_supported(std::int64_t m) noexcept {
    return m == 0 || (m >= 1 && m <= 6) || m == 33 || m == 34;
}

}  // namespace hiwin

namespace {

using DT = DataType;
namespace obj = protocol::obj;
namespace a = access;

constexpr std::uint16_t RW = a::RW;
constexpr std::uint16_t RO = a::RO;
constexpr std::uint16_t RWM = a::RxMap;  // RW, PDO mapping "O"
constexpr std::uint16_t ROM = a::TxMap;  // RO, PDO mapping "O"
constexpr std::int64_t kI32Max = 2147483647;
constexpr std::int64_t kI32Min = -kI32Max - 1;

ObjectDescription real(protocol::ObjectId<DT::Real32> id, const char* name, std::uint16_t acc, double def,
                       std::optional<std::pair<double, double>> range = std::nullopt) {
    auto o = make_var(id.index, name, DT::Real32, acc);
    o.entries[0].default_value = encode_real(DT::Real32, def);
    if (range) {
        o.entries[0].minimum = encode_real(DT::Real32, range->first);
        o.entries[0].maximum = encode_real(DT::Real32, range->second);
    }
    return o;
}

ObjectDescription pair_array(std::uint16_t index, const char* name, DT t,
                             std::pair<const char*, std::int64_t> first,
                             std::pair<const char*, std::int64_t> second) {
    auto o = make_array(index, name, t, RW, {first.second, second.second});
    o.entries[0].name = "Number of entries";
    o.entries[1].name = first.first;
    o.entries[2].name = second.first;
    return o;
}

// 3.6, 3.7: the manufacturer objects.
void manufacturer_objects(std::vector<ObjectDescription>& o) {
    namespace h = hiwin;
    o.push_back(
        make_ranged_var(h::motor_type, "Motor type", RO, 2, 0, 2));  // the emulated motor: AC servo motor
    o.push_back(make_var(h::velocity_encoder_resolution, "Encoder Resolution of Velocity Loop", RO, 1 << 20));
    o.push_back(make_var(h::position_encoder_resolution, "Encoder Resolution of Position Loop", RO, 1 << 20));
    o.push_back(make_var(h::screw_pitch, "Screw Pitch", RO, 0));
    o.push_back(make_var(h::input_function, "Input Function", RWM, 0));
    o.push_back(make_var(h::index_signal, "Index Signal", RO, 0));
    o.push_back(make_var(h::latched_index_position, "Latched Index Position", ROM, 0));
    o.push_back(real(h::motor_actual_current, "Motor actual current", ROM, 0.0));
    o.push_back(make_ranged_var(h::second_encoder, "Use the 2nd linear digital encoder", RO, 0, 0, 1));
    o.push_back(make_ranged_var(h::software_limit_protection, "Enable software position limit protection", RW,
                                1, 0, 1));
    o.push_back(
        make_ranged_var(h::hardware_limit_protection, "Enable hardware limit protection", RW, 1, 0, 1));
    o.push_back(real(h::common_gain, "Common gain (CG:0.01~1.0)", RW, 0.3, std::pair{0.01, 1.0}));
    o.push_back(real(h::velocity_gain, "Velocity proportional gain", RW, 0.001));
    o.push_back(make_ranged_var(h::multi_turn_reset, "Multi turn encoder reset flag", RW, 0, 0, 2));
    o.push_back(make_var(h::error_events_1, "Drive Error Events 1", RO, 0));
    o.push_back(make_var(h::error_events_2, "Drive Error Events 2", RO, 0));
}

// 3.5 (with the defaults of 9.3 and 9.4): the CiA 402 objects in HIWIN's types.
void cia402_objects(std::vector<ObjectDescription>& o) {
    o.push_back(make_var(obj::controlword, "ControlWord", RWM));
    o.push_back(make_var(obj::statusword, "StatusWord", ROM));
    o.push_back(make_var(obj::modes_of_operation, "Mode of operation", RWM, 8));
    o.push_back(make_var(obj::modes_of_operation_display, "Mode of operation display", ROM));
    o.push_back(make_var(obj::position_actual_internal_value, "Position Actual Internal Value", ROM));
    o.push_back(make_var(obj::position_actual_value, "Position Actual Value", ROM));
    o.push_back(make_var(obj::following_error_window, "Following Error Window", RW, 100000));
    o.push_back(make_var(obj::velocity_actual_value, "Velocity Actual Value", ROM));
    o.push_back(make_ranged_var(obj::target_torque, "Target Torque", RWM, 0, -1000, 1000));
    o.push_back(make_var(obj::motor_rated_current, "Continuous Current of Motor (mA)", RW, 3000));
    o.push_back(make_var(obj::current_actual_value, "Current Feedback of Motor (0.1%)", ROM));
    o.push_back(make_var(obj::target_position, "Target Position", RWM));
    o.push_back(make_var(obj::home_offset, "Home offset", RW));
    o.push_back(pair_array(obj::software_position_limit::index, "Software Position Limit", DT::Integer32,
                           {"Minimum Position Limit", kI32Min}, {"Maximum Position Limit", kI32Max}));
    o.push_back(make_var(obj::max_profile_velocity, "Maximum Profile Velocity", RW, 10'000'000));
    o.push_back(make_var(obj::profile_velocity, "Profile Velocity", RW, 1'000'000));
    o.push_back(make_var(obj::profile_acceleration, "Profile Acceleration", RW, 10'000'000));
    o.push_back(make_var(obj::profile_deceleration, "Profile Deceleration", RW, 10'000'000));
    o.push_back(make_var(obj::quick_stop_deceleration, "Quick Stop Deceleration", RWM, 50'000'000));
    // 9.3: "The unit is 0.1%/sec ... and the default value is 1000", range 0~4294967295.
    o.push_back(make_var(obj::torque_slope, "Torque Slope", RWM, 1000));
    // 9.4: "Drive supports 8 kinds of CiA402 homing methods", value 0.
    o.push_back(make_var(hiwin::homing_method, "Homing Method", RW, 0));
    {
        auto h =
            pair_array(obj::homing_speeds::index, "Homing Speeds", DT::Unsigned32,
                       {"Speed during search for switch", 100000}, {"Speed during search for zero", 10000});
        o.push_back(h);
    }
    o.push_back(make_var(obj::homing_acceleration, "Homing Acceleration", RW, 1'000'000));
    o.push_back(make_ranged_var(obj::velocity_offset, "Velocity Offset", RWM, 0, -1000, 1000));
    o.push_back(make_ranged_var(obj::torque_offset, "Torque Offset", RWM, 0, -1000, 1000));
    o.push_back(make_var(obj::touch_probe_function, "Touch Probe Function", RWM));
    o.push_back(make_var(hiwin::touch_probe_status, "Touch Probe Status", ROM));
    o.push_back(make_var(obj::touch_probe_1_positive_value, "Touch Probe 1 Position Value", ROM));
    {
        // "Highest sub-index supported INT8 RO 1", "Interpolation time period UINT16 RW 8" (62.5 us units,
        // 9.1.2: 1 ms is 16, 500 us is 8).
        ObjectDescription r = make_record(obj::interpolation_time_period::index, "Interpolation Time Period",
                                          {make_entry(hiwin::interpolation_period.subindex,
                                                      "Interpolation time period", DT::Unsigned16, RW, 8)});
        r.entries[0] = make_entry(0, "Highest sub-index supported", DT::Integer8, RO, 1);
        o.push_back(r);
    }
    o.push_back(make_var(obj::following_error_actual_value, "Following Error Actual Value", ROM));
    o.push_back(make_var(obj::position_demand_internal_value, "Position Demand Internal Value", ROM));
    o.push_back(make_var(obj::digital_inputs, "Digital Inputs", ROM));
    o.push_back(make_var(hiwin::target_velocity, "Target Velocity", RWM));
    // "Supported Drive Mode UINT32 RO 0x3AF".
    o.push_back(make_var(obj::supported_drive_modes, "Supported Drive Mode", RO, 0x3AF));
}

}  // namespace

DeviceDescription hiwin_d2() {
    DeviceDescription d;
    // 3.2: vendor 0x0000AAAA, D2COE product code 3, revision 0, serial 0.
    d.identity = {hiwin::kVendorId, hiwin::kProductD2, 0x00000000, 0x00000000};
    d.vendor_name = "HIWIN";
    d.name = "D2 CoE Drive";  // appendix A step 7, B step 3
    d.order_code = "D2COE";   // 4: the ESI file D2COE.xml
    d.group_type = "ServoDrives";
    d.group_name = "HIWIN drives";
    d.software_version = "vecat emulation of the HIWIN D2";
    // 1: "Mailbox (CoE): SDO Request", "Dynamic PDO mapping".
    d.mailbox_protocols = mbx_proto::CoE;
    d.coe_details = coe_details::Sdo | coe_details::SdoInfo | coe_details::PdoAssign | coe_details::PdoConfig;
    d.sync_managers = hiwin::sync_managers();
    d.fmmus = {FmmuUsage::Outputs, FmmuUsage::Inputs, FmmuUsage::MailboxState};
    // 7: RxPDO mapping objects 0x1600-0x1602 and TxPDO mapping objects 0x1A00-0x1A03, six subindexes each
    // (3.3), of which "the maximum numbers of data object ... are 5"; one PDO per SyncManager (3.4).
    auto pdo = [](std::uint16_t index, const char* name, std::uint8_t sm, bool assigned,
                  std::vector<PdoEntry> entries) {
        Pdo p;
        p.index = index;
        p.name = name;
        p.sm = sm;
        p.assigned = assigned;
        p.entries = std::move(entries);
        p.capacity = 6;
        p.max_entries = 5;
        return p;
    };
    d.rx_pdos = {
        pdo(0x1600, "Receive PDO Mapping", 2, true,
            {pdo_entry(obj::controlword, "ControlWord"), pdo_entry(obj::target_position, "Target Position"),
             pdo_entry(obj::modes_of_operation, "Mode of operation")}),
        pdo(0x1601, "Receive PDO Mapping 2", 2, false, {}),
        pdo(0x1602, "Receive PDO Mapping 3", 2, false, {})};
    d.tx_pdos = {pdo(0x1A00, "Transmit PDO Mapping", 3, true,
                     {pdo_entry(obj::statusword, "StatusWord"),
                      pdo_entry(obj::position_actual_value, "Position Actual Value"),
                      pdo_entry(obj::velocity_actual_value, "Velocity Actual Value")}),
                 pdo(0x1A01, "Transmit PDO Mapping 2", 3, false, {}),
                 pdo(0x1A02, "Transmit PDO Mapping 3", 3, false, {}),
                 pdo(0x1A03, "Transmit PDO Mapping 4", 3, false, {})};
    d.pdo_assign_slots = 1;
    d.pdo_remapping = PdoRemapping::AssignmentCleared;
    d.sync_managers[2].length = static_cast<std::uint16_t>(d.output_bytes());
    d.sync_managers[3].length = static_cast<std::uint16_t>(d.input_bytes());
    // 8: free run or DC (0x0980 = 0x0300) with SYNC0 cycles of 250 us to 4 ms.
    d.dc_modes = {
        DcOpMode{"FreeRun", "Free run", 0x0000, 0, 0, 0, 0, 0},
        DcOpMode{"DC", "DC SYNC0", 0x0300, 1000000, 0, 0, 1, 0},
    };
    d.min_cycle_time_ns = 250'000;
    d.drive_variant = DriveVariant::HiwinD2;
    manufacturer_objects(d.objects);
    cia402_objects(d.objects);
    return d;
}

std::vector<SyncManagerConfig> hiwin::sync_managers() {
    return {
        {0x1800, 0x00F6, 0x26, 0x01, SmType::MailboxOut},
        {0x18F6, 0x00F6, 0x22, 0x01, SmType::MailboxIn},
        {0x1000, 0x0000, 0x64, 0x01, SmType::Outputs},
        {0x1100, 0x0000, 0x20, 0x01, SmType::Inputs},
    };
}

}  // namespace vecat::device
