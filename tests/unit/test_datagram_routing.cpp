// The segment hands a datagram only to the ESCs it can concern (Segment::process_datagrams, an index of each
// ESC's station address, alias and FMMU range). These tests hold it against the plain rule, every ESC looking
// at every datagram in the frame's order, on random frames that change the addressing while they pass:
// station addresses and aliases written by auto-increment and broadcast commands, alias addressing switched
// on and off, FMMUs configured and moved, in the same frame as the datagrams that use them.
#include <gtest/gtest.h>

#include <initializer_list>
#include <random>
#include <set>

#include "device/simple_devices.hpp"
#include "esc/address_index.hpp"
#include "esc/segment.hpp"
#include "protocol/frame.hpp"
#include "test_support.hpp"

using namespace vecat;
using namespace vecat::test;
using protocol::Command;

namespace {

constexpr std::size_t kSlaves = 6;
constexpr std::uint64_t kNow = 1'000'000'000;

// Every ESC looks at every datagram, slave after slave: what the ESC datasheet describes.
void process_everywhere(std::vector<std::unique_ptr<esc::Esc>>& escs, std::vector<std::uint8_t>& frame) {
    const protocol::ParsedFrame pf = protocol::parse_frame(ConstBytes(frame.data(), frame.size()));
    ASSERT_EQ(pf.error, protocol::FrameError::None);
    const esc::FrameTiming t{kNow, kNow, kNow, kNow};
    for (auto& e : escs)
        for (std::size_t i = 0; i < pf.count; ++i)
            e->process(pf.datagram(Bytes(frame.data(), frame.size()), i), t);
}

struct Datagram {
    Command cmd;
    std::uint16_t adp;
    std::uint16_t ado;  // the logical address for LRx: adp | ado << 16
    std::vector<std::uint8_t> data;
};

std::vector<std::uint8_t> make_frame(const std::vector<Datagram>& ds) {
    std::vector<std::uint8_t> f(16, 0);
    for (int i = 0; i < 6; ++i)
        f[static_cast<std::size_t>(i)] = 0xFF;
    f[12] = 0x88;
    f[13] = 0xA4;
    std::size_t body = 0;
    for (std::size_t i = 0; i < ds.size(); ++i) {
        const Datagram& d = ds[i];
        const std::size_t at = f.size();
        f.resize(at + 10 + d.data.size() + 2, 0);
        f[at] = static_cast<std::uint8_t>(d.cmd);
        f[at + 1] = static_cast<std::uint8_t>(i);
        st_le16(&f[at + 2], d.adp);
        st_le16(&f[at + 4], d.ado);
        st_le16(&f[at + 6], static_cast<std::uint16_t>(d.data.size() | (i + 1 < ds.size() ? 0x8000 : 0)));
        std::copy(d.data.begin(), d.data.end(), f.begin() + static_cast<long>(at + 10));
        body += 10 + d.data.size() + 2;
    }
    st_le16(&f[14], static_cast<std::uint16_t>(body | 0x1000));
    f.resize(std::max<std::size_t>(f.size(), 60), 0);
    return f;
}

// A random datagram among the ones that matter here: addressing registers, FMMUs, RAM, logical access.
// indexed_only: configured-address and logical commands only (and NOP), the frames the segment hands to the
// slaves its AddressIndex names.
Datagram random_datagram(std::mt19937& rng, bool indexed_only = false) {
    const auto pick = [&](auto... v) {
        const std::uint16_t values[] = {static_cast<std::uint16_t>(v)...};
        return values[rng() % sizeof...(v)];
    };
    static constexpr Command kCommands[] = {Command::NOP,  Command::APRD, Command::APWR, Command::APRW,
                                            Command::FPRD, Command::FPWR, Command::FPRW, Command::BRD,
                                            Command::BWR,  Command::BRW,  Command::LRD,  Command::LWR,
                                            Command::LRW,  Command::ARMW, Command::FRMW};
    static constexpr Command kIndexed[] = {Command::NOP, Command::FPRD, Command::FPWR, Command::FPRW,
                                           Command::LRD, Command::LWR,  Command::LRW};
    Datagram d{indexed_only ? kIndexed[rng() % std::size(kIndexed)] : kCommands[rng() % std::size(kCommands)],
               0,
               0,
               {}};
    const std::uint16_t station = pick(0, 0x1000, 0x1001, 0x1002, 0x1003, 0x2000);
    const std::size_t len = 1 + rng() % 16;
    d.data.resize(len);
    for (auto& b : d.data)
        b = static_cast<std::uint8_t>(rng());
    switch (d.cmd) {
        case Command::LRD:
        case Command::LWR:
        case Command::LRW: {
            const auto logical = static_cast<std::uint32_t>(0x10000u + rng() % 48);
            d.adp = static_cast<std::uint16_t>(logical);
            d.ado = static_cast<std::uint16_t>(logical >> 16);
            return d;
        }
        case Command::FPRD:
        case Command::FPWR:
        case Command::FPRW:
        case Command::FRMW:
            d.adp = station;
            break;
        default:  // auto-increment positions, some beyond the line
            d.adp = static_cast<std::uint16_t>(-static_cast<int>(rng() % (kSlaves + 2)));
            break;
    }
    d.ado = pick(0x0010, 0x0012, 0x0100, 0x0600, 0x0610, 0x0620, 0x1000, 0x1010, 0x0130);
    if (d.ado == 0x0010 || d.ado == 0x0012) {
        d.data.assign(2, 0);
        st_le16(d.data.data(), station);
    } else if (d.ado == 0x0100) {
        d.data = {0x01, 0x00, 0x07, static_cast<std::uint8_t>(rng() % 2)};  // alias addressing on or off
    } else if (d.ado >= 0x0600 && d.ado < 0x0700) {
        // An FMMU: a small logical range onto the process RAM, read and/or write, active or not.
        d.data.assign(16, 0);
        st_le32(d.data.data(), 0x10000u + rng() % 32);
        st_le16(d.data.data() + 4, static_cast<std::uint16_t>(1 + rng() % 8));
        d.data[6] = static_cast<std::uint8_t>(rng() % 8);  // start and stop bits: a bit-wise mapping too
        d.data[7] = static_cast<std::uint8_t>(rng() % 8);
        st_le16(d.data.data() + 8, static_cast<std::uint16_t>(0x1000 + rng() % 16));
        d.data[11] = static_cast<std::uint8_t>(1 + rng() % 3);
        d.data[12] = static_cast<std::uint8_t>(rng() % 4 ? 1 : 0);
    }
    return d;
}

// Random frames against the plain rule. indexed_only: after a first frame that gives the slaves station
// addresses 0x1000..0x1005, frames of configured-address and logical datagrams only; those that write a
// station address or an FMMU change the index while the frame passes.
void answers_as_if_every_esc_saw_every_datagram(bool indexed_only) {
    const device::DeviceDescription desc = device::digital_output_terminal(8);
    auto seg = esc::make_segment(desc, kSlaves);
    std::vector<std::unique_ptr<esc::Esc>> reference;
    for (std::size_t k = 0; k < kSlaves; ++k) {
        seg->set_firmware_halted(k, true);  // only the ESCs answer, on both sides
        reference.push_back(
            std::make_unique<esc::Esc>(seg->slave(k).esc().config(), seg->slave(k).esc().eeprom()));
    }
    std::mt19937 rng(indexed_only ? 20261127 : 20261126);
    std::size_t addressed_by_alias = 0, logical_hits = 0, distinct_stations = 0;
    const auto exchange = [&](const std::vector<Datagram>& ds, int n) {
        std::vector<std::uint8_t> a = make_frame(ds), b = a;
        std::size_t len = a.size();
        ASSERT_TRUE(seg->process_frame(Bytes(a.data(), a.size()), len, kNow));
        process_everywhere(reference, b);
        b[6] |= 0x02;  // the mark of a processed frame
        ASSERT_EQ(a, b) << "frame " << n;
    };
    if (indexed_only) {
        std::vector<Datagram> ds;
        for (std::size_t k = 0; k < kSlaves; ++k) {
            ds.push_back({Command::APWR, static_cast<std::uint16_t>(-static_cast<int>(k)), 0x0010, {0, 0}});
            st_le16(ds.back().data.data(), static_cast<std::uint16_t>(0x1000 + k));
        }
        exchange(ds, -1);
    }
    for (int n = 0; n < 4000; ++n) {
        std::vector<Datagram> ds;
        const std::size_t count = 1 + rng() % 6;
        for (std::size_t i = 0; i < count; ++i)
            ds.push_back(random_datagram(rng, indexed_only));
        exchange(ds, n);
        if (::testing::Test::HasFatalFailure()) return;
        std::set<std::uint16_t> stations;
        for (std::size_t k = 0; k < kSlaves; ++k) {
            const esc::Esc& e = seg->slave(k).esc();
            for (std::uint16_t r : std::initializer_list<std::uint16_t>{
                     0x0010, 0x0012, 0x0100, 0x0103, 0x0130, 0x1000, 0x1008, 0x1010, 0x1018})
                ASSERT_EQ(e.peek32(r), reference[k]->peek32(r))
                    << "frame " << n << " slave " << k << " " << r;
            const esc::Esc::Addressing x = e.addressing();
            addressed_by_alias += x.alias_enabled && x.alias != x.station;
            logical_hits +=
                x.log_read_first_bit <= x.log_read_last_bit || x.log_write_first_bit <= x.log_write_last_bit;
            stations.insert(x.station);
        }
        distinct_stations += stations.size();
    }
    // The random frames did reach the cases this is about.
    if (!indexed_only) {
        EXPECT_GT(addressed_by_alias, 100u);
    }
    EXPECT_GT(logical_hits, 100u);
    if (indexed_only) {
        EXPECT_GT(distinct_stations, 4000u * 2);  // not all slaves at one address
    }
}

}  // namespace

TEST(DatagramRouting, AnswersAsIfEveryEscSawEveryDatagram) {
    answers_as_if_every_esc_saw_every_datagram(false);
}

TEST(DatagramRouting, FramesOfConfiguredAddressAndLogicalDatagramsAnswerAsIfEveryEscSawThem) {
    answers_as_if_every_esc_saw_every_datagram(true);
}

TEST(DatagramRouting, AnAutoIncrementDatagramLeavesWithTheAddressCountedUpByEverySlave) {
    const device::DeviceDescription desc = device::digital_output_terminal(8);
    auto seg = esc::make_segment(desc, kSlaves);
    // The third slave answers; the ADP comes back counted up once per slave of the line.
    auto r = raw_datagram(*seg, static_cast<std::uint8_t>(Command::APRD),
                          phys(static_cast<std::uint16_t>(-2), 0), {0, 0}, kNow);
    EXPECT_EQ(r.wkc, 1);
    EXPECT_EQ(r.adp, static_cast<std::uint16_t>(kSlaves - 2));
    // A position beyond the line: nobody answers, the ADP still counts every slave.
    r = raw_datagram(*seg, static_cast<std::uint8_t>(Command::APRD), phys(static_cast<std::uint16_t>(-9), 0),
                     {0, 0}, kNow);
    EXPECT_EQ(r.wkc, 0);
    EXPECT_EQ(r.adp, static_cast<std::uint16_t>(kSlaves - 9));
}

TEST(DatagramRouting, TheIndexNamesTheSlavesOfALogicalRangeInTheOrderOfTheirRanges) {
    // Slaves 0..3 read at bits 0-7, 8-15, 16-23 and 24-31; slave 4 (no FMMU) not at all; slave 5 writes
    // at 12-19, overlapping slaves 1 and 2.
    std::vector<esc::Esc::Addressing> table(7);
    for (std::uint64_t k = 0; k < 4; ++k) {
        table[k].log_read_first_bit = 8 * k;
        table[k].log_read_last_bit = 8 * k + 7;
    }
    table[5].log_write_first_bit = 12;
    table[5].log_write_last_bit = 19;
    // Slave 6 as a master that maps all outputs, then all inputs, leaves it: it writes at 40-47 and reads at
    // 800-807, and is no candidate for what lies between.
    table[6].log_write_first_bit = 40;
    table[6].log_write_last_bit = 47;
    table[6].log_read_first_bit = 800;
    table[6].log_read_last_bit = 807;
    esc::AddressIndex index;
    index.rebuild(table);
    std::vector<std::uint32_t> out{99};  // appends
    index.logical(8, 31, out);
    EXPECT_EQ(out, (std::vector<std::uint32_t>{99, 1, 5, 2, 3}));
    out.clear();
    index.logical(0, 7, out);
    index.logical(20, 20, out);
    EXPECT_EQ(out, (std::vector<std::uint32_t>{0, 2}));
    out.clear();
    index.logical(48, 799, out);
    EXPECT_TRUE(out.empty());
    index.logical(0, 1000, out);
    EXPECT_EQ(out, (std::vector<std::uint32_t>{0, 1, 5, 2, 3, 6, 6}));  // slave 6 by each range
    EXPECT_FALSE(table[6].logical(48, 799));
    EXPECT_TRUE(table[6].logical(47, 48));
    EXPECT_TRUE(table[6].logical(807, 900));
}
