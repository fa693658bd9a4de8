// Fuzz target: the SII EEPROM interface of the ESC (registers 0x0500-0x050F: control, address, data;
// read, write, reload commands, error bits) and the SII parser a master uses on the image it read.
// Input: steps of an opcode byte and arguments:
//   0  raw register write: offset (0..15), length (1..16), bytes
//   1  raw register read: offset, length
//   2  read command at a 32-bit word address, then the data registers are checked against the EEPROM
//   3  write command of one word (with or without write enable), checked against the EEPROM
//   4  reload command
//   5  parse the EEPROM image like a master (protocol::parse_sii). parse_sii is a pure function of the image,
//   so
//      the image is parsed once, after the last step of an input that has a step 5, unless it is the
//      pristine image (parsed once for all): an image seen earlier in an input is the last image of a
//      shorter input (its prefix), which the fuzzer tries as well.
// Invariants: the EEPROM never changes size; a read without error bit returns the EEPROM bytes; a write
// without error bit stores exactly the word; the command bits never stay set (no busy state is emulated).
#include <array>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "common/asan.hpp"
#include "esc/esc.hpp"
#include "esc/sii_image.hpp"
#include "fuzz_support.hpp"

using namespace vecat;
using namespace vecat::esc;
using namespace vecat::protocol;

namespace {

// One datagram addressed to this ESC (FPRD/FPWR at station 0 = the power-on address).
std::uint16_t access(Esc& e, Command cmd, std::uint16_t ado, Bytes data) {
    // On the stack (an allocation per access was a third of the time); the bytes after the working counter
    // are poisoned, so an ESC reading past the datagram is still an ASan report.
    alignas(8) std::array<std::uint8_t, 32> dg{};
    const std::size_t used = kDatagramHeaderSize + data.size() + kWkcSize;
    if (used > dg.size()) std::abort();
    dg[0] = static_cast<std::uint8_t>(cmd);
    st_le16(&dg[4], ado);
    st_le16(&dg[6], static_cast<std::uint16_t>(data.size()));
    std::copy(data.begin(), data.end(), dg.begin() + kDatagramHeaderSize);
    DatagramView d(dg.data());
    asan_poison(dg.data() + used, dg.size() - used);
    e.process(d, FrameTiming{});
    const std::uint16_t wkc = d.wkc();
    asan_unpoison(dg.data(), dg.size());
    std::copy(dg.begin() + kDatagramHeaderSize,
              dg.begin() + static_cast<long>(kDatagramHeaderSize + data.size()), data.begin());
    return wkc;
}

void write16(Esc& e, std::uint16_t ado, std::uint16_t v) {
    std::uint8_t b[2];
    st_le16(b, v);
    access(e, Command::FPWR, ado, Bytes(b, 2));
}

void write32(Esc& e, std::uint16_t ado, std::uint32_t v) {
    std::uint8_t b[4];
    st_le32(b, v);
    access(e, Command::FPWR, ado, Bytes(b, 4));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const auto image = build_sii_image(device::default_drive());
    static const bool pristine_ok = parse_sii(ConstBytes(image.data(), image.size())).strings.size() <= 255;
    VECAT_FUZZ_CHECK(pristine_ok);
    Esc esc(EscConfig{}, image);
    bool parse = false;
    const std::size_t eeprom_size = esc.eeprom().size();
    const std::uint16_t ctrl = addr(Reg::SiiControl);
    fuzz::Input in(data, size);
    std::vector<std::uint8_t> buf;
    unsigned steps = 0;
    while (!in.empty() && ++steps < 1024) {
        switch (in.u8() % 6) {
            case 0: {
                const auto off = static_cast<std::uint16_t>(in.u8() % 16);
                buf.assign(in.u8() % 16 + 1u, 0);
                for (auto& b : buf)
                    b = in.u8();
                access(esc, Command::FPWR, static_cast<std::uint16_t>(addr(Reg::SiiConfig) + off), buf);
                break;
            }
            case 1: {
                const auto off = static_cast<std::uint16_t>(in.u8() % 16);
                buf.assign(in.u8() % 16 + 1u, 0);
                access(esc, Command::FPRD, static_cast<std::uint16_t>(addr(Reg::SiiConfig) + off), buf);
                break;
            }
            case 2: {
                const std::uint32_t word = in.u16() | (static_cast<std::uint32_t>(in.u8() & 0x03) << 16);
                write32(esc, addr(Reg::SiiAddress), word);
                write16(esc, ctrl, sii_ctrl::CmdRead);
                const std::uint16_t c = esc.peek16(ctrl);
                VECAT_FUZZ_CHECK((c & (sii_ctrl::CmdMask | sii_ctrl::Busy)) == 0);
                if (c & sii_ctrl::ErrorAck) {
                    VECAT_FUZZ_CHECK(2ull * word >= eeprom_size);
                    break;
                }
                const unsigned n = (c & sii_ctrl::Read8Bytes) ? 8 : 4;
                for (unsigned k = 0; k < n; ++k) {
                    const std::size_t b = 2ull * word + k;
                    const std::uint8_t want = b < eeprom_size ? esc.eeprom()[b] : 0xFF;
                    VECAT_FUZZ_CHECK(esc.peek(static_cast<std::uint16_t>(addr(Reg::SiiData) + k)) == want);
                }
                break;
            }
            case 3: {
                const bool enable = in.u8() & 1;
                const std::uint32_t word = in.u16();
                const std::uint16_t value = in.u16();
                write32(esc, addr(Reg::SiiAddress), word);
                write16(esc, addr(Reg::SiiData), value);
                // Write enable and command in one access, as masters do.
                write16(
                    esc, ctrl,
                    static_cast<std::uint16_t>(sii_ctrl::CmdWrite | (enable ? sii_ctrl::WriteEnable : 0)));
                const std::uint16_t c = esc.peek16(ctrl);
                VECAT_FUZZ_CHECK((c & (sii_ctrl::CmdMask | sii_ctrl::Busy)) == 0);
                if (!enable) {
                    VECAT_FUZZ_CHECK(c & sii_ctrl::ErrorWriteEnable);
                } else if (!(c & (sii_ctrl::ErrorAck | sii_ctrl::ErrorWriteEnable))) {
                    VECAT_FUZZ_CHECK(2ull * word + 1 < eeprom_size);
                    VECAT_FUZZ_CHECK(ld_le16(&esc.eeprom()[2ull * word]) == value);
                }
                break;
            }
            case 4:
                write16(esc, ctrl, sii_ctrl::CmdReload);
                VECAT_FUZZ_CHECK((esc.peek16(ctrl) & (sii_ctrl::CmdMask | sii_ctrl::Busy)) == 0);
                break;
            case 5:
                parse = true;
                break;
        }
        VECAT_FUZZ_CHECK(esc.eeprom().size() == eeprom_size);
    }
    if (parse && esc.eeprom() != image) {
        const SiiInfo info = parse_sii(ConstBytes(esc.eeprom().data(), esc.eeprom().size()));
        VECAT_FUZZ_CHECK(info.strings.size() <= 255);
    }
    return 0;
}
