// A line of N default drives brought to OP by the project's master over an in-process link and enabled in
// CSP (controlword 6, 7, 15; mode 8), holding their positions: every servo period runs the whole drive model.
// Shared by the datagram benchmarks (bench_datagram.cpp) and vecat-cache-cycles (bench/cache).
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "cia402/drive.hpp"
#include "common/bytes.hpp"
#include "master/master.hpp"
#include "serve/in_process_link.hpp"

namespace vecat::bench {

struct DriveLine {
    std::unique_ptr<esc::Segment> seg;
    std::unique_ptr<net::InProcessLink> link;
    std::unique_ptr<master::Master> m;
    std::uint64_t now = 1'000'000'000;  // the link's time, ns

    // Throws std::runtime_error with the master's reason when the line does not reach OP.
    explicit DriveLine(std::size_t n) {
        seg = cia402::make_drive_segment(device::default_drive(), n);
        link = std::make_unique<net::InProcessLink>(*seg);
        link->set_time(now);
        m = std::make_unique<master::Master>(*link);
        if (std::string why; !m->startup(protocol::AlState::Op, &why))
            throw std::runtime_error("start-up failed: " + why);
        for (const std::uint16_t cw :
             {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}, std::uint16_t{0x0F}}) {
            for (std::size_t i = 0; i < n; ++i) {
                auto o = m->outputs(i);
                st_le16(o.data(), cw);
                o[2] = 8;
            }
            m->exchange_process_data();
            advance(1'000'000);
        }
    }
    void advance(std::uint64_t ns) {
        now += ns;
        link->set_time(now);
    }
};

}  // namespace vecat::bench
