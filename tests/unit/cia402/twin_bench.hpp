// Two vecat drives on one line, their TWINsync option cards connected by a cable, driven by the project's
// master in-process with 1 ms process data cycles (CSP): the bench of the TWINsync drive tests
// (test_twinsync_drive.cpp) and of the MSD TWINsync conformance tests (tests/conformance).
#pragma once

#include <gtest/gtest.h>

#include "cia402/drive.hpp"
#include "test_support.hpp"
#include "twinsync/parameters.hpp"

namespace vecat::cia402::twin_test {

inline constexpr std::uint64_t kMs = 1'000'000;
inline constexpr std::uint64_t kCycle = Drive::kServoPeriodNs;

inline std::unique_ptr<esc::Segment> gantry_line(const device::DeviceDescription& d, std::size_t n,
                                                 const esc::EscConfig& cfg) {
    return make_drive_segment(d, n, cfg, TwinsyncPreset::Gantry);
}
inline std::unique_ptr<esc::Segment> position_line(const device::DeviceDescription& d, std::size_t n,
                                                   const esc::EscConfig& cfg) {
    return make_drive_segment(d, n, cfg, TwinsyncPreset::Position);
}
inline std::unique_ptr<esc::Segment> speed_line(const device::DeviceDescription& d, std::size_t n,
                                                const esc::EscConfig& cfg) {
    return make_drive_segment(d, n, cfg, TwinsyncPreset::Speed);
}
// Connected, TWINsync OFF (P2614 = 0) until a test configures it.
inline std::unique_ptr<esc::Segment> connected_line(const device::DeviceDescription& d, std::size_t n,
                                                    const esc::EscConfig& cfg) {
    return make_drive_segment(d, n, cfg, TwinsyncPreset::None);
}

struct TwinBench : ::testing::Test {
    explicit TwinBench(test::SegmentFactory f = &gantry_line) : b{2, {}, device::default_drive(), f} {}
    test::Bench b;

    Drive& drive(std::size_t i) { return dynamic_cast<Drive&>(b.slave(i).app()); }
    coe::Entry& e(std::size_t i, std::uint16_t index, std::uint8_t sub = 0) {
        coe::Entry* x = b.od(i).find(index, sub);
        EXPECT_NE(x, nullptr) << std::hex << index;
        return *x;
    }
    coe::Entry& par(std::size_t i, std::uint16_t parameter, std::uint8_t sub = 0) {
        return e(i, twinsync::object_index(parameter), sub);
    }
    void SetUp() override {
        std::string why;
        ASSERT_TRUE(b.master.startup(protocol::AlState::Op, &why)) << why;
    }
    // One 1 ms process data cycle: controlword, mode and target position for each drive.
    void cycle(std::uint16_t cw0, std::int32_t pos0, std::uint16_t cw1 = 0, std::int8_t mode1 = 8,
               std::int32_t pos1 = 0, std::uint64_t ns = kMs) {
        auto o = b.master.outputs(0);
        st_le16(o.data(), cw0);
        o[2] = 8;
        st_le32(o.data() + 4, static_cast<std::uint32_t>(pos0));
        auto o1 = b.master.outputs(1);
        st_le16(o1.data(), cw1);
        o1[2] = static_cast<std::uint8_t>(mode1);
        st_le32(o1.data() + 4, static_cast<std::uint32_t>(pos1));
        ASSERT_EQ(b.master.exchange_process_data().value_or(0), b.master.expected_wkc());
        b.advance(ns);
    }
    std::uint16_t sw(std::size_t i) { return ld_le16(b.master.inputs(i).data()); }
    std::int32_t pos(std::size_t i) {
        return static_cast<std::int32_t>(ld_le32(b.master.inputs(i).data() + 4));
    }
    // Enables the master drive through EtherCAT; the slave drive follows its control word.
    void enable_gantry() {
        const std::int32_t p = pos(0);
        for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
            for (int i = 0; i < 5; ++i)
                cycle(cw, p);
        ASSERT_EQ(drive(0).cia402_state(), State::OperationEnabled);
        ASSERT_EQ(drive(1).cia402_state(), State::OperationEnabled);
    }
};

}  // namespace vecat::cia402::twin_test
