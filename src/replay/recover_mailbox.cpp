#include "replay/recover_mailbox.hpp"

#include <algorithm>

#include "common/bytes.hpp"
#include "protocol/coe.hpp"
#include "protocol/mailbox.hpp"
#include "protocol/registers.hpp"
#include "protocol/sdo_abort.hpp"
#include "protocol/sync_manager.hpp"

namespace vecat::replay {

namespace {

using protocol::CoeService;
using protocol::kCoeHeaderSize;
using protocol::kMailboxHeaderSize;
using protocol::kSdoHeaderSize;
using protocol::kSdoInfoHeaderSize;
namespace sdo = protocol::sdo;
namespace sdo_info = protocol::sdo_info;

constexpr std::size_t kMaxValueBytes = 65536;  // a larger upload is not kept
constexpr std::uint32_t kObjectDoesNotExist = 0x06020000;
constexpr std::uint8_t kWholeObject = 0xFF;  // in RecoveredDictionary::written: every entry
// Communication objects of fixed layout (ETG.1000.6 5.6.7.4): SyncManager communication types (U8 entries),
// PDO assignments (U16), PDO mappings (U32).
constexpr std::uint16_t kSyncManagerTypes = 0x1C00;
constexpr std::uint16_t kPdoAssignFirst = 0x1C10, kPdoAssignLast = 0x1C2F;
constexpr std::uint16_t kRxMappingFirst = 0x1600, kTxMappingFirst = 0x1A00, kMappingCount = 0x200;
constexpr std::uint32_t kSubindexDoesNotExist = 0x06090011;

std::uint8_t command_specifier(std::uint8_t cmd) {
    return static_cast<std::uint8_t>(cmd >> sdo::CsShift);
}

// A data type for a value whose entry the capture did not describe: by its size.
device::EntryDescription entry_for(std::uint8_t sub, std::size_t bytes) {
    device::EntryDescription e;
    e.subindex = sub;
    e.access = device::access::RO;
    switch (bytes) {
        case 1:
            e.type = device::DataType::Unsigned8;
            break;
        case 2:
            e.type = device::DataType::Unsigned16;
            break;
        case 4:
            e.type = device::DataType::Unsigned32;
            break;
        case 8:
            e.type = device::DataType::Unsigned64;
            break;
        default:
            e.type = device::DataType::OctetString;
            break;
    }
    e.bit_length = static_cast<std::uint16_t>(std::min<std::size_t>(8 * bytes, 0xFFFF));
    return e;
}

// The objects the PDO mappings map (0x1600-0x17FF receive, 0x1A00-0x1BFF transmit; entry value: index <<
// 16 | subindex << 8 | bit length, CiA 301 7.4.8) when the dictionary lacks them: a device checks its mapping
// against them before SAFEOP (ETG.1000.6, AL status 0x0024/0x0025).
void add_mapped_objects(
    std::map<std::uint16_t, device::ObjectDescription>& objs,
    const std::map<std::pair<std::uint16_t, std::uint8_t>, std::vector<std::uint8_t>>& values) {
    constexpr std::uint16_t kFirstMappableObject = 0x1000;  // below: data types, a gap in the PDO
    for (const auto& [at, bytes] : values) {
        const std::uint16_t index = at.first;
        const std::uint8_t sub = at.second;
        const bool rx = index >= kRxMappingFirst && index < kRxMappingFirst + kMappingCount;
        const bool tx = index >= kTxMappingFirst && index < kTxMappingFirst + kMappingCount;
        if ((!rx && !tx) || sub == 0 || bytes.size() != 4) continue;
        const std::uint32_t m = ld_le32(bytes.data());
        const auto target = static_cast<std::uint16_t>(m >> 16);
        const auto target_sub = static_cast<std::uint8_t>(m >> 8);
        const auto bits = static_cast<std::uint8_t>(m);
        if (target < kFirstMappableObject || bits == 0) continue;
        auto [it, made] = objs.try_emplace(target);
        device::ObjectDescription& o = it->second;
        if (made) {
            o.index = target;
            o.code = target_sub == 0 ? device::ObjectCode::Var : device::ObjectCode::Record;
            if (target_sub != 0) o.entries.push_back(entry_for(0, 1));
        }
        if (auto* have = const_cast<device::EntryDescription*>(o.entry(target_sub))) {
            have->access |= rx ? device::access::RxPdoMappable : device::access::TxPdoMappable;
            continue;
        }
        device::EntryDescription e = entry_for(target_sub, (bits + 7u) / 8u);
        if (bits == 1) e.type = device::DataType::Boolean;
        e.bit_length = bits;
        e.access = rx ? device::access::RxMap : device::access::TxMap;
        auto pos = std::find_if(o.entries.begin(), o.entries.end(),
                                [&](const auto& x) { return x.subindex > target_sub; });
        o.entries.insert(pos, e);
        if (o.code != device::ObjectCode::Var && !o.entries.empty() && o.entries.front().subindex == 0)
            o.entries.front().default_value = {o.entries.back().subindex};
    }
}

}  // namespace

void MailboxRecoverer::wrote(std::uint16_t ado, const std::uint8_t* data, std::size_t len) {
    // The master's configuration of SM0 and SM1 (ESC datasheet section II 0x0800, 0x0808).
    for (unsigned sm = 0; sm < 2; ++sm) {
        const std::uint16_t a = protocol::sm_addr(sm);
        if (ado <= a && a + 2u <= ado + len) (sm == 0 ? out_start_ : in_start_) = ld_le16(data + (a - ado));
    }
    if (!out_start_ || ado != *out_start_ || len < kMailboxHeaderSize + kCoeHeaderSize + kSdoHeaderSize)
        return;
    const auto h = protocol::parse_mailbox_header(ConstBytes(data, len));
    if (!h || h->type != static_cast<std::uint8_t>(protocol::MailboxType::CoE)) return;
    const std::uint8_t* p = data + kMailboxHeaderSize;
    if (protocol::coe_service(ld_le16(p)) != CoeService::SdoRequest) return;
    const std::uint8_t ccs = command_specifier(p[kCoeHeaderSize]);
    // A segment request carries no index: the initiating request's stays (and its complete access bit).
    if (ccs == sdo::CcsUploadSegment || ccs == sdo::CcsDownloadSegment) return;
    request_cmd_ = p[kCoeHeaderSize];
    request_index_ = ld_le16(p + kCoeHeaderSize + 1);
    request_sub_ = p[kCoeHeaderSize + 3];
    request_data_ = ld_le32(p + kCoeHeaderSize + 4);
    request_value_.clear();
    const std::uint8_t cmd = request_cmd_;
    if (command_specifier(cmd) == sdo::CcsInitiateDownload && (cmd & sdo::Expedited)) {
        const std::size_t size = cmd & sdo::SizeIndicated
                                     ? sdo::kExpeditedMax - ((cmd >> sdo::ExpeditedUnusedShift) & 3)
                                     : sdo::kExpeditedMax;
        request_value_.assign(p + kCoeHeaderSize + 4, p + kCoeHeaderSize + 4 + size);
    }
    if (command_specifier(request_cmd_) == sdo::CcsInitiateUpload) segmented_ = false;
}

void MailboxRecoverer::read(std::uint16_t ado, const std::uint8_t* data, std::size_t len) {
    constexpr std::uint16_t kInStatus = protocol::sm_addr(1) + protocol::sm::Status;
    if (in_read_ && ado <= kInStatus && kInStatus < ado + len) {
        in_read_ = false;
        const std::uint8_t st = data[kInStatus - ado];
        ++status_after_read_;
        if ((st & protocol::sm::StatusWriteBufferInUse) && !(st & protocol::sm::StatusIrqRead))
            ++opened_after_read_;
        // More than half of them, and more than once.
        dict_.open_early = opened_after_read_ >= 2 && 2 * opened_after_read_ > status_after_read_;
    }
    if (!in_start_ || ado != *in_start_ || len < kMailboxHeaderSize) return;
    in_read_ = true;
    const auto h = protocol::parse_mailbox_header(ConstBytes(data, len));
    if (!h || h->type != static_cast<std::uint8_t>(protocol::MailboxType::CoE)) return;
    const std::size_t n = std::min<std::size_t>(h->length, len - kMailboxHeaderSize);
    reply(data + kMailboxHeaderSize, n);
}

void MailboxRecoverer::reply(const std::uint8_t* msg, std::size_t len) {
    if (len < kCoeHeaderSize) return;
    const CoeService service = protocol::coe_service(ld_le16(msg));
    const std::uint8_t* p = msg + kCoeHeaderSize;
    const std::size_t n = len - kCoeHeaderSize;
    if (service == CoeService::SdoResponse) {
        sdo_response(p, n);
    } else if (service == CoeService::SdoRequest && n >= kSdoHeaderSize && p[0] == sdo::AbortCommand) {
        // An abort from the device (ETG.1000.6 5.6.2.7): the object or the subindex does not exist.
        const std::uint16_t index = ld_le16(p + 1);
        const std::uint8_t sub = p[3];
        const std::uint32_t code = ld_le32(p + 4);
        segmented_ = false;
        if (code == kObjectDoesNotExist) dict_.absent_objects.insert(index);
        if (code == kSubindexDoesNotExist) dict_.absent_entries.insert({index, sub});
    } else if (service == CoeService::SdoInformation) {
        info_response(p, n);
    }
}

void MailboxRecoverer::sdo_response(const std::uint8_t* p, std::size_t n) {
    if (n < 1) return;
    const std::uint8_t cmd = p[0];
    const bool complete_access = (request_cmd_ & sdo::CompleteAccess) != 0;
    if (command_specifier(cmd) == sdo::ScsInitiateUpload && n >= kSdoHeaderSize) {
        const std::uint16_t index = ld_le16(p + 1);
        const std::uint8_t sub = p[3];
        segmented_ = false;
        if (index != request_index_ || sub != request_sub_) return;
        if (cmd & sdo::Expedited) {
            const std::size_t size = cmd & sdo::SizeIndicated
                                         ? sdo::kExpeditedMax - ((cmd >> sdo::ExpeditedUnusedShift) & 3)
                                         : sdo::kExpeditedMax;
            store(index, sub, complete_access, std::vector<std::uint8_t>(p + 4, p + 4 + size));
            return;
        }
        const std::uint32_t size = ld_le32(p + 4);
        if (size > kMaxValueBytes) return;
        const std::size_t here = std::min<std::size_t>(n - kSdoHeaderSize, size);
        if (here == size) {
            store(index, sub, complete_access,
                  std::vector<std::uint8_t>(p + kSdoHeaderSize, p + kSdoHeaderSize + size));
            return;
        }
        segmented_ = true;
        segmented_size_ = size;
        segmented_data_.assign(p + kSdoHeaderSize, p + kSdoHeaderSize + here);
        return;
    }
    if (command_specifier(cmd) == sdo::ScsInitiateDownload && n >= kSdoHeaderSize) {
        // A download the device confirmed: the entry (with complete access, the object) is writable.
        const std::uint16_t index = ld_le16(p + 1);
        const std::uint8_t sub = p[3];
        if (index == request_index_ && sub == request_sub_ &&
            command_specifier(request_cmd_) == sdo::CcsInitiateDownload) {
            dict_.written[{index, complete_access ? kWholeObject : sub}] = request_value_;
            if (request_data_ != 0 && ld_le32(p + 4) == request_data_) dict_.download_echo = true;
        }
        return;
    }
    if (command_specifier(cmd) == sdo::ScsUploadSegment && segmented_) {
        // Segment data: 7 bytes less the unused ones in a 10-byte message, else all that follows the command
        // byte (ETG.1000.6 5.6.2.3).
        std::size_t size = n - sdo::kSegmentHeaderSize;
        if (n == sdo::kSegmentHeaderSize + sdo::kSegmentMin)
            size = sdo::kSegmentMin - ((cmd >> sdo::SegmentUnusedShift) & 7);
        segmented_data_.insert(segmented_data_.end(), p + 1, p + 1 + size);
        if (cmd & sdo::LastSegment) {
            segmented_ = false;
            if (segmented_data_.size() == segmented_size_)
                store(request_index_, request_sub_, (request_cmd_ & sdo::CompleteAccess) != 0,
                      std::move(segmented_data_));
            segmented_data_.clear();
        }
    }
}

// A value uploaded: one entry's, or with complete access (ETG.1000.6 5.6.2.1.2) the object's entries from
// `sub` on, subindex 0 taking 16 bits (its U8 and a padding byte); such a value is split into its entries
// where their size is known (described, or a communication object of fixed layout).
void MailboxRecoverer::store(std::uint16_t index, std::uint8_t sub, bool complete_access,
                             std::vector<std::uint8_t> bytes) {
    if (!complete_access) {
        dict_.values[{index, sub}] = std::move(bytes);
        return;
    }
    std::size_t width = 0;  // bytes per entry past subindex 0
    if (index == kSyncManagerTypes)
        width = 1;
    else if (index >= kPdoAssignFirst && index <= kPdoAssignLast)
        width = 2;
    else if ((index >= kRxMappingFirst && index < kRxMappingFirst + kMappingCount) ||
             (index >= kTxMappingFirst && index < kTxMappingFirst + kMappingCount))
        width = 4;
    else if (auto it = dict_.objects.find(index); it != dict_.objects.end() &&
                                                  it->second.entries.size() > 1 &&
                                                  it->second.entries[1].bit_length % 8 == 0)
        width = it->second.entries[1].bit_length / 8u;  // the first entry's size for all: arrays
    if (width == 0 || sub > 1) return;
    std::size_t at = 0;
    std::size_t count = 0;
    if (sub == 0) {
        if (bytes.size() < 2) return;
        count = bytes[0];
        dict_.values[{index, 0}] = {bytes[0]};
        at = 2;
    } else {
        count = (bytes.size() - at) / width;
    }
    for (std::size_t k = 1; k <= count && at + width <= bytes.size(); ++k, at += width)
        dict_.values[{index, static_cast<std::uint8_t>(k)}].assign(
            bytes.begin() + static_cast<long>(at), bytes.begin() + static_cast<long>(at + width));
}

void MailboxRecoverer::info_response(const std::uint8_t* p, std::size_t n) {
    if (n < kSdoInfoHeaderSize) return;
    const auto h = protocol::SdoInfoHeader::unpack(
        std::span<const std::uint8_t, kSdoInfoHeaderSize>(p, kSdoInfoHeaderSize));
    const std::uint8_t* b = p + kSdoInfoHeaderSize;
    std::size_t m = n - kSdoInfoHeaderSize;
    if (h.opcode == sdo_info::GetOdListResponse) {
        if (!list_type_) {
            if (m < 2) return;
            list_type_ = ld_le16(b);
            list_.clear();
            b += 2;
            m -= 2;
        }
        for (std::size_t k = 0; k + 1 < m; k += 2)
            list_.push_back(ld_le16(b + k));
        if (!h.incomplete) {
            if (*list_type_ == sdo_info::ListAll) dict_.all_objects = list_;
            list_type_.reset();
        }
        return;
    }
    if (h.opcode == sdo_info::GetObjectDescriptionResponse && !h.incomplete &&
        m >= protocol::SdoInfoObject::kSize) {
        const auto o = protocol::SdoInfoObject::unpack(
            std::span<const std::uint8_t, protocol::SdoInfoObject::kSize>(b, 6));
        device::ObjectDescription& d = dict_.objects[o.index];
        d.index = o.index;
        d.type = static_cast<device::DataType>(o.data_type);
        d.code = static_cast<device::ObjectCode>(o.object_code);
        d.declared_max_subindex = o.max_subindex;
        d.name.assign(reinterpret_cast<const char*>(b + 6), m - 6);
        return;
    }
    if (h.opcode == sdo_info::GetEntryDescriptionResponse && !h.incomplete &&
        m >= protocol::SdoInfoEntry::kSize) {
        const auto e = protocol::SdoInfoEntry::unpack(
            std::span<const std::uint8_t, protocol::SdoInfoEntry::kSize>(b, 10));
        device::EntryDescription d;
        d.subindex = e.subindex;
        d.type = static_cast<device::DataType>(e.data_type);
        d.bit_length = e.bit_length;
        d.access = e.access;
        std::size_t at = protocol::SdoInfoEntry::kSize;
        if (e.value_info & sdo_info::ValueUnitType) at += 4;  // the unit (ETG.1000.6 5.6.3.6), not served
        const std::size_t vb = (e.bit_length + 7u) / 8u;
        for (auto [flag, out] :
             {std::pair{sdo_info::ValueDefault, &d.default_value},
              std::pair{sdo_info::ValueMinimum, &d.minimum}, std::pair{sdo_info::ValueMaximum, &d.maximum}}) {
            if (!(e.value_info & flag)) continue;
            if (at + vb > m) return;
            out->assign(b + at, b + at + vb);
            at += vb;
        }
        if (at > m) return;
        d.name.assign(reinterpret_cast<const char*>(b + at), m - at);
        device::ObjectDescription& o = dict_.objects[e.index];
        o.index = e.index;
        auto it = std::find_if(o.entries.begin(), o.entries.end(),
                               [&](const auto& x) { return x.subindex >= d.subindex; });
        if (it != o.entries.end() && it->subindex == d.subindex)
            *it = std::move(d);
        else
            o.entries.insert(it, std::move(d));
    }
}

std::vector<device::ObjectDescription> merge_dictionary(
    std::vector<device::ObjectDescription> generated, const RecoveredDictionary& r,
    std::map<std::pair<std::uint16_t, std::uint8_t>, std::vector<std::uint8_t>>& values) {
    std::map<std::uint16_t, device::ObjectDescription> objs;
    for (auto& o : generated)
        objs[o.index] = std::move(o);
    for (const auto& [index, o] : r.objects) {
        device::ObjectDescription d = o;
        auto g = objs.find(index);
        // An object whose entries were not described keeps the generated ones; one described only by its
        // entries keeps the generated object's name, code and type.
        if (d.entries.empty() && g != objs.end()) d.entries = g->second.entries;
        if (!d.declared_max_subindex && g != objs.end()) {
            d.name = g->second.name;
            d.code = g->second.code;
            d.type = g->second.type;
        }
        objs[index] = std::move(d);
    }
    for (const auto index : r.absent_objects)
        objs.erase(index);
    if (r.all_objects) {
        const std::set<std::uint16_t> listed(r.all_objects->begin(), r.all_objects->end());
        std::erase_if(objs, [&](const auto& kv) { return !listed.contains(kv.first); });
        for (const auto index : listed)
            if (!objs.contains(index)) {
                device::ObjectDescription& d = objs[index];
                d.index = index;
                d.entries.push_back(entry_for(0, 1));
            }
    }
    for (const auto& [at, bytes] : r.values) {
        const std::uint16_t index = at.first;
        const std::uint8_t sub = at.second;
        if (r.absent_objects.contains(index)) continue;
        auto [it, made] = objs.try_emplace(index);
        device::ObjectDescription& o = it->second;
        if (made) {
            // A record when any subindex above 0 was uploaded; subindex 0 then holds the count.
            const auto next = r.values.upper_bound({index, 0});
            const bool record = sub != 0 || (next != r.values.end() && next->first.first == index);
            o.index = index;
            o.code = record ? device::ObjectCode::Record : device::ObjectCode::Var;
            if (record && sub != 0) o.entries.push_back(entry_for(0, 1));
        }
        if (!o.entry(sub)) {
            auto pos = std::find_if(o.entries.begin(), o.entries.end(),
                                    [&](const auto& x) { return x.subindex > sub; });
            o.entries.insert(pos, entry_for(sub, bytes.size()));
        }
        values[at] = bytes;
    }
    add_mapped_objects(objs, values);
    // A PDO assignment the device accepted names PDOs it has (ETG.1000.6 5.6.7.4.9); its entries exist.
    for (const auto& [at, v] : r.written) {
        const std::uint16_t index = at.first;
        const std::uint8_t sub = at.second;
        if (index < kPdoAssignFirst || index > kPdoAssignLast || sub == 0 || sub == kWholeObject) continue;
        auto it = objs.find(index);
        if (it == objs.end()) continue;
        if (!it->second.entry(sub)) {
            auto& entries = it->second.entries;
            auto pos =
                std::find_if(entries.begin(), entries.end(), [&](const auto& x) { return x.subindex > sub; });
            entries.insert(pos, entry_for(sub, 2));
        }
        if (v.size() != 2) continue;
        const std::uint16_t pdo = ld_le16(v.data());
        if (objs.contains(pdo)) continue;
        device::ObjectDescription& m = objs[pdo];
        m.index = pdo;
        m.code = device::ObjectCode::Record;
        m.entries.push_back(entry_for(0, 1));
    }
    // Written by the master and confirmed: writable (in which states the capture does not tell: in all).
    for (const auto& [at, v] : r.written) {
        const std::uint16_t index = at.first;
        const std::uint8_t sub = at.second;
        auto it = objs.find(index);
        if (it == objs.end()) continue;
        for (auto& e : it->second.entries)
            if (sub == kWholeObject || e.subindex == sub) e.access |= device::access::WriteAll;
    }
    for (const auto& at : r.absent_entries) {
        const std::uint16_t index = at.first;
        const std::uint8_t sub = at.second;
        auto it = objs.find(index);
        if (it == objs.end() || sub == 0) continue;
        std::erase_if(it->second.entries, [&](const auto& e) { return e.subindex == sub; });
    }
    // Subindex 0 of an object that gained entries may count up to the last one.
    for (auto& [index, o] : objs) {
        auto& entries = o.entries;
        if (entries.size() > 1 && entries.front().subindex == 0 && !entries.front().maximum.empty())
            entries.front().maximum = {std::max(entries.front().maximum[0], entries.back().subindex)};
    }
    std::vector<device::ObjectDescription> out;
    out.reserve(objs.size());
    for (auto& [index, o] : objs)
        if (!o.entries.empty()) out.push_back(std::move(o));
    return out;
}

}  // namespace vecat::replay
