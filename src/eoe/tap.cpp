#include "eoe/tap.hpp"

#include <fcntl.h>
#include <linux/if_tun.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace vecat::eoe {

namespace {

std::string errno_text(const char* what, const std::string& name) {
    return std::string(what) + " " + name + ": " + std::strerror(errno);
}

// Sets IFF_UP on the interface (through an ordinary socket, as `ip link set NAME up`).
bool bring_up(const std::string& name) {
    const int s = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (s < 0) return false;
    ifreq ifr{};
    std::strncpy(ifr.ifr_name, name.c_str(), IFNAMSIZ - 1);
    bool ok = ::ioctl(s, SIOCGIFFLAGS, &ifr) == 0;
    if (ok) {
        ifr.ifr_flags = static_cast<short>(ifr.ifr_flags | IFF_UP);
        ok = ::ioctl(s, SIOCSIFFLAGS, &ifr) == 0;
    }
    ::close(s);
    return ok;
}

}  // namespace

Tap::Tap(const std::string& name) : name_(name) {
    if (name.empty() || name.size() >= IFNAMSIZ)
        throw std::runtime_error("TAP interface name \"" + name + "\": 1 to 15 characters");
    fd_ = ::open("/dev/net/tun", O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) throw std::runtime_error(errno_text("cannot open /dev/net/tun for", name));
    ifreq ifr{};
    ifr.ifr_flags = IFF_TAP | IFF_NO_PI;
    std::strncpy(ifr.ifr_name, name.c_str(), IFNAMSIZ - 1);
    if (::ioctl(fd_, TUNSETIFF, &ifr) != 0) {
        const std::string why = errno_text("cannot create TAP interface", name) +
                                (errno == EPERM ? " (needs CAP_NET_ADMIN: root or vecat exec)" : "");
        ::close(fd_);
        throw std::runtime_error(why);
    }
    if (!bring_up(name)) {
        const std::string why = errno_text("cannot bring up TAP interface", name);
        ::close(fd_);
        throw std::runtime_error(why);
    }
}

Tap::~Tap() {
    if (fd_ >= 0) ::close(fd_);
}

long Tap::read(Bytes buf) {
    const ssize_t n = ::read(fd_, buf.data(), buf.size());
    if (n >= 0) return static_cast<long>(n);
    return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR ? 0 : -1;
}

bool Tap::write(ConstBytes frame) {
    return ::write(fd_, frame.data(), frame.size()) == static_cast<ssize_t>(frame.size());
}

}  // namespace vecat::eoe
