// EoE wire format (ETG.1000.6 5.7, Ethernet over EtherCAT): the 4-byte EoE header after the mailbox header,
// the frame types, the result codes, the IP parameter block of the set/get IP parameter services and the
// address filter block of the set/get address filter services. Shared by the slave's EoE server (src/eoe)
// and the project's master (src/master/eoe_client).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "common/bytes.hpp"
#include "protocol/frame.hpp"

namespace vecat::protocol {

// EoE frame types (ETG.1000.6 5.7, the Frame Type field of the EoE header).
enum class EoeFrameType : std::uint8_t {
    Fragment = 0,          // a fragment of an Ethernet frame (both directions)
    Timestamp = 1,         // the time a frame was sent, answering "time requested" (slave to master)
    SetIpRequest = 2,      // "init request" in SOEM/SOES
    SetIpResponse = 3,     // "init response"
    SetFilterRequest = 4,  // set address filter
    SetFilterResponse = 5,
    GetIpRequest = 6,  // get IP parameter
    GetIpResponse = 7,
    GetFilterRequest = 8,  // get address filter
    GetFilterResponse = 9,
};

// EoE result codes (ETG.1000.6 5.7, the Result field of the responses).
enum class EoeResult : std::uint16_t {
    Success = 0x0000,
    UnspecifiedError = 0x0001,
    UnsupportedFrameType = 0x0002,
    NoIpSupport = 0x0201,
    NoDhcpSupport = 0x0202,
    NoFilterSupport = 0x0401,
};

constexpr std::string_view describe(EoeResult r) noexcept {
    switch (r) {
        case EoeResult::Success:
            return "Success";
        case EoeResult::UnspecifiedError:
            return "Unspecified error";
        case EoeResult::UnsupportedFrameType:
            return "Unsupported frame type";
        case EoeResult::NoIpSupport:
            return "No IP support";
        case EoeResult::NoDhcpSupport:
            return "No DHCP support";
        case EoeResult::NoFilterSupport:
            return "No filter support";
    }
    return "Unknown EoE result";
}

inline constexpr std::size_t kEoeHeaderSize = 4;
// Fragment offsets and the complete size are counted in blocks of 32 bytes (6 bits each: at most 63
// blocks, 2016 bytes, more than the largest Ethernet frame).
inline constexpr std::size_t kEoeBlockSize = 32;
inline constexpr std::size_t kEoeMaxBlocks = 63;
inline constexpr std::size_t kEoeMaxFragmentNumber = 63;
inline constexpr std::size_t kEoeMaxFrameNumber = 15;
// The 32-bit time stamp a fragment carries after its data when "time appended" is set.
inline constexpr std::size_t kEoeTimestampSize = 4;
// The largest Ethernet frame (without FCS, with a VLAN tag): what a device's frame buffer holds.
inline constexpr std::size_t kEthernetMaxFrame = 1518;
inline constexpr std::size_t kMacSize = 6;

// The EoE header (ETG.1000.6 5.7): two little-endian words.
//   word 1: frame type (bits 0-3), port (4-7), last fragment (8), time appended (9), time requested (10)
//   word 2, fragments: fragment number (bits 0-5), complete size in blocks on fragment 0 / offset in blocks
//           on the others (6-11), frame number (12-15). Responses: the result code.
struct EoeHeader {
    static constexpr std::size_t kSize = kEoeHeaderSize;
    std::uint8_t type = 0;  // EoeFrameType, kept raw (4 bits) so unknown types can be answered
    std::uint8_t port = 0;  // 4 bits
    bool last_fragment = false;
    bool time_appended = false;
    bool time_requested = false;
    std::uint8_t fragment = 0;  // 6 bits
    std::uint8_t blocks = 0;    // 6 bits: complete size (fragment 0) or offset (others), in 32-byte blocks
    std::uint8_t frame = 0;     // 4 bits

    // Responses carry the result in word 2 instead of fragment, blocks and frame.
    std::uint16_t result() const noexcept {
        return static_cast<std::uint16_t>(fragment | (blocks << 6) | (frame << 12));
    }
    void set_result(std::uint16_t r) noexcept {
        fragment = static_cast<std::uint8_t>(r & 0x3F);
        blocks = static_cast<std::uint8_t>((r >> 6) & 0x3F);
        frame = static_cast<std::uint8_t>((r >> 12) & 0x0F);
    }
    EoeFrameType frame_type() const noexcept { return static_cast<EoeFrameType>(type); }

    void pack(std::span<std::uint8_t, kSize> out) const noexcept;
    static EoeHeader unpack(std::span<const std::uint8_t, kSize> in) noexcept;
    friend bool operator==(const EoeHeader&, const EoeHeader&) = default;
};

std::optional<EoeHeader> parse_eoe_header(ConstBytes b) noexcept;
// Writes the header; false (nothing written) when b is shorter than 4 bytes.
bool write_eoe_header(Bytes b, const EoeHeader& h) noexcept;
// A response header: the type, the port and "last fragment" (set on every single-message service, as SOES
// and TwinCAT do), the result in word 2.
EoeHeader eoe_response_header(EoeFrameType type, std::uint8_t port, EoeResult result) noexcept;

// MAC addresses as the Ethernet header of protocol/frame.hpp has them (kBroadcastMac there too).
using MacAddress = EthernetHeader::Mac;

// An IPv4 address as a number: 192.168.1.2 is 0xC0A80102. On the EoE wire it is that number little-endian
// (the bytes 02 01 A8 C0), as SOEM, SOES and TwinCAT put it.
using Ip4 = std::uint32_t;
std::string ip4_to_string(Ip4 ip);
std::optional<Ip4> parse_ip4(std::string_view s) noexcept;

// The IP parameter block (ETG.1000.6 5.7, set IP parameter request / get IP parameter response): a 32-bit
// flags word, then only the fields whose flag is set, in this order: MAC (6), IP (4), subnet mask (4),
// default gateway (4), DNS server (4), DNS name (32 bytes, NUL-padded).
namespace eoe_ip_flag {
inline constexpr std::uint32_t Mac = 1u << 0;
inline constexpr std::uint32_t Ip = 1u << 1;
inline constexpr std::uint32_t Subnet = 1u << 2;
inline constexpr std::uint32_t Gateway = 1u << 3;
inline constexpr std::uint32_t DnsServer = 1u << 4;
inline constexpr std::uint32_t DnsName = 1u << 5;
}  // namespace eoe_ip_flag
inline constexpr std::size_t kEoeFlagsSize = 4;
inline constexpr std::size_t kEoeDnsNameSize = 32;
// The whole block with every field: 4 + 6 + 4 * 4 + 32.
inline constexpr std::size_t kEoeIpBlockMaxSize = kEoeFlagsSize + kMacSize + 4 * 4 + kEoeDnsNameSize;

struct EoeIpParameters {
    std::optional<MacAddress> mac;
    std::optional<Ip4> ip;
    std::optional<Ip4> subnet;
    std::optional<Ip4> gateway;
    std::optional<Ip4> dns_server;
    std::optional<std::string> dns_name;  // at most 32 characters
    friend bool operator==(const EoeIpParameters&, const EoeIpParameters&) = default;
};

// Parses the block (the bytes after the EoE header). nullopt when it is shorter than its flags say. A DNS
// name may be shorter than 32 bytes when it is the last thing in the block (SOES reads what is there); it
// ends at the first NUL.
std::optional<EoeIpParameters> parse_eoe_ip(ConstBytes block) noexcept;
// Writes the block; its length, 0 when out is too short.
std::size_t write_eoe_ip(Bytes out, const EoeIpParameters& p) noexcept;

// The address filter block (ETG.1000.6 5.7, set address filter request / get address filter response):
// a 16-bit options word (bits 0-3 number of MAC filters, 4-5 number of filter masks, 7 "no broadcasts"),
// then 16 MAC addresses and 4 masks, each 6 bytes; the entries past the counts are not used.
inline constexpr std::size_t kEoeFilterSlots = 16;  // MAC filter entries in the block (count: 0..15)
inline constexpr std::size_t kEoeMaskSlots = 4;     // filter masks in the block (count: 0..3)
inline constexpr std::size_t kEoeFilterOptionsSize = 2;
inline constexpr std::size_t kEoeFilterBlockSize =
    kEoeFilterOptionsSize + (kEoeFilterSlots + kEoeMaskSlots) * kMacSize;  // 122
namespace eoe_filter_option {
inline constexpr std::uint16_t CountMask = 0x000F;
inline constexpr std::uint16_t MaskCountMask = 0x0030;
inline constexpr unsigned MaskCountShift = 4;
inline constexpr std::uint16_t NoBroadcasts = 0x0080;
}  // namespace eoe_filter_option

struct EoeAddressFilter {
    std::uint8_t count = 0;       // MAC filters in use (0..15)
    std::uint8_t mask_count = 0;  // masks in use (0..3)
    bool no_broadcasts = false;
    std::array<MacAddress, kEoeFilterSlots> macs{};
    std::array<MacAddress, kEoeMaskSlots> masks{};

    // Whether a frame to dst passes: the broadcast address unless "no broadcasts"; any other address when
    // it equals one of the filters. Filter i < mask_count is compared under mask i (bits set in the mask
    // must be equal), the others exactly. (ETG.1000.6 names the fields, not how masks pair with filters;
    // this pairing is vecat's reading, see src/eoe/README.md.)
    bool accepts(const MacAddress& dst) const noexcept;
    friend bool operator==(const EoeAddressFilter&, const EoeAddressFilter&) = default;
};

// Parses the block. It must hold the options and the filters in use; masks in use must be there too (at
// their place after the 16 filter slots). nullopt otherwise.
std::optional<EoeAddressFilter> parse_eoe_filter(ConstBytes block) noexcept;
// Writes the whole 122-byte block (unused slots as zero); 0 when out is too short.
std::size_t write_eoe_filter(Bytes out, const EoeAddressFilter& f) noexcept;

// Data a fragment that is not the last may carry in a mailbox payload of `payload_capacity` bytes: the
// room after the EoE header, rounded down to whole 32-byte blocks (the next fragment's offset counts
// blocks).
constexpr std::size_t eoe_fragment_capacity(std::size_t payload_capacity) noexcept {
    return payload_capacity > kEoeHeaderSize
               ? (payload_capacity - kEoeHeaderSize) / kEoeBlockSize * kEoeBlockSize
               : 0;
}
// The complete-size field of fragment 0 for a frame of `size` bytes: blocks, rounded up.
constexpr std::uint8_t eoe_size_blocks(std::size_t size) noexcept {
    return static_cast<std::uint8_t>((size + kEoeBlockSize - 1) / kEoeBlockSize);
}

}  // namespace vecat::protocol
