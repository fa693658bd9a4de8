#include "replay/classify.hpp"

#include "protocol/registers.hpp"

namespace vecat::replay {

using protocol::addr;
using protocol::Reg;

std::string_view to_string(Verdict v) noexcept {
    switch (v) {
        case Verdict::Same:
            return "same";
        case Verdict::TimeDependent:
            return "time-dependent";
        case Verdict::Counter:
            return "counter";
        case Verdict::MailboxPadding:
            return "mailbox padding";
        case Verdict::Timing:
            return "timing";
        case Verdict::ProcessData:
            return "process data";
        case Verdict::Differs:
            return "differs";
    }
    return "?";
}

namespace {

struct Range {
    std::uint16_t first;
    std::uint16_t end;  // one past the last
    Verdict verdict;
};

// ESC datasheet section II, distributed clocks and error counters.
constexpr Range kClasses[] = {
    {addr(Reg::RxErrorCounter), addr(Reg::LostLinkCounter) + 4, Verdict::Counter},
    {addr(Reg::WatchdogCounterProcessData), addr(Reg::WatchdogCounterPdi) + 1, Verdict::Counter},
    // Receive times of ports 0-3, system time, receive time of the processing unit.
    {addr(Reg::DcRecvTimePort0), addr(Reg::DcSystemTimeOffset), Verdict::TimeDependent},
    {addr(Reg::DcSystemTimeDifference), addr(Reg::DcSpeedCounterStart), Verdict::TimeDependent},
    {addr(Reg::DcSpeedCounterDiff), addr(Reg::DcSystemTimeDiffFilterDepth), Verdict::TimeDependent},
    // Start time of cyclic operation (the next SYNC0 once running) and the next SYNC1 pulse.
    {addr(Reg::DcStartTimeCyclic), addr(Reg::DcSync0CycleTime), Verdict::TimeDependent},
    // Latch status and times, buffer change event times (0x09AE-0x09FF).
    {addr(Reg::DcLatch0Status), 0x0A00, Verdict::TimeDependent},
};

}  // namespace

Verdict register_class(std::uint16_t a) noexcept {
    for (const Range& r : kClasses)
        if (a >= r.first && a < r.end) return r.verdict;
    return Verdict::Differs;
}

std::string area_name(std::uint16_t a) {
    struct Named {
        std::uint16_t first, end;
        const char* name;
    };
    static constexpr Named kNames[] = {
        {0x0000, 0x000A, "ESC information"},
        {addr(Reg::StationAddress), 0x0014, "station address/alias"},
        {addr(Reg::DlControl), 0x0104, "DL control"},
        {addr(Reg::DlStatus), 0x0112, "DL status"},
        {addr(Reg::AlControl), 0x0122, "AL control"},
        {addr(Reg::AlStatus), 0x0132, "AL status"},
        {addr(Reg::AlStatusCode), 0x0136, "AL status code"},
        {addr(Reg::PdiControl), 0x0160, "PDI control/configuration"},
        {addr(Reg::EcatEventMask), 0x0230, "event mask/request"},
        {addr(Reg::RxErrorCounter), 0x0314, "error counters"},
        {addr(Reg::WatchdogDivider), 0x0450, "watchdogs"},
        {addr(Reg::SiiConfig), 0x0510, "SII interface"},
        {addr(Reg::MiiControl), 0x0520, "MII management"},
        {addr(Reg::DcRecvTimePort0), 0x0980, "DC time loop"},
        {addr(Reg::DcCyclicUnitControl), 0x09A8, "DC SYNC"},
        {addr(Reg::DcLatch0Control), 0x0A00, "DC latch"},
        {addr(Reg::DigitalOutputData), 0x0F80, "digital I/O"},
    };
    if (a >= addr(Reg::Fmmu0) && a < addr(Reg::Sm0))
        return "FMMU " + std::to_string((a - addr(Reg::Fmmu0)) / 16);
    if (a >= addr(Reg::Sm0) && a < addr(Reg::DcRecvTimePort0))
        return "SM" + std::to_string((a - addr(Reg::Sm0)) / 8);
    for (const Named& n : kNames)
        if (a >= n.first && a < n.end) return n.name;
    if (a >= addr(Reg::ProcessRam)) return "process RAM";
    return "register";
}

}  // namespace vecat::replay
