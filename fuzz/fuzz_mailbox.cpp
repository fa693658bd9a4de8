// Fuzz target: the mailbox layer and the CoE stack of one CiA 402 drive (esc::Slave mailbox handling,
// coe::SdoServer: expedited/normal/segmented SDO, complete access, SDO information, emergencies, the
// drive's value checks). The slave is brought to PREOP like a master does; the input is a sequence of
// steps, each an opcode byte and its argument:
//   0, 1  a mailbox write into SM0 (length-prefixed bytes, padded to the SM0 length)
//   2     the master reads SM1
//   3     the master toggles the SM1 repeat request
//   4     AL control write (one byte)
//   5     time passes (up to 3.75 ms in servo periods of 250 us; the drive simulates every servo step, which
//         was most of an input's cost: the drive's own dynamics are not what this target explores)
// Every step also advances the time by 10 us; the slave's firmware runs after each frame it receives.
//   6     the application raises a fault (an emergency to queue)
// Invariants: every reply fits SM1 with its header length; replies are mailbox errors or CoE messages the
// server may send; the slave stays in a valid AL state.
#include <cstdint>
#include <vector>

#include "cia402/drive.hpp"
#include "esc/mailbox.hpp"
#include "fuzz_support.hpp"
#include "protocol/coe.hpp"

using namespace vecat;

namespace {

void check_reply(ConstBytes r) {
    const auto h = protocol::parse_mailbox_header(r);
    VECAT_FUZZ_CHECK(h.has_value());
    VECAT_FUZZ_CHECK(h->length <= r.size() - protocol::kMailboxHeaderSize);
    const auto type = static_cast<protocol::MailboxType>(h->type);
    VECAT_FUZZ_CHECK(type == protocol::MailboxType::Error || type == protocol::MailboxType::CoE);
    if (type == protocol::MailboxType::Error) {
        VECAT_FUZZ_CHECK(h->length >= 4 && ld_le16(&r[6]) == 0x0001);
        return;
    }
    VECAT_FUZZ_CHECK(h->length >= protocol::kCoeHeaderSize);
    const auto service = protocol::coe_service(ld_le16(&r[6]));
    VECAT_FUZZ_CHECK(
        service == protocol::CoeService::Emergency || service == protocol::CoeService::SdoRequest ||
        service == protocol::CoeService::SdoResponse || service == protocol::CoeService::SdoInformation);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // Description, SII image and dictionary objects are built once; every input gets a new drive from them.
    static const auto model = esc::DeviceModel::of(device::default_drive());
    static const auto& dev = *model.description;
    static const auto sm0 = dev.sync_managers.at(0);
    static const auto sm1 = dev.sync_managers.at(1);
    auto seg = cia402::make_drive_segment(model, 1);
    std::uint64_t now = 1'000'000'000;
    if (!fuzz::bring_to_preop(*seg, dev, now)) std::abort();
    auto& slave = seg->slave(0);
    auto* app = dynamic_cast<coe::CoeApplication*>(&slave.app());
    const std::uint16_t st = fuzz::kFirstStation;
    std::vector<std::uint8_t> buf;
    fuzz::Input in(data, size);
    unsigned steps = 0;
    while (!in.empty() && ++steps < 512) {
        switch (in.u8() % 7) {
            case 0:
            case 1: {
                const ConstBytes m = in.chunk(sm0.length);
                buf.assign(sm0.length, 0);
                std::copy(m.begin(), m.end(), buf.begin());
                fuzz::fpwr(*seg, st, sm0.start, buf, now);
                break;
            }
            case 2: {
                if (fuzz::read_mailbox(*seg, st, sm1, buf, now)) check_reply(buf);
                break;
            }
            case 3: {
                const std::uint16_t act = protocol::sm_addr(1) + protocol::sm::Activate;
                std::uint8_t v = 0;
                fuzz::transact(*seg, protocol::Command::FPRD, st, act, Bytes(&v, 1), now);
                v ^= protocol::sm::ActRepeatRequest;
                fuzz::fpwr(*seg, st, act, ConstBytes(&v, 1), now);
                break;
            }
            case 4: {
                const std::uint8_t ctl[2] = {in.u8(), 0};
                fuzz::fpwr(*seg, st, protocol::addr(protocol::Reg::AlControl), ConstBytes(ctl, 2), now);
                break;
            }
            case 5:
                now += cia402::Drive::kServoPeriodNs * (in.u8() & 0x0Fu);
                seg->tick(now);
                break;
            case 6:
                if (app) app->raise_fault(in.u16(), in.u8());
                seg->tick(now);
                break;
        }
        // The firmware of the slave runs after each of its frames (and ticks above): no tick per step.
        now += 10'000;
        const auto s = static_cast<std::uint8_t>(slave.state());
        VECAT_FUZZ_CHECK(s == 1 || s == 2 || s == 3 || s == 4 || s == 8);
    }
    return 0;
}
