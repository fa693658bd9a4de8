#include "protocol/mailbox.hpp"

namespace vecat::protocol {

namespace {
inline constexpr unsigned kChannelPriority = 4;  // channel bits 0..5, priority bits 6..7
inline constexpr unsigned kTypeCounter = 5;      // type bits 0..3, counter bits 4..6
inline constexpr std::uint8_t kChannelMask = 0x3F;
inline constexpr unsigned kPriorityShift = 6;
inline constexpr std::uint8_t kTypeMask = 0x0F;
inline constexpr unsigned kCounterShift = 4;
inline constexpr std::uint8_t kCounterMask = 0x07;
}  // namespace

void MailboxHeader::pack(std::span<std::uint8_t, kSize> out) const noexcept {
    st_le16(out.data(), length);
    st_le16(out.data() + 2, address);
    out[kChannelPriority] =
        static_cast<std::uint8_t>((channel & kChannelMask) | (priority << kPriorityShift));
    out[kTypeCounter] =
        static_cast<std::uint8_t>((type & kTypeMask) | ((counter & kCounterMask) << kCounterShift));
}

MailboxHeader MailboxHeader::unpack(std::span<const std::uint8_t, kSize> in) noexcept {
    MailboxHeader h;
    h.length = ld_le16(in.data());
    h.address = ld_le16(in.data() + 2);
    h.channel = in[kChannelPriority] & kChannelMask;
    h.priority = static_cast<std::uint8_t>(in[kChannelPriority] >> kPriorityShift);
    h.type = in[kTypeCounter] & kTypeMask;
    h.counter = static_cast<std::uint8_t>((in[kTypeCounter] >> kCounterShift) & kCounterMask);
    return h;
}

std::optional<MailboxHeader> parse_mailbox_header(ConstBytes b) noexcept {
    if (b.size() < kMailboxHeaderSize) return std::nullopt;
    return MailboxHeader::unpack(b.first<kMailboxHeaderSize>());
}

void write_mailbox_header(Bytes b, const MailboxHeader& h) noexcept {
    if (b.size() < kMailboxHeaderSize) return;
    h.pack(b.first<kMailboxHeaderSize>());
}

std::size_t make_mailbox_error(Bytes payload, MailboxError e) noexcept {
    if (payload.size() < kMailboxErrorSize) return 0;
    st_le16(payload.data(), kMailboxErrorService);
    st_le16(payload.data() + 2, static_cast<std::uint16_t>(e));
    return kMailboxErrorSize;
}

}  // namespace vecat::protocol
