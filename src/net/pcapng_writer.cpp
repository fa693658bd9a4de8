#include "net/pcapng_writer.hpp"

#include <cerrno>
#include <cstring>
#include <system_error>
#include <vector>

namespace vecat::net {
namespace {

void put32(std::FILE* f, std::uint32_t v) {
    std::uint8_t b[4];
    st_le32(b, v);
    std::fwrite(b, 1, 4, f);
}
void put16(std::FILE* f, std::uint16_t v) {
    std::uint8_t b[2];
    st_le16(b, v);
    std::fwrite(b, 1, 2, f);
}
std::uint32_t pad4(std::size_t n) {
    return static_cast<std::uint32_t>((n + 3) & ~std::size_t{3});
}
void put_padded(std::FILE* f, const void* p, std::size_t n) {
    static constexpr std::uint8_t zeros[4] = {};
    std::fwrite(p, 1, n, f);
    std::fwrite(zeros, 1, pad4(n) - n, f);
}

}  // namespace

PcapngWriter::PcapngWriter(const std::string& path, const std::string& ifname, std::uint64_t limit_bytes)
    : limit_(limit_bytes) {
    f_ = std::fopen(path.c_str(), "wb");
    if (!f_) throw std::system_error(errno, std::generic_category(), "pcapng " + path);
    // Section Header Block
    const char* app = "vecat";
    const std::uint32_t shb_opts = 4 + pad4(std::strlen(app)) + 4;  // shb_userappl + opt_endofopt
    const std::uint32_t shb_len = 28 + shb_opts;
    put32(f_, 0x0A0D0D0A);
    put32(f_, shb_len);
    put32(f_, 0x1A2B3C4D);
    put16(f_, 1);
    put16(f_, 0);
    put32(f_, 0xFFFFFFFF);
    put32(f_, 0xFFFFFFFF);  // section length unknown
    put16(f_, 4);           // shb_userappl
    put16(f_, static_cast<std::uint16_t>(std::strlen(app)));
    put_padded(f_, app, std::strlen(app));
    put32(f_, 0);
    put32(f_, shb_len);
    // Interface Description Block: Ethernet, nanosecond timestamps
    const std::uint32_t idb_opts = (4 + pad4(ifname.size())) + (4 + 4) + 4;
    const std::uint32_t idb_len = 20 + idb_opts;
    put32(f_, 0x00000001);
    put32(f_, idb_len);
    put16(f_, 1);  // LINKTYPE_ETHERNET
    put16(f_, 0);
    put32(f_, 0);  // snaplen: no limit
    put16(f_, 2);  // if_name
    put16(f_, static_cast<std::uint16_t>(ifname.size()));
    put_padded(f_, ifname.data(), ifname.size());
    put16(f_, 9);  // if_tsresol
    put16(f_, 1);
    const std::uint8_t tsresol[4] = {9, 0, 0, 0};  // 10^-9 s
    std::fwrite(tsresol, 1, 4, f_);
    put32(f_, 0);
    put32(f_, idb_len);
    bytes_ = static_cast<std::uint64_t>(std::ftell(f_));
}

PcapngWriter::~PcapngWriter() {
    if (f_) std::fclose(f_);
}

void PcapngWriter::write(ConstBytes frame, std::uint64_t unix_ns, int direction) {
    if (!f_) return;
    const std::uint32_t opts = 4 + 4 + 4;  // epb_flags + opt_endofopt
    const std::uint32_t len = 32 + pad4(frame.size()) + opts;
    if (limit_ && bytes_ + len > limit_) {
        ++dropped_;
        return;
    }
    bytes_ += len;
    put32(f_, 0x00000006);
    put32(f_, len);
    put32(f_, 0);  // interface 0
    put32(f_, static_cast<std::uint32_t>(unix_ns >> 32));
    put32(f_, static_cast<std::uint32_t>(unix_ns));
    put32(f_, static_cast<std::uint32_t>(frame.size()));
    put32(f_, static_cast<std::uint32_t>(frame.size()));
    put_padded(f_, frame.data(), frame.size());
    put16(f_, 2);  // epb_flags
    put16(f_, 4);
    put32(f_, static_cast<std::uint32_t>(direction & 0x3));
    put32(f_, 0);
    put32(f_, len);
    ++frames_;
}

void PcapngWriter::flush() {
    if (f_) std::fflush(f_);
}

}  // namespace vecat::net
