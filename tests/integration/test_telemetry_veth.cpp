// Telemetry end to end: `vecat run --telemetry` serves two drives on a veth pair, the project's master
// moves them in CSP, and a separate `vecat scope` process records what arrives over Cyclone DDS. The
// samples must carry what the master read over EtherCAT within one cycle. Everything runs in a private
// network namespace; DDS uses its loopback with unicast discovery (no multicast on the host network).
#include <gtest/gtest.h>
#include <signal.h>
#include <time.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <thread>

#include "child_process.hpp"
#include "master/master.hpp"
#include "net/netns.hpp"
#include "net/raw_socket.hpp"
#include "telemetry/dds.hpp"
#include "telemetry/recording.hpp"
#include "test_support.hpp"

using namespace vecat;

namespace {

bool g_netns = false;

// Cyclone DDS on the namespace's loopback, peers found by unicast (what a user does on a host whose
// network has no multicast): see src/telemetry/README.md.
constexpr const char* kDdsConfig =
    "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex>"
    "<Peers><Peer Address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>";

std::uint64_t monotonic_ns() {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<std::uint64_t>(ts.tv_nsec);
}

using Process = test::ChildProcess;

// What the master read in one cycle, and when its frame was on the wire.
struct MasterRead {
    std::uint64_t sent_ns, received_ns;
    std::uint16_t statusword[2];
    std::int32_t position[2];
};

TEST(VethTelemetry, SubscriberReceivesWhatTheMasterReadWithinOneCycle) {
    if (!g_netns) GTEST_SKIP() << "needs root for a private network namespace";
    if (!telemetry::dds_built_in()) GTEST_SKIP() << telemetry::kNotBuiltIn;
    std::string why;
    ASSERT_TRUE(net::create_veth_pair("tlm", "tls", &why)) << why;
    const auto dir = std::filesystem::temp_directory_path() / ("vecat-telemetry-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir);
    const std::string csv = (dir / "scope.csv").string();

    Process scope({VECAT_BINARY, "scope", "--csv", csv, "--svg", (dir / "scope.svg").string()});
    ASSERT_GT(scope.pid, 0);
    Process vecat({VECAT_BINARY, "run", "--iface", "tls", "--slaves", "2", "--telemetry"});
    ASSERT_GT(vecat.pid, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // vecat opens its socket

    net::RawSocket sock("tlm");
    master::Master m(sock);
    ASSERT_TRUE(m.startup(protocol::AlState::Op, &why)) << why;
    std::vector<MasterRead> reads;
    reads.reserve(2000);
    auto next = std::chrono::steady_clock::now();
    auto cycle = [&](std::uint16_t cw, std::int32_t p0, std::int32_t p1) {
        for (std::size_t s = 0; s < 2; ++s) {
            auto o = m.outputs(s);
            st_le16(o.data(), cw);
            o[2] = 8;  // CSP
            st_le32(o.data() + 4, static_cast<std::uint32_t>(s == 0 ? p0 : p1));
        }
        MasterRead r{};
        r.sent_ns = monotonic_ns();
        const auto wkc = m.exchange_process_data();
        r.received_ns = monotonic_ns();
        for (std::size_t s = 0; s < 2; ++s) {
            r.statusword[s] = ld_le16(m.inputs(s).data());
            r.position[s] = static_cast<std::int32_t>(ld_le32(m.inputs(s).data() + 4));
        }
        reads.push_back(r);
        next += std::chrono::milliseconds(1);
        std::this_thread::sleep_until(next);
        return wkc.value_or(0) == m.expected_wkc();
    };
    ASSERT_TRUE(cycle(0, 0, 0));
    const std::int32_t a0 = reads.back().position[0], b0 = reads.back().position[1];
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        for (int i = 0; i < 20; ++i)
            cycle(cw, a0, b0);
    for (int k = 1; k <= 1000; ++k)
        cycle(0x0F, a0 + 500 * k, b0 - 250 * k);
    for (int k = 0; k < 100; ++k)
        cycle(0x0F, a0 + 500'000, b0 - 250'000);
    EXPECT_NEAR(reads.back().position[0], a0 + 500'000, 200);  // settled
    ASSERT_TRUE(m.request_state(protocol::AlState::Init));
    EXPECT_EQ(vecat.stop(), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the last samples travel
    ASSERT_EQ(scope.stop(), 0);

    telemetry::Recording rec;
    ASSERT_TRUE(telemetry::read_csv(csv, rec, &why)) << why;
    ASSERT_FALSE(rec.axes.empty()) << "no sample arrived over DDS";
    // The frame of cycle k was processed between the master's send and receive times, and the sampler
    // read the drive right after it. The master read in that frame what the slave published before it, and
    // reads with its next frame what the slave published last before that one (vecat also exchanges process
    // data on its timer ticks between frames). A sample is therefore within one cycle when it lies between
    // the master's reads of cycles k and k + 1 (extended by one cycle on either side for a position that
    // dithers at standstill); the statusword must be one the master read in these cycles.
    std::size_t matched = 0, between = 0, moving = 0;
    for (const auto& a : rec.axes) {
        ASSERT_LT(a.slave, 2);
        const auto it = std::find_if(reads.begin(), reads.end(), [&](const MasterRead& r) {
            return a.time_ns >= r.sent_ns && a.time_ns <= r.received_ns;
        });
        if (it == reads.end() || it + 2 >= reads.end() || it == reads.begin()) continue;
        const std::size_t k = static_cast<std::size_t>(it - reads.begin());
        auto range = [&](std::size_t from, std::size_t to) {
            std::int32_t lo = reads[from].position[a.slave], hi = lo;
            for (std::size_t j = from; j <= to; ++j) {
                lo = std::min(lo, reads[j].position[a.slave]);
                hi = std::max(hi, reads[j].position[a.slave]);
            }
            return std::pair{lo, hi};
        };
        // Between two reads the axis can also turn (overshoot while it settles): the sample may lie beyond
        // the reads by as much as the axis moves between two consecutive reads of the window.
        const auto [lo_read, hi_read] = range(k - 1, k + 2);
        std::int32_t step = 0;
        for (std::size_t j = k - 1; j < k + 2; ++j)
            step = std::max(step, std::abs(reads[j + 1].position[a.slave] - reads[j].position[a.slave]));
        const std::int32_t lo = lo_read - step, hi = hi_read + step;
        EXPECT_TRUE(a.position_actual >= lo && a.position_actual <= hi)
            << "slave " << a.slave << " sample position " << a.position_actual << " master read " << lo
            << ".." << hi << " around cycle " << k;
        // Target reached (bit 10) flickers within a millisecond while a CSP ramp starts and ends; the
        // other bits must be ones the master read.
        constexpr std::uint16_t kMask = static_cast<std::uint16_t>(~(1u << 10));
        bool status_seen = false;
        for (std::size_t j = k - 1; j <= k + 2; ++j)
            status_seen |= (a.statusword & kMask) == (reads[j].statusword[a.slave] & kMask);
        EXPECT_TRUE(status_seen) << "slave " << a.slave << " statusword 0x" << std::hex << a.statusword
                                 << " cycle " << std::dec << k;
        const auto [lo1, hi1] = range(k, k + 1);
        between += a.position_actual >= lo1 && a.position_actual <= hi1;
        moving += reads[k + 1].position[a.slave] != reads[k].position[a.slave];
        ++matched;
    }
    std::printf(
        "telemetry: %zu samples received, %zu matched to master cycles (%zu between the reads of the same "
        "and "
        "the next cycle, %zu while moving), %zu master cycles\n",
        rec.axes.size(), matched, between, moving, reads.size());
    // Best effort over loopback loses little; discovery may cost the first cycles.
    EXPECT_GT(matched, reads.size());  // two drives: at least half of the samples of both arrived
    EXPECT_GT(moving, 1000u);
    // Status and events are reliable: the AL state changes to OP and back arrived.
    EXPECT_FALSE(rec.status.empty());
    const bool saw_init = std::any_of(rec.events.begin(), rec.events.end(), [](const telemetry::Event& e) {
        return e.kind == telemetry::EventKind::AlState && e.new_value == 1;
    });
    EXPECT_TRUE(saw_init) << "event OP -> INIT missing";
    EXPECT_TRUE(std::filesystem::exists(dir / "scope.svg"));
    std::filesystem::remove_all(dir);
}

// The I/O samples (topic vecat_io) cross DDS field by field: a publisher and a subscriber in this process,
// on the namespace's loopback; samples are written until well after discovery (best effort, volatile).
TEST(VethTelemetry, IoSamplesTravelOverDds) {
    if (!g_netns) GTEST_SKIP() << "needs root for a private network namespace";
    if (!telemetry::dds_built_in()) GTEST_SKIP() << telemetry::kNotBuiltIn;
    telemetry::Subscriber sub(7);
    auto q = std::make_unique<telemetry::TelemetryQueue>();
    telemetry::Publisher pub(*q, 7);
    pub.start();
    std::atomic<bool> writing{true};
    std::thread writer([&] {
        for (std::uint64_t k = 1; writing.load(); ++k) {
            telemetry::IoSample s;
            s.time_ns = k;
            s.cycle = k;
            s.slave = 3;
            s.analog = true;
            s.in_channels = 2;
            s.out_channels = 16;
            s.in[0] = -1234;
            s.in[1] = static_cast<std::int16_t>(k % 1000);
            s.out[15] = 32767;
            q->push(telemetry::Record{s});
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
    });
    telemetry::Recording rec;
    std::atomic<bool> stop{false};
    sub.record(rec, 2.0, stop);
    writing = false;
    writer.join();
    pub.stop();
    ASSERT_FALSE(rec.io.empty()) << "no I/O sample arrived over DDS";
    for (const auto& s : rec.io) {
        EXPECT_EQ(s.slave, 3);
        EXPECT_TRUE(s.analog);
        EXPECT_EQ(s.in_channels, 2);
        EXPECT_EQ(s.out_channels, 16);
        EXPECT_EQ(s.in[0], -1234);
        EXPECT_EQ(s.in[1], static_cast<std::int16_t>(s.cycle % 1000));
        EXPECT_EQ(s.out[15], 32767);
        EXPECT_EQ(s.time_ns, s.cycle);
    }
    EXPECT_TRUE(rec.axes.empty());
}

TEST(VethTelemetry, ScopeSaysClearlyWhenTelemetryIsNotBuiltIn) {
    if (telemetry::dds_built_in()) GTEST_SKIP() << "built with Cyclone DDS";
    const std::string out =
        test::run_capture(std::string(VECAT_BINARY) + " scope --duration 1 2>&1; echo rc=$?");
    EXPECT_NE(out.find("not built in"), std::string::npos) << out;
    EXPECT_NE(out.find("rc=2"), std::string::npos) << out;
}

}  // namespace

int main(int argc, char** argv) {
    std::string why;
    g_netns = net::enter_private_netns(&why);
    if (!g_netns) std::fprintf(stderr, "veth telemetry tests skipped: %s\n", why.c_str());
    if (g_netns && system("ip link set dev lo up") != 0) g_netns = false;
    setenv("CYCLONEDDS_URI", kDdsConfig, 1);
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
