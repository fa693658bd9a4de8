// Shared helpers of the fuzz targets: reading a fuzz input as a sequence of steps, building EtherCAT frames,
// and bringing an in-process slave to PREOP the way a master does (station address, SM0/SM1, AL control).
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "common/bytes.hpp"
#include "device/device_description.hpp"
#include "esc/segment.hpp"
#include "protocol/frame.hpp"
#include "protocol/registers.hpp"

namespace vecat::fuzz {

// A violated invariant is a finding: libFuzzer reports the abort with the input that caused it.
#define VECAT_FUZZ_CHECK(cond)                                                                      \
    do {                                                                                            \
        if (!(cond)) {                                                                              \
            std::fprintf(stderr, "fuzz invariant failed: %s (%s:%d)\n", #cond, __FILE__, __LINE__); \
            std::abort();                                                                           \
        }                                                                                           \
    } while (0)

// The fuzz input read front to back; reads past the end give zeros / empty chunks.
class Input {
  public:
    Input(const std::uint8_t* data, std::size_t size) : p_(data), n_(size) {}
    bool empty() const { return off_ >= n_; }
    std::uint8_t u8() { return off_ < n_ ? p_[off_++] : 0; }
    std::uint16_t u16() {
        const std::uint16_t lo = u8();
        return static_cast<std::uint16_t>(lo | (u8() << 8));
    }
    // A chunk preceded by its 16-bit little-endian length (cut to what is left, at most max).
    ConstBytes chunk(std::size_t max = 0xFFFF) {
        std::size_t len = u16();
        len = std::min({len, max, n_ - std::min(off_, n_)});
        ConstBytes c(p_ + off_, len);
        off_ += len;
        return c;
    }

  private:
    const std::uint8_t* p_;
    std::size_t n_;
    std::size_t off_ = 0;
};

// Appends a length-prefixed chunk in the format Input::chunk reads (the corpus generator writes these).
inline void put_chunk(std::vector<std::uint8_t>& out, ConstBytes c) {
    out.push_back(static_cast<std::uint8_t>(c.size()));
    out.push_back(static_cast<std::uint8_t>(c.size() >> 8));
    out.insert(out.end(), c.begin(), c.end());
}

// One Ethernet frame with one datagram (as a master builds it), processed by the segment. Returns the
// working counter; data receives what came back.
inline std::uint16_t transact(esc::Segment& seg, protocol::Command cmd, std::uint16_t adp, std::uint16_t ado,
                              Bytes data, std::uint64_t now_ns) {
    std::vector<std::uint8_t> f(
        std::max<std::size_t>(protocol::kMinEthFrame, protocol::kEthHeaderSize + protocol::kEcatHeaderSize +
                                                          protocol::kDatagramHeaderSize + data.size() +
                                                          protocol::kWkcSize),
        0);
    std::memset(f.data(), 0xFF, 6);
    f[6] = 0x02;  // locally administered master address
    f[12] = static_cast<std::uint8_t>(protocol::kEtherTypeEtherCat >> 8);  // EtherType is big-endian
    f[13] = static_cast<std::uint8_t>(protocol::kEtherTypeEtherCat & 0xFF);
    const std::size_t dlen = data.size();
    st_le16(f.data() + 14,
            static_cast<std::uint16_t>((protocol::kDatagramHeaderSize + dlen + protocol::kWkcSize) |
                                       (protocol::kEcatTypeCommands << 12)));
    std::uint8_t* d = f.data() + 16;
    d[0] = static_cast<std::uint8_t>(cmd);
    st_le16(d + 2, adp);
    st_le16(d + 4, ado);
    st_le16(d + 6, static_cast<std::uint16_t>(dlen));
    std::memcpy(d + protocol::kDatagramHeaderSize, data.data(), dlen);
    std::size_t len = protocol::kEthHeaderSize + protocol::kEcatHeaderSize + protocol::kDatagramHeaderSize +
                      dlen + protocol::kWkcSize;
    if (!seg.process_frame(Bytes(f.data(), f.size()), len, now_ns)) return 0;
    std::memcpy(data.data(), d + protocol::kDatagramHeaderSize, dlen);
    return ld_le16(d + protocol::kDatagramHeaderSize + dlen);
}

inline std::uint16_t fpwr(esc::Segment& seg, std::uint16_t station, std::uint16_t ado, ConstBytes v,
                          std::uint64_t now_ns) {
    std::vector<std::uint8_t> b(v.begin(), v.end());
    return transact(seg, protocol::Command::FPWR, station, ado, Bytes(b.data(), b.size()), now_ns);
}

// Reads the read mailbox (SM1 of the description) into buf when its status says "full" (otherwise the read
// sees plain memory). True when buf holds a reply.
inline bool read_mailbox(esc::Segment& seg, std::uint16_t station, const device::SyncManagerConfig& sm1,
                         std::vector<std::uint8_t>& buf, std::uint64_t now_ns) {
    std::uint8_t status = 0;
    transact(seg, protocol::Command::FPRD, station, protocol::sm_addr(1) + protocol::sm::Status,
             Bytes(&status, 1), now_ns);
    buf.assign(sm1.length, 0);
    const auto wkc = transact(seg, protocol::Command::FPRD, station, sm1.start, buf, now_ns);
    return wkc == 1 && (status & protocol::sm::StatusMailboxFull);
}

inline constexpr std::uint16_t kFirstStation = 0x1001;

// Station addresses 0x1001.. by position, SM0/SM1 from the description, then AL control PREOP: the slaves
// answer mailboxes afterwards. Returns false if a slave did not reach PREOP.
inline bool bring_to_preop(esc::Segment& seg, const device::DeviceDescription& d, std::uint64_t& now_ns) {
    for (std::size_t i = 0; i < seg.size(); ++i) {
        std::uint8_t a[2];
        st_le16(a, static_cast<std::uint16_t>(kFirstStation + i));
        transact(seg, protocol::Command::APWR, static_cast<std::uint16_t>(-static_cast<int>(i)),
                 protocol::addr(protocol::Reg::StationAddress), Bytes(a, 2), now_ns);
    }
    for (std::size_t i = 0; i < seg.size(); ++i) {
        const auto station = static_cast<std::uint16_t>(kFirstStation + i);
        for (unsigned sm = 0; sm < 2 && sm < d.sync_managers.size(); ++sm) {
            const auto& c = d.sync_managers[sm];
            std::uint8_t r[8] = {};
            st_le16(r, c.start);
            st_le16(r + 2, c.length);
            r[4] = c.control;
            r[6] = 0x01;  // enable
            fpwr(seg, station, static_cast<std::uint16_t>(protocol::addr(protocol::Reg::Sm0) + 8 * sm),
                 ConstBytes(r, 8), now_ns);
        }
        const std::uint8_t ctl[2] = {static_cast<std::uint8_t>(protocol::AlState::PreOp), 0};
        fpwr(seg, station, protocol::addr(protocol::Reg::AlControl), ConstBytes(ctl, 2), now_ns);
    }
    now_ns += 1'000'000;
    seg.tick(now_ns);
    for (std::size_t i = 0; i < seg.size(); ++i)
        if (seg.slave(i).state() != protocol::AlState::PreOp) return false;
    return true;
}

}  // namespace vecat::fuzz
