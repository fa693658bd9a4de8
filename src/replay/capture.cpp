// Reading captures through libpcap (pcap and pcapng), and pairing master frames with their replies.
#include "replay/capture.hpp"

#include <pcap/pcap.h>

#include <cstdio>
#include <memory>

#include "protocol/frame.hpp"

namespace vecat::replay {

namespace {

struct PcapCloser {
    void operator()(pcap_t* p) const noexcept { pcap_close(p); }
};
using PcapHandle = std::unique_ptr<pcap_t, PcapCloser>;

bool is_ethercat_commands(ConstBytes f) {
    const protocol::ParsedFrame pf = protocol::parse_frame(f);
    return pf.error == protocol::FrameError::None && pf.count > 0;
}

// Reads every packet of an open handle. pcap_close() also closes the FILE* it was opened on.
Capture read_all(PcapHandle h, const std::string& name) {
    const int link = pcap_datalink(h.get());
    if (link != DLT_EN10MB)
        throw CaptureError(name + ": link type " + std::to_string(link) + " (" +
                           (pcap_datalink_val_to_name(link) ? pcap_datalink_val_to_name(link) : "unknown") +
                           "), not Ethernet");
    Capture c;
    const bool nano = pcap_get_tstamp_precision(h.get()) == PCAP_TSTAMP_PRECISION_NANO;
    for (;;) {
        pcap_pkthdr* hdr = nullptr;
        const u_char* data = nullptr;
        const int r = pcap_next_ex(h.get(), &hdr, &data);
        if (r == PCAP_ERROR_BREAK) break;  // end of file
        if (r != 1) {
            c.problem = "after frame " + std::to_string(c.total) + ": " + pcap_geterr(h.get());
            break;
        }
        ++c.total;
        const ConstBytes bytes(data, hdr->caplen);
        if (!is_ethercat_commands(bytes)) {
            ++c.other_protocol;
            continue;
        }
        CapturedFrame f;
        f.number = c.total;
        f.time_ns = static_cast<std::uint64_t>(hdr->ts.tv_sec) * 1'000'000'000ull +
                    static_cast<std::uint64_t>(hdr->ts.tv_usec) * (nano ? 1ull : 1000ull);
        f.bytes.assign(bytes.begin(), bytes.end());
        c.frames.push_back(std::move(f));
    }
    return c;
}

}  // namespace

Capture read_capture(const std::string& path) {
    char err[PCAP_ERRBUF_SIZE] = {};
    PcapHandle h(pcap_open_offline_with_tstamp_precision(path.c_str(), PCAP_TSTAMP_PRECISION_NANO, err));
    if (!h) throw CaptureError(path + ": " + err);
    return read_all(std::move(h), path);
}

Capture read_capture(ConstBytes file, const std::string& name) {
    // fmemopen of an empty buffer fails; an empty file is no capture either.
    if (file.empty()) throw CaptureError(name + ": empty file");
    FILE* fp = fmemopen(const_cast<std::uint8_t*>(file.data()), file.size(), "rb");
    if (!fp) throw CaptureError(name + ": cannot be read");
    char err[PCAP_ERRBUF_SIZE] = {};
    PcapHandle h(pcap_fopen_offline_with_tstamp_precision(fp, PCAP_TSTAMP_PRECISION_NANO, err));
    if (!h) {
        std::fclose(fp);
        throw CaptureError(name + ": " + err);
    }
    return read_all(std::move(h), name);
}

namespace {

constexpr std::size_t kSourceMac0 = 6;        // first byte of the source address
constexpr std::uint8_t kForwardedBit = 0x02;  // set by every ESC that forwards the frame
constexpr std::size_t kReplyWindow = 16;      // frames after a request in which its reply is looked for

bool forwarded(const CapturedFrame& f) {
    return (f.bytes[kSourceMac0] & kForwardedBit) != 0;
}

// Same datagrams (command, index, length, in order): the reply of this request, as far as the frame says.
bool same_datagrams(const CapturedFrame& a, const CapturedFrame& b) {
    const protocol::ParsedFrame pa = protocol::parse_frame(a.bytes);
    const protocol::ParsedFrame pb = protocol::parse_frame(b.bytes);
    if (pa.count != pb.count) return false;
    for (std::size_t i = 0; i < pa.count; ++i) {
        const std::uint8_t* x = a.bytes.data() + pa.offsets[i];
        const std::uint8_t* y = b.bytes.data() + pb.offsets[i];
        if (x[protocol::datagram::Command] != y[protocol::datagram::Command] ||
            x[protocol::datagram::Index] != y[protocol::datagram::Index] ||
            (ld_le16(x + protocol::datagram::LengthFlags) & protocol::datagram::LengthMask) !=
                (ld_le16(y + protocol::datagram::LengthFlags) & protocol::datagram::LengthMask))
            return false;
    }
    return true;
}

}  // namespace

Pairing pair_frames(const Capture& c) {
    Pairing p;
    std::vector<std::uint8_t> used(c.frames.size(), 0);
    for (std::size_t i = 0; i < c.frames.size(); ++i) {
        if (used[i]) continue;
        const CapturedFrame& f = c.frames[i];
        if (forwarded(f)) {
            // A reply without its request in the capture.
            used[i] = 1;
            p.exchanges.push_back({i, i, false});
            continue;
        }
        bool answered = false;
        for (std::size_t j = i + 1; j < c.frames.size() && j <= i + kReplyWindow; ++j) {
            const CapturedFrame& r = c.frames[j];
            if (used[j] || !forwarded(r) ||
                (r.bytes[kSourceMac0] & ~kForwardedBit) != (f.bytes[kSourceMac0] & ~kForwardedBit) ||
                !same_datagrams(f, r))
                continue;
            used[i] = used[j] = 1;
            p.exchanges.push_back({i, j, true});
            answered = true;
            break;
        }
        if (!answered) ++p.unanswered;
    }
    return p;
}

}  // namespace vecat::replay
