#include "master/coe_client.hpp"

#include <algorithm>
#include <thread>

#include "esc/registers.hpp"

namespace vecat::master {

using namespace coe;
using Clock = std::chrono::steady_clock;

CoeClient::CoeClient(Master& m, std::uint16_t station) : m_(m), station_(station) {
    for (auto& s : m_.slaves())
        if (s.station == station) counter_ = &s.mailbox_counter;
    std::uint8_t b[16] = {};
    if (auto w = m_.fprd(station_, esc::sm_addr(0), Bytes(b, 16)); w && *w == 1) {
        sm0_ = ld_le16(b);
        sm0_len_ = ld_le16(b + 2);
        sm1_ = ld_le16(b + 8);
        sm1_len_ = ld_le16(b + 10);
    }
}

std::uint8_t CoeClient::next_counter() {
    *counter_ = static_cast<std::uint8_t>(*counter_ % 7 + 1);
    return *counter_;
}

bool CoeClient::send(esc::MailboxType type, ConstBytes payload, std::uint8_t counter) {
    if (!sm0_len_ || payload.size() + esc::kMailboxHeaderSize > sm0_len_) return false;
    std::vector<std::uint8_t> buf(sm0_len_, 0);
    esc::MailboxHeader h;
    h.length = static_cast<std::uint16_t>(payload.size());
    h.type = static_cast<std::uint8_t>(type);
    h.counter = counter;
    esc::write_mailbox_header(Bytes(buf.data(), esc::kMailboxHeaderSize), h);
    std::copy(payload.begin(), payload.end(), buf.begin() + esc::kMailboxHeaderSize);
    // At least one try, however late this thread runs: a deadline that passed while the thread was not
    // scheduled (a loaded machine) must not fail a write that was never attempted.
    const auto deadline = Clock::now() + std::chrono::milliseconds(100);
    while (true) {
        auto w = m_.fpwr(station_, sm0_, Bytes(buf.data(), buf.size()));
        if (w && *w == 1) return true;  // WKC 0: SM0 still full, try again
        if (Clock::now() >= deadline) return false;
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
}

std::optional<MailboxMessage> CoeClient::receive(std::chrono::milliseconds timeout) {
    if (!sm1_len_) return std::nullopt;
    const auto deadline = Clock::now() + timeout;
    std::vector<std::uint8_t> buf(sm1_len_);
    do {
        std::uint8_t st = 0;
        auto w =
            m_.fprd(station_, static_cast<std::uint16_t>(esc::sm_addr(1) + esc::sm::Status), Bytes(&st, 1));
        if (w && *w == 1 && (st & esc::sm::StatusMailboxFull)) {
            auto r = m_.fprd(station_, sm1_, Bytes(buf.data(), buf.size()));
            if (r && *r == 1) {
                auto h = esc::parse_mailbox_header(ConstBytes(buf.data(), buf.size()));
                if (!h) return std::nullopt;
                MailboxMessage msg;
                msg.header = *h;
                const std::size_t n = std::min<std::size_t>(h->length, buf.size() - esc::kMailboxHeaderSize);
                msg.payload.assign(buf.begin() + esc::kMailboxHeaderSize,
                                   buf.begin() + static_cast<std::ptrdiff_t>(esc::kMailboxHeaderSize + n));
                return msg;
            }
        }
        std::this_thread::sleep_for(std::chrono::microseconds(100));
    } while (Clock::now() < deadline);
    return std::nullopt;
}

std::optional<MailboxMessage> CoeClient::request(esc::MailboxType type, ConstBytes payload,
                                                 std::chrono::milliseconds timeout) {
    if (!send(type, payload, next_counter())) return std::nullopt;
    const auto deadline = Clock::now() + timeout;
    while (true) {
        // receive() looks at least once, even with the deadline passed.
        const auto left = std::max(Clock::duration::zero(), deadline - Clock::now());
        auto msg = receive(std::chrono::duration_cast<std::chrono::milliseconds>(left));
        if (!msg) return std::nullopt;
        const bool coe = msg->header.type == static_cast<std::uint8_t>(esc::MailboxType::CoE);
        if (coe && msg->payload.size() >= 10 &&
            coe_service(ld_le16(msg->payload.data())) == CoeService::Emergency) {
            coe::Emergency e;
            e.error_code = ld_le16(msg->payload.data() + 2);
            e.error_register = msg->payload[4];
            std::copy_n(msg->payload.begin() + 5, 5, e.data.begin());
            emergencies_.push_back(e);
            if (Clock::now() >= deadline) return std::nullopt;
            continue;
        }
        return msg;
    }
}

namespace {

bool is_abort(const MailboxMessage& m) {
    return m.payload.size() >= 10 && m.payload[2] == sdo::AbortCommand;
}

std::vector<std::uint8_t> sdo_frame(std::uint8_t cmd, std::uint16_t index, std::uint8_t sub,
                                    std::uint32_t data = 0) {
    std::vector<std::uint8_t> p(10, 0);
    st_le16(p.data(), coe_header(CoeService::SdoRequest));
    p[2] = cmd;
    st_le16(p.data() + 3, index);
    p[5] = sub;
    st_le32(p.data() + 6, data);
    return p;
}

}  // namespace

SdoResult CoeClient::upload(std::uint16_t index, std::uint8_t sub, bool complete) {
    SdoResult res;
    auto req = sdo_frame(
        static_cast<std::uint8_t>((sdo::CcsInitiateUpload << 5) | (complete ? sdo::CompleteAccess : 0)),
        index, sub);
    auto rsp = request(esc::MailboxType::CoE, req);
    if (!rsp || rsp->payload.size() < 10) return res;
    res.transport_ok = true;
    if (is_abort(*rsp)) {
        res.abort = static_cast<SdoAbort>(ld_le32(rsp->payload.data() + 6));
        return res;
    }
    const std::uint8_t cmd = rsp->payload[2];
    res.command = cmd;
    if (cmd & sdo::Expedited) {
        const std::size_t n = (cmd & sdo::SizeIndicated) ? 4 - ((cmd >> 2) & 3) : 4;
        res.data.assign(rsp->payload.begin() + 6, rsp->payload.begin() + 6 + static_cast<std::ptrdiff_t>(n));
        return res;
    }
    const std::uint32_t total = ld_le32(rsp->payload.data() + 6);
    res.data.assign(rsp->payload.begin() + 10, rsp->payload.end());
    if (res.data.size() > total) res.data.resize(total);
    std::uint8_t toggle = 0;
    while (res.data.size() < total) {
        auto seg =
            request(esc::MailboxType::CoE,
                    sdo_frame(static_cast<std::uint8_t>((sdo::CcsUploadSegment << 5) | toggle), index, sub));
        if (!seg || seg->payload.size() < 10) {
            res.transport_ok = false;
            return res;
        }
        if (is_abort(*seg)) {
            res.abort = static_cast<SdoAbort>(ld_le32(seg->payload.data() + 6));
            return res;
        }
        const std::uint8_t c = seg->payload[2];
        std::size_t n = seg->payload.size() - 3;
        if (seg->payload.size() == 10) n = 7 - ((c >> 1) & 7);
        res.data.insert(res.data.end(), seg->payload.begin() + 3,
                        seg->payload.begin() + 3 + static_cast<std::ptrdiff_t>(n));
        toggle ^= sdo::Toggle;
        if (c & sdo::LastSegment) break;
    }
    if (res.data.size() != total) res.abort = SdoAbort::GeneralError;
    return res;
}

SdoResult CoeClient::download(std::uint16_t index, std::uint8_t sub, ConstBytes data, bool complete,
                              Transfer how) {
    SdoResult res;
    const std::uint8_t ca = complete ? sdo::CompleteAccess : 0;
    if (how == Transfer::Auto)
        how = data.size() <= 4 && !data.empty() ? Transfer::Expedited : Transfer::Normal;
    auto finish = [&](const std::optional<MailboxMessage>& rsp) {
        if (!rsp || rsp->payload.size() < 10) return false;
        res.transport_ok = true;
        res.command = rsp->payload[2];
        if (is_abort(*rsp)) {
            res.abort = static_cast<SdoAbort>(ld_le32(rsp->payload.data() + 6));
            return false;
        }
        return true;
    };
    if (how == Transfer::Expedited) {
        std::uint32_t v = 0;
        for (std::size_t i = 0; i < data.size() && i < 4; ++i)
            v |= static_cast<std::uint32_t>(data[i]) << (8 * i);
        const auto cmd =
            static_cast<std::uint8_t>((sdo::CcsInitiateDownload << 5) | ca | ((4 - data.size()) << 2) |
                                      sdo::Expedited | sdo::SizeIndicated);
        finish(request(esc::MailboxType::CoE, sdo_frame(cmd, index, sub, v)));
        return res;
    }
    // Normal: as much as fits in the first message; the rest in segments (forced with Transfer::Segmented).
    const std::size_t max_first = sm0_len_ - esc::kMailboxHeaderSize - 10;
    std::size_t first = std::min(data.size(), max_first);
    if (how == Transfer::Segmented) first = 0;
    auto req = sdo_frame(static_cast<std::uint8_t>((sdo::CcsInitiateDownload << 5) | ca | sdo::SizeIndicated),
                         index, sub, static_cast<std::uint32_t>(data.size()));
    req.insert(req.end(), data.begin(), data.begin() + static_cast<std::ptrdiff_t>(first));
    if (!finish(request(esc::MailboxType::CoE, req))) return res;
    std::size_t off = first;
    std::uint8_t toggle = 0;
    const std::size_t max_seg = sm0_len_ - esc::kMailboxHeaderSize - 3;
    while (off < data.size()) {
        const std::size_t n = std::min(max_seg, data.size() - off);
        const bool last = off + n == data.size();
        std::vector<std::uint8_t> seg(3, 0);
        st_le16(seg.data(), coe_header(CoeService::SdoRequest));
        std::uint8_t cmd =
            static_cast<std::uint8_t>((sdo::CcsDownloadSegment << 5) | toggle | (last ? 1 : 0));
        seg.insert(seg.end(), data.begin() + static_cast<std::ptrdiff_t>(off),
                   data.begin() + static_cast<std::ptrdiff_t>(off + n));
        if (n < 7) {
            cmd = static_cast<std::uint8_t>(cmd | ((7 - n) << 1));
            seg.resize(10, 0);
        }
        seg[2] = cmd;
        if (!finish(request(esc::MailboxType::CoE, seg))) return res;
        off += n;
        toggle ^= sdo::Toggle;
    }
    return res;
}

std::optional<std::vector<std::uint16_t>> CoeClient::od_list(std::uint16_t list_type) {
    std::uint8_t arg[2];
    st_le16(arg, list_type);
    last_fragments_ = 0;
    auto rsp = info_request(sdo_info::GetOdListRequest, arg, 6);
    std::vector<std::uint8_t> data;
    // Fragments follow while the incomplete bit is set; only the first carries the list type.
    while (rsp && rsp->payload.size() >= 6 && (rsp->payload[2] & 0x7F) == sdo_info::GetOdListResponse) {
        ++last_fragments_;
        data.insert(data.end(), rsp->payload.begin() + 6, rsp->payload.end());
        if (!(rsp->payload[2] & sdo_info::Incomplete)) break;
        rsp = receive();
    }
    if (!rsp) return std::nullopt;
    if (data.size() < 2) return std::nullopt;
    std::vector<std::uint16_t> out;
    for (std::size_t i = 2; i + 1 < data.size(); i += 2)
        out.push_back(ld_le16(data.data() + i));
    return out;
}

// Sends an SDO information request (opcode + arguments) and returns the response of the next opcode, at
// least min_len bytes long. An SDO info error sets last_abort().
std::optional<MailboxMessage> CoeClient::info_request(std::uint8_t opcode, ConstBytes args,
                                                      std::size_t min_len) {
    std::vector<std::uint8_t> req(6, 0);
    st_le16(req.data(), coe_header(CoeService::SdoInformation));
    req[2] = opcode;
    req.insert(req.end(), args.begin(), args.end());
    last_abort_ = SdoAbort::None;
    auto rsp = request(esc::MailboxType::CoE, req);
    if (!rsp || rsp->payload.size() < 6) return std::nullopt;
    const std::uint8_t op = rsp->payload[2] & 0x7F;
    if (op == sdo_info::InfoErrorRequest) {
        last_abort_ = rsp->payload.size() >= 10 ? static_cast<SdoAbort>(ld_le32(rsp->payload.data() + 6))
                                                : SdoAbort::GeneralError;
        return std::nullopt;
    }
    if (op != opcode + 1 || rsp->payload.size() < min_len) return std::nullopt;
    return rsp;
}

std::optional<ObjectInfo> CoeClient::object_description(std::uint16_t index) {
    std::uint8_t arg[2];
    st_le16(arg, index);
    auto rsp = info_request(sdo_info::GetObjectDescriptionRequest, arg, 12);
    if (!rsp) return std::nullopt;
    ObjectInfo o;
    o.index = ld_le16(rsp->payload.data() + 6);
    o.data_type = ld_le16(rsp->payload.data() + 8);
    o.max_subindex = rsp->payload[10];
    o.object_code = rsp->payload[11];
    o.name.assign(rsp->payload.begin() + 12, rsp->payload.end());
    return o;
}

std::optional<EntryInfo> CoeClient::entry_description(std::uint16_t index, std::uint8_t sub,
                                                      std::uint8_t value_info) {
    std::uint8_t arg[4] = {0, 0, sub, value_info};
    st_le16(arg, index);
    auto rsp = info_request(sdo_info::GetEntryDescriptionRequest, arg, 16);
    if (!rsp) return std::nullopt;
    EntryInfo e;
    const auto& p = rsp->payload;
    e.index = ld_le16(p.data() + 6);
    e.subindex = p[8];
    e.value_info = p[9];
    e.data_type = ld_le16(p.data() + 10);
    e.bit_length = ld_le16(p.data() + 12);
    e.access = ld_le16(p.data() + 14);
    std::size_t off = 16;
    const std::size_t vbytes = (e.bit_length + 7u) / 8u;
    for (std::uint8_t bit : {sdo_info::ValueDefault, sdo_info::ValueMinimum, sdo_info::ValueMaximum}) {
        if (!(e.value_info & bit)) continue;
        if (off + vbytes > p.size()) return std::nullopt;
        e.values.insert(e.values.end(), p.begin() + static_cast<std::ptrdiff_t>(off),
                        p.begin() + static_cast<std::ptrdiff_t>(off + vbytes));
        off += vbytes;
    }
    e.name.assign(p.begin() + static_cast<std::ptrdiff_t>(off), p.end());
    return e;
}

}  // namespace vecat::master
