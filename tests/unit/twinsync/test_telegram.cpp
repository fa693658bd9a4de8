// The TWINsync telegram bit by bit: both layouts for every frame size, the CRC, the status word of
// table 4.5 and the control and status words of chapter 5.
#include <gtest/gtest.h>

#include <string_view>

#include "twinsync/telegram.hpp"

namespace vecat::twinsync {
namespace {

TEST(TwinTelegram, CrcIsCcittFalse) {
    constexpr std::string_view check = "123456789";
    const auto* p = reinterpret_cast<const std::uint8_t*>(check.data());
    EXPECT_EQ(crc16(ConstBytes(p, check.size())), 0x29B1);  // the CRC-16/CCITT-FALSE check value
    EXPECT_EQ(crc16({}), 0xFFFF);
}

TEST(TwinTelegram, FrameSizesOfP2709) {
    // Standard PDO bytes per selection (table 4.1) and the frame length that both layouts share.
    const std::size_t standard[] = {10, 8, 6, 4, 2, 0, 12, 14, 16, 18, 20, 22, 24, 26};
    for (std::uint16_t sel = 0; sel < kFrameSizeSelections; ++sel) {
        SCOPED_TRACE(sel);
        EXPECT_EQ(pdo_bytes(Layout::Standard, sel), standard[sel]);
        EXPECT_EQ(pdo_bytes(Layout::Extended, sel), standard[sel] + 4);
        EXPECT_EQ(frame_bytes(Layout::Standard, sel), standard[sel] + 6);
        EXPECT_EQ(frame_bytes(Layout::Extended, sel), frame_bytes(Layout::Standard, sel));
        EXPECT_GE(*frame_bytes(Layout::Standard, sel), 6u);
        EXPECT_LE(*frame_bytes(Layout::Standard, sel), 32u);
    }
    EXPECT_EQ(frame_bytes(Layout::Standard, 0), 16u);  // the example of table 4.3: 10 PDO bytes, 16 in all
    EXPECT_EQ(pdo_bytes(Layout::Extended, 0), 14u);    // table 4.4: 14 PDO bytes
    EXPECT_FALSE(pdo_bytes(Layout::Standard, 14));
}

TEST(TwinTelegram, EveryFrameSizeRoundTripsInBothLayouts) {
    for (Layout l : {Layout::Standard, Layout::Extended})
        for (std::uint16_t sel = 0; sel < kFrameSizeSelections; ++sel) {
            SCOPED_TRACE(static_cast<int>(l) * 100 + sel);
            Telegram t;
            t.layout = l;
            t.status = 0xA5C3;
            t.drivecom_word = 0x1234;
            t.pdo_size = static_cast<std::uint8_t>(*pdo_bytes(l, sel));
            for (std::size_t i = 0; i < t.pdo_size; ++i)
                t.pdo[i] = static_cast<std::uint8_t>(0x40 + i * 7);
            std::array<std::uint8_t, kMaxFrameBytes> buf{};
            const std::size_t n = encode(t, Bytes(buf.data(), buf.size()));
            ASSERT_EQ(n, frame_bytes(l, sel));
            // Byte layout: CRC first, then (standard) status word and DriveCom word, then the PDOs.
            EXPECT_EQ(ld_le16(buf.data()), crc16(ConstBytes(buf.data() + 2, n - 2)));
            if (l == Layout::Standard) {
                EXPECT_EQ(ld_le16(buf.data() + 2), 0xA5C3);
                EXPECT_EQ(ld_le16(buf.data() + 4), 0x1234);
            }
            if (t.pdo_size > 0) {
                EXPECT_EQ(buf[header_bytes(l)], 0x40);
            }
            Telegram back;
            ASSERT_EQ(decode(ConstBytes(buf.data(), n), l, t.pdo_size, back), DecodeError::None);
            EXPECT_EQ(back.pdo, t.pdo);
            EXPECT_EQ(back.pdo_size, t.pdo_size);
            EXPECT_EQ(back.status, l == Layout::Standard ? 0xA5C3 : 0);
            EXPECT_EQ(back.drivecom_word, l == Layout::Standard ? 0x1234 : 0);
            // The wrong length is refused.
            EXPECT_EQ(decode(ConstBytes(buf.data(), n - 1), l, t.pdo_size, back), DecodeError::Length);
        }
}

TEST(TwinTelegram, EverySingleBitErrorIsDetected) {
    Telegram t;
    t.pdo_size = 10;
    for (std::size_t i = 0; i < 10; ++i)
        t.pdo[i] = static_cast<std::uint8_t>(i * 31);
    std::array<std::uint8_t, kMaxFrameBytes> buf{};
    const std::size_t n = encode(t, Bytes(buf.data(), buf.size()));
    for (std::size_t bit = 0; bit < n * 8; ++bit) {
        auto bad = buf;
        bad[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
        Telegram out;
        EXPECT_EQ(decode(ConstBytes(bad.data(), n), Layout::Standard, 10, out), DecodeError::Crc) << bit;
    }
}

TEST(TwinTelegram, StatusWordBitsOfTable45) {
    // One field at a time from all-zero: the bits it sets.
    auto bits = [](auto set) {
        TwinStatusWord s;
        s.switching_frequency = 0;
        set(s);
        return s.pack();
    };
    EXPECT_EQ(bits([](TwinStatusWord&) {}), 0x0000);
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.cyclic = true; }), 0x0001);
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.switching_frequency = 3; }), 0x0006);  // 8 kHz = 011, bits 1-3
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.switching_frequency = 5; }), 0x000A);  // 16 kHz = 101
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.mode = Role::Slave; }), 0x0010);
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.mode = Role::Master; }), 0x0020);
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.drivecom_state = 5; }), 5u << 7);
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.drivecom_state = 8; }), 8u << 7);
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.chopper = true; }), 1u << 11);
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.pwm_counting_down = true; }), 1u << 12);
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.pwm_disable_event = true; }), 1u << 13);
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.system_error = true; }), 1u << 14);
    EXPECT_EQ(bits([](TwinStatusWord& s) { s.techopt_error = true; }), 1u << 15);
    for (unsigned w = 0; w < 0x10000; w += 0x41) {
        if (w & 0x40) continue;  // bit 6 is reserved and not kept
        EXPECT_EQ(TwinStatusWord::unpack(static_cast<std::uint16_t>(w)).pack(), w) << std::hex << w;
    }
}

TEST(TwinTelegram, ControlWordFromTheCia402Controlword) {
    // Enable operation (0x0F): switch on, enable voltage, no quick stop, enable operation.
    EXPECT_EQ(control_word_from_cia402(0x000F, false),
              control::SwitchOn | control::EnableVoltage | control::EnableOperation);
    // Disable voltage (bit 1 = 0) is the coast stop; quick stop (bit 2 = 0) the quick stop.
    EXPECT_EQ(control_word_from_cia402(0x0000, false), control::CoastStop | control::QuickStop);
    EXPECT_EQ(control_word_from_cia402(0x0002, false), control::EnableVoltage | control::QuickStop);
    EXPECT_EQ(control_word_from_cia402(0x0086, false) & control::FaultReset, control::FaultReset);
    // Bit 4 starts homing only in homing mode.
    EXPECT_EQ(control_word_from_cia402(0x001F, true) & control::StartHoming, control::StartHoming);
    EXPECT_EQ(control_word_from_cia402(0x001F, false) & control::StartHoming, 0);
    EXPECT_EQ(control_word_from_cia402(0x080F, false) & control::ReSyncPosition, control::ReSyncPosition);
    // And back: the slave's CiA 402 state machine sees the master's command.
    for (unsigned cw : {0x00u, 0x06u, 0x07u, 0x0Fu, 0x02u, 0x0Bu, 0x80u, 0x1Fu}) {
        const std::uint16_t back =
            cia402_from_control_word(control_word_from_cia402(static_cast<std::uint16_t>(cw), true));
        EXPECT_EQ(back & 0x9F, cw & 0x9F) << std::hex << cw;
    }
}

}  // namespace
}  // namespace vecat::twinsync
