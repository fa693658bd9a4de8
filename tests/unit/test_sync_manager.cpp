// SyncManagers at the ESC level: mailbox (one buffer) and buffered (three buffers) modes.
#include <gtest/gtest.h>

#include "esc/esc.hpp"
#include "esc/sii_image.hpp"
#include "test_support.hpp"

using namespace vecat;
using namespace vecat::esc;
using namespace vecat::protocol;

namespace {
// An ESC without firmware: the test plays the PDI side.
struct EscOnly : ::testing::Test {
    Esc esc{EscConfig{}, build_sii_image(device::default_drive())};

    std::uint16_t dg(Command cmd, std::uint16_t ado, std::vector<std::uint8_t>& data) {
        return test::esc_datagram(esc, cmd, ado, data);
    }
    std::uint16_t write(std::uint16_t ado, std::vector<std::uint8_t> data) {
        return dg(Command::APWR, ado, data);
    }
    std::uint16_t read(std::uint16_t ado, std::vector<std::uint8_t>& data) {
        return dg(Command::APRD, ado, data);
    }
    void sm(unsigned i, std::uint16_t start, std::uint16_t len, std::uint8_t ctrl) {
        std::vector<std::uint8_t> r{static_cast<std::uint8_t>(start),
                                    static_cast<std::uint8_t>(start >> 8),
                                    static_cast<std::uint8_t>(len),
                                    static_cast<std::uint8_t>(len >> 8),
                                    ctrl,
                                    0,
                                    1,
                                    0};
        ASSERT_EQ(write(sm_addr(i), r), 1);
    }
};
}  // namespace

TEST_F(EscOnly, MailboxWriteRefusedWhileFull) {
    sm(0, 0x1800, 8, 0x26);
    EXPECT_EQ(write(0x1800, {1, 2, 3, 4, 5, 6, 7, 8}), 1);
    EXPECT_TRUE(esc.sm_mailbox_full(0));
    EXPECT_EQ(esc.peek(0x0805) & 0x08, 0x08);
    EXPECT_EQ(write(0x1800, {9, 9, 9, 9, 9, 9, 9, 9}), 0);  // refused, content kept
    std::array<std::uint8_t, 8> got{};
    ASSERT_TRUE(esc.pdi_mailbox_take(0, got));
    EXPECT_EQ(got[0], 1);
    EXPECT_EQ(esc.peek(0x0805) & 0x08, 0);
    EXPECT_EQ(write(0x1800, {9, 9, 9, 9, 9, 9, 9, 9}), 1);
    std::vector<std::uint8_t> r(8);
    EXPECT_EQ(read(0x1800, r), 0);  // the master may not read its write mailbox
}

TEST_F(EscOnly, MailboxFullOnlyAfterTheLastByte) {
    sm(0, 0x1800, 8, 0x26);
    EXPECT_EQ(write(0x1800, {1, 2, 3, 4}), 1);
    EXPECT_FALSE(esc.sm_mailbox_full(0));
    EXPECT_EQ(write(0x1804, {5, 6, 7, 8}), 1);
    EXPECT_TRUE(esc.sm_mailbox_full(0));
}

TEST_F(EscOnly, MailboxReadEmptiesOnTheLastByte) {
    sm(1, 0x18F6, 8, 0x22);
    std::vector<std::uint8_t> r(8);
    EXPECT_EQ(read(0x18F6, r), 0);  // empty: not counted
    const std::uint8_t msg[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    ASSERT_TRUE(esc.pdi_mailbox_put(1, msg));
    EXPECT_FALSE(esc.pdi_mailbox_put(1, msg));  // still full
    std::vector<std::uint8_t> part(4);
    EXPECT_EQ(read(0x18F6, part), 1);
    EXPECT_TRUE(esc.sm_mailbox_full(1));
    EXPECT_EQ(read(0x18F6, r), 1);
    EXPECT_EQ(r[7], 8);
    EXPECT_FALSE(esc.sm_mailbox_full(1));
    EXPECT_EQ(esc.peek(0x080D) & 0x08, 0);
    EXPECT_EQ(read(0x18F6, r), 0);
}

TEST_F(EscOnly, RepeatRequestRaisesAnEvent) {
    sm(1, 0x18F6, 8, 0x22);
    esc.pdi_take_sm_activation_event();
    EXPECT_EQ(write(0x080E, {0x03}), 1);
    EXPECT_TRUE(esc.sm_repeat_request(1));
    EXPECT_TRUE(esc.pdi_take_sm_activation_event());
    esc.pdi_set_repeat_ack(1, true);
    EXPECT_EQ(esc.peek(0x080F) & 0x02, 0x02);
}

TEST_F(EscOnly, ThreeBufferOutputsAreConsistent) {
    sm(2, 0x1000, 4, 0x64);
    std::array<std::uint8_t, 4> out{};
    EXPECT_FALSE(esc.pdi_buffer_read(2, out));  // never written
    EXPECT_EQ(write(0x1000, {1, 1, 1, 1}), 1);
    ASSERT_TRUE(esc.pdi_buffer_read(2, out));
    EXPECT_EQ(out[0], 1);
    EXPECT_EQ(write(0x1000, {2, 2}), 1);  // incomplete write: not visible
    ASSERT_TRUE(esc.pdi_buffer_read(2, out));
    EXPECT_EQ(out[0], 1);
    EXPECT_EQ(write(0x1002, {2, 2}), 1);
    EXPECT_EQ(write(0x1000, {3, 3, 3, 3}), 1);  // two complete writes before the PDI looks: newest wins
    ASSERT_TRUE(esc.pdi_buffer_read(2, out));
    EXPECT_EQ(out, (std::array<std::uint8_t, 4>{3, 3, 3, 3}));
    EXPECT_EQ(esc.sm_buffer_writes(2), 3u);
}

TEST_F(EscOnly, ThreeBufferInputsAreConsistent) {
    sm(3, 0x1100, 4, 0x20);
    const std::uint8_t a[4] = {0xA, 0xA, 0xA, 0xA}, bb[4] = {0xB, 0xB, 0xB, 0xB};
    ASSERT_TRUE(esc.pdi_buffer_write(3, a));
    std::vector<std::uint8_t> first(2), second(2);
    EXPECT_EQ(read(0x1100, first), 1);
    ASSERT_TRUE(esc.pdi_buffer_write(3, bb));  // new data while the master is half-way through
    EXPECT_EQ(read(0x1102, second), 1);
    EXPECT_EQ(second[0], 0xA);  // the read finishes on the buffer it started with
    std::vector<std::uint8_t> all(4);
    EXPECT_EQ(read(0x1100, all), 1);
    EXPECT_EQ(all[0], 0xB);
    std::vector<std::uint8_t> again(4);
    EXPECT_EQ(read(0x1100, again), 1);  // no new data: the last buffer again
    EXPECT_EQ(again[3], 0xB);
    EXPECT_EQ(write(0x1100, {1, 2, 3, 4}), 0);  // the master may not write its read buffer
}

TEST_F(EscOnly, DisabledSyncManagerIsPlainMemory) {
    sm(2, 0x1000, 4, 0x64);
    EXPECT_EQ(write(sm_addr(2) + 6, {0x00}), 1);  // disable
    EXPECT_EQ(write(0x1000, {7, 7, 7, 7}), 1);
    std::vector<std::uint8_t> r(4);
    EXPECT_EQ(read(0x1000, r), 1);
    EXPECT_EQ(r[0], 7);
}

TEST_F(EscOnly, SyncManagerOutsideRamIsIgnored) {
    sm(2, 0x2FF0, 0x20, 0x64);  // three buffers would run past the 8 KiB RAM
    EXPECT_FALSE(esc.sm_config(2).valid);
    EXPECT_EQ(write(0x2FF0, {1}), 1);  // plain memory
}

// ESC datasheet section I 8.7: a SyncManager the PDI deactivated (0x0807 bit 0) while the master has it
// enabled keeps its whole area read/write protected; the working counter shows it.
TEST_F(EscOnly, SyncManagerDeactivatedByThePdiLocksItsArea) {
    sm(2, 0x1000, 4, 0x64);
    esc.pdi_deactivate_sm(2, true);
    EXPECT_EQ(write(0x1000, {7, 7, 7, 7}), 0);
    std::vector<std::uint8_t> r{0xAA, 0xAA, 0xAA, 0xAA};
    EXPECT_EQ(read(0x1000, r), 0);
    EXPECT_EQ(r[0], 0xAA);  // nothing placed in the frame
    EXPECT_EQ(esc.peek(0x1000), 0);
    // A datagram that also covers memory outside the area counts for that part only.
    std::vector<std::uint8_t> wide(8);
    EXPECT_EQ(read(0x0FFC, wide), 1);
    // The mailbox SMs as in INIT: configured and enabled by the master, deactivated by the firmware.
    sm(1, 0x1100, 8, 0x22);
    esc.pdi_deactivate_sm(1, true);
    std::vector<std::uint8_t> mbx(8);
    EXPECT_EQ(read(0x1100, mbx), 0);
    // Activated again by the PDI: a buffered SM works as before; disabled by the master: plain memory.
    esc.pdi_deactivate_sm(2, false);
    EXPECT_EQ(write(0x1000, {1, 2, 3, 4}), 1);
    EXPECT_EQ(write(sm_addr(1) + 6, {0x00}), 1);
    EXPECT_EQ(read(0x1100, mbx), 1);
}

// ESC datasheet section II 0x0120: without device emulation (0x0141 bit 0 = 0) AL control behaves like a
// mailbox: once written by the master it takes no further write until the PDI has read it.
// What Esc::prefetch_for_frame asks the caches for follows the process data SyncManagers as the master
// configures them: their buffers' areas, and not the mailboxes'.
TEST_F(EscOnly, ThePrefetchPlanFollowsTheProcessDataSyncManagers) {
    EXPECT_TRUE(esc.prefetch_sms().empty());
    sm(0, 0x1000, 128, 0x26);
    sm(1, 0x1080, 128, 0x22);
    sm(2, 0x1100, 16, 0x64);
    sm(3, 0x1180, 20, 0x20);
    auto plan = esc.prefetch_sms();
    ASSERT_EQ(plan.size(), 2u);
    EXPECT_EQ(plan[0].index, 2);
    EXPECT_EQ(plan[0].start, 0x1100);
    EXPECT_EQ(plan[0].span, 48);
    EXPECT_EQ(plan[1].index, 3);
    EXPECT_EQ(plan[1].start, 0x1180);
    EXPECT_EQ(plan[1].span, 60);
    ASSERT_EQ(write(sm_addr(2) + 6, {0}), 1);  // SM2 disabled
    plan = esc.prefetch_sms();
    ASSERT_EQ(plan.size(), 1u);
    EXPECT_EQ(plan[0].index, 3);
    ASSERT_EQ(write(sm_addr(3) + 6, {0}), 1);  // disabled (an enabled one keeps its area), then moved
    EXPECT_TRUE(esc.prefetch_sms().empty());
    sm(3, 0x1200, 8, 0x20);
    plan = esc.prefetch_sms();
    ASSERT_EQ(plan.size(), 1u);
    EXPECT_EQ(plan[0].start, 0x1200);
    EXPECT_EQ(plan[0].span, 24);
}

TEST_F(EscOnly, AlControlIsAMailboxWithoutDeviceEmulation) {
    ASSERT_EQ(esc.peek(addr(Reg::EscConfiguration)) & esc_config::DeviceEmulation, 0);
    EXPECT_EQ(write(addr(Reg::AlControl), {0x02, 0x00}), 1);
    EXPECT_EQ(write(addr(Reg::AlControl), {0x04, 0x00}), 0);  // not read yet: refused
    EXPECT_EQ(write(addr(Reg::AlControl) + 1, {0x00}), 0);    // either byte
    EXPECT_EQ(esc.peek16(addr(Reg::AlControl)), 0x0002);
    // A datagram that also covers other writable registers counts for them.
    EXPECT_EQ(write(addr(Reg::AlControl), std::vector<std::uint8_t>(25, 0)), 1);  // up to 0x0138
    EXPECT_EQ(esc.peek16(addr(Reg::AlControl)), 0x0002);
    EXPECT_EQ(esc.pdi_read_al_control(), 0x0002);
    EXPECT_EQ(write(addr(Reg::AlControl), {0x04, 0x00}), 1);
    EXPECT_EQ(esc.peek16(addr(Reg::AlControl)), 0x0004);
}

TEST(AlControl, AlwaysWritableWithDeviceEmulation) {
    auto dev = device::default_drive();
    dev.pdi_control = 0x0104;  // digital I/O PDI, device emulation (as an EL2004's SII word 0)
    Esc esc{EscConfig{}, build_sii_image(dev)};
    ASSERT_NE(esc.peek(addr(Reg::EscConfiguration)) & esc_config::DeviceEmulation, 0);
    for (const std::uint8_t state : {std::uint8_t{0x02}, std::uint8_t{0x04}}) {
        std::vector<std::uint8_t> data{state, 0};
        EXPECT_EQ(test::esc_datagram(esc, Command::APWR, addr(Reg::AlControl), data), 1);
        EXPECT_EQ(esc.peek(addr(Reg::AlControl)), state);
    }
}

// ESC datasheet section I 8.5: a buffered SyncManager of 1 byte has no buffer mechanism (accesses pass to
// the memory, the watchdog trigger still works); on an ESC with a digital I/O PDI such SyncManagers guard
// the digital output register 0x0F00-0x0F03. Without that PDI there is no such register.
TEST(SingleByteSyncManager, OnTheDigitalOutputRegisterOfADigitalIoEsc) {
    for (const std::uint16_t pdi : {std::uint16_t{0x0005}, std::uint16_t{0x0104}}) {
        auto dev = device::default_drive();
        dev.pdi_control = pdi;
        Esc esc{EscConfig{}, build_sii_image(dev)};
        auto dg = [&](Command cmd, std::uint16_t ado, std::vector<std::uint8_t> data) {
            return test::esc_datagram(esc, cmd, ado, data);
        };
        const bool dio = pdi == 0x0104;
        EXPECT_EQ(dg(Command::APWR, sm_addr(2), {0x00, 0x0F, 1, 0, 0x44, 0, 1, 0}), 1);
        EXPECT_EQ(esc.sm_config(2).valid, dio) << pdi;
        EXPECT_EQ(dg(Command::APWR, 0x0F00, {0x0A}), dio ? 1 : 0) << pdi;
        EXPECT_EQ(esc.peek(0x0F00), dio ? 0x0A : 0) << pdi;
        if (!dio) continue;
        EXPECT_EQ(esc.sm_buffer_writes(2), 1u);
        EXPECT_EQ(esc.peek(0x0440) & 1, 1);  // watchdog triggered
        std::array<std::uint8_t, 1> out{};
        EXPECT_TRUE(esc.pdi_buffer_read(2, out));
        EXPECT_EQ(out[0], 0x0A);
        EXPECT_EQ(dg(Command::APRD, 0x0F00, {0}), 1);  // readable: no buffer in the way
        // Deactivated by the PDI: locked like any SyncManager area.
        esc.pdi_deactivate_sm(2, true);
        EXPECT_EQ(dg(Command::APWR, 0x0F00, {0x05}), 0);
        EXPECT_EQ(esc.peek(0x0F00), 0x0A);
        // Disabled by the master: the plain register.
        EXPECT_EQ(dg(Command::APWR, sm_addr(2) + 6, {0}), 1);
        EXPECT_EQ(dg(Command::APWR, 0x0F00, {0x05}), 1);
        EXPECT_EQ(esc.peek(0x0F00), 0x05);
    }
}
