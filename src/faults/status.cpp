#include "faults/status.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "coe/coe_application.hpp"
#include "coe/object_dictionary.hpp"
#include "protocol/al_status.hpp"
#include "protocol/cia402.hpp"
#include "protocol/cia402_objects.hpp"
#include "protocol/objects.hpp"
#include "protocol/registers.hpp"

namespace vecat::faults {

namespace {

using protocol::Reg;

// The object's value, "-" where the device has none.
template <class Id>
std::string object(coe::ObjectDictionary& od, Id id) {
    const auto v = coe::bind(od, id);
    return v.bound() ? fmt::format("{}", +v.get_or({})) : std::string("-");
}

}  // namespace

std::string line_status(const esc::Segment& seg) {
    std::string s = fmt::format("ok {} slaves", seg.size());
    for (std::size_t i = 0; i < seg.size(); ++i) {
        const esc::Slave& slave = seg.slave(i);
        const esc::Esc& e = slave.esc();
        const auto al = static_cast<protocol::AlState>(e.al_status() & 0x0F);
        unsigned lost[4] = {}, rx_errors = 0;
        for (unsigned p = 0; p < 4; ++p) {
            lost[p] = e.peek(static_cast<std::uint16_t>(protocol::addr(Reg::LostLinkCounter) + p));
            rx_errors += e.peek(static_cast<std::uint16_t>(protocol::addr(Reg::RxErrorCounter) + 2 * p));
        }
        s += fmt::format(
            "\nslave={} al={}{} al_code=0x{:04X} lost_links={},{},{},{} rx_errors={} watchdog_pd={}", i,
            protocol::to_string(al), (e.al_status() & 0x10) ? "+ERROR" : "", e.al_status_code(), lost[0],
            lost[1], lost[2], lost[3], rx_errors, e.peek(protocol::addr(Reg::WatchdogCounterProcessData)));
        // The application is the slave's own; reading its dictionary changes nothing.
        auto* coe = dynamic_cast<coe::CoeApplication*>(&const_cast<esc::Slave&>(slave).app());
        if (!coe) continue;
        auto& od = coe->dictionary();
        const auto sw = coe::bind(od, protocol::obj::statusword);
        if (!sw.bound()) continue;
        const std::uint16_t word = sw.get_or(0);
        const auto state = protocol::cia402::decode_state(word);
        std::string name = state ? protocol::cia402::to_string(*state) : "UNKNOWN";
        std::replace(name.begin(), name.end(), ' ', '_');  // one word: the line stays key=value pairs
        s += fmt::format(" statusword=0x{:04X} state={} mode={} position={} velocity={} error_code=0x{:04X}",
                         word, name, object(od, protocol::obj::modes_of_operation_display),
                         object(od, protocol::obj::position_actual_value),
                         object(od, protocol::obj::velocity_actual_value),
                         coe::bind(od, protocol::obj::error_code).get_or(0));
    }
    return s;
}

}  // namespace vecat::faults
