// Helpers shared by the tests: an in-process segment driven by the project's master.
#pragma once

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "coe/coe_application.hpp"
#include "device/device_description.hpp"
#include "esc/segment.hpp"
#include "master/master.hpp"
#include "protocol/registers.hpp"
#include "serve/in_process_link.hpp"

namespace vecat::test {

using SegmentFactory = std::unique_ptr<esc::Segment> (*)(const device::DeviceDescription&, std::size_t,
                                                         const esc::EscConfig&);

// A line of n default devices behind an in-process link, with a master on the other end. By default each
// slave is a CoE application without drive behaviour; the drive tests pass cia402::make_drive_segment.
struct Bench {
    explicit Bench(std::size_t n = 1, esc::EscConfig cfg = {},
                   device::DeviceDescription dev = device::default_drive(),
                   SegmentFactory make = &coe::make_coe_segment)
        : desc(std::move(dev)), seg(make(desc, n, cfg)), link(*seg), master(link) {
        link.set_time(1'000'000'000);
    }
    esc::Slave& slave(std::size_t i = 0) { return seg->slave(i); }
    esc::Esc& escx(std::size_t i = 0) { return seg->slave(i).esc(); }
    coe::CoeApplication& app(std::size_t i = 0) {
        return dynamic_cast<coe::CoeApplication&>(seg->slave(i).app());
    }
    coe::ObjectDictionary& od(std::size_t i = 0) { return app(i).dictionary(); }
    void advance(std::uint64_t ns) {
        now += ns;
        link.set_time(now);
        seg->tick(now);
    }

    device::DeviceDescription desc;
    std::unique_ptr<esc::Segment> seg;
    net::InProcessLink link;
    master::Master master;
    std::uint64_t now = 1'000'000'000;
};

// Output of a shell command (tshark in the capture checks).
inline std::string run_capture(const std::string& cmd) {
    std::string out;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return out;
    char buf[4096];
    std::size_t n;
    while ((n = fread(buf, 1, sizeof buf, p)) > 0)
        out.append(buf, n);
    pclose(p);
    return out;
}

inline std::uint16_t reg(protocol::Reg r) {
    return protocol::addr(r);
}

// One datagram (auto-increment address 0) processed by one ESC, with the test playing the frame: its data
// is read back into `data`; returns the working counter.
inline std::uint16_t esc_datagram(esc::Esc& esc, protocol::Command cmd, std::uint16_t ado,
                                  std::vector<std::uint8_t>& data) {
    std::vector<std::uint8_t> buf(protocol::kDatagramHeaderSize + data.size() + 2, 0);
    buf[0] = static_cast<std::uint8_t>(cmd);
    st_le16(&buf[4], ado);
    st_le16(&buf[6], static_cast<std::uint16_t>(data.size()));
    std::copy(data.begin(), data.end(), buf.begin() + protocol::kDatagramHeaderSize);
    protocol::DatagramView d(buf.data());
    esc.process(d, esc::FrameTiming{1000, 2000});
    std::copy_n(buf.begin() + protocol::kDatagramHeaderSize, data.size(), data.begin());
    return d.wkc();
}

// One datagram sent through a segment as a raw frame; what came back.
struct RawReply {
    bool replied = false;
    std::uint16_t adp = 0;
    std::uint16_t wkc = 0;
    std::vector<std::uint8_t> data;
    std::vector<std::uint8_t> frame;
};

inline RawReply raw_datagram(esc::Segment& seg, std::uint8_t cmd, std::uint32_t address,
                             std::vector<std::uint8_t> data, std::uint64_t now = 1'000'000'000) {
    std::vector<std::uint8_t> f(14 + 2 + 10 + data.size() + 2, 0);
    for (int i = 0; i < 6; ++i)
        f[i] = 0xFF;
    for (int i = 6; i < 12; ++i)
        f[i] = 0x10;
    f[12] = 0x88;
    f[13] = 0xA4;
    st_le16(f.data() + 14, static_cast<std::uint16_t>((10 + data.size() + 2) | 0x1000));
    f[16] = cmd;
    f[17] = 0x42;
    st_le32(f.data() + 18, address);
    st_le16(f.data() + 22, static_cast<std::uint16_t>(data.size()));
    std::copy(data.begin(), data.end(), f.begin() + 26);
    const std::size_t flen = f.size();
    f.resize(std::max<std::size_t>(flen, 60) + 16, 0);
    std::size_t len = flen;
    RawReply r;
    r.replied = seg.process_frame(Bytes(f.data(), f.size()), len, now);
    r.adp = ld_le16(f.data() + 18);
    r.data.assign(f.begin() + 26, f.begin() + 26 + static_cast<long>(data.size()));
    r.wkc = ld_le16(f.data() + 26 + data.size());
    f.resize(len);
    r.frame = f;
    return r;
}

inline std::uint32_t phys(std::uint16_t adp, std::uint16_t ado) {
    return adp | (static_cast<std::uint32_t>(ado) << 16);
}

}  // namespace vecat::test
