// Real-time helpers of the transport: pinning takes effect, bad requests are refused with a reason.
#include <gtest/gtest.h>
#include <sched.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <thread>
#include <vector>

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

namespace {

// The kB of AnonHugePages of the [heap] mappings (/proc/self/smaps: madvise splits it in up to three), or
// -1 without a [heap].
long heap_huge_kb() {
    std::ifstream smaps("/proc/self/smaps");
    std::string line;
    bool in_heap = false;
    long kb = -1;
    while (std::getline(smaps, line)) {
        // A mapping's first line starts with its address range ("55d3f46ce000-55d3fb5f9000 rw-p ...").
        if (!line.empty() && std::isxdigit(static_cast<unsigned char>(line[0])) &&
            line.find('-') != std::string::npos && line.find(':') > line.find(' ')) {
            in_heap = line.find("[heap]") != std::string::npos;
            continue;
        }
        if (in_heap && line.rfind("AnonHugePages:", 0) == 0)
            kb = std::max(kb, 0L) + std::stol(line.substr(14));
    }
    return kb;
}

std::string file_text(const char* path) {
    std::ifstream f(path);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

}  // namespace

// A heap of small blocks (as a network's slaves leave it) goes on huge pages where the kernel has them.
TEST(Realtime, TheHeapGoesOnHugePages) {
    const std::string thp = file_text("/sys/kernel/mm/transparent_hugepage/enabled");
    if (thp.empty() || thp.find("[never]") != std::string::npos)
        GTEST_SKIP() << "no transparent huge pages on this kernel";
    // 24 MiB in 4 KiB blocks: below the allocator's mmap threshold, so on the heap, with whole huge pages.
    std::vector<std::unique_ptr<std::uint8_t[]>> blocks;
    for (int i = 0; i < 6 * 1024; ++i) {
        blocks.push_back(std::make_unique<std::uint8_t[]>(4096));
        std::fill_n(blocks.back().get(), 4096, static_cast<std::uint8_t>(i));
    }
    if (heap_huge_kb() < 0) GTEST_SKIP() << "no [heap] mapping (a sanitizer's allocator)";
    std::string why;
    if (!net::back_heap_with_huge_pages(&why)) {
        // An older kernel without MADV_COLLAPSE: refused with a reason, not silently.
        EXPECT_NE(why.find("huge pages"), std::string::npos) << why;
        GTEST_SKIP() << why;
    }
    EXPECT_GE(heap_huge_kb(), 2048) << "no huge page in the heap";
    // The blocks kept their bytes.
    for (int i = 0; i < 6 * 1024; i += 511)
        EXPECT_EQ(blocks[static_cast<std::size_t>(i)][4095], static_cast<std::uint8_t>(i));
}
