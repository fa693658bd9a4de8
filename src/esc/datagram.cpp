#include "esc/datagram.hpp"

namespace vecat::esc {

ParsedFrame parse_frame(ConstBytes frame) noexcept {
    ParsedFrame pf;
    if (frame.size() < kEthHeaderSize + kEcatHeaderSize) {
        pf.error = FrameError::TooShort;
        return pf;
    }
    std::size_t off = 12;
    std::uint16_t ethertype = static_cast<std::uint16_t>((frame[off] << 8) | frame[off + 1]);
    if (ethertype == kEtherTypeVlan) {
        off += 4;
        if (frame.size() < off + 2 + kEcatHeaderSize) {
            pf.error = FrameError::TooShort;
            return pf;
        }
        ethertype = static_cast<std::uint16_t>((frame[off] << 8) | frame[off + 1]);
    }
    if (ethertype != kEtherTypeEtherCat) {
        pf.error = FrameError::NotEtherCat;
        return pf;
    }
    off += 2;
    pf.ecat_offset = off;
    const std::uint16_t ecat_hdr = ld_le16(frame.data() + off);
    const std::size_t ecat_len = ecat_hdr & 0x07FF;
    const unsigned type = ecat_hdr >> 12;
    if (type != kEcatTypeCommands) {
        pf.error = FrameError::NotCommands;
        return pf;
    }
    off += kEcatHeaderSize;
    if (ecat_len > frame.size() - off) {
        pf.error = FrameError::HeaderLength;
        return pf;
    }
    const std::size_t end = off + ecat_len;
    if (ecat_len < kDatagramHeaderSize + kWkcSize) {
        pf.error = FrameError::TooShort;
        return pf;
    }
    while (true) {
        if (end - off < kDatagramHeaderSize + kWkcSize) {
            pf.error = FrameError::DatagramOverrun;
            return pf;
        }
        const std::uint16_t lenflags = ld_le16(frame.data() + off + 6);
        const std::size_t dlen = lenflags & 0x07FF;
        if (end - off - kDatagramHeaderSize - kWkcSize < dlen) {
            pf.error = FrameError::DatagramOverrun;
            return pf;
        }
        if (pf.count == kMaxDatagramsPerFrame) {
            pf.error = FrameError::TooManyDatagrams;
            return pf;
        }
        pf.offsets[pf.count++] = static_cast<std::uint16_t>(off);
        off += kDatagramHeaderSize + dlen + kWkcSize;
        if (!(lenflags & 0x8000)) break;
    }
    return pf;
}

}  // namespace vecat::esc
