// The rules the report on the master checks (vecat run --report): what a master does that real devices
// reject, or that the EtherCAT specifications advise against. One row per rule, with the document it
// comes from; the checks themselves are in master_checks.cpp.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

namespace vecat::report {

enum class Rule : std::uint8_t {
    SmConfiguration,
    FmmuConfiguration,
    AlStatusNotRead,
    AlErrorNotAcknowledged,
    OpWithoutOutputs,
    Sync0StartInThePast,
    Sync0BeforeDriftCompensation,
    MailboxCounter,
    WatchdogShorterThanCycle,
    ReadOnlyRegisterWrite,
    EepromNotAssigned,
};
inline constexpr std::size_t kRuleCount = 11;

enum class Severity : std::uint8_t {
    Error,    // a real device rejects it or stops (AL status error, lost data, no SYNC)
    Warning,  // the specifications advise against it; real devices mostly cope
};

struct RuleInfo {
    Rule rule;
    std::string_view id;  // short name, used in the JUnit test case name and the summary
    Severity severity;
    std::string_view what;    // what the master must do (the passing test case)
    std::string_view source;  // where the rule is written
};

inline constexpr std::array<RuleInfo, kRuleCount> kRules{{
    {Rule::SmConfiguration, "sm-config", Severity::Error,
     "SyncManagers are configured as the SII describes them (start, control) and the process data "
     "SyncManagers as long as their PDO assignment",
     "ETG.2010 (SII category SyncM); ETG.1000.6 (PDO assignment objects 0x1C12/0x1C13)"},
    {Rule::FmmuConfiguration, "fmmu-config", Severity::Error,
     "every process data SyncManager with a length is mapped by an active FMMU of its direction before "
     "SAFEOP is requested",
     "Beckhoff ESC datasheet section I (FMMU, SyncManager); ETG.1000.4 (FMMU attributes)"},
    {Rule::AlStatusNotRead, "al-status-read", Severity::Warning,
     "the AL status (0x0130) is read after a state change request before another state is requested",
     "ETG.1000.6 (AL state machine: the master reads the AL status to learn the outcome of a request)"},
    {Rule::AlErrorNotAcknowledged, "al-error-ack", Severity::Error,
     "a state change requested while the AL status shows an error sets Error Ind Ack (0x0120 bit 4)",
     "ETG.1000.6 (AL control: error acknowledge); Beckhoff ESC datasheet section II (0x0120, 0x0130)"},
    {Rule::OpWithoutOutputs, "outputs-before-op", Severity::Warning,
     "valid outputs are sent in SAFEOP before OP is requested",
     "ETG.1000.6 (AL state machine, SAFEOP to OP: the master sends valid outputs first)"},
    {Rule::Sync0StartInThePast, "sync0-start-time", Severity::Error,
     "SYNC0 is activated with a start time (0x0990) that lies ahead of the slave's system time",
     "Beckhoff ESC datasheet section I (Distributed Clocks, SYNC/LATCH: start time of cyclic operation)"},
    {Rule::Sync0BeforeDriftCompensation, "sync0-after-drift", Severity::Warning,
     "the reference clock's system time is distributed (ARMW/FRMW 0x0910) before SYNC0 is activated",
     "Beckhoff ESC datasheet section I (Distributed Clocks: propagation delay, offset and drift "
     "compensation before SYNC activation)"},
    {Rule::MailboxCounter, "mailbox-counter", Severity::Error,
     "the mailbox header counter of each new request follows 1..7 (0: no counter)",
     "ETG.1000.4 (mailbox header, Cnt); ETG.1000.6 (mailbox repeat)"},
    {Rule::WatchdogShorterThanCycle, "watchdog-cycle", Severity::Error,
     "process data reach a slave in OP more often than its SyncManager watchdog time",
     "Beckhoff ESC datasheet section I (Watchdogs: process data watchdog, 0x0400/0x0420)"},
    {Rule::ReadOnlyRegisterWrite, "read-only-write", Severity::Warning,
     "write datagrams address at least one register the EtherCAT side may write",
     "Beckhoff ESC datasheet section II (register access: ECAT read-only registers)"},
    {Rule::EepromNotAssigned, "eeprom-owner", Severity::Warning,
     "the EEPROM interface is assigned to EtherCAT (0x0500) before the master issues an EEPROM command",
     "Beckhoff ESC datasheet section II (EEPROM configuration 0x0500, PDI access state 0x0501)"},
}};

constexpr bool rules_in_order() noexcept {
    for (std::size_t i = 0; i < kRules.size(); ++i)
        if (static_cast<std::size_t>(kRules[i].rule) != i) return false;
    return true;
}
static_assert(rules_in_order(), "kRules is indexed by Rule");

constexpr const RuleInfo& info(Rule r) noexcept {
    return kRules[static_cast<std::size_t>(r)];
}

constexpr std::string_view to_string(Severity s) noexcept {
    return s == Severity::Error ? "error" : "warning";
}

}  // namespace vecat::report
