// The CiA 402 (IEC 61800-7-201) objects of the vecat drive, as described data. Their behaviour lives in
// src/cia402; this file only says which objects exist, their types, access, limits and defaults.
#include "device/device_description.hpp"

namespace vecat::device {
namespace {

using DT = DataType;

ObjectDescription var(std::uint16_t index, const char* name, DT t, std::uint16_t acc, std::int64_t def = 0) {
    return make_var(index, name, t, acc, def);
}

ObjectDescription ranged(std::uint16_t index, const char* name, DT t, std::uint16_t acc, std::int64_t def,
                         std::int64_t min, std::int64_t max) {
    auto o = make_var(index, name, t, acc, def);
    set_range(o.entries[0], min, max);
    return o;
}

ObjectDescription named_array(std::uint16_t index, const char* name, DT t, std::uint16_t acc,
                              std::vector<std::pair<const char*, std::int64_t>> elems) {
    std::vector<std::int64_t> defs;
    for (const auto& e : elems)
        defs.push_back(e.second);
    auto o = make_array(index, name, t, acc, defs);
    for (std::size_t i = 0; i < elems.size(); ++i)
        o.entries[i + 1].name = elems[i].first;
    return o;
}

}  // namespace

std::vector<ObjectDescription> cia402_drive_objects() {
    namespace a = access;
    constexpr std::uint16_t RW = a::RW;
    constexpr std::uint16_t RWM = a::RxMap;  // read/write, RxPDO-mappable
    constexpr std::uint16_t ROM = a::TxMap;  // read-only, TxPDO-mappable
    constexpr std::int64_t kI32Max = 2147483647;
    constexpr std::int64_t kI32Min = -kI32Max - 1;
    std::vector<ObjectDescription> o;

    // Manufacturer area: the simulated motor and a few diagnostic values.
    o.push_back(make_record(0x2000, "Motor parameters",
                            {make_entry(1, "Rated speed (rpm)", DT::Unsigned32, RW, 3000),
                             make_entry(2, "Rotor inertia (g cm2)", DT::Unsigned32, RW, 120),
                             make_entry(3, "Torque constant (mNm/A)", DT::Unsigned32, RW, 600),
                             make_entry(4, "Load inertia (g cm2)", DT::Unsigned32, RW, 240),
                             make_entry(5, "Viscous friction (uNm s/rad)", DT::Unsigned32, RW, 50),
                             make_entry(6, "Coulomb friction (mNm)", DT::Unsigned32, RW, 10),
                             make_entry(7, "Peak current (mA)", DT::Unsigned32, RW, 9000)}));
    // Gains of the cascaded loops; 0 = tuned from the motor parameters when the drive is enabled.
    o.push_back(make_record(0x2003, "Control loop gains",
                            {make_entry(1, "Position loop gain (0.01/s)", DT::Unsigned32, RW, 0),
                             make_entry(2, "Velocity loop gain (uNm s/rad)", DT::Unsigned32, RW, 0),
                             make_entry(3, "Velocity loop integral time (us)", DT::Unsigned32, RW, 0),
                             make_entry(4, "Current loop bandwidth (rad/s)", DT::Unsigned32, RW, 0)}));
    // The simulated machine around the motor: switches (in increments of the machine position, which
    // homing does not move), the index pulse, an external load, the touch probe inputs.
    {
        auto r = make_record(0x2100, "Simulated machine",
                             {make_entry(1, "Negative limit switch (inc)", DT::Integer32, RW, -(100ll << 20)),
                              make_entry(2, "Positive limit switch (inc)", DT::Integer32, RW, 100ll << 20),
                              make_entry(3, "Home switch (inc)", DT::Integer32, RW, 5ll << 20),
                              make_entry(4, "Index pulse offset (inc)", DT::Integer32, RW, 0),
                              make_entry(5, "Load torque (0.1 %)", DT::Integer16, RWM, 0),
                              make_entry(6, "Touch probe inputs", DT::Unsigned8, RWM, 0),
                              make_entry(7, "Limit switch reaction", DT::Unsigned8, RW, 0)});
        set_range(r.entries[7], 0, 1);
        o.push_back(r);
    }
    // Fault injection: the 0x603F code of a fault condition to simulate (0 = none).
    o.push_back(var(0x2101, "Simulated fault", DT::Unsigned16, RWM, 0));
    // TwinCAT NC PTP online changes as manufacturer functions of the profile modes.
    o.push_back(ranged(0x2110, "Velocity override (ppm)", DT::Unsigned32, RWM, 1'000'000, 0, 1'000'000));
    o.push_back(make_record(0x2111, "Position compensation",
                            {make_entry(1, "Compensation distance", DT::Integer32, RW, 0),
                             make_entry(2, "Compensation length", DT::Unsigned32, RW, 0),
                             make_entry(3, "Start compensation", DT::Unsigned8, RW, 0)}));
    o.push_back(var(0x2001, "Drive temperature (0.1 C)", DT::Integer16, ROM, 350));
    o.push_back(var(0x2002, "DC bus voltage (0.1 V)", DT::Unsigned16, ROM, 3250));
    {
        auto s = make_string_var(0x2010, "User label", "axis");
        s.entries[0].bit_length = 8 * 32;
        s.entries[0].access = RW;
        o.push_back(s);
    }
    {
        // A large read-only value (served by segmented upload).
        ObjectDescription d;
        d.index = 0x2020;
        d.name = "Diagnosis history";
        d.code = ObjectCode::Var;
        d.type = DT::OctetString;
        EntryDescription e;
        e.subindex = 0;
        e.name = d.name;
        e.type = DT::OctetString;
        e.bit_length = 8 * 512;
        e.access = a::RO;
        e.default_value.assign(512, 0);
        d.entries.push_back(e);
        o.push_back(d);
    }

    // Device control (CiA 402 part 2, section 8).
    o.push_back(var(0x603F, "Error code", DT::Unsigned16, ROM));
    o.push_back(var(0x6040, "Controlword", DT::Unsigned16, RWM));
    o.push_back(var(0x6041, "Statusword", DT::Unsigned16, ROM));
    o.push_back(ranged(0x605A, "Quick stop option code", DT::Integer16, RW, 2, 0, 8));
    o.push_back(ranged(0x605B, "Shutdown option code", DT::Integer16, RW, 0, -1, 1));
    o.push_back(ranged(0x605C, "Disable operation option code", DT::Integer16, RW, 1, -1, 1));
    o.push_back(ranged(0x605D, "Halt option code", DT::Integer16, RW, 1, 1, 4));
    o.push_back(ranged(0x605E, "Fault reaction option code", DT::Integer16, RW, 2, 0, 4));
    o.push_back(ranged(0x6060, "Modes of operation", DT::Integer8, RWM, 8, -128, 127));
    o.push_back(var(0x6061, "Modes of operation display", DT::Integer8, ROM));

    // Position control function and factors.
    o.push_back(var(0x6062, "Position demand value", DT::Integer32, ROM));
    o.push_back(var(0x6063, "Position actual internal value", DT::Integer32, ROM));
    o.push_back(var(0x6064, "Position actual value", DT::Integer32, ROM));
    o.push_back(var(0x6065, "Following error window", DT::Unsigned32, RWM, 100000));
    o.push_back(var(0x6066, "Following error time out", DT::Unsigned16, RW, 10));
    o.push_back(var(0x6067, "Position window", DT::Unsigned32, RWM, 100));
    o.push_back(var(0x6068, "Position window time", DT::Unsigned16, RW, 10));
    o.push_back(var(0x606B, "Velocity demand value", DT::Integer32, ROM));
    o.push_back(var(0x606C, "Velocity actual value", DT::Integer32, ROM));
    o.push_back(var(0x606D, "Velocity window", DT::Unsigned16, RW, 100));
    o.push_back(var(0x606E, "Velocity window time", DT::Unsigned16, RW, 10));
    o.push_back(var(0x606F, "Velocity threshold", DT::Unsigned16, RW, 10));
    o.push_back(var(0x6070, "Velocity threshold time", DT::Unsigned16, RW, 10));
    o.push_back(var(0x6071, "Target torque", DT::Integer16, RWM));
    o.push_back(var(0x6072, "Max torque", DT::Unsigned16, RWM, 3000));
    o.push_back(var(0x6074, "Torque demand", DT::Integer16, ROM));
    o.push_back(var(0x6075, "Motor rated current", DT::Unsigned32, RW, 3000));
    o.push_back(var(0x6076, "Motor rated torque", DT::Unsigned32, RW, 1270));
    o.push_back(var(0x6077, "Torque actual value", DT::Integer16, ROM));
    o.push_back(var(0x6078, "Current actual value", DT::Integer16, ROM));
    o.push_back(var(0x607A, "Target position", DT::Integer32, RWM));
    o.push_back(named_array(0x607B, "Position range limit", DT::Integer32, RW,
                            {{"Min position range limit", kI32Min}, {"Max position range limit", kI32Max}}));
    o.push_back(var(0x607C, "Home offset", DT::Integer32, RWM));
    o.push_back(named_array(0x607D, "Software position limit", DT::Integer32, RW,
                            {{"Min position limit", kI32Min}, {"Max position limit", kI32Max}}));
    o.push_back(var(0x607E, "Polarity", DT::Unsigned8, RW));
    o.push_back(var(0x607F, "Max profile velocity", DT::Unsigned32, RWM, 10'000'000));
    o.push_back(var(0x6080, "Max motor speed", DT::Unsigned32, RW, 5000));
    o.push_back(var(0x6081, "Profile velocity", DT::Unsigned32, RWM, 1'000'000));
    o.push_back(var(0x6082, "End velocity", DT::Unsigned32, RWM));
    o.push_back(var(0x6083, "Profile acceleration", DT::Unsigned32, RWM, 10'000'000));
    o.push_back(var(0x6084, "Profile deceleration", DT::Unsigned32, RWM, 10'000'000));
    o.push_back(var(0x6085, "Quick stop deceleration", DT::Unsigned32, RWM, 50'000'000));
    o.push_back(ranged(0x6086, "Motion profile type", DT::Integer16, RW, 0, -1, 3));
    o.push_back(var(0x6087, "Torque slope", DT::Unsigned32, RWM, 10000));
    o.push_back(var(0x6088, "Torque profile type", DT::Integer16, RW, 0));
    o.push_back(named_array(0x608F, "Position encoder resolution", DT::Unsigned32, RW,
                            {{"Encoder increments", 1 << 20}, {"Motor revolutions", 1}}));
    o.push_back(named_array(0x6091, "Gear ratio", DT::Unsigned32, RW,
                            {{"Motor revolutions", 1}, {"Shaft revolutions", 1}}));
    o.push_back(named_array(0x6092, "Feed constant", DT::Unsigned32, RW,
                            {{"Feed", 1 << 20}, {"Shaft revolutions", 1}}));

    // Homing.
    o.push_back(ranged(0x6098, "Homing method", DT::Integer8, RWM, 35, -128, 127));
    o.push_back(
        named_array(0x6099, "Homing speeds", DT::Unsigned32, RW,
                    {{"Speed during search for switch", 100000}, {"Speed during search for zero", 10000}}));
    o.push_back(var(0x609A, "Homing acceleration", DT::Unsigned32, RWM, 1'000'000));
    o.push_back(named_array(0x60A4, "Profile jerk", DT::Unsigned32, RW, {{"Profile jerk 1", 1'000'000'000}}));

    // Cyclic modes: offsets, touch probe, interpolation period.
    o.push_back(var(0x60B0, "Position offset", DT::Integer32, RWM));
    o.push_back(var(0x60B1, "Velocity offset", DT::Integer32, RWM));
    o.push_back(var(0x60B2, "Torque offset", DT::Integer16, RWM));
    o.push_back(var(0x60B8, "Touch probe function", DT::Unsigned16, RWM));
    o.push_back(var(0x60B9, "Touch probe status", DT::Unsigned16, ROM));
    o.push_back(var(0x60BA, "Touch probe 1 positive value", DT::Integer32, ROM));
    o.push_back(var(0x60BB, "Touch probe 1 negative value", DT::Integer32, ROM));
    o.push_back(var(0x60BC, "Touch probe 2 positive value", DT::Integer32, ROM));
    o.push_back(var(0x60BD, "Touch probe 2 negative value", DT::Integer32, ROM));
    {
        auto r = make_record(0x60C2, "Interpolation time period",
                             {make_entry(1, "Interpolation time period value", DT::Unsigned8, RW, 1),
                              make_entry(2, "Interpolation time index", DT::Integer8, RW, -3)});
        set_range(r.entries[2], -6, 63);
        o.push_back(r);
    }
    o.push_back(var(0x60C5, "Max acceleration", DT::Unsigned32, RW, 100'000'000));
    o.push_back(var(0x60C6, "Max deceleration", DT::Unsigned32, RW, 100'000'000));
    o.push_back(var(0x60E0, "Positive torque limit value", DT::Unsigned16, RWM, 3000));
    o.push_back(var(0x60E1, "Negative torque limit value", DT::Unsigned16, RWM, 3000));
    o.push_back(var(0x60F4, "Following error actual value", DT::Integer32, ROM));
    o.push_back(var(0x60FC, "Position demand internal value", DT::Integer32, ROM));
    o.push_back(var(0x60FD, "Digital inputs", DT::Unsigned32, ROM));
    o.push_back(named_array(0x60FE, "Digital outputs", DT::Unsigned32, RWM,
                            {{"Physical outputs", 0}, {"Bit mask", 0}}));
    o.push_back(var(0x60FF, "Target velocity", DT::Integer32, RWM));
    // Supported drive modes: PP (bit 0), PV (2), PT (3), HM (5), CSP (7), CSV (8), CST (9).
    o.push_back(var(0x6502, "Supported drive modes", DT::Unsigned32, a::RO, 0x000003AD));
    return o;
}

}  // namespace vecat::device
