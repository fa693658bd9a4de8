// Fuzz target: SoE (ETG.1000.6 5.6). The parser of protocol/soe.hpp and the attribute word on raw bytes,
// and the two-axis SoE drive of one slave (src/soe: its server, drive numbers 0 and 1 with their IDNs,
// telegrams, commands and drive cores; 2-7 answered 0x800A) behind its mailbox, brought to PREOP like a
// master does. The input is a sequence of steps, each an opcode byte and its argument:
//   0, 1  an SoE message into SM0: header byte (opcode, incomplete, error, drive), elements, 16-bit IDN or
//         fragments left, length-prefixed data
//   2     a whole mailbox write (length-prefixed bytes, padded to the SM0 length: any type, any header)
//   3     the master reads SM1
//   4     AL control write (one byte: INIT, PREOP, SAFEOP, OP or anything)
//   5     the parsers alone on a length-prefixed chunk: parse_soe (and its round trip), SoeAttribute
// Invariants: every reply fits SM1 with its header length; replies are mailbox errors or SoE messages a
// slave may send (read or write response, notification), an error response carries a code of the SoE
// error list; a parsed message written again gives the same bytes; the server holds at most its transfer
// limit; the slave stays in a valid AL state.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "device/soe_drive.hpp"
#include "esc/mailbox.hpp"
#include "fuzz_support.hpp"
#include "protocol/soe.hpp"
#include "soe/soe_drive.hpp"

using namespace vecat;

namespace {

bool known_error(std::uint16_t c) {
    const auto e = static_cast<protocol::SoeError>(c);
    return protocol::describe(e) != "Unknown SoE error";
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
    VECAT_FUZZ_CHECK(type == protocol::MailboxType::SoE);
    const auto m = protocol::parse_soe(p);
    VECAT_FUZZ_CHECK(m.has_value());
    VECAT_FUZZ_CHECK(m->op == protocol::SoeOpCode::ReadResponse ||
                     m->op == protocol::SoeOpCode::WriteResponse ||
                     m->op == protocol::SoeOpCode::Notification);
    if (m->error) {
        VECAT_FUZZ_CHECK(m->data.size() == 2 && !m->incomplete);
        VECAT_FUZZ_CHECK(known_error(*m->error_code()));
    }
    if (m->op == protocol::SoeOpCode::Notification)
        VECAT_FUZZ_CHECK(m->data.size() == 2 && m->elements == protocol::soe_element::DataState);
}

void parsers(ConstBytes c) {
    if (const auto m = protocol::parse_soe(c)) {
        std::vector<std::uint8_t> again(c.size());
        VECAT_FUZZ_CHECK(protocol::write_soe(again, *m) == c.size());
        VECAT_FUZZ_CHECK(std::equal(again.begin(), again.end(), c.begin()));
    } else {
        VECAT_FUZZ_CHECK(c.size() < protocol::kSoeHeaderSize);
    }
    if (c.size() >= 4) {
        // Every attribute word but its reserved bits (23, 31) round-trips.
        const std::uint32_t w = ld_le32(c.data()) & ~((1u << 23) | (1u << 31));
        VECAT_FUZZ_CHECK(protocol::SoeAttribute::unpack(w).pack() == w);
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const auto model = esc::DeviceModel::of(device::soe_drive(2));
    static const auto& dev = *model.description;
    static const auto sm0 = dev.sync_managers.at(0);
    static const auto sm1 = dev.sync_managers.at(1);
    auto seg = esc::make_segment(model, 1, {}, soe::make_soe_drive);
    std::uint64_t now = 1'000'000'000;
    if (!fuzz::bring_to_preop(*seg, dev, now)) std::abort();
    auto& slave = seg->slave(0);
    auto* drive = dynamic_cast<soe::SoeDrive*>(&slave.app());
    VECAT_FUZZ_CHECK(drive != nullptr && drive->server() != nullptr);
    const std::uint16_t st = fuzz::kFirstStation;
    std::vector<std::uint8_t> buf;
    std::uint8_t counter = 0;
    fuzz::Input in(data, size);
    unsigned steps = 0;
    while (!in.empty() && ++steps < 512) {
        switch (in.u8() % 6) {
            case 0:
            case 1: {
                const std::uint8_t flags = in.u8();
                protocol::SoeMessage m;
                m.op = static_cast<protocol::SoeOpCode>(flags & 7u);
                m.incomplete = (flags & 0x08) != 0;
                m.error = (flags & 0x10) != 0;
                m.drive = static_cast<std::uint8_t>(flags >> 5);
                m.elements = in.u8();
                m.idn_or_fragments = in.u16();
                m.data = in.chunk(sm0.length);
                buf.assign(sm0.length, 0);
                const std::size_t n = protocol::write_soe(Bytes(buf.data() + protocol::kMailboxHeaderSize,
                                                                buf.size() - protocol::kMailboxHeaderSize),
                                                          m);
                protocol::MailboxHeader h;
                h.length = static_cast<std::uint16_t>(n);
                h.type = static_cast<std::uint8_t>(protocol::MailboxType::SoE);
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
                parsers(in.chunk());
                break;
        }
        now += 10'000;
        seg->tick(now);
        const auto s = static_cast<std::uint8_t>(slave.state());
        VECAT_FUZZ_CHECK(s == 1 || s == 2 || s == 3 || s == 4 || s == 8);
        VECAT_FUZZ_CHECK(drive->server()->buffered() <= soe::SoeServer::kMaxTransfer + 1024 + 8);
        // The MDT and AT stay what the configuration lists say, within the lists' maximum (two axes).
        VECAT_FUZZ_CHECK(drive->output_bytes() <= 2 * (2 + 8 * 8) && drive->input_bytes() <= 2 * (2 + 8 * 8));
    }
    return 0;
}
