// Working counters of register writes against a real line: ethercrab's start-up of an EK1100 coupler with
// EL2828 and EL2889 terminals (../shared/data/pcap/ek1100-el2828-el2889.pcapng) clears all 16 FMMU and all
// 16 SyncManager blocks and 0x092C with broadcast writes. The real ESCs count a write only where the
// register exists and is writable (ESC datasheet section I 2.4, section II 1): the coupler has 8 FMMUs and
// 8 SyncManagers, the terminals 3 FMMUs and 4 SyncManagers, 0x092C is read-only. Three vecat ESCs with
// the same numbers (0x0004, 0x0005) get the recorded datagrams in line order and must count as they did.
#include <gtest/gtest.h>

#include <vector>

#include "esc/esc.hpp"
#include "esc/sii_image.hpp"
#include "pcapng_reader.hpp"
#include "shared_data.hpp"

using namespace vecat;

namespace {

struct Datagram {
    std::uint8_t cmd;
    std::uint16_t ado;
    std::size_t offset;  // of the header in the frame
    std::size_t length;
    std::uint16_t wkc;
};

std::vector<Datagram> datagrams(const std::vector<std::uint8_t>& f) {
    std::vector<Datagram> out;
    std::size_t p = 16;
    while (p + 12 <= f.size()) {
        const std::uint16_t len_field = ld_le16(&f[p + 6]);
        const std::size_t n = len_field & 0x07FF;
        if (p + 12 + n > f.size()) break;
        out.push_back({f[p], ld_le16(&f[p + 4]), p, n, ld_le16(&f[p + 10 + n])});
        p += 12 + n;
        if (!(len_field & 0x8000)) break;
    }
    return out;
}

bool checked_address(std::uint16_t a) {
    return (a >= protocol::fmmu_addr(0) && a < protocol::sm_addr(protocol::kMaxSms)) ||
           a == protocol::addr(protocol::Reg::DcSystemTimeDifference);
}

}  // namespace

TEST(RegisterReplay, WritesToAbsentAndReadOnlyRegistersCountAsOnTheRealLine) {
    VECAT_REQUIRE_SHARED_DATA("pcap/ek1100-el2828-el2889.pcapng");
    const auto frames = test::read_pcapng_frames(test::shared_data("pcap/ek1100-el2828-el2889.pcapng"));
    const auto sii = esc::build_sii_image(device::default_drive());
    esc::EscConfig coupler, terminal;
    terminal.fmmu_count = 3;
    terminal.sm_count = 4;
    esc::Esc ek1100(coupler, sii), el2828(terminal, sii), el2889(terminal, sii);
    esc::Esc* line[] = {&ek1100, &el2828, &el2889};
    unsigned checked = 0, zero = 0;
    for (std::size_t i = 0; i + 1 < frames.size(); ++i) {
        const auto& req = frames[i];
        const auto& rep = frames[i + 1];
        if (req.size() < 30 || req[12] != 0x88 || req[13] != 0xA4 || (req[6] & 0x02) || !(rep[6] & 0x02))
            continue;
        auto q = req;
        const auto dq = datagrams(q), dr = datagrams(rep);
        if (dq.size() != dr.size()) continue;
        for (std::size_t k = 0; k < dq.size(); ++k) {
            if (dq[k].cmd != static_cast<std::uint8_t>(protocol::Command::BWR) || !checked_address(dq[k].ado))
                continue;
            protocol::DatagramView d(q.data() + dq[k].offset);
            for (auto* e : line)
                e->process(d, esc::FrameTiming{1000, 2000});
            EXPECT_EQ(d.wkc(), dr[k].wkc) << "frame " << i + 1 << " BWR 0x" << std::hex << dq[k].ado;
            ++checked;
            zero += dr[k].wkc == 0;
        }
    }
    EXPECT_GE(checked, 33u);  // 16 FMMU blocks, 16 SyncManager blocks, 0x092C
    EXPECT_GE(zero, 17u);     // FMMUs 8-15, SyncManagers 8-15, 0x092C
}
