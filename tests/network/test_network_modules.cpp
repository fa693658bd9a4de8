// Modular devices of ESI files in network files (modules:): the reader's refusals, the ESI checks of the
// chosen modules (each with the line of its entry), the device built from them (PDOs and objects with the
// slot increments, the Detected Module Ident List 0xF050) and the configuration check of ETG.5001.1: a
// Configured Module Ident List 0xF030 the master writes that differs from 0xF050 refuses SAFEOP with AL
// status code 0x0070. examples/networks/modular-io.xml is the self-contained modular device; the ETG.2001
// example of ../shared is used where it is there.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include "common/bytes.hpp"
#include "device/from_sii.hpp"
#include "esc/sii_image.hpp"
#include "esi/esi_reader.hpp"
#include "esi/esi_writer.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "network/build.hpp"
#include "network/network_file.hpp"
#include "network_support.hpp"
#include "protocol/objects.hpp"
#include "protocol/sii.hpp"
#include "serve/in_process_link.hpp"
#include "shared_data.hpp"
#include "test_support.hpp"

namespace vecat::network {
namespace {

namespace md = protocol::obj::modular_device;

const std::string kModularIo = std::string(VECAT_SOURCE_DIR) + "/examples/networks/modular-io.xml";

// A network of one device of modular-io.xml: the device lines, then modules: as given (line 5 on).
std::string net(const std::string& modules, const std::string& type = "VECAT-MOD-3") {
    return "devices:\n  - name: io\n    esi: " + kModularIo + "\n    type: " + type + "\n" + modules;
}

// The message of the refusal of text, reading it and making its devices ("" if it was accepted).
const auto refusal = vecat::test::build_refusal;

#define EXPECT_REFUSED(text, part)                                                      \
    do {                                                                                \
        const std::string why_ = refusal(text);                                         \
        EXPECT_NE(why_.find(part), std::string::npos) << "refusal: \"" << why_ << "\""; \
    } while (0)

TEST(NetworkModules, TheReaderRefusesBadListsWithTheirLine) {
    EXPECT_REFUSED("devices:\n  - name: a\n    device: drive\n    modules: [1]\n",
                   "net.yaml:4: a: modules: chooses the modules of a modular device of an esi: file");
    EXPECT_REFUSED(net("    modules: 0x1001\n"), "net.yaml:5: modules: a list, one entry per slot");
    EXPECT_REFUSED(net("    modules: []\n"), "net.yaml:5: modules: an empty list");
    EXPECT_REFUSED(net("    modules:\n      - DO8\n      - {module: DI8}\n"),
                   "net.yaml:7: modules: a list, one entry per slot");
    EXPECT_REFUSED(net("    modules:\n      - DO8\n      - \"\"\n"), "net.yaml:7: modules: an empty name");
    // The entries as read: a Type, a number as written, empty and null for an empty slot.
    const auto f =
        parse_network(net("    modules:\n      - DO8\n      - 0x1001\n      - empty\n      - ~\n"));
    const auto& m = f.devices.at(0).modules;
    ASSERT_EQ(m.size(), 4u);
    EXPECT_EQ(m[0].module, "DO8");
    EXPECT_EQ(m[1].module, "0x1001");
    EXPECT_FALSE(m[2].module.has_value());
    EXPECT_FALSE(m[3].module.has_value());
    EXPECT_EQ(m[3].line, 9u);
    EXPECT_EQ(f.devices.at(0).modules_line, 6u);
}

TEST(NetworkModules, TheEsiChecksEachEntryWithItsLine) {
    EXPECT_REFUSED(
        net("    modules:\n      - DO8\n      - DX9\n"),
        "net.yaml:7: io: modules: unknown module \"DX9\"; the file has \"DI8\" (ModuleIdent 0x1001)");
    EXPECT_REFUSED(net("    modules:\n      - DO8\n      - 0x4711\n"),
                   "net.yaml:7: io: modules: unknown module");
    EXPECT_REFUSED(net("    modules:\n      - DI8\n"),
                   "net.yaml:6: io: modules: 2 modules have the Type \"DI8\" (ModuleIdent 0x1001, 0x1003)");
    // Slot 1 takes 0x1001 and 0x1002 by ModuleIdent, slot 2 the modules of class IO.
    EXPECT_REFUSED(
        net("    modules:\n      - AI1\n"),
        "net.yaml:6: io: modules: slot 1 \"Slot 1\" does not take module \"AI1\" (ModuleIdent 0x2001); "
        "it takes ModuleIdent #x1001, ModuleIdent #x1002");
    EXPECT_REFUSED(
        net("    modules:\n      - DO8\n      - 8193\n"),
        "net.yaml:7: io: modules: slot 2 \"Slot 2\" does not take module \"AI1\" (ModuleIdent 0x2001); "
        "it takes ModuleClass IO");
    EXPECT_REFUSED(net("    modules:\n      - empty\n"),
                   "net.yaml:6: io: modules: slot 1 \"Slot 1\" cannot stay empty (MinInstances 1)");
    EXPECT_REFUSED(net("    modules: [DO8, empty, AI1, AI1]\n"),
                   "net.yaml:5: io: modules: 4 modules for 3 slots");
    EXPECT_REFUSED(net("    modules:\n      - DO8\n      - empty\n      - AI1\n      - AI1\n"),
                   "net.yaml:9: io: modules: 4 modules for 3 slots");
    EXPECT_REFUSED(net("    modules: [DI8]\n", "VECAT-PLAIN"),
                   "net.yaml:5: io: modules: the device has no slots");
    EXPECT_EQ(refusal(net("    modules: [DO8, 0x1003, AI1]\n")), "");
}

std::vector<std::uint16_t> assigned(const std::vector<device::Pdo>& pdos) {
    std::vector<std::uint16_t> v;
    for (const auto& p : pdos)
        if (p.assigned) v.push_back(p.index);
    return v;
}

const device::ObjectDescription* object(const std::vector<device::ObjectDescription>& objs, std::uint16_t i) {
    const auto it = std::find_if(objs.begin(), objs.end(), [&](const auto& o) { return o.index == i; });
    return it == objs.end() ? nullptr : &*it;
}

// The ModuleIdents an object's elements hold by default (subindex 1 on).
std::vector<std::uint32_t> idents(const device::ObjectDescription* o) {
    std::vector<std::uint32_t> v;
    if (!o) return v;
    for (const auto& e : o->entries)
        if (e.subindex != 0) v.push_back(static_cast<std::uint32_t>(ld_le32(e.default_value.data())));
    return v;
}

TEST(NetworkModules, TheDefaultModulesStayWithoutAList) {
    esi::DeviceSelector sel;
    sel.type = "VECAT-MOD-3";
    const auto r = esi::import_esi_file(kModularIo, sel);
    const auto& d = r.desc;
    // Slot 1 its default 0x1002 DO8, slot 2 (by class, no default) empty, slot 3 0x2001 AI1 (PDO +2,
    // objects +0x20).
    EXPECT_EQ(d.module_idents, (std::vector<std::uint32_t>{0x1002, 0, 0x2001}));
    EXPECT_EQ(assigned(d.rx_pdos), (std::vector<std::uint16_t>{0x1600}));
    EXPECT_EQ(assigned(d.tx_pdos), (std::vector<std::uint16_t>{0x1A02}));
    ASSERT_EQ(d.tx_pdos.at(0).entries.size(), 1u);
    EXPECT_EQ(d.tx_pdos[0].entries[0].index, 0x6020);
    EXPECT_EQ(d.rx_pdos.at(0).entries.at(0).index, 0x7000);
    EXPECT_EQ(d.output_bytes(), 1u);
    EXPECT_EQ(d.input_bytes(), 2u);
    const auto objs = device::dictionary_objects(d);
    EXPECT_EQ(idents(object(objs, md::detected_module_ident_list)), d.module_idents);
    EXPECT_EQ(idents(object(objs, md::configured_module_ident_list)), d.module_idents);
    // AI1's own objects, moved to its slot.
    const auto* ai = object(objs, 0x6020);
    ASSERT_NE(ai, nullptr);
    EXPECT_EQ(ai->name, "AI value");
    EXPECT_EQ(ld_le16(ai->entries.at(0).default_value.data()), 1234);
    EXPECT_NE(object(objs, 0x8020), nullptr);
    EXPECT_EQ(object(objs, 0x6000), nullptr);
}

TEST(NetworkModules, ChosenModulesBringTheirPdosAndObjectsWithTheSlotIncrements) {
    esi::DeviceSelector sel;
    sel.type = "VECAT-MOD-3";
    sel.modules = std::vector<std::optional<std::string>>{"DO8", "0x1001"};  // slot 3 keeps its default
    auto d = esi::import_esi_file(kModularIo, sel).desc;
    EXPECT_EQ(d.module_idents, (std::vector<std::uint32_t>{0x1002, 0x1001, 0x2001}));
    EXPECT_EQ(assigned(d.tx_pdos), (std::vector<std::uint16_t>{0x1A01, 0x1A02}));
    EXPECT_EQ(d.tx_pdos.at(0).entries.at(0).index, 0x6010);
    EXPECT_EQ(d.input_bytes(), 3u);

    sel.modules = std::vector<std::optional<std::string>>{"#x1001", std::nullopt, std::nullopt};
    d = esi::import_esi_file(kModularIo, sel).desc;
    EXPECT_EQ(d.module_idents, (std::vector<std::uint32_t>{0x1001, 0, 0}));
    EXPECT_TRUE(d.rx_pdos.empty());
    EXPECT_EQ(assigned(d.tx_pdos), (std::vector<std::uint16_t>{0x1A00}));
    const auto objs = device::dictionary_objects(d);
    EXPECT_EQ(idents(object(objs, md::detected_module_ident_list)),
              (std::vector<std::uint32_t>{0x1001, 0, 0}));
    EXPECT_EQ(object(objs, 0x6020), nullptr) << "AI1 is not in slot 3";
}

// A built network to PREOP: the master reads 0xF050, writes 0xF030; SAFEOP only with a matching list.
using Served = vecat::test::ServedNetwork;

master::SdoResult write32(master::CoeClient& c, std::uint16_t index, std::uint8_t sub, std::uint32_t v) {
    return c.download_value(index, sub, v);
}

std::uint32_t read32(master::CoeClient& c, std::uint16_t index, std::uint8_t sub) {
    const auto r = c.upload(index, sub);
    EXPECT_TRUE(r.ok()) << "0x" << std::hex << index << ":" << int(sub);
    return r.ok() && r.data.size() >= 4 ? ld_le32(r.data.data()) : 0xFFFFFFFFu;
}

TEST(NetworkModules, AConfiguredListThatDiffersRefusesSafeOpWithCode0x0070) {
    Served s(net("    modules: [DO8, 0x1003, AI1]\n"));
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::PreOp, &why)) << why;
    const auto station = s.master.slaves().at(0).station;
    master::CoeClient c(s.master, station);
    // The detected list: one ModuleIdent per slot, read-only.
    EXPECT_EQ(c.upload(md::detected_module_ident_list, 0).data, (std::vector<std::uint8_t>{3}));
    EXPECT_EQ(read32(c, md::detected_module_ident_list, 1), 0x1002u);
    EXPECT_EQ(read32(c, md::detected_module_ident_list, 2), 0x1003u);
    EXPECT_EQ(read32(c, md::detected_module_ident_list, 3), 0x2001u);
    EXPECT_EQ(write32(c, md::detected_module_ident_list, 2, 0x1001).abort, protocol::SdoAbort::ReadOnly);
    // The master configured 0x1001 in slot 2: refused with 0x0070, the device stays in PREOP and serves CoE.
    ASSERT_TRUE(write32(c, md::configured_module_ident_list, 2, 0x1001).ok());
    EXPECT_FALSE(s.master.request_state(station, protocol::AlState::SafeOp));
    auto st = s.master.read_al_status(station);
    ASSERT_TRUE(st.ok);
    EXPECT_TRUE(st.error());
    EXPECT_EQ(st.state(), protocol::AlState::PreOp);
    EXPECT_EQ(st.code, static_cast<std::uint16_t>(protocol::AlStatusCode::ModuleIdentListMismatch));
    EXPECT_EQ(read32(c, md::detected_module_ident_list, 2), 0x1003u);
    ASSERT_TRUE(s.master.acknowledge_error(station, protocol::AlState::PreOp));
    // A shorter list does not match either.
    ASSERT_TRUE(write32(c, md::configured_module_ident_list, 2, 0x1003).ok());
    ASSERT_TRUE(c.download_value(md::configured_module_ident_list, 0, std::uint8_t{2}).ok());
    EXPECT_FALSE(s.master.request_state(station, protocol::AlState::SafeOp));
    EXPECT_EQ(s.master.read_al_status(station).code,
              static_cast<std::uint16_t>(protocol::AlStatusCode::ModuleIdentListMismatch));
    ASSERT_TRUE(s.master.acknowledge_error(station, protocol::AlState::PreOp));
    // The matching list written whole by complete access, as TwinCAT's start-up list does (subindex 0 as a
    // byte and a pad byte, then the three UDINTs): SAFEOP and OP, process data of the chosen modules.
    std::vector<std::uint8_t> list(2 + 3 * 4, 0);
    list[0] = 3;
    st_le32(&list[2], 0x1002);
    st_le32(&list[6], 0x1003);
    st_le32(&list[10], 0x2001);
    ASSERT_TRUE(
        c.download(md::configured_module_ident_list, 0, ConstBytes(list.data(), list.size()), true).ok());
    EXPECT_EQ(read32(c, md::configured_module_ident_list, 3), 0x2001u);
    ASSERT_TRUE(s.master.startup(protocol::AlState::Op, &why)) << why;
    EXPECT_EQ(s.master.slaves().at(0).out_bytes, 1u);
    EXPECT_EQ(s.master.slaves().at(0).in_bytes, 3u);
    for (int i = 0; i < 5; ++i)
        ASSERT_EQ(s.master.exchange_process_data().value_or(0), s.master.expected_wkc());
}

TEST(NetworkModules, AnUnconfiguredOrClearedListPasses) {
    Served s(net(""));
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::PreOp, &why)) << why;
    const auto station = s.master.slaves().at(0).station;
    master::CoeClient c(s.master, station);
    EXPECT_EQ(read32(c, md::detected_module_ident_list, 2), 0u) << "slot 2 empty by default";
    // Subindex 0 = 0: the master configures no modules, nothing is compared.
    ASSERT_TRUE(write32(c, md::configured_module_ident_list, 1, 0x1001).ok());
    ASSERT_TRUE(c.download_value(md::configured_module_ident_list, 0, std::uint8_t{0}).ok());
    EXPECT_EQ(c.download_value(md::configured_module_ident_list, 0, std::uint8_t{4}).abort,
              protocol::SdoAbort::ValueTooHigh);
    ASSERT_TRUE(s.master.configure_process_data());
    ASSERT_TRUE(s.master.request_state(station, protocol::AlState::SafeOp));
    // In SAFEOP the configured list is no longer writable (PREOP only).
    EXPECT_NE(c.download_value(md::configured_module_ident_list, 0, std::uint8_t{3}).abort,
              protocol::SdoAbort::None);
}

// The ETG.2001 example (../shared): two drive axes; a chosen module moves its PDOs by 16 and its objects
// by 0x800 per slot, as the default modules do.
TEST(NetworkModules, TheEtg2001ExampleTakesChosenModules) {
    VECAT_REQUIRE_SHARED_DATA("esi/etg2001-modules-cia402.xml");
    const std::string file = test::shared_data("esi/etg2001-modules-cia402.xml");
    auto d = esi::import_esi_file(file, {}).desc;
    EXPECT_EQ(d.module_idents, (std::vector<std::uint32_t>{0x100, 0x100}));
    esi::DeviceSelector sel;
    sel.modules = std::vector<std::optional<std::string>>{"Velocity Mode (DC)", "0x110"};
    d = esi::import_esi_file(file, sel).desc;
    EXPECT_EQ(d.module_idents, (std::vector<std::uint32_t>{0x201, 0x110}));
    std::vector<std::uint16_t> rx;
    for (const auto& p : d.rx_pdos)
        rx.push_back(p.index);
    EXPECT_EQ(rx, (std::vector<std::uint16_t>{0x1600, 0x1610, 0x1611, 0x1612}));
    EXPECT_EQ(d.rx_pdos.at(1).entries.at(0).index, 0x607A + 0x800);
    // "Position Mode" names two modules (0x100 and 0x110).
    sel.modules = std::vector<std::optional<std::string>>{"Position Mode"};
    try {
        (void)esi::import_esi_file(file, sel);
        ADD_FAILURE() << "accepted";
    } catch (const esi::ModuleError& e) {
        EXPECT_EQ(e.entry, std::optional<std::size_t>(0));
        EXPECT_NE(std::string(e.what()).find("ModuleIdent 0x100, 0x110"), std::string::npos) << e.what();
    }
    // A network of it reaches OP with the chosen modules.
    Served s("devices:\n  - name: axes\n    esi: " + file + "\n    modules: [0x201, 0x110]\n");
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::Op, &why)) << why;
    for (int i = 0; i < 5; ++i)
        ASSERT_EQ(s.master.exchange_process_data().value_or(0), s.master.expected_wkc());
}

// VECAT-MOD-R of modular-io.xml: Slot elements that repeat (ETG.2000 SlotType MinInstances/MaxInstances):
// "Head" once, "Inputs" 2 or 3 times with its own SlotPdoIncrement 0x10 and SlotIndexIncrement 0x100 (those
// of Slots: 1 and 0x10), "Analog" 0 to 3 times in slot group 1 (group increments 0x10 and 0x100);
// MaxSlotCount 6.
std::vector<std::uint16_t> indexes(const std::vector<device::Pdo>& pdos) {
    std::vector<std::uint16_t> v;
    for (const auto& p : pdos)
        v.push_back(p.index);
    return v;
}

std::vector<std::uint16_t> entry_indexes(const std::vector<device::Pdo>& pdos) {
    std::vector<std::uint16_t> v;
    for (const auto& p : pdos)
        for (const auto& e : p.entries)
            v.push_back(e.index);
    return v;
}

device::DeviceDescription repeating(std::optional<std::vector<std::optional<std::string>>> modules) {
    esi::DeviceSelector sel;
    sel.type = "VECAT-MOD-R";
    sel.modules = std::move(modules);
    return esi::import_esi_file(kModularIo, sel).desc;
}

TEST(NetworkModules, ARepeatingSlotTakesOneEntryPerInstanceWithItsOwnIncrements) {
    const auto d =
        repeating(std::vector<std::optional<std::string>>{"DO8", "0x1001", "0x1003", "0x1001", "AI1", "AO1"});
    // Slot n from 0: Head 0, Inputs 1-3, Analog 4-5.
    EXPECT_EQ(d.module_idents, (std::vector<std::uint32_t>{0x1002, 0x1001, 0x1003, 0x1001, 0x2001, 0x2002}));
    // Inputs' own increments: n * 0x10 for the PDOs, n * 0x100 for the entries (not Slots' 1 and 0x10).
    // AI1 in slot 4 by the increments of Slots: 0x1A04, 0x6040.
    EXPECT_EQ(indexes(d.tx_pdos), (std::vector<std::uint16_t>{0x1A10, 0x1A20, 0x1A30, 0x1A04}));
    EXPECT_EQ(entry_indexes(d.tx_pdos), (std::vector<std::uint16_t>{0x6100, 0x6200, 0x6300, 0x6040}));
    // AO1 in slot 5, slot group 1: 0x1600 + 5 + 0x10, 0x7000 + 5 * 0x10 + 0x100.
    EXPECT_EQ(indexes(d.rx_pdos), (std::vector<std::uint16_t>{0x1600, 0x1615}));
    EXPECT_EQ(entry_indexes(d.rx_pdos), (std::vector<std::uint16_t>{0x7000, 0x7150}));
    EXPECT_EQ(d.input_bytes(), 5u);
    EXPECT_EQ(d.output_bytes(), 3u);
    // The modules' own objects follow the same increments, one per instance.
    const auto objs = device::dictionary_objects(d);
    for (const std::uint16_t i :
         std::initializer_list<std::uint16_t>{0x6100, 0x6200, 0x6300, 0x6040, 0x8040, 0x7150})
        EXPECT_NE(object(objs, i), nullptr) << std::hex << i;
    EXPECT_EQ(object(objs, 0x6010), nullptr) << "not by the increment of Slots";
    EXPECT_EQ(idents(object(objs, md::detected_module_ident_list)), d.module_idents);
    EXPECT_EQ(idents(object(objs, md::configured_module_ident_list)), d.module_idents);
    // The SII and the generated ESI describe the same PDOs (the ESI without Slots of its own).
    const auto sii = protocol::parse_sii(esc::build_sii_image(d));
    const auto from_sii = device::description_from_sii(sii, nullptr);
    EXPECT_EQ(indexes(from_sii.tx_pdos), indexes(d.tx_pdos));
    EXPECT_EQ(entry_indexes(from_sii.rx_pdos), entry_indexes(d.rx_pdos));
    const auto again = esi::import_esi_text(esi::write_esi(d)).desc;
    EXPECT_EQ(indexes(again.tx_pdos), indexes(d.tx_pdos));
    EXPECT_EQ(entry_indexes(again.rx_pdos), entry_indexes(d.rx_pdos));
    EXPECT_EQ(idents(object(device::dictionary_objects(again), md::detected_module_ident_list)),
              d.module_idents);
}

TEST(NetworkModules, ARepeatingSlotGetsMinInstancesDefaultModules) {
    const auto d = repeating(std::nullopt);
    // Head DO8, Inputs twice its default DI8 0x1001 (MinInstances 2), Analog once AI1 (MinInstances 0).
    EXPECT_EQ(d.module_idents, (std::vector<std::uint32_t>{0x1002, 0x1001, 0x1001, 0x2001}));
    EXPECT_EQ(indexes(d.tx_pdos), (std::vector<std::uint16_t>{0x1A10, 0x1A20, 0x1A03}));
    EXPECT_EQ(entry_indexes(d.tx_pdos), (std::vector<std::uint16_t>{0x6100, 0x6200, 0x6030}));
    // A list that ends in a Slot: the Slots after it keep their defaults.
    const auto e = repeating(std::vector<std::optional<std::string>>{"DO8", "0x1003", "0x1003", "0x1003"});
    EXPECT_EQ(e.module_idents, (std::vector<std::uint32_t>{0x1002, 0x1003, 0x1003, 0x1003, 0x2001}));
    EXPECT_EQ(indexes(e.tx_pdos), (std::vector<std::uint16_t>{0x1A10, 0x1A20, 0x1A30, 0x1A04}));
}

TEST(NetworkModules, TooManyOrTooFewInstancesAreRefusedWithTheLineOfTheEntry) {
    const auto mod_r = [](const std::string& modules) { return net(modules, "VECAT-MOD-R"); };
    // A fourth DI8: Inputs is full (MaxInstances 3) and Analog does not take it.
    EXPECT_REFUSED(mod_r("    modules:\n      - DO8\n      - 0x1001\n      - 0x1001\n      - 0x1001\n"
                         "      - 0x1001\n"),
                   "net.yaml:10: io: modules: slot 5 \"Analog\" does not take module \"DI8\" (ModuleIdent "
                   "0x1001); it takes ModuleIdent #x2001, ModuleIdent #x2002; the Slot \"Inputs\" takes at "
                   "most 3 (MaxInstances)");
    // More than all Slots take.
    EXPECT_REFUSED(mod_r("    modules: [DO8, 0x1001, 0x1001, AI1, AI1, AI1, AO1]\n"),
                   "net.yaml:5: io: modules: 7 modules for 3 slots, which take at most 7 (MaxInstances); the "
                   "Slot \"Analog\" takes at most 3 (MaxInstances)");
    // MaxSlotCount 6 of Slots: the 7th slot.
    EXPECT_REFUSED(mod_r("    modules:\n      - DO8\n      - 0x1001\n      - 0x1001\n      - 0x1001\n"
                         "      - AI1\n      - AI1\n      - AO1\n"),
                   "net.yaml:12: io: modules: 7 slots: the device has at most 6 (Slots MaxSlotCount)");
    // Too few: Inputs takes at least 2 (MinInstances), given one, then a module it does not take ...
    EXPECT_REFUSED(mod_r("    modules:\n      - DO8\n      - 0x1001\n      - AI1\n"),
                   "net.yaml:8: io: modules: slot 3 \"Inputs\" does not take module \"AI1\" (ModuleIdent "
                   "0x2001) and the Slot has 1 of at least 2 instances (MinInstances)");
    // ... or the end of the list, at its last entry.
    EXPECT_REFUSED(mod_r("    modules:\n      - DO8\n      - 0x1001\n"),
                   "net.yaml:7: io: modules: 1 module for the Slot \"Inputs\", which takes at least 2 "
                   "(MinInstances)");
    // empty ends a Slot of MinInstances 0: Analog stays empty (one empty slot, 0 in 0xF050).
    EXPECT_EQ(refusal(mod_r("    modules: [DO8, 0x1001, 0x1003, empty]\n")), "");
    EXPECT_EQ(repeating(std::vector<std::optional<std::string>>{"DO8", "0x1001", "0x1003", std::nullopt})
                  .module_idents,
              (std::vector<std::uint32_t>{0x1002, 0x1001, 0x1003, 0}));
    EXPECT_REFUSED(mod_r("    modules: [DO8, empty]\n"),
                   "net.yaml:5: io: modules: slot 2 \"Inputs\" cannot stay empty (MinInstances 2)");
}

TEST(NetworkModules, ARepeatingSlotDeviceServesItsInstances) {
    Served s(net("    modules: [DO8, 0x1001, 0x1003, 0x1001, AI1, AO1]\n", "VECAT-MOD-R"));
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::PreOp, &why)) << why;
    const auto station = s.master.slaves().at(0).station;
    master::CoeClient c(s.master, station);
    EXPECT_EQ(c.upload(md::detected_module_ident_list, 0).data, (std::vector<std::uint8_t>{6}));
    EXPECT_EQ(read32(c, md::detected_module_ident_list, 3), 0x1003u);
    EXPECT_EQ(read32(c, md::detected_module_ident_list, 6), 0x2002u);
    // The mapping of the 2nd instance of Inputs and of AO1: entry 0x6200:0, 8 bits; 0x7150:0, 16 bits.
    EXPECT_EQ(read32(c, 0x1A20, 1), 0x62000008u);
    EXPECT_EQ(read32(c, 0x1615, 1), 0x71500010u);
    EXPECT_TRUE(c.upload(0x6300, 0).ok());
    ASSERT_TRUE(s.master.startup(protocol::AlState::Op, &why)) << why;
    EXPECT_EQ(s.master.slaves().at(0).out_bytes, 3u);
    EXPECT_EQ(s.master.slaves().at(0).in_bytes, 5u);
    for (int i = 0; i < 5; ++i)
        ASSERT_EQ(s.master.exchange_process_data().value_or(0), s.master.expected_wkc());
}

// vecat esi generate / sii generate / run --esi FILE --modules LIST: the same choice as modules: (the
// generated ESI describes the device with the chosen modules in place, 0xF050 with their ModuleIdents).
TEST(NetworkModules, TheModulesOptionOfTheCommandLine) {
    const auto out = std::filesystem::temp_directory_path() / ("vecat-modules-" + std::to_string(::getpid()));
    std::filesystem::create_directories(out);
    const std::string esi = (out / "gen.xml").string();
    const std::string log =
        test::run_capture(std::string(VECAT_BINARY) + " esi generate --esi " + kModularIo +
                          " --device VECAT-MOD-3 --modules DO8,0x1003,empty -o " + esi + " 2>&1");
    EXPECT_NE(log.find("slot 2 \"Slot 2\": chosen module \"DI8\" (ModuleIdent 0x1003)"), std::string::npos)
        << log;
    const auto d = esi::import_esi_file(esi).desc;  // no Slots in it: the objects as written
    EXPECT_EQ(assigned(d.tx_pdos), (std::vector<std::uint16_t>{0x1A01}));
    const auto objs = device::dictionary_objects(d);
    EXPECT_EQ(idents(object(objs, md::detected_module_ident_list)),
              (std::vector<std::uint32_t>{0x1002, 0x1003, 0}));
    const std::string refused =
        test::run_capture(std::string(VECAT_BINARY) + " sii generate --esi " + kModularIo +
                          " --device VECAT-MOD-3 --modules AI1 -o " + (out / "x.sii").string() + " 2>&1");
    EXPECT_NE(refused.find("slot 1 \"Slot 1\" does not take module \"AI1\""), std::string::npos) << refused;
    EXPECT_FALSE(std::filesystem::exists(out / "x.sii"));
    std::filesystem::remove_all(out);
}

}  // namespace
}  // namespace vecat::network
