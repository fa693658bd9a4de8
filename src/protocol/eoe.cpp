#include "protocol/eoe.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>

namespace vecat::protocol {

namespace {
// Word 1 of the EoE header.
inline constexpr std::uint16_t kTypeMask = 0x000F;
inline constexpr unsigned kPortShift = 4;
inline constexpr std::uint16_t kPortMask = 0x000F;
inline constexpr std::uint16_t kLastFragment = 1u << 8;
inline constexpr std::uint16_t kTimeAppended = 1u << 9;
inline constexpr std::uint16_t kTimeRequested = 1u << 10;
// Word 2 of a fragment.
inline constexpr std::uint16_t kFragmentMask = 0x003F;
inline constexpr unsigned kBlocksShift = 6;
inline constexpr std::uint16_t kBlocksMask = 0x003F;
inline constexpr unsigned kFrameShift = 12;
inline constexpr std::uint16_t kFrameMask = 0x000F;

inline constexpr std::size_t kIp4Size = 4;
}  // namespace

void EoeHeader::pack(std::span<std::uint8_t, kSize> out) const noexcept {
    std::uint16_t w1 = static_cast<std::uint16_t>((type & kTypeMask) | ((port & kPortMask) << kPortShift));
    if (last_fragment) w1 |= kLastFragment;
    if (time_appended) w1 |= kTimeAppended;
    if (time_requested) w1 |= kTimeRequested;
    const auto w2 =
        static_cast<std::uint16_t>((fragment & kFragmentMask) | ((blocks & kBlocksMask) << kBlocksShift) |
                                   ((frame & kFrameMask) << kFrameShift));
    st_le16(out.data(), w1);
    st_le16(out.data() + 2, w2);
}

EoeHeader EoeHeader::unpack(std::span<const std::uint8_t, kSize> in) noexcept {
    const std::uint16_t w1 = ld_le16(in.data());
    const std::uint16_t w2 = ld_le16(in.data() + 2);
    EoeHeader h;
    h.type = static_cast<std::uint8_t>(w1 & kTypeMask);
    h.port = static_cast<std::uint8_t>((w1 >> kPortShift) & kPortMask);
    h.last_fragment = (w1 & kLastFragment) != 0;
    h.time_appended = (w1 & kTimeAppended) != 0;
    h.time_requested = (w1 & kTimeRequested) != 0;
    h.fragment = static_cast<std::uint8_t>(w2 & kFragmentMask);
    h.blocks = static_cast<std::uint8_t>((w2 >> kBlocksShift) & kBlocksMask);
    h.frame = static_cast<std::uint8_t>((w2 >> kFrameShift) & kFrameMask);
    return h;
}

std::optional<EoeHeader> parse_eoe_header(ConstBytes b) noexcept {
    if (b.size() < kEoeHeaderSize) return std::nullopt;
    return EoeHeader::unpack(b.first<kEoeHeaderSize>());
}

bool write_eoe_header(Bytes b, const EoeHeader& h) noexcept {
    if (b.size() < kEoeHeaderSize) return false;
    h.pack(b.first<kEoeHeaderSize>());
    return true;
}

EoeHeader eoe_response_header(EoeFrameType type, std::uint8_t port, EoeResult result) noexcept {
    EoeHeader h;
    h.type = static_cast<std::uint8_t>(type);
    h.port = port;
    h.last_fragment = true;
    h.set_result(static_cast<std::uint16_t>(result));
    return h;
}

std::string ip4_to_string(Ip4 ip) {
    char b[16];
    std::snprintf(b, sizeof b, "%u.%u.%u.%u", ip >> 24, (ip >> 16) & 0xFF, (ip >> 8) & 0xFF, ip & 0xFF);
    return b;
}

std::optional<Ip4> parse_ip4(std::string_view s) noexcept {
    Ip4 ip = 0;
    for (int i = 0; i < 4; ++i) {
        unsigned v = 0;
        const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (ec != std::errc{} || v > 255 || p == s.data()) return std::nullopt;
        ip = (ip << 8) | v;
        s.remove_prefix(static_cast<std::size_t>(p - s.data()));
        if (i < 3) {
            if (s.empty() || s.front() != '.') return std::nullopt;
            s.remove_prefix(1);
        }
    }
    if (!s.empty()) return std::nullopt;
    return ip;
}

std::optional<EoeIpParameters> parse_eoe_ip(ConstBytes block) noexcept {
    const auto flags = read_le32(block, 0);
    if (!flags) return std::nullopt;
    EoeIpParameters p;
    std::size_t off = kEoeFlagsSize;
    if (*flags & eoe_ip_flag::Mac) {
        if (block.size() - off < kMacSize) return std::nullopt;
        MacAddress m;
        std::copy_n(block.begin() + static_cast<std::ptrdiff_t>(off), kMacSize, m.begin());
        p.mac = m;
        off += kMacSize;
    }
    const auto ip_field = [&](std::uint32_t flag, std::optional<Ip4>& into) {
        if (!(*flags & flag)) return true;
        const auto v = read_le32(block, off);
        if (!v) return false;
        into = *v;
        off += kIp4Size;
        return true;
    };
    if (!ip_field(eoe_ip_flag::Ip, p.ip) || !ip_field(eoe_ip_flag::Subnet, p.subnet) ||
        !ip_field(eoe_ip_flag::Gateway, p.gateway) || !ip_field(eoe_ip_flag::DnsServer, p.dns_server))
        return std::nullopt;
    if (*flags & eoe_ip_flag::DnsName) {
        const std::size_t n = std::min(block.size() - off, kEoeDnsNameSize);
        const auto* s = reinterpret_cast<const char*>(block.data() + off);
        p.dns_name = std::string(s, std::find(s, s + n, '\0'));
    }
    return p;
}

std::size_t write_eoe_ip(Bytes out, const EoeIpParameters& p) noexcept {
    std::uint32_t flags = 0;
    std::size_t need = kEoeFlagsSize;
    if (p.mac) flags |= eoe_ip_flag::Mac, need += kMacSize;
    if (p.ip) flags |= eoe_ip_flag::Ip, need += kIp4Size;
    if (p.subnet) flags |= eoe_ip_flag::Subnet, need += kIp4Size;
    if (p.gateway) flags |= eoe_ip_flag::Gateway, need += kIp4Size;
    if (p.dns_server) flags |= eoe_ip_flag::DnsServer, need += kIp4Size;
    if (p.dns_name) flags |= eoe_ip_flag::DnsName, need += kEoeDnsNameSize;
    if (out.size() < need) return 0;
    st_le32(out.data(), flags);
    std::size_t off = kEoeFlagsSize;
    if (p.mac) {
        std::copy(p.mac->begin(), p.mac->end(), out.begin() + static_cast<std::ptrdiff_t>(off));
        off += kMacSize;
    }
    for (const auto* v : {&p.ip, &p.subnet, &p.gateway, &p.dns_server}) {
        if (!*v) continue;
        st_le32(out.data() + off, **v);
        off += kIp4Size;
    }
    if (p.dns_name) {
        // Always the full 32 bytes, NUL-padded (TwinCAT and SOEM send it so).
        const std::size_t n = std::min(p.dns_name->size(), kEoeDnsNameSize);
        std::fill_n(out.begin() + static_cast<std::ptrdiff_t>(off), kEoeDnsNameSize, std::uint8_t{0});
        std::copy_n(p.dns_name->begin(), n, out.begin() + static_cast<std::ptrdiff_t>(off));
        off += kEoeDnsNameSize;
    }
    return off;
}

bool EoeAddressFilter::accepts(const MacAddress& dst) const noexcept {
    if (dst == kBroadcastMac) return !no_broadcasts;
    for (std::size_t i = 0; i < count && i < kEoeFilterSlots; ++i) {
        bool match = true;
        for (std::size_t b = 0; b < kMacSize && match; ++b) {
            const std::uint8_t m = i < mask_count ? masks[i][b] : 0xFF;
            match = ((dst[b] ^ macs[i][b]) & m) == 0;
        }
        if (match) return true;
    }
    return false;
}

namespace {
constexpr std::size_t kMasksAt = kEoeFilterOptionsSize + kEoeFilterSlots * kMacSize;
}  // namespace

std::optional<EoeAddressFilter> parse_eoe_filter(ConstBytes block) noexcept {
    const auto options = read_le16(block, 0);
    if (!options) return std::nullopt;
    EoeAddressFilter f;
    f.count = static_cast<std::uint8_t>(*options & eoe_filter_option::CountMask);
    f.mask_count = static_cast<std::uint8_t>((*options & eoe_filter_option::MaskCountMask) >>
                                             eoe_filter_option::MaskCountShift);
    f.no_broadcasts = (*options & eoe_filter_option::NoBroadcasts) != 0;
    if (block.size() < kEoeFilterOptionsSize + f.count * kMacSize) return std::nullopt;
    if (f.mask_count > 0 && block.size() < kMasksAt + f.mask_count * kMacSize) return std::nullopt;
    for (std::size_t i = 0; i < f.count; ++i)
        std::copy_n(block.begin() + static_cast<std::ptrdiff_t>(kEoeFilterOptionsSize + i * kMacSize),
                    kMacSize, f.macs[i].begin());
    for (std::size_t i = 0; i < f.mask_count; ++i)
        std::copy_n(block.begin() + static_cast<std::ptrdiff_t>(kMasksAt + i * kMacSize), kMacSize,
                    f.masks[i].begin());
    return f;
}

std::size_t write_eoe_filter(Bytes out, const EoeAddressFilter& f) noexcept {
    if (out.size() < kEoeFilterBlockSize) return 0;
    std::uint16_t options = static_cast<std::uint16_t>(f.count & eoe_filter_option::CountMask);
    options |= static_cast<std::uint16_t>((f.mask_count << eoe_filter_option::MaskCountShift) &
                                          eoe_filter_option::MaskCountMask);
    if (f.no_broadcasts) options |= eoe_filter_option::NoBroadcasts;
    st_le16(out.data(), options);
    std::fill_n(out.begin() + kEoeFilterOptionsSize, kEoeFilterBlockSize - kEoeFilterOptionsSize,
                std::uint8_t{0});
    for (std::size_t i = 0; i < (f.count & eoe_filter_option::CountMask); ++i)
        std::copy(f.macs[i].begin(), f.macs[i].end(),
                  out.begin() + static_cast<std::ptrdiff_t>(kEoeFilterOptionsSize + i * kMacSize));
    for (std::size_t i = 0; i < std::min<std::size_t>(f.mask_count, 3); ++i)
        std::copy(f.masks[i].begin(), f.masks[i].end(),
                  out.begin() + static_cast<std::ptrdiff_t>(kMasksAt + i * kMacSize));
    return kEoeFilterBlockSize;
}

}  // namespace vecat::protocol
