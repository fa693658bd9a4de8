#include "protocol/foe.hpp"

#include <algorithm>

namespace vecat::protocol {

namespace {
inline constexpr std::size_t kOpCode = 0;
inline constexpr std::size_t kReserved = 1;
inline constexpr std::size_t kValue = 2;  // password, packet number, error code, or done + entire
}  // namespace

bool is_foe_opcode(std::uint8_t b) noexcept {
    return b >= static_cast<std::uint8_t>(FoeOpCode::Read) && b <= static_cast<std::uint8_t>(FoeOpCode::Busy);
}

std::optional<FoeMessage> parse_foe(ConstBytes payload) noexcept {
    if (payload.size() < kFoeHeaderSize || !is_foe_opcode(payload[kOpCode])) return std::nullopt;
    FoeMessage m;
    m.op = static_cast<FoeOpCode>(payload[kOpCode]);
    m.value = ld_le32(payload.data() + kValue);
    m.tail = payload.subspan(kFoeHeaderSize);
    return m;
}

std::size_t write_foe(Bytes out, FoeOpCode op, std::uint32_t value, ConstBytes tail) noexcept {
    if (out.size() < kFoeHeaderSize) return 0;
    out[kOpCode] = static_cast<std::uint8_t>(op);
    out[kReserved] = 0;
    st_le32(out.data() + kValue, value);
    const std::size_t n = std::min(tail.size(), out.size() - kFoeHeaderSize);
    std::copy_n(tail.begin(), n, out.begin() + kFoeHeaderSize);
    return kFoeHeaderSize + n;
}

namespace {
ConstBytes as_bytes(std::string_view s) noexcept {
    return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}
}  // namespace

std::size_t write_foe_request(Bytes out, FoeOpCode op, std::uint32_t password,
                              std::string_view name) noexcept {
    return write_foe(out, op, password, as_bytes(name));
}

std::size_t write_foe_data(Bytes out, std::uint32_t packet, ConstBytes data) noexcept {
    return write_foe(out, FoeOpCode::Data, packet, data);
}

std::size_t write_foe_ack(Bytes out, std::uint32_t packet) noexcept {
    return write_foe(out, FoeOpCode::Ack, packet);
}

std::size_t write_foe_error(Bytes out, FoeError e, std::string_view text) noexcept {
    return write_foe(out, FoeOpCode::Error, static_cast<std::uint32_t>(e),
                     as_bytes(text.empty() ? describe(e) : text));
}

std::size_t write_foe_busy(Bytes out, std::uint16_t done, std::uint16_t entire,
                           std::string_view text) noexcept {
    return write_foe(out, FoeOpCode::Busy, static_cast<std::uint32_t>(done) | (std::uint32_t{entire} << 16),
                     as_bytes(text));
}

}  // namespace vecat::protocol
