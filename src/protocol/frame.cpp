#include "protocol/frame.hpp"

#include <algorithm>

namespace vecat::protocol {

void EthernetHeader::pack(std::span<std::uint8_t, kSize> out) const noexcept {
    std::copy(destination.begin(), destination.end(), out.begin());
    std::copy(source.begin(), source.end(), out.begin() + 6);
    out[kEtherTypeOffset] = static_cast<std::uint8_t>(ether_type >> 8);
    out[kEtherTypeOffset + 1] = static_cast<std::uint8_t>(ether_type & 0xFF);
}

EthernetHeader EthernetHeader::unpack(std::span<const std::uint8_t, kSize> in) noexcept {
    EthernetHeader h;
    std::copy_n(in.begin(), 6, h.destination.begin());
    std::copy_n(in.begin() + 6, 6, h.source.begin());
    h.ether_type = static_cast<std::uint16_t>((in[kEtherTypeOffset] << 8) | in[kEtherTypeOffset + 1]);
    return h;
}

void DatagramHeader::pack(std::span<std::uint8_t, kSize> out) const noexcept {
    std::uint8_t* p = out.data();
    p[datagram::Command] = static_cast<std::uint8_t>(command);
    p[datagram::Index] = index;
    st_le32(p + datagram::Address, address);
    std::uint16_t lf = length & datagram::LengthMask;
    if (circulating) lf |= datagram::Circulating;
    if (more) lf |= datagram::More;
    st_le16(p + datagram::LengthFlags, lf);
    st_le16(p + datagram::Irq, irq);
}

DatagramHeader DatagramHeader::unpack(std::span<const std::uint8_t, kSize> in) noexcept {
    const std::uint8_t* p = in.data();
    const std::uint16_t lf = ld_le16(p + datagram::LengthFlags);
    return {static_cast<Command>(p[datagram::Command]),
            p[datagram::Index],
            ld_le32(p + datagram::Address),
            static_cast<std::uint16_t>(lf & datagram::LengthMask),
            (lf & datagram::Circulating) != 0,
            (lf & datagram::More) != 0,
            ld_le16(p + datagram::Irq)};
}

ParsedFrame parse_frame(ConstBytes frame) noexcept {
    ParsedFrame pf;
    if (frame.size() < kEthHeaderSize + kEcatHeaderSize) {
        pf.error = FrameError::TooShort;
        return pf;
    }
    std::size_t off = EthernetHeader::kEtherTypeOffset;
    auto ether_type = [&] { return static_cast<std::uint16_t>((frame[off] << 8) | frame[off + 1]); };
    std::uint16_t ethertype = ether_type();
    if (ethertype == kEtherTypeVlan) {
        off += kVlanTagSize;
        if (frame.size() < off + 2 + kEcatHeaderSize) {
            pf.error = FrameError::TooShort;
            return pf;
        }
        ethertype = ether_type();
    }
    if (ethertype != kEtherTypeEtherCat) {
        pf.error = FrameError::NotEtherCat;
        return pf;
    }
    off += 2;
    pf.ecat_offset = off;
    const EcatHeader ecat = EcatHeader::from_word(ld_le16(frame.data() + off));
    const std::size_t ecat_len = ecat.length;
    if (ecat.type != kEcatTypeCommands) {
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
        const std::uint16_t lenflags = ld_le16(frame.data() + off + datagram::LengthFlags);
        const std::size_t dlen = lenflags & datagram::LengthMask;
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
        if (!(lenflags & datagram::More)) break;
    }
    return pf;
}

}  // namespace vecat::protocol
