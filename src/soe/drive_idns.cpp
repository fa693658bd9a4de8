// The IDN table of the SoE drive: names, attributes, units, limits and defaults of the IDNs it knows
// (IEC 61800-7-204 numbers and names; P-0-0100 is vecat's data container for long transfers, P-0-0101 the
// execution time of a procedure command). The units: soe_axis.hpp (kIncrementsPerRevolution...).
#include <string_view>

#include "soe/soe_axis.hpp"

namespace vecat::soe {

namespace {

using protocol::SoeDataType;

// Attribute of a fixed value: length code (1: 2 bytes, 2: 4 bytes), type, write protection in CP3/CP4.
SoeAttribute fixed(std::uint8_t length_code, SoeDataType type, bool wp_cyclic_phases = false,
                   std::uint8_t decimals = 0) {
    SoeAttribute a;
    a.length_code = length_code;
    a.type = type;
    a.decimals = decimals;
    a.wp_safeop = wp_cyclic_phases;
    a.wp_op = wp_cyclic_phases;
    return a;
}

IdnEntry value(Idn idn, std::string name, SoeAttribute a, std::string unit, std::uint64_t v,
               std::optional<std::uint64_t> min = std::nullopt,
               std::optional<std::uint64_t> max = std::nullopt) {
    IdnEntry e;
    e.idn = idn;
    e.name = std::move(name);
    e.attribute = a;
    e.unit = std::move(unit);
    e.min = min;
    e.max = max;
    e.value.assign(a.element_size(), 0);
    e.set_number(v);
    e.default_value = e.value;
    return e;
}

IdnEntry read_only(IdnEntry e) {
    e.read_only = true;
    e.default_value.reset();
    return e;
}

IdnEntry text(Idn idn, std::string name, std::string_view s) {
    IdnEntry e;
    e.idn = idn;
    e.name = std::move(name);
    e.attribute.length_code = 0;
    e.attribute.list = true;
    e.attribute.type = SoeDataType::Text;
    e.value.assign(s.begin(), s.end());
    e.max_list_bytes = 64;
    e.read_only = true;
    return e;
}

// An IDN list (2-byte elements) of at most max entries.
IdnEntry idn_list(Idn idn, std::string name, std::vector<std::uint16_t> idns, std::size_t max,
                  bool writable) {
    IdnEntry e;
    e.idn = idn;
    e.name = std::move(name);
    e.attribute.length_code = 1;
    e.attribute.list = true;
    e.attribute.type = SoeDataType::IdnList;
    // The configuration lists change in CP2 (PREOP) only.
    e.attribute.wp_safeop = writable;
    e.attribute.wp_op = writable;
    e.set_words(idns);
    e.max_list_bytes = 2 * max;
    e.read_only = !writable;
    return e;
}

IdnEntry procedure(Idn idn, std::string name) {
    IdnEntry e;
    e.idn = idn;
    e.name = std::move(name);
    e.attribute.length_code = 1;
    e.attribute.command = true;
    e.attribute.type = SoeDataType::Binary;
    e.value.assign(2, 0);
    e.data_state = command_state::NotSet;
    return e;
}

constexpr std::uint16_t kMaxMapped = 8;  // IDNs an MDT or AT list holds at most

}  // namespace

std::vector<IdnEntry> drive_idns() {
    using T = SoeDataType;
    std::vector<IdnEntry> v;
    v.push_back(value(idn::NcCycleTime, "NC cycle time (TNcyc)", fixed(1, T::Unsigned, true), "us", 1000, 125,
                      65000));
    v.push_back(value(idn::CommunicationCycleTime, "Communication cycle time (tScyc)",
                      fixed(1, T::Unsigned, true), "us", 1000, 125, 65000));
    v.push_back(read_only(value(idn::Class1Diagnostic, "Class 1 diagnostic", fixed(1, T::Binary), "", 0)));
    v.push_back(value(idn::TelegramType, "Telegram type parameter", fixed(1, T::Binary, true), "",
                      kDefaultTelegram, 0, kApplicationTelegram));
    v.push_back(idn_list(idn::AtConfiguration, "Configuration list of the AT", {idn::PositionFeedback.raw},
                         kMaxMapped, true));
    v.push_back(idn_list(idn::AllOperationData, "IDN-list of all operation data", {}, 64, false));
    v.push_back(idn_list(idn::MdtConfiguration, "Configuration list of the MDT", {idn::PositionCommand.raw},
                         kMaxMapped, true));
    v.push_back(text(idn::ManufacturerVersion, "Manufacturer version", "vecat SoE drive 0.1"));
    // The operation modes S-0-0134 bits 8-9 select: position (feedback 1), velocity, torque control.
    v.push_back(value(idn::PrimaryOperationMode, "Primary operation mode", fixed(1, T::Binary, true), "",
                      op_mode::PositionFeedback1));
    v.push_back(value(idn::SecondaryOperationMode1, "Secondary operation mode 1", fixed(1, T::Binary, true),
                      "", op_mode::Velocity));
    v.push_back(value(idn::SecondaryOperationMode2, "Secondary operation mode 2", fixed(1, T::Binary, true),
                      "", op_mode::Torque));
    v.push_back(value(idn::SecondaryOperationMode3, "Secondary operation mode 3", fixed(1, T::Binary, true),
                      "", op_mode::None));
    // Velocities in 0.0001 rpm (4 decimals).
    v.push_back(
        value(idn::VelocityCommand, "Velocity command value", fixed(2, T::Signed, false, 4), "rpm", 0));
    v.push_back(read_only(
        value(idn::VelocityFeedback, "Velocity feedback value 1", fixed(2, T::Signed, false, 4), "rpm", 0)));
    v.push_back(value(idn::PositionCommand, "Position command value", fixed(2, T::Signed), "inc", 0));
    v.push_back(
        read_only(value(idn::PositionFeedback, "Position feedback value 1", fixed(2, T::Signed), "inc", 0)));
    v.push_back(value(idn::TorqueCommand, "Torque command value", fixed(1, T::Signed, false, 1), "%", 0));
    v.push_back(read_only(
        value(idn::TorqueFeedback, "Torque feedback value", fixed(1, T::Signed, false, 1), "%", 0)));
    v.push_back(value(idn::VelocityLimit, "Bipolar velocity limit value", fixed(2, T::Unsigned, false, 4),
                      "rpm", static_cast<std::uint64_t>(6000 * kVelocityUnitsPerRpm), 0, 0x7FFFFFFF));
    v.push_back(text(idn::DiagnosticMessage, "Diagnostic message", "ready"));
    v.push_back(procedure(idn::ResetClass1Diagnostic, "Reset class 1 diagnostic"));
    v.push_back(procedure(idn::Cp3TransitionCheck, "CP3 transition check"));
    v.push_back(procedure(idn::Cp4TransitionCheck, "CP4 transition check"));
    v.push_back(read_only(value(idn::ControlWord, "Master control word", fixed(1, T::Binary), "", 0)));
    v.push_back(read_only(value(idn::StatusWord, "Drive status word", fixed(1, T::Binary), "", 0)));
    v.push_back(text(idn::ControllerType, "Controller type", "vecat SoE drive (AX5000-like)"));
    v.push_back(value(idn::MonitoringWindow, "Monitoring window", fixed(2, T::Unsigned), "inc", 100000, 0,
                      0x7FFFFFFF));
    v.push_back(idn_list(idn::AtConfigurable, "IDN-list of configurable data in the AT",
                         {idn::VelocityFeedback.raw, idn::PositionFeedback.raw, idn::TorqueFeedback.raw}, 8,
                         false));
    v.push_back(idn_list(idn::MdtConfigurable, "IDN-list of configurable data in the MDT",
                         {idn::VelocityCommand.raw, idn::PositionCommand.raw, idn::TorqueCommand.raw}, 8,
                         false));
    // P-0-0100: a list of up to 256 4-byte values the master may fill and read back, longer than one mailbox
    // (segmented transfers).
    IdnEntry c;
    c.idn = idn::DataContainer;
    c.name = "Data container";
    c.attribute.length_code = 2;
    c.attribute.list = true;
    c.attribute.type = SoeDataType::Hex;
    c.max_list_bytes = 1024;
    v.push_back(std::move(c));
    // P-0-0101: how long a procedure command is "in progress" before it is executed, in µs (0: at once).
    v.push_back(value(idn::CommandDuration, "Procedure command execution time", fixed(2, T::Unsigned), "us",
                      kDefaultCommandDurationUs, 0, kMaxCommandDurationUs));
    // S-0-0017 lists them all.
    std::vector<std::uint16_t> all;
    for (const auto& e : v)
        all.push_back(e.idn.raw);
    for (auto& e : v)
        if (e.idn == idn::AllOperationData) e.set_words(all);
    return v;
}

}  // namespace vecat::soe
