#include "soe/soe_server.hpp"

#include <algorithm>

namespace vecat::soe {

using protocol::MailboxType;
using protocol::SoeMessage;
using protocol::SoeOpCode;
namespace el = protocol::soe_element;

void SoeServer::handle(const protocol::MailboxHeader&, ConstBytes payload, esc::MailboxReplySink& out) {
    const auto m = protocol::parse_soe(payload);
    if (!m) {
        end_read();
        end_write();
        // Not even an SoE header: the mailbox layer's answer (ETG.1000.4 Table 30), as for FoE.
        ++counters_.errors_sent;
        out.commit(MailboxType::Error,
                   protocol::make_mailbox_error(out.reply_buffer(), protocol::MailboxError::SizeTooShort));
        return;
    }
    switch (m->op) {
        case SoeOpCode::ReadRequest:
            end_write();
            read(*m, out);
            return;
        case SoeOpCode::WriteRequest:
            end_read();
            write(*m, out);
            return;
        default:
            // Responses, notifications and slave information go from the slave to the master: a master
            // sending one asks for a service the SoE server does not have (ETG.1000.4 Table 30, 0x0004).
            end_read();
            end_write();
            ++counters_.errors_sent;
            out.commit(MailboxType::Error,
                       protocol::make_mailbox_error(out.reply_buffer(),
                                                    protocol::MailboxError::ServiceNotSupported));
            return;
    }
}

void SoeServer::error(SoeOpCode response, const SoeMessage& m, SoeError e, esc::MailboxReplySink& out,
                      std::uint16_t idn) {
    ++counters_.errors_sent;
    const std::size_t n =
        protocol::write_soe_error(out.reply_buffer(), response, m.drive, m.elements, Idn{idn}, e);
    out.commit(MailboxType::SoE, n);
}

void SoeServer::read(const SoeMessage& m, esc::MailboxReplySink& out) {
    end_read();
    const std::uint16_t idn = m.idn_or_fragments;
    // A read request is one message: with the incomplete flag its IDN field holds no IDN.
    if (m.incomplete) return error(SoeOpCode::ReadResponse, m, SoeError::GeneralError, out, idn);
    if (m.drive >= device_.drives())
        return error(SoeOpCode::ReadResponse, m, SoeError::InvalidDriveNumber, out, idn);
    if (m.elements == 0) return error(SoeOpCode::ReadResponse, m, SoeError::NoElementAddressed, out, idn);
    IdnEntry* e = device_.table(m.drive).find(Idn{idn});
    if (!e) return error(SoeOpCode::ReadResponse, m, SoeError::NoIdn, out, idn);
    device_.refresh(m.drive, *e);
    scratch_.clear();
    if (const auto err = IdnTable::read(*e, m.elements, scratch_))
        return error(SoeOpCode::ReadResponse, m, *err, out, idn);
    ++counters_.reads;
    read_buf_.swap(scratch_);
    read_off_ = 0;
    read_drive_ = m.drive;
    read_elements_ = m.elements;
    read_idn_ = idn;
    send_fragment(out);  // the whole response, or its first fragment
}

void SoeServer::send_fragment(esc::MailboxReplySink& out) {
    const Bytes b = out.reply_buffer();
    const std::size_t cap = b.size() > protocol::kSoeHeaderSize ? b.size() - protocol::kSoeHeaderSize : 0;
    if (cap == 0) return end_read();
    const std::size_t remaining = read_buf_.size() - read_off_;
    const std::size_t n = std::min(cap, remaining);
    const bool last = n == remaining;
    SoeMessage r;
    r.op = SoeOpCode::ReadResponse;
    r.drive = read_drive_;
    r.elements = read_elements_;
    r.incomplete = !last;
    // ETG.1000.6 5.6.3: a fragment with the incomplete flag carries the number of fragments still to come
    // instead of the IDN; the last one carries the IDN.
    r.idn_or_fragments = last ? read_idn_ : static_cast<std::uint16_t>((remaining - n + cap - 1) / cap);
    r.data = ConstBytes(read_buf_.data() + read_off_, n);
    out.commit(MailboxType::SoE, protocol::write_soe(b, r));
    read_off_ += n;
    if (last) {
        std::vector<std::uint8_t>().swap(read_buf_);
        read_off_ = 0;
    } else {
        ++counters_.fragments_sent;
    }
}

void SoeServer::write(const SoeMessage& m, esc::MailboxReplySink& out) {
    auto append = [this](ConstBytes d) {
        const std::size_t room = kMaxTransfer - std::min(kMaxTransfer, write_buf_.size());
        if (d.size() > room) write_overflow_ = true;
        write_buf_.insert(write_buf_.end(), d.begin(),
                          d.begin() + static_cast<std::ptrdiff_t>(std::min(room, d.size())));
    };
    const bool continues = writing_ && m.drive == write_drive_ && m.elements == write_elements_;
    if (writing_ && !continues) end_write();  // another transfer: the one in progress is abandoned
    if (m.incomplete) {
        // A fragment (ETG.1000.6 5.6.3): held, not answered; its IDN field counts the fragments still to
        // come. The count is not checked: masters count it differently (SOEM sends the fragments including
        // this one, IgH those after it); the last fragment, without the flag, names the IDN.
        if (!writing_) {
            writing_ = true;
            write_overflow_ = false;
            write_drive_ = m.drive;
            write_elements_ = m.elements;
        }
        ++counters_.fragments_received;
        append(m.data);
        return;
    }
    ConstBytes data = m.data;
    if (writing_) {
        append(m.data);
        data = ConstBytes(write_buf_.data(), write_buf_.size());
    }
    const bool overflow = writing_ && write_overflow_;
    const std::uint16_t idn = m.idn_or_fragments;
    auto fail = [&](SoeError e) {
        end_write(false);
        error(SoeOpCode::WriteResponse, m, e, out, idn);
    };
    if (m.drive >= device_.drives()) return fail(SoeError::InvalidDriveNumber);
    if (m.elements == 0) return fail(SoeError::NoElementAddressed);
    IdnEntry* e = device_.table(m.drive).find(Idn{idn});
    if (!e) return fail(SoeError::NoIdn);
    auto err = IdnTable::check_write(*e, m.elements, data, device_.phase());
    if (overflow && (!err || *err == SoeError::DataTooShort)) err = SoeError::DataTooLong;
    if (!err) err = device_.write_value(m.drive, *e, IdnTable::value_of(*e, data));
    if (err) return fail(*err);
    ++counters_.writes;
    end_write(false);
    SoeMessage r;
    r.op = SoeOpCode::WriteResponse;
    r.drive = m.drive;
    r.elements = m.elements;
    r.idn_or_fragments = idn;
    out.commit(MailboxType::SoE, protocol::write_soe(out.reply_buffer(), r));
}

void SoeServer::poll(esc::MailboxReplySink& out) {
    // One message in the mailbox at a time: the next fragment when the master has read the last one.
    if (out.pending() != 0 || !out.can_commit()) return;
    if (fragments_pending()) return send_fragment(out);
    unsigned drive = 0;
    Idn idn;
    while (device_.take_notification(drive, idn)) {
        if (!notifications_) continue;
        const IdnEntry* e = drive < device_.drives() ? device_.table(drive).find(idn) : nullptr;
        if (!e) continue;
        // ETG.1000.6 5.6: the notification carries the IDN and its data state.
        std::uint8_t state[2];
        st_le16(state, e->data_state);
        SoeMessage n;
        n.op = SoeOpCode::Notification;
        n.drive = static_cast<std::uint8_t>(drive);
        n.elements = el::DataState;
        n.idn_or_fragments = idn.raw;
        n.data = ConstBytes(state, 2);
        out.commit(MailboxType::SoE, protocol::write_soe(out.reply_buffer(), n));
        ++counters_.notifications_sent;
        return;
    }
}

void SoeServer::end_read() {
    if (fragments_pending()) ++counters_.transfers_abandoned;
    std::vector<std::uint8_t>().swap(read_buf_);
    read_off_ = 0;
}

void SoeServer::end_write(bool abandoned) {
    if (abandoned && writing_) ++counters_.transfers_abandoned;
    writing_ = false;
    write_overflow_ = false;
    std::vector<std::uint8_t>().swap(write_buf_);
}

void SoeServer::reset() {
    end_read();
    end_write();
}

}  // namespace vecat::soe
