#include "faults/twinsync_faults.hpp"

#include <algorithm>
#include <stdexcept>

#include "coe/coe_application.hpp"

namespace vecat::faults {

namespace {
// 0x2104: 1 cable break, 2 sync loss, 3 corrupt next n frames, 5 corrupted frames per million.
constexpr std::uint16_t kInjection = 0x2104;
}  // namespace

void TwinsyncFaults::write(const FaultSpec& f, bool on) {
    if (f.slave >= seg_.size())
        throw std::invalid_argument("no slave " + std::to_string(f.slave) + " on the line");
    auto* app = dynamic_cast<coe::CoeApplication*>(&seg_.slave(f.slave).app());
    coe::Entry* any = app ? app->dictionary().find(kInjection, 1) : nullptr;
    if (!any)
        throw std::invalid_argument("slave " + std::to_string(f.slave) + " has no TWINsync option (0x2104)");
    auto& od = app->dictionary();
    if (f.name == "twinsync_cable_break") {
        od.find(kInjection, 1)->set<std::uint8_t>(on ? 1 : 0);
    } else if (f.name == "twinsync_sync_loss") {
        od.find(kInjection, 2)->set<std::uint8_t>(on ? 1 : 0);
    } else if (f.name == "twinsync_crc_errors") {
        // A count corrupts that many frames; otherwise the probability is the rate per frame.
        if (on && f.count > 0) {
            coe::Entry* e = od.find(kInjection, 3);
            const auto n = static_cast<std::uint32_t>(std::min<std::uint64_t>(f.count, 0xFFFFFFFFu));
            // Through the SDO path's hook, which hands the count to the cable.
            std::uint8_t v[4] = {static_cast<std::uint8_t>(n), static_cast<std::uint8_t>(n >> 8),
                                 static_cast<std::uint8_t>(n >> 16), static_cast<std::uint8_t>(n >> 24)};
            const auto abort = od.download(kInjection, 3, false, protocol::AlState::PreOp, ConstBytes(v, 4));
            if (abort != protocol::SdoAbort::None || !e)
                throw std::invalid_argument("0x2104:03 refused the count");
        } else {
            const double p = on ? std::clamp(f.probability, 0.0, 1.0) : 0.0;
            od.find(kInjection, 5)->set<std::uint32_t>(static_cast<std::uint32_t>(p * 1e6));
        }
    } else {
        throw std::invalid_argument("not a TWINsync fault: " + f.name);
    }
}

void TwinsyncFaults::start(const FaultSpec& f, std::uint64_t) {
    write(f, true);
}

void TwinsyncFaults::stop(const FaultSpec& f, std::uint64_t) {
    write(f, false);
}

void register_twinsync_faults(FaultInjector& injector, TwinsyncFaults& handler) {
    for (const char* kind : {"twinsync_cable_break", "twinsync_crc_errors", "twinsync_sync_loss"})
        injector.register_handler(kind, handler);
}

}  // namespace vecat::faults
