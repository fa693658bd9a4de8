#include "eoe/eoe_server.hpp"

#include <algorithm>

#include "eoe/ip_responder.hpp"

namespace vecat::eoe {

using protocol::AlState;
using protocol::EoeFrameType;
using protocol::EoeHeader;
using protocol::EoeResult;
using protocol::kEoeBlockSize;
using protocol::kEoeHeaderSize;
using protocol::MailboxError;
using protocol::MailboxType;

namespace {

// The device has one Ethernet port. Port 0 means "the device" (what SOEM and TwinCAT send), port 1 is that
// port; any other port number is answered with "unspecified error" (as SOES does).
constexpr std::uint8_t kLastPort = 1;

// Slave N's default MAC address: locally administered (bit 1 of the first byte), unicast (bit 0 clear).
constexpr std::uint8_t kLocalUnicast = 0x02;
constexpr std::uint8_t kMacTag = 0x45;  // 'E'

// Frame numbers of frames to the master run 1..15 (0 is left out so that the first frame differs from a
// never-sent one, as SOES counts).
constexpr std::uint8_t next_frame_number(std::uint8_t n) {
    return static_cast<std::uint8_t>(n % protocol::kEoeMaxFrameNumber + 1);
}

bool mailbox_running(AlState s) {
    return s == AlState::PreOp || s == AlState::SafeOp || s == AlState::Op;
}

}  // namespace

protocol::MacAddress default_mac(std::size_t slave_index) {
    const std::size_t n = slave_index + 1;
    return {
        kLocalUnicast, 0x00, 0x00, kMacTag, static_cast<std::uint8_t>(n >> 8), static_cast<std::uint8_t>(n)};
}

EoeServer::EoeServer(esc::Slave& slave, EoeOptions options, protocol::MacAddress mac)
    : slave_(slave), options_(options) {
    params_.mac = mac;
    const std::size_t slots = std::max<std::size_t>(options_.queue_frames, 1);
    q_.resize(slots);
    q_len_.resize(slots);
}

void EoeServer::handle(const protocol::MailboxHeader&, ConstBytes payload, esc::MailboxReplySink& out) {
    const auto h = protocol::parse_eoe_header(payload);
    if (!h) return mailbox_error(MailboxError::SizeTooShort, out);  // ETG.1000.4 Table 30
    const ConstBytes body = payload.subspan(kEoeHeaderSize);
    switch (h->frame_type()) {
        case EoeFrameType::Fragment:
            return take_fragment(*h, body, out);
        case EoeFrameType::SetIpRequest:
            return set_ip(*h, body, out);
        case EoeFrameType::GetIpRequest:
            return get_ip(*h, out);
        case EoeFrameType::SetFilterRequest:
            return set_filter(*h, body, out);
        case EoeFrameType::GetFilterRequest:
            return get_filter(*h, out);
        default:
            // Responses, the time stamp (slave to master only) and the types ETG.1000.6 does not define:
            // answered with the same type and "unsupported frame type", as SOES does.
            return respond(static_cast<EoeFrameType>(h->type), h->port, EoeResult::UnsupportedFrameType, out);
    }
}

// ETG.1000.6 5.7: the fragments of a frame come in order: fragment 0 with the complete size (in 32-byte
// blocks), then fragments 1, 2, ... each with its offset (in blocks) and the same frame number; the last
// has "last fragment" set. A frame that breaks the order is given up.
void EoeServer::take_fragment(const EoeHeader& h, ConstBytes data, esc::MailboxReplySink& out) {
    if (h.fragment == 0) {
        if (rx_next_ != 0) drop_rx();  // a new frame begins: the half one is given up
        rx_size_ = std::size_t{h.blocks} * kEoeBlockSize;
        if (rx_size_ + protocol::kEoeTimestampSize > kRxBufferSize) {
            ++counters_.oversize;
            clear_rx();
            return mailbox_error(MailboxError::NoMoreMemory, out);
        }
        rx_frame_ = h.frame;
        rx_len_ = 0;
    } else if (rx_next_ == 0 || h.fragment != rx_next_ || h.frame != rx_frame_ ||
               std::size_t{h.blocks} * kEoeBlockSize != rx_len_) {
        // A gap, an overlap (the offset is not where the data so far ends), a repeated fragment or one of
        // another frame: the frame in progress (if any) is given up with it.
        ++counters_.out_of_sequence;
        if (rx_next_ != 0) drop_rx();
        return mailbox_error(MailboxError::InvalidHeader, out);
    }
    // The data may end with a 4-byte time stamp (time appended) beyond the announced size.
    const std::size_t room =
        rx_size_ + (h.last_fragment && h.time_appended ? protocol::kEoeTimestampSize : 0);
    if (data.size() > room - rx_len_ || (!h.last_fragment && data.size() % kEoeBlockSize != 0)) {
        ++counters_.oversize;
        drop_rx();
        return mailbox_error(MailboxError::InvalidSize, out);
    }
    std::copy(data.begin(), data.end(), rx_.begin() + static_cast<std::ptrdiff_t>(rx_len_));
    rx_len_ += data.size();
    ++counters_.fragments_in;
    if (!h.last_fragment) {
        if (rx_next_ == protocol::kEoeMaxFragmentNumber) {  // the 6-bit fragment number would wrap
            ++counters_.oversize;
            drop_rx();
            return mailbox_error(MailboxError::InvalidSize, out);
        }
        rx_next_ = static_cast<std::uint8_t>(h.fragment + 1);
        return;
    }
    std::size_t len = rx_len_;
    if (h.time_appended) len = len >= protocol::kEoeTimestampSize ? len - protocol::kEoeTimestampSize : 0;
    ++counters_.frames_in;
    deliver(ConstBytes(rx_.data(), len));
    clear_rx();
    // Fragments are not answered (ETG.1000.6 5.7); "time requested" would ask for a time stamp frame
    // (type 1), which vecat's devices do not send (src/eoe/README.md).
}

void EoeServer::deliver(ConstBytes frame) {
    std::size_t n = 0;
    const protocol::Ip4 ip = params_.ip.value_or(0);
    switch (answer(frame, mac(), ip, answer_, n)) {
        case Answer::ArpReply:
            ++counters_.arp_replies;
            enqueue(ConstBytes(answer_.data(), n));
            break;
        case Answer::EchoReply:
            ++counters_.echo_replies;
            enqueue(ConstBytes(answer_.data(), n));
            return;  // for the device alone
        case Answer::None:
            break;
    }
    // Everything not addressed to the device alone goes to its Ethernet side: other unicast addresses,
    // broadcasts (an ARP request for the device's address too: the Ethernet side may have the address as
    // well) and multicasts. Frames to the device's own MAC that its stack does not answer end here.
    const auto dst = destination_mac(frame);
    if (!dst || *dst == mac()) return;
    if (!port_) {
        ++counters_.no_ethernet;
        return;
    }
    ++counters_.to_ethernet;
    port_->send(frame);
}

bool EoeServer::from_ethernet(ConstBytes frame) {
    if (!mailbox_running(slave_.state())) {
        ++counters_.not_running;
        return false;
    }
    const auto dst = destination_mac(frame);
    if (!dst || frame.size() > protocol::kEthernetMaxFrame) {
        ++counters_.oversize;
        return false;
    }
    if (filter_ && !filter_->accepts(*dst)) {
        ++counters_.filtered;
        return false;
    }
    if (!enqueue(frame)) return false;
    ++counters_.from_ethernet;
    return true;
}

bool EoeServer::enqueue(ConstBytes frame) {
    if (q_count_ == q_.size()) {
        ++counters_.queue_full;
        return false;
    }
    const std::size_t slot = (q_head_ + q_count_) % q_.size();
    std::copy(frame.begin(), frame.end(), q_[slot].begin());
    q_len_[slot] = static_cast<std::uint16_t>(frame.size());
    ++q_count_;
    return true;
}

// One fragment of the head frame per call, and only when no other reply waits for the master: the
// mailbox keeps serving CoE between the fragments of a frame.
void EoeServer::poll(esc::MailboxReplySink& out) {
    if (q_count_ == 0 || out.pending() > 0 || !out.can_commit()) return;
    const Bytes b = out.reply_buffer();
    const std::size_t total = q_len_[q_head_];
    const std::size_t left = total - tx_off_;
    const std::size_t full = protocol::eoe_fragment_capacity(b.size());
    if (full == 0) {  // a mailbox too small for one block: the frame cannot be sent
        ++counters_.queue_full;
        q_head_ = (q_head_ + 1) % q_.size();
        --q_count_;
        return;
    }
    const bool last = left + kEoeHeaderSize <= b.size();
    const std::size_t n = last ? left : full;
    EoeHeader h;
    h.type = static_cast<std::uint8_t>(EoeFrameType::Fragment);
    h.last_fragment = last;
    h.fragment = tx_fragment_;
    if (tx_fragment_ == 0) tx_frame_ = next_frame_number(tx_frame_);
    h.blocks = tx_fragment_ == 0 ? protocol::eoe_size_blocks(total)
                                 : static_cast<std::uint8_t>(tx_off_ / kEoeBlockSize);
    h.frame = tx_frame_;
    protocol::write_eoe_header(b, h);
    std::copy_n(q_[q_head_].begin() + static_cast<std::ptrdiff_t>(tx_off_), n, b.begin() + kEoeHeaderSize);
    out.commit(MailboxType::EoE, kEoeHeaderSize + n);
    ++counters_.fragments_out;
    if (last) {
        ++counters_.frames_out;
        q_head_ = (q_head_ + 1) % q_.size();
        --q_count_;
        tx_off_ = 0;
        tx_fragment_ = 0;
    } else {
        tx_off_ += n;
        ++tx_fragment_;
    }
}

void EoeServer::set_ip(const EoeHeader& h, ConstBytes block, esc::MailboxReplySink& out) {
    constexpr auto resp = EoeFrameType::SetIpResponse;
    if (!options_.ip_support) return respond(resp, h.port, EoeResult::NoIpSupport, out);
    if (h.port > kLastPort) return respond(resp, h.port, EoeResult::UnspecifiedError, out);
    const auto p = protocol::parse_eoe_ip(block);
    if (!p) return respond(resp, h.port, EoeResult::UnspecifiedError, out);
    // 0.0.0.0 as the device's address asks it to find one itself (DHCP), which vecat's devices cannot.
    if (p->ip && *p->ip == 0) return respond(resp, h.port, EoeResult::NoDhcpSupport, out);
    if (p->mac && ((*p->mac)[0] & 0x01)) return respond(resp, h.port, EoeResult::UnspecifiedError, out);
    if (p->mac) params_.mac = p->mac;
    if (p->ip) params_.ip = p->ip;
    if (p->subnet) params_.subnet = p->subnet;
    if (p->gateway) params_.gateway = p->gateway;
    if (p->dns_server) params_.dns_server = p->dns_server;
    if (p->dns_name) params_.dns_name = p->dns_name;
    respond(resp, h.port, EoeResult::Success, out);
}

void EoeServer::get_ip(const EoeHeader& h, esc::MailboxReplySink& out) {
    constexpr auto resp = EoeFrameType::GetIpResponse;
    if (!options_.ip_support) return respond(resp, h.port, EoeResult::NoIpSupport, out);
    if (h.port > kLastPort) return respond(resp, h.port, EoeResult::UnspecifiedError, out);
    std::array<std::uint8_t, protocol::kEoeIpBlockMaxSize> block{};
    const std::size_t n = protocol::write_eoe_ip(block, params_);
    respond(resp, h.port, EoeResult::Success, out, ConstBytes(block.data(), n));
}

void EoeServer::set_filter(const EoeHeader& h, ConstBytes block, esc::MailboxReplySink& out) {
    constexpr auto resp = EoeFrameType::SetFilterResponse;
    if (!options_.filter_support) return respond(resp, h.port, EoeResult::NoFilterSupport, out);
    if (h.port > kLastPort) return respond(resp, h.port, EoeResult::UnspecifiedError, out);
    const auto f = protocol::parse_eoe_filter(block);
    if (!f) return respond(resp, h.port, EoeResult::UnspecifiedError, out);
    filter_ = *f;
    respond(resp, h.port, EoeResult::Success, out);
}

void EoeServer::get_filter(const EoeHeader& h, esc::MailboxReplySink& out) {
    constexpr auto resp = EoeFrameType::GetFilterResponse;
    if (!options_.filter_support) return respond(resp, h.port, EoeResult::NoFilterSupport, out);
    if (h.port > kLastPort) return respond(resp, h.port, EoeResult::UnspecifiedError, out);
    std::array<std::uint8_t, protocol::kEoeFilterBlockSize> block{};
    // No filter set: an empty one is reported (the device forwards every frame until one is set).
    const std::size_t n = protocol::write_eoe_filter(block, filter_.value_or(protocol::EoeAddressFilter{}));
    respond(resp, h.port, EoeResult::Success, out, ConstBytes(block.data(), n));
}

void EoeServer::respond(EoeFrameType type, std::uint8_t port, EoeResult r, esc::MailboxReplySink& out,
                        ConstBytes block) {
    if (r != EoeResult::Success) ++counters_.results_sent;
    const Bytes b = out.reply_buffer();
    if (b.size() < kEoeHeaderSize + block.size()) return mailbox_error(MailboxError::NoMoreMemory, out);
    protocol::write_eoe_header(b, protocol::eoe_response_header(type, port, r));
    std::copy(block.begin(), block.end(), b.begin() + kEoeHeaderSize);
    out.commit(MailboxType::EoE, kEoeHeaderSize + block.size());
}

void EoeServer::mailbox_error(MailboxError e, esc::MailboxReplySink& out) {
    ++counters_.mailbox_errors;
    const std::size_t n = protocol::make_mailbox_error(out.reply_buffer(), e);
    out.commit(MailboxType::Error, n);
}

void EoeServer::drop_rx() {
    if (rx_next_ != 0 || rx_len_ != 0) ++counters_.incomplete;
    clear_rx();
}

void EoeServer::clear_rx() {
    rx_next_ = 0;
    rx_len_ = 0;
    rx_size_ = 0;
    rx_frame_ = 0;
}

void EoeServer::reset() {
    // The mailbox was reset (INIT, BOOT): the half frame and the frames not yet sent are lost, as in a
    // device whose mailbox buffers are cleared. The IP parameters and the filter stay (device memory).
    drop_rx();
    counters_.not_running += q_count_;
    q_head_ = 0;
    q_count_ = 0;
    tx_off_ = 0;
    tx_fragment_ = 0;
}

std::size_t attach_eoe(esc::Segment& seg, const EoeOptions& options) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < seg.size(); ++i) {
        auto& s = seg.slave(i);
        const auto& d = s.description();
        if (!(d.mailbox_protocols & device::mbx_proto::EoE) || !d.sm_of_type(device::SmType::MailboxOut))
            continue;
        s.add_mailbox_protocol(std::make_unique<EoeServer>(s, options, default_mac(i)));
        ++n;
    }
    return n;
}

EoeServer* eoe_server(esc::Slave& slave) {
    return dynamic_cast<EoeServer*>(slave.mailbox_protocol(MailboxType::EoE));
}

}  // namespace vecat::eoe
