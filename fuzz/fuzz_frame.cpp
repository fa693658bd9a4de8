// Fuzz target: EtherCAT frames through a segment of two slaves (esc::Segment::process_frame: frame parser,
// datagram engine, registers, SyncManagers, FMMUs, SII interface, DC, the slaves' firmware: AL state
// machine, mailbox layer, process data). The slaves have a bare process image: the CoE stack behind the
// mailbox has its own target (fuzz_mailbox), and building a dictionary per input would slow this one 3x.
// The description and SII image are built once (esc::DeviceModel); every input gets a new segment from them.
// Input: length-prefixed frames, processed in order 100 us apart against the same segment. The report on the
// master (report::MasterChecks) watches every request and reply, as with vecat run --report.
// Invariants beyond "no crash": a frame is answered exactly when the parser accepts it (or counted lost when
// it left through a port forced open without link); the reply has the request's length (padded to 60); only
// data, working counters, IRQ fields and auto-increment addresses change; auto-increment addresses grow by
// one per slave the frame reached (ports closed by DL control leave slaves out); each datagram's working
// counter grows by at most 3 per slave reached; the header lengths never change.
#include <cstdint>
#include <vector>

#include "fuzz_support.hpp"
#include "report/master_checks.hpp"

using namespace vecat;

namespace {

constexpr std::size_t kSlaves = 2;

bool auto_increment(protocol::Command c) {
    switch (c) {
        case protocol::Command::APRD:
        case protocol::Command::APWR:
        case protocol::Command::APRW:
        case protocol::Command::ARMW:
        case protocol::Command::BRD:
        case protocol::Command::BWR:
        case protocol::Command::BRW:
            return true;
        default:
            return false;
    }
}

// reached: the slaves the frame passed (the master may have closed ports by earlier frames, DL control).
void check_reply(ConstBytes in, ConstBytes out, std::size_t in_len, std::size_t out_len,
                 std::size_t reached) {
    VECAT_FUZZ_CHECK(out_len == std::max(in_len, protocol::kMinEthFrame));
    // Ethernet header: only the "processed" bit of the source address is set.
    for (std::size_t i = 0; i < protocol::kEthHeaderSize; ++i)
        VECAT_FUZZ_CHECK(out[i] == (i == 6 ? (in[i] | 0x02) : in[i]));
    for (std::size_t i = in_len; i < out_len; ++i)
        VECAT_FUZZ_CHECK(out[i] == 0);  // padding
    const protocol::ParsedFrame pf = protocol::parse_frame(in.first(in_len));
    if (pf.error != protocol::FrameError::None) {
        // Passed unprocessed (other EtherCAT types).
        VECAT_FUZZ_CHECK(std::equal(in.begin() + protocol::kEthHeaderSize,
                                    in.begin() + static_cast<long>(in_len),
                                    out.begin() + protocol::kEthHeaderSize));
        return;
    }
    VECAT_FUZZ_CHECK(ld_le16(&in[pf.ecat_offset]) == ld_le16(&out[pf.ecat_offset]));
    for (std::size_t k = 0; k < pf.count; ++k) {
        const std::size_t o = pf.offsets[k];
        const std::uint8_t* a = &in[o];
        const std::uint8_t* b = &out[o];
        VECAT_FUZZ_CHECK(a[0] == b[0] && a[1] == b[1]);      // command, index
        VECAT_FUZZ_CHECK(ld_le16(a + 6) == ld_le16(b + 6));  // length, circulating, more
        const auto cmd = static_cast<protocol::Command>(a[0]);
        const std::uint16_t adp_in = ld_le16(a + 2), adp_out = ld_le16(b + 2);
        if (auto_increment(cmd))
            VECAT_FUZZ_CHECK(adp_out == static_cast<std::uint16_t>(adp_in + reached));
        else
            VECAT_FUZZ_CHECK(adp_out == adp_in);
        VECAT_FUZZ_CHECK(ld_le16(a + 4) == ld_le16(b + 4));
        const std::size_t len = ld_le16(a + 6) & 0x07FF;
        const std::uint16_t wkc_in = ld_le16(a + protocol::kDatagramHeaderSize + len);
        const std::uint16_t wkc_out = ld_le16(b + protocol::kDatagramHeaderSize + len);
        const auto grown = static_cast<std::uint16_t>(wkc_out - wkc_in);
        VECAT_FUZZ_CHECK(grown <= 3 * reached);
        if (cmd == protocol::Command::NOP || a[0] > static_cast<std::uint8_t>(protocol::Command::FRMW)) {
            VECAT_FUZZ_CHECK(grown == 0);
            VECAT_FUZZ_CHECK(std::equal(a + protocol::kDatagramHeaderSize,
                                        a + protocol::kDatagramHeaderSize + len,
                                        b + protocol::kDatagramHeaderSize));
        }
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const auto model = esc::DeviceModel::of(device::default_drive());
    auto seg = esc::make_segment(model, kSlaves);
    report::MasterChecks checks(*seg);
    std::uint64_t now = 1'000'000'000;
    fuzz::Input in(data, size);
    std::vector<std::uint8_t> req, buf;
    while (!in.empty()) {
        const ConstBytes f = in.chunk(protocol::kMaxEthFrame);
        req.assign(f.begin(), f.end());
        buf.assign(std::max(f.size(), protocol::kMinEthFrame), 0);
        std::copy(f.begin(), f.end(), buf.begin());
        req.resize(buf.size(), 0);
        std::size_t len = f.size();
        checks.on_request(f, now);
        const std::size_t reached = seg->reachable();
        const std::uint64_t lost = seg->counters().lost;
        const bool answered = seg->process_frame(Bytes(buf.data(), buf.size()), len, now);
        if (answered) checks.on_reply(ConstBytes(buf.data(), len), now);
        const protocol::ParsedFrame pf = protocol::parse_frame(f);
        const bool parsable =
            pf.error == protocol::FrameError::None || pf.error == protocol::FrameError::NotCommands;
        // A parsable frame is answered, unless it left through a port the master forced open without a
        // link (DL control loop setting "open"): then it is lost, and counted so.
        VECAT_FUZZ_CHECK(answered == parsable || (parsable && seg->counters().lost == lost + 1));
        if (answered) check_reply(req, buf, f.size(), len, reached);
        now += 100'000;
    }
    return 0;
}
