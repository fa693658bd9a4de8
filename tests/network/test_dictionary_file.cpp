// The dictionary file (src/network/dictionary_file.*): its round trip, its refusals (each names the line),
// and an sii: device of a network file that serves a dictionary file: exactly its objects and values, over
// SDO uploads and SDO information, writes where the access allows, SDO information refused when the file
// says the device refused it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "device/device_description.hpp"
#include "esc/sii_image.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "network/build.hpp"
#include "network/dictionary_file.hpp"
#include "network/network_file.hpp"
#include "network_support.hpp"
#include "serve/in_process_link.hpp"

namespace vecat::network {
namespace {

using device::ObjectDescription;

// A dictionary of the default drive's objects, with some values and what a clone could not read.
DeviceDictionary sample() {
    DeviceDictionary d;
    d.objects = device::dictionary_objects(device::default_drive());
    d.objects.front().name = "Device \"type\"\tx";  // quotes and a control character survive
    for (const auto& o : d.objects)
        for (const auto& e : o.entries)
            if (o.index < 0x1100 && !e.default_value.empty())
                d.values[{o.index, e.subindex}] = e.default_value;
    d.values[{0x1008, 0}] = {'c', 'o', 'p', 'y'};
    d.objects.back().declared_max_subindex = static_cast<std::uint8_t>(d.objects.back().max_subindex() + 3);
    d.sdo_information = false;
    d.missing = {"0x2000:01: upload refused (0x06010001)", "second line\nsdo_information: maybe"};
    return d;
}

void expect_same(const DeviceDictionary& a, const DeviceDictionary& b) {
    ASSERT_EQ(a.objects.size(), b.objects.size());
    for (std::size_t i = 0; i < a.objects.size(); ++i) {
        const ObjectDescription &x = a.objects[i], &y = b.objects[i];
        SCOPED_TRACE(x.index);
        EXPECT_EQ(x.index, y.index);
        EXPECT_EQ(x.name, y.name);
        EXPECT_EQ(x.code, y.code);
        EXPECT_EQ(x.type, y.type);
        EXPECT_EQ(x.max_subindex(), y.max_subindex());
        ASSERT_EQ(x.entries.size(), y.entries.size());
        for (std::size_t k = 0; k < x.entries.size(); ++k) {
            const auto &e = x.entries[k], &f = y.entries[k];
            EXPECT_EQ(e.subindex, f.subindex);
            EXPECT_EQ(e.name, f.name);
            EXPECT_EQ(e.type, f.type);
            EXPECT_EQ(e.bit_length, f.bit_length);
            EXPECT_EQ(e.access, f.access);
            EXPECT_EQ(e.default_value, f.default_value);
            EXPECT_EQ(e.minimum, f.minimum);
            EXPECT_EQ(e.maximum, f.maximum);
        }
    }
    EXPECT_EQ(a.values, b.values);
    EXPECT_EQ(a.sdo_information, b.sdo_information);
    EXPECT_EQ(a.missing, b.missing);
}

TEST(DictionaryFile, WrittenAndReadBackIsTheSame) {
    const DeviceDictionary d = sample();
    const std::string text = write_dictionary(d, {"vecat clone of a test"});
    const DeviceDictionary back = parse_dictionary(text, "d.yaml");
    expect_same(d, back);
    EXPECT_EQ(write_dictionary(back, {"vecat clone of a test"}), text);
    // What is missing is in the comments at the top too.
    EXPECT_NE(text.find("#   0x2000:01: upload refused"), std::string::npos);
}

TEST(DictionaryFile, HexBytes) {
    std::vector<std::uint8_t> b;
    EXPECT_TRUE(parse_hex("9a 00 Ff", b));
    EXPECT_EQ(b, (std::vector<std::uint8_t>{0x9a, 0x00, 0xff}));
    EXPECT_TRUE(parse_hex("", b));
    EXPECT_TRUE(b.empty());
    EXPECT_FALSE(parse_hex("9", b));
    EXPECT_FALSE(parse_hex("9a0", b));
    EXPECT_FALSE(parse_hex("zz", b));
    EXPECT_EQ(to_hex({0x01, 0xab}), "01 ab");
}

std::string refusal(const std::string& text) {
    try {
        parse_dictionary(text, "d.yaml");
    } catch (const DictionaryFileError& e) {
        return e.what();
    }
    return "";
}

constexpr const char* kObject = R"(objects:
  - index: 0x1000
    name: "Device type"
    code: var
    type: UDINT
    entries:
      - subindex: 0
        name: "Device type"
        type: 0x0007
        bits: 32
        access: 0x0007
)";

TEST(DictionaryFile, EveryRefusalNamesTheLine) {
    EXPECT_EQ(refusal(kObject), "");
    EXPECT_EQ(refusal(std::string(kObject) + "        value: \"92 01 02 00\"\n"), "");
    const struct {
        std::string text, expect;
    } cases[] = {
        {"objects: [", "d.yaml:1:"},
        {"- a\n", "d.yaml: a dictionary file is a map"},
        {"objects: []\n", "objects: a list of at least one object"},
        {"object: 1\n", "d.yaml:1: unknown key object"},
        {std::string(kObject) + "        value: \"92 01 02\"\n",
         "d.yaml:12: value: 3 bytes for an entry of 32 bits"},
        {std::string(kObject) + "        value: \"92 01 02 00 00\"\n",
         "d.yaml:12: value: 5 bytes, more than"},
        {std::string(kObject) + "        value: \"9201\"\n", "d.yaml:12: value: bytes in hexadecimal"},
        {std::string(kObject) + "        colour: red\n", "d.yaml:12: unknown key colour"},
        {std::string(kObject) + "      - subindex: 0\n        type: 5\n        bits: 8\n        access: 1\n",
         "d.yaml:12: a second entry of subindex 0"},
        {std::string(kObject) + "      - subindex: 1\n        bits: 8\n        access: 1\n",
         "d.yaml:12: an entry needs subindex:, type:, bits: and access:"},
        {std::string(kObject) + std::string(kObject).substr(9), "d.yaml:12: a second object of index 0x1000"},
        {"objects:\n  - index: 0x10000\n", "d.yaml:2: index: 0x10000 is larger than 65535"},
        {"objects:\n  - index: 1\n    code: list\n", "d.yaml:3: code: var, array, record"},
        {"objects:\n  - index: 1\n    code: var\n    type: 7\n", "d.yaml:2: object 1: entries: a list"},
        {"objects:\n  - index: 1\n    code: var\n    type: 7\n    max_subindex: 0\n    entries:\n      - "
         "{subindex: "
         "2, type: 5, bits: 8, access: 1}\n    \n",
         "d.yaml:2: max_subindex 0 is below the entry of subindex 2"},
        {"sdo_information: maybe\n" + std::string(kObject), "d.yaml:1: sdo_information: true or false"},
        {"missing: 3\n" + std::string(kObject), "d.yaml:1: missing: a list of lines"},
    };
    for (const auto& c : cases) {
        const std::string why = refusal(c.text);
        EXPECT_NE(why.find(c.expect), std::string::npos) << "text:\n" << c.text << "\nrefusal: " << why;
    }
}

// A folder with the default drive's SII image and a dictionary file, and a network file naming both.
struct Files {
    std::filesystem::path dir;
    explicit Files(const DeviceDictionary& d, const std::string& name) {
        dir = std::filesystem::temp_directory_path() / ("vecat-dictionary-" + name);
        std::filesystem::create_directories(dir);
        const auto img = esc::build_sii_image(device::default_drive());
        std::ofstream(dir / "d.sii.bin", std::ios::binary)
            .write(reinterpret_cast<const char*>(img.data()), static_cast<std::streamsize>(img.size()));
        std::ofstream(dir / "d.dictionary.yaml") << write_dictionary(d);
        std::ofstream(dir / "network.yaml")
            << "devices:\n  - name: d\n    sii: d.sii.bin\n    dictionary: d.dictionary.yaml\n";
    }
    ~Files() { std::filesystem::remove_all(dir); }
};

struct Served : vecat::test::ServedNetwork {
    explicit Served(const std::string& file) : ServedNetwork(file, From::File) {}
};

TEST(DictionaryFile, AnSiiDeviceServesExactlyTheObjectsAndValuesOfItsFile) {
    // Given a dictionary that differs from the generated one: fewer objects, other values, a new object.
    DeviceDictionary d;
    for (const auto& o : device::dictionary_objects(device::default_drive()))
        if (o.index < 0x2000) d.objects.push_back(o);
    auto extra =
        device::make_var(0x2345, "Extra parameter", device::DataType::Integer16, device::access::RW, 5);
    extra.entries[0].minimum = {0xF6, 0xFF};  // -10
    extra.entries[0].maximum = {0x64, 0x00};  // 100
    d.objects.push_back(extra);
    d.values[{0x1008, 0}] = {'c', 'o', 'p', 'y'};
    d.values[{0x1018, 4}] = {0x78, 0x56, 0x34, 0x12};
    d.values[{0x2345, 0}] = {0x2A, 0x00};
    // The drive's PDOs map 0x6040...: without them in the dictionary the mapping is left as is, but the
    // PDO sizes the master reads are those of the mapping objects' values.
    const Files files(d, "serve");
    Served s((files.dir / "network.yaml").string());
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::PreOp, &why)) << why;
    master::CoeClient c(s.master, s.master.slaves()[0].station);

    // When the master uploads and reads SDO information, it gets the file's objects and values.
    EXPECT_EQ(c.upload(0x1008, 0).data, (std::vector<std::uint8_t>{'c', 'o', 'p', 'y'}));
    EXPECT_EQ(c.upload(0x1018, 4).data, (std::vector<std::uint8_t>{0x78, 0x56, 0x34, 0x12}));
    EXPECT_EQ(c.upload(0x2345, 0).data, (std::vector<std::uint8_t>{0x2A, 0x00}));
    EXPECT_EQ(c.upload(0x6040, 0).abort, protocol::SdoAbort::ObjectDoesNotExist);
    const auto list = c.od_list(protocol::sdo_info::ListAll);
    ASSERT_TRUE(list);
    std::vector<std::uint16_t> want;
    for (const auto& o : d.objects)
        want.push_back(o.index);
    EXPECT_EQ(*list, want);
    const auto od = c.object_description(0x2345);
    ASSERT_TRUE(od);
    EXPECT_EQ(od->name, "Extra parameter");
    // The description's default stays the described one (5), not the value (42).
    const auto ed =
        c.entry_description(0x2345, 0, protocol::sdo_info::ValueDefault | protocol::sdo_info::ValueMaximum);
    ASSERT_TRUE(ed);
    EXPECT_EQ(ed->values, (std::vector<std::uint8_t>{0x05, 0x00, 0x64, 0x00}));
    // Writes where the access allows, with the file's range; none of a read-only entry.
    EXPECT_TRUE(c.download_value<std::int16_t>(0x2345, 0, 77).ok());
    EXPECT_EQ(c.upload(0x2345, 0).data, (std::vector<std::uint8_t>{77, 0x00}));
    EXPECT_EQ(c.download_value<std::int16_t>(0x2345, 0, 101).abort, protocol::SdoAbort::ValueTooHigh);
    EXPECT_EQ(c.download_value<std::uint32_t>(0x1018, 4, 1).abort, protocol::SdoAbort::ReadOnly);
}

TEST(DictionaryFile, ACopyOfADeviceWithoutSdoInformationRefusesItToo) {
    DeviceDictionary d;
    d.objects = device::dictionary_objects(device::default_drive());
    d.sdo_information = false;
    const Files files(d, "noinfo");
    Served s((files.dir / "network.yaml").string());
    std::string why;
    ASSERT_TRUE(s.master.startup(protocol::AlState::PreOp, &why)) << why;
    master::CoeClient c(s.master, s.master.slaves()[0].station);
    EXPECT_FALSE(c.od_list(protocol::sdo_info::ListAll));
    EXPECT_TRUE(c.upload(0x1018, 1).ok());  // SDO uploads are served
}

TEST(DictionaryFile, ABadDictionaryIsRefusedWithTheNetworkFileItIsNamedIn) {
    const auto dir = std::filesystem::temp_directory_path() / "vecat-dictionary-bad";
    std::filesystem::create_directories(dir);
    const auto img = esc::build_sii_image(device::default_drive());
    std::ofstream(dir / "d.sii.bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(img.data()), static_cast<std::streamsize>(img.size()));
    std::ofstream(dir / "d.yaml") << "objects: 1\n";
    std::ofstream(dir / "n.yaml") << "devices:\n  - name: d\n    sii: d.sii.bin\n    dictionary: d.yaml\n";
    try {
        build_network(read_network_file((dir / "n.yaml").string()), "n.yaml");
        ADD_FAILURE() << "accepted";
    } catch (const NetworkFileError& e) {
        EXPECT_NE(std::string(e.what()).find("n.yaml:2: d: "), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("d.yaml: objects: a list"), std::string::npos) << e.what();
    }
    // dictionary: is for sii: devices only; esc: keys are checked.
    EXPECT_THROW(parse_network("devices:\n  - name: d\n    device: drive\n    dictionary: x.yaml\n"),
                 NetworkFileError);
    EXPECT_THROW(parse_network("devices:\n  - name: d\n    device: drive\n    esc: {sii_read_bytes: 6}\n"),
                 NetworkFileError);
    std::filesystem::remove_all(dir);
}

TEST(DictionaryFile, TheEscKeySetsTheEscRegisters) {
    const auto f = parse_network(
        "devices:\n  - name: d\n    device: coupler\n    esc: {type: 0x98, revision: 2, build: 0x1234, "
        "fmmus: 3, "
        "syncmanagers: 4, ram_kib: 16, port_descriptor: 0x0f, features: 0x01fc, sii_read_bytes: 4}\n");
    const auto b = build_network(f, "n.yaml");
    std::uint8_t regs[10] = {};
    for (std::uint16_t a = 0; a < 10; ++a)
        regs[a] = b.segment->slave(0).esc().peek(a);
    EXPECT_EQ(regs[0], 0x98);
    EXPECT_EQ(regs[1], 2);
    EXPECT_EQ(regs[2] | regs[3] << 8, 0x1234);
    EXPECT_EQ(regs[4], 3);
    EXPECT_EQ(regs[5], 4);
    EXPECT_EQ(regs[6], 16);
    EXPECT_EQ(regs[7], 0x0f);
    EXPECT_EQ(regs[8] | regs[9] << 8, 0x01fc);
}

}  // namespace
}  // namespace vecat::network
