#include "coe/sdo_server.hpp"

#include <algorithm>

namespace vecat::coe {

using protocol::coe_header;
using protocol::coe_service;
using protocol::CoeService;
using protocol::Emergency;
using protocol::kCoeHeaderSize;
using protocol::kSdoHeaderSize;
using protocol::kSdoInfoHeaderSize;
using protocol::MailboxError;
using protocol::MailboxType;
using protocol::SdoHeader;
using protocol::SdoInfoEntry;
using protocol::SdoInfoHeader;
using protocol::SdoInfoObject;
namespace sdo = protocol::sdo;
namespace sdo_info = protocol::sdo_info;

namespace {

using esc::MailboxReplySink;

// Writes the fields of a reply payload into the sink's buffer; every write is bounds-checked.
class Reply : public LeWriter<SpanSink> {
  public:
    explicit Reply(Bytes b) : LeWriter<SpanSink>(sink_), sink_(b) {}
    void zeros(std::size_t k) { fill(k, 0); }
    std::size_t size() const { return sink_.size(); }
    bool fits() const { return sink_.fits(); }
    std::size_t room() const { return sink_.room(); }

  private:
    SpanSink sink_;
};

void mailbox_error(MailboxError e, MailboxReplySink& out) {
    const std::size_t n = protocol::make_mailbox_error(out.reply_buffer(), e);
    out.commit(MailboxType::Error, n);
}

bool in_list(const Object& o, std::uint16_t list_type) {
    switch (list_type) {
        case sdo_info::ListAll:
            return true;
        case sdo_info::ListRxPdoMappable:
            return std::any_of(o.entries().begin(), o.entries().end(),
                               [](const Entry& e) { return e.rx_mappable(); });
        case sdo_info::ListTxPdoMappable:
            return std::any_of(o.entries().begin(), o.entries().end(),
                               [](const Entry& e) { return e.tx_mappable(); });
        case sdo_info::ListBackup:
            return std::any_of(o.entries().begin(), o.entries().end(),
                               [](const Entry& e) { return e.access() & device::access::Backup; });
        case sdo_info::ListSettings:
            return std::any_of(o.entries().begin(), o.entries().end(),
                               [](const Entry& e) { return e.access() & device::access::Settings; });
        default:
            return false;
    }
}

// The natural minimum/maximum of an integer type, little-endian, for entries without a declared range.
void type_limit(const Entry& e, bool max, Reply& r) {
    const std::size_t n = (e.bit_length() + 7) / 8;
    const bool sig = device::is_signed(e.type());
    for (std::size_t i = 0; i < n; ++i) {
        std::uint8_t b = max ? 0xFF : 0x00;
        if (sig && i + 1 == n) b = max ? 0x7F : 0x80;
        if (device::is_real(e.type())) b = 0;
        if (e.type() == DataType::Boolean) b = max ? 0x01 : 0x00;
        r.u8(b);
    }
}

// The CoE header of an SDO information message and the SDO information header.
void info_header(Reply& r, const SdoInfoHeader& h) {
    r.u16(coe_header(CoeService::SdoInformation));
    std::uint8_t b[SdoInfoHeader::kSize];
    h.pack(b);
    r.bytes(b);
}

void value_field(const std::vector<std::uint8_t>& v, const Entry& e, Reply& r) {
    const std::size_t n = (e.bit_length() + 7) / 8;
    for (std::size_t i = 0; i < n; ++i)
        r.u8(i < v.size() ? v[i] : 0);
}

}  // namespace

SdoServer::SdoServer(ObjectDictionary& od, std::function<AlState()> state)
    : od_(od), state_(std::move(state)) {
    buf_.resize(std::max<std::size_t>(od_.max_transfer_size(), 64));
    info_buf_.resize(std::max<std::size_t>(16, 2 + 2 * od_.objects().size()));
}

void SdoServer::reset() {
    set_transfer(Idle{});
    emcy_head_ = emcy_count_ = 0;
}

std::uint64_t SdoServer::next_deadline_ns() const {
    if (std::holds_alternative<Idle>(transfer_)) return ~std::uint64_t{0};
    if (quiet_since_ns_ == kNotYet) return 0;
    return quiet_since_ns_ + kSdoTimeoutNs;
}

void SdoServer::tick(std::uint64_t now_ns) {
    if (std::holds_alternative<Idle>(transfer_)) return;
    if (quiet_since_ns_ == kNotYet) {
        quiet_since_ns_ = now_ns;
        return;
    }
    if (now_ns - quiet_since_ns_ < kSdoTimeoutNs) return;
    // Dropped; the master hears of it with its next segment request (see segment_acceptable).
    if (const auto* u = std::get_if<Upload>(&transfer_))
        set_transfer(TimedOut{u->index, u->sub});
    else if (const auto* d = std::get_if<Download>(&transfer_))
        set_transfer(TimedOut{d->index, d->sub});
    else
        set_transfer(Idle{});
}

bool SdoServer::emergency(const Emergency& e) {
    if (emcy_count_ >= kEmergencySlots) {
        ++counters_.emergencies_dropped;
        return false;
    }
    emcy_[(emcy_head_ + emcy_count_) % kEmergencySlots] = e;
    ++emcy_count_;
    return true;
}

void SdoServer::poll(MailboxReplySink& out) {
    while (std::holds_alternative<InfoResponse>(transfer_) && out.can_commit())
        if (!send_info_fragment(out)) break;
    // Emergencies go out when nothing else is waiting, so they never sit between a request and its reply.
    while (emcy_count_ > 0 && !std::holds_alternative<InfoResponse>(transfer_) && out.pending() == 0 &&
           out.can_commit()) {
        std::uint8_t msg[Emergency::kSize];
        emcy_[emcy_head_].pack(msg);
        Reply r(out.reply_buffer());
        r.u16(coe_header(CoeService::Emergency));
        r.bytes(msg);
        if (!r.fits()) break;
        out.commit(MailboxType::CoE, r.size());
        emcy_head_ = (emcy_head_ + 1) % kEmergencySlots;
        --emcy_count_;
        ++counters_.emergencies_sent;
    }
}

void SdoServer::handle(const protocol::MailboxHeader&, ConstBytes p, MailboxReplySink& out) {
    if (p.size() < kCoeHeaderSize) {
        mailbox_error(MailboxError::SizeTooShort, out);
        return;
    }
    switch (coe_service(ld_le16(p.data()))) {
        case CoeService::SdoRequest:
            sdo_request(p, out);
            return;
        case CoeService::SdoInformation:
            if (!info_served_) {
                mailbox_error(MailboxError::ServiceNotSupported, out);
                return;
            }
            sdo_info(p, out);
            return;
        default:
            // Emergencies, SDO responses and PDOs over the mailbox are not served by this slave.
            mailbox_error(MailboxError::ServiceNotSupported, out);
            return;
    }
}

// ---------------------------------------------------------------------------------------------------------
// SDO

void SdoServer::abort(std::uint16_t index, std::uint8_t sub, SdoAbort code, MailboxReplySink& out) {
    Reply r(out.reply_buffer());
    r.u16(coe_header(CoeService::SdoRequest));  // an abort travels as an SDO request (ETG.1000.6 5.6.2.7)
    r.u8(sdo::AbortCommand);
    r.u16(index);
    r.u8(sub);
    r.u32(static_cast<std::uint32_t>(code));
    out.commit(MailboxType::CoE, r.size());
    ++counters_.sdo_aborts_sent;
}

void SdoServer::sdo_request(ConstBytes p, MailboxReplySink& out) {
    if (p.size() < kCoeHeaderSize + kSdoHeaderSize) {
        mailbox_error(MailboxError::SizeTooShort, out);
        return;
    }
    const SdoHeader h = SdoHeader::unpack(p.subspan<kCoeHeaderSize, kSdoHeaderSize>());
    // A segmented SDO transfer ends with an abort of either side.
    const auto end_segmented = [&] {
        if (!std::holds_alternative<InfoResponse>(transfer_)) set_transfer(Idle{});
    };
    switch (sdo::ccs(h.command)) {
        case sdo::CcsInitiateDownload:
            initiate_download(h, p, out);
            return;
        case sdo::CcsDownloadSegment:
            download_segment(h.command, p, out);
            return;
        case sdo::CcsInitiateUpload:
            initiate_upload(h, out);
            return;
        case sdo::CcsUploadSegment:
            upload_segment(h.command, out);
            return;
        case sdo::CcsAbort:
            // The master aborts a transfer: no answer (CiA 301 7.2.4.3.17).
            ++counters_.sdo_aborts_received;
            end_segmented();
            return;
        default:
            end_segmented();
            abort(h.index, h.subindex, SdoAbort::UnknownCommand, out);
            return;
    }
}

void SdoServer::initiate_download(const SdoHeader& h, ConstBytes p, MailboxReplySink& out) {
    set_transfer(Idle{});
    const std::uint16_t index = h.index;
    const std::uint8_t sub = h.subindex;
    const bool complete = h.command & sdo::CompleteAccess;
    const AlState st = state_();
    auto respond = [&] {
        Reply r(out.reply_buffer());
        r.u16(coe_header(CoeService::SdoResponse));
        std::uint8_t rsp[kSdoHeaderSize];
        SdoHeader{sdo::command(sdo::ScsInitiateDownload, complete ? sdo::CompleteAccess : 0), index, sub,
                  download_echo_ ? h.data : 0}
            .pack(rsp);
        r.bytes(rsp);
        out.commit(MailboxType::CoE, r.size());
    };
    if (complete && (sub > 1 || !complete_access_served_)) {
        abort(index, sub, SdoAbort::UnsupportedAccess, out);
        return;
    }
    // The whole value is here: write it, answer with the response or the abort.
    auto store = [&](ConstBytes data) {
        if (const SdoAbort a = od_.download(index, sub, complete, st, data); a != SdoAbort::None) {
            abort(index, sub, a, out);
            return;
        }
        ++counters_.sdo_downloads;
        respond();
    };
    constexpr std::size_t kData = kCoeHeaderSize + 4;  // the data field of the SDO header
    if (h.command & sdo::Expedited) {
        std::size_t n = sdo::expedited_length(h.command);
        if (!(h.command & sdo::SizeIndicated) && !complete) {
            // Size not indicated: the entry's own size, if it fits in four bytes.
            if (const Entry* e = od_.find(index, sub); e && e->capacity() <= 4) n = e->capacity();
        }
        store(p.subspan(kData, n));
        return;
    }
    // Normal transfer: the complete size in the data field, the first data after the SDO header.
    const std::uint32_t total = h.data;
    const ConstBytes first = p.subspan(kCoeHeaderSize + kSdoHeaderSize);
    // Refuse early what cannot succeed, so that no segment is accepted for it.
    if (const SdoAbort a = od_.check_download_start(index, sub, complete, st, total); a != SdoAbort::None) {
        abort(index, sub, a, out);
        return;
    }
    if (total > buf_.size()) {
        abort(index, sub, SdoAbort::LengthTooHigh, out);
        return;
    }
    if (first.size() >= total) {
        store(first.first(total));
        return;
    }
    std::copy(first.begin(), first.end(), buf_.begin());
    set_transfer(Download{complete, index, sub, total, first.size(), 0});
    respond();
}

// A segment request needs its transfer open (else 0x05040001, or 0x05040000 when the transfer timed out) and
// the alternating toggle bit (else the transfer ends with 0x05030000). The transfer, or nullptr after an
// abort.
template <class T>
T* SdoServer::segment_acceptable(std::uint8_t cmd, MailboxReplySink& out) {
    if (const auto* late = std::get_if<TimedOut>(&transfer_)) {
        const TimedOut t = *late;
        set_transfer(Idle{});
        abort(t.index, t.sub, SdoAbort::Timeout, out);
        return nullptr;
    }
    T* t = std::get_if<T>(&transfer_);
    if (!t) {
        abort(0, 0, SdoAbort::UnknownCommand, out);
        return nullptr;
    }
    if ((cmd & sdo::Toggle) != t->toggle) {
        const std::uint16_t index = t->index;
        const std::uint8_t sub = t->sub;
        set_transfer(Idle{});
        abort(index, sub, SdoAbort::ToggleBit, out);
        return nullptr;
    }
    quiet_since_ns_ = kNotYet;  // the transfer moves on
    return t;
}

void SdoServer::download_segment(std::uint8_t cmd, ConstBytes p, MailboxReplySink& out) {
    Download* d = segment_acceptable<Download>(cmd, out);
    if (!d) return;
    const std::uint8_t toggle = cmd & sdo::Toggle;
    // Segment data follows the command byte; with a 10-byte mailbox the size field gives the unused bytes.
    constexpr std::size_t kData = kCoeHeaderSize + sdo::kSegmentHeaderSize;
    std::size_t n = p.size() - kData;
    if (p.size() == kCoeHeaderSize + kSdoHeaderSize) n = sdo::segment_length(cmd);
    if (d->received + n > d->total) {
        const Download gone = *d;
        set_transfer(Idle{});
        abort(gone.index, gone.sub, SdoAbort::LengthTooHigh, out);
        return;
    }
    std::copy_n(p.begin() + kData, n, buf_.begin() + static_cast<std::ptrdiff_t>(d->received));
    d->received += n;
    if (cmd & sdo::LastSegment) {
        const Download done = *d;
        set_transfer(Idle{});
        if (done.received < done.total) {
            abort(done.index, done.sub, SdoAbort::LengthTooLow, out);
            return;
        }
        const SdoAbort a = od_.download(done.index, done.sub, done.complete, state_(),
                                        ConstBytes(buf_.data(), done.received));
        if (a != SdoAbort::None) {
            abort(done.index, done.sub, a, out);
            return;
        }
        ++counters_.sdo_downloads;
    } else {
        d->toggle ^= sdo::Toggle;
    }
    Reply r(out.reply_buffer());
    r.u16(coe_header(CoeService::SdoResponse));
    r.u8(sdo::command(sdo::ScsDownloadSegment, toggle));
    r.zeros(sdo::kSegmentMin);
    out.commit(MailboxType::CoE, r.size());
}

void SdoServer::initiate_upload(const SdoHeader& h, MailboxReplySink& out) {
    set_transfer(Idle{});
    const std::uint16_t index = h.index;
    const std::uint8_t sub = h.subindex;
    const bool complete = h.command & sdo::CompleteAccess;
    if (complete && !complete_access_served_) {
        abort(index, sub, SdoAbort::UnsupportedAccess, out);
        return;
    }
    std::size_t len = 0;
    const SdoAbort a = od_.upload(index, sub, complete, state_(), Bytes(buf_.data(), buf_.size()), len);
    if (a != SdoAbort::None) {
        abort(index, sub, a, out);
        return;
    }
    ++counters_.sdo_uploads;
    const std::uint8_t ca = complete ? sdo::CompleteAccess : 0;
    Reply r(out.reply_buffer());
    r.u16(coe_header(CoeService::SdoResponse));
    if (len >= 1 && len <= sdo::kExpeditedMax) {
        r.u8(sdo::command(sdo::ScsInitiateUpload, ca | sdo::expedited_size(len)));
        r.u16(index);
        r.u8(sub);
        r.bytes(ConstBytes(buf_.data(), len));
        r.zeros(sdo::kExpeditedMax - len);
        out.commit(MailboxType::CoE, r.size());
        return;
    }
    r.u8(sdo::command(sdo::ScsInitiateUpload, ca | sdo::SizeIndicated));
    r.u16(index);
    r.u8(sub);
    r.u32(static_cast<std::uint32_t>(len));
    const std::size_t first = std::min(len, r.room());
    r.bytes(ConstBytes(buf_.data(), first));
    out.commit(MailboxType::CoE, r.size());
    if (first < len) set_transfer(Upload{index, sub, len, first, 0});
}

void SdoServer::upload_segment(std::uint8_t cmd, MailboxReplySink& out) {
    Upload* u = segment_acceptable<Upload>(cmd, out);
    if (!u) return;
    const std::uint8_t toggle = cmd & sdo::Toggle;
    Reply r(out.reply_buffer());
    r.u16(coe_header(CoeService::SdoResponse));
    const std::size_t room = r.room() > sdo::kSegmentHeaderSize ? r.room() - sdo::kSegmentHeaderSize : 0;
    const std::size_t n = std::min(u->total - u->offset, room);
    const bool last = u->offset + n == u->total;
    r.u8(
        sdo::command(sdo::ScsUploadSegment, toggle | sdo::segment_unused(n) | (last ? sdo::LastSegment : 0)));
    r.bytes(ConstBytes(buf_.data() + u->offset, n));
    r.zeros(n < sdo::kSegmentMin ? sdo::kSegmentMin - n : 0);  // a segment carries at least 7 bytes
    out.commit(MailboxType::CoE, r.size());
    u->offset += n;
    u->toggle ^= sdo::Toggle;
    if (last) set_transfer(Idle{});
}

// ---------------------------------------------------------------------------------------------------------
// SDO information

void SdoServer::info_error(SdoAbort code, MailboxReplySink& out) {
    Reply r(out.reply_buffer());
    info_header(r, {sdo_info::InfoErrorRequest});
    r.u32(static_cast<std::uint32_t>(code));
    out.commit(MailboxType::CoE, r.size());
    ++counters_.sdo_aborts_sent;
}

void SdoServer::sdo_info(ConstBytes p, MailboxReplySink& out) {
    ++counters_.info_requests;
    if (p.size() < kCoeHeaderSize + kSdoInfoHeaderSize) {
        mailbox_error(MailboxError::SizeTooShort, out);
        return;
    }
    // A new request ends a fragmented response in progress.
    if (std::holds_alternative<InfoResponse>(transfer_)) set_transfer(Idle{});
    const std::uint8_t opcode = SdoInfoHeader::unpack(p.subspan<kCoeHeaderSize, kSdoInfoHeaderSize>()).opcode;
    const ConstBytes d = p.subspan(kCoeHeaderSize + kSdoInfoHeaderSize);
    switch (opcode) {
        case sdo_info::GetOdListRequest:
            if (d.size() < 2) break;
            od_list(ld_le16(d.data()), out);
            return;
        case sdo_info::GetObjectDescriptionRequest:
            if (d.size() < 2) break;
            object_description(ld_le16(d.data()), out);
            return;
        case sdo_info::GetEntryDescriptionRequest:
            if (d.size() < 4) break;
            entry_description(ld_le16(d.data()), d[2], d[3], out);
            return;
        default:
            info_error(SdoAbort::UnknownCommand, out);
            return;
    }
    mailbox_error(MailboxError::SizeTooShort, out);
}

void SdoServer::od_list(std::uint16_t list_type, MailboxReplySink& out) {
    std::size_t n = 0;
    auto put16 = [&](std::uint16_t v) {
        if (n + 2 <= info_buf_.size()) st_le16(info_buf_.data() + n, v);
        n += 2;
    };
    put16(list_type);
    if (list_type == sdo_info::ListLengths) {
        for (std::uint16_t t = sdo_info::ListAll; t <= sdo_info::ListSettings; ++t) {
            std::uint16_t count = 0;
            for (const auto& o : od_.objects())
                if (in_list(o, t)) ++count;
            put16(count);
        }
    } else if (list_type <= sdo_info::ListSettings) {
        for (const auto& o : od_.objects())
            if (in_list(o, list_type)) put16(o.index());
    } else {
        info_error(SdoAbort::UnsupportedAccess, out);
        return;
    }
    const std::size_t per_fragment = out.max_payload() - kCoeHeaderSize - kSdoInfoHeaderSize;
    const std::size_t total = std::min(n, info_buf_.size());
    set_transfer(InfoResponse{sdo_info::GetOdListResponse, total, 0,
                              static_cast<std::uint16_t>((total + per_fragment - 1) / per_fragment - 1)});
    send_info_fragment(out);
    poll(out);  // further fragments as far as the reply queue takes them
}

bool SdoServer::send_info_fragment(MailboxReplySink& out) {
    auto* info = std::get_if<InfoResponse>(&transfer_);
    if (!info || !out.can_commit()) return false;
    Reply r(out.reply_buffer());
    const std::size_t per_fragment = r.room() - kCoeHeaderSize - kSdoInfoHeaderSize;
    const std::size_t n = std::min(per_fragment, info->total - info->offset);
    const bool more = info->offset + n < info->total;
    info_header(r, {info->opcode, more, info->fragments_left});
    r.bytes(ConstBytes(info_buf_.data() + info->offset, n));
    out.commit(MailboxType::CoE, r.size());
    info->offset += n;
    if (info->fragments_left > 0) --info->fragments_left;
    quiet_since_ns_ = kNotYet;  // the master read the previous fragment
    if (!more) set_transfer(Idle{});
    return true;
}

void SdoServer::object_description(std::uint16_t index, MailboxReplySink& out) {
    const Object* o = od_.find(index);
    if (!o) {
        info_error(SdoAbort::ObjectDoesNotExist, out);
        return;
    }
    Reply r(out.reply_buffer());
    info_header(r, {sdo_info::GetObjectDescriptionResponse});
    std::uint8_t fixed[SdoInfoObject::kSize];
    SdoInfoObject{index, static_cast<std::uint16_t>(o->type()), o->max_subindex(),
                  static_cast<std::uint8_t>(o->code())}
        .pack(fixed);
    r.bytes(fixed);
    const auto& name = o->name();
    const std::size_t k = std::min(name.size(), r.room());
    r.bytes(ConstBytes(reinterpret_cast<const std::uint8_t*>(name.data()), k));
    out.commit(MailboxType::CoE, r.size());
}

void SdoServer::entry_description(std::uint16_t index, std::uint8_t sub, std::uint8_t value_info,
                                  MailboxReplySink& out) {
    Object* o = od_.find(index);
    if (!o) {
        info_error(SdoAbort::ObjectDoesNotExist, out);
        return;
    }
    const Entry* e = o->entry(sub);
    if (!e) {
        info_error(SdoAbort::SubindexDoesNotExist, out);
        return;
    }
    // Units are not modelled: the unit type bit is cleared in the answer, so no field is expected for it.
    const auto vi = static_cast<std::uint8_t>(value_info & ~sdo_info::ValueUnitType);
    Reply r(out.reply_buffer());
    info_header(r, {sdo_info::GetEntryDescriptionResponse});
    std::uint8_t fixed[SdoInfoEntry::kSize];
    SdoInfoEntry{index,
                 sub,
                 vi,
                 static_cast<std::uint16_t>(e->type()),
                 static_cast<std::uint16_t>(e->bit_length()),
                 e->access()}
        .pack(fixed);
    r.bytes(fixed);
    const auto& d = e->desc();
    if (vi & sdo_info::ValueDefault) value_field(d.default_value, *e, r);
    if (vi & sdo_info::ValueMinimum) {
        if (d.minimum.empty())
            type_limit(*e, false, r);
        else
            value_field(d.minimum, *e, r);
    }
    if (vi & sdo_info::ValueMaximum) {
        if (d.maximum.empty())
            type_limit(*e, true, r);
        else
            value_field(d.maximum, *e, r);
    }
    if (!r.fits()) {
        info_error(SdoAbort::ObjectTooLongForMailbox, out);
        return;
    }
    const std::size_t k = std::min(d.name.size(), r.room());
    r.bytes(ConstBytes(reinterpret_cast<const std::uint8_t*>(d.name.data()), k));
    out.commit(MailboxType::CoE, r.size());
}

}  // namespace vecat::coe
