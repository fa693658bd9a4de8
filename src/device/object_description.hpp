// Object dictionary entries as described data (CiA 301 / ETG.1000.6 5.6.3): index, object code, and per
// sub-object the data type, bit length, access per AL state, PDO mappability, default, minimum, maximum
// and name. The runtime dictionary (src/coe), the SII and the ESI file are all generated from this.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/objects.hpp"

namespace vecat::device {

// CoE base data types (ETG.1000.6 Table 64) and their properties, from the protocol library.
using protocol::DataType;
using protocol::fixed_bit_length;
using protocol::is_real;
using protocol::is_signed;
using protocol::is_variable_length;
using protocol::type_name;

// Object code of the object description (ETG.1000.6 Table 46).
enum class ObjectCode : std::uint8_t {
    Domain = 0x02,
    DefType = 0x05,
    DefStruct = 0x06,
    Var = 0x07,
    Array = 0x08,
    Record = 0x09,
};

// Object access bits as reported in the SDO information entry description (ETG.1000.6 Table 47).
namespace access {
inline constexpr std::uint16_t ReadPreop = 0x0001;
inline constexpr std::uint16_t ReadSafeop = 0x0002;
inline constexpr std::uint16_t ReadOp = 0x0004;
inline constexpr std::uint16_t WritePreop = 0x0008;
inline constexpr std::uint16_t WriteSafeop = 0x0010;
inline constexpr std::uint16_t WriteOp = 0x0020;
inline constexpr std::uint16_t RxPdoMappable = 0x0040;
inline constexpr std::uint16_t TxPdoMappable = 0x0080;
inline constexpr std::uint16_t Backup = 0x0100;
inline constexpr std::uint16_t Settings = 0x0200;

inline constexpr std::uint16_t ReadAll = ReadPreop | ReadSafeop | ReadOp;
inline constexpr std::uint16_t WriteAll = WritePreop | WriteSafeop | WriteOp;
inline constexpr std::uint16_t RO = ReadAll;                    // read only in every state
inline constexpr std::uint16_t RW = ReadAll | WriteAll;         // read/write in every state
inline constexpr std::uint16_t RWPreop = ReadAll | WritePreop;  // writable in PREOP only
inline constexpr std::uint16_t RxMap = RW | RxPdoMappable;      // typical RxPDO-mappable parameter
inline constexpr std::uint16_t TxMap = RO | TxPdoMappable;      // typical TxPDO-mappable actual value
}  // namespace access

struct EntryDescription {
    std::uint8_t subindex = 0;
    std::string name;
    DataType type = DataType::Unsigned8;
    std::uint16_t bit_length = 8;  // for strings and domains: the maximum length
    std::uint16_t access = access::RO;
    // Values in their little-endian wire encoding (strings: the characters). Empty: none.
    std::vector<std::uint8_t> default_value;
    std::vector<std::uint8_t> minimum;
    std::vector<std::uint8_t> maximum;

    bool readable_in_some_state() const { return (access & access::ReadAll) != 0; }
};

struct ObjectDescription {
    std::uint16_t index = 0;
    std::string name;
    ObjectCode code = ObjectCode::Var;
    DataType type = DataType::Unsigned8;    // object data type shown by SDO information (ARRAY: element type)
    std::vector<EntryDescription> entries;  // VAR: exactly subindex 0; ARRAY/RECORD: subindex 0 (count) first
    // The max subindex SDO information reports when it is not the last entry's: a dictionary read from a
    // device whose description of some subindexes could not be read (network/dictionary_file.hpp).
    std::optional<std::uint8_t> declared_max_subindex;

    std::uint8_t max_subindex() const {
        if (declared_max_subindex) return *declared_max_subindex;
        return entries.empty() ? 0 : entries.back().subindex;
    }
    const EntryDescription* entry(std::uint8_t sub) const {
        for (const auto& e : entries)
            if (e.subindex == sub) return &e;
        return nullptr;
    }
};

// Little-endian encoding of an integer value of a fixed-size type.
std::vector<std::uint8_t> encode_integer(DataType t, std::int64_t v);
std::vector<std::uint8_t> encode_real(DataType t, double v);

// Builders for the common shapes.
EntryDescription make_entry(std::uint8_t sub, std::string name, DataType t, std::uint16_t access,
                            std::int64_t default_value = 0);
EntryDescription make_string_entry(std::uint8_t sub, std::string name, std::string_view text,
                                   std::uint16_t access = access::RO);
ObjectDescription make_var(std::uint16_t index, std::string name, DataType t, std::uint16_t access,
                           std::int64_t default_value = 0);
ObjectDescription make_string_var(std::uint16_t index, std::string name, std::string_view text);
// A VAR of a catalogue object: index and type from the catalogue (protocol/objects.hpp).
template <DataType T>
ObjectDescription make_var(protocol::ObjectId<T> id, std::string name, std::uint16_t access,
                           std::int64_t default_value = 0) {
    static_assert(fixed_bit_length(T) > 0, "a VAR of a fixed-size type");
    return make_var(id.index, std::move(name), T, access, default_value);
}
// An entry of a catalogue record: subindex and type from the catalogue.
template <DataType T>
EntryDescription make_entry(protocol::ObjectId<T> id, std::string name, std::uint16_t access,
                            std::int64_t default_value = 0) {
    return make_entry(id.subindex, std::move(name), T, access, default_value);
}
// A RECORD whose subindex 0 (U8, read-only) holds the highest subindex.
ObjectDescription make_record(std::uint16_t index, std::string name, std::vector<EntryDescription> subs,
                              DataType struct_type = DataType::Unsigned8);
// An ARRAY of n elements of one type; subindex 0 (U8) has sub0_access.
ObjectDescription make_array(std::uint16_t index, std::string name, DataType element, std::uint16_t access,
                             std::vector<std::int64_t> defaults, std::uint16_t sub0_access = access::RO);

// "SubIndex 001": the name given to array elements and mapping entries.
std::string subindex_name(unsigned sub);

// Sets minimum and maximum of an entry from integers (encoded in the entry's type).
void set_range(EntryDescription& e, std::int64_t min, std::int64_t max);
// A VAR of a catalogue object with its value range.
template <DataType T>
ObjectDescription make_ranged_var(protocol::ObjectId<T> id, std::string name, std::uint16_t access,
                                  std::int64_t default_value, std::int64_t min, std::int64_t max) {
    auto o = make_var(id, std::move(name), access, default_value);
    set_range(o.entries[0], min, max);
    return o;
}

}  // namespace vecat::device
