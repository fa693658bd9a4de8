// The slots of a modular device (ETG.2000 SlotType) beyond their ModuleIdent entries: the Slot's Default
// attribute (the default module of a slot that lists ModuleClass entries) and its Fallback attribute (the
// module "automatically plugged when no other module is plugged to this slot").
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "esi/esi_reader.hpp"

using namespace vecat;

namespace {

// A device of two slots: slot 1 takes modules of class IO, slot 2 takes AI1 (0x2001) and may stay empty.
// slot1 / slot2: the attributes of each Slot element. Modules: DI8 (0x1001, class IO), DO8 (0x1002, class
// IO), AI1 (0x2001) and EMPTY (0x2003, no process data: what a real device plugs into a free slot).
std::string modular(const std::string& slot1, const std::string& slot2) {
    const auto module = [](const char* ident, const char* cls, const char* type, const char* pdo) {
        return std::string("<Module><Type ModuleIdent=\"") + ident + "\"" +
               (*cls ? std::string(" ModuleClass=\"") + cls + "\"" : std::string()) + ">" + type + "</Type>" +
               pdo + "</Module>";
    };
    const auto pdo = [](const char* dir, const char* sm, const char* index, const char* entry) {
        return std::string("<") + dir + " Fixed=\"true\" Sm=\"" + sm + "\"><Index DependOnSlot=\"true\">" +
               index + "</Index><Name>P</Name><Entry><Index DependOnSlot=\"true\">" + entry +
               "</Index><SubIndex>0</SubIndex><BitLen>8</BitLen><Name>V</Name><DataType>USINT</DataType>"
               "</Entry></" +
               dir + ">";
    };
    return R"(<?xml version="1.0"?>
<EtherCATInfo><Vendor><Id>#x1234</Id></Vendor><Descriptions><Devices><Device>
<Type ProductCode="#x4D33" RevisionNo="#x1">SLOTS</Type><Name>S</Name>
<Sm DefaultSize="128" StartAddress="#x1000" ControlByte="#x26" Enable="1">MBoxOut</Sm>
<Sm DefaultSize="128" StartAddress="#x1080" ControlByte="#x22" Enable="1">MBoxIn</Sm>
<Sm StartAddress="#x1100" ControlByte="#x64" Enable="1">Outputs</Sm>
<Sm StartAddress="#x1180" ControlByte="#x20" Enable="1">Inputs</Sm>
<Mailbox><CoE/></Mailbox>
<Slots SlotPdoIncrement="1" SlotIndexIncrement="#x10">
<Slot MinInstances="1" MaxInstances="1" )" +
           slot1 + R"(><Name>IO</Name><ModuleClass><Class>IO</Class></ModuleClass></Slot>
<Slot MinInstances="0" MaxInstances="1" )" +
           slot2 + R"(><Name>Analog</Name><ModuleIdent>#x2001</ModuleIdent></Slot>
</Slots></Device></Devices><Modules>)" +
           module("#x1001", "IO", "DI8", pdo("TxPdo", "3", "#x1A00", "#x6000").c_str()) +
           module("#x1002", "IO", "DO8", pdo("RxPdo", "2", "#x1600", "#x7000").c_str()) +
           module("#x2001", "", "AI1", pdo("TxPdo", "3", "#x1A00", "#x6000").c_str()) +
           module("#x2003", "", "EMPTY", "") + "</Modules></Descriptions></EtherCATInfo>";
}

esi::ImportResult import(const std::string& xml,
                         std::optional<std::vector<std::optional<std::string>>> modules = std::nullopt) {
    esi::DeviceSelector sel;
    sel.modules = std::move(modules);
    return esi::import_esi_text(xml, sel);
}

bool has_note(const esi::ImportResult& r, const std::string& text) {
    return std::any_of(r.notes.begin(), r.notes.end(),
                       [&](const std::string& n) { return n.find(text) != std::string::npos; });
}

TEST(EsiSlots, TheSlotsDefaultAttributeNamesTheDefaultModuleOfAClassSlot) {
    // Without it the IO slot, which lists only a class, has no default and stays empty.
    EXPECT_EQ(import(modular("", "")).desc.module_idents, (std::vector<std::uint32_t>{0, 0x2001}));
    const auto r = import(modular(R"(Default="#x1002")", ""));
    EXPECT_EQ(r.desc.module_idents, (std::vector<std::uint32_t>{0x1002, 0x2001}));
    ASSERT_EQ(r.desc.rx_pdos.size(), 1u);
    EXPECT_EQ(r.desc.rx_pdos[0].index, 0x1600);
    EXPECT_TRUE(has_note(r, "default module \"DO8\""));
    // A Default that names no module leaves the slot empty, and says so.
    const auto missing = import(modular(R"(Default="#x1009")", ""));
    EXPECT_EQ(missing.desc.module_idents, (std::vector<std::uint32_t>{0, 0x2001}));
    EXPECT_TRUE(has_note(missing, "default module #x1009 not found"));
}

TEST(EsiSlots, TheFallbackModuleIsPluggedWhereASlotWouldStayEmpty) {
    // The list leaves the analog slot empty: its Fallback EMPTY is plugged (its ModuleIdent in 0xF050).
    const auto listed = import(modular("", R"(Fallback="#x2003")"), {{"DI8", std::nullopt}});
    EXPECT_EQ(listed.desc.module_idents, (std::vector<std::uint32_t>{0x1001, 0x2003}));
    EXPECT_TRUE(has_note(listed, "the list leaves it empty, fallback module \"EMPTY\""));
    // Without a Fallback the slot stays empty.
    EXPECT_EQ(import(modular("", ""), {{"DI8", std::nullopt}}).desc.module_idents,
              (std::vector<std::uint32_t>{0x1001, 0}));
    // A slot without a default module takes its Fallback too, even one that must not stay empty.
    const auto defaults = import(modular(R"(Fallback="#x2003")", ""));
    EXPECT_EQ(defaults.desc.module_idents, (std::vector<std::uint32_t>{0x2003, 0x2001}));
    EXPECT_TRUE(has_note(defaults, "no default module (it takes ModuleClass IO), fallback module \"EMPTY\""));
    const auto chosen_empty = import(modular(R"(Fallback="#x2003")", ""), {{std::nullopt}});
    EXPECT_EQ(chosen_empty.desc.module_idents, (std::vector<std::uint32_t>{0x2003, 0x2001}));
    // A chosen module still takes the place of the Fallback.
    EXPECT_EQ(import(modular("", R"(Fallback="#x2003")"), {{"DO8", "AI1"}}).desc.module_idents,
              (std::vector<std::uint32_t>{0x1002, 0x2001}));
}

// Also when no slot needs it.
TEST(EsiSlots, AFallbackThatNamesNoModuleRefusesTheFile) {
    for (const auto& modules : {std::optional<std::vector<std::optional<std::string>>>{{"DI8", std::nullopt}},
                                std::optional<std::vector<std::optional<std::string>>>{}}) {
        try {
            import(modular("", R"(Fallback="#x2004")"), modules);
            ADD_FAILURE() << "accepted";
        } catch (const esi::EsiError& e) {
            EXPECT_STREQ(e.what(), "Slot \"Analog\": Fallback #x2004 names no Module of the file");
        }
    }
}

}  // namespace
