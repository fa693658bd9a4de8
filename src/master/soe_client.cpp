#include "master/soe_client.hpp"

#include <algorithm>

namespace vecat::master {

using namespace protocol;

SoeClient::SoeClient(Master& m, std::uint16_t station) : mbx_(m, station) {}

std::optional<SoeMessage> SoeClient::answer(SoeResult& r) {
    for (;;) {
        last_ = mbx_.receive(timeout);
        if (!last_) {
            r.transport_ok = false;
            return std::nullopt;
        }
        if (last_->header.type == static_cast<std::uint8_t>(MailboxType::Error)) {
            if (last_->payload.size() >= kMailboxErrorSize)
                r.mailbox_error = static_cast<MailboxError>(ld_le16(last_->payload.data() + 2));
            else
                r.unexpected = true;
            return std::nullopt;
        }
        if (last_->header.type != static_cast<std::uint8_t>(MailboxType::SoE)) {
            r.unexpected = true;
            return std::nullopt;
        }
        auto m = parse_soe(last_->payload);
        if (!m) {
            r.unexpected = true;
            return std::nullopt;
        }
        if (m->op == SoeOpCode::Notification) {
            // Unsolicited: kept for notification(), then the answer is still to come.
            SoeNotification n;
            n.drive = m->drive;
            n.idn = m->idn();
            if (m->data.size() >= 2) n.data_state = ld_le16(m->data.data());
            notifications_.push_back(n);
            continue;
        }
        if (m->error) {
            r.error = m->error_code();
            if (!r.error) r.unexpected = true;
            return std::nullopt;
        }
        return m;
    }
}

SoeResult SoeClient::read(std::uint8_t drive, std::uint8_t elements, Idn idn, std::size_t max_size) {
    SoeResult r;
    r.transport_ok = true;
    SoeMessage q;
    q.op = SoeOpCode::ReadRequest;
    q.drive = drive;
    q.elements = elements;
    q.idn_or_fragments = idn.raw;
    std::uint8_t buf[kSoeHeaderSize];
    if (!mbx_.send(MailboxType::SoE, ConstBytes(buf, write_soe(buf, q)), mbx_.next_counter())) {
        r.transport_ok = false;
        return r;
    }
    for (;;) {
        auto m = answer(r);
        if (!m) return r;
        if (m->op != SoeOpCode::ReadResponse || m->drive != drive || m->elements != elements ||
            (!m->incomplete && m->idn() != idn)) {
            r.unexpected = true;
            return r;
        }
        const std::size_t n = std::min(m->data.size(), max_size - std::min(max_size, r.data.size()));
        r.data.insert(r.data.end(), m->data.begin(), m->data.begin() + static_cast<std::ptrdiff_t>(n));
        if (!m->incomplete) return r;
        ++r.fragments;
    }
}

SoeResult SoeClient::write(std::uint8_t drive, std::uint8_t elements, Idn idn, ConstBytes data) {
    SoeResult r;
    r.transport_ok = true;
    const std::size_t cap = soe_data_capacity(mbx_.mailbox_size_out());
    if (cap == 0) {
        r.transport_ok = false;
        return r;
    }
    std::vector<std::uint8_t> buf(kSoeHeaderSize + cap);
    std::size_t off = 0;
    do {
        const std::size_t remaining = data.size() - off;
        const std::size_t n = std::min(cap, remaining);
        const bool last = n == remaining;
        SoeMessage q;
        q.op = SoeOpCode::WriteRequest;
        q.drive = drive;
        q.elements = elements;
        q.incomplete = !last;
        // ETG.1000.6 5.6.3: the fragments still to come after this one; the last fragment names the IDN.
        q.idn_or_fragments = last ? idn.raw : static_cast<std::uint16_t>((remaining - n + cap - 1) / cap);
        q.data = data.subspan(off, n);
        if (!mbx_.send(MailboxType::SoE, ConstBytes(buf.data(), write_soe(buf, q)), mbx_.next_counter())) {
            r.transport_ok = false;
            return r;
        }
        if (!last) ++r.fragments;
        off += n;
    } while (off < data.size());
    auto m = answer(r);
    if (!m) return r;
    if (m->op != SoeOpCode::WriteResponse || m->drive != drive || m->idn() != idn) r.unexpected = true;
    return r;
}

std::optional<SoeNotification> SoeClient::notification(std::chrono::milliseconds t) {
    if (notifications_.empty()) {
        auto m = mbx_.receive(t);
        if (!m || m->header.type != static_cast<std::uint8_t>(MailboxType::SoE)) return std::nullopt;
        auto s = parse_soe(m->payload);
        if (!s || s->op != SoeOpCode::Notification) return std::nullopt;
        SoeNotification n;
        n.drive = s->drive;
        n.idn = s->idn();
        if (s->data.size() >= 2) n.data_state = ld_le16(s->data.data());
        return n;
    }
    SoeNotification n = notifications_.front();
    notifications_.erase(notifications_.begin());
    return n;
}

}  // namespace vecat::master
