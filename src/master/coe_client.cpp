#include "master/coe_client.hpp"

#include <algorithm>
#include <thread>

#include "protocol/registers.hpp"
#include "protocol/sync_manager.hpp"

namespace vecat::master {

using namespace protocol;
using Clock = std::chrono::steady_clock;

CoeClient::CoeClient(Master& m, std::uint16_t station) : m_(m), station_(station) {
    for (auto& s : m_.slaves())
        if (s.station == station) counter_ = &s.mailbox_counter;
    // SM0 (master to slave) and SM1 (slave to master) as configured, in one read.
    std::uint8_t b[2 * SmConfig::kSize] = {};
    if (auto w = m_.fprd(station_, sm_addr(0), Bytes(b, sizeof b)); w && *w == 1) {
        const auto sm0 = SmConfig::unpack(std::span(b).first<SmConfig::kSize>());
        const auto sm1 = SmConfig::unpack(std::span(b).last<SmConfig::kSize>());
        sm0_ = sm0.physical_start;
        sm0_len_ = sm0.length;
        sm1_ = sm1.physical_start;
        sm1_len_ = sm1.length;
    }
}

std::uint8_t CoeClient::next_counter() {
    *counter_ = static_cast<std::uint8_t>(*counter_ % 7 + 1);
    return *counter_;
}

bool CoeClient::repeat(std::chrono::milliseconds timeout) {
    const auto at = static_cast<std::uint16_t>(sm_addr(1) + sm::Activate);  // activate, PDI control
    std::uint8_t b[2] = {};
    if (auto w = m_.fprd(station_, at, Bytes(b, 2)); !w || *w != 1) return false;
    const std::uint8_t activate = b[0] ^ sm::ActRepeatRequest;
    if (!m_.write8(station_, at, activate)) return false;
    const bool want = (activate & sm::ActRepeatRequest) != 0;
    const auto deadline = Clock::now() + timeout;
    do {
        if (auto w = m_.fprd(station_, at, Bytes(b, 2));
            w && *w == 1 && ((b[1] & sm::PdiRepeatAck) != 0) == want)
            return true;
        std::this_thread::sleep_for(std::chrono::microseconds(100));
    } while (Clock::now() < deadline);
    return false;
}

bool CoeClient::send(MailboxType type, ConstBytes payload, std::uint8_t counter) {
    if (!sm0_len_ || payload.size() + kMailboxHeaderSize > sm0_len_) return false;
    std::vector<std::uint8_t> buf(sm0_len_, 0);
    MailboxHeader h;
    h.length = static_cast<std::uint16_t>(payload.size());
    h.type = static_cast<std::uint8_t>(type);
    h.counter = counter;
    write_mailbox_header(Bytes(buf.data(), kMailboxHeaderSize), h);
    std::copy(payload.begin(), payload.end(), buf.begin() + kMailboxHeaderSize);
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
        auto w = m_.fprd(station_, static_cast<std::uint16_t>(sm_addr(1) + sm::Status), Bytes(&st, 1));
        if (w && *w == 1 && (st & sm::StatusMailboxFull)) {
            auto r = m_.fprd(station_, sm1_, Bytes(buf.data(), buf.size()));
            if (r && *r == 1) {
                auto h = parse_mailbox_header(ConstBytes(buf.data(), buf.size()));
                if (!h) return std::nullopt;
                MailboxMessage msg;
                msg.header = *h;
                const std::size_t n = std::min<std::size_t>(h->length, buf.size() - kMailboxHeaderSize);
                msg.payload.assign(buf.begin() + kMailboxHeaderSize,
                                   buf.begin() + static_cast<std::ptrdiff_t>(kMailboxHeaderSize + n));
                return msg;
            }
        }
        std::this_thread::sleep_for(std::chrono::microseconds(100));
    } while (Clock::now() < deadline);
    return std::nullopt;
}

std::optional<MailboxMessage> CoeClient::request(MailboxType type, ConstBytes payload,
                                                 std::chrono::milliseconds timeout) {
    if (!send(type, payload, next_counter())) return std::nullopt;
    const auto deadline = Clock::now() + timeout;
    while (true) {
        // receive() looks at least once, even with the deadline passed.
        const auto left = std::max(Clock::duration::zero(), deadline - Clock::now());
        auto msg = receive(std::chrono::duration_cast<std::chrono::milliseconds>(left));
        if (!msg) return std::nullopt;
        const bool coe = msg->header.type == static_cast<std::uint8_t>(MailboxType::CoE);
        if (coe && msg->payload.size() >= kCoeHeaderSize + Emergency::kSize &&
            coe_service(ld_le16(msg->payload.data())) == CoeService::Emergency) {
            emergencies_.push_back(
                Emergency::unpack(std::span(msg->payload).subspan<kCoeHeaderSize, Emergency::kSize>()));
            if (Clock::now() >= deadline) return std::nullopt;
            continue;
        }
        return msg;
    }
}

namespace {

constexpr std::size_t kSdoMessage = kCoeHeaderSize + kSdoHeaderSize;  // the shortest SDO message

// The SDO header of a response at least kSdoMessage long.
SdoHeader sdo_header(const MailboxMessage& m) {
    return SdoHeader::unpack(std::span(m.payload).subspan<kCoeHeaderSize, kSdoHeaderSize>());
}

bool is_abort(const MailboxMessage& m) {
    return m.payload.size() >= kSdoMessage && sdo_header(m).command == sdo::AbortCommand;
}

// SDO information: the data after the CoE and SDO information headers.
constexpr std::size_t kInfoData = kCoeHeaderSize + kSdoInfoHeaderSize;

// The SDO information header of a message at least kInfoData long.
SdoInfoHeader info_header(const MailboxMessage& m) {
    return SdoInfoHeader::unpack(std::span(m.payload).subspan<kCoeHeaderSize, kSdoInfoHeaderSize>());
}

SdoAbort abort_code(const MailboxMessage& m) {
    return static_cast<SdoAbort>(sdo_header(m).data);
}

std::vector<std::uint8_t> sdo_frame(std::uint8_t cmd, std::uint16_t index, std::uint8_t sub,
                                    std::uint32_t data = 0) {
    std::vector<std::uint8_t> p(kSdoMessage, 0);
    st_le16(p.data(), coe_header(CoeService::SdoRequest));
    SdoHeader{cmd, index, sub, data}.pack(std::span(p).subspan<kCoeHeaderSize, kSdoHeaderSize>());
    return p;
}

}  // namespace

SdoResult CoeClient::upload(std::uint16_t index, std::uint8_t sub, bool complete) {
    SdoResult res;
    auto req =
        sdo_frame(sdo::command(sdo::CcsInitiateUpload, complete ? sdo::CompleteAccess : 0), index, sub);
    auto rsp = request(MailboxType::CoE, req);
    if (!rsp || rsp->payload.size() < kSdoMessage) return res;
    res.transport_ok = true;
    if (is_abort(*rsp)) {
        res.abort = abort_code(*rsp);
        return res;
    }
    const SdoHeader h = sdo_header(*rsp);
    res.command = h.command;
    if (h.command & sdo::Expedited) {
        const auto value = rsp->payload.begin() + kCoeHeaderSize + 4;  // the data field of the SDO header
        res.data.assign(value, value + static_cast<std::ptrdiff_t>(sdo::expedited_length(h.command)));
        return res;
    }
    const std::uint32_t total = h.data;
    res.data.assign(rsp->payload.begin() + kSdoMessage, rsp->payload.end());
    if (res.data.size() > total) res.data.resize(total);
    std::uint8_t toggle = 0;
    while (res.data.size() < total) {
        auto seg =
            request(MailboxType::CoE, sdo_frame(sdo::command(sdo::CcsUploadSegment, toggle), index, sub));
        if (!seg || seg->payload.size() < kSdoMessage) {
            res.transport_ok = false;
            return res;
        }
        if (is_abort(*seg)) {
            res.abort = abort_code(*seg);
            return res;
        }
        const std::uint8_t c = seg->payload[kCoeHeaderSize];
        constexpr std::size_t kData = kCoeHeaderSize + sdo::kSegmentHeaderSize;
        std::size_t n = seg->payload.size() - kData;
        if (seg->payload.size() == kSdoMessage) n = sdo::segment_length(c);
        res.data.insert(res.data.end(), seg->payload.begin() + kData,
                        seg->payload.begin() + static_cast<std::ptrdiff_t>(kData + n));
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
        if (!rsp || rsp->payload.size() < kSdoMessage) return false;
        res.transport_ok = true;
        res.command = sdo_header(*rsp).command;
        if (is_abort(*rsp)) {
            res.abort = abort_code(*rsp);
            return false;
        }
        return true;
    };
    if (how == Transfer::Expedited) {
        std::uint32_t v = 0;
        for (std::size_t i = 0; i < data.size() && i < 4; ++i)
            v |= static_cast<std::uint32_t>(data[i]) << (8 * i);
        const auto cmd = sdo::command(sdo::CcsInitiateDownload, ca | sdo::expedited_size(data.size()));
        finish(request(MailboxType::CoE, sdo_frame(cmd, index, sub, v)));
        return res;
    }
    // Normal: as much as fits in the first message; the rest in segments (forced with Transfer::Segmented).
    const std::size_t max_first = sm0_len_ - kMailboxHeaderSize - kSdoMessage;
    std::size_t first = std::min(data.size(), max_first);
    if (how == Transfer::Segmented) first = 0;
    auto req = sdo_frame(sdo::command(sdo::CcsInitiateDownload, ca | sdo::SizeIndicated), index, sub,
                         static_cast<std::uint32_t>(data.size()));
    req.insert(req.end(), data.begin(), data.begin() + static_cast<std::ptrdiff_t>(first));
    if (!finish(request(MailboxType::CoE, req))) return res;
    std::size_t off = first;
    std::uint8_t toggle = 0;
    constexpr std::size_t kData = kCoeHeaderSize + sdo::kSegmentHeaderSize;
    const std::size_t max_seg = sm0_len_ - kMailboxHeaderSize - kData;
    while (off < data.size()) {
        const std::size_t n = std::min(max_seg, data.size() - off);
        const bool last = off + n == data.size();
        std::vector<std::uint8_t> seg(kData, 0);
        st_le16(seg.data(), coe_header(CoeService::SdoRequest));
        seg.insert(seg.end(), data.begin() + static_cast<std::ptrdiff_t>(off),
                   data.begin() + static_cast<std::ptrdiff_t>(off + n));
        if (n < sdo::kSegmentMin) seg.resize(kSdoMessage, 0);
        seg[kCoeHeaderSize] = sdo::command(sdo::CcsDownloadSegment,
                                           toggle | sdo::segment_unused(n) | (last ? sdo::LastSegment : 0));
        if (!finish(request(MailboxType::CoE, seg))) return res;
        off += n;
        toggle ^= sdo::Toggle;
    }
    return res;
}

std::optional<std::vector<std::uint16_t>> CoeClient::od_list(std::uint16_t list_type) {
    std::uint8_t arg[2];
    st_le16(arg, list_type);
    last_fragments_ = 0;
    auto rsp = info_request(sdo_info::GetOdListRequest, arg, kInfoData);
    std::vector<std::uint8_t> data;
    // Fragments follow while the incomplete bit is set; only the first carries the list type.
    while (rsp && rsp->payload.size() >= kInfoData &&
           info_header(*rsp).opcode == sdo_info::GetOdListResponse) {
        ++last_fragments_;
        data.insert(data.end(), rsp->payload.begin() + kInfoData, rsp->payload.end());
        if (!info_header(*rsp).incomplete) break;
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
    std::vector<std::uint8_t> req(kInfoData, 0);
    st_le16(req.data(), coe_header(CoeService::SdoInformation));
    SdoInfoHeader{opcode}.pack(std::span(req).subspan<kCoeHeaderSize, kSdoInfoHeaderSize>());
    req.insert(req.end(), args.begin(), args.end());
    last_abort_ = SdoAbort::None;
    auto rsp = request(MailboxType::CoE, req);
    if (!rsp || rsp->payload.size() < kInfoData) return std::nullopt;
    const std::uint8_t op = info_header(*rsp).opcode;
    if (op == sdo_info::InfoErrorRequest) {
        // The error's abort code follows the header.
        last_abort_ = rsp->payload.size() >= kInfoData + 4
                          ? static_cast<SdoAbort>(ld_le32(rsp->payload.data() + kInfoData))
                          : SdoAbort::GeneralError;
        return std::nullopt;
    }
    if (op != opcode + 1 || rsp->payload.size() < min_len) return std::nullopt;
    return rsp;
}

std::optional<ObjectInfo> CoeClient::object_description(std::uint16_t index) {
    std::uint8_t arg[2];
    st_le16(arg, index);
    constexpr std::size_t kName = kInfoData + SdoInfoObject::kSize;
    auto rsp = info_request(sdo_info::GetObjectDescriptionRequest, arg, kName);
    if (!rsp) return std::nullopt;
    const auto h = SdoInfoObject::unpack(std::span(rsp->payload).subspan<kInfoData, SdoInfoObject::kSize>());
    ObjectInfo o;
    o.index = h.index;
    o.data_type = h.data_type;
    o.max_subindex = h.max_subindex;
    o.object_code = h.object_code;
    o.name.assign(rsp->payload.begin() + kName, rsp->payload.end());
    return o;
}

std::optional<EntryInfo> CoeClient::entry_description(std::uint16_t index, std::uint8_t sub,
                                                      std::uint8_t value_info) {
    std::uint8_t arg[4] = {0, 0, sub, value_info};
    st_le16(arg, index);
    constexpr std::size_t kValues = kInfoData + SdoInfoEntry::kSize;
    auto rsp = info_request(sdo_info::GetEntryDescriptionRequest, arg, kValues);
    if (!rsp) return std::nullopt;
    const auto& p = rsp->payload;
    const auto h = SdoInfoEntry::unpack(std::span(p).subspan<kInfoData, SdoInfoEntry::kSize>());
    EntryInfo e;
    e.index = h.index;
    e.subindex = h.subindex;
    e.value_info = h.value_info;
    e.data_type = h.data_type;
    e.bit_length = h.bit_length;
    e.access = h.access;
    std::size_t off = kValues;
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
