// The runtime object dictionary: the objects of a device description with their current values, and the
// checked SDO access to them (access per AL state, lengths, value ranges, complete access).
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "common/bytes.hpp"
#include "device/object_description.hpp"
#include "protocol/al_status.hpp"
#include "protocol/objects.hpp"
#include "protocol/sdo_abort.hpp"

namespace vecat::coe {

using device::DataType;
using device::ObjectCode;
using protocol::AlState;
using protocol::SdoAbort;

// An entry refers to its description, which the dictionary keeps (shared by every dictionary built from
// the same descriptions: a segment of many drives, or a fuzz target building a drive per input, does not
// copy names, defaults and ranges per entry), and keeps its value in the dictionary's one value buffer
// (a dictionary is a handful of allocations, not one per entry). Not copyable: a copy would share the value.
class Entry;

// Hooks the device installs on an entry. on_download validates a value about to be written by SDO (it may
// refuse with an abort code); after_download runs once it is stored; before_upload refreshes the value.
struct EntryHooks {
    std::function<SdoAbort(const Entry&, ConstBytes)> on_download;
    std::function<void(Entry&)> after_download;
    std::function<void(Entry&)> before_upload;
    // Incremented on every write through Entry::set or Entry::assign (SDO downloads, tools, tests), not by
    // the device's own writes through a coe::Value: the device can tell that none of its parameters changed
    // without reading them (cia402::Drive). Process data outputs are counted by the ProcessDataMap
    // (outputs_changed()).
    std::uint32_t* writes = nullptr;
};

class Entry {
  public:
    // storage: storage_size(d) bytes that outlive the entry; the value starts at the default.
    Entry(const device::EntryDescription& d, Bytes storage);
    // The same with storage that already holds the value, `size` bytes of it current.
    Entry(const device::EntryDescription& d, Bytes storage, std::size_t size)
        : desc_(&d), storage_(storage), size_(size) {}
    Entry(const Entry&) = delete;
    Entry& operator=(const Entry&) = delete;
    Entry(Entry&&) = default;
    Entry& operator=(Entry&&) = default;
    static std::size_t storage_size(const device::EntryDescription& d) {
        return std::max<std::size_t>(1, (d.bit_length + 7u) / 8u);
    }

    const device::EntryDescription& desc() const { return *desc_; }
    std::uint8_t subindex() const { return desc_->subindex; }
    DataType type() const { return desc_->type; }
    unsigned bit_length() const { return desc_->bit_length; }
    std::uint16_t access() const { return desc_->access; }
    bool readable(AlState s) const;
    bool writable(AlState s) const;
    bool rx_mappable() const { return desc_->access & device::access::RxPdoMappable; }
    bool tx_mappable() const { return desc_->access & device::access::TxPdoMappable; }

    // Value storage: capacity() bytes; size() of them are the current value (shorter for strings).
    std::size_t capacity() const { return storage_.size(); }
    std::size_t size() const { return size_; }
    ConstBytes value() const { return ConstBytes(storage_.data(), size_); }
    Bytes storage() { return Bytes(storage_.data(), storage_.size()); }
    // Stores a value without any check or hook (the application's own writes). Longer input is cut.
    void assign(ConstBytes v);
    void reset_to_default();

    // Untyped access: any integer or real, cut or zero-extended to the entry's size (tests and tools; the
    // device's own code reads its objects through typed handles, coe::Value below).
    template <class T>
    T get() const {
        static_assert(std::is_arithmetic_v<T>);
        // The usual case, a value of the entry's size on a little-endian host, is one load (the drive reads
        // dozens of entries every servo step).
        if constexpr (std::endian::native == std::endian::little && !std::is_same_v<T, bool>)
            if (storage_.size() >= sizeof(T)) {
                T v;
                std::memcpy(&v, storage_.data(), sizeof(T));
                return v;
            }
        std::uint64_t u = 0;
        const std::size_t n = std::min(sizeof(T), storage_.size());
        for (std::size_t i = 0; i < n; ++i)
            u |= static_cast<std::uint64_t>(storage_[i]) << (8 * i);
        if constexpr (std::is_floating_point_v<T>) {
            T v{};
            std::memcpy(&v, &u, sizeof(T));
            return v;
        } else {
            return static_cast<T>(u);
        }
    }
    template <class T>
    void set(T v) {
        static_assert(std::is_arithmetic_v<T>);
        touch();
        if constexpr (std::endian::native == std::endian::little)
            if (storage_.size() >= sizeof(T)) {
                std::memcpy(storage_.data(), &v, sizeof(T));
                return;
            }
        std::uint64_t u = 0;
        std::memcpy(&u, &v, sizeof(T));
        const std::size_t n = std::min(sizeof(T), storage_.size());
        for (std::size_t i = 0; i < n; ++i)
            storage_[i] = static_cast<std::uint8_t>(u >> (8 * i));
    }
    // The value as a signed/unsigned integer of the entry's type (sign-extended for INTEGERn).
    std::int64_t as_int64() const;
    std::uint64_t as_uint64() const { return static_cast<std::uint64_t>(as_int64()); }

    // The entry's hooks (see EntryHooks), made on first use: few entries have any, and an entry without
    // stays small (the drive reads and writes dozens of entries per servo step, of many drives).
    EntryHooks& hooks() {
        if (!hooks_) hooks_ = std::make_unique<EntryHooks>();
        return *hooks_;
    }
    // The hooks' calls; none installed: no refusal, nothing to do.
    SdoAbort check_download(ConstBytes v) const {
        return hooks_ && hooks_->on_download ? hooks_->on_download(*this, v) : SdoAbort::None;
    }
    void run_after_download() {
        if (hooks_ && hooks_->after_download) hooks_->after_download(*this);
    }
    // Counts a write in the watching counter (EntryHooks::writes), if any.
    void touch() {
        if (hooks_ && hooks_->writes) ++*hooks_->writes;
    }
    void run_before_upload() {
        if (hooks_ && hooks_->before_upload) hooks_->before_upload(*this);
    }

  private:
    const device::EntryDescription* desc_;
    Bytes storage_;
    std::size_t size_ = 0;
    std::unique_ptr<EntryHooks> hooks_;
};

// Refers to its description like Entry; its entries lie in the dictionary.
class Object {
  public:
    Object(const device::ObjectDescription& d, std::span<Entry> entries);
    Object(const Object&) = delete;
    Object& operator=(const Object&) = delete;
    Object(Object&&) = default;
    Object& operator=(Object&&) = default;
    std::uint16_t index() const { return index_; }
    const std::string& name() const { return desc_->name; }
    ObjectCode code() const { return code_; }
    DataType type() const { return type_; }
    std::uint8_t max_subindex() const { return max_sub_; }
    Entry* entry(std::uint8_t sub);
    const Entry* entry(std::uint8_t sub) const;
    std::span<Entry> entries() { return entries_; }
    std::span<const Entry> entries() const { return entries_; }
    // Subindexes a complete access covers: 1..value of subindex 0 for ARRAY/RECORD.
    std::uint8_t complete_access_last() const;

  private:
    const device::ObjectDescription* desc_;
    std::uint16_t index_;
    ObjectCode code_;
    DataType type_;
    std::uint8_t max_sub_;
    std::span<Entry> entries_;
};

class ObjectDictionary {
  public:
    explicit ObjectDictionary(std::vector<device::ObjectDescription> objects);
    // Values start at the defaults of descriptions shared with other dictionaries (built once per device).
    explicit ObjectDictionary(std::shared_ptr<const std::vector<device::ObjectDescription>> objects);
    // Objects and entries point into the dictionary's buffers: moving keeps them, a copy could not.
    ObjectDictionary(const ObjectDictionary&) = delete;
    ObjectDictionary& operator=(const ObjectDictionary&) = delete;
    ObjectDictionary(ObjectDictionary&&) = default;
    ~ObjectDictionary();
    ObjectDictionary& operator=(ObjectDictionary&&) = default;

    Object* find(std::uint16_t index);
    const Object* find(std::uint16_t index) const;
    Entry* find(std::uint16_t index, std::uint8_t sub);
    const Entry* find(std::uint16_t index, std::uint8_t sub) const;
    // A catalogue entry (protocol/objects.hpp) by its index and subindex.
    Entry* find(protocol::ObjectRef r) { return find(r.index, r.subindex); }
    const Entry* find(protocol::ObjectRef r) const { return find(r.index, r.subindex); }
    std::vector<Object>& objects() { return objects_; }
    const std::vector<Object>& objects() const { return objects_; }
    // Largest value an upload can produce (complete access included): the size of transfer buffers.
    std::size_t max_transfer_size() const { return max_transfer_; }

    // SDO upload: writes the value into out, sets len. With complete access the object from sub (0 or 1).
    SdoAbort upload(std::uint16_t index, std::uint8_t sub, bool complete, AlState state, Bytes out,
                    std::size_t& len);
    // SDO download with every check (access, length, range, hooks).
    SdoAbort download(std::uint16_t index, std::uint8_t sub, bool complete, AlState state, ConstBytes data);
    // What a download of `size` bytes is refused for before its data is there (a segmented download is
    // refused at its start, so that no segment is taken for it): the object, the subindex, the access in
    // this state and the size. The value checks come with download().
    SdoAbort check_download_start(std::uint16_t index, std::uint8_t sub, bool complete, AlState state,
                                  std::size_t size) const;
    // Checked before every SDO write of an entry (e.g. objects mapped into an active RxPDO).
    std::function<SdoAbort(const Entry&, AlState)> download_guard;

  private:
    // What every dictionary of the same descriptions starts from, computed once (see layout_of()).
    struct Layout;
    static std::shared_ptr<const Layout> layout_of(
        const std::shared_ptr<const std::vector<device::ObjectDescription>>& descriptions);
    static Layout make_layout(const std::vector<device::ObjectDescription>& descriptions);
    SdoAbort download_entry(Entry& e, AlState state, ConstBytes data, bool run_after);
    SdoAbort download_complete(Object& o, std::uint8_t sub, AlState state, ConstBytes data);
    std::shared_ptr<const std::vector<device::ObjectDescription>> descriptions_;
    std::vector<std::uint8_t> values_;  // every entry's storage
    std::vector<Entry> entries_;        // every object's entries, object after object
    std::vector<Object> objects_;       // sorted by index
    std::size_t max_transfer_ = 0;
    std::vector<std::uint8_t> undo_;  // previous values during a complete-access download
};

// How strictly a handle's type must match its entry's data type when it is bound.
enum class Match : std::uint8_t {
    Exact,      // the same width, signedness and kind (integer, real, boolean)
    SameWidth,  // the same width and kind, either signedness: a vendor's dictionary (ESI) that declares a
                // profile object with the other signedness (DINT digital inputs) is read bit for bit
    Convert,    // any type, as Entry::get/set read and write it (the little-endian bytes, zero-extended or
                // cut): for vendors' dictionaries that give a profile object another type (USINT for UDINT,
                // REAL for DINT). Such a handle takes the slower untyped path; one of the right type the
                // fast one.
};

// Whether an entry of data type t can be bound as a value of C++ type V.
template <class V>
constexpr bool binds_as(DataType t, Match m) noexcept {
    if (protocol::holds<V>(t)) return true;
    if (m == Match::Convert) return true;
    if (m == Match::Exact || !std::is_integral_v<V> || std::is_same_v<V, bool>) return false;
    return t != DataType::Boolean && !device::is_real(t) && device::fixed_bit_length(t) == 8 * sizeof(V);
}

// A typed handle on one entry, in the spirit of typed object access (lely-core's Read<T>): bound once, when
// the device is built, and checked then against the entry's data type (a handle of std::int32_t binds only
// to an INTEGER32 entry: a wrong width or signedness throws std::invalid_argument at bind time, never a
// silent cut in the cycle). get() and set() then are one load and one store, without check, lock or
// allocation. A handle of an object the dictionary does not have (a vendor ESI without it) is unbound:
// get_or() gives the fallback and set() does nothing.
template <class T>
class Value {
  public:
    static_assert(std::is_arithmetic_v<T>);
    Value() = default;
    // e: the entry (nullptr: unbound).
    explicit Value(Entry* e, Match m = Match::Exact) : entry_(e) {
        if (!e) return;
        if (!binds_as<T>(e->type(), m))
            throw std::invalid_argument("entry of type " + std::string(device::type_name(e->type())) +
                                        " bound as a value of " + std::to_string(8 * sizeof(T)) + " bits" +
                                        (std::is_signed_v<T> ? " (signed)" : ""));
        // Loads and stores straight into the storage when the value is T's own little-endian bytes.
        if (binds_as<T>(e->type(), Match::SameWidth) && std::endian::native == std::endian::little)
            data_ = e->storage().data();
    }

    bool bound() const { return entry_ != nullptr; }
    // Bound with Match::Convert to an entry of another type.
    bool converts() const { return entry_ && !binds_as<T>(entry_->type(), Match::SameWidth); }
    Entry* entry() const { return entry_; }
    // The value; the handle must be bound.
    T get() const {
        if (!data_) [[unlikely]]
            return entry_->get<T>();
        if constexpr (std::is_same_v<T, bool>) {
            return (data_[0] & 1u) != 0;
        } else {
            T v;
            std::memcpy(&v, data_, sizeof(T));
            return v;
        }
    }
    T get_or(T fallback) const { return entry_ ? get() : fallback; }
    // Stores the value without check or hook (the device's own write); nothing when unbound.
    void set(T v) {
        if (data_) [[likely]] {
            if constexpr (std::is_same_v<T, bool>)
                data_[0] = v ? 1 : 0;
            else
                std::memcpy(data_, &v, sizeof(T));
        } else if (entry_) {
            entry_->set(v);
        }
    }

  private:
    // Two pointers, no more: a drive's cycle reads dozens of handles, and each line of them it reads is a
    // cache miss on a line of hundreds of drives.
    Entry* entry_ = nullptr;
    std::uint8_t* data_ = nullptr;  // the storage, when get() and set() may load and store it as a T
};

// Binds a handle to a catalogue entry: its C++ type is the catalogue's data type (protocol/objects.hpp).
template <DataType T>
Value<protocol::value_type_t<T>> bind(ObjectDictionary& od, protocol::ObjectId<T> id,
                                      Match m = Match::Exact) {
    return Value<protocol::value_type_t<T>>(od.find(id.index, id.subindex), m);
}
// Binds a handle of type V to an entry found at run time (checked as Value's constructor does).
template <class V>
Value<V> bind(ObjectDictionary& od, std::uint16_t index, std::uint8_t sub = 0, Match m = Match::Exact) {
    return Value<V>(od.find(index, sub), m);
}

// Value checks against an entry's description (type size, range). Exposed for SDO info and tests.
SdoAbort check_length(const Entry& e, std::size_t len);
SdoAbort check_range(const Entry& e, ConstBytes v);
// Byte size of a complete access from `from` (0 or 1) over subindexes up to `last`.
std::size_t complete_access_size(const Object& o, std::uint8_t from, std::uint8_t last);

}  // namespace vecat::coe
