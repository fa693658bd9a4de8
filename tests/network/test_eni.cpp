// ENI files (src/network/eni*): the reader (ETG.2100 elements, every refusal naming the element and its
// line), the network made from one (order from PreviousPort, devices from ESI files or from the ENI alone),
// and an ENI against the equivalent hand-written network file: the same devices, SII images byte for byte,
// and the same replies to every frame of the project master's start-up to OP.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "device/device_description.hpp"
#include "esi/esi_writer.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "network/build.hpp"
#include "network/eni.hpp"
#include "network/eni_network.hpp"
#include "network/network_file.hpp"
#include "serve/in_process_link.hpp"
#include "shared_data.hpp"

namespace vecat::network {
namespace {

namespace fs = std::filesystem;

const std::string kData = std::string(VECAT_SOURCE_DIR) + "/tests/network/data/";

std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// A folder of its own under the temporary directory, removed at the end.
struct TempDir {
    explicit TempDir(const std::string& name) : path(fs::temp_directory_path() / ("vecat-eni-" + name)) {
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~TempDir() { fs::remove_all(path); }
    fs::path path;
};

// The vecat drive's ESI, as `vecat esi generate` writes it, in dir/vecat-drive.xml.
void write_drive_esi(const fs::path& dir) {
    std::ofstream(dir / "vecat-drive.xml") << esi::write_esi(device::default_drive());
}

// The message of the refusal of an ENI text ("" if it was accepted and made into a network).
std::string refusal(const std::string& xml, const EniOptions& o = {}) {
    try {
        network_from_eni(parse_eni(xml, "m.xml"), o);
    } catch (const EniError& e) {
        return e.what();
    }
    return "";
}

std::string names(const NetworkFile& f) {
    std::string s;
    for (const auto& d : f.devices)
        s += (s.empty() ? "" : " ") + d.name;
    return s;
}

TEST(EniReader, ReadsTheElementsOfEachSlave) {
    const Eni eni = read_eni_file(kData + "line.eni.xml");
    EXPECT_EQ(eni.master_name, "Hand-written test master");
    ASSERT_EQ(eni.slaves.size(), 5u);
    const EniSlave& coupler = eni.slaves[0];
    EXPECT_EQ(coupler.name, "Term 1 (EK1100)");
    EXPECT_EQ(coupler.phys_addr, 1001);
    EXPECT_EQ(coupler.auto_inc_addr, 0);
    EXPECT_EQ(coupler.physics, "YY K");
    EXPECT_EQ(coupler.vendor_id, 2u);
    EXPECT_EQ(coupler.product_code, 72100946u);
    EXPECT_EQ(coupler.revision, 0x00110000u);
    EXPECT_FALSE(coupler.mailbox);
    ASSERT_EQ(coupler.init_cmds.size(), 2u);
    EXPECT_EQ(coupler.init_cmds[0].transitions, bit(EniTransition::IP));
    EXPECT_TRUE(coupler.init_cmds[0].before_slave);
    EXPECT_EQ(coupler.init_cmds[0].cmd, 2);  // APWR
    EXPECT_EQ(coupler.init_cmds[0].ado, 0x0010);
    EXPECT_EQ(coupler.init_cmds[0].data, (std::vector<std::uint8_t>{0xE9, 0x03}));
    EXPECT_EQ(coupler.init_cmds[0].cnt, 1);
    EXPECT_EQ(coupler.init_cmds[0].retries, 3);
    EXPECT_EQ(coupler.init_cmds[1].transitions,
              bit(EniTransition::PI) | bit(EniTransition::SI) | bit(EniTransition::OI));
    EXPECT_EQ(coupler.init_cmds[1].adp, 1001);
    EXPECT_EQ(coupler.init_cmds[1].ado, 0x0800);
    EXPECT_EQ(coupler.init_cmds[1].data.size(), 32u);  // DataLength
    EXPECT_TRUE(coupler.previous_ports.empty());

    const EniSlave& in = eni.slaves[1];
    EXPECT_EQ(in.auto_inc_addr, 0xFFFF);
    EXPECT_FALSE(in.serial);
    ASSERT_EQ(in.sync_managers.size(), 1u);
    EXPECT_EQ(in.sync_managers[0].number, 0u);
    EXPECT_FALSE(in.sync_managers[0].outputs);
    EXPECT_EQ(in.sync_managers[0].start, 0x1000);
    EXPECT_EQ(in.sync_managers[0].pdos, (std::vector<std::uint16_t>{0x1A00, 0x1A01, 0x1A02, 0x1A03}));
    ASSERT_EQ(in.tx_pdos.size(), 4u);
    EXPECT_TRUE(in.tx_pdos[3].fixed);
    EXPECT_EQ(in.tx_pdos[3].sm, 0);
    ASSERT_EQ(in.tx_pdos[3].entries.size(), 2u);
    EXPECT_EQ(in.tx_pdos[3].entries[0].index, 0x6030);
    EXPECT_EQ(in.tx_pdos[3].entries[0].data_type, "BOOL");
    EXPECT_EQ(in.tx_pdos[3].entries[1].index, 0);  // the gap
    EXPECT_EQ(in.tx_pdos[3].entries[1].bit_length, 4);
    ASSERT_EQ(in.previous_ports.size(), 1u);
    EXPECT_TRUE(in.previous_ports[0].selected);
    EXPECT_EQ(in.previous_ports[0].port, 3u);  // D
    EXPECT_EQ(in.previous_ports[0].phys_addr, 1001);

    EXPECT_EQ(eni.slaves[2].auto_inc_addr, 0xFFFE);  // written -2
    const EniSlave& drive = eni.slaves[3];
    ASSERT_TRUE(drive.mailbox);
    EXPECT_EQ(drive.mailbox->send.start, 0x1000);
    EXPECT_EQ(drive.mailbox->recv.start, 0x1080);
    EXPECT_EQ(drive.mailbox->protocols, device::mbx_proto::CoE);
    ASSERT_EQ(drive.mailbox->coe_init_cmds.size(), 1u);
    EXPECT_EQ(drive.mailbox->coe_init_cmds[0].index, 0x1C12);
    EXPECT_EQ(drive.mailbox->coe_init_cmds[0].ccs, 1);
    EXPECT_EQ(drive.mailbox->coe_init_cmds[0].transitions, bit(EniTransition::PS));
    EXPECT_EQ(drive.init_cmds[0].adp, 0xFFFD);  // -3
    EXPECT_EQ(drive.serial, 4660u);
    EXPECT_EQ(eni.slaves[4].sync_managers[1].default_size, 0);  // none given
}

// Each bad input is refused with the file, the line and the path of the element.
TEST(EniReader, EveryRefusalNamesTheElementAndItsLine) {
    const auto slave = [](const std::string& info, const std::string& rest = "") {
        return "<EtherCATConfig><Config>\n<Slave>\n<Info><Name>a</Name><PhysAddr>1001</PhysAddr>" + info +
               "</Info>" + rest + "</Slave>\n</Config></EtherCATConfig>\n";
    };
    const std::string id = "<VendorId>2</VendorId><ProductCode>3</ProductCode><RevisionNo>4</RevisionNo>";
    struct Case {
        std::string xml, expected;
    };
    const Case cases[] = {
        {"this is not XML", "m.xml:1: not XML"},
        {"<EtherCATConfig><Config><Slave></Config>", "m.xml:1: not XML"},
        {"<?xml version=\"1.0\"?>\n<EtherCATInfo/>", "m.xml:2: <EtherCATInfo> is no ENI"},
        {"<EtherCATConfig/>", "EtherCATConfig: no <Config>"},
        {"<EtherCATConfig><Config/></EtherCATConfig>", "EtherCATConfig/Config: no <Slave>"},
        {slave(""), "m.xml:3: EtherCATConfig/Config/Slave/Info: no <VendorId>"},
        {slave("<VendorId>2</VendorId><ProductCode>3</ProductCode>"), "Slave/Info: no <RevisionNo>"},
        {slave("<VendorId>x2</VendorId><ProductCode>3</ProductCode><RevisionNo>4</RevisionNo>"),
         "m.xml:3: EtherCATConfig/Config/Slave/Info/VendorId: \"x2\" is not a number"},
        {slave("<VendorId>#x100000000</VendorId><ProductCode>3</ProductCode><RevisionNo>4</RevisionNo>"),
         "Info/VendorId: #x100000000 is out of range"},
        {slave(id, "<Mailbox><Send><Start>70000</Start><Length>1</Length></Send></Mailbox>"),
         "Slave/Mailbox/Send/Start: 70000 is out of range [0, 65535]"},
        {slave(id, "<Mailbox><Send><Start>0</Start><Length>1</Length></Send></Mailbox>"),
         "Slave/Mailbox: no <Recv>"},
        {slave(id, "<ProcessData><Sm2><Type>Sideways</Type></Sm2></ProcessData>"),
         "ProcessData/Sm2/Type: \"Sideways\" is neither Inputs nor Outputs"},
        {slave(id,
               "<ProcessData><RxPdo><Index>#x1600</Index><Entry><Index>#x7000</Index><BitLen>300</BitLen>"
               "</Entry></RxPdo></ProcessData>"),
         "RxPdo/Entry/BitLen: 300 is out of range [0, 255]"},
        {slave(id,
               "<InitCmds><InitCmd><Transition>XY</Transition><Cmd>1</Cmd><Ado>0</Ado></InitCmd></InitCmds>"),
         "InitCmds/InitCmd/Transition: unknown transition \"XY\""},
        {slave(id, "<InitCmds><InitCmd><Cmd>15</Cmd><Ado>0</Ado></InitCmd></InitCmds>"),
         "InitCmd/Cmd: unknown datagram command 15"},
        {slave(id, "<InitCmds><InitCmd><Cmd>1</Cmd><Ado>0</Ado><Data>abc</Data></InitCmd></InitCmds>"),
         "InitCmd/Data: hexBinary of odd length"},
        {slave(id, "<PreviousPort><Port>E</Port></PreviousPort>"), "PreviousPort/Port: \"E\": A, B, C or D"},
        {slave("<Physics>YX</Physics>" + id), "Info/Physics: port physics 'X'"},
    };
    for (const auto& c : cases) {
        const std::string why = refusal(c.xml);
        EXPECT_NE(why.find(c.expected), std::string::npos) << "got: " << why << "\nexpected: " << c.expected;
    }
}

// Topologies that cannot be, and slaves that cannot be made: refused naming the element.
TEST(EniNetwork, ImpossibleTopologiesAreRefusedNamingTheElement) {
    const auto two = [](const std::string& second_rest, const std::string& second_addr = "1002") {
        const std::string id = "<VendorId>2</VendorId><ProductCode>3</ProductCode><RevisionNo>4</RevisionNo>";
        return "<EtherCATConfig><Config>\n<Slave><Info><Name>a</Name><PhysAddr>1001</PhysAddr>" + id +
               "</Info></Slave>\n<Slave><Info><Name>b</Name><PhysAddr>" + second_addr + "</PhysAddr>" + id +
               "</Info>\n" + second_rest + "</Slave>\n<Slave><Info><Name>c</Name><PhysAddr>1003</PhysAddr>" +
               id +
               "</Info>\n<PreviousPort><Port>B</Port><PhysAddr>1001</PhysAddr></PreviousPort></Slave>\n"
               "</Config></EtherCATConfig>";
    };
    // b at port B of a (by default, the slave before it), c at port B of a too: two slaves at one port.
    EXPECT_NE(refusal(two("")).find("m.xml:6: EtherCATConfig/Config/Slave[3]/PreviousPort: port B of a is "
                                    "already cabled to b (line 3)"),
              std::string::npos)
        << refusal(two(""));
    EXPECT_NE(refusal(two("<PreviousPort><Port>B</Port><PhysAddr>999</PhysAddr></PreviousPort>"))
                  .find("m.xml:4: EtherCATConfig/Config/Slave[2]/PreviousPort: PhysAddr 999 names no slave"),
              std::string::npos);
    EXPECT_NE(refusal(two("<PreviousPort><Port>A</Port><PhysAddr>1001</PhysAddr></PreviousPort>"))
                  .find("Slave[2]/PreviousPort: port A of a slave leads to the master"),
              std::string::npos);
    EXPECT_NE(refusal(two("<PreviousPort><Port>D</Port><PhysAddr>1002</PhysAddr></PreviousPort>"))
                  .find("Slave[2]/PreviousPort: the slave is cabled to itself"),
              std::string::npos);
    EXPECT_NE(
        refusal(two("<PreviousPort><Port>D</Port><PhysAddr>1001</PhysAddr></PreviousPort>", "1001"))
            .find(
                "m.xml:3: EtherCATConfig/Config/Slave[2]: PhysAddr 1001 is also that of the slave on line 2"),
        std::string::npos);
    // b and c cabled to each other: a loop, with no way to the master.
    const std::string loop = two("<PreviousPort><Port>B</Port><PhysAddr>1003</PhysAddr></PreviousPort>");
    std::string l = loop;
    l.replace(l.rfind("<PhysAddr>1001"), 14, "<PhysAddr>1002");
    EXPECT_NE(refusal(l).find("loop"), std::string::npos) << refusal(l);
    // The positions the ENI gives must be those of its cabling.
    std::string order = two("<PreviousPort><Port>D</Port><PhysAddr>1001</PhysAddr></PreviousPort>");
    order.replace(order.find("<Name>c</Name>"), 14, "<Name>c</Name><AutoIncAddr>-1</AutoIncAddr>");
    // a's port D comes before its port B: b is position 1, c position 2.
    EXPECT_NE(refusal(order).find("Slave[3]: AutoIncAddr -1 (position 1), but the PreviousPort cabling puts "
                                  "it at position 2"),
              std::string::npos)
        << refusal(order);
    // A port the device does not have (Physics: two ports).
    std::string ports = two("<PreviousPort><Port>C</Port><PhysAddr>1001</PhysAddr></PreviousPort>");
    ports.replace(ports.find("<PhysAddr>1001</PhysAddr>"), 25,
                  "<PhysAddr>1001</PhysAddr><Physics>YY</Physics>");
    std::string why;
    try {
        build_network(network_from_eni(parse_eni(ports, "m.xml")).file, "m.xml");
    } catch (const NetworkFileError& e) {
        why = e.what();
    }
    EXPECT_NE(why.find("m.xml:3: b: a has no port 2"), std::string::npos) << why;
    // A slave vecat cannot build: no vendor.
    std::string novendor = two("<PreviousPort><Port>D</Port><PhysAddr>1001</PhysAddr></PreviousPort>");
    novendor.replace(novendor.find("<VendorId>2"), 11, "<VendorId>0");
    EXPECT_NE(refusal(novendor).find("m.xml:2: EtherCATConfig/Config/Slave[1]: VendorId 0"),
              std::string::npos)
        << refusal(novendor);
    // A PDO assigned to a SyncManager the slave does not have of its direction.
    std::string pdo =
        two("<ProcessData><Sm2><Type>Inputs</Type><StartAddress>#x1100</StartAddress><ControlByte>"
            "#x20</ControlByte></Sm2><RxPdo Sm=\"2\"><Index>#x1600</Index></RxPdo></ProcessData>"
            "<PreviousPort><Port>D</Port><PhysAddr>1001</PhysAddr></PreviousPort>");
    EXPECT_NE(refusal(pdo).find("Slave[2]/ProcessData/RxPdo: an RxPdo assigned to Sm2, which is no Outputs"),
              std::string::npos)
        << refusal(pdo);
}

TEST(EniNetwork, TheLineIsOrderedByItsPreviousPortsAndDevicesComeFromTheEsiOrTheEni) {
    TempDir dir("order");
    write_drive_esi(dir.path);
    const Eni eni = read_eni_file(kData + "line.eni.xml");
    const EniNetwork with_esi = network_from_eni(eni, {dir.path.string()});
    EXPECT_EQ(names(with_esi.file), "Term-1-EK1100 Term-2-EL1004 Term-3-EL2004 Drive-4-vecat Box-5-CoE-I-O");
    EXPECT_EQ(with_esi.file.parent, (std::vector<int>{-1, 0, 1, 0, 3}));
    EXPECT_EQ(with_esi.file.children[0][3], 1);  // port D: the E-bus
    EXPECT_EQ(with_esi.file.children[0][1], 3);  // port B
    EXPECT_EQ(with_esi.file.devices[3].source, Source::Esi);
    EXPECT_EQ(with_esi.file.devices[3].identity.serial, 4660u);
    for (std::size_t i : {0u, 1u, 2u, 4u}) {
        EXPECT_EQ(with_esi.file.devices[i].source, Source::Sii) << i;
        EXPECT_TRUE(with_esi.file.devices[i].sii_image) << i;
    }
    // Without the ESI folder the drive is made from the ENI too.
    const EniNetwork alone = network_from_eni(eni);
    EXPECT_EQ(alone.file.devices[3].source, Source::Sii);
    // An ESI of another revision is not taken, and said so.
    std::string other = slurp(kData + "line.eni.xml");
    other.replace(other.find("#x00010000"), 10, "#x00010007");
    const EniNetwork rev = network_from_eni(parse_eni(other, "m.xml"), {dir.path.string()});
    EXPECT_EQ(rev.file.devices[3].source, Source::Sii);
    bool said = false;
    for (const auto& n : rev.notes)
        said |= n.find("no ESI of revision 0x10007") != std::string::npos;
    EXPECT_TRUE(said);
}

// A recorded start-up: each frame the master sent, and the reply, at a clock that advances per frame.
struct Exchange {
    std::vector<std::uint8_t> request, reply;
    std::uint64_t at_ns = 0;
};

class SteppingLink final : public net::Link {
  public:
    explicit SteppingLink(esc::Segment& seg) : inner_(seg) {
        inner_.set_time(1'000'000'000);
        inner_.set_time_step(50'000);
    }
    bool send(ConstBytes f) override {
        const bool sent = inner_.send(f);  // (at the time one step on)
        log.push_back({std::vector<std::uint8_t>(f.begin(), f.end()), {}, inner_.now_ns()});
        return sent;
    }
    long receive(Bytes b, std::int64_t timeout_us) override {
        // The replies come in the order of the frames (a cycle's frames go out before the first reply).
        const long n = inner_.receive(b, timeout_us);
        if (n > 0 && replied_ < log.size()) log[replied_++].reply.assign(b.begin(), b.begin() + n);
        return n;
    }
    std::vector<Exchange> log;

  private:
    std::size_t replied_ = 0;
    net::InProcessLink inner_;
};

// Brings a network to OP with the project master and some cycles of process data; the exchanges.
std::vector<Exchange> start_up(esc::Segment& seg) {
    SteppingLink link(seg);
    master::Master m(link);
    std::string why;
    EXPECT_TRUE(m.startup(protocol::AlState::Op, &why)) << why;
    for (int i = 0; i < 20; ++i)
        EXPECT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
    return link.log;
}

// The same frames, at the same times, to another network: its replies must be the same bytes.
void expect_same_replies(const std::vector<Exchange>& log, esc::Segment& other) {
    net::InProcessLink link(other);
    std::array<std::uint8_t, 1600> buf{};
    std::size_t differ = 0;
    for (std::size_t i = 0; i < log.size(); ++i) {
        link.set_time(log[i].at_ns);
        link.send(ConstBytes(log[i].request.data(), log[i].request.size()));
        const long n = link.receive(Bytes(buf.data(), buf.size()), 0);
        const std::vector<std::uint8_t> reply(buf.begin(), buf.begin() + std::max(0L, n));
        if (reply != log[i].reply && differ++ < 3) ADD_FAILURE() << "frame " << i << ": another reply";
    }
    EXPECT_EQ(differ, 0u) << "of " << log.size() << " frames";
    EXPECT_GT(log.size(), 100u);
}

void expect_same_network(esc::Segment& a, esc::Segment& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a.slave(i).esc().eeprom(), b.slave(i).esc().eeprom()) << "SII of slave " << i;
        EXPECT_EQ(a.slave(i).esc().config().port_descriptor, b.slave(i).esc().config().port_descriptor) << i;
    }
}

// The ENI of a tree of vecat drives (their ESI in the ESI folder) and the network file a user would write
// for it: the same network.
TEST(EniNetwork, AnEniBuildsTheSameNetworkAsTheEquivalentNetworkFile) {
    TempDir dir("same");
    fs::create_directories(dir.path / "esi");
    write_drive_esi(dir.path / "esi");
    fs::copy_file(kData + "drive-tree.yaml", dir.path / "drive-tree.yaml");
    const NetworkFile yaml = read_network_file((dir.path / "drive-tree.yaml").string());
    const EniNetwork eni =
        network_from_eni(read_eni_file(kData + "drive-tree.eni.xml"), {(dir.path / "esi").string()});
    ASSERT_EQ(names(eni.file), names(yaml));
    EXPECT_EQ(eni.file.parent, yaml.parent);
    EXPECT_EQ(eni.file.children, yaml.children);
    for (std::size_t i = 0; i < yaml.devices.size(); ++i) {
        EXPECT_EQ(eni.file.devices[i].source, Source::Esi);
        EXPECT_EQ(eni.file.devices[i].identity.serial, yaml.devices[i].identity.serial);
    }
    BuiltNetwork a = build_network(eni.file, "drive-tree.eni.xml");
    BuiltNetwork b = build_network(yaml, "drive-tree.yaml");
    expect_same_network(*a.segment, *b.segment);
    const auto log = start_up(*a.segment);
    expect_same_replies(log, *b.segment);
}

// The same with vendor drives from the ESI files of ../shared/data/esi: the ENI against its network file.
TEST(EniNetwork, AnEniOfVendorDrivesBuildsTheSameNetworkAsTheEquivalentNetworkFile) {
    VECAT_REQUIRE_SHARED_DATA("esi/elmo-gold.xml");
    const NetworkFile yaml = read_network_file(kData + "vendor-drives.yaml");
    const EniNetwork eni =
        network_from_eni(read_eni_file(kData + "vendor-drives.eni.xml"), {test::shared_data("esi")});
    ASSERT_EQ(names(eni.file), names(yaml));
    EXPECT_EQ(eni.file.parent, yaml.parent);
    for (const auto& d : eni.file.devices)
        EXPECT_EQ(d.source, Source::Esi) << d.name;
    EXPECT_EQ(eni.file.devices[1].esi_revision, 0x00010420u);  // of the two Elmo revisions, the ENI's
    BuiltNetwork a = build_network(eni.file, "vendor-drives.eni.xml");
    BuiltNetwork b = build_network(yaml, "vendor-drives.yaml");
    expect_same_network(*a.segment, *b.segment);
    const auto log = start_up(*a.segment);
    expect_same_replies(log, *b.segment);
}

// Devices made from the ENI alone: the SII the master reads has the ENI's identity, SyncManagers and PDOs,
// the process data has the ENI's sizes, and the objects the PDOs map are in the dictionary.
TEST(EniNetwork, DevicesMadeFromTheEniAloneReachOpWithTheirProcessData) {
    TempDir dir("alone");
    write_drive_esi(dir.path);
    const EniNetwork eni = network_from_eni(read_eni_file(kData + "line.eni.xml"), {dir.path.string()});
    BuiltNetwork built = build_network(eni.file, "line.eni.xml");
    net::InProcessLink link(*built.segment);
    master::Master m(link);
    std::string why;
    const bool up = m.startup(protocol::AlState::Op, &why);
    ASSERT_TRUE(up) << why;
    const auto& sl = m.slaves();
    ASSERT_EQ(sl.size(), 5u);
    EXPECT_EQ(sl[0].sii.identity.product_code, 72100946u);
    EXPECT_EQ(sl[0].sii.device_name(), "Term 1 (EK1100)");
    EXPECT_EQ(sl[1].sii.identity.product_code, 0x03EC3052u);
    EXPECT_EQ(sl[1].in_bytes, 1u);
    EXPECT_EQ(sl[2].out_bytes, 1u);
    EXPECT_EQ(sl[4].sii.identity.vendor_id, 0xABCu);
    EXPECT_EQ(sl[4].sii.identity.serial, 77u);
    EXPECT_EQ(sl[4].out_bytes, 2u);
    EXPECT_EQ(sl[4].in_bytes, 6u);  // Sm3 without DefaultSize: its PDO 0x1A00, 16 + 32 bits
    // Ports: the coupler's Physics "YY K" (port 2 none, port 3 E-bus), the terminals' "KK".
    EXPECT_EQ(built.segment->slave(0).esc().config().port_descriptor, 0b10'00'11'11);
    EXPECT_EQ(built.segment->slave(1).esc().config().port_descriptor, 0b00'00'10'10);
    // The SII's PDOs are the ENI's.
    const auto& tx = sl[4].sii.tx_pdos;
    ASSERT_EQ(tx.size(), 2u);
    EXPECT_EQ(tx[0].index, 0x1A00);
    EXPECT_EQ(tx[0].sm, 3);
    ASSERT_EQ(tx[0].entries.size(), 2u);
    EXPECT_EQ(tx[0].entries[1].index, 0x6010);
    EXPECT_EQ(tx[0].entries[1].subindex, 2);
    EXPECT_EQ(tx[0].entries[1].bit_length, 32);
    EXPECT_EQ(tx[1].sm, 0xFF);  // not assigned
    // The mapped objects answer by SDO.
    master::CoeClient coe(m, sl[4].station);
    const auto mapping = coe.upload(0x1A00, 2);
    ASSERT_TRUE(mapping.ok());
    EXPECT_EQ(mapping.data, (std::vector<std::uint8_t>{0x20, 0x02, 0x10, 0x60}));  // 0x6010:02, 32 bits
    const auto value = coe.upload(0x6010, 2);
    ASSERT_TRUE(value.ok());
    EXPECT_EQ(value.data.size(), 4u);
    for (int i = 0; i < 10; ++i)
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
}

// vecat network from-eni: the network file it writes (with the SII images of the devices made from the ENI
// alone beside it), read back, builds the same network as the ENI.
TEST(EniNetwork, TheNetworkFileWrittenFromAnEniBuildsTheSameNetwork) {
    TempDir dir("roundtrip");
    fs::create_directories(dir.path / "esi");
    fs::create_directories(dir.path / "out");
    write_drive_esi(dir.path / "esi");
    const Eni eni = read_eni_file(kData + "line.eni.xml");
    const EniNetwork n = network_from_eni(eni, {(dir.path / "esi").string()});
    const EniNetworkFile text = network_file_from_eni(eni, n, (dir.path / "out").string());
    EXPECT_NE(text.yaml.find("esi: ../esi/vecat-drive.xml"), std::string::npos) << text.yaml;
    EXPECT_NE(text.yaml.find("upstream: Term-1-EK1100:3"), std::string::npos) << text.yaml;
    ASSERT_EQ(text.files.size(), 4u);  // all but the drive
    for (const auto& [name, bytes] : text.files)
        std::ofstream(dir.path / "out" / name, std::ios::binary)
            .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    std::ofstream(dir.path / "out" / "net.yaml") << text.yaml;
    const NetworkFile back = read_network_file((dir.path / "out" / "net.yaml").string());
    EXPECT_EQ(names(back), names(n.file));
    EXPECT_EQ(back.parent, n.file.parent);
    EXPECT_EQ(back.children, n.file.children);
    BuiltNetwork a = build_network(n.file, "line.eni.xml");
    BuiltNetwork b = build_network(back, "net.yaml");
    expect_same_network(*a.segment, *b.segment);
    const auto log = start_up(*a.segment);
    expect_same_replies(log, *b.segment);
}

// Names a network file cannot hold: made into names it can, unique, and the written file reads back.
TEST(EniNetwork, SlaveNamesBecomeUniqueNetworkFileNames) {
    const std::string id = "<VendorId>2</VendorId><ProductCode>3</ProductCode><RevisionNo>4</RevisionNo>";
    const Eni eni = parse_eni("<EtherCATConfig><Config><Slave><Info><Name><![CDATA[Box 1\n(x: y)]]></Name>" +
                                  id + "</Info></Slave><Slave><Info><Name>Box 1 # (x: y)</Name>" + id +
                                  "</Info></Slave><Slave><Info><Name>*</Name>" + id +
                                  "</Info></Slave></Config></EtherCATConfig>",
                              "m.xml");
    const EniNetwork n = network_from_eni(eni);
    EXPECT_EQ(names(n.file), "Box-1-x-y Box-1-x-y-2 slave");
    const auto text = network_file_from_eni(eni, n, ".");
    const NetworkFile back = parse_network(text.yaml, "back.yaml");
    EXPECT_EQ(names(back), names(n.file));
    EXPECT_EQ(back.parent, n.file.parent);
}

}  // namespace
}  // namespace vecat::network
