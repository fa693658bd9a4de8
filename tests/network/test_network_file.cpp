// Network files (src/network): the reader and its checks (every refusal names the line), the order the
// frame reaches the devices, and networks of mixed devices built and brought to OP by the project master.
// About 700 lines: the reader and the networks it builds share the Served fixture and the example files.
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "common/bytes.hpp"
#include "device/simple_devices.hpp"
#include "device/soe_drive.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "network/build.hpp"
#include "network/network_file.hpp"
#include "network_support.hpp"
#include "protocol/cia402_objects.hpp"
#include "serve/in_process_link.hpp"
#include "shared_data.hpp"

namespace vecat::network {
namespace {

std::string names(const NetworkFile& f) {
    std::string s;
    for (const auto& d : f.devices)
        s += (s.empty() ? "" : " ") + d.name;
    return s;
}

// The message of the refusal of text ("" if it was accepted).
std::string refusal(const std::string& text) {
    try {
        parse_network(text, "net.yaml");
    } catch (const NetworkFileError& e) {
        return e.what();
    }
    return "";
}

TEST(NetworkFile, ALineNeedsNoCabling) {
    const auto f = parse_network(R"(
devices:
  - name: a
    device: drive
  - name: b
    device: drive
  - name: c
    device: digital-in
    channels: 4
)");
    EXPECT_EQ(names(f), "a b c");
    EXPECT_EQ(f.parent, (std::vector<int>{-1, 0, 1}));
    EXPECT_EQ(f.children[0][1], 1);
    EXPECT_EQ(f.devices[2].channels, 4u);
    EXPECT_EQ(f.devices[2].source, Source::DigitalIn);
}

TEST(NetworkFile, ATreeIsOrderedAsTheFramePassesThePorts) {
    // coupler: port 3 (E-bus) before port 1; the junction: 3, then 1, then 2 (ESC processing order).
    const auto f = parse_network(R"(
devices:
  - name: coupler
    device: coupler
  - name: out-rj45
    device: junction
    upstream: coupler:1
  - name: j-port2
    device: drive
    upstream: out-rj45:2
  - name: j-port1
    device: drive
    upstream: out-rj45:1
  - name: ebus1
    device: digital-out
    upstream: coupler:3
  - name: ebus2
    device: digital-in
  - name: j-port3
    device: analog-in
    upstream: out-rj45:3
    cable_delay_ns: 120
)");
    EXPECT_EQ(names(f), "coupler ebus1 ebus2 out-rj45 j-port3 j-port1 j-port2");
    EXPECT_EQ(f.parent, (std::vector<int>{-1, 0, 1, 0, 3, 3, 3}));
    EXPECT_EQ(f.children[0][3], 1);
    EXPECT_EQ(f.children[0][1], 3);
    EXPECT_EQ(f.children[3][2], 6);
    EXPECT_EQ(f.devices[4].cable_delay_ns, 120u);
    EXPECT_EQ(f.devices[1].cable_delay_ns, kDefaultCableDelayNs);
}

TEST(NetworkFile, EveryRefusalNamesTheLine) {
    const std::pair<const char*, const char*> cases[] = {
        {"devices:\n  - name: a\n    device: drive\n  - name: a\n    device: drive\n",
         "net.yaml:4: a second device named a (the first is on line 2)"},
        {"devices:\n  - name: a\n    device: drive\n  - name: b\n    device: drive\n    upstream: x\n",
         "net.yaml:4: b: upstream: no device named x"},
        {"devices:\n  - name: a\n    device: junction\n  - name: b\n    device: drive\n  - name: c\n    "
         "device: drive\n"
         "    upstream: a:1\n",
         "net.yaml:6: c: port 1 of a is already cabled to b (line 4)"},
        {"devices:\n  - name: a\n    device: drive\n  - name: b\n    device: drive\n    upstream: c\n  - "
         "name: c\n"
         "    device: drive\n    upstream: b\n",
         "its upstream cables form a loop"},
        {"devices:\n  - name: a\n    device: drive\n    colour: red\n", "net.yaml:4: unknown key colour"},
        {"devices:\n  - name: a\n    device: toaster\n", "net.yaml:3: device: unknown device toaster"},
        {"devices:\n  - name: a\n    device: drive\n    upstream: b\n",
         "net.yaml:2: a: the first device is cabled to the master"},
        {"devices:\n  - name: a\n    device: drive\n    channels: 4\n",
         "net.yaml:4: a: channels: is for the built-in I/O terminals"},
        {"devices:\n  - name: a\n    device: digital-in\n    channels: lots\n",
         "net.yaml:4: channels: \"lots\" is not a number"},
        {"devices:\n  - name: a\n    device: digital-in\n    channels: 65\n", "is larger than 64"},
        {"devices:\n  - name: a\n    device: drive\n  - name: b\n    device: drive\n    upstream: a:4\n",
         "net.yaml:6: upstream: the port after ':' is 1, 2 or 3"},
        {"devices:\n  - name: a\n    device: drive\n  - name: b\n    device: drive\n    upstream: a:3\n",
         "net.yaml:4: b: a (drive) has no port 3"},
        {"devices:\n  - name: a\n    device: drive\n    type: X\n",
         "net.yaml:4: a: type:, product: and revision:"},
        {"devices:\n  - name: a\n    device: drive\n    esi: x.xml\n", "net.yaml:2: a: give exactly one of"},
        {"devices:\n  - name: a\n", "net.yaml:2: a: give exactly one of"},
        {"devices:\n  - device: drive\n", "net.yaml:2: a device without name:"},
        {"devices: [\n", "net.yaml:"},
        {"devices: []\n", "devices: a list of at least one device"},
        {"- a\n- b\n", "a network file is a map with devices:"},
        {"devices:\n  - name: a\n    device: drive\n    identity: {vendor: 1, colour: 2}\n",
         "identity: unknown key colour"},
        {"devices:\n  - name: a\n    device: drive\n  - name: b\n    device: drive\nredundancy: a:1\n",
         "net.yaml:6: redundancy: port 1 of a is already cabled to b"},
        {"devices:\n  - name: a\n    device: drive\nredundancy: x:1\n",
         "net.yaml:4: redundancy: no device named x"},
        {"devices:\n  - name: a\n    device: drive\nredundancy: a:3\n",
         "net.yaml:4: redundancy: a (drive) has no port 3"},
        {"devices:\n  - name: a\n    device: drive\nredundancy: a:0\n",
         "net.yaml:4: upstream: the port after"},
    };
    for (const auto& [text, expected] : cases) {
        const std::string got = refusal(text);
        EXPECT_NE(got.find(expected), std::string::npos) << "file:\n" << text << "\nrefused with: " << got;
    }
}

TEST(NetworkFile, RelativePathsStartAtTheFilesFolder) {
    const auto f = parse_network("devices:\n  - name: a\n    sii: dumps/x.bin\n", "n", "/etc/machine");
    EXPECT_EQ(f.devices[0].path, "/etc/machine/dumps/x.bin");
    EXPECT_EQ(f.devices[0].source, Source::Sii);
}

// A mixed line brought to OP by the project master behind an in-process link.
using Served = vecat::test::ServedNetwork;

TEST(Network, BuiltInDevicesAndDrivesReachOpWithTheExpectedWorkingCounter) {
    Served s(R"(
devices:
  - name: coupler
    device: coupler
    alias: 7
  - name: drive
    device: drive
    identity: {serial: 0x1234}
  - name: di
    device: digital-in
    channels: 12
  - name: do
    device: digital-out
  - name: ai
    device: analog-in
    channels: 2
  - name: ao
    device: analog-out
)");
    ASSERT_EQ(s.built.segment->size(), 6u);
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::Op, &why)) << why;
    const auto& sl = s.master.slaves();
    EXPECT_EQ(sl[0].sii.identity.product_code, device::simple_product::Coupler);
    EXPECT_EQ(sl[0].sii.station_alias, 7);
    EXPECT_EQ(sl[1].sii.identity.serial, 0x1234u);
    EXPECT_EQ(sl[2].sii.identity.product_code, device::simple_product::DigitalIn | 12);
    EXPECT_EQ(sl[2].in_bytes, 2u);
    EXPECT_EQ(sl[3].out_bytes, 1u);
    EXPECT_EQ(sl[4].in_bytes, 4u);
    EXPECT_EQ(sl[5].out_bytes, 8u);
    // drive: outputs and inputs (3); each terminal one direction (2 for outputs, 1 for inputs).
    EXPECT_EQ(s.master.expected_wkc(), 3 + 1 + 2 + 1 + 2);
    for (int i = 0; i < 100; ++i)
        ASSERT_EQ(s.master.exchange_process_data().value_or(0), s.master.expected_wkc());
    // The outputs of the digital output terminal reach its process image.
    s.master.outputs(3)[0] = 0xA5;
    s.master.exchange_process_data();
    auto& app = dynamic_cast<esc::ProcessImageApplication&>(s.built.segment->slave(3).app());
    s.built.segment->tick(s.link.now_ns());
    EXPECT_EQ(app.outputs()[0], 0xA5);
}

// The entries the master mapped, from the PDO assignment read by SDO (the drive) and from the SII (the
// terminals): each object at the bit where the slave's data hold it.
TEST(Network, TheMasterKnowsWhereEachMappedObjectLies) {
    Served s(R"(
devices:
  - name: drive
    device: drive
  - name: do
    device: digital-out
    channels: 4
  - name: ai
    device: analog-in
    channels: 2
)");
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::Op, &why)) << why;
    const auto& drive = s.master.slaves()[0];
    const auto* cw = master::find_entry(drive.out_entries, protocol::obj::controlword.index);
    const auto* target = master::find_entry(drive.out_entries, protocol::obj::target_position.index);
    const auto* sw = master::find_entry(drive.in_entries, protocol::obj::statusword.index);
    const auto* pos = master::find_entry(drive.in_entries, protocol::obj::position_actual_value.index);
    ASSERT_TRUE(cw && target && sw && pos);
    EXPECT_EQ(cw->bits, 16);
    EXPECT_EQ(target->bits, 32);
    // The entries tile the area: each starts where the one before it ends, and the last ends at its size.
    for (const auto* entries : {&drive.out_entries, &drive.in_entries}) {
        std::uint32_t bit = 0;
        for (const auto& e : *entries) {
            EXPECT_EQ(e.bit_offset, bit);
            bit += e.bits;
        }
        EXPECT_EQ((bit + 7) / 8, entries == &drive.out_entries ? drive.out_bytes : drive.in_bytes);
    }
    // The drive's statusword, read where the entry says, is what the drive shows.
    ASSERT_TRUE(s.master.exchange_process_data());
    const auto in = s.master.inputs(0);
    EXPECT_NE(ld_le16(in.data() + sw->bit_offset / 8), 0) << "a CiA 402 drive in OP shows its state";
    // The output terminal: four 1-bit channels from the SII, bits 0-3, and a 4-bit gap (index 0) to the
    // byte; the analog inputs two 16-bit values.
    const auto& out = s.master.slaves()[1].out_entries;
    ASSERT_EQ(out.size(), 5u);
    for (std::uint32_t i = 0; i < 4; ++i) {
        EXPECT_NE(out[i].index, 0);
        EXPECT_EQ(out[i].bits, 1);
        EXPECT_EQ(out[i].bit_offset, i);
    }
    EXPECT_EQ(out[4].index, 0);
    EXPECT_EQ(out[4].bit_offset, 4u);
    EXPECT_EQ(out[4].bits, 4);
    const auto& ai = s.master.slaves()[2].in_entries;
    ASSERT_EQ(ai.size(), 2u);
    EXPECT_EQ(ai[1].bit_offset, 16u);
    EXPECT_EQ(ai[1].bits, 16);
}

// Wires to and from the vecat drive: a terminal's output drives touch probe input 1 of a drive, another
// drive's digital output (0x60FE, where its mask lets it through) touch probe input 2, and the touch probe
// latches on the wired edge.
TEST(Network, WiresDriveTheTouchProbeInputsOfADrive) {
    Served s(R"(
devices:
  - name: axis
    device: drive
  - name: valves
    device: digital-out
    channels: 2
  - name: gauge
    device: drive
    identity: {serial: 2}
    inputs:
      0: {wire: valves:1}
      1: {wire: axis:16}
)");
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::Op, &why)) << why;
    master::CoeClient axis(s.master, s.master.slaves()[0].station),
        gauge(s.master, s.master.slaves()[2].station);
    auto download32 = [](master::CoeClient& c, protocol::ObjectId<protocol::DataType::Unsigned32> o,
                         std::uint32_t v) {
        std::uint8_t b[4];
        st_le32(b, v);
        return c.download(o.index, o.subindex, ConstBytes(b, 4)).ok();
    };
    // Touch probe 1: enabled, first event, its input, positive edge (0x60B8 = 0x0011, CiA 402 60B8h).
    const auto* tp =
        master::find_entry(s.master.slaves()[2].out_entries, protocol::obj::touch_probe_function.index);
    ASSERT_NE(tp, nullptr) << "the drive's default RxPDO maps 0x60B8";
    auto run = [&](int cycles) {
        for (int i = 0; i < cycles; ++i) {
            st_le16(s.master.outputs(2).data() + tp->bit_offset / 8, 0x0011);
            ASSERT_EQ(s.master.exchange_process_data().value_or(0), s.master.expected_wkc());
            std::this_thread::sleep_for(std::chrono::microseconds(500));
        }
    };
    auto digital_inputs = [&] {
        const auto r = gauge.upload(protocol::obj::digital_inputs.index, 0);
        EXPECT_TRUE(r.ok());
        return r.ok() && r.data.size() >= 4 ? ld_le32(r.data.data()) : 0u;
    };
    auto probe_status = [&] {
        const auto r = gauge.upload(protocol::obj::touch_probe_status.index, 0);
        return r.ok() && r.data.size() >= 2 ? ld_le16(r.data.data()) : 0u;
    };
    run(10);
    EXPECT_EQ(digital_inputs() & (3u << 16), 0u) << "nothing set: both probe inputs low";
    EXPECT_EQ(probe_status() & 0x2u, 0u);
    // valves channel 1 on: touch probe input 1 (0x60FD bit 16) and a latched positive edge (0x60B9 bit 1).
    s.master.outputs(1)[0] = 0x02;
    run(10);
    EXPECT_EQ(digital_inputs() & (3u << 16), 1u << 16);
    EXPECT_EQ(probe_status() & 0x3u, 0x3u) << "probe 1 enabled, its positive edge stored";
    s.master.outputs(1)[0] = 0x00;
    run(10);
    EXPECT_EQ(digital_inputs() & (1u << 16), 0u);
    // axis: digital output 16 set but masked off: the wire stays low; with its mask bit: high.
    ASSERT_TRUE(download32(axis, protocol::obj::digital_outputs::physical_outputs, 1u << 16));
    run(10);
    EXPECT_EQ(digital_inputs() & (1u << 17), 0u) << "0x60FE:2 masks the output off";
    ASSERT_TRUE(download32(axis, protocol::obj::digital_outputs::bit_mask, 1u << 16));
    run(10);
    EXPECT_EQ(digital_inputs() & (1u << 17), 1u << 17);
    ASSERT_TRUE(download32(axis, protocol::obj::digital_outputs::physical_outputs, 0));
    run(10);
    EXPECT_EQ(digital_inputs() & (1u << 17), 0u);
}

TEST(NetworkFile, DriveWiresAreCheckedWithTheirLine) {
    auto refused = [](const std::string& text) {
        try {
            parse_network(text, "n.yaml");
        } catch (const NetworkFileError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    EXPECT_NE(
        refused(
            "devices:\n  - name: a\n    device: drive\n    inputs:\n      2: {signal: constant, value: 1}\n")
            .find("n.yaml:5: a: inputs: channel 2: it has channels 0-1 (touch probe inputs 1 and 2)"),
        std::string::npos);
    EXPECT_NE(refused("devices:\n  - name: a\n    device: drive\n  - name: b\n    device: digital-in\n"
                      "    inputs:\n      0: {wire: a:32}\n")
                  .find("n.yaml:7: b: wire: a has channels 0-31"),
              std::string::npos);
    EXPECT_NE(refused("devices:\n  - name: a\n    device: coupler\n  - name: b\n    device: drive\n"
                      "    inputs:\n      0: {wire: a:0}\n")
                  .find("n.yaml:7: b: wire: a is no output terminal"),
              std::string::npos);
    EXPECT_NE(refused("devices:\n  - name: a\n    device: hiwin-d2\n    inputs:\n      0: {wire: a:0}\n")
                  .find("n.yaml:5: a: inputs: is for the built-in input terminals"),
              std::string::npos);
}

// A device with two output SyncManagers (the EL2262's oversampling outputs, SM0 and SM1): an FMMU for each
// area, one after the other, and the slave counted once per datagram (2 for its outputs, 1 for its inputs)
// however many FMMUs it has. The master counted each SyncManager before, and missed every cycle.
TEST(Network, ADeviceWithSeveralOutputSyncManagersCountsOncePerDatagram) {
    VECAT_REQUIRE_SHARED_DATA("sii/beckhoff-el2262.bin");
    const std::string path = std::string(VECAT_SOURCE_DIR) + "/examples/networks/machine.yaml";
    auto built = build_network(read_network_file(path), path);
    net::InProcessLink link(*built.segment);
    master::Master m(link);
    std::string why;
    ASSERT_TRUE(m.startup(protocol::AlState::Op, &why)) << why;
    const auto& el2262 = m.slaves()[5];
    ASSERT_EQ(el2262.sii.identity.product_code, 0x08D63052u);
    unsigned output_sms = 0, out_bytes = 0;
    for (const auto& pd : el2262.pd_sms)
        if (pd.outputs) ++output_sms, out_bytes += pd.bytes;
    EXPECT_EQ(output_sms, 2u);
    EXPECT_EQ(out_bytes, el2262.out_bytes);
    // Outputs of EL2004, EL2828, EL2889, EL2262 and three drives (2 each); inputs of the EL2262 and the
    // three drives (1 each): what SOEM's simple_ng expects on this machine too.
    EXPECT_EQ(m.expected_wkc(), 7 * 2 + 4);
    for (int i = 0; i < 50; ++i)
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc()) << "cycle " << i;
}

// A network of mixed drives: the vecat drive and the HIWIN D2 (device: hiwin-d2), each with its own
// identity and default process data, on the same line to OP.
TEST(Network, TheHiwinD2BesideTheVecatDrive) {
    Served s(R"(
devices:
  - name: vecat
    device: drive
  - name: d2
    device: hiwin-d2
)");
    ASSERT_EQ(s.built.segment->size(), 2u);
    EXPECT_EQ(parse_network("devices:\n  - name: d2\n    device: hiwin-d2\n", "n.yaml").devices.at(0).source,
              Source::HiwinD2);
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::Op, &why)) << why;
    const auto& sl = s.master.slaves();
    EXPECT_EQ(sl[0].sii.identity.vendor_id, 0x00000A3Cu);
    EXPECT_EQ(sl[1].sii.identity.vendor_id, 0x0000AAAAu);
    EXPECT_EQ(sl[1].sii.identity.product_code, 3u);
    EXPECT_EQ(sl[1].out_bytes, 7u);  // HIWIN guide 7: ControlWord, Target Position, Mode of operation
    EXPECT_EQ(sl[1].in_bytes, 10u);  // StatusWord, Position Actual Value, Velocity Actual Value
    for (int i = 0; i < 10; ++i)
        ASSERT_EQ(s.master.exchange_process_data().value_or(0), s.master.expected_wkc());
}

// The SoE drive (device: soe-drive) beside the vecat CoE drive: the master maps one by CoE, the other by
// SoE (S-0-0024/S-0-0016 and the attributes, as SOEM's ecx_readIDNmap), both reach OP.
TEST(Network, TheSoeDriveBesideTheVecatDrive) {
    Served s(R"(
devices:
  - name: vecat
    device: drive
  - name: ax
    device: soe-drive
)");
    ASSERT_EQ(s.built.segment->size(), 2u);
    EXPECT_EQ(parse_network("devices:\n  - name: ax\n    device: soe-drive\n", "n.yaml").devices.at(0).source,
              Source::SoeDrive);
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::Op, &why)) << why;
    const auto& sl = s.master.slaves();
    EXPECT_EQ(sl[1].sii.mailbox_protocols, 0x0010);
    EXPECT_EQ(sl[1].out_bytes, 6u);  // control word + S-0-0047
    EXPECT_EQ(sl[1].in_bytes, 6u);   // status word + S-0-0051
    for (int i = 0; i < 10; ++i)
        ASSERT_EQ(s.master.exchange_process_data().value_or(0), s.master.expected_wkc());
}

// device: soe-drive-2, the two-axis SoE drive: the master sums drives 0 and 1 (drives 2-7 answer 0x800A), the
// SyncManagers hold both blocks, OP with both.
TEST(Network, TheTwoAxisSoeDrive) {
    Served s("devices:\n  - name: ax2\n    device: soe-drive-2\n");
    EXPECT_EQ(
        parse_network("devices:\n  - name: ax2\n    device: soe-drive-2\n", "n.yaml").devices.at(0).source,
        Source::SoeDrive2);
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::Op, &why)) << why;
    const auto& sl = s.master.slaves();
    EXPECT_EQ(sl[0].sii.identity.product_code, device::kSoeDrive2Product);
    EXPECT_EQ(sl[0].out_bytes, 12u);  // (control word + S-0-0047) x 2
    EXPECT_EQ(sl[0].in_bytes, 12u);   // (status word + S-0-0051) x 2
    for (int i = 0; i < 10; ++i)
        ASSERT_EQ(s.master.exchange_process_data().value_or(0), s.master.expected_wkc());
}

TEST(Network, ADeviceFromAnSiiDumpServesTheDumpAndItsProcessData) {
    VECAT_REQUIRE_SHARED_DATA("sii");
    const std::string sii = test::shared_data("sii/");
    Served s("devices:\n  - name: coupler\n    sii: " + sii +
             "beckhoff-ek1100.bin\n  - name: out\n    sii: " + sii +
             "beckhoff-el2004.bin\n  - name: akd\n    sii: " + sii + "kollmorgen-akd.bin\n    alias: 0x42\n");
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::PreOp, &why)) << why;
    const auto& sl = s.master.slaves();
    ASSERT_EQ(sl.size(), 3u);
    EXPECT_EQ(sl[0].sii.identity.vendor_id, 2u);  // Beckhoff
    EXPECT_NE(sl[0].sii.device_name().find("EK1100"), std::string::npos) << sl[0].sii.device_name();
    EXPECT_NE(sl[1].sii.device_name().find("EL2004"), std::string::npos) << sl[1].sii.device_name();
    EXPECT_EQ(sl[2].sii.station_alias, 0x42);
    EXPECT_TRUE(sl[2].sii.checksum_ok);
    // The dump itself is what the ESC serves, but for the alias and its checksum.
    std::ifstream f(sii + "beckhoff-el2004.bin", std::ios::binary);
    const std::vector<std::uint8_t> dump((std::istreambuf_iterator<char>(f)),
                                         std::istreambuf_iterator<char>());
    EXPECT_EQ(s.built.segment->slave(1).esc().eeprom(), dump);
}

TEST(Network, AnUnreadableSiiDumpIsRefusedWithItsLine) {
    const auto junk = std::filesystem::temp_directory_path() / "vecat-not-an-sii.bin";
    std::ofstream(junk) << "hello";
    try {
        build_network(parse_network("devices:\n  - name: a\n    device: drive\n  - name: b\n    sii: " +
                                    junk.string() + "\n"),
                      "net.yaml");
        ADD_FAILURE() << "accepted";
    } catch (const NetworkFileError& e) {
        EXPECT_NE(std::string(e.what()).find("net.yaml:4: b: "), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("not an SII image"), std::string::npos) << e.what();
    }
    std::filesystem::remove(junk);
}

// A junction with a branch on each port (as examples/networks/junction-tree.yaml): positions 0 junction,
// 1 on port 3, 2-3 on port 1, 4 on port 2; every cable 500 ns unless given.
constexpr const char* kTree = R"(
devices:
  - name: junction
    device: junction
  - name: p3
    device: drive
    upstream: junction:3
  - name: p1
    device: digital-out
    upstream: junction:1
    cable_delay_ns: 200
  - name: p1b
    device: analog-out
  - name: p2
    device: drive
    upstream: junction:2
)";

std::uint16_t brd_wkc(master::Master& m) {
    std::uint8_t b[2] = {};
    return m.brd(0x0000, b).value_or(0xFFFF);
}

TEST(NetworkPorts, TheFramePassesTheTreeAndEachPortLatchesItsReceiveTime) {
    Served s(kTree);
    auto& m = s.master;
    ASSERT_EQ(brd_wkc(m), 5);
    std::uint8_t z[4] = {};
    ASSERT_EQ(m.bwr(protocol::addr(protocol::Reg::DcRecvTimePort0), z).value_or(0), 5);
    std::uint8_t t[16] = {};
    ASSERT_EQ(m.aprd(0, protocol::addr(protocol::Reg::DcRecvTimePort0), t).value_or(0), 1);
    const auto at = [&](unsigned p) { return ld_le32(t + 4 * p) - ld_le32(t); };
    // Port 3 first: 500 ns there and back; port 1: then 200 + 500 to the second terminal and back; port 2
    // last.
    EXPECT_EQ(at(3), 1000u);
    EXPECT_EQ(at(1), 1000u + 2 * (200 + 500));
    EXPECT_EQ(at(2), 1000u + 1400 + 1000);
    // Every port of the junction has a link and is open (DL status: link bits 4-7, no loop closed).
    std::uint8_t dl[2] = {};
    ASSERT_EQ(m.aprd(0, protocol::addr(protocol::Reg::DlStatus), dl).value_or(0), 1);
    EXPECT_EQ(ld_le16(dl) & 0xF0, 0xF0);
    EXPECT_EQ(ld_le16(dl) & 0x5500, 0);
    // Auto-increment addressing follows the order: position 2 is the first terminal on port 1.
    std::uint8_t id[4] = {};
    ASSERT_EQ(m.aprd(2, protocol::addr(protocol::Reg::Type), id).value_or(0), 1);
    EXPECT_EQ(s.built.segment->slave(2).description().identity.product_code,
              device::simple_product::DigitalOut | 8);
}

// The project master with distributed clocks brought to PREOP on a network file: it must find the file's
// devices (identities), tree (parent and its port) and propagation delays (within 10 ns).
void expect_the_files_tree_and_delays(const NetworkFile& f, const std::string& name,
                                      const std::vector<std::uint32_t>& delays) {
    auto built = build_network(f, name);
    net::InProcessLink link(*built.segment);
    master::MasterOptions o;
    o.dc.enable = true;
    o.dc.sync0_cycle_ns = 0;
    o.dc.static_drift_frames = 10;
    master::Master m(link, o);
    std::string why;
    ASSERT_TRUE(m.startup(protocol::AlState::PreOp, &why)) << why;
    ASSERT_TRUE(m.configure_dc());
    const auto& sl = m.slaves();
    ASSERT_EQ(sl.size(), f.devices.size());
    ASSERT_EQ(delays.size(), f.devices.size());
    for (std::size_t i = 0; i < sl.size(); ++i) {
        SCOPED_TRACE(f.devices[i].name);
        EXPECT_EQ(sl[i].sii.identity.product_code,
                  built.segment->slave(i).description().identity.product_code);
        EXPECT_EQ(sl[i].parent, f.parent[i]);
        if (f.parent[i] >= 0) {
            EXPECT_EQ(sl[i].parent_port, f.devices[i].upstream_port);
        }
        EXPECT_NEAR(sl[i].dc_delay_ns, delays[i], 10);
    }
}

TEST(NetworkPorts, TheProjectMasterComputesTheTreeAndItsDelaysAsTheFileDescribesThem) {
    // Propagation delays from the reference clock (the junction): the frame's arrival at each device, from
    // the cable delays of the file and the branches it passes first.
    expect_the_files_tree_and_delays(parse_network(kTree), "tree",
                                     {0, 500, 1000 + 200, 1000 + 200 + 500, 1000 + 1400 + 500});
}

// The machine of examples/networks/machine.yaml (EK1100 and four terminals from SII dumps, a junction, two
// vecat drives and a vendor drive from its ESI): the project master finds the file's tree and delays (SOEM
// 2.x and 1.4 slaveinfo show the same delays: docs/network-file.md).
TEST(NetworkPorts, TheExampleMachinesTreeAndDelaysAsTheFileDescribesThem) {
    VECAT_REQUIRE_SHARED_DATA("sii/beckhoff-el2262.bin");
    const std::string path = std::string(VECAT_SOURCE_DIR) + "/examples/networks/machine.yaml";
    // The coupler's E-bus (port 1) with the junction and its branch of 150 + 700 + 3 x 150 ns comes first;
    // the drives behind its X2 (port 2, 900 ns) see the frame after its round trip through that branch.
    expect_the_files_tree_and_delays(read_network_file(path), path,
                                     {0, 150, 850, 1000, 1150, 1300, 2 * 1300 + 900, 3500 + 500, 4000 + 600});
}

// DL control 0x0101: the loop setting of ports 0-3, two bits each (0 auto, 1 auto close, 2 open, 3 closed).
void set_loop(master::Master& m, unsigned port, unsigned setting) {
    std::uint8_t v[1] = {static_cast<std::uint8_t>(setting << (2 * port))};
    ASSERT_EQ(m.apwr(0, protocol::addr(protocol::Reg::DlControl) + 1, v).value_or(0), 1);
}
bool loop_closed(master::Master& m, unsigned port) {
    std::uint8_t dl[2] = {};
    m.aprd(0, protocol::addr(protocol::Reg::DlStatus), dl);
    return (ld_le16(dl) >> (8 + 2 * port)) & 1u;
}

TEST(NetworkPorts, EveryLoopSettingOnEveryPort) {
    Served s(kTree);
    auto& m = s.master;
    auto& seg = *s.built.segment;
    // Slaves behind each port of the junction.
    const std::pair<unsigned, std::uint16_t> behind[] = {{1, 2}, {2, 1}, {3, 1}};
    for (const auto& [port, n] : behind) {
        SCOPED_TRACE("port " + std::to_string(port));
        set_loop(m, port, 3);  // closed: the frame turns back at the junction
        EXPECT_EQ(brd_wkc(m), 5 - n);
        EXPECT_TRUE(loop_closed(m, port));
        set_loop(m, port, 2);  // open (it has a link)
        EXPECT_EQ(brd_wkc(m), 5);
        EXPECT_FALSE(loop_closed(m, port));
        set_loop(m, port, 0);  // auto: open while the link is there
        EXPECT_EQ(brd_wkc(m), 5);
        // Auto: the cable into the branch breaks and comes back, the port follows the link.
        const std::size_t first = port == 3 ? 1 : port == 1 ? 2 : 4;  // the slave cabled to the port
        seg.set_cable(first, false);
        EXPECT_EQ(brd_wkc(m), 5 - n);
        EXPECT_TRUE(loop_closed(m, port));
        seg.set_cable(first, true);
        EXPECT_EQ(brd_wkc(m), 5);
        // Auto close: closed at the link loss, and it stays closed when the link is back...
        set_loop(m, port, 1);
        seg.set_cable(first, false);
        seg.set_cable(first, true);
        EXPECT_EQ(brd_wkc(m), 5 - n);
        EXPECT_TRUE(loop_closed(m, port));
        // ... until the master writes the setting again.
        set_loop(m, port, 1);
        EXPECT_EQ(brd_wkc(m), 5);
        // Open without a link: the frame leaves through the port and is lost.
        set_loop(m, port, 2);
        seg.set_cable(first, false);
        EXPECT_EQ(brd_wkc(m), 0xFFFF) << "no reply";
        seg.set_cable(first, true);
        EXPECT_EQ(brd_wkc(m), 5);
        set_loop(m, port, 0);
    }
}

TEST(Network, EveryExampleFileBuilds) {
    unsigned n = 0;
    for (const auto& e :
         std::filesystem::directory_iterator(std::string(VECAT_SOURCE_DIR) + "/examples/networks")) {
        if (e.path().extension() != ".yaml") continue;
        const auto f = read_network_file(e.path().string());
        // The example of real devices needs ../shared beside the clone.
        bool shared = false;
        for (const auto& d : f.devices)
            shared |= d.path.find("shared/data") != std::string::npos;
        if (shared && !std::filesystem::exists(test::shared_data("sii"))) continue;
        EXPECT_NO_THROW(build_network(f, e.path().string())) << e.path();
        ++n;
    }
    EXPECT_GE(n, 2u);
}

TEST(NetworkFile, RedundancyCablesAFreePortBackToTheMaster) {
    // A junction with a branch of two drives on port 3, a drive on port 1; the branch's far end is cabled
    // back to the master's second port.
    const auto f = parse_network(R"(
devices:
  - name: junction
    device: junction
  - name: b1
    device: drive
    upstream: junction:3
  - name: b2
    device: drive
  - name: main
    device: drive
    upstream: junction:1
redundancy: b2:1
)");
    ASSERT_EQ(f.devices.size(), 4u);
    EXPECT_EQ(f.devices[static_cast<std::size_t>(f.redundancy_device)].name, "b2");
    EXPECT_EQ(f.redundancy_port, 1u);
    EXPECT_EQ(f.redundancy_line, 13u);
    auto built = build_network(f, "net.yaml");
    esc::Segment& seg = *built.segment;
    ASSERT_TRUE(seg.redundant());
    EXPECT_EQ(seg.redundancy_slave(), 2u);  // junction, b1, b2, main
    // Whole: the frame from the primary port goes through the junction's port 3, b1, b2 and out to the
    // secondary port: it leaves the ring before the junction's port 1 (main) in the order 0 -> 3 -> 1.
    std::array<std::uint8_t, 64> buf{};
    const auto brd = [&](esc::MasterPort from, std::uint16_t& wkc, esc::MasterPort& at) {
        buf.fill(0);
        std::memset(buf.data(), 0xFF, 6);
        buf[12] = 0x88, buf[13] = 0xA4;
        st_le16(buf.data() + 14, 0x1000 | 14);
        buf[16] = static_cast<std::uint8_t>(protocol::Command::BRD);
        st_le16(buf.data() + 22, 2);
        std::size_t len = 14 + 2 + 14;
        const bool back = seg.process_frame(Bytes(buf.data(), buf.size()), len, 1'000'000, {}, from);
        wkc = ld_le16(buf.data() + 14 + 2 + 12);
        at = seg.reply_port();
        return back;
    };
    std::uint16_t wkc = 0;
    esc::MasterPort at{};
    ASSERT_TRUE(brd(esc::MasterPort::Primary, wkc, at));
    EXPECT_EQ(at, esc::MasterPort::Secondary);
    EXPECT_EQ(wkc, 3);  // the junction, b1, b2: the frame leaves the ring at b2 before it reaches main
    // The branch cable into b2 breaks: the junction, b1 from the primary side (and main, behind port 1 of
    // the junction), b2 from the secondary side.
    seg.set_cable(2, false);
    ASSERT_TRUE(brd(esc::MasterPort::Primary, wkc, at));
    EXPECT_EQ(at, esc::MasterPort::Primary);
    EXPECT_EQ(wkc, 3);
    ASSERT_TRUE(brd(esc::MasterPort::Secondary, wkc, at));
    EXPECT_EQ(at, esc::MasterPort::Secondary);
    EXPECT_EQ(wkc, 1);
}

}  // namespace
}  // namespace vecat::network
