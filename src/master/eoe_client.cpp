#include "master/eoe_client.hpp"

#include <algorithm>
#include <array>

namespace vecat::master {

using namespace protocol;
using Clock = std::chrono::steady_clock;

EoeClient::EoeClient(Master& m, std::uint16_t station) : mbx_(m, station) {}

bool EoeClient::send_frame(ConstBytes frame, std::uint8_t port) {
    if (eoe_size_blocks(frame.size()) > kEoeMaxBlocks || mbx_.mailbox_size_out() <= kMailboxHeaderSize)
        return false;
    const std::size_t cap = mbx_.mailbox_size_out() - kMailboxHeaderSize;  // mailbox payload
    const std::size_t full = eoe_fragment_capacity(cap);
    if (full == 0) return false;
    tx_frame_ = static_cast<std::uint8_t>(tx_frame_ % kEoeMaxFrameNumber + 1);
    std::vector<std::uint8_t> buf(cap);
    std::size_t off = 0;
    std::uint8_t fragment = 0;
    do {
        const std::size_t left = frame.size() - off;
        const bool last = left + kEoeHeaderSize <= cap;
        const std::size_t n = last ? left : full;
        EoeHeader h;
        h.type = static_cast<std::uint8_t>(EoeFrameType::Fragment);
        h.port = port;
        h.last_fragment = last;
        h.fragment = fragment;
        h.blocks =
            fragment == 0 ? eoe_size_blocks(frame.size()) : static_cast<std::uint8_t>(off / kEoeBlockSize);
        h.frame = tx_frame_;
        write_eoe_header(buf, h);
        std::copy_n(frame.begin() + static_cast<std::ptrdiff_t>(off), n, buf.begin() + kEoeHeaderSize);
        if (!mbx_.send(MailboxType::EoE, ConstBytes(buf.data(), kEoeHeaderSize + n), mbx_.next_counter()))
            return false;
        off += n;
        ++fragment;
    } while (off < frame.size());
    return true;
}

void EoeClient::take_fragment(const EoeHeader& h, ConstBytes data) {
    if (h.fragment == 0) {
        rx_size_ = std::size_t{h.blocks} * kEoeBlockSize;
        rx_.clear();
        rx_frame_ = h.frame;
        rx_next_ = 0;
    } else if (rx_next_ == 0 || h.fragment != rx_next_ || h.frame != rx_frame_ ||
               std::size_t{h.blocks} * kEoeBlockSize != rx_.size()) {
        ++bad_fragments_;
        rx_next_ = 0;
        rx_.clear();
        return;
    }
    const std::size_t room = rx_size_ + (h.time_appended ? kEoeTimestampSize : 0);
    if (data.size() > room - std::min(room, rx_.size())) {
        ++bad_fragments_;
        rx_next_ = 0;
        rx_.clear();
        return;
    }
    rx_.insert(rx_.end(), data.begin(), data.end());
    if (!h.last_fragment) {
        rx_next_ = static_cast<std::uint8_t>(h.fragment + 1);
        return;
    }
    if (h.time_appended) rx_.resize(rx_.size() >= kEoeTimestampSize ? rx_.size() - kEoeTimestampSize : 0);
    frames_.push_back(std::move(rx_));
    rx_.clear();
    rx_next_ = 0;
}

std::optional<MailboxMessage> EoeClient::take(std::chrono::milliseconds t) {
    auto m = mbx_.receive(t);
    if (!m) return std::nullopt;
    if (m->header.type == static_cast<std::uint8_t>(MailboxType::EoE)) {
        const auto h = parse_eoe_header(m->payload);
        if (h && h->frame_type() == EoeFrameType::Fragment) {
            take_fragment(*h, ConstBytes(m->payload).subspan(kEoeHeaderSize));
            return std::nullopt;
        }
    }
    return m;
}

std::optional<std::vector<std::uint8_t>> EoeClient::receive_frame(std::chrono::milliseconds t) {
    const auto deadline = Clock::now() + t;
    while (frames_.empty()) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
        if (auto m = take(std::max(left, std::chrono::milliseconds(0)))) {
            if (m->header.type == static_cast<std::uint8_t>(MailboxType::Error) && m->payload.size() >= 4)
                mailbox_errors_.push_back(static_cast<MailboxError>(ld_le16(m->payload.data() + 2)));
        }
        if (Clock::now() >= deadline) break;
    }
    if (frames_.empty()) return std::nullopt;
    auto f = std::move(frames_.front());
    frames_.pop_front();
    return f;
}

EoeServiceResult EoeClient::service(ConstBytes payload, EoeFrameType response_type) {
    EoeServiceResult r;
    if (!mbx_.send(MailboxType::EoE, payload, mbx_.next_counter())) return r;
    const auto deadline = Clock::now() + timeout;
    while (true) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
        if (auto m = take(std::max(left, std::chrono::milliseconds(0)))) {
            r.transport_ok = true;
            if (m->header.type == static_cast<std::uint8_t>(MailboxType::Error)) {
                if (m->payload.size() >= kMailboxErrorSize)
                    r.mailbox_error = static_cast<MailboxError>(ld_le16(m->payload.data() + 2));
                else
                    r.unexpected = true;
                return r;
            }
            const auto h = parse_eoe_header(m->payload);
            if (m->header.type != static_cast<std::uint8_t>(MailboxType::EoE) || !h ||
                h->frame_type() != response_type) {
                r.unexpected = true;
                return r;
            }
            r.result = h->result();
            const ConstBytes block = ConstBytes(m->payload).subspan(kEoeHeaderSize);
            if (*r.result == 0 && response_type == EoeFrameType::GetIpResponse) {
                r.ip = parse_eoe_ip(block);
                if (!r.ip) r.unexpected = true;
            }
            if (*r.result == 0 && response_type == EoeFrameType::GetFilterResponse) {
                r.filter = parse_eoe_filter(block);
                if (!r.filter) r.unexpected = true;
            }
            return r;
        }
        if (Clock::now() >= deadline) return r;
    }
}

namespace {
EoeHeader request_header(EoeFrameType type, std::uint8_t port) {
    EoeHeader h;
    h.type = static_cast<std::uint8_t>(type);
    h.port = port;
    h.last_fragment = true;
    return h;
}
}  // namespace

EoeServiceResult EoeClient::set_ip(const EoeIpParameters& p, std::uint8_t port) {
    std::array<std::uint8_t, kEoeHeaderSize + kEoeIpBlockMaxSize> b{};
    write_eoe_header(b, request_header(EoeFrameType::SetIpRequest, port));
    const std::size_t n = write_eoe_ip(Bytes(b).subspan(kEoeHeaderSize), p);
    return service(ConstBytes(b.data(), kEoeHeaderSize + n), EoeFrameType::SetIpResponse);
}

EoeServiceResult EoeClient::get_ip(std::uint8_t port) {
    std::array<std::uint8_t, kEoeHeaderSize> b{};
    write_eoe_header(b, request_header(EoeFrameType::GetIpRequest, port));
    return service(b, EoeFrameType::GetIpResponse);
}

EoeServiceResult EoeClient::set_filter(const EoeAddressFilter& f, std::uint8_t port) {
    std::array<std::uint8_t, kEoeHeaderSize + kEoeFilterBlockSize> b{};
    write_eoe_header(b, request_header(EoeFrameType::SetFilterRequest, port));
    write_eoe_filter(Bytes(b).subspan(kEoeHeaderSize), f);
    return service(b, EoeFrameType::SetFilterResponse);
}

EoeServiceResult EoeClient::get_filter(std::uint8_t port) {
    std::array<std::uint8_t, kEoeHeaderSize> b{};
    write_eoe_header(b, request_header(EoeFrameType::GetFilterRequest, port));
    return service(b, EoeFrameType::GetFilterResponse);
}

}  // namespace vecat::master
