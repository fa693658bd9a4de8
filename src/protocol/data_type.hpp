// CoE base data types (ETG.1000.6 5.6.3.3, Table 64) and what the rest of the tree asks of them: bit
// length, signedness, the ESI spelling, and the C++ type a value of a fixed-size type is read as. The
// object catalogue (protocol/objects.hpp, protocol/cia402_objects.hpp) names each object's type with them.
#pragma once

#include <cstdint>
#include <string_view>
#include <type_traits>

namespace vecat::protocol {

enum class DataType : std::uint16_t {
    Boolean = 0x0001,
    Integer8 = 0x0002,
    Integer16 = 0x0003,
    Integer32 = 0x0004,
    Unsigned8 = 0x0005,
    Unsigned16 = 0x0006,
    Unsigned32 = 0x0007,
    Real32 = 0x0008,
    VisibleString = 0x0009,
    OctetString = 0x000A,
    UnicodeString = 0x000B,
    Domain = 0x000F,
    Integer24 = 0x0010,
    Real64 = 0x0011,
    Integer64 = 0x0015,
    Unsigned24 = 0x0016,
    Unsigned64 = 0x001B,
    // ETG.1020 structure types of the communication area.
    PdoMapping = 0x0021,
    Identity = 0x0023,
    SyncParameter = 0x0029,  // ETG.1000.6: record type of 0x1C32/0x1C33
};

// Bit length of a fixed-size base type; 0 for strings, domains and structures.
constexpr unsigned fixed_bit_length(DataType t) noexcept {
    switch (t) {
        case DataType::Boolean:
            return 1;
        case DataType::Integer8:
        case DataType::Unsigned8:
            return 8;
        case DataType::Integer16:
        case DataType::Unsigned16:
            return 16;
        case DataType::Integer24:
        case DataType::Unsigned24:
            return 24;
        case DataType::Integer32:
        case DataType::Unsigned32:
        case DataType::Real32:
            return 32;
        case DataType::Integer64:
        case DataType::Unsigned64:
        case DataType::Real64:
            return 64;
        default:
            return 0;
    }
}

constexpr bool is_signed(DataType t) noexcept {
    switch (t) {
        case DataType::Integer8:
        case DataType::Integer16:
        case DataType::Integer24:
        case DataType::Integer32:
        case DataType::Integer64:
            return true;
        default:
            return false;
    }
}

constexpr bool is_real(DataType t) noexcept {
    return t == DataType::Real32 || t == DataType::Real64;
}

// Strings, octet strings and domains: values whose length may be shorter than the entry's bit length.
constexpr bool is_variable_length(DataType t) noexcept {
    return t == DataType::VisibleString || t == DataType::OctetString || t == DataType::UnicodeString ||
           t == DataType::Domain;
}

// The ESI spelling: "UINT", "DINT", "STRING"...
constexpr std::string_view type_name(DataType t) noexcept {
    switch (t) {
        case DataType::Boolean:
            return "BOOL";
        case DataType::Integer8:
            return "SINT";
        case DataType::Integer16:
            return "INT";
        case DataType::Integer24:
            return "INT24";
        case DataType::Integer32:
            return "DINT";
        case DataType::Integer64:
            return "LINT";
        case DataType::Unsigned8:
            return "USINT";
        case DataType::Unsigned16:
            return "UINT";
        case DataType::Unsigned24:
            return "UINT24";
        case DataType::Unsigned32:
            return "UDINT";
        case DataType::Unsigned64:
            return "ULINT";
        case DataType::Real32:
            return "REAL";
        case DataType::Real64:
            return "LREAL";
        case DataType::VisibleString:
            return "STRING";
        case DataType::OctetString:
            return "OCTET_STRING";
        case DataType::UnicodeString:
            return "UNICODE_STRING";
        case DataType::Domain:
            return "DOMAIN";
        case DataType::PdoMapping:
            return "PDO_MAPPING";
        case DataType::Identity:
            return "IDENTITY";
        case DataType::SyncParameter:
            return "SYNC_PAR";
    }
    return "UNKNOWN";
}

// The C++ type that holds exactly a value of a fixed-size type (24-bit types have none: they are read
// through the wider type by hand). The one mapping between the two, used by the typed dictionary handles.
template <DataType T>
struct value_type_of {};
template <>
struct value_type_of<DataType::Boolean> {
    using type = bool;
};
template <>
struct value_type_of<DataType::Integer8> {
    using type = std::int8_t;
};
template <>
struct value_type_of<DataType::Integer16> {
    using type = std::int16_t;
};
template <>
struct value_type_of<DataType::Integer32> {
    using type = std::int32_t;
};
template <>
struct value_type_of<DataType::Integer64> {
    using type = std::int64_t;
};
template <>
struct value_type_of<DataType::Unsigned8> {
    using type = std::uint8_t;
};
template <>
struct value_type_of<DataType::Unsigned16> {
    using type = std::uint16_t;
};
template <>
struct value_type_of<DataType::Unsigned32> {
    using type = std::uint32_t;
};
template <>
struct value_type_of<DataType::Unsigned64> {
    using type = std::uint64_t;
};
template <>
struct value_type_of<DataType::Real32> {
    using type = float;
};
template <>
struct value_type_of<DataType::Real64> {
    using type = double;
};
template <DataType T>
using value_type_t = typename value_type_of<T>::type;

// Whether a value of C++ type V is exactly a value of data type t (width, signedness, integer or real):
// what a typed handle checks when it is bound to an entry.
template <class V>
constexpr bool holds(DataType t) noexcept {
    if constexpr (std::is_same_v<V, bool>)
        return t == DataType::Boolean;
    else if constexpr (std::is_floating_point_v<V>)
        return is_real(t) && fixed_bit_length(t) == 8 * sizeof(V);
    else if constexpr (std::is_integral_v<V>)
        return t != DataType::Boolean && !is_real(t) && fixed_bit_length(t) == 8 * sizeof(V) &&
               is_signed(t) == std::is_signed_v<V>;
    else
        return false;
}

}  // namespace vecat::protocol
