// The runtime object dictionary: the objects of a device description with their current values, and the
// checked SDO access to them (access per AL state, lengths, value ranges, complete access).
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <span>
#include <type_traits>
#include <vector>

#include "coe/sdo_abort.hpp"
#include "common/bytes.hpp"
#include "device/object_description.hpp"
#include "esc/al_status.hpp"

namespace vecat::coe {

using device::DataType;
using device::ObjectCode;
using esc::AlState;

class Entry {
  public:
    explicit Entry(device::EntryDescription d);

    const device::EntryDescription& desc() const { return desc_; }
    std::uint8_t subindex() const { return desc_.subindex; }
    DataType type() const { return desc_.type; }
    unsigned bit_length() const { return desc_.bit_length; }
    std::uint16_t access() const { return desc_.access; }
    bool readable(AlState s) const;
    bool writable(AlState s) const;
    bool rx_mappable() const { return desc_.access & device::access::RxPdoMappable; }
    bool tx_mappable() const { return desc_.access & device::access::TxPdoMappable; }

    // Value storage: capacity() bytes; size() of them are the current value (shorter for strings).
    std::size_t capacity() const { return capacity_; }
    std::size_t size() const { return size_; }
    ConstBytes value() const { return ConstBytes(data(), size_); }
    Bytes storage() { return Bytes(data(), capacity_); }
    // Stores a value without any check or hook (the application's own writes). Longer input is cut.
    void assign(ConstBytes v);
    void reset_to_default();

    // Typed access for integers and reals of the entry's size (the device's own code).
    template <class T>
    T get() const {
        static_assert(std::is_arithmetic_v<T>);
        // The usual case, a value of the entry's size on a little-endian host, is one load (the drive reads
        // dozens of entries every servo step).
        if constexpr (std::endian::native == std::endian::little && !std::is_same_v<T, bool>)
            if (capacity_ >= sizeof(T)) {
                T v;
                std::memcpy(&v, data(), sizeof(T));
                return v;
            }
        std::uint64_t u = 0;
        const std::size_t n = std::min<std::size_t>(sizeof(T), capacity_);
        const std::uint8_t* d = data();
        for (std::size_t i = 0; i < n; ++i)
            u |= static_cast<std::uint64_t>(d[i]) << (8 * i);
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
        if constexpr (std::endian::native == std::endian::little)
            if (capacity_ >= sizeof(T)) {
                std::memcpy(data(), &v, sizeof(T));
                return;
            }
        std::uint64_t u = 0;
        std::memcpy(&u, &v, sizeof(T));
        const std::size_t n = std::min<std::size_t>(sizeof(T), capacity_);
        std::uint8_t* d = data();
        for (std::size_t i = 0; i < n; ++i)
            d[i] = static_cast<std::uint8_t>(u >> (8 * i));
    }
    // The value as a signed/unsigned integer of the entry's type (sign-extended for INTEGERn).
    std::int64_t as_int64() const;
    std::uint64_t as_uint64() const { return static_cast<std::uint64_t>(as_int64()); }

    // Hooks the device installs. on_download validates a value about to be written by SDO (it may
    // refuse with an abort code); after_download runs once it is stored; before_upload refreshes the value.
    std::function<SdoAbort(const Entry&, ConstBytes)> on_download;
    std::function<void(Entry&)> after_download;
    std::function<void(Entry&)> before_upload;

  private:
    // Values of up to 8 bytes (nearly every entry) live inside the Entry, the rest on the heap: a drive
    // reads and writes dozens of entries every servo step, and with a hundred drives in one process one
    // cache line per access instead of two (the Entry, then its value) is a good part of the cost.
    static constexpr std::size_t kInline = 8;
    std::uint8_t* data() { return capacity_ <= kInline ? inline_ : heap_.get(); }
    const std::uint8_t* data() const { return capacity_ <= kInline ? inline_ : heap_.get(); }

    std::uint32_t capacity_ = 0;
    std::uint32_t size_ = 0;
    alignas(8) std::uint8_t inline_[kInline] = {};
    std::unique_ptr<std::uint8_t[]> heap_;
    device::EntryDescription desc_;
};

class Object {
  public:
    explicit Object(const device::ObjectDescription& d);
    std::uint16_t index() const { return index_; }
    const std::string& name() const { return name_; }
    ObjectCode code() const { return code_; }
    DataType type() const { return type_; }
    std::uint8_t max_subindex() const { return max_sub_; }
    Entry* entry(std::uint8_t sub);
    const Entry* entry(std::uint8_t sub) const;
    std::vector<Entry>& entries() { return entries_; }
    const std::vector<Entry>& entries() const { return entries_; }
    // Subindexes a complete access covers: 1..value of subindex 0 for ARRAY/RECORD.
    std::uint8_t complete_access_last() const;

  private:
    std::uint16_t index_;
    std::string name_;
    ObjectCode code_;
    DataType type_;
    std::uint8_t max_sub_;
    std::vector<Entry> entries_;
};

class ObjectDictionary {
  public:
    explicit ObjectDictionary(const std::vector<device::ObjectDescription>& objects);

    Object* find(std::uint16_t index);
    const Object* find(std::uint16_t index) const;
    Entry* find(std::uint16_t index, std::uint8_t sub);
    std::vector<Object>& objects() { return objects_; }
    const std::vector<Object>& objects() const { return objects_; }
    // Largest value an upload can produce (complete access included): the size of transfer buffers.
    std::size_t max_transfer_size() const { return max_transfer_; }

    // SDO upload: writes the value into out, sets len. With complete access the object from sub (0 or 1).
    SdoAbort upload(std::uint16_t index, std::uint8_t sub, bool complete, AlState state, Bytes out,
                    std::size_t& len);
    // SDO download with every check (access, length, range, hooks).
    SdoAbort download(std::uint16_t index, std::uint8_t sub, bool complete, AlState state, ConstBytes data);
    // Checked before every SDO write of an entry (e.g. objects mapped into an active RxPDO).
    std::function<SdoAbort(const Entry&, AlState)> download_guard;

  private:
    SdoAbort download_entry(Entry& e, AlState state, ConstBytes data, bool run_after);
    SdoAbort download_complete(Object& o, std::uint8_t sub, AlState state, ConstBytes data);
    std::vector<Object> objects_;
    std::size_t max_transfer_ = 0;
    std::vector<std::uint8_t> undo_;  // previous values during a complete-access download
};

// Value checks against an entry's description (type size, range). Exposed for SDO info and tests.
SdoAbort check_length(const Entry& e, std::size_t len);
SdoAbort check_range(const Entry& e, ConstBytes v);
// Byte size of a complete access from `from` (0 or 1) over subindexes up to `last`.
std::size_t complete_access_size(const Object& o, std::uint8_t from, std::uint8_t last);

}  // namespace vecat::coe
