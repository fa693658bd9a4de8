// The mapping words and the automatic mappings of every P2580 operation mode, written out as the
// specification's tables 6.5-6.14 print them (hex parameter value pppp.SSww).
#include <gtest/gtest.h>

#include "twinsync/mapping.hpp"

namespace vecat::twinsync {
namespace {

// A P2615/P2616 column of a table: sub-ID 0 (count) then the objects.
MappingWords col(std::initializer_list<std::uint32_t> objects) {
    MappingWords m{};
    m[0] = static_cast<std::uint32_t>(objects.size());
    std::size_t i = 1;
    for (auto w : objects)
        m[i++] = w;
    return m;
}

struct Row {
    Setting setting;
    MappingWords send, receive;
};

TEST(TwinMapping, StandardAndExtendedWords) {
    // 0A5A.0110: P2650 element 1 (current error location), 16 bit.
    EXPECT_EQ(decode_standard(0x0A5A0110), (MappedObject{2650, 1, 0x10, false}));
    EXPECT_EQ(decode_standard(0x0A280020), (MappedObject{2600, 0, 0x20, false}));
    EXPECT_FALSE(decode_standard(0x0A280018));  // widths are 0x10 or 0x20
    EXPECT_FALSE(decode_standard(0x0A280000));
    // Extended: pppp.SS.tt with type 0 = parameter, 1 = scope.
    EXPECT_EQ(decode_extended(0x0A2F0000), (MappedObject{2607, 0, 0, false}));
    EXPECT_EQ(decode_extended(0x03F30001), (MappedObject{1011, 0, 0, true}));
    EXPECT_FALSE(decode_extended(0x0A2F0002));
    EXPECT_EQ(mapping_word(2650, 1, 0x10), 0x0A5A0110u);
}

TEST(TwinMapping, EveryAutomaticMappingEqualsTheSpecificationTables) {
    const auto errors = col({0x0A5A0010, 0x0A5A0110});
    const auto speed_master = col({0x0A250010, 0x0A270010, 0x107C0010});
    const auto speed_slave_rx = col({0x0A2C0010, 0x0A2E0010, 0x107D0010});
    const Row rows[] = {
        // Table 6.5 TWD V1, 6.6 TWD V2, 6.7 SCON: master sends torque, speed, single-turn position.
        {Setting::TwdMasterV1, speed_master, errors},
        {Setting::TwdSlaveV1, errors, speed_slave_rx},
        {Setting::TwdMasterV2, speed_master, errors},
        {Setting::TwdSlaveV2, errors, speed_slave_rx},
        {Setting::SconMaster, speed_master, errors},
        {Setting::SconSlave, errors, speed_slave_rx},
        // Table 6.8 PCON: P0412 (019C.0020) and P2599; the slave receives P2608 and P2606.
        {Setting::PconMaster, col({0x019C0020, 0x0A270010}), errors},
        {Setting::PconSlave, errors, col({0x0A300020, 0x0A2E0010})},
        // 6.2.8 PCON_IP_SLAVE: the counterpart of PCON_MASTER.
        {Setting::PconIpSlave, errors, col({0x0A300020, 0x0A2E0010})},
        // Table 6.9 RPDC.
        {Setting::RpdcMaster, col({0x106A0010, 0x106C0010}), col({0x106B0010})},
        {Setting::RpdcSlave, col({0x106A0010}), col({0x106B0010, 0x0A2D0010})},
        // Table 6.10 VE: torque set-point P2596, speed P2599, P4220.
        {Setting::VeTconMaster, col({0x0A240010, 0x0A270010, 0x107C0010}), errors},
        {Setting::VeTconSlave, errors, col({0x0A2B0010, 0x0A2E0010, 0x107D0010})},
        // Table 6.11 REFPOS (the master's receive word printed 0A30.0010 is 32 bit: 0A30.0020).
        {Setting::PconRefposMaster, col({0x0A280020, 0x0A8E0010}), col({0x0A300020})},
        {Setting::PconRefposSlave, col({0x0A290020}), col({0x0A2F0020, 0x0A2D0010})},
        // Table 6.14 GANTRY.
        {Setting::PconGantryMaster, col({0x0A280020, 0x02FC0020, 0x08E00010}), col({0x0A300020, 0x0A1B0020})},
        {Setting::PconGantrySlave, col({0x0A290020, 0x01190020}), col({0x0A2F0020, 0x0A1B0020, 0x0A2C0010})},
    };
    for (const Row& r : rows) {
        SCOPED_TRACE(mode_info(static_cast<std::uint8_t>(r.setting))->name);
        const auto m = automatic_mapping(r.setting);
        ASSERT_TRUE(m.has_value());
        EXPECT_EQ(m->send, r.send);
        EXPECT_EQ(m->receive, r.receive);
        // Both directions fit the default frame (10 PDO bytes) and every word is a valid standard word.
        for (const auto* words : {&m->send, &m->receive}) {
            std::size_t bytes = 0;
            for (std::size_t i = 1; i <= (*words)[0]; ++i) {
                const auto o = decode_standard((*words)[i]);
                ASSERT_TRUE(o.has_value());
                bytes += o->bits / 8u;
            }
            EXPECT_LE(bytes, 10u);
        }
    }
    // A master's send mapping is its slave's receive mapping, width by width.
    auto widths = [](const MappingWords& w) {
        std::vector<unsigned> v;
        for (std::size_t i = 1; i <= w[0]; ++i)
            v.push_back(w[i] & 0xFF);
        return v;
    };
    for (auto [ms, ss] : {std::pair{Setting::TwdMasterV1, Setting::TwdSlaveV1},
                          std::pair{Setting::PconMaster, Setting::PconSlave},
                          std::pair{Setting::VeTconMaster, Setting::VeTconSlave},
                          std::pair{Setting::PconRefposMaster, Setting::PconRefposSlave},
                          std::pair{Setting::PconGantryMaster, Setting::PconGantrySlave}}) {
        EXPECT_EQ(widths(automatic_mapping(ms)->send), widths(automatic_mapping(ss)->receive));
        EXPECT_EQ(widths(automatic_mapping(ss)->send), widths(automatic_mapping(ms)->receive));
    }
    // No automatic mapping: user-specific, extended mapping, PLC.
    for (Setting s : {Setting::User, Setting::ExtMapMaster, Setting::ExtMapSlave, Setting::Plc})
        EXPECT_FALSE(automatic_mapping(s).has_value());
}

TEST(TwinMapping, ModesThatNeedHardwareAreRefusedWithAReason) {
    for (std::uint8_t s = 0; s <= kLastSetting; ++s) {
        const ModeInfo* m = mode_info(s);
        ASSERT_NE(m, nullptr);
        EXPECT_EQ(static_cast<std::uint8_t>(m->setting), s);
        const bool hardware = s == 9 || (s >= 14 && s <= 18) || s == 20 || (s >= 23 && s <= 28) || s >= 33;
        const bool rpdc = s == 10 || s == 11;
        EXPECT_EQ(!m->refusal.empty(), hardware || rpdc) << m->name;
    }
    EXPECT_NE(mode_info(14)->refusal.find("dSPACE"), std::string_view::npos);
    EXPECT_EQ(mode_info(35), nullptr);
    EXPECT_TRUE(mode_info(31)->extended);
    EXPECT_EQ(mode_info(30)->follow, Follow::PositionAbsolute);
    EXPECT_EQ(mode_info(8)->follow, Follow::PositionDelta);
    EXPECT_EQ(mode_info(13)->follow, Follow::Torque);
    EXPECT_EQ(mode_info(29)->role, Role::Master);
    EXPECT_EQ(mode_info(30)->role, Role::Slave);
}

// The slave tables with "P0301 Setpoint mode ... IP-Mode(1)" in the slave column: 6.5 (2), 6.6 (4), 6.7 (6),
// 6.8 (8), 6.9 (11), 6.10 (13), 6.11 (22), 6.14 (30). Masters ("any"), USER and EXT_MAP ("-", "any") and
// PCON_IP_SLAVE (no table) do not.
TEST(TwinMapping, SlaveTablesThatRequireIpMode) {
    for (std::uint8_t s = 0; s <= kLastSetting; ++s) {
        const bool table = s == 2 || s == 4 || s == 6 || s == 8 || s == 11 || s == 13 || s == 22 || s == 30;
        EXPECT_EQ(requires_ip_mode(static_cast<Setting>(s)), table) << mode_info(s)->name;
    }
}

}  // namespace
}  // namespace vecat::twinsync
