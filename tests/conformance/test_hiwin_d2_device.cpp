// Conformance of the built-in HIWIN D2 (device/hiwin_d2.hpp, `vecat run --device hiwin-d2`) to the HIWIN
// Drive User Guide with EtherCAT (CoE) Interface (../shared/seeds/004_938c11eaa867f7ff.txt), as a master
// sees it: the project's master scans it, reads its dictionary through SDO information and uploads, remaps
// its PDOs in the guide's order, brings it to OP, homes it with each method and moves it in every mode.
// Test names cite the guide's sections; "BadInput" tests write one device's format to the other.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <initializer_list>
#include <map>
#include <optional>

#include "common/bytes.hpp"
#include "device/hiwin_d2.hpp"
#include "master/coe_client.hpp"
#include "protocol/cia402.hpp"
#include "testing/virtual_segment.hpp"

namespace vecat::conformance {
namespace {

using protocol::AlState;
using protocol::SdoAbort;
namespace cmd = protocol::cia402::cmd;
namespace sw = protocol::cia402::sw;
using DT = protocol::DataType;
constexpr std::int32_t kRev = 1 << 20;

std::uint32_t abort_of(const master::SdoResult& r) {
    return r.transport_ok ? static_cast<std::uint32_t>(r.abort) : 0xFFFFFFFFu;
}

std::int64_t value_of(const master::SdoResult& r, bool is_signed) {
    std::uint64_t u = 0;
    for (std::size_t i = 0; i < r.data.size() && i < 8; ++i)
        u |= static_cast<std::uint64_t>(r.data[i]) << (8 * i);
    if (is_signed && !r.data.empty() && r.data.size() < 8 && (r.data.back() & 0x80))
        u |= ~std::uint64_t{0} << (8 * r.data.size());
    return static_cast<std::int64_t>(u);
}

struct D2 {
    explicit D2(AlState target = AlState::Op, device::DeviceDescription d = device::hiwin_d2())
        : vs({.device = std::move(d), .target = target}), coe(vs.master(), vs.station(0)) {}
    testing::VirtualSegment vs;
    master::CoeClient coe;
};

// 3.2: identity object and device type; the SII carries the same identity.
TEST(HiwinD2Device, Hiwin_3_2_Identity) {
    D2 d(AlState::PreOp);
    const auto& s = d.vs.master().slaves().at(0);
    EXPECT_EQ(s.sii.identity.vendor_id, 0x0000AAAAu);
    EXPECT_EQ(s.sii.identity.product_code, 0x00000003u);
    struct Row {
        std::uint8_t sub;
        std::uint32_t value;
    };
    for (const Row r : {Row{1, 0x0000AAAA}, Row{2, 0x00000003}, Row{3, 0}, Row{4, 0}}) {
        const auto u = d.coe.upload(0x1018, r.sub);
        ASSERT_TRUE(u.ok()) << int(r.sub);
        EXPECT_EQ(value_of(u, false), r.value) << "0x1018:" << int(r.sub);
    }
    EXPECT_EQ(value_of(d.coe.upload(0x1018, 0), false), 4);
    EXPECT_EQ(value_of(d.coe.upload(0x1000, 0), false), 0x00020192);
}

// 3.5, 3.6 (and the defaults of 9.3/9.4): every object of the tables with its type, access, PDO mapping
// and, where the guide gives one, its value, as SDO information and an upload report them.
struct ObjectRow {
    std::uint16_t index;
    std::uint8_t sub;
    DT type;
    bool writable;
    bool mappable;
    std::optional<std::int64_t> value;
};
const ObjectRow kTables[] = {
    // 3.5
    {0x6040, 0, DT::Unsigned16, true, true, {}},
    {0x6041, 0, DT::Unsigned16, false, true, {}},
    {0x6060, 0, DT::Integer8, true, true, {}},
    {0x6061, 0, DT::Integer8, false, true, {}},
    {0x6063, 0, DT::Integer32, false, true, {}},
    {0x6064, 0, DT::Integer32, false, true, {}},
    {0x6065, 0, DT::Unsigned32, true, false, {}},
    {0x606C, 0, DT::Integer32, false, true, {}},
    {0x6071, 0, DT::Integer16, true, true, 0},
    {0x6075, 0, DT::Unsigned32, true, false, {}},
    {0x6078, 0, DT::Integer16, false, true, {}},
    {0x607A, 0, DT::Integer32, true, true, {}},
    {0x607C, 0, DT::Integer32, true, false, {}},
    {0x607D, 0, DT::Unsigned8, false, false, 2},
    {0x607D, 1, DT::Integer32, true, false, {}},
    {0x607D, 2, DT::Integer32, true, false, {}},
    {0x607F, 0, DT::Unsigned32, true, false, {}},
    {0x6081, 0, DT::Unsigned32, true, false, {}},
    {0x6083, 0, DT::Unsigned32, true, false, {}},
    {0x6084, 0, DT::Unsigned32, true, false, {}},
    {0x6085, 0, DT::Unsigned32, true, true, {}},
    {0x6087, 0, DT::Unsigned32, true, true, 1000},  // 9.3: default 1000
    {0x6098, 0, DT::Unsigned16, true, false, 0},    // 9.4: value 0
    {0x6099, 0, DT::Unsigned8, false, false, 2},
    {0x6099, 1, DT::Unsigned32, true, false, {}},
    {0x6099, 2, DT::Unsigned32, true, false, {}},
    {0x609A, 0, DT::Unsigned32, true, false, 1000000},
    {0x60B1, 0, DT::Integer32, true, true, {}},
    {0x60B2, 0, DT::Integer16, true, true, {}},
    {0x60B8, 0, DT::Unsigned16, true, true, {}},
    {0x60B9, 0, DT::Integer32, false, true, {}},
    {0x60BA, 0, DT::Integer32, false, true, {}},
    {0x60C2, 0, DT::Integer8, false, false, 1},
    {0x60C2, 1, DT::Unsigned16, true, false, 8},
    {0x60F4, 0, DT::Integer32, false, true, {}},
    {0x60FC, 0, DT::Integer32, false, true, {}},
    {0x60FD, 0, DT::Unsigned32, false, true, {}},
    {0x60FF, 0, DT::Unsigned32, true, true, {}},
    {0x6502, 0, DT::Unsigned32, false, false, 0x3AF},
    // 3.6
    {0x2000, 0, DT::Unsigned16, false, false, {}},
    {0x2001, 0, DT::Integer32, false, false, {}},
    {0x2002, 0, DT::Integer32, false, false, {}},
    {0x2003, 0, DT::Integer32, false, false, {}},
    {0x2010, 0, DT::Unsigned16, true, true, 0},
    {0x2020, 0, DT::Integer8, false, false, {}},
    {0x2021, 0, DT::Integer32, false, true, {}},
    {0x2022, 0, DT::Real32, false, true, {}},
    {0x2040, 0, DT::Unsigned16, false, false, {}},
    {0x2041, 0, DT::Unsigned16, true, false, 1},
    {0x2042, 0, DT::Unsigned16, true, false, 1},
    {0x2050, 0, DT::Real32, true, false, {}},
    {0x2051, 0, DT::Real32, true, false, {}},
    {0x2060, 0, DT::Unsigned8, true, false, 0},
    {0x2100, 0, DT::Unsigned32, false, false, 0},
    {0x2101, 0, DT::Unsigned32, false, false, 0},
};

TEST(HiwinD2Device, Hiwin_3_5_And_3_6_ObjectsAsTheTablesGiveThem) {
    D2 d(AlState::PreOp);
    for (const ObjectRow& r : kTables) {
        SCOPED_TRACE(::testing::Message() << std::hex << "0x" << r.index << ":" << int(r.sub));
        const auto e = d.coe.entry_description(r.index, r.sub, 0);
        ASSERT_TRUE(e);
        EXPECT_EQ(e->data_type, static_cast<std::uint16_t>(r.type));
        EXPECT_EQ(e->bit_length, protocol::fixed_bit_length(r.type));
        EXPECT_EQ((e->access & 0x0038) != 0, r.writable) << "access 0x" << e->access;
        EXPECT_EQ((e->access & 0x00C0) != 0, r.mappable) << "access 0x" << e->access;
        if (r.value) {
            const auto u = d.coe.upload(r.index, r.sub);
            ASSERT_TRUE(u.ok());
            EXPECT_EQ(value_of(u, protocol::is_signed(r.type)), *r.value);
        }
    }
    // 3.6 REAL32 defaults: common gain 0.3, velocity gain 0.001.
    for (auto [index, v] : {std::pair{0x2050, 0.3f}, std::pair{0x2051, 0.001f}}) {
        const auto u = d.coe.upload(static_cast<std::uint16_t>(index), 0);
        ASSERT_TRUE(u.ok());
        float f = 0;
        std::memcpy(&f, u.data.data(), 4);
        EXPECT_FLOAT_EQ(f, v);
    }
    // Objects of the vecat drive the D2 does not have.
    for (std::uint16_t absent :
         std::initializer_list<std::uint16_t>{0x603F, 0x605A, 0x6067, 0x6077, 0x608F, 0x60BB, 0x2110, 0x2111})
        EXPECT_EQ(abort_of(d.coe.upload(absent, 0)), 0x06020000u) << std::hex << absent;
}

// 3.4 and 4: SyncManagers 0-3 (mailbox at 0x1800/0x18F6, process data at 0x1000/0x1100), 0x1C00 and one
// assignment slot each.
TEST(HiwinD2Device, Hiwin_3_4_And_4_SyncManagers) {
    D2 d(AlState::PreOp);
    const auto& s = d.vs.master().slaves().at(0);
    ASSERT_GE(s.sii.sync_managers.size(), 4u);
    const std::uint16_t starts[] = {0x1800, 0x18F6, 0x1000, 0x1100};
    for (unsigned i = 0; i < 4; ++i)
        EXPECT_EQ(s.sii.sync_managers[i].start, starts[i]) << "SM" << i;
    EXPECT_EQ(value_of(d.coe.upload(0x1C00, 0), false), 4);
    for (std::uint8_t i = 1; i <= 4; ++i)
        EXPECT_EQ(value_of(d.coe.upload(0x1C00, i), false), i);
    EXPECT_EQ(value_of(d.coe.upload(0x1C12, 1), false), 0x1600);
    EXPECT_EQ(value_of(d.coe.upload(0x1C13, 1), false), 0x1A00);
    EXPECT_EQ(abort_of(d.coe.upload(0x1C12, 2)), 0x06090011u);
}

// 7: the default layout: RxPDO 0x1600 ControlWord, Target Position, Mode of Operation; TxPDO 0x1A00
// StatusWord, Position Actual Value, Velocity Actual Value.
TEST(HiwinD2Device, Hiwin_7_DefaultLayout) {
    D2 d(AlState::PreOp);
    EXPECT_EQ(value_of(d.coe.upload(0x1600, 0), false), 3);
    EXPECT_EQ(value_of(d.coe.upload(0x1600, 1), false), 0x60400010);
    EXPECT_EQ(value_of(d.coe.upload(0x1600, 2), false), 0x607A0020);
    EXPECT_EQ(value_of(d.coe.upload(0x1600, 3), false), 0x60600008);
    EXPECT_EQ(value_of(d.coe.upload(0x1A00, 0), false), 3);
    EXPECT_EQ(value_of(d.coe.upload(0x1A00, 1), false), 0x60410010);
    EXPECT_EQ(value_of(d.coe.upload(0x1A00, 2), false), 0x60640020);
    EXPECT_EQ(value_of(d.coe.upload(0x1A00, 3), false), 0x606C0020);
    // 0x1600-0x1602 and 0x1A00-0x1A03, six subindexes each (3.3).
    for (std::uint16_t i :
         std::initializer_list<std::uint16_t>{0x1600, 0x1601, 0x1602, 0x1A00, 0x1A01, 0x1A02, 0x1A03})
        EXPECT_TRUE(d.coe.upload(i, 6).ok()) << std::hex << i;
    EXPECT_EQ(abort_of(d.coe.upload(0x1603, 0)), 0x06020000u);
    EXPECT_EQ(abort_of(d.coe.upload(0x1A04, 0)), 0x06020000u);
}

// The guide's remapping (7): 0x1C12:0/0x1C13:0 = 0, the objects into subindexes 1-5 (without clearing
// subindex 0 first), subindex 0 = their number, the mapping object into 0x1C1x:1, 0x1C1x:0 = 1, then OP.
// rx/tx: mapping values.
void remap_in_the_guides_order(master::CoeClient& c, const std::vector<std::uint32_t>& rx,
                               const std::vector<std::uint32_t>& tx) {
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1C12, 0, 0).ok());
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1C13, 0, 0).ok());
    for (std::size_t i = 0; i < rx.size(); ++i)
        ASSERT_TRUE(c.download_value<std::uint32_t>(0x1600, static_cast<std::uint8_t>(i + 1), rx[i]).ok())
            << i;
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1600, 0, static_cast<std::uint8_t>(rx.size())).ok());
    for (std::size_t i = 0; i < tx.size(); ++i)
        ASSERT_TRUE(c.download_value<std::uint32_t>(0x1A00, static_cast<std::uint8_t>(i + 1), tx[i]).ok())
            << i;
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1A00, 0, static_cast<std::uint8_t>(tx.size())).ok());
    ASSERT_TRUE(c.download_value<std::uint16_t>(0x1C12, 1, 0x1600).ok());
    ASSERT_TRUE(c.download_value<std::uint16_t>(0x1C13, 1, 0x1A00).ok());
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1C12, 0, 1).ok());
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1C13, 0, 1).ok());
}

// Outputs: controlword, target position, mode, target velocity, target torque; inputs: statusword,
// position, velocity, mode display, touch probe 1 value.
const std::vector<std::uint32_t> kRx = {0x60400010, 0x607A0020, 0x60600008, 0x60FF0020, 0x60710010};
const std::vector<std::uint32_t> kTx = {0x60410010, 0x60640020, 0x606C0020, 0x60610008, 0x60BA0020};
namespace out {
constexpr std::size_t kControlword = 0, kTargetPosition = 2, kMode = 6, kTargetVelocity = 7,
                      kTargetTorque = 11;
}
namespace in {
constexpr std::size_t kStatusword = 0, kPosition = 2, kVelocity = 6, kModeDisplay = 10, kProbeValue = 11;
}

// 7 with a master: the guide's order is accepted by the D2 and the D2 reaches OP with the new layout; at
// most five objects per mapping object; the entries of an assigned mapping object are refused.
TEST(HiwinD2Device, Hiwin_7_RemappingInTheGuidesOrderThenOp) {
    D2 d(AlState::PreOp);
    remap_in_the_guides_order(d.coe, kRx, kTx);
    auto& m = d.vs.master();
    ASSERT_TRUE(m.configure_process_data());
    ASSERT_TRUE(m.request_state(AlState::SafeOp));
    m.exchange_process_data();
    ASSERT_TRUE(m.request_state(AlState::Op));
    EXPECT_EQ(m.outputs(0).size(), 13u);
    EXPECT_EQ(m.inputs(0).size(), 15u);
}

TEST(HiwinD2Device, Hiwin_7_BadInput_SixObjectsAndAssignedPdo) {
    D2 d(AlState::PreOp);
    // While 0x1C12 lists 0x1600, its entries cannot change.
    EXPECT_EQ(abort_of(d.coe.download_value<std::uint32_t>(0x1600, 4, 0x60FF0020)), 0x06010003u);
    ASSERT_TRUE(d.coe.download_value<std::uint8_t>(0x1C12, 0, 0).ok());
    for (std::uint8_t i = 1; i <= 6; ++i)
        ASSERT_TRUE(d.coe.download_value<std::uint32_t>(0x1600, i, kRx[(i - 1) % kRx.size()]).ok());
    EXPECT_EQ(abort_of(d.coe.download_value<std::uint8_t>(0x1600, 0, 6)), 0x06090031u) << "at most 5 objects";
}

// The vecat drive keeps CiA 301's rule: the guide's order (entries written while subindex 0 is not 0) is
// refused with 0x06010003 there.
TEST(HiwinD2Device, Hiwin_7_BadInput_TheGuidesOrderOnTheVecatDrive) {
    D2 d(AlState::PreOp, device::default_drive());
    ASSERT_TRUE(d.coe.download_value<std::uint8_t>(0x1C12, 0, 0).ok());
    EXPECT_EQ(abort_of(d.coe.download_value<std::uint32_t>(0x1600, 1, 0x60400010)), 0x06010003u);
}

// 9.1.2: 0x60C2:1 is one UINT16 in 62.5 us (16 = 1 ms); 0x60C2:2 does not exist. The vecat drive has
// CiA 402's UINT8 value and INT8 index: a master writing one device's format to the other gets that
// device's abort.
TEST(HiwinD2Device, Hiwin_9_1_2_BadInput_InterpolationPeriodFormats) {
    D2 d(AlState::PreOp);
    EXPECT_TRUE(d.coe.download_value<std::uint16_t>(0x60C2, 1, 16).ok());
    EXPECT_EQ(value_of(d.coe.upload(0x60C2, 1), false), 16);
    EXPECT_EQ(abort_of(d.coe.download_value<std::uint8_t>(0x60C2, 1, 1)), 0x06070013u) << "CiA 402 format";
    EXPECT_EQ(abort_of(d.coe.download_value<std::int8_t>(0x60C2, 2, -3)), 0x06090011u);
    D2 v(AlState::PreOp, device::default_drive());
    EXPECT_EQ(abort_of(v.coe.download_value<std::uint16_t>(0x60C2, 1, 16)), 0x06070012u) << "HIWIN format";
    EXPECT_TRUE(v.coe.download_value<std::uint8_t>(0x60C2, 1, 1).ok());
}

// 9.1.2 II (2): "After switching on the distributed clock, the drive will automatically set up the content
// of interpolation time period (0x60C2:1) in accordance with the synchronization signal cycle ... 500us,
// then the drive will set up the interpolation time period to (0.5/0.0625=8)". Here 1 ms: 16.
TEST(HiwinD2Device, Hiwin_9_1_2_DcSetsTheInterpolationPeriodFromSync0) {
    D2 d(AlState::Init);
    auto& o = d.vs.master().options();
    o.dc.enable = true;
    o.dc.sync0_cycle_ns = 1'000'000;
    o.dc.static_drift_frames = 100;
    std::string why;
    ASSERT_TRUE(d.vs.master().startup(AlState::SafeOp, &why)) << why;  // SYNC0 set up, checked by the slave
    master::CoeClient c(d.vs.master(), d.vs.station(0));               // (the mailbox is configured now)
    // Never in CiA 402's format (1 x 10^-3 s would read as 1, 62.5 us): still the default 8 (500 us) or 16.
    const auto before = value_of(c.upload(0x60C2, 1), false);
    EXPECT_TRUE(before == 8 || before == 16) << before;
    d.vs.cycles(200);
    const auto u = c.upload(0x60C2, 1);
    ASSERT_TRUE(u.ok()) << std::hex << abort_of(u);
    EXPECT_EQ(value_of(u, false), 16);
}

// 9.4: the D2 takes 0, 1-6, 33 and 34 in its UINT16 0x6098; other methods are out of range. The vecat
// drive's 0x6098 is CiA 402's INT8.
TEST(HiwinD2Device, Hiwin_9_4_BadInput_HomingMethods) {
    D2 d(AlState::PreOp);
    for (std::uint16_t m : std::initializer_list<std::uint16_t>{0, 1, 2, 3, 4, 5, 6, 33, 34})
        EXPECT_TRUE(d.coe.download_value<std::uint16_t>(0x6098, 0, m).ok()) << m;
    for (std::uint16_t m : std::initializer_list<std::uint16_t>{7, 17, 35, 37, 0xFFFF})
        EXPECT_EQ(abort_of(d.coe.download_value<std::uint16_t>(0x6098, 0, m)), 0x06090030u) << m;
    EXPECT_EQ(abort_of(d.coe.download_value<std::int8_t>(0x6098, 0, 35)), 0x06070013u) << "CiA 402 format";
    D2 v(AlState::PreOp, device::default_drive());
    EXPECT_EQ(abort_of(v.coe.download_value<std::uint16_t>(0x6098, 0, 4)), 0x06070012u) << "HIWIN format";
    EXPECT_TRUE(v.coe.download_value<std::int8_t>(0x6098, 0, 35).ok());
}

// 3.5/9.3: target torque -1000~1000 on the D2 (the vecat drive takes any INT16).
TEST(HiwinD2Device, Hiwin_9_3_BadInput_TargetTorqueRange) {
    D2 d(AlState::PreOp);
    EXPECT_TRUE(d.coe.download_value<std::int16_t>(0x6071, 0, -1000).ok());
    EXPECT_EQ(abort_of(d.coe.download_value<std::int16_t>(0x6071, 0, 1001)), 0x06090031u);
    EXPECT_EQ(abort_of(d.coe.download_value<std::int16_t>(0x6071, 0, -1001)), 0x06090032u);
    // 3.7: the index signal is read-only (9.4's "input function (0x2020)" is 0x2010).
    EXPECT_EQ(abort_of(d.coe.download_value<std::int8_t>(0x2020, 0, 1)), 0x06010002u);
    D2 v(AlState::PreOp, device::default_drive());
    EXPECT_TRUE(v.coe.download_value<std::int16_t>(0x6071, 0, 1500).ok());
}

// 3.6: the manufacturer areas differ. The vecat drive's simulated machine (0x2100:1-7) and fault injection
// (0x2101) written to the D2 meet its read-only error events; the D2's limit protection 0x2041 does not
// exist on the vecat drive.
TEST(HiwinD2Device, Hiwin_3_6_BadInput_ManufacturerObjectsOfTheOtherDevice) {
    D2 d(AlState::PreOp);
    EXPECT_EQ(abort_of(d.coe.download_value<std::int32_t>(0x2100, 1, -1000)), 0x06090011u);
    EXPECT_EQ(abort_of(d.coe.download_value<std::uint32_t>(0x2101, 0, 0x7305)), 0x06010002u);
    EXPECT_EQ(abort_of(d.coe.download_value<std::uint16_t>(0x2041, 0, 2)), 0x06090031u) << "0 or 1";
    EXPECT_TRUE(d.coe.download_value<std::uint16_t>(0x2041, 0, 0).ok());
    D2 v(AlState::PreOp, device::default_drive());
    EXPECT_EQ(abort_of(v.coe.download_value<std::uint16_t>(0x2041, 0, 0)), 0x06020000u);
    EXPECT_TRUE(v.coe.download_value<std::int32_t>(0x2100, 1, -1000).ok());
}

// ---- Through a master in OP with the guide's layout: homing with each method, moves in every mode.
struct D2InOp : ::testing::Test {
    D2 d{AlState::PreOp};
    master::Master& m = d.vs.master();
    void SetUp() override {
        remap_in_the_guides_order(d.coe, kRx, kTx);
        ASSERT_TRUE(m.configure_process_data());
        ASSERT_TRUE(m.request_state(AlState::SafeOp));
        m.exchange_process_data();
        ASSERT_TRUE(m.request_state(AlState::Op));
        ASSERT_TRUE(d.coe.download_value<std::uint32_t>(0x6099, 1, 4 * kRev).ok());
        ASSERT_TRUE(d.coe.download_value<std::uint32_t>(0x6099, 2, kRev / 2).ok());
        ASSERT_TRUE(d.coe.download_value<std::uint32_t>(0x609A, 0, 40 * kRev).ok());
        ASSERT_TRUE(d.coe.download_value<std::uint32_t>(0x6081, 0, 4 * kRev).ok());
        ASSERT_TRUE(d.coe.download_value<std::uint32_t>(0x6083, 0, 40 * kRev).ok());
        ASSERT_TRUE(d.coe.download_value<std::uint32_t>(0x6084, 0, 40 * kRev).ok());
        set_mode(8);
        set_target(position());
        for (std::uint16_t c : {cmd::Shutdown, cmd::SwitchOn, cmd::EnableOperation}) {
            set_cw(c);
            d.vs.cycles(5);
        }
        ASSERT_EQ(statusword() & 0x6F, 0x27) << "operation enabled";
    }
    Bytes o() { return m.outputs(0); }
    ConstBytes i() const { return m.inputs(0); }
    void set_cw(std::uint16_t c) { st_le16(o().data() + out::kControlword, c); }
    void set_mode(std::int8_t md) { o()[out::kMode] = static_cast<std::uint8_t>(md); }
    void set_target(std::int32_t p) {
        st_le32(o().data() + out::kTargetPosition, static_cast<std::uint32_t>(p));
    }
    void set_velocity(std::uint32_t v) { st_le32(o().data() + out::kTargetVelocity, v); }
    void set_torque(std::int16_t t) {
        st_le16(o().data() + out::kTargetTorque, static_cast<std::uint16_t>(t));
    }
    std::uint16_t statusword() const { return ld_le16(i().data() + in::kStatusword); }
    std::int32_t position() const { return static_cast<std::int32_t>(ld_le32(i().data() + in::kPosition)); }
    std::int32_t velocity() const { return static_cast<std::int32_t>(ld_le32(i().data() + in::kVelocity)); }
    std::int8_t mode_display() const { return static_cast<std::int8_t>(i()[in::kModeDisplay]); }
    // Cycles (1 ms) until pred or max cycles; true when pred came.
    template <class P>
    bool until(P pred, unsigned max) {
        for (unsigned k = 0; k < max; ++k) {
            d.vs.cycle();
            if (pred()) return true;
        }
        return false;
    }
    void switch_mode(std::int8_t md) {
        set_mode(md);
        ASSERT_TRUE(until([&] { return mode_display() == md; }, 50)) << int(md);
    }
    void pp_move_to(std::int32_t target) {
        switch_mode(1);
        set_target(target);
        set_cw(cmd::EnableOperation | 0x10);
        ASSERT_TRUE(until([&] { return (statusword() & sw::Bit12) != 0; }, 50));
        set_cw(cmd::EnableOperation);
        ASSERT_TRUE(until([&] { return (statusword() & sw::TargetReached) != 0; }, 20000));
        ASSERT_NEAR(position(), target, 200);
    }
    // 9.4's steps: 0x6060 = 6, 0x6098, bit 4 until bits 10 and 12, bit 4 cleared.
    bool home(std::uint16_t method) {
        EXPECT_TRUE(d.coe.download_value<std::uint16_t>(0x6098, 0, method).ok());
        switch_mode(6);
        set_cw(cmd::EnableOperation | 0x10);
        // The bits of an earlier homing go when this one starts ("performing homing": 10, 12, 13 = 0).
        if (!until([&] { return (statusword() & sw::Bit12) == 0; }, 50)) return false;
        const bool done = until(
            [&] {
                return (statusword() & (sw::TargetReached | sw::Bit12)) == (sw::TargetReached | sw::Bit12);
            },
            30000);
        set_cw(cmd::EnableOperation);
        d.vs.cycles(2);
        return done && !(statusword() & sw::Bit13);
    }
};

// 9.4 through a master: each method homes, and afterwards 0x6064 reads 0 at the home position (offset 0):
// the axis stands within what it braked past it. 0x2020 (3.7) shows the index touched.
TEST_F(D2InOp, Hiwin_9_4_HomesWithEachMethod) {
    for (std::uint16_t method : std::initializer_list<std::uint16_t>{1, 2, 3, 4, 5, 6, 33, 34}) {
        SCOPED_TRACE(method);
        if (method == 5 || method == 6) {
            // Start above the home switch dog (3 to 4 revolutions of the machine).
            pp_move_to(position() + 8 * kRev -
                       static_cast<std::int32_t>(value_of(d.coe.upload(0x6063, 0), true)));
        }
        ASSERT_TRUE(home(method));
        EXPECT_LT(std::abs(position()), kRev / 50);
        // Where the home is on the machine (0x6063, the encoder, which homing does not move; the D2's
        // machine: limit switches at -/+20 revolutions, the home switch dog from 3 to 4, the index at k +
        // 1/4).
        const auto home_at =
            value_of(d.coe.upload(0x6063, 0), true) - value_of(d.coe.upload(0x6064, 0), true);
        const std::map<int, std::int64_t> expected = {{1, -20 * kRev + kRev / 4}, {2, 19 * kRev + kRev / 4},
                                                      {3, 2 * kRev + kRev / 4},   {4, 4 * kRev + kRev / 4},
                                                      {5, 4 * kRev + kRev / 4},   {6, 2 * kRev + kRev / 4}};
        if (expected.count(method))
            EXPECT_NEAR(static_cast<double>(home_at), static_cast<double>(expected.at(method)), 2);
        else
            EXPECT_EQ(((home_at - kRev / 4) % kRev + kRev) % kRev, 0) << "33/34: on an index";
        EXPECT_EQ(value_of(d.coe.upload(0x2020, 0), true), 1) << "3.7: index touched";
    }
    // 0: no homing, nothing moves, no error.
    const auto before = position();
    EXPECT_TRUE(d.coe.download_value<std::uint16_t>(0x6098, 0, 0).ok());
    switch_mode(6);
    set_cw(cmd::EnableOperation | 0x10);
    d.vs.cycles(200);
    EXPECT_NEAR(position(), before, 50);
    EXPECT_EQ(statusword() & (sw::Bit12 | sw::Bit13), 0);
}

// 9.4 VI-VIII: after homing, 0x2010 bit 0 through the SDO: bit 15 and the position cleared to 0.
TEST_F(D2InOp, Hiwin_9_4_AccuracyCompensationThroughTheMaster) {
    ASSERT_TRUE(home(34));
    EXPECT_FALSE(statusword() & 0x8000);
    ASSERT_TRUE(d.coe.download_value<std::uint16_t>(0x2010, 0, 1).ok());
    d.vs.cycles(5);
    EXPECT_TRUE(statusword() & 0x8000);
    EXPECT_NEAR(position(), 0, 5);
}

// 9: PP, PV, PT, CSP, CSV, CST through the guide's layout.
TEST_F(D2InOp, Hiwin_9_MovesInEveryMode) {
    // 9.1.2 CSP in free run, the target every 1 ms cycle: step (2), "the content of 0x60C2:1 shall be set to
    // (1/0.0625)=16".
    ASSERT_TRUE(d.coe.download_value<std::uint16_t>(0x60C2, 1, 16).ok());
    std::int32_t p = position();
    for (int k = 0; k < 500; ++k) {
        p += 1000;
        set_target(p);
        d.vs.cycle();
    }
    d.vs.cycles(300);  // settled
    EXPECT_NEAR(position(), p, 100);
    // 9.1.1 PP.
    pp_move_to(p + 2 * kRev);
    // 9.2 PV and CSV (0x60FF UINT32, count/s).
    switch_mode(3);
    set_velocity(kRev);
    d.vs.cycles(500);
    EXPECT_NEAR(velocity(), kRev, kRev / 50);
    set_mode(9);
    set_velocity(2 * kRev);
    d.vs.cycles(300);
    EXPECT_EQ(mode_display(), 9);
    EXPECT_NEAR(velocity(), 2 * kRev, kRev / 20);
    set_velocity(0);
    d.vs.cycles(300);
    EXPECT_LT(std::abs(velocity()), kRev / 50);
    // 9.3 PT with the torque slope 0x6087 (0.1 %/s), and CST.
    switch_mode(4);
    ASSERT_TRUE(d.coe.download_value<std::uint32_t>(0x6087, 0, 10000).ok());
    set_torque(50);
    d.vs.cycles(200);
    const auto v_pt = velocity();
    EXPECT_GT(v_pt, kRev / 10);
    set_mode(10);
    set_torque(-100);
    d.vs.cycles(100);
    EXPECT_EQ(mode_display(), 10);
    EXPECT_LT(velocity(), v_pt);
}

// 3.7 0x2100 "Bit 1: Encoder error": an encoder fault injected (`vecat fault inject encoder`) faults the
// D2 and shows in its error events 1; its own read-only 0x2101 (error events 2) is left alone. 0x2010 bit 1
// "Reset the drive" resets the fault once it is gone and clears the events.
TEST_F(D2InOp, Hiwin_3_7_ErrorEventsOfAnInjectedFault) {
    const auto r = d.vs.fault("inject encoder slave=0");
    ASSERT_EQ(r.substr(0, 2), "ok") << r;
    ASSERT_TRUE(until([&] { return (statusword() & 0x4F) == 0x08; }, 3000)) << "FAULT";
    EXPECT_EQ(value_of(d.coe.upload(0x2100, 0), false), 0x2);
    EXPECT_EQ(value_of(d.coe.upload(0x2101, 0), false), 0);
    ASSERT_EQ(d.vs.fault("clear all").substr(0, 2), "ok");
    set_cw(0);
    d.vs.cycles(5);
    ASSERT_TRUE(d.coe.download_value<std::uint16_t>(0x2010, 0, 2).ok());
    EXPECT_TRUE(until([&] { return (statusword() & 0x4F) == 0x40; }, 100)) << "SWITCH ON DISABLED";
    EXPECT_EQ(value_of(d.coe.upload(0x2100, 0), false), 0);
}

// 10 through a master: 0x60B8 = 0x0011, the value in 0x60BA (mapped) at the next Z phase.
TEST_F(D2InOp, Hiwin_10_TouchProbeLatchesTheZPhase) {
    ASSERT_TRUE(d.coe.download_value<std::uint16_t>(0x60B8, 0, 0x0011).ok());
    d.vs.cycles(2);
    EXPECT_EQ(value_of(d.coe.upload(0x60B9, 0), true), 0x0001);
    switch_mode(3);
    set_velocity(kRev);
    d.vs.cycles(1500);
    EXPECT_EQ(value_of(d.coe.upload(0x60B9, 0), true), 0x0003);
    const auto latched = static_cast<std::int32_t>(ld_le32(i().data() + in::kProbeValue));
    EXPECT_EQ(latched % kRev, value_of(d.coe.upload(0x2021, 0), true) % kRev) << "on an index";
}

}  // namespace
}  // namespace vecat::conformance
