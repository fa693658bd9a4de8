#include "net/netns.hpp"

#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sched.h>
#include <spawn.h>
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
    return false;
}

}  // namespace vecat::net
