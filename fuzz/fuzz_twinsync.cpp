// Fuzz target: the TWINsync telegram and the option card that receives it. The input is a frame as it
// arrives on the cable (any length, any bytes) plus the layout and frame size the card expects.
// Invariants: decode accepts exactly the frames of the configured length whose CRC matches, and an
// accepted frame encodes back to the same bytes; a card fed the frame through its cable never crashes,
// counts it either as received or as a CRC error, and keeps its link state consistent.
#include <cstdint>
#include <vector>

#include "cia402/drive.hpp"
#include "device/device_description.hpp"
#include "fuzz_support.hpp"
#include "twinsync/telegram.hpp"

using namespace vecat;

namespace {

struct Pair {
    Pair() : a(dev), b(dev) {
        ch = cia402::connect_twinsync(a, b);
        cia402::apply_twinsync_preset(a, b, cia402::TwinsyncPreset::Gantry);
    }
    device::DeviceDescription dev = device::default_drive();
    cia402::Drive a, b;
    std::shared_ptr<twinsync::Channel> ch;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 2) return 0;
    const auto layout = (data[0] & 1) ? twinsync::Layout::Extended : twinsync::Layout::Standard;
    const auto selection = static_cast<std::uint16_t>(data[1] % twinsync::kFrameSizeSelections);
    const ConstBytes frame(data + 2, size - 2);

    // The telegram codec alone.
    const std::size_t pdo = *twinsync::pdo_bytes(layout, selection);
    twinsync::Telegram t;
    const auto result = twinsync::decode(frame, layout, pdo, t);
    const bool right_length = frame.size() == twinsync::header_bytes(layout) + pdo;
    const bool crc_ok = right_length && ld_le16(frame.data()) == twinsync::crc16(frame.subspan(2));
    VECAT_FUZZ_CHECK((result == twinsync::DecodeError::None) == crc_ok);
    VECAT_FUZZ_CHECK(right_length || result == twinsync::DecodeError::Length);
    if (result == twinsync::DecodeError::None) {
        std::uint8_t back[twinsync::kMaxFrameBytes];
        const std::size_t n = twinsync::encode(t, Bytes(back, sizeof back));
        VECAT_FUZZ_CHECK(n == frame.size());
        VECAT_FUZZ_CHECK(std::equal(frame.begin(), frame.end(), back));
    }

    // The same bytes on the cable of a gantry pair: the slave's card receives them.
    static Pair pair;  // built once: a drive pair takes far longer to build than a frame to check
    auto& port = pair.b.twinsync_port();
    const auto before = port.status();
    pair.ch->send(0, frame, 1000);
    twinsync::LocalState local;
    port.receive(2000, local);
    const auto& after = port.status();
    const std::uint64_t counted = (after.frames_received - before.frames_received) +
                                  (after.crc_errors - before.crc_errors) +
                                  (after.frames_missing - before.frames_missing);
    VECAT_FUZZ_CHECK(counted == 1);
    // Frames longer than the cable carries are not sent at all.
    if (frame.size() > twinsync::kMaxFrameBytes)
        VECAT_FUZZ_CHECK(after.frames_missing == before.frames_missing + 1);
    return 0;
}
