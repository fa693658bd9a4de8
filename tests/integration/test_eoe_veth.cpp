// EoE end to end: IP traffic from a master's network namespace through EoE to a vecat device and out of the
// device's Ethernet side. `vecat run --eoe-tap vdev` serves one drive on a veth pair; the test is the master
// (the project master over a raw socket) and bridges its own TAP interface to the device through its EoE
// client, as a master that routes IP through EoE does (IgH's eoeXsY interfaces, SOEM's eoe_test). The
// device's TAP is moved into a namespace of its own with an address behind the device. Then real ICMP echo
// (a raw socket, as ping) and a TCP connection (48 KiB each way) go from the master's namespace to the kernel
// behind the device, and a ping to the device's own address (set IP parameter) is answered by the device. The
// address filter, set by the master, is honoured on the way back. Needs root or unprivileged user namespaces
// (skipped otherwise), and ip, unshare and nsenter.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <fcntl.h>
#include <net/if.h>
#include <netinet/in.h>
#include <netinet/ip.h>
#include <netinet/ip_icmp.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "child_process.hpp"
#include "eoe/ip_responder.hpp"
#include "eoe/tap.hpp"
#include "master/eoe_client.hpp"
#include "master/master.hpp"
#include "net/netns.hpp"
#include "net/raw_socket.hpp"

using namespace vecat;
using protocol::AlState;

namespace {

bool g_netns = false;

std::string read_text(const std::string& p) {
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

bool sh(const std::string& cmd) {
    return std::system(("{ " + cmd + "; } >/dev/null 2>&1").c_str()) == 0;
}

// The MAC address of an interface of this namespace (sysfs shows the namespace it was mounted in).
std::optional<protocol::MacAddress> mac_of(const char* ifname) {
    const int s = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    ifreq ifr{};
    std::strncpy(ifr.ifr_name, ifname, IFNAMSIZ - 1);
    const bool ok = s >= 0 && ::ioctl(s, SIOCGIFHWADDR, &ifr) == 0;
    if (s >= 0) ::close(s);
    if (!ok) return std::nullopt;
    protocol::MacAddress m;
    std::copy_n(reinterpret_cast<const std::uint8_t*>(ifr.ifr_hwaddr.sa_data), m.size(), m.begin());
    return m;
}

// Sends ICMP echo requests to `to` from this namespace (a raw socket, as ping) until one is answered or the
// timeout passes.
bool ping(const char* to, std::uint16_t seq,
          std::chrono::milliseconds timeout = std::chrono::milliseconds(3000)) {
    const int s = ::socket(AF_INET, SOCK_RAW | SOCK_CLOEXEC, IPPROTO_ICMP);
    if (s < 0) return false;
    sockaddr_in dst{};
    dst.sin_family = AF_INET;
    ::inet_pton(AF_INET, to, &dst.sin_addr);
    constexpr std::uint16_t kId = 0x5EC4;
    std::uint8_t req[8 + 56] = {ICMP_ECHO,
                                0,
                                0,
                                0,
                                kId >> 8,
                                kId & 0xFF,
                                static_cast<std::uint8_t>(seq >> 8),
                                static_cast<std::uint8_t>(seq)};
    for (std::size_t i = 8; i < sizeof req; ++i)
        req[i] = static_cast<std::uint8_t>(i);
    const std::uint16_t c = eoe::internet_checksum(ConstBytes(req, sizeof req));
    req[2] = static_cast<std::uint8_t>(c >> 8);
    req[3] = static_cast<std::uint8_t>(c);
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    bool answered = false;
    while (!answered && std::chrono::steady_clock::now() < deadline) {
        ::sendto(s, req, sizeof req, 0, reinterpret_cast<sockaddr*>(&dst), sizeof dst);
        const auto until =
            std::min(deadline, std::chrono::steady_clock::now() + std::chrono::milliseconds(500));
        while (!answered && std::chrono::steady_clock::now() < until) {
            pollfd p{s, POLLIN, 0};
            if (::poll(&p, 1, 50) <= 0) continue;
            std::uint8_t buf[1500];
            sockaddr_in from{};
            socklen_t fl = sizeof from;
            const ssize_t n = ::recvfrom(s, buf, sizeof buf, 0, reinterpret_cast<sockaddr*>(&from), &fl);
            if (n < 28) continue;
            const std::size_t ihl = (buf[0] & 0x0F) * 4u;
            if (static_cast<std::size_t>(n) < ihl + 8) continue;
            const std::uint8_t* ic = buf + ihl;
            answered = from.sin_addr.s_addr == dst.sin_addr.s_addr && ic[0] == ICMP_ECHOREPLY &&
                       ((ic[4] << 8) | ic[5]) == kId && ((ic[6] << 8) | ic[7]) == seq;
        }
    }
    ::close(s);
    return answered;
}

// The master's side of the bridge: frames of its TAP go to the device through EoE, frames from the device
// into its TAP. The master is used by this thread alone while it runs.
struct Pump {
    Pump(master::EoeClient& c, eoe::Tap& t) : client(c), tap(t), th([this] { run(); }) {}
    ~Pump() {
        stop = true;
        th.join();
    }
    void run() {
        std::array<std::uint8_t, 2048> buf{};
        while (!stop) {
            for (int k = 0; k < 8; ++k) {
                const long n = tap.read(Bytes(buf.data(), buf.size()));
                if (n <= 0) break;
                if (client.send_frame(ConstBytes(buf.data(), static_cast<std::size_t>(n)))) ++to_device;
            }
            if (auto f = client.receive_frame(std::chrono::milliseconds(1))) {
                if (tap.write(*f)) ++from_device;
            }
        }
    }
    master::EoeClient& client;
    eoe::Tap& tap;
    std::atomic<bool> stop{false};
    std::atomic<std::uint64_t> to_device{0}, from_device{0};
    std::thread th;
};

}  // namespace

TEST(EoeVeth, PingAndTcpThroughTheDeviceToTheNetworkBehindIt) {
    if (!g_netns)
        GTEST_SKIP() << "needs root or unprivileged user namespaces for a private network namespace";
    if (!sh("command -v ip && command -v unshare && command -v nsenter"))
        GTEST_SKIP() << "needs ip, unshare and nsenter";
    std::string why;
    ASSERT_TRUE(net::loopback_up(&why)) << why;
    ASSERT_TRUE(net::create_veth_pair("eoem", "eoes", &why)) << why;
    const std::string log =
        (std::filesystem::temp_directory_path() / ("vecat-eoe-veth-" + std::to_string(getpid()) + ".log"))
            .string();
    test::ChildProcess vecat({VECAT_BINARY, "run", "--iface", "eoes", "--slaves", "1", "--eoe-tap", "vdev"},
                             log);
    ASSERT_GT(vecat.pid, 0);
    for (int i = 0; i < 100 && read_text(log).find("Ctrl-C stops") == std::string::npos; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ASSERT_NE(read_text(log).find("EoE Ethernet side of a device on TAP vdev0"), std::string::npos)
        << read_text(log);

    // The network behind the device: its TAP moved into a namespace of its own, 10.77.0.2/24.
    test::ChildProcess behind({"/usr/bin/unshare", "--net", "/bin/sleep", "120"});
    ASSERT_GT(behind.pid, 0);
    const std::string in_behind = "/usr/bin/nsenter -t " + std::to_string(behind.pid) + " -n ";
    bool moved = false;
    for (int i = 0; i < 50 && !moved; ++i) {  // unshare needs a moment to make its namespace
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        moved = sh("ip link set vdev0 netns " + std::to_string(behind.pid));
    }
    ASSERT_TRUE(moved);
    ASSERT_TRUE(sh(in_behind + "ip link set lo up"));
    ASSERT_TRUE(sh(in_behind + "ip addr add 10.77.0.2/24 dev vdev0"));
    ASSERT_TRUE(sh(in_behind + "ip link set vdev0 up"));

    // The master: PREOP, the device's IP parameters, its own TAP 10.77.0.1/24.
    net::RawSocket sock("eoem");
    master::Master m(sock);
    ASSERT_TRUE(m.startup(AlState::PreOp, &why)) << why;
    ASSERT_EQ(m.slaves().size(), 1u);
    ASSERT_TRUE(m.slaves()[0].sii.mailbox_protocols & 0x0002) << "the drive declares EoE";
    master::EoeClient client(m, m.slaves()[0].station);
    protocol::EoeIpParameters p;
    p.ip = *protocol::parse_ip4("10.77.0.5");
    p.subnet = *protocol::parse_ip4("255.255.255.0");
    const auto set = client.set_ip(p);
    ASSERT_TRUE(set.ok()) << "result " << set.result.value_or(0xFFFF);
    eoe::Tap mtap("mtap");
    ASSERT_TRUE(sh("ip addr add 10.77.0.1/24 dev mtap"));
    const auto mtap_mac = mac_of("mtap");
    ASSERT_TRUE(mtap_mac);

    // The listener behind the device: a thread that enters that namespace and echoes what it gets.
    std::atomic<bool> listening{false};
    std::string heard;
    std::thread server([&] {
        const int ns =
            ::open(("/proc/" + std::to_string(behind.pid) + "/ns/net").c_str(), O_RDONLY | O_CLOEXEC);
        if (ns < 0 || ::setns(ns, CLONE_NEWNET) != 0) return;
        ::close(ns);
        const int l = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_port = htons(7777);
        if (::bind(l, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(l, 1) != 0) return;
        listening = true;
        pollfd pf{l, POLLIN, 0};
        if (::poll(&pf, 1, 20000) <= 0) return ::close(l), void();
        const int c = ::accept(l, nullptr, nullptr);
        timeval tv{10, 0};
        ::setsockopt(c, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
        ::setsockopt(c, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
        char buf[4096];
        for (ssize_t n; (n = ::recv(c, buf, sizeof buf, 0)) > 0;)  // until the client shuts down its side
            heard.append(buf, static_cast<std::size_t>(n));
        const std::string reply = "echo: " + heard;
        for (std::size_t off = 0; off < reply.size();) {
            const ssize_t n = ::send(c, reply.data() + off, reply.size() - off, 0);
            if (n <= 0) break;
            off += static_cast<std::size_t>(n);
        }
        ::close(c);
        ::close(l);
    });
    for (int i = 0; i < 100 && !listening; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ASSERT_TRUE(listening);

    {
        Pump pump(client, mtap);
        // The kernel behind the device answers ARP and ICMP echo; the device answers for its own address.
        for (std::uint16_t seq = 1; seq <= 3; ++seq)
            EXPECT_TRUE(ping("10.77.0.2", seq)) << "ping 10.77.0.2 #" << seq;
        for (std::uint16_t seq = 1; seq <= 3; ++seq)
            EXPECT_TRUE(ping("10.77.0.5", seq)) << "ping 10.77.0.5 (the device) #" << seq;

        // TCP: connect, send 48 KiB (full-size segments: 1514-byte frames in 7 fragments each way), read
        // the echo.
        std::string hello = "hello over EoE ";
        for (int i = 0; i < 48 * 1024; ++i)
            hello.push_back(static_cast<char>('a' + i % 26));
        const int c = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_port = htons(7777);
        ::inet_pton(AF_INET, "10.77.0.2", &a.sin_addr);
        timeval tv{10, 0};
        ::setsockopt(c, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
        ::setsockopt(c, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
        ASSERT_EQ(::connect(c, reinterpret_cast<sockaddr*>(&a), sizeof a), 0) << std::strerror(errno);
        for (std::size_t off = 0; off < hello.size();) {
            const ssize_t n = ::send(c, hello.data() + off, hello.size() - off, 0);
            ASSERT_GT(n, 0) << std::strerror(errno);
            off += static_cast<std::size_t>(n);
        }
        ::shutdown(c, SHUT_WR);
        char buf[4096];
        std::string got;
        for (ssize_t n; (n = ::recv(c, buf, sizeof buf, 0)) > 0;)
            got.append(buf, static_cast<std::size_t>(n));
        ::close(c);
        EXPECT_EQ(got.size(), hello.size() + 6);
        EXPECT_TRUE(got == "echo: " + hello);
        EXPECT_GT(pump.to_device.load(), 30u);
        EXPECT_GT(pump.from_device.load(), 30u);
    }
    server.join();
    EXPECT_EQ(heard.substr(0, 15), "hello over EoE ");
    EXPECT_EQ(heard.size(), 15u + 48 * 1024);

    // The address filter on the way back: with only another address (and no broadcasts) the answers from
    // behind the device stay there; with the master's TAP address they come again.
    protocol::EoeAddressFilter f;
    f.count = 1;
    f.macs[0] = {0x02, 0xAA, 0xBB, 0xCC, 0xDD, 0xEE};
    f.no_broadcasts = true;
    ASSERT_TRUE(client.set_filter(f).ok());
    ASSERT_TRUE(sh("ip neigh flush dev mtap"));
    {
        Pump pump(client, mtap);
        EXPECT_FALSE(ping("10.77.0.2", 10, std::chrono::milliseconds(1500)));
    }
    f.macs[0] = *mtap_mac;
    ASSERT_TRUE(client.set_filter(f).ok());
    {
        Pump pump(client, mtap);
        EXPECT_TRUE(ping("10.77.0.2", 11));
    }
    EXPECT_EQ(vecat.stop(), 0) << read_text(log);
    std::filesystem::remove(log);
}

int main(int argc, char** argv) {
    std::string why;
    g_netns = net::enter_private_netns(&why);
    if (!g_netns) std::fprintf(stderr, "EoE veth test skipped: %s\n", why.c_str());
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
