#include "coe/object_dictionary.hpp"

#include <algorithm>
#include <mutex>

#include "common/asan.hpp"
#include "common/bits.hpp"

namespace vecat::coe {
namespace {

namespace acc = device::access;

std::uint16_t read_bit(AlState s) {
    switch (s) {
        case AlState::PreOp:
            return acc::ReadPreop;
        case AlState::SafeOp:
            return acc::ReadSafeop;
        case AlState::Op:
            return acc::ReadOp;
        default:
            return 0;  // no SDO access in INIT/BOOT (the mailbox is off there)
    }
}

std::uint16_t write_bit(AlState s) {
    switch (s) {
        case AlState::PreOp:
            return acc::WritePreop;
        case AlState::SafeOp:
            return acc::WriteSafeop;
        case AlState::Op:
            return acc::WriteOp;
        default:
            return 0;
    }
}

std::size_t byte_size(const Entry& e) {
    return (e.bit_length() + 7) / 8;
}

// Layout of a complete access: sub 0 takes 16 bits (U8 + one pad byte, ETG.1000.6 5.6.2.1.1); entries of
// 8 bits or more start on a byte boundary, smaller ones are packed.
template <class F>
std::size_t for_each_ca_entry(const Object& o, std::uint8_t from, std::uint8_t last, F&& f) {
    std::size_t bit = 0;
    for (const auto& e : o.entries()) {
        if (e.subindex() < from || e.subindex() > last) continue;
        if (e.subindex() == 0) {
            f(e, bit, 8u);
            bit += 16;
            continue;
        }
        if (e.bit_length() >= 8 && bit % 8) bit += 8 - bit % 8;
        f(e, bit, e.bit_length());
        bit += e.bit_length();
    }
    return (bit + 7) / 8;
}

}  // namespace

// ---- Entry ----

Entry::Entry(const device::EntryDescription& d, Bytes storage) : desc_(&d), storage_(storage) {
    reset_to_default();
}

bool Entry::readable(AlState s) const {
    return (desc_->access & read_bit(s)) != 0;
}
bool Entry::writable(AlState s) const {
    return (desc_->access & write_bit(s)) != 0;
}

void Entry::assign(ConstBytes v) {
    touch();
    const std::size_t n = std::min(v.size(), storage_.size());
    std::copy_n(v.begin(), n, storage_.begin());
    if (device::is_variable_length(desc_->type)) {
        std::fill(storage_.begin() + static_cast<std::ptrdiff_t>(n), storage_.end(), 0);
        size_ = n;
    } else {
        size_ = (desc_->bit_length + 7u) / 8u;
    }
}

void Entry::reset_to_default() {
    std::fill(storage_.begin(), storage_.end(), 0);
    assign(ConstBytes(desc_->default_value.data(), desc_->default_value.size()));
    if (!device::is_variable_length(desc_->type)) size_ = (desc_->bit_length + 7u) / 8u;
}

std::int64_t Entry::as_int64() const {
    const std::size_t n = std::min<std::size_t>(8, size_);
    std::uint64_t u = 0;
    for (std::size_t i = 0; i < n; ++i)
        u |= static_cast<std::uint64_t>(storage_[i]) << (8 * i);
    const unsigned bits = desc_->bit_length;
    if (device::is_signed(desc_->type) && bits > 0 && bits < 64 && (u >> (bits - 1)) & 1u)
        u |= ~std::uint64_t{0} << bits;
    if (bits < 64 && !device::is_signed(desc_->type)) u &= (std::uint64_t{1} << bits) - 1;
    return static_cast<std::int64_t>(u);
}

// ---- Object ----

Object::Object(const device::ObjectDescription& d, std::span<Entry> entries)
    : desc_(&d),
      index_(d.index),
      code_(d.code),
      type_(d.type),
      max_sub_(d.max_subindex()),
      entries_(entries) {}

Entry* Object::entry(std::uint8_t sub) {
    for (auto& e : entries_)
        if (e.subindex() == sub) return &e;
    return nullptr;
}
const Entry* Object::entry(std::uint8_t sub) const {
    for (const auto& e : entries_)
        if (e.subindex() == sub) return &e;
    return nullptr;
}

std::uint8_t Object::complete_access_last() const {
    if (code_ == ObjectCode::Var) return 0;
    const Entry* s0 = entry(0);
    if (!s0) return max_sub_;
    return static_cast<std::uint8_t>(std::min<std::uint64_t>(s0->as_uint64(), max_sub_));
}

// ---- checks ----

SdoAbort check_length(const Entry& e, std::size_t len) {
    if (device::is_variable_length(e.type()))
        return len > e.capacity() ? SdoAbort::LengthTooHigh : SdoAbort::None;
    const std::size_t want = byte_size(e);
    if (len > want) return SdoAbort::LengthTooHigh;
    if (len < want) return SdoAbort::LengthTooLow;
    return SdoAbort::None;
}

SdoAbort check_range(const Entry& e, ConstBytes v) {
    const auto& d = e.desc();
    if (device::is_variable_length(d.type) || device::is_real(d.type)) return SdoAbort::None;
    const unsigned bits = d.bit_length;
    auto decode = [&](ConstBytes b) {
        std::uint64_t u = 0;
        for (std::size_t i = 0; i < std::min<std::size_t>(8, b.size()); ++i)
            u |= static_cast<std::uint64_t>(b[i]) << (8 * i);
        if (bits < 64) {
            u &= (std::uint64_t{1} << bits) - 1;
            if (device::is_signed(d.type) && ((u >> (bits - 1)) & 1u)) u |= ~std::uint64_t{0} << bits;
        }
        return u;
    };
    // A BOOLEAN travels as one byte that must be 0 or 1 (checked before masking to the 1-bit length).
    if (d.type == DataType::Boolean && !v.empty() && v[0] > 1) return SdoAbort::ValueRange;
    const std::uint64_t x = decode(v);
    auto less = [&](std::uint64_t a, std::uint64_t b) {
        return device::is_signed(d.type) ? static_cast<std::int64_t>(a) < static_cast<std::int64_t>(b)
                                         : a < b;
    };
    if (!d.minimum.empty() && less(x, decode(d.minimum))) return SdoAbort::ValueTooLow;
    if (!d.maximum.empty() && less(decode(d.maximum), x)) return SdoAbort::ValueTooHigh;
    return SdoAbort::None;
}

std::size_t complete_access_size(const Object& o, std::uint8_t from, std::uint8_t last) {
    return for_each_ca_entry(o, from, last, [](const Entry&, std::size_t, unsigned) {});
}

// ---- dictionary ----

ObjectDictionary::ObjectDictionary(std::vector<device::ObjectDescription> objects)
    : ObjectDictionary(std::make_shared<const std::vector<device::ObjectDescription>>(std::move(objects))) {}

namespace {

// Under AddressSanitizer every value starts on an 8-byte boundary with at least 8 poisoned bytes after it:
// an access past an entry's value is reported as with separate allocations.
std::size_t value_slot(const device::EntryDescription& e) {
    const std::size_t n = Entry::storage_size(e);
    return kAsan ? (n + 15) / 8 * 8 : n;
}

}  // namespace

struct ObjectDictionary::Layout {
    std::vector<const device::ObjectDescription*> order;  // by index
    std::vector<std::uint8_t> values;                     // every entry's default value, at its place
    std::vector<std::size_t> places;                      // every entry's place in values
    std::vector<std::size_t> sizes;                       // every entry's current size at the defaults
    std::size_t max_transfer = 0;
    std::size_t undo = 0;
};

ObjectDictionary::Layout ObjectDictionary::make_layout(const std::vector<device::ObjectDescription>& d) {
    Layout l;
    l.order.reserve(d.size());
    std::size_t n_entries = 0, n_bytes = 0;
    for (const auto& o : d) {
        l.order.push_back(&o);
        n_entries += o.entries.size();
        for (const auto& e : o.entries)
            n_bytes += value_slot(e);
    }
    std::stable_sort(l.order.begin(), l.order.end(),
                     [](const auto* a, const auto* b) { return a->index < b->index; });
    // The values' places: those the PDO mapping objects map by default first (their entries' default values:
    // index, subindex and length, ETG.1000.6 5.6.7.4.7), then the others a TxPDO may map, those an RxPDO may
    // map, and the rest, each in the order of the indexes. What a cycle copies and the feedback an
    // application writes every cycle then lie in a few cache lines of the dictionary, not one line each
    // among strings and parameters (a line of hundreds of drives runs each drive's cycle out of the caches).
    std::vector<std::uint32_t> mapped;  // index << 8 | subindex
    for (const auto* o : l.order) {
        const bool mapping = (o->index >= protocol::obj::rx_pdo_mapping_first &&
                              o->index <= protocol::obj::rx_pdo_mapping_last) ||
                             (o->index >= protocol::obj::tx_pdo_mapping_first &&
                              o->index <= protocol::obj::tx_pdo_mapping_last);
        if (!mapping) continue;
        for (const auto& e : o->entries)
            if (e.subindex != 0 && e.default_value.size() == 4)
                mapped.push_back(ld_le32(e.default_value.data()) >> 8);
    }
    std::sort(mapped.begin(), mapped.end());
    const auto rank = [&](const device::ObjectDescription& o, const device::EntryDescription& e) {
        const auto key = static_cast<std::uint32_t>(o.index) << 8 | e.subindex;
        if (std::binary_search(mapped.begin(), mapped.end(), key)) return 0;
        if (e.access & device::access::TxPdoMappable) return 1;
        return (e.access & device::access::RxPdoMappable) ? 2 : 3;
    };
    l.places.assign(n_entries, 0);
    std::size_t at = 0;
    for (int pass = 0; pass < 4; ++pass) {
        std::size_t i = 0;
        for (const auto* o : l.order)
            for (const auto& e : o->entries) {
                if (rank(*o, e) == pass) {
                    l.places[i] = at;
                    at += value_slot(e);
                }
                ++i;
            }
    }
    // Entries and objects at the defaults, as a dictionary has them: their sizes and transfer sizes.
    l.values.assign(n_bytes, 0);
    std::vector<Entry> entries;
    std::vector<Object> objects;
    entries.reserve(n_entries);
    objects.reserve(l.order.size());
    for (const auto* o : l.order) {
        const std::size_t first = entries.size();
        for (const auto& e : o->entries)
            entries.emplace_back(e,
                                 Bytes(l.values.data() + l.places[entries.size()], Entry::storage_size(e)));
        objects.emplace_back(*o, std::span<Entry>(entries.data() + first, o->entries.size()));
    }
    l.sizes.reserve(n_entries);
    for (const auto& e : entries)
        l.sizes.push_back(e.size());
    for (const auto& o : objects) {
        l.max_transfer = std::max(l.max_transfer, complete_access_size(o, 0, o.max_subindex()));
        std::size_t n = 0;  // the undo of a complete-access download keeps each value at its capacity
        for (const auto& e : o.entries()) {
            l.max_transfer = std::max(l.max_transfer, e.capacity());
            n += e.capacity();
        }
        l.undo = std::max(l.undo, n);
    }
    return l;
}

std::shared_ptr<const ObjectDictionary::Layout> ObjectDictionary::layout_of(
    const std::shared_ptr<const std::vector<device::ObjectDescription>>& descriptions) {
    // One layout per description vector (the same control block: a freed vector's address may come back),
    // dropped with the vector. Dictionaries are built at start-up and on slave restarts, never cyclically.
    static std::mutex mutex;
    static std::vector<
        std::pair<std::weak_ptr<const std::vector<device::ObjectDescription>>, std::shared_ptr<const Layout>>>
        cache;
    const std::lock_guard lock(mutex);
    std::erase_if(cache, [](const auto& c) { return c.first.expired(); });
    for (const auto& [owner, layout] : cache)
        if (!owner.owner_before(descriptions) && !descriptions.owner_before(owner)) return layout;
    auto layout = std::make_shared<const Layout>(make_layout(*descriptions));
    cache.emplace_back(descriptions, layout);
    return layout;
}

ObjectDictionary::ObjectDictionary(std::shared_ptr<const std::vector<device::ObjectDescription>> objects)
    : descriptions_(std::move(objects)) {
    const auto layout = layout_of(descriptions_);
    // Sized once: the entries' storage and the objects' entry spans must not move.
    values_ = layout->values;
    entries_.reserve(layout->sizes.size());
    objects_.reserve(layout->order.size());
    for (const auto* o : layout->order) {
        const std::size_t first = entries_.size();
        for (const auto& e : o->entries) {
            const std::size_t n = Entry::storage_size(e);
            const std::size_t at = layout->places[entries_.size()];
            asan_poison(values_.data() + at + n, value_slot(e) - n);
            entries_.emplace_back(e, Bytes(values_.data() + at, n), layout->sizes[entries_.size()]);
        }
        objects_.emplace_back(*o, std::span<Entry>(entries_.data() + first, o->entries.size()));
    }
    max_transfer_ = layout->max_transfer;
    undo_.resize(layout->undo);
}

ObjectDictionary::~ObjectDictionary() {
    asan_unpoison(values_.data(), values_.size());
}

Object* ObjectDictionary::find(std::uint16_t index) {
    auto it = std::lower_bound(objects_.begin(), objects_.end(), index,
                               [](const Object& o, std::uint16_t i) { return o.index() < i; });
    return it != objects_.end() && it->index() == index ? &*it : nullptr;
}
const Object* ObjectDictionary::find(std::uint16_t index) const {
    return const_cast<ObjectDictionary*>(this)->find(index);
}
Entry* ObjectDictionary::find(std::uint16_t index, std::uint8_t sub) {
    Object* o = find(index);
    return o ? o->entry(sub) : nullptr;
}
const Entry* ObjectDictionary::find(std::uint16_t index, std::uint8_t sub) const {
    return const_cast<ObjectDictionary*>(this)->find(index, sub);
}

SdoAbort ObjectDictionary::upload(std::uint16_t index, std::uint8_t sub, bool complete, AlState state,
                                  Bytes out, std::size_t& len) {
    len = 0;
    Object* o = find(index);
    if (!o) return SdoAbort::ObjectDoesNotExist;
    if (!complete) {
        Entry* e = o->entry(sub);
        if (!e) return SdoAbort::SubindexDoesNotExist;
        if (!e->readable(state))
            return (e->access() & acc::ReadAll) ? SdoAbort::WrongState : SdoAbort::WriteOnly;
        e->run_before_upload();
        if (e->size() > out.size()) return SdoAbort::ObjectTooLongForMailbox;
        std::copy_n(e->value().begin(), e->size(), out.begin());
        len = e->size();
        return SdoAbort::None;
    }
    if (sub > 1) return SdoAbort::UnsupportedAccess;
    if (o->code() == ObjectCode::Var) return SdoAbort::UnsupportedAccess;
    for (auto& e : o->entries()) {
        if (device::is_variable_length(e.type())) return SdoAbort::CompleteAccessNotSupported;
        if (!e.readable(state))
            return (e.access() & acc::ReadAll) ? SdoAbort::WrongState : SdoAbort::WriteOnly;
    }
    for (auto& e : o->entries())
        e.run_before_upload();
    const std::uint8_t last = o->complete_access_last();
    const std::size_t n = complete_access_size(*o, sub, last);
    if (n > out.size()) return SdoAbort::ObjectTooLongForMailbox;
    std::fill_n(out.begin(), n, 0);
    for_each_ca_entry(*o, sub, last, [&](const Entry& e, std::size_t bit, unsigned bits) {
        copy_bits(out.data(), bit, e.value().data(), 0, bits);
    });
    len = n;
    return SdoAbort::None;
}

SdoAbort ObjectDictionary::download_entry(Entry& e, AlState state, ConstBytes data, bool run_after) {
    if (download_guard)
        if (auto a = download_guard(e, state); a != SdoAbort::None) return a;
    if (!e.writable(state)) return (e.access() & acc::WriteAll) ? SdoAbort::WrongState : SdoAbort::ReadOnly;
    if (auto a = check_length(e, data.size()); a != SdoAbort::None) return a;
    if (auto a = check_range(e, data); a != SdoAbort::None) return a;
    if (auto a = e.check_download(data); a != SdoAbort::None) return a;
    e.assign(data);
    if (run_after) e.run_after_download();
    return SdoAbort::None;
}

SdoAbort ObjectDictionary::check_download_start(std::uint16_t index, std::uint8_t sub, bool complete,
                                                AlState state, std::size_t size) const {
    const Object* o = find(index);
    if (!o) return SdoAbort::ObjectDoesNotExist;
    if (complete) return SdoAbort::None;  // sizes and access of a complete access are checked with the data
    const Entry* e = o->entry(sub);
    if (!e) return SdoAbort::SubindexDoesNotExist;
    if (!e->writable(state)) return (e->access() & acc::WriteAll) ? SdoAbort::WrongState : SdoAbort::ReadOnly;
    if (size > e->capacity()) return SdoAbort::LengthTooHigh;
    return SdoAbort::None;
}

SdoAbort ObjectDictionary::download(std::uint16_t index, std::uint8_t sub, bool complete, AlState state,
                                    ConstBytes data) {
    Object* o = find(index);
    if (!o) return SdoAbort::ObjectDoesNotExist;
    if (!complete) {
        Entry* e = o->entry(sub);
        if (!e) return SdoAbort::SubindexDoesNotExist;
        return download_entry(*e, state, data, true);
    }
    if (sub > 1) return SdoAbort::UnsupportedAccess;
    if (o->code() == ObjectCode::Var) return SdoAbort::UnsupportedAccess;
    return download_complete(*o, sub, state, data);
}

// Complete access download (ETG.1000.6 5.6.2.2): from subindex 0, the new subindex 0 value is in the data
// and the entries 1..n follow; from subindex 1, entries 1..current count. With a writable subindex 0 the
// sequence is the one ETG.1020 prescribes for PDO objects: subindex 0 := 0, entries, subindex 0 := n.
// If any entry is refused, every value is restored and the abort is returned.
SdoAbort ObjectDictionary::download_complete(Object& o, std::uint8_t sub, AlState state, ConstBytes data) {
    for (auto& e : o.entries())
        if (device::is_variable_length(e.type())) return SdoAbort::CompleteAccessNotSupported;
    Entry* s0 = o.entry(0);
    std::uint8_t last = o.complete_access_last();
    if (sub == 0) {
        if (data.empty()) return SdoAbort::LengthTooLow;
        if (data[0] > o.max_subindex()) return SdoAbort::ValueTooHigh;
        last = data[0];
    }
    const std::size_t need = complete_access_size(o, sub, last);
    if (data.size() < need) return SdoAbort::LengthTooLow;
    if (data.size() > complete_access_size(o, sub, o.max_subindex())) return SdoAbort::LengthTooHigh;
    const bool sub0_writable = sub == 0 && s0 && s0->writable(state);
    if (sub == 0 && s0 && !sub0_writable && data[0] != s0->as_uint64())
        return (s0->access() & acc::WriteAll) ? SdoAbort::WrongState : SdoAbort::ReadOnly;

    // Keep the old values for the undo.
    std::size_t undo_len = 0;
    for (auto& e : o.entries()) {
        std::copy_n(e.value().begin(), e.size(), undo_.begin() + static_cast<std::ptrdiff_t>(undo_len));
        undo_len += e.capacity();
    }
    auto restore = [&] {
        std::size_t off = 0;
        for (auto& e : o.entries()) {
            e.assign(ConstBytes(undo_.data() + off, e.size()));
            off += e.capacity();
        }
        for (auto& e : o.entries())
            e.run_after_download();
    };

    SdoAbort result = SdoAbort::None;
    const std::uint8_t zero = 0;
    if (sub0_writable) result = download_entry(*s0, state, ConstBytes(&zero, 1), true);
    std::uint8_t tmp[8];
    for_each_ca_entry(o, static_cast<std::uint8_t>(sub == 0 ? 1 : sub), last,
                      [&](const Entry& ce, std::size_t bit, unsigned bits) {
                          if (result != SdoAbort::None) return;
                          Entry& e = const_cast<Entry&>(ce);
                          // Offsets were computed from subindex 1: shift by sub 0's 16 bits if present.
                          const std::size_t at = bit + (sub == 0 ? 16 : 0);
                          const std::size_t nbytes = (bits + 7) / 8;
                          if (nbytes > sizeof tmp) {
                              result = SdoAbort::CompleteAccessNotSupported;
                              return;
                          }
                          std::fill_n(tmp, sizeof tmp, 0);
                          copy_bits(tmp, 0, data.data(), at, bits);
                          result = download_entry(e, state, ConstBytes(tmp, nbytes), true);
                      });
    if (result == SdoAbort::None && sub0_writable)
        result = download_entry(*s0, state, ConstBytes(&data[0], 1), true);
    if (result != SdoAbort::None) restore();
    return result;
}

}  // namespace vecat::coe
