// The runtime object dictionary (src/coe/object_dictionary): built from the device description, typed
// values, length and range checks, SDO access per AL state, complete access layout and its undo.
// Long (about 660 lines): one dictionary fixture for every access rule.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include <string>
#include <tuple>
#include <vector>

#include "coe/object_dictionary.hpp"
#include "device/device_description.hpp"
#include "protocol/cia402_objects.hpp"

namespace obj = vecat::protocol::obj;

using namespace vecat;
using namespace vecat::coe;
using protocol::AlState;
namespace acc = device::access;

namespace {

using Buf = std::vector<std::uint8_t>;

ConstBytes cb(const Buf& b) {
    return ConstBytes(b.data(), b.size());
}

Buf value_of(const Entry& e) {
    return Buf(e.value().begin(), e.value().end());
}

// A dictionary of the default drive, built the way CoeApplication builds it (without the PDO hooks).
struct DefaultDictionary : ::testing::Test {
    DefaultDictionary() : desc(device::default_drive()), od(device::dictionary_objects(desc)) {}
    device::DeviceDescription desc;
    ObjectDictionary od;
};

}  // namespace

// ---- construction from the device description ----

TEST_F(DefaultDictionary, EveryDescribedObjectAndEntryIsFound) {
    const auto objects = device::dictionary_objects(desc);
    ASSERT_FALSE(objects.empty());
    EXPECT_EQ(od.objects().size(), objects.size());
    for (const auto& d : objects) {
        const Object* o = od.find(d.index);
        ASSERT_NE(o, nullptr) << std::hex << d.index;
        EXPECT_EQ(o->index(), d.index);
        EXPECT_EQ(o->name(), d.name) << std::hex << d.index;
        EXPECT_EQ(o->code(), d.code) << std::hex << d.index;
        EXPECT_EQ(o->type(), d.type) << std::hex << d.index;
        EXPECT_EQ(o->max_subindex(), d.max_subindex()) << std::hex << d.index;
        ASSERT_EQ(o->entries().size(), d.entries.size()) << std::hex << d.index;
        for (const auto& ed : d.entries) {
            Entry* e = od.find(d.index, ed.subindex);
            ASSERT_NE(e, nullptr) << std::hex << d.index << ":" << unsigned{ed.subindex};
            EXPECT_EQ(e->bit_length(), ed.bit_length);
            EXPECT_EQ(e->type(), ed.type);
            EXPECT_EQ(e->access(), ed.access);
            // The initial value is the default (fixed types: zero-extended to the entry size).
            Buf want = ed.default_value;
            if (!device::is_variable_length(ed.type)) want.resize((ed.bit_length + 7u) / 8u, 0);
            EXPECT_EQ(value_of(*e), want) << std::hex << d.index << ":" << unsigned{ed.subindex};
        }
    }
}

// Typed handles: bound once against the entry's data type, then plain loads and stores.
TEST_F(DefaultDictionary, TypedHandlesCheckTheEntryTypeWhenTheyAreBound) {
    auto cw = coe::bind(od, obj::controlword);  // UNSIGNED16: a Value<std::uint16_t>
    static_assert(std::is_same_v<decltype(cw), coe::Value<std::uint16_t>>);
    ASSERT_TRUE(cw.bound());
    cw.set(0x1234);
    EXPECT_EQ(od.find(obj::controlword)->get<std::uint16_t>(), 0x1234);
    EXPECT_EQ(cw.get(), 0x1234);
    auto limit = coe::bind(od, obj::software_position_limit::min);  // INTEGER32, subindex 1
    EXPECT_EQ(limit.get(), std::numeric_limits<std::int32_t>::min());
    // Wrong width or signedness: refused when bound, not cut at every access.
    EXPECT_THROW(coe::bind<std::int32_t>(od, obj::profile_velocity.index), std::invalid_argument);
    EXPECT_THROW(coe::bind<std::uint8_t>(od, obj::controlword.index), std::invalid_argument);
    EXPECT_THROW(coe::bind<float>(od, obj::target_position.index), std::invalid_argument);
    // The same width with the other signedness only when asked (a vendor's dictionary).
    EXPECT_NO_THROW(coe::bind<std::int32_t>(od, obj::profile_velocity.index, 0, coe::Match::SameWidth));
    auto conv = coe::bind<std::uint32_t>(od, obj::controlword.index, 0, coe::Match::Convert);
    EXPECT_TRUE(conv.converts());
    EXPECT_EQ(conv.get(), 0x1234u);
    // An object the dictionary does not have: unbound, the fallback, writes go nowhere.
    coe::Value<std::uint16_t> none = coe::bind<std::uint16_t>(od, 0x5FFF);
    EXPECT_FALSE(none.bound());
    EXPECT_EQ(none.get_or(7), 7);
    none.set(1);
}

TEST_F(DefaultDictionary, CommunicationAreaObjectsExist) {
    for (int i : {0x1000, 0x1001, 0x1008, 0x1009, 0x100A, 0x1018, 0x10F1, 0x1600, 0x1601, 0x1602,
                  0x1603, 0x1A00, 0x1A01, 0x1A02, 0x1A03, 0x1C00, 0x1C12, 0x1C13, 0x1C32, 0x1C33})
        EXPECT_NE(od.find(static_cast<std::uint16_t>(i)), nullptr) << std::hex << i;
}

TEST_F(DefaultDictionary, UnknownIndexOrSubindexIsNotFound) {
    EXPECT_EQ(od.find(0x1234), nullptr);
    EXPECT_EQ(od.find(0x0000), nullptr);
    EXPECT_EQ(od.find(0xFFFF), nullptr);
    EXPECT_EQ(od.find(0x1018, 5), nullptr);
    EXPECT_EQ(od.find(obj::controlword.index, 1), nullptr);
    // 0x1C32 has subindexes 0..13 and 32: the ones in between do not exist.
    EXPECT_NE(od.find(0x1C32, 13), nullptr);
    EXPECT_EQ(od.find(0x1C32, 14), nullptr);
    EXPECT_EQ(od.find(0x1C32, 31), nullptr);
    EXPECT_NE(od.find(0x1C32, 32), nullptr);
}

TEST_F(DefaultDictionary, ObjectsAreSortedByIndex) {
    const auto& objs = od.objects();
    for (std::size_t i = 1; i < objs.size(); ++i)
        EXPECT_LT(objs[i - 1].index(), objs[i].index()) << i;
}

TEST_F(DefaultDictionary, VarObjectsHaveSubindexZeroOnly) {
    unsigned vars = 0;
    for (const auto& o : od.objects()) {
        if (o.code() != ObjectCode::Var) continue;
        ++vars;
        ASSERT_EQ(o.entries().size(), 1u) << std::hex << o.index();
        EXPECT_EQ(o.entries()[0].subindex(), 0) << std::hex << o.index();
        EXPECT_EQ(o.max_subindex(), 0) << std::hex << o.index();
        EXPECT_EQ(o.complete_access_last(), 0) << std::hex << o.index();
    }
    EXPECT_GT(vars, 50u);
}

TEST_F(DefaultDictionary, ArraysAndRecordsStartWithTheirCount) {
    for (const auto& o : od.objects()) {
        if (o.code() == ObjectCode::Var) continue;
        const Entry* s0 = o.entry(0);
        ASSERT_NE(s0, nullptr) << std::hex << o.index();
        EXPECT_EQ(s0->type(), DataType::Unsigned8) << std::hex << o.index();
        EXPECT_LE(s0->as_uint64(), o.max_subindex()) << std::hex << o.index();
    }
}

TEST_F(DefaultDictionary, SyncManagerTypesMatchTheLayout) {
    // 0x1C00: one U8 per SyncManager: mailbox out (1), mailbox in (2), outputs (3), inputs (4).
    const Object* o = od.find(0x1C00);
    ASSERT_NE(o, nullptr);
    EXPECT_EQ(o->code(), ObjectCode::Array);
    EXPECT_EQ(od.find(0x1C00, 0)->as_uint64(), 4u);
    for (std::uint8_t i = 1; i <= 4; ++i) {
        ASSERT_NE(od.find(0x1C00, i), nullptr);
        EXPECT_EQ(od.find(0x1C00, i)->as_uint64(), i);
        EXPECT_EQ(od.find(0x1C00, i)->as_uint64(), static_cast<unsigned>(desc.sync_managers[i - 1u].type));
        EXPECT_FALSE(od.find(0x1C00, i)->writable(AlState::PreOp));
    }
}

TEST_F(DefaultDictionary, PdoAssignmentDefaultsAreTheAssignedPdos) {
    // Only the first RxPDO and TxPDO are assigned by default; the other slots are zero.
    for (auto [index, pdos, first] :
         {std::tuple{0x1C12, &desc.rx_pdos, 0x1600}, std::tuple{0x1C13, &desc.tx_pdos, 0x1A00}}) {
        SCOPED_TRACE(index);
        const auto idx = static_cast<std::uint16_t>(index);
        std::vector<std::uint16_t> assigned;
        for (const auto& p : *pdos)
            if (p.assigned) assigned.push_back(p.index);
        ASSERT_EQ(assigned, std::vector<std::uint16_t>{static_cast<std::uint16_t>(first)});
        const Object* o = od.find(idx);
        ASSERT_NE(o, nullptr);
        EXPECT_EQ(o->code(), ObjectCode::Array);
        EXPECT_EQ(o->type(), DataType::Unsigned16);
        EXPECT_EQ(o->max_subindex(), pdos->size());
        EXPECT_EQ(od.find(idx, 0)->as_uint64(), 1u);
        EXPECT_EQ(od.find(idx, 1)->get<std::uint16_t>(), first);
        for (std::uint8_t s = 2; s <= o->max_subindex(); ++s)
            EXPECT_EQ(od.find(idx, s)->get<std::uint16_t>(), 0u) << unsigned{s};
        // Writable in PREOP only (ETG.1020: the assignment is changed in PREOP).
        EXPECT_TRUE(od.find(idx, 0)->writable(AlState::PreOp));
        EXPECT_FALSE(od.find(idx, 0)->writable(AlState::SafeOp));
        EXPECT_FALSE(od.find(idx, 0)->writable(AlState::Op));
        EXPECT_TRUE(od.find(idx, 0)->readable(AlState::Op));
    }
}

TEST_F(DefaultDictionary, PdoMappingObjectsHoldTheDescribedEntries) {
    for (const auto* list : {&desc.rx_pdos, &desc.tx_pdos}) {
        for (const auto& p : *list) {
            SCOPED_TRACE(p.index);
            const Object* o = od.find(p.index);
            ASSERT_NE(o, nullptr);
            EXPECT_EQ(o->type(), DataType::PdoMapping);
            EXPECT_EQ(o->max_subindex(), p.capacity);
            EXPECT_EQ(od.find(p.index, 0)->as_uint64(), p.entries.size());
            for (std::size_t i = 0; i < p.capacity; ++i) {
                const auto sub = static_cast<std::uint8_t>(i + 1);
                std::uint32_t want = 0;
                if (i < p.entries.size())
                    want = (std::uint32_t{p.entries[i].index} << 16) |
                           (std::uint32_t{p.entries[i].subindex} << 8) | p.entries[i].bit_length;
                EXPECT_EQ(od.find(p.index, sub)->get<std::uint32_t>(), want) << unsigned{sub};
            }
        }
    }
    // Spot check against the wire values: controlword, 16 bits.
    EXPECT_EQ(od.find(0x1600, 1)->get<std::uint32_t>(), 0x60400010u);
    EXPECT_EQ(od.find(0x1600, 3)->get<std::uint32_t>(), 0x00000008u);  // the 8-bit gap
    EXPECT_EQ(od.find(0x1A00, 1)->get<std::uint32_t>(), 0x60410010u);
}

// The values a cycle copies lie together in the value storage (ObjectDictionary::make_layout): those the PDO
// mappings map by default first, then the other PDO-mappable ones, then the rest; strings and parameters
// never lie between two of them.
TEST_F(DefaultDictionary, DefaultMappedValuesLieBeforeEveryOtherValue) {
    // mapped: by default; tx_mappable, rx_mappable: the other PDO-mappable ones; others: the rest.
    std::vector<const std::uint8_t*> mapped, tx_mappable, rx_mappable, others;
    std::vector<std::pair<std::uint16_t, std::uint8_t>> by_default;
    for (const auto* list : {&desc.rx_pdos, &desc.tx_pdos})
        for (const auto& p : *list)
            for (const auto& e : p.entries)
                if (e.index != 0) by_default.emplace_back(e.index, e.subindex);
    std::sort(by_default.begin(), by_default.end());  // (several PDOs may map one entry)
    by_default.erase(std::unique(by_default.begin(), by_default.end()), by_default.end());
    ASSERT_GE(by_default.size(), 4u);
    for (const Object& o : od.objects())
        for (const Entry& e : o.entries()) {
            const std::uint8_t* at = e.value().data();  // (its storage)
            if (std::find(by_default.begin(), by_default.end(), std::pair{o.index(), e.subindex()}) !=
                by_default.end())
                mapped.push_back(at);
            else if (e.tx_mappable())
                tx_mappable.push_back(at);
            else if (e.rx_mappable())
                rx_mappable.push_back(at);
            else
                others.push_back(at);
        }
    ASSERT_EQ(mapped.size(), by_default.size());
    ASSERT_FALSE(tx_mappable.empty());
    ASSERT_FALSE(rx_mappable.empty());
    ASSERT_FALSE(others.empty());
    const auto first = [](const auto& v) { return *std::min_element(v.begin(), v.end()); };
    const auto last = [](const auto& v) { return *std::max_element(v.begin(), v.end()); };
    // Each group wholly before the next: nothing lies between two default-mapped values.
    EXPECT_LT(last(mapped), first(tx_mappable));
    EXPECT_LT(last(tx_mappable), first(rx_mappable));
    EXPECT_LT(last(rx_mappable), first(others));
}

TEST_F(DefaultDictionary, IdentityAndDeviceNameComeFromTheDescription) {
    EXPECT_EQ(od.find(0x1018, 0)->as_uint64(), 4u);
    EXPECT_EQ(od.find(0x1018, 1)->get<std::uint32_t>(), 0x00000A3Cu);
    EXPECT_EQ(od.find(0x1018, 2)->get<std::uint32_t>(), desc.identity.product_code);
    EXPECT_EQ(od.find(0x1018, 3)->get<std::uint32_t>(), desc.identity.revision);
    EXPECT_EQ(od.find(0x1018, 4)->get<std::uint32_t>(), desc.identity.serial);
    EXPECT_EQ(od.find(0x1000, 0)->get<std::uint32_t>(), 0x00020192u);
    const Entry* name = od.find(0x1008, 0);
    ASSERT_NE(name, nullptr);
    EXPECT_EQ(std::string(name->value().begin(), name->value().end()), "vecat CiA402 servo drive");
    EXPECT_EQ(name->size(), desc.name.size());
}

// ---- typed values ----

TEST_F(DefaultDictionary, AsInt64SignExtendsSignedTypesOnly) {
    Entry& i8 = *od.find(obj::modes_of_operation);  // INTEGER8
    i8.set(std::uint8_t{0xF6});
    EXPECT_EQ(i8.as_int64(), -10);
    i8.set(std::int8_t{127});
    EXPECT_EQ(i8.as_int64(), 127);
    i8.set(std::uint8_t{0x80});
    EXPECT_EQ(i8.as_int64(), -128);

    Entry& i16 = *od.find(obj::quick_stop_option_code);  // INTEGER16
    i16.set(std::uint16_t{0xFFFE});
    EXPECT_EQ(i16.as_int64(), -2);
    i16.set(std::uint16_t{0x7FFF});
    EXPECT_EQ(i16.as_int64(), 32767);
    i16.set(std::uint16_t{0x8000});
    EXPECT_EQ(i16.as_int64(), -32768);

    Entry& i32 = *od.find(obj::target_position);  // INTEGER32
    i32.set(std::int32_t{-100000});
    EXPECT_EQ(i32.as_int64(), -100000);

    Entry& u16 = *od.find(obj::controlword);  // UNSIGNED16: no sign extension
    u16.set(std::uint16_t{0xFFFF});
    EXPECT_EQ(u16.as_int64(), 0xFFFF);
    EXPECT_EQ(u16.as_uint64(), 0xFFFFu);
    Entry& u8 = *od.find(0x1C12, 0);
    u8.set(std::uint8_t{0xFF});
    EXPECT_EQ(u8.as_uint64(), 0xFFu);
}

TEST_F(DefaultDictionary, GetSetAreLittleEndian) {
    Entry& e = *od.find(obj::target_position);
    e.set(std::int32_t{0x12345678});
    EXPECT_EQ(value_of(e), (Buf{0x78, 0x56, 0x34, 0x12}));
    EXPECT_EQ(e.get<std::int32_t>(), 0x12345678);
    EXPECT_EQ(e.get<std::uint16_t>(), 0x5678);
}

TEST_F(DefaultDictionary, AssignCutsLongInputAndKeepsStringLengths) {
    Entry& label = *od.find(0x2010, 0);  // VISIBLE_STRING, at most 32 characters
    EXPECT_EQ(label.capacity(), 32u);
    EXPECT_EQ(label.size(), 4u);  // "axis"
    const std::string s = "xy";
    label.assign(ConstBytes(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()));
    EXPECT_EQ(label.size(), 2u);
    EXPECT_EQ(value_of(label), (Buf{'x', 'y'}));
    const Buf long_value(40, 'z');
    label.assign(cb(long_value));
    EXPECT_EQ(label.size(), 32u);
    label.reset_to_default();
    EXPECT_EQ(value_of(label), (Buf{'a', 'x', 'i', 's'}));

    Entry& u16 = *od.find(obj::controlword);  // fixed size: always 2 bytes
    u16.assign(cb(Buf{0x11, 0x22, 0x33}));
    EXPECT_EQ(value_of(u16), (Buf{0x11, 0x22}));
    u16.assign(cb(Buf{0x44}));
    EXPECT_EQ(u16.size(), 2u);
    EXPECT_EQ(value_of(u16), (Buf{0x44, 0x22}));
}

// ---- checks ----

TEST_F(DefaultDictionary, CheckLengthOfFixedAndVariableTypes) {
    const Entry& u16 = *od.find(obj::following_error_time_out);
    EXPECT_EQ(check_length(u16, 2), SdoAbort::None);
    EXPECT_EQ(check_length(u16, 1), SdoAbort::LengthTooLow);
    EXPECT_EQ(check_length(u16, 0), SdoAbort::LengthTooLow);
    EXPECT_EQ(check_length(u16, 4), SdoAbort::LengthTooHigh);
    const Entry& u32 = *od.find(obj::following_error_window);
    EXPECT_EQ(check_length(u32, 4), SdoAbort::None);
    EXPECT_EQ(check_length(u32, 3), SdoAbort::LengthTooLow);
    EXPECT_EQ(check_length(u32, 5), SdoAbort::LengthTooHigh);
    const Entry& i8 = *od.find(obj::modes_of_operation);
    EXPECT_EQ(check_length(i8, 1), SdoAbort::None);
    EXPECT_EQ(check_length(i8, 2), SdoAbort::LengthTooHigh);
    // Strings: anything up to the capacity.
    const Entry& label = *od.find(0x2010, 0);
    EXPECT_EQ(check_length(label, 0), SdoAbort::None);
    EXPECT_EQ(check_length(label, 1), SdoAbort::None);
    EXPECT_EQ(check_length(label, 32), SdoAbort::None);
    EXPECT_EQ(check_length(label, 33), SdoAbort::LengthTooHigh);
}

TEST_F(DefaultDictionary, CheckRangeOfSignedAndUnsignedEntries) {
    const Entry& qs = *od.find(obj::quick_stop_option_code);  // INTEGER16, 0..8
    EXPECT_EQ(check_range(qs, cb(Buf{0x00, 0x00})), SdoAbort::None);
    EXPECT_EQ(check_range(qs, cb(Buf{0x08, 0x00})), SdoAbort::None);
    EXPECT_EQ(check_range(qs, cb(Buf{0x09, 0x00})), SdoAbort::ValueTooHigh);
    EXPECT_EQ(check_range(qs, cb(Buf{0xFF, 0xFF})), SdoAbort::ValueTooLow);  // -1, not 65535
    EXPECT_EQ(check_range(qs, cb(Buf{0x00, 0x80})), SdoAbort::ValueTooLow);  // -32768

    const Entry& sd = *od.find(obj::shutdown_option_code);  // INTEGER16, -1..1
    EXPECT_EQ(check_range(sd, cb(Buf{0xFF, 0xFF})), SdoAbort::None);
    EXPECT_EQ(check_range(sd, cb(Buf{0xFE, 0xFF})), SdoAbort::ValueTooLow);
    EXPECT_EQ(check_range(sd, cb(Buf{0x02, 0x00})), SdoAbort::ValueTooHigh);

    const Entry& ip = *od.find(obj::interpolation_time_period::time_index);  // INTEGER8, -6..63
    EXPECT_EQ(check_range(ip, cb(Buf{0xFA})), SdoAbort::None);               // -6
    EXPECT_EQ(check_range(ip, cb(Buf{0xF9})), SdoAbort::ValueTooLow);
    EXPECT_EQ(check_range(ip, cb(Buf{0x3F})), SdoAbort::None);
    EXPECT_EQ(check_range(ip, cb(Buf{0x40})), SdoAbort::ValueTooHigh);
    EXPECT_EQ(check_range(ip, cb(Buf{0x80})), SdoAbort::ValueTooLow);  // -128

    const Entry& assign = *od.find(0x1C12, 0);  // UNSIGNED8, 0..4
    EXPECT_EQ(check_range(assign, cb(Buf{0x04})), SdoAbort::None);
    EXPECT_EQ(check_range(assign, cb(Buf{0x05})), SdoAbort::ValueTooHigh);
    EXPECT_EQ(check_range(assign, cb(Buf{0xFF})), SdoAbort::ValueTooHigh);  // 255, not -1

    // No declared range: every value of the type is accepted.
    EXPECT_EQ(check_range(*od.find(obj::controlword), cb(Buf{0xFF, 0xFF})), SdoAbort::None);
    EXPECT_EQ(check_range(*od.find(obj::target_position), cb(Buf{0x00, 0x00, 0x00, 0x80})), SdoAbort::None);
    EXPECT_EQ(check_range(*od.find(0x2010, 0), cb(Buf{'a'})), SdoAbort::None);
}

TEST(ObjectDictionaryChecks, BooleanAcceptsOnlyZeroAndOne) {
    // Given a writable BOOLEAN entry, when 2 is written, then it is refused as out of range (CiA 301:
    // BOOLEAN is FALSE/TRUE; check_range has an explicit "x > 1" test for it).
    device::ObjectDescription d = device::make_var(0x3000, "Flag", DataType::Boolean, acc::RW, 0);
    ObjectDictionary od({d});
    const Entry& e = *od.find(0x3000, 0);
    EXPECT_EQ(check_range(e, cb(Buf{0x00})), SdoAbort::None);
    EXPECT_EQ(check_range(e, cb(Buf{0x01})), SdoAbort::None);
    EXPECT_EQ(check_range(e, cb(Buf{0x02})), SdoAbort::ValueRange);
    EXPECT_EQ(od.download(0x3000, 0, false, AlState::PreOp, cb(Buf{0xFF})), SdoAbort::ValueRange);
    EXPECT_EQ(value_of(*od.find(0x3000, 0)), (Buf{0x00}));
}

// ---- sizes ----

TEST_F(DefaultDictionary, MaxTransferSizeCoversTheLargestValue) {
    EXPECT_GE(od.max_transfer_size(), 512u);  // 0x2020: 512-byte octet string
    for (const auto& o : od.objects()) {
        EXPECT_LE(complete_access_size(o, 0, o.max_subindex()), od.max_transfer_size())
            << std::hex << o.index();
        for (const auto& e : o.entries())
            EXPECT_LE(e.capacity(), od.max_transfer_size()) << std::hex << o.index();
    }
}

TEST_F(DefaultDictionary, CompleteAccessSizes) {
    // Subindex 0 takes 16 bits (U8 + pad byte, ETG.1000.6 5.6.2.1.1), then the entries in order.
    const Object& assign = *od.find(0x1C12);
    EXPECT_EQ(complete_access_size(assign, 0, 0), 2u);
    EXPECT_EQ(complete_access_size(assign, 0, 1), 4u);
    EXPECT_EQ(complete_access_size(assign, 0, 4), 10u);
    EXPECT_EQ(complete_access_size(assign, 1, 1), 2u);
    EXPECT_EQ(complete_access_size(assign, 1, 4), 8u);
    EXPECT_EQ(assign.complete_access_last(), 1);  // one PDO assigned

    const Object& map = *od.find(0x1600);
    EXPECT_EQ(map.complete_access_last(), 7);
    EXPECT_EQ(complete_access_size(map, 0, 7), 2u + 7u * 4u);
    EXPECT_EQ(complete_access_size(map, 1, 7), 7u * 4u);
    EXPECT_EQ(complete_access_size(map, 0, 16), 2u + 16u * 4u);

    const Object& id = *od.find(0x1018);
    EXPECT_EQ(complete_access_size(id, 0, 4), 18u);
    EXPECT_EQ(complete_access_size(id, 1, 4), 16u);
}

TEST_F(DefaultDictionary, CompleteAccessSizeOfSyncParameterSkipsMissingSubindexes) {
    // 0x1C32 has subindexes 1..13 (320 bits) and 32 (BOOLEAN, 1 bit); 14..31 do not exist and take no
    // space. Subindex 0 says 32, so a complete access covers everything.
    const Object& sp = *od.find(0x1C32);
    EXPECT_EQ(sp.max_subindex(), 32);
    EXPECT_EQ(sp.complete_access_last(), 32);
    EXPECT_EQ(complete_access_size(sp, 0, 13), 2u + 40u);
    EXPECT_EQ(complete_access_size(sp, 0, 31), 2u + 40u);
    EXPECT_EQ(complete_access_size(sp, 0, 32), 2u + 40u + 1u);  // 337 bits
    EXPECT_EQ(complete_access_size(sp, 1, 32), 40u + 1u);
}

TEST_F(DefaultDictionary, CompleteAccessUploadOfSyncParameterPacksTheBoolean) {
    od.find(0x1C32, 32)->set(std::uint8_t{1});
    od.find(0x1C32, 1)->set(std::uint16_t{0x0002});
    od.find(0x1C32, 13)->set(std::uint16_t{0xBEEF});
    Buf out(od.max_transfer_size(), 0xEE);
    std::size_t len = 0;
    ASSERT_EQ(od.upload(0x1C32, 0, true, AlState::PreOp, Bytes(out.data(), out.size()), len), SdoAbort::None);
    ASSERT_EQ(len, 43u);
    EXPECT_EQ(out[0], 32);  // subindex 0
    EXPECT_EQ(out[1], 0);   // its pad byte
    EXPECT_EQ(out[2], 0x02);
    EXPECT_EQ(out[3], 0x00);
    EXPECT_EQ(out[4], 0x40);  // cycle time 1'000'000 = 0x000F4240
    EXPECT_EQ(out[5], 0x42);
    EXPECT_EQ(out[6], 0x0F);
    EXPECT_EQ(out[7], 0x00);
    EXPECT_EQ(out[40], 0xEF);  // subindex 13 at bit 320
    EXPECT_EQ(out[41], 0xBE);
    EXPECT_EQ(out[42], 0x01);  // subindex 32 at bit 336
}

TEST(ObjectDictionaryCompleteAccess, SmallEntriesArePackedAndBytesAligned) {
    // The layout the dictionary documents: BOOLEANs are packed bit by bit, an entry of 8 bits or more
    // starts on the next byte boundary.
    ObjectDictionary od(
        {device::make_record(0x3002, "Mixed",
                             {device::make_entry(1, "a", DataType::Boolean, acc::RW, 1),
                              device::make_entry(2, "b", DataType::Boolean, acc::RW, 0),
                              device::make_entry(3, "c", DataType::Boolean, acc::RW, 1),
                              device::make_entry(4, "d", DataType::Unsigned16, acc::RW, 0x1234)})});
    const Object& o = *od.find(0x3002);
    EXPECT_EQ(complete_access_size(o, 0, 4), 5u);  // 16 + 3 bits, padded to 24, + 16
    EXPECT_EQ(complete_access_size(o, 1, 4), 3u);
    Buf out(8, 0xEE);
    std::size_t len = 0;
    ASSERT_EQ(od.upload(0x3002, 0, true, AlState::PreOp, Bytes(out.data(), out.size()), len), SdoAbort::None);
    EXPECT_EQ(Buf(out.begin(), out.begin() + static_cast<long>(len)), (Buf{0x04, 0x00, 0x05, 0x34, 0x12}));
    // Written back the same way.
    ASSERT_EQ(od.download(0x3002, 0, true, AlState::PreOp, cb(Buf{0x04, 0x00, 0x02, 0x78, 0x56})),
              SdoAbort::None);
    EXPECT_EQ(od.find(0x3002, 1)->as_uint64(), 0u);
    EXPECT_EQ(od.find(0x3002, 2)->as_uint64(), 1u);
    EXPECT_EQ(od.find(0x3002, 3)->as_uint64(), 0u);
    EXPECT_EQ(od.find(0x3002, 4)->as_uint64(), 0x5678u);
}

// ---- SDO access through the dictionary ----

TEST_F(DefaultDictionary, UploadCopiesTheValue) {
    Buf out(16, 0xEE);
    std::size_t len = 99;
    ASSERT_EQ(od.upload(0x1018, 1, false, AlState::PreOp, Bytes(out.data(), out.size()), len),
              SdoAbort::None);
    ASSERT_EQ(len, 4u);
    EXPECT_EQ(Buf(out.begin(), out.begin() + 4), (Buf{0x3C, 0x0A, 0x00, 0x00}));
    EXPECT_EQ(od.upload(0x1234, 0, false, AlState::PreOp, Bytes(out.data(), out.size()), len),
              SdoAbort::ObjectDoesNotExist);
    EXPECT_EQ(len, 0u);
    EXPECT_EQ(od.upload(0x1018, 9, false, AlState::PreOp, Bytes(out.data(), out.size()), len),
              SdoAbort::SubindexDoesNotExist);
    // Too small an output buffer is refused, not overrun.
    Buf tiny(8, 0xEE);
    EXPECT_EQ(od.upload(0x1008, 0, false, AlState::PreOp, Bytes(tiny.data(), tiny.size()), len),
              SdoAbort::ObjectTooLongForMailbox);
    EXPECT_EQ(tiny, Buf(8, 0xEE));
}

TEST_F(DefaultDictionary, NoSdoAccessInInit) {
    // Given INIT (the mailbox is off), when an object is read or written, then the state refuses it.
    Buf out(16);
    std::size_t len = 0;
    EXPECT_EQ(od.upload(0x1018, 1, false, AlState::Init, Bytes(out.data(), out.size()), len),
              SdoAbort::WrongState);
    EXPECT_EQ(od.download(obj::following_error_time_out.index, 0, false, AlState::Init, cb(Buf{1, 0})),
              SdoAbort::WrongState);
    EXPECT_EQ(od.download(obj::following_error_time_out.index, 0, false, AlState::PreOp, cb(Buf{1, 0})),
              SdoAbort::None);
}

TEST_F(DefaultDictionary, DownloadChecksInOrder) {
    EXPECT_EQ(od.download(0x1234, 0, false, AlState::PreOp, cb(Buf{1})), SdoAbort::ObjectDoesNotExist);
    EXPECT_EQ(od.download(obj::controlword.index, 1, false, AlState::PreOp, cb(Buf{1, 0})),
              SdoAbort::SubindexDoesNotExist);
    EXPECT_EQ(od.download(0x1018, 1, false, AlState::PreOp, cb(Buf{1, 0, 0, 0})), SdoAbort::ReadOnly);
    EXPECT_EQ(od.download(0x1C12, 0, false, AlState::SafeOp, cb(Buf{1})), SdoAbort::WrongState);
    EXPECT_EQ(od.download(obj::following_error_time_out.index, 0, false, AlState::PreOp, cb(Buf{1, 0, 0, 0})),
              SdoAbort::LengthTooHigh);
    EXPECT_EQ(od.download(obj::following_error_time_out.index, 0, false, AlState::PreOp, cb(Buf{1})),
              SdoAbort::LengthTooLow);
    EXPECT_EQ(od.download(obj::quick_stop_option_code.index, 0, false, AlState::PreOp, cb(Buf{9, 0})),
              SdoAbort::ValueTooHigh);
    EXPECT_EQ(od.find(obj::quick_stop_option_code)->as_int64(), 2);  // refused writes change nothing
    EXPECT_EQ(od.download(obj::quick_stop_option_code.index, 0, false, AlState::Op, cb(Buf{8, 0})),
              SdoAbort::None);
    EXPECT_EQ(od.find(obj::quick_stop_option_code)->as_int64(), 8);
}

TEST_F(DefaultDictionary, DownloadHooksValidateStoreAndRefresh) {
    Entry& e = *od.find(obj::following_error_time_out);
    int after = 0;
    e.hooks().on_download = [](const Entry&, ConstBytes v) {
        return v[0] == 0x77 ? SdoAbort::CannotTransfer : SdoAbort::None;
    };
    e.hooks().after_download = [&](Entry& x) {
        ++after;
        EXPECT_EQ(x.get<std::uint16_t>(), 0x0102);  // already stored
    };
    EXPECT_EQ(od.download(obj::following_error_time_out.index, 0, false, AlState::PreOp, cb(Buf{0x77, 0x00})),
              SdoAbort::CannotTransfer);
    EXPECT_EQ(e.get<std::uint16_t>(), 10u);
    EXPECT_EQ(after, 0);
    EXPECT_EQ(od.download(obj::following_error_time_out.index, 0, false, AlState::PreOp, cb(Buf{0x02, 0x01})),
              SdoAbort::None);
    EXPECT_EQ(after, 1);

    od.find(obj::statusword)->hooks().before_upload = [](Entry& x) { x.set(std::uint16_t{0x1234}); };
    Buf out(4);
    std::size_t len = 0;
    ASSERT_EQ(od.upload(obj::statusword.index, 0, false, AlState::Op, Bytes(out.data(), out.size()), len),
              SdoAbort::None);
    EXPECT_EQ(Buf(out.begin(), out.begin() + 2), (Buf{0x34, 0x12}));
}

TEST_F(DefaultDictionary, DownloadGuardRunsFirst) {
    od.download_guard = [](const Entry& e, AlState st) {
        return e.desc().subindex == 0 && st == AlState::Op ? SdoAbort::LocalControl : SdoAbort::None;
    };
    EXPECT_EQ(od.download(obj::following_error_time_out.index, 0, false, AlState::Op, cb(Buf{1, 0})),
              SdoAbort::LocalControl);
    EXPECT_EQ(od.download(obj::following_error_time_out.index, 0, false, AlState::PreOp, cb(Buf{1, 0})),
              SdoAbort::None);
}

TEST_F(DefaultDictionary, CompleteAccessRefusesVarObjectsAndHighSubindexes) {
    Buf out(od.max_transfer_size());
    std::size_t len = 0;
    EXPECT_EQ(od.upload(obj::controlword.index, 0, true, AlState::PreOp, Bytes(out.data(), out.size()), len),
              SdoAbort::UnsupportedAccess);
    EXPECT_EQ(od.upload(0x1018, 2, true, AlState::PreOp, Bytes(out.data(), out.size()), len),
              SdoAbort::UnsupportedAccess);
    EXPECT_EQ(od.download(0x1018, 2, true, AlState::PreOp, cb(Buf(16))), SdoAbort::UnsupportedAccess);
    EXPECT_EQ(od.download(obj::controlword.index, 0, true, AlState::PreOp, cb(Buf(2))),
              SdoAbort::UnsupportedAccess);
}

TEST_F(DefaultDictionary, CompleteAccessDownloadLengths) {
    // 0x1C12 from subindex 0: the new count says how many entries must follow.
    EXPECT_EQ(od.download(0x1C12, 0, true, AlState::PreOp, cb(Buf{})), SdoAbort::LengthTooLow);
    EXPECT_EQ(od.download(0x1C12, 0, true, AlState::PreOp, cb(Buf{2, 0, 0x00, 0x16})),
              SdoAbort::LengthTooLow);
    EXPECT_EQ(od.download(0x1C12, 0, true, AlState::PreOp, cb(Buf(12, 0))), SdoAbort::LengthTooHigh);
    EXPECT_EQ(od.download(0x1C12, 0, true, AlState::PreOp, cb(Buf{5, 0, 0, 0, 0, 0, 0, 0, 0, 0})),
              SdoAbort::ValueTooHigh);
    // Nothing changed.
    EXPECT_EQ(od.find(0x1C12, 0)->as_uint64(), 1u);
    EXPECT_EQ(od.find(0x1C12, 1)->get<std::uint16_t>(), 0x1600);
}

TEST_F(DefaultDictionary, CompleteAccessDownloadWritesEntriesThenCount) {
    // Without the PDO rules installed, a plain complete write of a record: the new count is written
    // last. 0x10F1 (Error settings): sub 0 is read-only and must keep its value.
    EXPECT_EQ(od.download(0x10F1, 0, true, AlState::PreOp, cb(Buf{2, 0, 0x05, 0, 0, 0, 0x09, 0})),
              SdoAbort::None);
    EXPECT_EQ(od.find(0x10F1, 1)->get<std::uint32_t>(), 5u);
    EXPECT_EQ(od.find(0x10F1, 2)->get<std::uint16_t>(), 9u);
    // A different count for the read-only subindex 0 is refused, nothing is written.
    EXPECT_EQ(od.download(0x10F1, 0, true, AlState::PreOp, cb(Buf{1, 0, 0x07, 0, 0, 0})), SdoAbort::ReadOnly);
    EXPECT_EQ(od.find(0x10F1, 1)->get<std::uint32_t>(), 5u);
    // From subindex 1: entries only.
    EXPECT_EQ(od.download(0x10F1, 1, true, AlState::PreOp, cb(Buf{0x06, 0, 0, 0, 0x03, 0})), SdoAbort::None);
    EXPECT_EQ(od.find(0x10F1, 1)->get<std::uint32_t>(), 6u);
    EXPECT_EQ(od.find(0x10F1, 2)->get<std::uint16_t>(), 3u);
}

TEST_F(DefaultDictionary, CompleteAccessDownloadIsUndoneWhenAnEntryIsRefused) {
    // Given a hook refusing one value of subindex 2, when a complete write changes subindexes 1 and 2,
    // then subindex 1 is back to its old value as well.
    od.find(0x10F1, 2)->hooks().on_download = [](const Entry&, ConstBytes v) {
        return v[0] == 0x66 ? SdoAbort::ValueRange : SdoAbort::None;
    };
    EXPECT_EQ(od.download(0x10F1, 0, true, AlState::PreOp, cb(Buf{2, 0, 0x05, 0, 0, 0, 0x66, 0})),
              SdoAbort::ValueRange);
    EXPECT_EQ(od.find(0x10F1, 1)->get<std::uint32_t>(), 1u);
    EXPECT_EQ(od.find(0x10F1, 2)->get<std::uint16_t>(), 4u);
    EXPECT_EQ(od.find(0x10F1, 0)->as_uint64(), 2u);
}

TEST(ObjectDictionaryCompleteAccess, UndoOfARecordOfBooleansStaysInItsBuffer) {
    // Given a dictionary whose only object is a RECORD of 16 BOOLEANs (complete access: 2 + 2 bytes),
    // when it is written by complete access and an entry is refused, then the old values come back.
    std::vector<device::EntryDescription> subs;
    for (std::uint8_t i = 1; i <= 16; ++i)
        subs.push_back(device::make_entry(i, device::subindex_name(i), DataType::Boolean, acc::RW, 0));
    ObjectDictionary od({device::make_record(0x3000, "Flags", std::move(subs))});
    EXPECT_EQ(complete_access_size(*od.find(0x3000), 0, 16), 4u);
    od.find(0x3000, 16)->hooks().on_download = [](const Entry&, ConstBytes v) {
        return v[0] ? SdoAbort::CannotTransfer : SdoAbort::None;
    };
    EXPECT_EQ(od.download(0x3000, 0, true, AlState::PreOp, cb(Buf{16, 0, 0xFF, 0xFF})),
              SdoAbort::CannotTransfer);
    for (std::uint8_t i = 1; i <= 16; ++i)
        EXPECT_EQ(od.find(0x3000, i)->as_uint64(), 0u) << unsigned{i};
    EXPECT_EQ(od.download(0x3000, 0, true, AlState::PreOp, cb(Buf{16, 0, 0x05, 0x00})), SdoAbort::None);
    EXPECT_EQ(od.find(0x3000, 1)->as_uint64(), 1u);
    EXPECT_EQ(od.find(0x3000, 2)->as_uint64(), 0u);
    EXPECT_EQ(od.find(0x3000, 3)->as_uint64(), 1u);
}

TEST(ObjectDictionaryAccess, WriteOnlyEntryCannotBeRead) {
    auto d = device::make_var(0x3001, "Command", DataType::Unsigned16, acc::WriteAll, 0);
    ObjectDictionary od({d});
    Buf out(4);
    std::size_t len = 0;
    EXPECT_EQ(od.upload(0x3001, 0, false, AlState::PreOp, Bytes(out.data(), out.size()), len),
              SdoAbort::WriteOnly);
    EXPECT_EQ(od.download(0x3001, 0, false, AlState::PreOp, cb(Buf{1, 2})), SdoAbort::None);
}
