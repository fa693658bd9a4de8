// EtherCAT frames and datagrams (ETG.1000.4 clause 5.3 and 5.4): the Ethernet and EtherCAT headers, the
// datagram header and the commands, and a parser that validates a whole frame before any slave touches it.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string_view>

#include "common/bytes.hpp"

namespace vecat::protocol {

inline constexpr std::uint16_t kEtherTypeEtherCat = 0x88A4;
inline constexpr std::uint16_t kEtherTypeVlan = 0x8100;
inline constexpr std::size_t kEthHeaderSize = 14;
inline constexpr std::size_t kVlanTagSize = 4;
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

// Physical (register/memory) commands that write, and that read, at the slaves they address (ETG.1000.4
// 5.4: the read-multiple-writes read at the addressed slave and write at the others).
constexpr bool physical_write(Command c) noexcept {
    return c == Command::APWR || c == Command::APRW || c == Command::FPWR || c == Command::FPRW ||
           c == Command::BWR || c == Command::BRW;
}
constexpr bool physical_read(Command c) noexcept {
    return c == Command::APRD || c == Command::APRW || c == Command::FPRD || c == Command::FPRW ||
           c == Command::BRD || c == Command::BRW || c == Command::ARMW || c == Command::FRMW;
}

// Ethernet header (IEEE 802.3): destination, source, EtherType (big-endian, the only big-endian field of an
// EtherCAT frame). Frames with a VLAN tag are accepted by parse_frame; this layout is the untagged one.
struct EthernetHeader {
    using Mac = std::array<std::uint8_t, 6>;
    static constexpr std::size_t kSize = kEthHeaderSize;
    static constexpr std::size_t kEtherTypeOffset = 12;
    Mac destination{};
    Mac source{};
    std::uint16_t ether_type = kEtherTypeEtherCat;

    void pack(std::span<std::uint8_t, kSize> out) const noexcept;
    static EthernetHeader unpack(std::span<const std::uint8_t, kSize> in) noexcept;
};
inline constexpr EthernetHeader::Mac kBroadcastMac = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};

// EtherCAT header (ETG.1000.4 5.3.1): length of the datagrams (11 bits), a reserved bit, and the
// type (4 bits; 1: EtherCAT commands).
struct EcatHeader {
    static constexpr std::size_t kSize = kEcatHeaderSize;
    static constexpr std::uint16_t kLengthMask = 0x07FF;
    static constexpr unsigned kTypeShift = 12;
    std::uint16_t length = 0;  // bytes of datagrams after this header
    std::uint8_t type = kEcatTypeCommands;

    constexpr std::uint16_t word() const noexcept {
        return static_cast<std::uint16_t>((length & kLengthMask) | (unsigned{type} << kTypeShift));
    }
    void pack(std::span<std::uint8_t, kSize> out) const noexcept { st_le16(out.data(), word()); }
    static constexpr EcatHeader from_word(std::uint16_t w) noexcept {
        return {static_cast<std::uint16_t>(w & kLengthMask), static_cast<std::uint8_t>(w >> kTypeShift)};
    }
    static EcatHeader unpack(std::span<const std::uint8_t, kSize> in) noexcept {
        return from_word(ld_le16(in.data()));
    }
};

// Datagram header (ETG.1000.4 5.4.1.2): cmd(1) idx(1) address(4) len/flags(2) irq(2), followed by
// data(len) and the working counter(2). The address is ADP | ADO << 16, or one 32-bit logical address.
namespace datagram {
inline constexpr unsigned Command = 0;
inline constexpr unsigned Index = 1;
inline constexpr unsigned Address = 2;  // u32; ADP: u16 at 2, ADO: u16 at 4
inline constexpr unsigned Adp = 2;
inline constexpr unsigned Ado = 4;
inline constexpr unsigned LengthFlags = 6;  // u16
inline constexpr unsigned Irq = 8;          // u16
inline constexpr std::uint16_t LengthMask = 0x07FF;
inline constexpr std::uint16_t Circulating = 0x4000;  // C: the frame has circulated once
inline constexpr std::uint16_t More = 0x8000;         // M: another datagram follows

constexpr std::uint32_t address(std::uint16_t adp, std::uint16_t ado) noexcept {
    return static_cast<std::uint32_t>(adp) | (static_cast<std::uint32_t>(ado) << 16);
}
}  // namespace datagram

struct DatagramHeader {
    static constexpr std::size_t kSize = kDatagramHeaderSize;
    Command command = Command::NOP;
    std::uint8_t index = 0;
    std::uint32_t address = 0;  // datagram::address(adp, ado), or the logical address
    std::uint16_t length = 0;   // data bytes, 11 bits
    bool circulating = false;
    bool more = false;  // another datagram follows in the frame
    std::uint16_t irq = 0;

    void pack(std::span<std::uint8_t, kSize> out) const noexcept;
    static DatagramHeader unpack(std::span<const std::uint8_t, kSize> in) noexcept;
};

// A view of one datagram inside a frame buffer that parse_frame has checked (the datagram's header, data and
// working counter lie inside it). The fields are read in place: the ESCs process datagrams through it.
class DatagramView {
  public:
    DatagramView() = default;
    explicit DatagramView(std::uint8_t* hdr) : p_(hdr) {}

    DatagramHeader header() const {
        return DatagramHeader::unpack(
            std::span<const std::uint8_t, kDatagramHeaderSize>(p_, kDatagramHeaderSize));
    }
    Command command() const { return static_cast<Command>(p_[datagram::Command]); }
    std::uint8_t raw_command() const { return p_[datagram::Command]; }
    std::uint8_t index() const { return p_[datagram::Index]; }
    std::uint16_t adp() const { return ld_le16(p_ + datagram::Adp); }
    void set_adp(std::uint16_t v) { st_le16(p_ + datagram::Adp, v); }
    std::uint16_t ado() const { return ld_le16(p_ + datagram::Ado); }
    std::uint32_t logical_address() const { return ld_le32(p_ + datagram::Address); }
    std::uint16_t length() const { return ld_le16(p_ + datagram::LengthFlags) & datagram::LengthMask; }
    bool circulating() const { return (ld_le16(p_ + datagram::LengthFlags) & datagram::Circulating) != 0; }
    bool more() const { return (ld_le16(p_ + datagram::LengthFlags) & datagram::More) != 0; }
    std::uint16_t irq() const { return ld_le16(p_ + datagram::Irq); }
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

}  // namespace vecat::protocol
