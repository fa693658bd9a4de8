// Wires from the outputs of a CoE device of an ESI file or SII image (docs/network-file.md, "Inputs of the
// I/O terminals") when the master assigns and maps other RxPDOs than the default ones, as SOEM, IgH and
// TwinCAT do by SDO in PREOP (ETG.1000.6 5.6.7.4: 0x1C12 and 0x16xx): the wire reads the output object,
// wherever the master mapped it, and 0 below OP; a wire may name an entry of an RxPDO the device does not
// assign by default. The device is VECAT-REMAP of tests/network/data/remap-io.xml, once from the ESI file and
// once from the SII image made of it (an sii: device with CoE); and, for what is refused, an SII image of it
// without CoE and one with a dictionary file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/bytes.hpp"
#include "esc/slave.hpp"
#include "esi/esi_reader.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "network/build.hpp"
#include "network/dictionary_file.hpp"
#include "network/network_file.hpp"
#include "protocol/sdo_abort.hpp"
#include "serve/in_process_link.hpp"

namespace vecat::network {
namespace {

using protocol::AlState;

const std::string kEsi = VECAT_SOURCE_DIR "/tests/network/data/remap-io.xml";

// The wires of a line: the digital input terminal's channels 0 and 1, the analog input terminal's channel 0.
struct WireTargets {
    std::string ch0 = "out:0";  // the device's first one-bit output, 0x7000:1
    std::string ch1 = "out:0x7030:1";
    std::string level = "out:0x7100:0";  // the INT level
};

// Slave 0 the device; slave 1 a digital input terminal, its channels 0 and 1 wired as w says; slave 2 an
// analog input terminal, its channel 0 wired as w says (the wire on line 14).
std::string line(const std::string& source, const WireTargets& w = {}) {
    return "devices:\n"
           "  - name: out\n"
           "    " +
           source +
           "\n"
           "  - name: ins\n"
           "    device: digital-in\n"
           "    channels: 2\n"
           "    inputs:\n"
           "      0: {wire: " +
           w.ch0 +
           "}\n"
           "      1: {wire: " +
           w.ch1 +
           "}\n"
           "  - name: level\n"
           "    device: analog-in\n"
           "    channels: 1\n"
           "    inputs:\n"
           "      0: {wire: " +
           w.level + "}\n";
}

enum class Source { Esi, Sii };

NetworkFile network_of(Source source, const WireTargets& w = {}) {
    if (source == Source::Esi) return parse_network(line("esi: " + kEsi, w), "wires.yaml");
    // The SII image vecat makes of the ESI device (vecat sii generate), served as an sii: device.
    NetworkFile f = parse_network(line("sii: remap-io.bin", w), "wires.yaml");
    auto d = esi::import_esi_file(kEsi, {}).desc;
    esi::complete_for_emulation(d);
    f.devices.at(0).sii_image = esc::DeviceModel::of(d).sii_image;
    return f;
}

// The line served in-process to the project master, 1 ms of the link's time per cycle.
struct WiredLine {
    explicit WiredLine(Source source, const WireTargets& w = {})
        : built(build_network(network_of(source, w), "wires.yaml")), link(*built.segment), m(link) {
        link.set_time(now);
    }
    void cycle() {
        now += 1'000'000;
        link.set_time(now);
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
    }
    // An output reaches the device with one frame; the input terminal samples the wire after a frame and
    // the master reads it with the next one (docs/network-file.md: within three cycles).
    void settle() {
        for (int i = 0; i < 3; ++i)
            cycle();
    }
    std::uint16_t station() { return m.slaves().at(0).station; }
    master::CoeClient coe() { return master::CoeClient(m, station()); }
    // From PREOP, with the RxPDOs the master configured: the process data as read back by SDO, SAFEOP, OP.
    void to_op() {
        ASSERT_TRUE(m.configure_process_data());
        ASSERT_TRUE(m.request_state(AlState::SafeOp))
            << "AL status code 0x" << std::hex << m.read_al_status(station()).code;
        cycle();
        ASSERT_TRUE(m.request_state(AlState::Op));
    }
    // Sets an entry of the device's outputs where the master mapped it (out_entries: read from 0x1C12 and
    // the 0x16xx objects).
    void put(std::uint16_t index, std::uint8_t sub, std::uint32_t value) {
        const auto* e = master::find_entry(m.slaves().at(0).out_entries, index, sub);
        ASSERT_NE(e, nullptr) << std::hex << index << ":" << int{sub} << " is not mapped";
        const Bytes out = m.outputs(0);
        for (unsigned b = 0; b < e->bits; ++b) {
            const unsigned at = e->bit_offset + b;
            const auto bit = static_cast<std::uint8_t>(1u << (at % 8));
            out[at / 8] =
                static_cast<std::uint8_t>((value >> b) & 1u ? out[at / 8] | bit : out[at / 8] & ~bit);
        }
    }
    std::uint32_t offset_of(std::uint16_t index, std::uint8_t sub) {
        const auto* e = master::find_entry(m.slaves().at(0).out_entries, index, sub);
        return e ? e->bit_offset : ~0u;
    }
    unsigned channels() const { return m.inputs(1)[0] & 0x03; }
    std::int16_t level() const { return static_cast<std::int16_t>(ld_le16(m.inputs(2).data())); }

    BuiltNetwork built;
    net::InProcessLink link;
    master::Master m;
    std::uint64_t now = 1'000'000'000;
};

bool download8(master::CoeClient& c, std::uint16_t index, std::uint8_t sub, std::uint8_t v) {
    return c.download_value(index, sub, v).ok();
}
bool download16(master::CoeClient& c, std::uint16_t index, std::uint8_t sub, std::uint16_t v) {
    return c.download_value(index, sub, v).ok();
}
bool download32(master::CoeClient& c, std::uint16_t index, std::uint8_t sub, std::uint32_t v) {
    return c.download_value(index, sub, v).ok();
}

class Wires : public ::testing::TestWithParam<Source> {};

// The master assigns 0x1601 (the level) before 0x1600 and maps 0x1600's outputs in reverse order: the level
// moves from bit 8 to bit 0, 0x7030:1 from bit 3 to bit 16, 0x7000:1 from bit 0 to bit 19. The wires read
// the entries' values, not the bits at their places in the default mapping.
TEST_P(Wires, FollowTheEntryWhereTheMasterMappedIt) {
    WiredLine l(GetParam());
    std::string why;
    ASSERT_TRUE(l.m.startup(AlState::PreOp, &why)) << why;
    auto c = l.coe();
    ASSERT_TRUE(download8(c, 0x1C12, 0, 0));
    ASSERT_TRUE(download8(c, 0x1600, 0, 0));
    ASSERT_TRUE(download32(c, 0x1600, 1, 0x70300101));
    ASSERT_TRUE(download32(c, 0x1600, 2, 0x70200101));
    ASSERT_TRUE(download32(c, 0x1600, 3, 0x70100101));
    ASSERT_TRUE(download32(c, 0x1600, 4, 0x70000101));
    ASSERT_TRUE(download32(c, 0x1600, 5, 0x00000004));  // a gap of 4 bits (CiA 301 7.4.8: index 0)
    ASSERT_TRUE(download8(c, 0x1600, 0, 5));
    ASSERT_TRUE(download16(c, 0x1C12, 1, 0x1601));
    ASSERT_TRUE(download16(c, 0x1C12, 2, 0x1600));
    ASSERT_TRUE(download8(c, 0x1C12, 0, 2));
    l.to_op();
    ASSERT_EQ(l.offset_of(0x7100, 0), 0u);
    ASSERT_EQ(l.offset_of(0x7030, 1), 16u);
    ASSERT_EQ(l.offset_of(0x7000, 1), 19u);
    // Level -1234 (0xFB2E: bit 0 clear, bit 3 set, where the default mapping had 0x7000:1 and 0x7030:1).
    l.put(0x7100, 0, static_cast<std::uint16_t>(std::int16_t{-1234}));
    l.put(0x7000, 1, 1);
    l.put(0x7030, 1, 0);
    l.settle();
    EXPECT_EQ(l.channels(), 0x1u) << "channel 0: 0x7000:1 on; channel 1: 0x7030:1 off";
    EXPECT_EQ(l.level(), -1234);
    l.put(0x7100, 0, 77);  // 0x004D: bit 0 set, bit 3 set
    l.put(0x7000, 1, 0);
    l.put(0x7030, 1, 1);
    l.settle();
    EXPECT_EQ(l.channels(), 0x2u);
    EXPECT_EQ(l.level(), 77);
    // Below OP the outputs are in their safe state.
    ASSERT_TRUE(l.m.request_state(AlState::SafeOp));
    l.settle();
    EXPECT_EQ(l.channels(), 0x0u);
    EXPECT_EQ(l.level(), 0);
}

// The master assigns 0x1601 alone: 0x7000:1 and 0x7030:1 are in no RxPDO. Their wires read the objects,
// which the process data do not write: 0 (the safe state zeroed them when the device left OP), or what an SDO
// download wrote (the device takes it in OP: an object not mapped to an RxPDO may be written). Below OP, 0.
TEST_P(Wires, ReadAnEntryTheMappingLeavesOutAsItsObject) {
    WiredLine l(GetParam());
    std::string why;
    ASSERT_TRUE(l.m.startup(AlState::PreOp, &why)) << why;
    auto c = l.coe();
    ASSERT_TRUE(download8(c, 0x1C12, 0, 0));
    ASSERT_TRUE(download16(c, 0x1C12, 1, 0x1601));
    ASSERT_TRUE(download8(c, 0x1C12, 0, 1));
    l.to_op();
    ASSERT_EQ(l.m.outputs(0).size(), 2u) << "the level alone";
    // Level -1 (all bits set, also those where the default mapping had 0x7000:1 and 0x7030:1).
    l.put(0x7100, 0, 0xFFFF);
    l.settle();
    EXPECT_EQ(l.channels(), 0x0u);
    EXPECT_EQ(l.level(), -1);
    // 0x7000:1 written by SDO in OP: its wire reads 1; the level, mapped, is the master's PDO data only.
    l.put(0x7100, 0, 0);
    ASSERT_TRUE(download8(c, 0x7000, 1, 1));
    EXPECT_EQ(c.download_value(0x7100, 0, std::uint16_t{5}).abort, protocol::SdoAbort::MappedToRxPdo);
    l.settle();
    EXPECT_EQ(l.channels(), 0x1u);
    EXPECT_EQ(l.level(), 0);
    // SAFEOP: 0. Back in OP the object still holds what SDO wrote (the safe state zeroes the mapped
    // objects only).
    ASSERT_TRUE(l.m.request_state(AlState::SafeOp));
    l.settle();
    EXPECT_EQ(l.channels(), 0x0u);
    ASSERT_TRUE(l.m.request_state(AlState::Op));
    l.settle();
    EXPECT_EQ(l.channels(), 0x1u);
    ASSERT_TRUE(download8(c, 0x7000, 1, 0));
    l.settle();
    EXPECT_EQ(l.channels(), 0x0u);
}

// Unchanged mapping: the wires read the default places, as before (the CHANNEL form counts the one-bit
// entries of the default RxPDOs).
TEST_P(Wires, ReadTheDefaultMappingUnchanged) {
    WiredLine l(GetParam());
    std::string why;
    ASSERT_TRUE(l.m.startup(AlState::Op, &why)) << why;
    ASSERT_EQ(l.offset_of(0x7000, 1), 0u);
    ASSERT_EQ(l.offset_of(0x7030, 1), 3u);
    ASSERT_EQ(l.offset_of(0x7100, 0), 8u);
    l.put(0x7000, 1, 1);
    l.put(0x7030, 1, 1);
    l.put(0x7100, 0, static_cast<std::uint16_t>(std::int16_t{-300}));
    l.settle();
    EXPECT_EQ(l.channels(), 0x3u);
    EXPECT_EQ(l.level(), -300);
}

// 0x7040:1 and 0x7200:0 are mapped by 0x1603 alone, an RxPDO the device describes but does not assign by
// default: they have no place in the default image, and their wires read their objects. With the default
// assignment they read 0, whatever the master writes into the image; once the master assigns 0x1603 (0x1C12)
// and writes them in OP, their values. Channel 1 keeps to 0x7000:1 (the CHANNEL form counts the one-bit
// entries of the default RxPDOs).
TEST_P(Wires, ReadAnEntryOfAnRxPdoTheDefaultAssignmentLeavesOut) {
    WiredLine l(GetParam(), {"out:0x7040:1", "out:0", "out:0x7200:0"});
    std::string why;
    ASSERT_TRUE(l.m.startup(AlState::Op, &why)) << why;
    ASSERT_EQ(l.offset_of(0x7040, 1), ~0u) << "not mapped by default";
    ASSERT_EQ(l.m.outputs(0).size(), 3u) << "0x1600 and 0x1601";
    for (auto& b : l.m.outputs(0))
        b = 0xFF;
    l.settle();
    EXPECT_EQ(l.channels(), 0x2u) << "channel 0: 0x7040:1 unmapped, its object 0; channel 1: 0x7000:1 on";
    EXPECT_EQ(l.level(), 0);
    // The master starts again (INIT, where the SyncManagers may be set up anew) and in PREOP assigns 0x1603
    // before 0x1600; 0x7040:1 at bit 0, 0x7200:0 at bit 8, 0x7000:1 at bit 24.
    ASSERT_TRUE(l.m.startup(AlState::PreOp, &why)) << why;
    auto c = l.coe();
    ASSERT_TRUE(download8(c, 0x1C12, 0, 0));
    ASSERT_TRUE(download16(c, 0x1C12, 1, 0x1603));
    ASSERT_TRUE(download16(c, 0x1C12, 2, 0x1600));
    ASSERT_TRUE(download8(c, 0x1C12, 0, 2));
    l.to_op();
    ASSERT_EQ(l.offset_of(0x7040, 1), 0u);
    ASSERT_EQ(l.offset_of(0x7200, 0), 8u);
    ASSERT_EQ(l.offset_of(0x7000, 1), 24u);
    l.settle();
    EXPECT_EQ(l.channels(), 0x0u) << "nothing written yet";
    EXPECT_EQ(l.level(), 0);
    l.put(0x7040, 1, 1);
    l.put(0x7200, 0, static_cast<std::uint16_t>(std::int16_t{-4321}));
    l.settle();
    EXPECT_EQ(l.channels(), 0x1u);
    EXPECT_EQ(l.level(), -4321);
    l.put(0x7040, 1, 0);
    l.put(0x7000, 1, 1);
    l.put(0x7200, 0, 1234);
    l.settle();
    EXPECT_EQ(l.channels(), 0x2u);
    EXPECT_EQ(l.level(), 1234);
    // Below OP the outputs are in their safe state.
    ASSERT_TRUE(l.m.request_state(AlState::SafeOp));
    l.settle();
    EXPECT_EQ(l.channels(), 0x0u);
    EXPECT_EQ(l.level(), 0);
}

std::string refusal(const NetworkFile& f) {
    try {
        (void)build_network(f, "wires.yaml");
    } catch (const NetworkFileError& e) {
        return e.what();
    }
    return "accepted";
}

// An entry that no RxPDO of the device maps, not even one it does not assign by default, is refused naming
// the wire's line; the message lists the entries its RxPDOs map.
TEST_P(Wires, RefuseAnEntryNoRxPdoMaps) {
    EXPECT_EQ(refusal(network_of(GetParam(), {"out:0x7040:1", "out:0", "out:0x7300:0"})),
              "wires.yaml:14: level: wire: out maps no output PDO entry 0x7300:0 (its RxPDOs map 0x7000:1, "
              "0x7010:1, 0x7020:1, 0x7030:1, 0x7100:0, 0x7040:1, 0x7200:0)");
}

// An sii: device with CoE served with a dictionary file that lacks 0x7200 (the offset, mapped by 0x1603
// alone): the wire to it is refused naming its line, since nothing holds the entry's value.
TEST(WiresToAnSiiDeviceWithADictionaryFile, RefuseAnEntryOutsideTheDefaultMappingTheDictionaryLacks) {
    NetworkFile f = network_of(Source::Sii, {"out:0", "out:0x7030:1", "out:0x7200:0"});
    auto d = esi::import_esi_file(kEsi, {}).desc;
    esi::complete_for_emulation(d);
    DeviceDictionary dict;
    const esc::DeviceModel model = esc::DeviceModel::of(d);
    for (const auto& o : *model.dictionary)
        if (o.index != 0x7200) dict.objects.push_back(o);
    const auto dir = std::filesystem::temp_directory_path() / "vecat-wires-dictionary";
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "out.dictionary.yaml") << write_dictionary(dict);
    f.devices.at(0).dictionary = (dir / "out.dictionary.yaml").string();
    const std::string why = refusal(f);
    std::filesystem::remove_all(dir);
    EXPECT_EQ(
        why,
        "wires.yaml:14: level: wire: out: its dictionary lacks 0x7200:0 (of RxPDO 0x1603, not assigned by "
        "default)");
}

INSTANTIATE_TEST_SUITE_P(EsiAndSii, Wires, ::testing::Values(Source::Esi, Source::Sii),
                         [](const ::testing::TestParamInfo<Source>& i) {
                             return i.param == Source::Esi ? std::string("Esi") : std::string("Sii");
                         });

// A device without CoE (an SII image that names no CoE mailbox): no master can assign another RxPDO, so a
// wire names an entry of the default RxPDOs only; 0x7200:0, mapped by 0x1603 alone, is refused naming the
// wire's line.
TEST(WiresToABareSiiDevice, RefuseAnEntryOfAnRxPdoNotAssignedByDefault) {
    NetworkFile f =
        parse_network(line("sii: bare.bin", {"out:0", "out:0x7030:1", "out:0x7200:0"}), "wires.yaml");
    auto d = esi::import_esi_file(kEsi, {}).desc;
    esi::complete_for_emulation(d);
    d.mailbox_protocols = 0;
    f.devices.at(0).sii_image = esc::DeviceModel::of(d).sii_image;
    EXPECT_EQ(refusal(f),
              "wires.yaml:14: level: wire: out maps no output PDO entry 0x7200:0 (its default "
              "RxPDOs map 0x7000:1, 0x7010:1, 0x7020:1, 0x7030:1, 0x7100:0)");
    f.devices.at(2).inputs.at(0).signal.wire_index = 0x7100;
    f.devices.at(2).inputs.at(0).signal.wire_subindex = 0;
    EXPECT_EQ(refusal(f), "accepted") << "an entry of the default RxPDOs";
}

}  // namespace
}  // namespace vecat::network
