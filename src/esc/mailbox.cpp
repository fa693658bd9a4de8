#include "esc/mailbox.hpp"

namespace vecat::esc {

std::optional<MailboxHeader> parse_mailbox_header(ConstBytes b) noexcept {
    if (b.size() < kMailboxHeaderSize) return std::nullopt;
    MailboxHeader h;
    h.length = ld_le16(b.data());
    h.address = ld_le16(b.data() + 2);
    h.channel = b[4] & 0x3F;
    h.priority = static_cast<std::uint8_t>(b[4] >> 6);
    h.type = b[5] & 0x0F;
    h.counter = static_cast<std::uint8_t>((b[5] >> 4) & 0x07);
    return h;
}

void write_mailbox_header(Bytes b, const MailboxHeader& h) noexcept {
    if (b.size() < kMailboxHeaderSize) return;
    st_le16(b.data(), h.length);
    st_le16(b.data() + 2, h.address);
    b[4] = static_cast<std::uint8_t>((h.channel & 0x3F) | (h.priority << 6));
    b[5] = static_cast<std::uint8_t>((h.type & 0x0F) | ((h.counter & 0x07) << 4));
}

std::size_t make_mailbox_error(Bytes payload, MailboxError e) noexcept {
    if (payload.size() < 4) return 0;
    st_le16(payload.data(), 0x0001);
    st_le16(payload.data() + 2, static_cast<std::uint16_t>(e));
    return 4;
}

}  // namespace vecat::esc
