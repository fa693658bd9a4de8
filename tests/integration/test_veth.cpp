// End to end on a veth pair in a private network namespace: the vecat program serves the slaves on one
// end, the project's master runs on the other; the capture is checked with tshark.
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "child_process.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "net/netns.hpp"
#include "net/raw_socket.hpp"
#include "protocol/cia402.hpp"
#include "protocol/cia402_objects.hpp"
#include "protocol/registers.hpp"
#include "test_support.hpp"

namespace cia = vecat::protocol::cia402;

namespace obj = vecat::protocol::obj;

using namespace vecat;
using protocol::AlState;

namespace {

bool g_netns = false;
int g_pair = 0;

// `vecat run` on an interface with n slaves and a capture, given a moment to open its socket.
struct VecatProcess : test::ChildProcess {
    VecatProcess(const std::string& iface, unsigned slaves, const std::string& pcap,
                 const std::vector<std::string>& extra = {})
        : ChildProcess(arguments(iface, slaves, pcap, extra)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
    }
    static std::vector<std::string> arguments(const std::string& iface, unsigned slaves,
                                              const std::string& pcap,
                                              const std::vector<std::string>& extra) {
        std::vector<std::string> args{VECAT_BINARY,           "run",    "--iface", iface, "--slaves",
                                      std::to_string(slaves), "--pcap", pcap};
        args.insert(args.end(), extra.begin(), extra.end());
        return args;
    }
};

std::vector<std::string> split(const std::string& s, char c) {
    std::vector<std::string> v;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, c))
        v.push_back(item);
    if (!s.empty() && s.back() == c) v.emplace_back();
    return v;
}

// The working counter every datagram of this run must carry, from the command and the line alone.
unsigned expected_wkc(unsigned cmd, unsigned adp, unsigned n, unsigned lrw_expected) {
    const bool exists_pos = static_cast<std::uint16_t>(-static_cast<int>(adp)) < n;
    const bool exists_station = adp >= 0x1001 && adp < 0x1001 + n;
    switch (cmd) {
        case 1:
        case 2:
            return exists_pos ? 1 : 0;
        case 3:
            return exists_pos ? 3 : 0;
        case 4:
        case 5:
            return exists_station ? 1 : 0;
        case 6:
            return exists_station ? 3 : 0;
        case 7:
        case 8:
            return n;
        case 9:
            return 3 * n;
        case 12:
            return lrw_expected;
        case 13:
        case 14:
            return n;
        default:
            return 0;
    }
}

void check_capture(const std::string& pcap, unsigned n, unsigned lrw_expected) {
    if (system("command -v tshark >/dev/null 2>&1") != 0) GTEST_SKIP() << "tshark not installed";
    const std::string verbose = test::run_capture("tshark -r " + pcap + " -V 2>/dev/null");
    ASSERT_FALSE(verbose.empty());
    EXPECT_EQ(verbose.find("Malformed"), std::string::npos);
    EXPECT_EQ(test::run_capture("tshark -r " + pcap + " -z expert,error -q 2>/dev/null").find("Error"),
              std::string::npos);
    const std::string fields = test::run_capture(
        "tshark -r " + pcap +
        " -T fields -E separator=';' -e eth.src -e ecat.cmd -e ecat.adp -e ecat.cnt 2>/dev/null");
    auto lines = split(fields, '\n');
    unsigned checked = 0, lrw_in_preop = 0;
    std::vector<std::string> request;
    for (const auto& line : lines) {
        auto f = split(line, ';');
        if (f.size() < 4) continue;
        const unsigned first = static_cast<unsigned>(std::stoul(f[0].substr(0, 2), nullptr, 16));
        if (!(first & 0x02)) {
            request = f;
            continue;
        }
        ASSERT_FALSE(request.empty());
        auto cmds = split(request[1], ','), adps = split(request[2], ','), wkcs = split(f[3], ',');
        ASSERT_EQ(cmds.size(), wkcs.size());
        for (std::size_t i = 0; i < cmds.size(); ++i) {
            const unsigned cmd = static_cast<unsigned>(std::stoul(cmds[i], nullptr, 16));
            // Logical commands carry no ADP field: tshark leaves it out.
            const unsigned adp = i < adps.size() && !adps[i].empty()
                                     ? static_cast<unsigned>(std::stoul(adps[i], nullptr, 16))
                                     : 0;
            const unsigned long wkc = std::stoul(wkcs[i]);
            // An LRW sent while the slaves still are in PREOP (the master's SAFEOP request) finds their
            // process data SyncManagers deactivated by the firmware: locked, not counted (ESC datasheet
            // section I 8.7). All slaves change state after the same frame: 0 or the full count.
            if (cmd == 12 && wkc == 0)
                ++lrw_in_preop;
            else
                EXPECT_EQ(wkc, expected_wkc(cmd, adp, n, lrw_expected))
                    << "command " << cmd << " adp 0x" << std::hex << adp;
            ++checked;
        }
        request.clear();
    }
    EXPECT_GT(checked, 100u);
    EXPECT_LT(lrw_in_preop, 20u);  // only while a SAFEOP request is under way
}

class Veth : public ::testing::TestWithParam<unsigned> {
  protected:
    void SetUp() override {
        if (!g_netns)
            GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
        ++g_pair;
        m_ = "tm" + std::to_string(g_pair);
        s_ = "ts" + std::to_string(g_pair);
        std::string why;
        ASSERT_TRUE(net::create_veth_pair(m_, s_, &why)) << why;
        pcap_ = (std::filesystem::temp_directory_path() /
                 ("vecat-veth-" + std::to_string(getpid()) + "-" + std::to_string(g_pair) + ".pcapng"))
                    .string();
    }
    void TearDown() override {
        if (!pcap_.empty()) std::filesystem::remove(pcap_);
    }
    std::string m_, s_, pcap_;
};

}  // namespace

TEST_P(Veth, MasterFindsConfiguresAndWalksTheStates) {
    const unsigned n = GetParam();
    VecatProcess vecat(s_, n, pcap_);
    ASSERT_GT(vecat.pid, 0);
    net::RawSocket sock(m_);
    master::Master m(sock);
    EXPECT_EQ(m.count_slaves(), static_cast<int>(n));
    std::string why;
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    ASSERT_EQ(m.slaves().size(), n);
    const auto dev = device::default_drive();
    for (const auto& s : m.slaves()) {
        EXPECT_EQ(s.sii.identity.vendor_id, dev.identity.vendor_id);
        EXPECT_EQ(s.sii.identity.product_code, dev.identity.product_code);
        EXPECT_EQ(s.sii.identity.revision, dev.identity.revision);
        EXPECT_EQ(s.sii.device_name(), dev.name);
        EXPECT_EQ(s.sii.sync_managers.size(), 4u);
        EXPECT_EQ(s.out_bytes, dev.output_bytes());
    }
    for (int i = 0; i < 200; ++i)
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
    // ... and back down.
    ASSERT_TRUE(m.request_state(AlState::SafeOp));
    ASSERT_TRUE(m.request_state(AlState::PreOp));
    ASSERT_TRUE(m.request_state(AlState::Init));
    // A refused transition reports its AL status code.
    EXPECT_FALSE(m.request_state(AlState::Op, std::chrono::milliseconds(200)));
    for (const auto& r : m.last_states()) {
        EXPECT_EQ(r.state(), AlState::Init);
        EXPECT_TRUE(r.error());
        EXPECT_EQ(r.code, 0x0011);
    }
    for (const auto& s : m.slaves())
        EXPECT_TRUE(m.acknowledge_error(s.station, AlState::Init));
    EXPECT_FALSE(m.read_al_status(m.slaves()[0].station).error());
    EXPECT_EQ(vecat.stop(), 0);
    check_capture(pcap_, n, m.expected_wkc());
}

INSTANTIATE_TEST_SUITE_P(Slaves, Veth, ::testing::Values(1u, 3u));

// A master remaps the PDOs through CoE in PREOP, reaches OP with the new layout, and a wrong SM2 length
// is refused with 0x001D (and reported by an emergency).
TEST(VethCoe, RemapInPreOpReachesOpWithTheNewLayout) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    ++g_pair;
    const std::string mi = "cm" + std::to_string(g_pair), si = "cs" + std::to_string(g_pair);
    std::string why;
    ASSERT_TRUE(net::create_veth_pair(mi, si, &why)) << why;
    const std::string pcap =
        (std::filesystem::temp_directory_path() / ("vecat-coe-" + std::to_string(getpid()) + ".pcapng"))
            .string();
    VecatProcess vecat(si, 1, pcap);
    ASSERT_GT(vecat.pid, 0);
    net::RawSocket sock(mi);
    master::Master m(sock);
    ASSERT_TRUE(m.startup(AlState::PreOp, &why)) << why;
    const auto st = m.slaves()[0].station;
    master::CoeClient c(m, st);
    auto u32 = [](std::uint32_t v) { return v; };
    // Given: RxPDO 0x1601 (controlword, target position, profile velocity) and a new TxPDO 0x1A02
    // (statusword, position actual value, torque actual value) assigned instead of the defaults.
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1C12, 0, 0).ok());
    ASSERT_TRUE(c.download_value<std::uint16_t>(0x1C12, 1, 0x1601).ok());
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1C12, 0, 1).ok());
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1A02, 0, 0).ok());
    ASSERT_TRUE(c.download_value(0x1A02, 1, u32(0x60410010)).ok());
    ASSERT_TRUE(c.download_value(0x1A02, 2, u32(0x60640020)).ok());
    ASSERT_TRUE(c.download_value(0x1A02, 3, u32(0x60770010)).ok());
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1A02, 0, 3).ok());
    // Rules of ETG.1020: entries change only while subindex 0 is 0; only mappable objects are accepted.
    EXPECT_EQ(c.download_value(0x1A02, 1, u32(0x60410010)).abort, protocol::SdoAbort::Subindex0NotZero);
    EXPECT_EQ(c.download_value<std::uint8_t>(0x1A03, 0, 0).abort, protocol::SdoAbort::None);
    EXPECT_EQ(c.download_value(0x1A03, 1, u32(0x60400010)).abort, protocol::SdoAbort::NotMappable);
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1C13, 0, 0).ok());
    ASSERT_TRUE(c.download_value<std::uint16_t>(0x1C13, 1, 0x1A02).ok());
    ASSERT_TRUE(c.download_value<std::uint8_t>(0x1C13, 0, 1).ok());

    // When: the master reads the new layout through CoE and goes to OP.
    ASSERT_TRUE(m.configure_process_data());
    EXPECT_EQ(m.slaves()[0].out_bytes, 10u);
    EXPECT_EQ(m.slaves()[0].in_bytes, 8u);
    ASSERT_TRUE(m.request_state(AlState::SafeOp));
    auto out = m.outputs(0);
    st_le32(out.data() + 2, 123456);  // target position
    m.exchange_process_data();
    ASSERT_TRUE(m.request_state(AlState::Op));
    for (int i = 0; i < 100; ++i)
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
    // Then: the drive received the target position through the new mapping, and refuses to have it
    // written by SDO while it is mapped.
    auto tp = c.upload(obj::target_position.index, 0);
    ASSERT_TRUE(tp.ok());
    EXPECT_EQ(ld_le32(tp.data.data()), 123456u);
    EXPECT_EQ(c.download_value<std::int32_t>(obj::target_position.index, 0, 1).abort,
              protocol::SdoAbort::MappedToRxPdo);
    EXPECT_EQ(c.download_value<std::uint8_t>(0x1C12, 0, 0).abort, protocol::SdoAbort::WrongState);

    // A wrong SM2 length is refused at PREOP -> SAFEOP with 0x001D.
    ASSERT_TRUE(m.request_state(AlState::PreOp));
    std::uint8_t sm2[8] = {};
    ASSERT_EQ(m.fpwr(st, protocol::sm_addr(2), sm2).value_or(0), 1);  // disable, then configure 11 bytes
    st_le16(sm2, 0x1000);
    st_le16(sm2 + 2, 11);
    sm2[4] = 0x64;
    sm2[6] = 1;
    ASSERT_EQ(m.fpwr(st, protocol::sm_addr(2), sm2).value_or(0), 1);
    EXPECT_FALSE(m.request_state(AlState::SafeOp, std::chrono::milliseconds(300)));
    const auto r = m.read_al_status(st);
    EXPECT_EQ(r.state(), AlState::PreOp);
    EXPECT_TRUE(r.error());
    EXPECT_EQ(r.code, 0x001D);
    // The refusal is also reported by an emergency (0xA000, AL status code in the data).
    c.emergencies().clear();
    ASSERT_TRUE(c.upload(0x1001, 0).ok());
    ASSERT_FALSE(c.emergencies().empty());
    EXPECT_EQ(c.emergencies()[0].error_code, 0xA000);
    EXPECT_EQ(ld_le16(c.emergencies()[0].data.data()), 0x001D);
    EXPECT_EQ(vecat.stop(), 0);
    if (system("command -v tshark >/dev/null 2>&1") == 0) {
        EXPECT_EQ(test::run_capture("tshark -r " + pcap + " -V 2>/dev/null").find("Malformed"),
                  std::string::npos);
    }
    std::filesystem::remove(pcap);
}

// The real binary's drives move: the master enables two drives (6, 7, 15) and runs CSP with a ramp of
// set-points every millisecond of real time; both follow and stop at the last set-point.
TEST(VethDrive, TwoDrivesEnableAndFollowCyclicPositions) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    ++g_pair;
    const std::string mi = "dm" + std::to_string(g_pair), si = "ds" + std::to_string(g_pair);
    std::string why;
    ASSERT_TRUE(net::create_veth_pair(mi, si, &why)) << why;
    const std::string pcap =
        (std::filesystem::temp_directory_path() / ("vecat-drive-" + std::to_string(getpid()) + ".pcapng"))
            .string();
    VecatProcess vecat(si, 2, pcap);
    ASSERT_GT(vecat.pid, 0);
    net::RawSocket sock(mi);
    master::Master m(sock);
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    // Default mapping: controlword, mode, pad, target position, ... / statusword, mode display, pad,
    // position actual value, velocity actual value, torque, following error.
    auto next = std::chrono::steady_clock::now();
    auto cycle = [&](std::uint16_t cw, std::int32_t p0, std::int32_t p1) {
        for (std::size_t s = 0; s < 2; ++s) {
            auto o = m.outputs(s);
            st_le16(o.data(), cw);
            o[2] = 8;  // CSP
            st_le32(o.data() + 4, static_cast<std::uint32_t>(s == 0 ? p0 : p1));
        }
        const auto wkc = m.exchange_process_data();
        next += std::chrono::milliseconds(1);
        std::this_thread::sleep_until(next);
        return wkc.value_or(0) == m.expected_wkc();
    };
    auto sw = [&](std::size_t s) { return ld_le16(m.inputs(s).data()); };
    auto pos = [&](std::size_t s) { return static_cast<std::int32_t>(ld_le32(m.inputs(s).data() + 4)); };
    ASSERT_TRUE(cycle(0, 0, 0));
    const std::int32_t a0 = pos(0), b0 = pos(1);
    int misses = 0;
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}})
        for (int i = 0; i < 20; ++i)
            misses += !cycle(cw, a0, b0);
    EXPECT_EQ(cia::decode_state(sw(0)), cia::State::OperationEnabled) << std::hex << sw(0);
    EXPECT_EQ(cia::decode_state(sw(1)), cia::State::OperationEnabled) << std::hex << sw(1);
    // 1000 cycles: drive 0 ramps forward at 500000 units/s, drive 1 backward at 250000 units/s.
    for (int k = 1; k <= 1000; ++k)
        misses += !cycle(0x0F, a0 + 500 * k, b0 - 250 * k);
    for (int k = 0; k < 300; ++k)
        misses += !cycle(0x0F, a0 + 500'000, b0 - 250'000);
    EXPECT_EQ(misses, 0);
    // Settled within the position window 0x6067 (100) against Coulomb friction.
    EXPECT_NEAR(pos(0), a0 + 500'000, 100);
    EXPECT_NEAR(pos(1), b0 - 250'000, 100);
    EXPECT_TRUE(sw(0) & (1u << 12)) << "drive follows the command value";
    EXPECT_FALSE(sw(0) & (1u << 13)) << "no following error";
    for (int i = 0; i < 5; ++i)
        cycle(0x00, a0 + 500'000, b0 - 250'000);
    EXPECT_EQ(cia::decode_state(sw(0)), cia::State::SwitchOnDisabled);  // disable voltage: switch on disabled
    ASSERT_TRUE(m.request_state(AlState::Init));
    EXPECT_EQ(vecat.stop(), 0);
    std::filesystem::remove(pcap);
}

// Distributed clocks end to end: the project's master measures the delays, sets the offsets, compensates
// the static drift with FRMW bursts, waits for 0x092C, starts SYNC0 at 1 ms and runs 3 s in OP with the
// reference clock distributed in every cyclic frame. vecat runs with drifting clocks (--dc-drift-ppm).
TEST(VethDc, Sync0AtOneMillisecondInOpWithDriftingClocks) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    std::string why;
    ASSERT_TRUE(net::create_veth_pair("dcm", "dcs", &why)) << why;
    const std::string pcap =
        (std::filesystem::temp_directory_path() / ("vecat-dc-" + std::to_string(getpid()) + ".pcapng"))
            .string();
    VecatProcess vecat("dcs", 3, pcap, {"--dc-drift-ppm", "50"});
    ASSERT_GT(vecat.pid, 0);
    net::RawSocket sock("dcm");
    master::MasterOptions opt;
    opt.dc.enable = true;
    opt.dc.sync0_cycle_ns = 1'000'000;
    opt.dc.static_drift_frames = 1000;
    opt.dc.max_sync_diff_ns = 10'000;
    master::Master m(sock, opt);
    const auto t0 = std::chrono::steady_clock::now();
    // This machine is no real-time host (shared cores, builds running): vecat's serve loop often runs
    // frames later than they arrived, so a SYNC0 due in between is taken first and counted as an SM event
    // missed (see the report: frames should be processed at their kernel receive time). The sync error
    // counter limit 0x10F1:02 is set to 0 (no limit) here; the misses are still counted and printed.
    ASSERT_TRUE(m.startup(AlState::PreOp, &why)) << why;
    for (const auto& s : m.slaves()) {
        master::CoeClient c(m, s.station);
        ASSERT_TRUE(c.download_value(0x10F1, 2, std::uint16_t{0}).ok());
    }
    ASSERT_TRUE(m.startup(AlState::SafeOp, &why)) << why;
    ASSERT_NE(m.dc_reference(), 0);
    for (std::size_t i = 1; i < m.slaves().size(); ++i)
        // vecat's hop delay, measured on clocks drifting by 50 ppm and truncated to whole ns: +-1 ns.
        EXPECT_NEAR(static_cast<double>(m.slaves()[i].dc_delay_ns), m.slaves()[i - 1].dc_delay_ns + 500.0,
                    1.0)
            << i;
    // Cycles at 1 ms. Like SOEM's ec_sample, the master locks its own period to the reference clock so that
    // its frames arrive half a cycle after SYNC0 (frames too close to SYNC0 count as missed SM events).
    auto next = std::chrono::steady_clock::now();
    unsigned bad_wkc = 0;
    std::int64_t integral = 0, toff = 0;
    auto cycle = [&] {
        next += std::chrono::nanoseconds(1'000'000 + toff);
        std::this_thread::sleep_until(next);
        const bool ok = m.exchange_process_data().value_or(0) == m.expected_wkc();
        const std::int64_t err =
            static_cast<std::int64_t>((m.reference_time() + 500'000) % 1'000'000) - 500'000;
        integral += err;
        toff = -(err / 100 + integral / 50'000);  // SOEM ec_sample's gains: 0.01 and 0.00002
        return ok;
    };
    for (int c = 0; c < 500; ++c)  // SAFEOP: SYNC0 starts (100 ms after the start-up), the master locks on
        cycle();
    std::uint8_t op[2] = {static_cast<std::uint8_t>(AlState::Op), 0};
    ASSERT_TRUE(m.bwr(protocol::addr(protocol::Reg::AlControl), op));
    bool all_op = false;
    for (int c = 0; c < 1500 && !all_op; ++c) {
        cycle();
        if (c % 10 == 9) {
            all_op = true;
            for (const auto& s : m.slaves())
                all_op &= m.read_al_status(s.station).state() == AlState::Op;
        }
    }
    ASSERT_TRUE(all_op);
    std::printf("[ VethDc   ] start-up with DC to OP took %.2f s\n",
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    std::uint32_t worst_diff = 0;
    for (int c = 0; c < 3000; ++c) {
        if (!cycle()) ++bad_wkc;
        if (c % 100 == 99)
            if (auto d = m.max_system_time_difference()) worst_diff = std::max(worst_diff, *d);
    }
    EXPECT_LT(bad_wkc, 10u);
    std::printf("[ VethDc   ] 3 slaves, +-50 ppm: worst |0x092C| during 3 s in OP: %u ns\n", worst_diff);
    EXPECT_LT(worst_diff, 1000u);
    for (const auto& s : m.slaves()) {
        const auto st = m.read_al_status(s.station);
        EXPECT_EQ(st.state(), AlState::Op) << std::hex << st.code;
        master::CoeClient c(m, s.station);
        auto mode = c.upload(0x1C32, 1);
        ASSERT_TRUE(mode.ok());
        EXPECT_EQ(ld_le16(mode.data.data()), 2u);  // DC SYNC0
        auto missed = c.upload(0x1C32, 11);
        ASSERT_TRUE(missed.ok());
        std::printf(
            "[ VethDc   ] slave 0x%04X: 0x1C32:01 = %u, SM events missed %u, cycle time too small %u\n",
            s.station, ld_le16(mode.data.data()), ld_le16(missed.data.data()),
            ld_le16(c.upload(0x1C32, 12).data.data()));
        // SYNC0 runs: the next pulse (0x0990) is ahead of the system time, by at most one cycle. The three
        // registers come in three frames: the system time counts only when the next pulse read before and
        // after it is the same (no pulse fell between the frames, which a slow host makes likely).
        std::uint8_t b[8] = {};
        std::uint64_t next_pulse = 0, sys = 0;
        bool same = false;
        for (int attempt = 0; attempt < 20 && !same; ++attempt) {
            ASSERT_EQ(m.fprd(s.station, 0x0990, b).value_or(0), 1);
            next_pulse = ld_le64(b);
            ASSERT_EQ(m.fprd(s.station, 0x0910, b).value_or(0), 1);
            sys = ld_le64(b);
            ASSERT_EQ(m.fprd(s.station, 0x0990, b).value_or(0), 1);
            same = ld_le64(b) == next_pulse;
        }
        ASSERT_TRUE(same) << "a SYNC0 pulse fell between the frames 20 times";
        EXPECT_GT(next_pulse, sys);
        EXPECT_LE(next_pulse - sys, 1'000'000u);
    }
    ASSERT_TRUE(m.request_state(AlState::Init));
    EXPECT_EQ(vecat.stop(), 0);
    std::filesystem::remove(pcap);
}

TEST(VethCli, RefusesAnInterfaceWithAnAddress) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    std::string why;
    ASSERT_TRUE(net::create_veth_pair("ipm", "ips", &why)) << why;
    ASSERT_EQ(system("ip addr add 192.0.2.1/24 dev ips"), 0);  // documentation range, inside our namespace
    const std::string out =
        test::run_capture(std::string(VECAT_BINARY) + " run --iface ips 2>&1; echo rc=$?");
    EXPECT_NE(out.find("refusing"), std::string::npos) << out;
    EXPECT_NE(out.find("rc=2"), std::string::npos) << out;
}

// vecat run on an interface set up by `setup` (inside our namespace): refused with exit code 2, and served
// with --allow-used-interface.
void expect_refused(const std::string& iface, const std::string& setup, const std::string& reason) {
    std::string why;
    ASSERT_TRUE(net::create_veth_pair(iface + "m", iface, &why)) << why;
    ASSERT_EQ(system(setup.c_str()), 0) << setup;
    const std::string out =
        test::run_capture(std::string(VECAT_BINARY) + " run --iface " + iface + " 2>&1; echo rc=$?");
    EXPECT_NE(out.find("refusing"), std::string::npos) << out;
    EXPECT_NE(out.find(reason), std::string::npos) << out;
    EXPECT_NE(out.find("rc=2"), std::string::npos) << out;
    VecatProcess v(iface, 1, "/dev/null", {"--allow-used-interface"});
    EXPECT_EQ(kill(v.pid, 0), 0) << "--allow-used-interface: vecat should be serving";
    EXPECT_EQ(v.stop(), 0);
}

TEST(VethCli, RefusesTheDefaultRouteInterface) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    expect_refused("drs", "ip route add default dev drs", "default route");
}

TEST(VethCli, RefusesTheIpv6DefaultRouteInterface) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    expect_refused("d6s", "ip -6 route add default dev d6s", "IPv6 default route");
}

TEST(VethCli, RefusesABridgePort) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    expect_refused("brs", "ip link add vbr0 type bridge && ip link set brs master vbr0", "port of vbr0");
}

// Capability sets of a running vecat (/proc/PID/status): empty once the socket is open.
TEST(VethCli, ServesWithoutCapabilities) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    std::string why;
    ASSERT_TRUE(net::create_veth_pair("capm", "caps", &why)) << why;
    VecatProcess v("caps", 1, "/dev/null");
    std::ifstream f("/proc/" + std::to_string(v.pid) + "/status");
    std::map<std::string, std::string> st;
    for (std::string line; std::getline(f, line);) {
        const auto colon = line.find(':');
        if (colon == std::string::npos) continue;
        const auto value = line.find_first_not_of(" \t", colon + 1);
        st[line.substr(0, colon)] = value == std::string::npos ? "" : line.substr(value);
    }
    ASSERT_TRUE(st.count("CapEff")) << "no status of the vecat process";
    EXPECT_EQ(st["CapEff"], "0000000000000000");
    EXPECT_EQ(st["CapPrm"], "0000000000000000");
    EXPECT_EQ(st["CapInh"], "0000000000000000");
    EXPECT_EQ(st["CapAmb"], "0000000000000000");
    EXPECT_EQ(st["CapBnd"], "0000000000000000");
    EXPECT_EQ(st["NoNewPrivs"], "1");
    // Still serving: the master sees the slave.
    net::RawSocket sock("capm");
    master::Master m(sock);
    ASSERT_TRUE(m.startup(AlState::PreOp, &why)) << why;
    EXPECT_EQ(m.slaves().size(), 1u);
    EXPECT_EQ(v.stop(), 0);
}

int main(int argc, char** argv) {
    std::string why;
    g_netns = net::enter_private_netns(&why);
    if (!g_netns) std::fprintf(stderr, "veth tests skipped: %s\n", why.c_str());
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
