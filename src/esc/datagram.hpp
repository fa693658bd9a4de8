// EtherCAT frames and datagrams (ETG.1000.4 clause 5): commands, header layout, and a parser that
// validates a whole frame before any slave touches it.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "common/bytes.hpp"

namespace vecat::esc {

inline constexpr std::uint16_t kEtherTypeEtherCat = 0x88A4;
inline constexpr std::uint16_t kEtherTypeVlan = 0x8100;
inline constexpr std::size_t kEthHeaderSize = 14;
inline constexpr std::size_t kEcatHeaderSize = 2;
inline constexpr std::size_t kDatagramHeaderSize = 10;
inline constexpr std::size_t kWkcSize = 2;
inline constexpr std::size_t kMinEthFrame = 60;  // without FCS
inline constexpr std::size_t kMaxEthFrame = 1514;
inline constexpr std::size_t kMaxDatagramsPerFrame = 128;
inline constexpr std::uint8_t kEcatTypeCommands = 0x1;

enum class Command : std::uint8_t {
    NOP = 0,
    APRD = 1,
    APWR = 2,
    APRW = 3,
    FPRD = 4,
    FPWR = 5,
    FPRW = 6,
    BRD = 7,
    BWR = 8,
    BRW = 9,
    LRD = 10,
    LWR = 11,
    LRW = 12,
    ARMW = 13,
    FRMW = 14,
};

constexpr std::string_view to_string(Command c) noexcept {
    constexpr std::string_view names[] = {"NOP", "APRD", "APWR", "APRW", "FPRD", "FPWR", "FPRW", "BRD",
                                          "BWR", "BRW",  "LRD",  "LWR",  "LRW",  "ARMW", "FRMW"};
    const auto i = static_cast<unsigned>(c);
    return i < 15 ? names[i] : std::string_view{"?"};
}

// A view of one datagram inside a frame buffer. Layout: cmd(1) idx(1) address(4) len/flags(2) irq(2)
// data(len) wkc(2).
class DatagramView {
  public:
    DatagramView() = default;
    explicit DatagramView(std::uint8_t* hdr) : p_(hdr) {}

    Command command() const { return static_cast<Command>(p_[0]); }
    std::uint8_t raw_command() const { return p_[0]; }
    std::uint8_t index() const { return p_[1]; }
    std::uint16_t adp() const { return ld_le16(p_ + 2); }
    void set_adp(std::uint16_t v) { st_le16(p_ + 2, v); }
    std::uint16_t ado() const { return ld_le16(p_ + 4); }
    std::uint32_t logical_address() const { return ld_le32(p_ + 2); }
    std::uint16_t length() const { return ld_le16(p_ + 6) & 0x07FF; }
    bool circulating() const { return (ld_le16(p_ + 6) & 0x4000) != 0; }
    bool more() const { return (ld_le16(p_ + 6) & 0x8000) != 0; }
    std::uint16_t irq() const { return ld_le16(p_ + 8); }
    std::uint8_t* data() const { return p_ + kDatagramHeaderSize; }
    std::uint16_t wkc() const { return ld_le16(p_ + kDatagramHeaderSize + length()); }
    void set_wkc(std::uint16_t v) { st_le16(p_ + kDatagramHeaderSize + length(), v); }
    void add_wkc(unsigned n) { set_wkc(static_cast<std::uint16_t>(wkc() + n)); }
    std::size_t total_size() const { return kDatagramHeaderSize + length() + kWkcSize; }

  private:
    std::uint8_t* p_ = nullptr;
};

enum class FrameError : std::uint8_t {
    None,
    TooShort,         // shorter than Ethernet + EtherCAT header + one datagram
    NotEtherCat,      // other EtherType
    NotCommands,      // EtherCAT header type other than 1 (forwarded unprocessed)
    HeaderLength,     // EtherCAT header length exceeds the frame
    DatagramOverrun,  // a datagram runs past the EtherCAT payload
    TooManyDatagrams,
};

constexpr std::string_view to_string(FrameError e) noexcept {
    switch (e) {
        case FrameError::None:
            return "ok";
        case FrameError::TooShort:
            return "frame too short";
        case FrameError::NotEtherCat:
            return "not an EtherCAT frame";
        case FrameError::NotCommands:
            return "EtherCAT type is not datagrams";
        case FrameError::HeaderLength:
            return "EtherCAT length exceeds the frame";
        case FrameError::DatagramOverrun:
            return "datagram runs past the EtherCAT payload";
        case FrameError::TooManyDatagrams:
            return "too many datagrams";
    }
    return "?";
}

// The datagrams of one frame, located and bounds-checked.
struct ParsedFrame {
    FrameError error = FrameError::None;
    std::size_t ecat_offset = 0;  // offset of the EtherCAT header
    std::size_t count = 0;
    // Of each datagram header; only the first count are set (not zeroed: parsed for every frame).
    std::array<std::uint16_t, kMaxDatagramsPerFrame> offsets;

    DatagramView datagram(Bytes frame, std::size_t i) const {
        return DatagramView(frame.data() + offsets[i]);
    }
};

// Locates and checks every datagram. Never reads past frame.size().
ParsedFrame parse_frame(ConstBytes frame) noexcept;

}  // namespace vecat::esc
