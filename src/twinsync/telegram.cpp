#include "twinsync/telegram.hpp"

namespace vecat::twinsync {
namespace {

// P2709[1]: PDO bytes of the standard layout per frame size selection.
constexpr std::array<std::uint8_t, kFrameSizeSelections> kStandardPdo = {10, 8,  6,  4,  2,  0,  12,
                                                                         14, 16, 18, 20, 22, 24, 26};

constexpr std::array<std::uint16_t, 256> make_crc_table() {
    std::array<std::uint16_t, 256> t{};
    for (unsigned i = 0; i < 256; ++i) {
        auto c = static_cast<std::uint16_t>(i << 8);
        for (int b = 0; b < 8; ++b)
            c = static_cast<std::uint16_t>((c & 0x8000) ? (c << 1) ^ 0x1021 : c << 1);
        t[i] = c;
    }
    return t;
}
constexpr auto kCrcTable = make_crc_table();

}  // namespace

std::optional<std::size_t> pdo_bytes(Layout l, std::uint16_t sel) noexcept {
    if (sel >= kFrameSizeSelections) return std::nullopt;
    return kStandardPdo[sel] + (l == Layout::Extended ? 4u : 0u);
}

std::optional<std::size_t> frame_bytes(Layout l, std::uint16_t sel) noexcept {
    const auto n = pdo_bytes(l, sel);
    if (!n) return std::nullopt;
    return *n + header_bytes(l);
}

std::uint16_t crc16(ConstBytes data) noexcept {
    std::uint16_t crc = 0xFFFF;
    for (std::uint8_t b : data)
        crc = static_cast<std::uint16_t>((crc << 8) ^ kCrcTable[((crc >> 8) ^ b) & 0xFF]);
    return crc;
}

std::uint16_t TwinStatusWord::pack() const noexcept {
    std::uint16_t w = 0;
    if (cyclic) w |= 1u;
    w |= static_cast<std::uint16_t>((switching_frequency & 0x7u) << 1);
    w |= static_cast<std::uint16_t>((static_cast<unsigned>(mode) & 0x3u) << 4);
    w |= static_cast<std::uint16_t>((drivecom_state & 0xFu) << 7);
    if (chopper) w |= 1u << 11;
    if (pwm_counting_down) w |= 1u << 12;
    if (pwm_disable_event) w |= 1u << 13;
    if (system_error) w |= 1u << 14;
    if (techopt_error) w |= 1u << 15;
    return w;
}

TwinStatusWord TwinStatusWord::unpack(std::uint16_t w) noexcept {
    TwinStatusWord s;
    s.cyclic = w & 1u;
    s.switching_frequency = static_cast<std::uint8_t>((w >> 1) & 0x7u);
    s.mode = static_cast<Role>((w >> 4) & 0x3u);
    s.drivecom_state = static_cast<std::uint8_t>((w >> 7) & 0xFu);
    s.chopper = w & (1u << 11);
    s.pwm_counting_down = w & (1u << 12);
    s.pwm_disable_event = w & (1u << 13);
    s.system_error = w & (1u << 14);
    s.techopt_error = w & (1u << 15);
    return s;
}

std::uint16_t control_word_from_cia402(std::uint16_t cw, bool homing_mode) noexcept {
    std::uint16_t t = 0;
    if (cw & 0x0001) t |= control::SwitchOn;
    if (cw & 0x0002)
        t |= control::EnableVoltage;
    else
        t |= control::CoastStop;
    if (!(cw & 0x0004)) t |= control::QuickStop;
    if (cw & 0x0008) t |= control::EnableOperation;
    if (homing_mode && (cw & 0x0010)) t |= control::StartHoming;
    if (cw & 0x0080) t |= control::FaultReset;
    if (cw & kCia402ResyncBit) t |= control::ReSyncPosition;
    return t;
}

std::uint16_t cia402_from_control_word(std::uint16_t t) noexcept {
    std::uint16_t cw = 0;
    if (t & control::SwitchOn) cw |= 0x0001;
    if ((t & control::EnableVoltage) && !(t & control::CoastStop)) cw |= 0x0002;
    if (!(t & control::QuickStop)) cw |= 0x0004;
    if (t & control::EnableOperation) cw |= 0x0008;
    if (t & control::StartHoming) cw |= 0x0010;
    if (t & control::FaultReset) cw |= 0x0080;
    if (t & control::ReSyncPosition) cw |= kCia402ResyncBit;
    return cw;
}

std::size_t encode(const Telegram& t, Bytes out) noexcept {
    const std::size_t head = header_bytes(t.layout);
    const std::size_t n = head + t.pdo_size;
    if (t.pdo_size > kMaxPdoBytes || out.size() < n) return 0;
    if (t.layout == Layout::Standard) {
        st_le16(out.data() + 2, t.status);
        st_le16(out.data() + 4, t.drivecom_word);
    }
    for (std::size_t i = 0; i < t.pdo_size; ++i)
        out[head + i] = t.pdo[i];
    st_le16(out.data(), crc16(ConstBytes(out.data() + 2, n - 2)));
    return n;
}

DecodeError decode(ConstBytes frame, Layout layout, std::size_t pdo_size, Telegram& out) noexcept {
    const std::size_t head = header_bytes(layout);
    if (pdo_size > kMaxPdoBytes || frame.size() != head + pdo_size) return DecodeError::Length;
    if (ld_le16(frame.data()) != crc16(frame.subspan(2))) return DecodeError::Crc;
    out.layout = layout;
    out.status = layout == Layout::Standard ? ld_le16(frame.data() + 2) : 0;
    out.drivecom_word = layout == Layout::Standard ? ld_le16(frame.data() + 4) : 0;
    out.pdo_size = static_cast<std::uint8_t>(pdo_size);
    out.pdo.fill(0);
    for (std::size_t i = 0; i < pdo_size; ++i)
        out.pdo[i] = frame[head + i];
    return DecodeError::None;
}

}  // namespace vecat::twinsync
