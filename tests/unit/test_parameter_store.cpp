// Parameter persistence: 0x1010 store / 0x1011 restore with the CiA 301 signatures, the file format
// (version, CRC-32) and its atomic replacement, what a start finds in a good, missing or corrupted file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "coe/coe_application.hpp"
#include "coe/parameter_store.hpp"
#include "device/device_description.hpp"
#include "master/coe_client.hpp"
#include "protocol/cia402_objects.hpp"
#include "test_support.hpp"

namespace obj = vecat::protocol::obj;

using namespace vecat;
using namespace vecat::coe;
namespace fs = std::filesystem;

namespace {

std::vector<std::uint8_t> le32(std::uint32_t v) {
    return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8),
            static_cast<std::uint8_t>(v >> 16), static_cast<std::uint8_t>(v >> 24)};
}

class ParameterStoreTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("vecat-param-test-" + std::to_string(::getpid()) + "-" +
                                           ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir);
        fs::create_directories(dir);
        path = (dir / "slave-0.param").string();
    }
    void TearDown() override { fs::remove_all(dir); }

    SdoAbort write(CoeApplication& app, std::uint16_t index, std::uint8_t sub, std::uint32_t v) {
        return app.dictionary().download(index, sub, false, AlState::PreOp, le32(v));
    }
    SdoAbort write16(CoeApplication& app, std::uint16_t index, std::uint8_t sub, std::uint16_t v) {
        const std::uint8_t b[2] = {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8)};
        return app.dictionary().download(index, sub, false, AlState::PreOp, ConstBytes(b, 2));
    }
    std::uint32_t read(CoeApplication& app, std::uint16_t index, std::uint8_t sub) {
        return app.dictionary().find(index, sub)->get<std::uint32_t>();
    }
    std::vector<std::uint8_t> file_bytes() {
        std::ifstream f(path, std::ios::binary);
        return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
    }
    void write_bytes(const std::vector<std::uint8_t>& b) {
        std::ofstream(path, std::ios::binary | std::ios::trunc)
            .write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
    }

    device::DeviceDescription dev = device::default_drive();
    fs::path dir;
    std::string path;
};

TEST_F(ParameterStoreTest, ObjectsDescribeTheirCapability) {
    CoeApplication without(dev);
    for (const std::uint16_t index : {std::uint16_t{0x1010}, std::uint16_t{0x1011}}) {
        const Object* o = without.dictionary().find(index);
        ASSERT_NE(o, nullptr);
        EXPECT_EQ(o->max_subindex(), 4);
        EXPECT_EQ(read(without, index, 1), 0u) << "no store attached: the device does not save";
    }
    CoeApplication with(dev);
    with.attach_parameter_store(path);
    EXPECT_EQ(read(with, 0x1010, 1), 1u);  // saves on command
    EXPECT_EQ(read(with, 0x1011, 4), 1u);
}

TEST_F(ParameterStoreTest, WrongSignatureAndNoStoreAreRefused) {
    CoeApplication without(dev);
    EXPECT_EQ(write(without, 0x1010, 1, kStoreSignature), SdoAbort::LocalControl);
    CoeApplication app(dev);
    app.attach_parameter_store(path);
    EXPECT_EQ(write(app, 0x1010, 1, 0x12345678), SdoAbort::CannotTransfer);
    EXPECT_EQ(write(app, 0x1010, 1, kRestoreSignature), SdoAbort::CannotTransfer);
    EXPECT_EQ(write(app, 0x1011, 1, kStoreSignature), SdoAbort::CannotTransfer);
    EXPECT_FALSE(fs::exists(path));
    EXPECT_EQ(read(app, 0x1010, 1), 1u) << "a refused write leaves the capability";
}

TEST_F(ParameterStoreTest, StoredValuesComeBackAtTheNextStart) {
    {
        CoeApplication app(dev);
        app.attach_parameter_store(path);
        ASSERT_EQ(write(app, 0x2000, 1, 4500), SdoAbort::None);
        ASSERT_EQ(write16(app, 0x10F1, 2, 9), SdoAbort::None);
        ASSERT_EQ(write(app, 0x1010, 1, kStoreSignature), SdoAbort::None);
        EXPECT_EQ(read(app, 0x1010, 1), 1u) << "reads give the capability, not the signature";
        EXPECT_FALSE(fs::exists(path + ".tmp"));
    }
    CoeApplication next(dev);
    EXPECT_EQ(read(next, 0x2000, 1), 3000u);  // default before the store is attached
    const auto rep = next.attach_parameter_store(path);
    EXPECT_EQ(rep.load.status, LoadStatus::Loaded);
    EXPECT_GT(rep.applied, 0u);
    EXPECT_EQ(rep.refused, 0u);
    EXPECT_EQ(read(next, 0x2000, 1), 4500u);
    EXPECT_EQ(next.dictionary().find(0x10F1, 2)->get<std::uint16_t>(), 9);
}

TEST_F(ParameterStoreTest, GroupsStoreAndRestoreTheirOwnPart) {
    {
        CoeApplication app(dev);
        app.attach_parameter_store(path);
        ASSERT_EQ(write(app, 0x2000, 1, 4500), SdoAbort::None);  // manufacturer
        ASSERT_EQ(write16(app, 0x10F1, 2, 9), SdoAbort::None);   // communication
        ASSERT_EQ(write(app, 0x1010, 4, kStoreSignature), SdoAbort::None);
    }
    {
        CoeApplication app(dev);
        app.attach_parameter_store(path);
        EXPECT_EQ(read(app, 0x2000, 1), 4500u);
        EXPECT_EQ(app.dictionary().find(0x10F1, 2)->get<std::uint16_t>(), 4) << "communication not stored";
        ASSERT_EQ(write16(app, 0x10F1, 2, 7), SdoAbort::None);
        ASSERT_EQ(write(app, 0x1010, 2, kStoreSignature), SdoAbort::None);
    }
    {
        CoeApplication app(dev);
        app.attach_parameter_store(path);
        EXPECT_EQ(read(app, 0x2000, 1), 4500u) << "storing communication kept the manufacturer part";
        EXPECT_EQ(app.dictionary().find(0x10F1, 2)->get<std::uint16_t>(), 7);
        ASSERT_EQ(write(app, 0x1011, 4, kRestoreSignature), SdoAbort::None);
        EXPECT_EQ(read(app, 0x2000, 1), 4500u) << "CiA 301: defaults take effect at the next start";
    }
    CoeApplication app(dev);
    app.attach_parameter_store(path);
    EXPECT_EQ(read(app, 0x2000, 1), 3000u);
    EXPECT_EQ(app.dictionary().find(0x10F1, 2)->get<std::uint16_t>(), 7);
}

TEST_F(ParameterStoreTest, RestoreAllRemovesTheFile) {
    CoeApplication app(dev);
    app.attach_parameter_store(path);
    ASSERT_EQ(write(app, 0x1010, 1, kStoreSignature), SdoAbort::None);
    ASSERT_TRUE(fs::exists(path));
    ASSERT_EQ(write(app, 0x1011, 1, kRestoreSignature), SdoAbort::None);
    EXPECT_FALSE(fs::exists(path));
}

TEST_F(ParameterStoreTest, ProcessValuesAreNotStored) {
    CoeApplication app(dev);
    app.attach_parameter_store(path);
    ASSERT_EQ(write(app, 0x1010, 1, kStoreSignature), SdoAbort::None);
    const auto r = load_parameter_file(path);
    ASSERT_EQ(r.status, LoadStatus::Loaded);
    for (const auto& rec : r.set.records) {
        EXPECT_NE(rec.index, obj::controlword.index) << "controlword is the master's, not a setting";
        EXPECT_NE(rec.index, 0x1010);
        EXPECT_NE(rec.index, 0x1011);
    }
    EXPECT_TRUE(std::any_of(r.set.records.begin(), r.set.records.end(), [](const ParameterRecord& x) {
        return x.index == 0x1C12;
    })) << "the PDO assignment is a setting";
}

TEST_F(ParameterStoreTest, EveryFlippedByteAndEveryTruncationIsDetected) {
    CoeApplication app(dev);
    app.attach_parameter_store(path);
    ASSERT_EQ(write(app, 0x1010, 1, kStoreSignature), SdoAbort::None);
    const auto good = file_bytes();
    ASSERT_EQ(decode_parameter_set(good).status, LoadStatus::Loaded);
    for (std::size_t i = 0; i < good.size(); ++i) {
        auto bad = good;
        bad[i] ^= 0x10;
        EXPECT_EQ(decode_parameter_set(bad).status, LoadStatus::Corrupt) << "byte " << i;
    }
    for (std::size_t n = 0; n < good.size(); ++n) {
        const std::vector<std::uint8_t> cut(good.begin(), good.begin() + static_cast<long>(n));
        EXPECT_EQ(decode_parameter_set(cut).status, LoadStatus::Corrupt) << "length " << n;
    }
}

TEST_F(ParameterStoreTest, CorruptedFileGivesDefaultsAndAnEmergency) {
    {
        CoeApplication app(dev);
        app.attach_parameter_store(path);
        ASSERT_EQ(write(app, 0x2000, 1, 4500), SdoAbort::None);
        ASSERT_EQ(write(app, 0x1010, 1, kStoreSignature), SdoAbort::None);
    }
    auto b = file_bytes();
    b[b.size() / 2] ^= 0xFF;
    write_bytes(b);
    test::Bench bench(1);
    std::string why;
    const auto rep = bench.app().attach_parameter_store(path);
    EXPECT_EQ(rep.load.status, LoadStatus::Corrupt);
    EXPECT_NE(rep.load.detail.find("checksum"), std::string::npos) << rep.load.detail;
    EXPECT_EQ(bench.od().find(0x2000, 1)->get<std::uint32_t>(), 3000u);
    ASSERT_TRUE(bench.master.startup(AlState::PreOp, &why)) << why;
    master::CoeClient coe(bench.master, bench.master.slaves().at(0).station);
    coe.upload(0x1000, 0);  // collects the emergency waiting in the mailbox
    ASSERT_FALSE(coe.emergencies().empty());
    EXPECT_EQ(coe.emergencies().front().error_code, emcy::DataSet);
    EXPECT_EQ(coe.emergencies().front().data[0], 'P');
}

TEST_F(ParameterStoreTest, FileOfAnotherDeviceIsNotApplied) {
    ParameterSet s;
    s.identity = dev.identity;
    s.identity.product_code ^= 1;
    s.records.push_back({0x2000, 1, le32(4500)});
    write_bytes(encode_parameter_set(s));
    CoeApplication app(dev);
    EXPECT_EQ(app.attach_parameter_store(path).load.status, LoadStatus::OtherDevice);
    EXPECT_EQ(read(app, 0x2000, 1), 3000u);
}

TEST_F(ParameterStoreTest, SignaturesThroughTheMailbox) {
    test::Bench bench(1);
    bench.app().attach_parameter_store(path);
    std::string why;
    ASSERT_TRUE(bench.master.startup(AlState::PreOp, &why)) << why;
    master::CoeClient coe(bench.master, bench.master.slaves().at(0).station);
    EXPECT_EQ(coe.download_value<std::uint32_t>(0x1010, 1, 0x11111111).abort, SdoAbort::CannotTransfer);
    EXPECT_TRUE(coe.download_value<std::uint32_t>(0x1010, 1, kStoreSignature).ok());
    EXPECT_TRUE(fs::exists(path));
    const auto r = coe.upload(0x1010, 1);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.data, le32(1));
}

TEST_F(ParameterStoreTest, UnwritableDirectoryIsAHardwareError) {
    CoeApplication app(dev);
    app.attach_parameter_store((dir / "missing-subdir" / "slave-0.param").string());
    EXPECT_EQ(write(app, 0x1010, 1, kStoreSignature), SdoAbort::HardwareError);
    EXPECT_FALSE(app.parameter_store()->last_error().empty());
}

}  // namespace
