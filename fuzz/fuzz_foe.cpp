// Fuzz target: FoE (ETG.1000.6 5.8) and the BOOT state. The parser of protocol/foe.hpp and of the firmware
// header (src/foe/firmware.hpp) on raw bytes, and the FoE server of one slave (files in memory, a small size
// limit) behind its mailbox, brought to PREOP like a master does. The input is a sequence of steps, each an
// opcode byte and its argument:
//   0, 1  an FoE message into SM0: opcode byte, 32-bit value, length-prefixed tail (file name or data)
//   2     a whole mailbox write (length-prefixed bytes, padded to the SM0 length: any type, any header)
//   3     the master reads SM1
//   4     AL control write (one byte: INIT, PREOP, BOOT, SAFEOP, OP or anything)
//   5     the parsers alone on a length-prefixed chunk: parse_foe (and its round trip), parse_firmware
// Invariants: every reply fits SM1 with its header length; replies are mailbox errors or FoE messages a slave
// may send (data, ack, error with a code of Table 93, busy), never a request; a parsed message written again
// gives the same bytes; the server's file buffer stays within the size limit; the slave stays in a valid AL
// state and the SII revision changes only on BOOT -> INIT after a firmware was accepted.
#include <cstdint>
#include <vector>

#include "coe/coe_application.hpp"
#include "esc/mailbox.hpp"
#include "foe/firmware.hpp"
#include "foe/foe_server.hpp"
#include "fuzz_support.hpp"
#include "protocol/foe.hpp"

using namespace vecat;

namespace {

constexpr std::size_t kMaxFile = 2048;

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
    // CoE replies (the application's, outside BOOT) are the mailbox target's business; FoE is checked here.
    if (type == protocol::MailboxType::CoE) return;
    VECAT_FUZZ_CHECK(type == protocol::MailboxType::FoE);
    const auto m = protocol::parse_foe(p);
    VECAT_FUZZ_CHECK(m.has_value());
    VECAT_FUZZ_CHECK(m->op == protocol::FoeOpCode::Data || m->op == protocol::FoeOpCode::Ack ||
                     m->op == protocol::FoeOpCode::Error || m->op == protocol::FoeOpCode::Busy);
    if (m->op == protocol::FoeOpCode::Error)
        VECAT_FUZZ_CHECK(m->value >= static_cast<std::uint32_t>(protocol::FoeError::NotDefined) &&
                         m->value <= static_cast<std::uint32_t>(protocol::FoeError::ProgramError));
    if (m->op == protocol::FoeOpCode::Ack || m->op == protocol::FoeOpCode::Busy)
        VECAT_FUZZ_CHECK(m->tail.size() < 64);
}

void parsers(ConstBytes c) {
    if (const auto m = protocol::parse_foe(c)) {
        std::vector<std::uint8_t> again(c.size());
        const std::size_t n = protocol::write_foe(again, m->op, m->value, m->tail);
        VECAT_FUZZ_CHECK(n == c.size());
        again[1] = c[1];  // the reserved byte is written as 0
        VECAT_FUZZ_CHECK(std::equal(again.begin(), again.end(), c.begin()));
    } else {
        VECAT_FUZZ_CHECK(c.size() < protocol::kFoeHeaderSize || !protocol::is_foe_opcode(c[0]));
    }
    std::string why;
    if (!foe::parse_firmware(c, &why)) VECAT_FUZZ_CHECK(!why.empty());
    const auto name =
        foe::trim_file_name(std::string_view(reinterpret_cast<const char*>(c.data()), c.size()));
    if (foe::valid_file_name(name))
        VECAT_FUZZ_CHECK(name.find('/') == std::string_view::npos &&
                         name.find("..") == std::string_view::npos);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const auto model = esc::DeviceModel::of(device::default_drive());
    static const auto& dev = *model.description;
    static const auto sm0 = dev.sync_managers.at(0);
    static const auto sm1 = dev.sync_managers.at(1);
    auto seg = coe::make_coe_segment(model, 1);
    foe::FoeOptions opt;
    opt.max_file_size = kMaxFile;
    foe::attach_foe(*seg, opt);
    std::uint64_t now = 1'000'000'000;
    if (!fuzz::bring_to_preop(*seg, dev, now)) std::abort();
    auto& slave = seg->slave(0);
    auto* server = foe::foe_server(slave);
    VECAT_FUZZ_CHECK(server != nullptr);
    const std::uint16_t st = fuzz::kFirstStation;
    std::vector<std::uint8_t> buf;
    std::uint8_t counter = 0;
    fuzz::Input in(data, size);
    unsigned steps = 0;
    while (!in.empty() && ++steps < 512) {
        const auto before = static_cast<std::uint8_t>(slave.state());
        const auto pending = server->pending_revision();
        const auto revision = slave.sii_revision();
        switch (in.u8() % 6) {
            case 0:
            case 1: {
                const std::uint8_t op = in.u8();
                const std::uint32_t value =
                    static_cast<std::uint32_t>(in.u16()) | (std::uint32_t{in.u16()} << 16);
                const ConstBytes tail = in.chunk(sm0.length);
                buf.assign(sm0.length, 0);
                const std::size_t n = protocol::write_foe(Bytes(buf.data() + protocol::kMailboxHeaderSize,
                                                                buf.size() - protocol::kMailboxHeaderSize),
                                                          static_cast<protocol::FoeOpCode>(op), value, tail);
                protocol::MailboxHeader h;
                h.length = static_cast<std::uint16_t>(n);
                h.type = static_cast<std::uint8_t>(protocol::MailboxType::FoE);
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
        const auto s = static_cast<std::uint8_t>(slave.state());
        VECAT_FUZZ_CHECK(s == 1 || s == 2 || s == 3 || s == 4 || s == 8);
        // The revision changes on BOOT -> INIT with a firmware accepted, and only then.
        const bool update = before == 3 && s == 1 && pending;
        VECAT_FUZZ_CHECK(slave.sii_revision() == (update ? *pending : revision));
        VECAT_FUZZ_CHECK(server->buffered() <= kMaxFile);
    }
    return 0;
}
