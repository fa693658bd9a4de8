// The project's master on the interface it is given, as a user's test would run under `vecat exec`:
//   vecat_exec_probe IFACE N [--break-a-rule | --redundant IFACE2]
// scans the line, brings it to OP, exchanges 100 cycles of process data, prints one line per slave and exits
// 0 when N slaves were found and every cycle had the expected working counter (1 otherwise).
// --break-a-rule: also writes the AL status register (read-only) of the first slave, for the report on the
// master (vecat run --report) to flag.
// --redundant IFACE2: a redundant master on both ports (vecat exec --redundant). With a control socket
// (VECAT_CONTROL) the cable between slaves 2 and 3 breaks for 100 cycles and comes back for 100 more; every
// cycle must still have the expected working counter, and the ring must have been seen whole, then broken.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <string>

#include "faults/control.hpp"
#include "master/master.hpp"
#include "net/raw_socket.hpp"
#include "protocol/registers.hpp"
#include "redundant_raw_link.hpp"

namespace {

bool control(const char* socket, const std::string& command) {
    std::string reply;
    const bool ok = vecat::faults::send_control_command(socket, command, reply) && reply.rfind("ok", 0) == 0;
    std::printf("control: %s -> %s\n", command.c_str(), reply.c_str());
    return ok;
}

}  // namespace

int main(int argc, char** argv) {
    const std::string option = argc >= 4 ? argv[3] : "";
    const bool break_a_rule = argc == 4 && option == "--break-a-rule";
    const bool redundant = argc == 5 && option == "--redundant";
    if (argc != 3 && !break_a_rule && !redundant) {
        std::fprintf(stderr, "usage: %s IFACE N [--break-a-rule | --redundant IFACE2]\n", argv[0]);
        return 2;
    }
    try {
        std::unique_ptr<vecat::net::Link> link;
        vecat::test::RedundantRawLink* ring = nullptr;
        if (redundant) {
            auto r = std::make_unique<vecat::test::RedundantRawLink>(argv[1], argv[4]);
            ring = r.get();
            link = std::move(r);
        } else {
            link = std::make_unique<vecat::net::RawSocket>(argv[1]);
        }
        vecat::master::Master m(*link);
        std::string why;
        if (!m.startup(vecat::protocol::AlState::Op, &why)) {
            std::fprintf(stderr, "start-up failed: %s\n", why.c_str());
            return 1;
        }
        for (const auto& s : m.slaves())
            std::printf("slave %u: station 0x%04X, vendor 0x%08X, product 0x%08X, %s\n", s.position + 1u,
                        s.station, s.sii.identity.vendor_id, s.sii.identity.product_code,
                        s.sii.device_name().c_str());
        if (break_a_rule) {
            std::uint8_t state[2] = {0x08, 0};
            m.fpwr(m.slaves().at(0).station, vecat::protocol::addr(vecat::protocol::Reg::AlStatus), state);
        }
        int good = 0, cycles = 0;
        const auto exchange = [&](int n) {
            for (int i = 0; i < n; ++i, ++cycles)
                good += m.exchange_process_data().value_or(0) == m.expected_wkc();
        };
        exchange(100);
        bool ring_ok = true;
        if (ring) {
            const char* socket = std::getenv("VECAT_CONTROL");
            if (socket) {
                ring_ok = control(socket, "inject link_down slave=1 port=1 id=probe-cut");
                exchange(100);
                ring_ok = control(socket, "clear probe-cut") && ring_ok;
                exchange(100);
            }
            std::printf("ring: %u frames round the whole ring, %u through a broken one\n", ring->whole_,
                        ring->broken_);
            ring_ok = ring_ok && ring->whole_ >= 100 && (!socket || ring->broken_ >= 100);
        }
        std::printf("%zu slaves, %d of %d cycles with the expected working counter\n", m.slaves().size(),
                    good, cycles);
        return m.slaves().size() == std::strtoul(argv[2], nullptr, 10) && good == cycles && ring_ok ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
