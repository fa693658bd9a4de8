// The project's master on the interface it is given, as a user's test would run under `vecat exec`:
//   vecat_exec_probe IFACE N [--break-a-rule]
// scans the line, brings it to OP, exchanges 100 cycles of process data, prints one line per slave and exits
// 0 when N slaves were found and every cycle had the expected working counter (1 otherwise).
// --break-a-rule: also writes the AL status register (read-only) of the first slave, for the report on the
// master (vecat run --report) to flag.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "master/master.hpp"
#include "net/raw_socket.hpp"
#include "protocol/registers.hpp"

int main(int argc, char** argv) {
    const bool break_a_rule = argc == 4 && std::string(argv[3]) == "--break-a-rule";
    if (argc != 3 && !break_a_rule) {
        std::fprintf(stderr, "usage: %s IFACE N [--break-a-rule]\n", argv[0]);
        return 2;
    }
    try {
        vecat::net::RawSocket sock(argv[1]);
        vecat::master::Master m(sock);
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
        int good = 0;
        for (int i = 0; i < 100; ++i)
            good += m.exchange_process_data().value_or(0) == m.expected_wkc();
        std::printf("%zu slaves, %d of 100 cycles with the expected working counter\n", m.slaves().size(),
                    good);
        return m.slaves().size() == std::strtoul(argv[2], nullptr, 10) && good == 100 ? 0 : 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
