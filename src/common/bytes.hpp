// Explicit little-endian load/store helpers. EtherCAT is little-endian on the wire and in the ESC
// address space; every multi-byte field goes through these, never through a cast onto a packed struct.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace vecat {

using Bytes = std::span<std::uint8_t>;
using ConstBytes = std::span<const std::uint8_t>;

constexpr std::uint16_t ld_le16(const std::uint8_t* p) noexcept {
    return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
constexpr std::uint32_t ld_le32(const std::uint8_t* p) noexcept {
    return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
           (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
constexpr std::uint64_t ld_le64(const std::uint8_t* p) noexcept {
    return static_cast<std::uint64_t>(ld_le32(p)) | (static_cast<std::uint64_t>(ld_le32(p + 4)) << 32);
}
constexpr void st_le16(std::uint8_t* p, std::uint16_t v) noexcept {
    p[0] = static_cast<std::uint8_t>(v);
    p[1] = static_cast<std::uint8_t>(v >> 8);
}
constexpr void st_le32(std::uint8_t* p, std::uint32_t v) noexcept {
    for (int i = 0; i < 4; ++i)
        p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
constexpr void st_le64(std::uint8_t* p, std::uint64_t v) noexcept {
    for (int i = 0; i < 8; ++i)
        p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

// Checked reads: nullopt when the field does not fit in the buffer.
inline std::optional<std::uint8_t> read_u8(ConstBytes b, std::size_t off) noexcept {
    if (off >= b.size()) return std::nullopt;
    return b[off];
}
inline std::optional<std::uint16_t> read_le16(ConstBytes b, std::size_t off) noexcept {
    if (off > b.size() || b.size() - off < 2) return std::nullopt;
    return ld_le16(b.data() + off);
}
inline std::optional<std::uint32_t> read_le32(ConstBytes b, std::size_t off) noexcept {
    if (off > b.size() || b.size() - off < 4) return std::nullopt;
    return ld_le32(b.data() + off);
}
inline std::optional<std::uint64_t> read_le64(ConstBytes b, std::size_t off) noexcept {
    if (off > b.size() || b.size() - off < 8) return std::nullopt;
    return ld_le64(b.data() + off);
}

// Checked writes: false (and nothing written) when the field does not fit.
inline bool write_le16(Bytes b, std::size_t off, std::uint16_t v) noexcept {
    if (off > b.size() || b.size() - off < 2) return false;
    st_le16(b.data() + off, v);
    return true;
}
inline bool write_le32(Bytes b, std::size_t off, std::uint32_t v) noexcept {
    if (off > b.size() || b.size() - off < 4) return false;
    st_le32(b.data() + off, v);
    return true;
}
inline bool write_le64(Bytes b, std::size_t off, std::uint64_t v) noexcept {
    if (off > b.size() || b.size() - off < 8) return false;
    st_le64(b.data() + off, v);
    return true;
}

// Appends little-endian fields to a byte container (std::vector<uint8_t> or similar).
template <class Container>
class LeWriter {
  public:
    explicit LeWriter(Container& out) : out_(out) {}
    void u8(std::uint8_t v) { out_.push_back(v); }
    void u16(std::uint16_t v) {
        u8(static_cast<std::uint8_t>(v));
        u8(static_cast<std::uint8_t>(v >> 8));
    }
    void u32(std::uint32_t v) {
        u16(static_cast<std::uint16_t>(v));
        u16(static_cast<std::uint16_t>(v >> 16));
    }
    void u64(std::uint64_t v) {
        u32(static_cast<std::uint32_t>(v));
        u32(static_cast<std::uint32_t>(v >> 32));
    }
    void bytes(ConstBytes b) { out_.insert(out_.end(), b.begin(), b.end()); }
    void str(std::string_view s) { out_.insert(out_.end(), s.begin(), s.end()); }
    void fill(std::size_t n, std::uint8_t v) { out_.insert(out_.end(), n, v); }

  private:
    Container& out_;
};

// A byte sink over a fixed span for LeWriter: bytes past the end are counted but not written, so the
// caller sees an overflow (size() > capacity()) instead of a write out of bounds.
class SpanSink {
  public:
    struct End {};
    explicit SpanSink(Bytes b) : b_(b) {}
    void push_back(std::uint8_t v) {
        if (n_ < b_.size()) b_[n_] = v;
        ++n_;
    }
    End end() const { return {}; }
    template <class It>
    void insert(End, It first, It last) {
        for (; first != last; ++first)
            push_back(static_cast<std::uint8_t>(*first));
    }
    void insert(End, std::size_t count, std::uint8_t v) {
        for (std::size_t i = 0; i < count; ++i)
            push_back(v);
    }
    std::size_t size() const { return n_; }
    std::size_t capacity() const { return b_.size(); }
    bool fits() const { return n_ <= b_.size(); }
    std::size_t room() const { return b_.size() > n_ ? b_.size() - n_ : 0; }

  private:
    Bytes b_;
    std::size_t n_ = 0;
};

}  // namespace vecat
