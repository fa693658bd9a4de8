// Fuzz target: EoE (ETG.1000.6 5.7). The parsers of protocol/eoe.hpp and of the device's IP responder
// (src/eoe/ip_responder.hpp) on raw bytes, and the EoE server of one slave (a small queue to the master, an
// Ethernet side that keeps what it gets) behind its mailbox, brought to PREOP like a master does. The input
// is a sequence of steps, each an opcode byte and its argument:
//   0, 1  an EoE message into SM0: the two header words, then length-prefixed data (fragments, services)
//   2     a whole mailbox write (length-prefixed bytes, padded to the SM0 length: any type, any header)
//   3     the master reads SM1
//   4     AL control write (one byte: INIT, PREOP, BOOT, SAFEOP, OP or anything)
//   5     a frame from the device's Ethernet side (length-prefixed bytes)
//   6     the parsers alone on a length-prefixed chunk: header, IP parameter and filter blocks (and their
//         round trips), the responder's answer
// Invariants: every reply fits SM1 with its header length; replies are mailbox errors or EoE messages a
// slave may send (fragments, responses with a result code of ETG.1000.6, an unsupported type echoed with
// 0x0002), never a request; the half frame stays within the reassembly buffer, the queue within its
// slots; frames out of the Ethernet side are whole frames no larger than the buffer; a parsed block written
// again parses the same; the slave stays in a valid AL state.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "coe/coe_application.hpp"
#include "eoe/eoe_server.hpp"
#include "eoe/ip_responder.hpp"
#include "esc/mailbox.hpp"
#include "fuzz_support.hpp"
#include "protocol/eoe.hpp"

using namespace vecat;

namespace {

constexpr std::size_t kQueue = 4;

struct Sink final : eoe::EthernetPort {
    std::size_t frames = 0;
    void send(ConstBytes f) override {
        VECAT_FUZZ_CHECK(f.size() >= eoe::kEthernetHeaderSize && f.size() <= eoe::EoeServer::kRxBufferSize);
        ++frames;
    }
};

bool slave_may_send(std::uint8_t type) {
    using T = protocol::EoeFrameType;
    const auto t = static_cast<T>(type);
    return t == T::Fragment || t == T::SetIpResponse || t == T::SetFilterResponse || t == T::GetIpResponse ||
           t == T::GetFilterResponse;
}

void check_reply(ConstBytes r) {
    const auto h = protocol::parse_mailbox_header(r);
    VECAT_FUZZ_CHECK(h.has_value());
    VECAT_FUZZ_CHECK(h->length <= r.size() - protocol::kMailboxHeaderSize);
    const auto type = static_cast<protocol::MailboxType>(h->type);
    const ConstBytes p = r.subspan(protocol::kMailboxHeaderSize, h->length);
    if (type == protocol::MailboxType::Error) {
        VECAT_FUZZ_CHECK(h->length >= 4 && ld_le16(p.data()) == protocol::kMailboxErrorService);
        return;
    }
    if (type == protocol::MailboxType::CoE || type == protocol::MailboxType::FoE) return;  // their targets'
    VECAT_FUZZ_CHECK(type == protocol::MailboxType::EoE);
    const auto e = protocol::parse_eoe_header(p);
    VECAT_FUZZ_CHECK(e.has_value());
    if (e->frame_type() == protocol::EoeFrameType::Fragment) {
        VECAT_FUZZ_CHECK(p.size() > protocol::kEoeHeaderSize);
        return;
    }
    const std::uint16_t res = e->result();
    VECAT_FUZZ_CHECK(e->last_fragment);
    if (slave_may_send(e->type))  // a response, or a response type the master sent, echoed as unsupported
        VECAT_FUZZ_CHECK(res == 0x0000 || res == 0x0001 || res == 0x0002 || res == 0x0201 || res == 0x0202 ||
                         res == 0x0401);
    else
        VECAT_FUZZ_CHECK(res == static_cast<std::uint16_t>(protocol::EoeResult::UnsupportedFrameType));
}

void parsers(ConstBytes c) {
    if (const auto h = protocol::parse_eoe_header(c)) {
        std::array<std::uint8_t, 4> again{};
        protocol::write_eoe_header(again, *h);
        // Bits 11-15 of word 1 are reserved and written as 0.
        VECAT_FUZZ_CHECK(again[0] == c[0] && (again[1] & 0x07) == (c[1] & 0x07) && again[2] == c[2] &&
                         again[3] == c[3]);
    }
    if (const auto p = protocol::parse_eoe_ip(c)) {
        std::array<std::uint8_t, protocol::kEoeIpBlockMaxSize> b{};
        const std::size_t n = protocol::write_eoe_ip(b, *p);
        VECAT_FUZZ_CHECK(n > 0);
        auto q = protocol::parse_eoe_ip(ConstBytes(b.data(), n));
        VECAT_FUZZ_CHECK(q.has_value());
        VECAT_FUZZ_CHECK(*q == *p);
    }
    if (const auto f = protocol::parse_eoe_filter(c)) {
        std::array<std::uint8_t, protocol::kEoeFilterBlockSize> b{};
        VECAT_FUZZ_CHECK(protocol::write_eoe_filter(b, *f) == b.size());
        VECAT_FUZZ_CHECK(protocol::parse_eoe_filter(b) == f);
    }
    std::array<std::uint8_t, protocol::kEthernetMaxFrame> out{};
    std::size_t len = 0;
    const protocol::MacAddress mac = eoe::default_mac(0);
    const auto a = eoe::answer(c, mac, 0x0A000005, out, len);
    if (a == eoe::Answer::None)
        VECAT_FUZZ_CHECK(len == 0);
    else
        VECAT_FUZZ_CHECK(len >= 60 && len <= out.size() &&
                         std::equal(mac.begin(), mac.end(), out.begin() + 6));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const auto model = esc::DeviceModel::of(device::default_drive());
    static const auto& dev = *model.description;
    static const auto sm0 = dev.sync_managers.at(0);
    static const auto sm1 = dev.sync_managers.at(1);
    auto seg = coe::make_coe_segment(model, 1);
    eoe::EoeOptions opt;
    opt.queue_frames = kQueue;
    eoe::attach_eoe(*seg, opt);
    std::uint64_t now = 1'000'000'000;
    if (!fuzz::bring_to_preop(*seg, dev, now)) std::abort();
    auto& slave = seg->slave(0);
    auto* server = eoe::eoe_server(slave);
    VECAT_FUZZ_CHECK(server != nullptr);
    Sink sink;
    server->attach(&sink);
    const std::uint16_t st = fuzz::kFirstStation;
    std::vector<std::uint8_t> buf;
    std::uint8_t counter = 0;
    fuzz::Input in(data, size);
    unsigned steps = 0;
    while (!in.empty() && ++steps < 512) {
        switch (in.u8() % 7) {
            case 0:
            case 1: {
                const std::uint16_t w1 = in.u16();
                const std::uint16_t w2 = in.u16();
                const ConstBytes tail = in.chunk(sm0.length);
                buf.assign(sm0.length, 0);
                const std::size_t room = buf.size() - protocol::kMailboxHeaderSize - protocol::kEoeHeaderSize;
                const std::size_t n = std::min(tail.size(), room);
                st_le16(buf.data() + protocol::kMailboxHeaderSize, w1);
                st_le16(buf.data() + protocol::kMailboxHeaderSize + 2, w2);
                std::copy_n(tail.begin(), n,
                            buf.begin() + protocol::kMailboxHeaderSize + protocol::kEoeHeaderSize);
                protocol::MailboxHeader h;
                h.length = static_cast<std::uint16_t>(protocol::kEoeHeaderSize + n);
                h.type = static_cast<std::uint8_t>(protocol::MailboxType::EoE);
                counter = static_cast<std::uint8_t>(counter % 7 + 1);
                h.counter = counter;
                protocol::write_mailbox_header(buf, h);
                fuzz::fpwr(*seg, st, sm0.start, buf, now);
                break;
            }
            case 2: {
                const ConstBytes m = in.chunk(sm0.length);
                buf.assign(sm0.length, 0);
                std::copy(m.begin(), m.end(), buf.begin());
                fuzz::fpwr(*seg, st, sm0.start, buf, now);
                break;
            }
            case 3: {
                if (fuzz::read_mailbox(*seg, st, sm1, buf, now)) check_reply(buf);
                break;
            }
            case 4: {
                const std::uint8_t ctl[2] = {in.u8(), 0};
                fuzz::fpwr(*seg, st, protocol::addr(protocol::Reg::AlControl), ConstBytes(ctl, 2), now);
                break;
            }
            case 5:
                server->from_ethernet(in.chunk(2048));
                break;
            case 6:
                parsers(in.chunk());
                break;
        }
        now += 10'000;
        const auto s = static_cast<std::uint8_t>(slave.state());
        VECAT_FUZZ_CHECK(s == 1 || s == 2 || s == 3 || s == 4 || s == 8);
        VECAT_FUZZ_CHECK(server->reassembling() <= eoe::EoeServer::kRxBufferSize);
        VECAT_FUZZ_CHECK(server->queued() <= kQueue);
    }
    return 0;
}
