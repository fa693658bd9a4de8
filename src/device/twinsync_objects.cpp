// The TWINsync option's parameters as CoE objects (drive parameter Pnnnn = object 0x2000 + nnnn, names as
// in the MSD specification CB08759-001), and vecat's own TWINsync objects 0x2102-0x2104. Their behaviour
// lives in src/twinsync (the port) and src/cia402 (the drive).
#include "device/device_description.hpp"
#include "twinsync/parameters.hpp"

namespace vecat::device {
namespace {

using DT = DataType;
namespace tp = twinsync::p;

constexpr std::uint16_t RW = access::RW;
constexpr std::uint16_t RO = access::RO;
constexpr std::uint16_t RWT = access::RW | access::TxPdoMappable;  // received values: readable in a TxPDO
constexpr std::uint16_t ROT = access::TxMap;

std::uint16_t ix(std::uint16_t parameter) {
    return twinsync::object_index(parameter);
}

std::string pname(std::uint16_t parameter, const char* name) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "P%04u ", parameter);
    return std::string(buf) + name;
}

ObjectDescription var(std::uint16_t parameter, const char* name, DT t, std::uint16_t acc,
                      std::int64_t def = 0) {
    return make_var(ix(parameter), pname(parameter, name), t, acc, def);
}

ObjectDescription ranged(std::uint16_t parameter, const char* name, DT t, std::uint16_t acc, std::int64_t def,
                         std::int64_t min, std::int64_t max) {
    auto o = var(parameter, name, t, acc, def);
    set_range(o.entries[0], min, max);
    return o;
}

ObjectDescription real(std::uint16_t parameter, const char* name, std::uint16_t acc, double def = 0) {
    auto o = var(parameter, name, DT::Real32, acc);
    o.entries[0].default_value = encode_real(DT::Real32, def);
    return o;
}

EntryDescription real_entry(std::uint8_t sub, const char* name, std::uint16_t acc, double def) {
    auto e = make_entry(sub, name, DT::Real32, acc);
    e.default_value = encode_real(DT::Real32, def);
    return e;
}

}  // namespace

std::vector<ObjectDescription> twinsync_objects() {
    std::vector<ObjectDescription> o;
    // General drive parameters the TWINsync operation modes use. The specification names P0149, P0301,
    // P0507, P0520 and P0521 with the values its tables require and nothing more (no type, unit, default
    // or range): vecat's choices are listed in src/twinsync/README.md, "Parameters the specification only
    // names".
    // P0149 MPRO_DRVCOM_Init (4.1.2): writing 1 forces an initialisation of the TWINsync communication;
    // it reads 0 again once done.
    o.push_back(
        ranged(tp::DriveComInit, "MPRO_DRVCOM_Init (1 = initialise TWINsync)", DT::Unsigned16, RW, 0, 0, 1));
    o.push_back(
        ranged(tp::ControlSelector, "MPRO_CTRL_SEL (0 EtherCAT, 10 TWINSYNC)", DT::Unsigned16, RW, 0, 0, 10));
    o.push_back(
        ranged(tp::SetpointSelector, "MPRO_REF_SEL (0 EtherCAT, 11 TWINSYNC)", DT::Unsigned16, RW, 0, 0, 11));
    o.push_back(
        ranged(tp::LocalResolution, "Resolution factor (local)", DT::Unsigned32, RW, 1, 1, 0x7FFFFFFF));
    o.push_back(real(tp::SpeedActualRpm, "Speed actual value (rpm)", ROT));
    o.push_back(ranged(tp::ControlMode, "CON_CfgCon (1 TCON, 2 SCON, 3 PCON)", DT::Unsigned16, RW, 3, 1, 3));
    o.push_back(ranged(tp::SetpointMode, "Setpoint mode (1 IP-Mode)", DT::Unsigned16, RW,
                       twinsync::kSetpointModeIp, 0, 1));
    o.push_back(ranged(tp::SwitchingFrequency, "CON_SwitchFreq (0 2k, 1 4k, 2 6k, 3 8k, 4 12k, 5 16kHz)",
                       DT::Unsigned16, RW, 1, 0, 5));
    o.push_back(var(tp::PositionActual, "Position actual value", DT::Integer32, ROT));
    // Tables 6.1 / 6.2: the virtual encoder of TWD V1 and VE on the slave (channel 3 = TWINSYNC, used for
    // commutation and speed control). Stored and reported; vecat's motor model has no encoder channels.
    o.push_back(ranged(tp::EncoderChannel3, "Selector for encoder channel 3 (6 TWINSYNC)", DT::Unsigned16, RW,
                       0, 0, twinsync::kEncoderChannel3Twinsync));
    o.push_back(ranged(tp::CommutationEncoder, "Encoder for commutation (3 CH3)", DT::Unsigned16, RW, 1, 0,
                       twinsync::kEncoderCh3));
    o.push_back(ranged(tp::SpeedEncoder, "Encoder for speed control (3 CH3)", DT::Unsigned16, RW, 1, 0,
                       twinsync::kEncoderCh3));
    o.push_back(
        var(tp::GantryPositionLimit, "Max. position tracking error (gantry)", DT::Unsigned32, RW, 50000));
    o.push_back(real(tp::SpeedSetpointRpm, "Speed set-point (rpm)", ROT));
    o.push_back(var(tp::TorqueActualScaled, "Torque actual value (scaled)", DT::Integer16, ROT));

    // The TWINsync option (chapter 4 and 6).
    o.push_back(ranged(tp::Setting, "MPRO_TWIN_Setting", DT::Unsigned8, RW, 0, 0, 34));
    // Table 6.10 (VE slave): the filter time of the master's torque set-point, a first-order lag; 0 = none.
    o.push_back(real(tp::MasterTorqueTF, "MPRO_TWIN_MasterTorqueTF (ms)", RW, 0.0));
    o.push_back(ranged(tp::SlaveInverted, "MPRO_TWIN_SlaveInverted", DT::Integer16, RW, 1, -1, 1));
    o.push_back(real(tp::SpeedUp, "MPRO_TWIN_SpeedUp (%)", RW));
    o.push_back(real(tp::SpeedUpMinimum, "MPRO_TWIN_SpeedUpMin (rpm)", RW));
    o.push_back(real(tp::ActSpeedMaster, "MPRO_TWIN_ActSpeedMaster (rpm)", RWT));
    o.push_back(real(tp::GantrySpeedLimit, "Max. speed tracking error (gantry, rpm)", RW, 300.0));
    o.push_back(var(tp::LocalRefTorque, "MPRO_TWIN_LocalRefTorque", DT::Integer16, ROT));
    o.push_back(var(tp::LocalActTorque, "MPRO_TWIN_LocalActTorque", DT::Integer16, ROT));
    o.push_back(var(tp::LocalRefSpeed, "MPRO_TWIN_LocalRefSpeed", DT::Integer16, ROT));
    o.push_back(var(tp::LocalActSpeed, "MPRO_TWIN_LocalActSpeed", DT::Integer16, ROT));
    o.push_back(var(tp::LocalRefPos, "MPRO_TWIN_LocalRefPos", DT::Integer32, ROT));
    o.push_back(var(tp::LocalActPos, "MPRO_TWIN_LocalActPos", DT::Integer32, ROT));
    o.push_back(make_record(ix(tp::LocalScaling), pname(tp::LocalScaling, "MPRO_TWIN_LocalScaling"),
                            {real_entry(1, "MPRO_TWIN_LocalScalingTorque (Nm)", RW, 5.0),
                             real_entry(2, "MPRO_TWIN_LocalScalingSpeed (rpm)", RW, 5000.0)}));
    o.push_back(var(tp::RemoteRefTorque, "MPRO_TWIN_RemoteRefTorque", DT::Integer16, RWT));
    o.push_back(var(tp::RemoteActTorque, "MPRO_TWIN_RemoteActTorque", DT::Integer16, RWT));
    o.push_back(var(tp::RemoteRefSpeed, "MPRO_TWIN_RemoteRefSpeed", DT::Integer16, RWT));
    o.push_back(var(tp::RemoteActSpeed, "MPRO_TWIN_RemoteActSpeed", DT::Integer16, RWT));
    o.push_back(var(tp::RemoteRefPos, "MPRO_TWIN_RemoteRefPos", DT::Integer32, RWT));
    o.push_back(var(tp::RemoteActPos, "MPRO_TWIN_RemoteActPos", DT::Integer32, RWT));
    o.push_back(make_record(ix(tp::RemoteScaling), pname(tp::RemoteScaling, "MPRO_TWIN_RemoteScaling"),
                            {real_entry(1, "MPRO_TWIN_RemoteScalingTorque (Nm)", RW, 5.0),
                             real_entry(2, "MPRO_TWIN_RemoteScalingSpeed (rpm)", RW, 5000.0),
                             real_entry(3, "MPRO_TWIN_RemoteScaleCurrent (100 mA)", RW, 90.0)}));
    o.push_back(var(tp::SlaveCtrlWord, "MPRO_TWIN_SlaveCtrlWord", DT::Unsigned16, ROT));
    o.push_back(var(tp::SlaveStatus, "MPRO_TWIN_SlaveStatus", DT::Unsigned16, ROT));
    o.push_back(real(tp::MaxFaultTime, "TOPT_TWIN_MaxFaultTime (ms)", RW, 10.0));
    o.push_back(ranged(tp::Mode, "TOPT_TWIN_Mode (0 OFF, 1 SLAVE, 2 MASTER)", DT::Unsigned16, RW, 0, 0, 2));
    o.push_back(make_array(ix(tp::ProcessSendData), pname(tp::ProcessSendData, "TOPT_TWIN_ProcessSendData"),
                           DT::Unsigned32, RW, std::vector<std::int64_t>(8, 0)));
    o.push_back(make_array(ix(tp::ProcessReceiveData),
                           pname(tp::ProcessReceiveData, "TOPT_TWIN_ProcessReceiveData"), DT::Unsigned32, RW,
                           std::vector<std::int64_t>(8, 0)));
    o.push_back(var(tp::Statusword, "TOPT_TWIN_Statusword", DT::Unsigned16, ROT));
    o.push_back(var(tp::SyncTicks, "TOPT_TWIN_SyncTicks", DT::Integer16, RW, 20));
    // Table 4.1: bit 0 "no error", also before the link runs.
    o.push_back(
        var(tp::CommStatus, "TOPT_TWIN_CommStatus", DT::Unsigned16, ROT, twinsync::comm_status::NoError));
    o.push_back(real(tp::SystemLoad, "TOPT_TWIN_SystemLoad (ns)", RO));
    o.push_back(make_array(ix(tp::CurrentError), pname(tp::CurrentError, "Current error (number, location)"),
                           DT::Unsigned16, ROT, {0, 0}));
    o.push_back(var(tp::Config, "TOPT_TWIN_Config", DT::Unsigned32, RW));
    o.push_back(
        ranged(tp::RemoteResolution, "Resolution factor (master)", DT::Unsigned32, RW, 1, 1, 0x7FFFFFFF));
    // The coupling factor of a PCON slave may arrive cyclically (TwinCAT NC's cyclic slave axis, TX1250
    // 3.3; smoothed by AccBound 0x2115): the numerator is RxPDO-mappable, the denominator its scale.
    o.push_back(
        var(tp::GearNumerator, "Electronic gear numerator", DT::Integer32, RW | access::RxPdoMappable, 1));
    o.push_back(
        ranged(tp::GearDenominator, "Electronic gear denominator", DT::Integer32, RW, 1, 1, 0x7FFFFFFF));
    // Section 4.1.6 / table 4.7: P2609[2], the partner's reference current, is "see P2697[2]": this
    // drive's reference current (100 mA). The specification names no other element; [0] and [1] are kept
    // so that element 2 is subindex 3, as everywhere else.
    o.push_back(
        make_record(ix(tp::ReferenceValues), pname(tp::ReferenceValues, "Reference values"),
                    {real_entry(1, "Element 0 (not described by the TWINsync specification)", RW, 0.0),
                     real_entry(2, "Element 1 (not described by the TWINsync specification)", RW, 0.0),
                     real_entry(3, "Reference current (100 mA)", RW, 90.0)}));
    o.push_back(var(tp::RemoteAcc, "MPRO_TWIN_RemoteAcc", DT::Integer16, RWT));
    o.push_back(ranged(tp::SyncSel, "TOPT_TWIN_SyncSel", DT::Unsigned16, RW, 0, 0, 3));
    o.push_back(var(tp::LocalRefFFSpeed, "MPRO_TWIN_LocalRefFFISpeed", DT::Integer16, ROT));
    {
        auto r = make_array(ix(tp::PhyLinkConfig), pname(tp::PhyLinkConfig, "TOPT_TWIN_PhyLinkConfig"),
                            DT::Unsigned16, RW, {0, 0});
        r.entries[1].name = "Baud rate (0 4M, 1 2M, 2 1M, 3 800k, 4 500k, 5 400k, 6 250k)";
        r.entries[2].name = "Frame size";
        set_range(r.entries[1], 0, 6);
        set_range(r.entries[2], 0, 13);
        o.push_back(r);
    }
    o.push_back(
        var(tp::LocalActEps, "Local position actual value (single-turn, 16 bit)", DT::Unsigned16, ROT));
    o.push_back(var(tp::RemoteActEps, "RemoteActEps (single-turn, 16 bit)", DT::Unsigned16, RWT));

    // vecat's own: why the last TWINsync configuration was refused, the gantry torque monitoring (39-01)
    // and the fault injection of the cable.
    {
        auto s = make_string_var(0x2102, "TWINsync message", "");
        s.entries[0].bit_length = 8 * 200;
        o.push_back(s);
    }
    o.push_back(var(0x2103, "TWINsync torque difference limit (0.1 %, 0 = off)", DT::Unsigned16, RW, 0));
    o.push_back(make_record(
        0x2104, "TWINsync fault injection",
        {make_entry(1, "Cable break", DT::Unsigned8, RW, 0), make_entry(2, "Sync loss", DT::Unsigned8, RW, 0),
         make_entry(3, "Corrupt next frames", DT::Unsigned32, RW, 0),
         make_entry(4, "Drop next frames", DT::Unsigned32, RW, 0),
         make_entry(5, "Corrupted frames per million", DT::Unsigned32, RW, 0),
         make_entry(6, "Dropped frames per million", DT::Unsigned32, RW, 0)}));
    return o;
}

}  // namespace vecat::device
