// Quirks per device in a network file (quirks:, docs/network-file.md): read, refused with the line, and
// what the master sees of the devices built with them: the SII the ESC serves (a generated one, or an
// sii: dump with its CoE details patched), the ESI written for the device, the mailbox answers.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "esi/esi_reader.hpp"
#include "esi/esi_writer.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "network/build.hpp"
#include "network/network_file.hpp"
#include "network_support.hpp"
#include "protocol/coe.hpp"
#include "protocol/sii.hpp"
#include "serve/in_process_link.hpp"
#include "shared_data.hpp"

namespace vecat::network {
namespace {

namespace cd = device::coe_details;
using protocol::AlState;

// The message of the refusal of text, reading it and making its devices ("" if it was accepted).
const auto refusal = vecat::test::build_refusal;

struct Served : vecat::test::ServedNetwork {
    explicit Served(const std::string& text) : ServedNetwork(text, From::Text, 1'000'000'000) {}
};

TEST(NetworkQuirks, ReadAsAListOrOneQuirk) {
    const auto f = parse_network(R"(
devices:
  - name: axis
    device: drive
    quirks: [no_sdo_info, max_pdo_entries=12, mailbox_delay_ms=3]
  - name: io
    device: digital-in
    quirks: sii_without=strings+dc
)");
    ASSERT_EQ(f.devices.size(), 2u);
    EXPECT_TRUE(f.devices[0].quirks.no_sdo_info);
    EXPECT_EQ(f.devices[0].quirks.max_pdo_entries, 12u);
    EXPECT_EQ(f.devices[0].quirks.mailbox_delay_ns, 3'000'000u);
    EXPECT_EQ(f.devices[0].quirks_line, 5u);
    EXPECT_EQ(f.devices[1].quirks.sii_without, device::sii_optional::Strings | device::sii_optional::Dc);
    EXPECT_FALSE(f.devices[1].quirks.no_sdo_info);
}

TEST(NetworkQuirks, EveryRefusalNamesTheLine) {
    const std::pair<const char*, const char*> cases[] = {
        {"devices:\n  - name: a\n    device: drive\n    quirks: [no_sdo_info, slow]\n",
         "net.yaml:4: quirks: unknown quirk \"slow\""},
        {"devices:\n  - name: a\n    device: drive\n    quirks:\n      - fixed_pdos\n      - "
         "max_pdo_entries=0\n",
         "net.yaml:6: quirks: max_pdo_entries: \"0\" is not 1..254"},
        {"devices:\n  - name: a\n    device: drive\n    quirks: {no_sdo_info: true}\n",
         "net.yaml:4: quirks: a list of quirks"},
        {"devices:\n  - name: a\n    device: drive\n    quirks: [max_pdo_entries=4]\n",
         "net.yaml:4: a: quirks: max_pdo_entries=4: the default mapping of 0x1600 has 7 entries"},
        {"devices:\n  - name: a\n    device: coupler\n  - name: b\n    device: digital-out\n    quirks: "
         "[no_complete_access]\n",
         "net.yaml:6: b: quirks: no_sdo_info, no_complete_access, max_pdo_entries, fixed_pdos and "
         "sdo_download_echo are CoE quirks"},
        {"devices:\n  - name: a\n    device: digital-out\n    quirks: [mailbox_drop_every=3]\n",
         "net.yaml:4: a: quirks: mailbox_delay_ms, mailbox_drop_every and mailbox_open_early: the device has "
         "no "
         "mailbox"},
        {"devices:\n  - name: a\n    sii: x.bin\n    quirks: [sii_without=pdo]\n",
         "net.yaml:4: a: quirks: sii_without: an sii: device serves its dump as it is"},
    };
    for (const auto& [text, expected] : cases) {
        const std::string got = refusal(text);
        EXPECT_NE(got.find(expected), std::string::npos) << "file:\n" << text << "\nrefused with: " << got;
    }
}

// The quirks of each device reach what the master reads and what the ESI of the device says; a device of
// the same file without quirks is not touched.
TEST(NetworkQuirks, TheSiiAndTheEsiOfADeviceSayWhatItLacks) {
    Served s(R"(
devices:
  - name: plain
    device: drive
  - name: lean
    device: drive
    quirks: [no_sdo_info, no_complete_access, fixed_pdos]
  - name: io
    device: digital-in
    quirks: [sii_without=strings]
)");
    std::string why;
    ASSERT_TRUE(s.master.startup(AlState::PreOp, &why)) << why;
    const auto& sl = s.master.slaves();
    ASSERT_EQ(sl.size(), 3u);
    const std::uint8_t all = cd::SdoInfo | cd::CompleteAccess | cd::PdoAssign | cd::PdoConfig;
    EXPECT_EQ(sl[0].sii.coe_details & all, all);
    EXPECT_EQ(sl[1].sii.coe_details & all, 0);
    EXPECT_TRUE(sl[1].sii.coe_details & cd::Sdo);
    EXPECT_FALSE(sl[0].sii.strings.empty());
    EXPECT_TRUE(sl[2].sii.strings.empty());
    // The ESI written for the lean drive: CoE without SdoInfo, CompleteAccess, PdoAssign, PdoConfig.
    const auto esi = esi::import_esi_text(esi::write_esi(s.built.segment->slave(1).description()));
    EXPECT_EQ(esi.desc.coe_details & all, 0);
    EXPECT_TRUE(esi.desc.coe_details & cd::Sdo);
    for (const auto& p : esi.desc.rx_pdos)
        EXPECT_TRUE(p.fixed && p.mandatory) << p.index;
    // The lean drive answers as its SII says; the plain one serves SDO information.
    master::CoeClient plain(s.master, sl[0].station), lean(s.master, sl[1].station);
    EXPECT_TRUE(plain.object_description(0x1018));
    EXPECT_FALSE(lean.object_description(0x1018));
    EXPECT_EQ(lean.upload(0x1C12, 0, true).abort, protocol::SdoAbort::UnsupportedAccess);
    EXPECT_EQ(lean.download_value(0x1C12, 0, std::uint8_t{0}).abort, protocol::SdoAbort::ReadOnly);
    EXPECT_TRUE(plain.download_value(0x1C12, 0, std::uint8_t{0}).ok());
}

// The example file's devices, each with its quirks, reach OP with the project master on the host's clock
// (the delayed replies come in time, the master takes the sizes of the process data from CoE) and exchange
// process data with the working counter expected; a drive that loses every 50th reply gets through the
// mailbox traffic of the start-up only because the master asks for no more than 49 replies of it.
TEST(NetworkQuirks, TheExampleDevicesReachOp) {
    const auto f = read_network_file(std::string(VECAT_SOURCE_DIR) + "/examples/networks/quirks.yaml");
    BuiltNetwork built = build_network(f, "quirks.yaml");
    net::InProcessLink link(*built.segment);  // the host's clock: the mailbox delays pass
    master::Master m(link);
    std::string why;
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    ASSERT_EQ(m.slaves().size(), 5u);
    for (int i = 0; i < 50; ++i)
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
    EXPECT_EQ(built.segment->slave(3).counters().mailbox_replies_lost, 0u);
    // The drive with fixed PDOs has its one default mapping: the same sizes as the full drive.
    EXPECT_EQ(m.slaves()[1].out_bytes, m.slaves()[0].out_bytes);
    EXPECT_EQ(m.slaves()[1].in_bytes, m.slaves()[0].in_bytes);
    EXPECT_EQ(m.slaves()[4].in_bytes, 1u);
}

// An sii: device keeps its dump, but for the CoE details byte of its General category: a master reading
// the SII of the SOES device (CoE details 0x2F) with no_sdo_info and no_complete_access learns that it has
// neither, and its SDO information and complete access requests are refused.
TEST(NetworkQuirks, AnSiiDumpGetsItsCoeDetailsPatched) {
    VECAT_REQUIRE_SHARED_DATA("sii");
    const std::string sii = test::shared_data("sii/");
    Served plain("devices:\n  - name: soes\n    sii: " + sii + "soes-dynpdo.bin\n");
    Served s("devices:\n  - name: soes\n    sii: " + sii +
             "soes-dynpdo.bin\n    quirks: [no_sdo_info, no_complete_access]\n");
    std::string why;
    ASSERT_TRUE(plain.master.startup(AlState::PreOp, &why)) << why;
    ASSERT_TRUE(s.master.startup(AlState::PreOp, &why)) << why;
    const auto& before = plain.master.slaves()[0].sii;
    const auto& after = s.master.slaves()[0].sii;
    const std::uint8_t lacking = cd::SdoInfo | cd::CompleteAccess;
    ASSERT_EQ(before.coe_details & lacking, lacking) << "the dump names SDO information and complete access";
    EXPECT_EQ(after.coe_details, before.coe_details & ~lacking);
    // Every other byte of the image is the dump's.
    const auto& a = plain.built.segment->slave(0).esc().eeprom();
    const auto& b = s.built.segment->slave(0).esc().eeprom();
    ASSERT_EQ(a.size(), b.size());
    unsigned differ = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
        differ += a[i] != b[i];
    EXPECT_EQ(differ, 1u);
    master::CoeClient c(s.master, s.master.slaves()[0].station);
    EXPECT_FALSE(c.od_list(protocol::sdo_info::ListAll));
    EXPECT_EQ(c.upload(0x1C12, 0, true).abort, protocol::SdoAbort::UnsupportedAccess);
    master::CoeClient pc(plain.master, plain.master.slaves()[0].station);
    EXPECT_TRUE(pc.od_list(protocol::sdo_info::ListAll));
    EXPECT_TRUE(pc.upload(0x1C12, 0, true).ok());
}

}  // namespace
}  // namespace vecat::network
