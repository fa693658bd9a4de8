#include "net/netns.hpp"

#include <ifaddrs.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sched.h>
#include <spawn.h>
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

bool enter_private_netns(std::string* why) {
    if (::unshare(CLONE_NEWNET) != 0) {
        if (why) *why = std::string("unshare(CLONE_NEWNET): ") + std::strerror(errno) + " (needs root)";
        return false;
    }
    return true;
}

bool create_veth_pair(const std::string& a, const std::string& b, std::string* why) {
    return run({"ip", "link", "add", "name", a, "type", "veth", "peer", "name", b}, why) &&
           run({"ip", "link", "set", "dev", a, "up"}, why) && run({"ip", "link", "set", "dev", b, "up"}, why);
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
