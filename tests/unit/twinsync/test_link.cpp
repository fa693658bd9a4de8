// The physical link: baud rate and frame size against the TWIN sampling time, the cable with its
// faults, and the slave's synchronisation controller.
#include <gtest/gtest.h>

#include <initializer_list>

#include "twinsync/link.hpp"

namespace vecat::twinsync {
namespace {

TEST(TwinLink, FrameMustFitTheSamplingTime) {
    LinkConfig c;  // 4 MBaud, 16-byte frame, 4 kHz: 40 us of 250 us
    EXPECT_EQ(check_link(c), "");
    EXPECT_EQ(frame_time_ns(16, 4'000'000), 40'000u);
    c.baud_selection = 6;  // 250 kBaud: 16 bytes take 640 us
    const std::string why = check_link(c);
    EXPECT_NE(why.find("640.0 us"), std::string::npos) << why;
    EXPECT_NE(why.find("250.0 us"), std::string::npos) << why;
    c.frame_size_selection = 5;  // 6 bytes: 240 us fit at 4 kHz...
    EXPECT_EQ(check_link(c), "");
    c.switching_frequency = 3;  // ...but not in the 125 us of 8 kHz
    EXPECT_NE(check_link(c), "");
    // 32 bytes at 1 MBaud (320 us) do not fit 250 us, at 2 MBaud (160 us) they do; at 8 kHz neither.
    c = {};
    c.frame_size_selection = 13;
    c.baud_selection = 2;
    EXPECT_NE(check_link(c), "");
    c.baud_selection = 1;
    EXPECT_EQ(check_link(c), "");
    c.switching_frequency = 3;
    EXPECT_NE(check_link(c), "");
    // The mapping must fit the frame.
    c = {};
    c.send_pdo_bytes = 12;
    EXPECT_NE(check_link(c).find("P2615"), std::string::npos);
    c.send_pdo_bytes = 10;
    c.receive_pdo_bytes = 11;
    EXPECT_NE(check_link(c).find("P2616"), std::string::npos);
    c.receive_pdo_bytes = 0;
    c.baud_selection = 7;
    EXPECT_NE(check_link(c), "");
}

// Chapter 2: the TWIN sampling time is 250 us or 125 us, 125 us at 8 kHz (P0302 = 3).
TEST(TwinLink, SamplingTimeIs125UsAt8kHzAnd250UsOtherwise) {
    EXPECT_EQ(sampling_time_ns(3), 125'000u);
    for (std::uint8_t code : std::initializer_list<std::uint8_t>{0, 1, 2, 4, 5})
        EXPECT_EQ(sampling_time_ns(code), 250'000u) << int{code};
    EXPECT_FALSE(sampling_time_ns(6));
    // The payload against the sampling time: a 32-byte frame (26 PDO bytes) takes 160 us at 2 MBaud, which
    // fits 250 us (16 kHz) but not 125 us (8 kHz); at 4 MBaud (80 us) it fits both.
    LinkConfig c;
    c.frame_size_selection = 13;
    c.baud_selection = 1;
    c.switching_frequency = 5;
    EXPECT_EQ(check_link(c), "");
    c.switching_frequency = 3;
    EXPECT_NE(check_link(c).find("125.0 us"), std::string::npos) << check_link(c);
    c.baud_selection = 0;
    EXPECT_EQ(check_link(c), "");
}

TEST(TwinLink, ChannelDeliversFromTheNextCycleAndInjectsFaults) {
    Channel ch;
    const std::uint8_t f[] = {1, 2, 3, 4, 5, 6};
    ch.send(0, f, 1000);
    EXPECT_TRUE(ch.receive(1, 1000).empty());  // not within the cycle it was sent in
    EXPECT_TRUE(ch.receive(0, 2000).empty());  // nor back to its sender
    ASSERT_EQ(ch.receive(1, 2000).size(), 6u);
    EXPECT_TRUE(ch.receive(1, 3000).empty());  // each frame once
    // Only the newest of several waiting frames is taken.
    const std::uint8_t g[] = {9, 9, 9, 9, 9, 9};
    ch.send(0, f, 3000);
    ch.send(0, g, 3100);
    auto r = ch.receive(1, 4000);
    ASSERT_EQ(r.size(), 6u);
    EXPECT_EQ(r[0], 9);
    EXPECT_TRUE(ch.receive(1, 5000).empty());
    // Corruption flips a bit; a drop loses the frame; a cable break stops everything, sync included.
    ch.faults().corrupt_next = 1;
    ch.send(0, f, 5000);
    r = ch.receive(1, 6000);
    ASSERT_EQ(r.size(), 6u);
    EXPECT_NE(r[5], 6);
    EXPECT_EQ(ch.frames_corrupted(), 1u);
    ch.faults().drop_next = 1;
    ch.send(0, f, 6000);
    EXPECT_TRUE(ch.receive(1, 7000).empty());
    EXPECT_EQ(ch.frames_dropped(), 1u);
    ch.sync_pulse(0, 7000);
    EXPECT_TRUE(ch.sync_seen(1, 6500));
    EXPECT_FALSE(ch.sync_seen(0, 6500));
    Channel::Injected i;
    i.cable_break = true;
    ch.inject(1, i);
    ch.send(0, f, 8000);
    EXPECT_TRUE(ch.receive(1, 9000).empty());
    EXPECT_FALSE(ch.sync_seen(1, 6500));
    ch.inject(1, {});
    i = {};
    i.sync_loss = true;
    ch.inject(0, i);
    ch.send(0, f, 9000);
    EXPECT_EQ(ch.receive(1, 10000).size(), 6u);  // data still passes
    EXPECT_FALSE(ch.sync_seen(1, 6500));
}

TEST(TwinLink, SyncControllerLocksWithEnoughGainAndLosesWithout) {
    // 40 ppm between the oscillators: 10 ns per 250 us cycle.
    SyncController s;
    s.reset();
    int locked_after = -1;
    for (int k = 0; k < 1000; ++k) {
        s.step(250'000, 40.0, 20, true, SyncController::Source::Twin);
        if (s.locked() && locked_after < 0) locked_after = k;
    }
    EXPECT_GE(locked_after, 20);  // 10 us at up to 300 ns per cycle
    EXPECT_LE(locked_after, 60);
    EXPECT_TRUE(s.locked());
    EXPECT_LT(std::abs(s.phase_ns()), 50.0);  // steady state: drift / gain = 10 / 0.5 ns
    // A gain below the drift cannot follow: 1 tick = 15 ns per cycle against 25 ns (100 ppm).
    s.reset();
    for (int k = 0; k < 4000; ++k)
        s.step(250'000, 100.0, 1, true, SyncController::Source::Twin);
    EXPECT_FALSE(s.locked());
    // Without pulses the slave is not synchronised, whatever its phase.
    s.reset();
    for (int k = 0; k < 100; ++k)
        s.step(250'000, 0.0, 20, true, SyncController::Source::Twin);
    ASSERT_TRUE(s.locked());
    s.step(250'000, 0.0, 20, false, SyncController::Source::Twin);
    EXPECT_FALSE(s.locked());
    // Synchronised by the fieldbus (DC): no phase to SYNC_OUT; free-running fieldbus: drift, no control.
    s.reset();
    s.step(250'000, 100.0, 0, true, SyncController::Source::FieldbusSynchronised);
    EXPECT_TRUE(s.locked());
    s.reset();
    for (int k = 0; k < 100; ++k)
        s.step(250'000, 100.0, 20, true, SyncController::Source::FieldbusFreeRun);
    EXPECT_FALSE(s.locked());
}

}  // namespace
}  // namespace vecat::twinsync
