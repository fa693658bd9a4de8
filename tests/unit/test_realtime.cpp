// Real-time helpers of the transport: pinning takes effect, bad requests are refused with a reason.
#include <gtest/gtest.h>
#include <sched.h>

#include <thread>

#include "net/realtime.hpp"

using namespace vecat;

TEST(Realtime, PinningMovesTheThreadAndRefusesCpusThatDoNotExist) {
    std::string why;
    bool pinned = false;
    int cpu = -2;
    std::thread t([&] {
        pinned = net::pin_current_thread(0, &why);
        cpu = sched_getcpu();
    });
    t.join();
    ASSERT_TRUE(pinned) << why;
    EXPECT_EQ(cpu, 0);
    EXPECT_FALSE(net::pin_current_thread(-1, &why));
    EXPECT_FALSE(why.empty());
    why.clear();
    EXPECT_FALSE(net::pin_current_thread(CPU_SETSIZE - 1, &why));  // no machine here has 1024 CPUs
    EXPECT_FALSE(why.empty());
}

TEST(Realtime, FifoPriorityOutOfRangeIsRefused) {
    std::string why;
    bool ok = true;
    std::thread t([&] { ok = net::set_current_thread_fifo(1000, &why); });
    t.join();
    EXPECT_FALSE(ok);
    EXPECT_NE(why.find("SCHED_FIFO"), std::string::npos);
}

// A setting that fails does not keep the ones after it from taking effect (vecat-roundtrip carries on
// without it): a CPU that does not exist, then SCHED_FIFO.
TEST(Realtime, ASettingThatFailsLeavesTheOthersInEffectAndIsReported) {
    bool may_fifo = false;
    std::thread probe([&] { may_fifo = net::set_current_thread_fifo(1); });
    probe.join();
    if (!may_fifo) GTEST_SKIP() << "SCHED_FIFO needs CAP_SYS_NICE";
    std::string why;
    bool ok = true;
    int policy = -1;
    std::thread t([&] {
        net::RealtimeOptions opt;
        opt.cpu = 1 << 20;
        opt.fifo_priority = 1;
        ok = net::apply_realtime(opt, &why);
        policy = sched_getscheduler(0);
    });
    t.join();
    EXPECT_FALSE(ok);
    EXPECT_NE(why.find("CPU"), std::string::npos) << why;
    EXPECT_EQ(policy, SCHED_FIFO);
}

TEST(Realtime, CyclicThreadsGetATightTimerSlackUnlessAskedToLeaveIt) {
    unsigned long before = 0, applied = 0, left = 0;
    std::string why;
    bool ok = false, ok_left = false;
    std::thread t([&] {
        // Start from Linux's default, whatever this thread inherited.
        net::set_current_thread_timer_slack(50'000);
        before = net::current_thread_timer_slack();
        ok = net::apply_realtime(net::RealtimeOptions{}, &why);
        applied = net::current_thread_timer_slack();
    });
    t.join();
    ASSERT_TRUE(ok) << why;
    EXPECT_EQ(before, 50'000u);
    EXPECT_EQ(applied, net::RealtimeOptions::kTightTimerSlackNs);
    std::thread u([&] {
        net::RealtimeOptions opt;
        opt.timer_slack_ns = 0;
        net::set_current_thread_timer_slack(50'000);
        ok_left = net::apply_realtime(opt, &why);
        left = net::current_thread_timer_slack();
    });
    u.join();
    ASSERT_TRUE(ok_left) << why;
    EXPECT_EQ(left, 50'000u);  // untouched
}
