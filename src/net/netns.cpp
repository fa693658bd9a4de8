#include "net/netns.hpp"

#include <ifaddrs.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sched.h>
#include <spawn.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

extern char** environ;

namespace vecat::net {
namespace {

bool run(const std::vector<std::string>& args, std::string* why) {
    std::vector<char*> argv;
    for (const auto& a : args)
        argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    pid_t pid = 0;
    const int rc = posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ);
    if (rc != 0) {
        if (why) *why = "cannot run " + args[0] + ": " + std::strerror(rc);
        return false;
    }
    int status = 0;
    if (waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        if (why) {
            std::ostringstream s;
            for (const auto& a : args)
                s << a << ' ';
            *why = "command failed: " + s.str();
        }
        return false;
    }
    return true;
}

// The ifindex of the interface's master (bridge, bond), 0 if none: IFLA_MASTER of an RTM_GETLINK answer.
// Netlink rather than /sys/class/net, which shows the namespace sysfs was mounted in.
unsigned link_master(const std::string& ifname) {
    const unsigned index = if_nametoindex(ifname.c_str());
    if (index == 0) return 0;
    const int fd = ::socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE);
    if (fd < 0) return 0;
    struct {
        nlmsghdr nh;
        ifinfomsg ifi;
    } req{};
    req.nh.nlmsg_len = sizeof req;
    req.nh.nlmsg_type = RTM_GETLINK;
    req.nh.nlmsg_flags = NLM_F_REQUEST;
    req.ifi.ifi_family = AF_UNSPEC;
    req.ifi.ifi_index = static_cast<int>(index);
    unsigned master = 0;
    alignas(nlmsghdr) char buf[16384];
    if (::send(fd, &req, sizeof req, 0) == static_cast<ssize_t>(sizeof req)) {
        const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
        auto len = static_cast<unsigned>(n > 0 ? n : 0);
        for (auto* nh = reinterpret_cast<nlmsghdr*>(buf); NLMSG_OK(nh, len); nh = NLMSG_NEXT(nh, len)) {
            if (nh->nlmsg_type != RTM_NEWLINK) continue;
            auto* ifi = static_cast<ifinfomsg*>(NLMSG_DATA(nh));
            auto alen = static_cast<unsigned>(IFLA_PAYLOAD(nh));
            for (auto* a = IFLA_RTA(ifi); RTA_OK(a, alen); a = RTA_NEXT(a, alen))
                if (a->rta_type == IFLA_MASTER && RTA_PAYLOAD(a) >= sizeof(std::uint32_t))
                    std::memcpy(&master, RTA_DATA(a), sizeof master);
        }
    }
    ::close(fd);
    return master;
}

}  // namespace

namespace {

bool g_user_namespace = false;

std::string read_first_line(const char* path) {
    std::ifstream f(path);
    std::string line;
    std::getline(f, line);
    return line;
}

bool write_file(const std::string& path, const std::string& text, std::string* why) {
    std::ofstream f(path);
    f << text;
    f.flush();
    if (f) return true;
    if (why) *why = "cannot write " + path + ": " + std::strerror(errno);
    return false;
}

}  // namespace

std::string user_namespace_hint() {
    // Debian and Ubuntu kernels: kernel.unprivileged_userns_clone; every kernel: user.max_user_namespaces;
    // Ubuntu 23.10 and later: AppArmor restricts unprivileged user namespaces.
    if (read_first_line("/proc/sys/kernel/unprivileged_userns_clone") == "0")
        return "unprivileged user namespaces are turned off: sudo sysctl -w "
               "kernel.unprivileged_userns_clone=1";
    if (read_first_line("/proc/sys/user/max_user_namespaces") == "0")
        return "user namespaces are turned off: sudo sysctl -w user.max_user_namespaces=15000";
    if (read_first_line("/proc/sys/kernel/apparmor_restrict_unprivileged_userns") == "1")
        return "AppArmor restricts unprivileged user namespaces: sudo sysctl -w "
               "kernel.apparmor_restrict_unprivileged_userns=0 (or an AppArmor profile for vecat)";
    return "";
}

bool enter_private_netns(std::string* why) {
    if (::geteuid() == 0) {
        if (::unshare(CLONE_NEWNET) == 0) return true;
        if (why) *why = std::string("unshare(CLONE_NEWNET): ") + std::strerror(errno);
        return false;
    }
    // An ordinary user: a user namespace in which this process is root (uid and gid 0 mapped to its own),
    // then the network namespace, owned by that user namespace. The kernel needs a single-threaded caller.
    const uid_t uid = ::geteuid();
    const gid_t gid = ::getegid();
    if (::unshare(CLONE_NEWUSER | CLONE_NEWNET) != 0) {
        if (why) {
            *why = std::string("unshare(CLONE_NEWUSER | CLONE_NEWNET): ") + std::strerror(errno) +
                   " (an ordinary user needs unprivileged user namespaces; or run as root)";
            if (const auto hint = user_namespace_hint(); !hint.empty()) *why += "; " + hint;
        }
        return false;
    }
    // setgroups must be denied before an unprivileged process may write its gid_map (user_namespaces(7)).
    if (!write_file("/proc/self/setgroups", "deny", why) ||
        !write_file("/proc/self/uid_map", "0 " + std::to_string(uid) + " 1", why) ||
        !write_file("/proc/self/gid_map", "0 " + std::to_string(gid) + " 1", why))
        return false;
    g_user_namespace = true;
    return true;
}

bool in_private_user_namespace() {
    return g_user_namespace;
}

bool loopback_up(std::string* why) {
    return run({"ip", "link", "set", "dev", "lo", "up"}, why);
}

namespace {

// An interface is running once the kernel's link watch has seen its carrier (IFF_RUNNING) and given it its
// queueing discipline: a frame sent before that is dropped without an error.
bool running(int fd, const std::string& ifname) {
    ifreq ifr{};
    std::strncpy(ifr.ifr_name, ifname.c_str(), IFNAMSIZ - 1);
    return ::ioctl(fd, SIOCGIFFLAGS, &ifr) == 0 && (ifr.ifr_flags & IFF_RUNNING) != 0;
}

}  // namespace

bool create_veth_pair(const std::string& a, const std::string& b, std::string* why) {
    if (!run({"ip", "link", "add", "name", a, "type", "veth", "peer", "name", b}, why) ||
        !run({"ip", "link", "set", "dev", a, "up"}, why) || !run({"ip", "link", "set", "dev", b, "up"}, why))
        return false;
    const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return true;  // (nothing to ask the flags with: as before)
    bool up = false;
    for (int ms = 0; ms < 3000 && !up; ++ms) {
        up = running(fd, a) && running(fd, b);
        if (!up) ::usleep(1000);
    }
    ::close(fd);
    if (!up && why) *why = "veth pair " + a + "/" + b + ": no carrier 3 s after it was set up";
    return up;
}

bool interface_in_use(const std::string& ifname, std::string* why) {
    ifaddrs* list = nullptr;
    if (getifaddrs(&list) == 0) {
        for (ifaddrs* i = list; i; i = i->ifa_next) {
            if (!i->ifa_addr || ifname != i->ifa_name) continue;
            const int fam = i->ifa_addr->sa_family;
            if (fam == AF_INET || fam == AF_INET6) {
                // An IPv6 link-local address alone does not make an interface a production network.
                if (fam == AF_INET6) {
                    const auto* a6 = reinterpret_cast<const sockaddr_in6*>(i->ifa_addr);
                    if (IN6_IS_ADDR_LINKLOCAL(&a6->sin6_addr)) continue;
                }
                if (why) *why = ifname + " carries an IP address";
                freeifaddrs(list);
                return true;
            }
        }
        freeifaddrs(list);
    }
    // The default route's interface, IPv4 (/proc/net/route: destination 00000000) and IPv6
    // (/proc/net/ipv6_route: destination ::/0, interface in the last column).
    std::ifstream routes("/proc/net/route");
    std::string line;
    std::getline(routes, line);  // header
    while (std::getline(routes, line)) {
        std::istringstream s(line);
        std::string iface, dest;
        s >> iface >> dest;
        if (iface == ifname && dest == "00000000") {
            if (why) *why = ifname + " carries the default route";
            return true;
        }
    }
    std::ifstream routes6("/proc/net/ipv6_route");
    while (std::getline(routes6, line)) {
        std::istringstream s(line);
        std::vector<std::string> f;
        for (std::string w; s >> w;)
            f.push_back(w);
        if (f.size() == 10 && f[0] == std::string(32, '0') && f[1] == "00" && f[9] == ifname) {
            if (why) *why = ifname + " carries the IPv6 default route";
            return true;
        }
    }
    // A port of a bridge or bond: the network is the master's, which may carry addresses and routes.
    if (const unsigned m = link_master(ifname)) {
        char name[IF_NAMESIZE] = {};
        if (why) *why = ifname + " is a port of " + (if_indextoname(m, name) ? name : "another interface");
        return true;
    }
    return false;
}

}  // namespace vecat::net
