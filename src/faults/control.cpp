#include "faults/control.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>

#include "faults/injector.hpp"

namespace vecat::faults {
namespace {

sockaddr_un address_of(const std::string& path) {
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    if (path.size() >= sizeof(a.sun_path)) throw std::runtime_error("socket path too long: " + path);
    std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
    return a;
}

// Reads until a newline, EOF, the size limit or the timeout.
std::string read_some(int fd, std::size_t limit, int timeout_ms, bool until_newline) {
    std::string s;
    char buf[512];
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (s.size() < limit) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        if (left.count() <= 0) break;
        pollfd p{fd, POLLIN, 0};
        if (poll(&p, 1, static_cast<int>(left.count())) <= 0) break;
        const ssize_t n = read(fd, buf, sizeof buf);
        if (n <= 0) break;
        s.append(buf, static_cast<std::size_t>(n));
        if (until_newline && s.find('\n') != std::string::npos) break;
    }
    return s;
}

void write_all(int fd, const std::string& s) {
    std::size_t off = 0;
    while (off < s.size()) {
        const ssize_t n = write(fd, s.data() + off, s.size() - off);
        if (n <= 0) return;
        off += static_cast<std::size_t>(n);
    }
}

}  // namespace

ControlServer::ControlServer(std::string path, FaultInjector& injector)
    : path_(std::move(path)), injector_(injector) {
    const sockaddr_un a = address_of(path_);
    fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
    unlink(path_.c_str());  // a socket left by an earlier run
    if (bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0 || listen(fd_, 4) != 0) {
        const std::string why = std::strerror(errno);
        close(fd_);
        throw std::runtime_error("cannot listen on " + path_ + ": " + why);
    }
    thread_ = std::thread([this] { serve(); });
}

ControlServer::~ControlServer() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    close(fd_);
    unlink(path_.c_str());
}

void ControlServer::serve() {
    while (!stop_) {
        pollfd p{fd_, POLLIN, 0};
        if (poll(&p, 1, 100) <= 0) continue;
        const int c = accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC);
        if (c < 0) continue;
        // One bounded command per connection.
        std::string line = read_some(c, kMaxCommand, 1000, true);
        if (const auto nl = line.find('\n'); nl != std::string::npos) line.resize(nl);
        const std::string reply =
            line.empty() ? "error empty command" : injector_.submit(line, std::chrono::milliseconds(2000));
        write_all(c, reply + "\n");
        close(c);
    }
}

bool send_control_command(const std::string& path, const std::string& command, std::string& reply) {
    sockaddr_un a{};
    try {
        a = address_of(path);
    } catch (const std::exception& e) {
        reply = e.what();
        return false;
    }
    const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        reply = std::strerror(errno);
        return false;
    }
    if (connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
        reply = "cannot connect to " + path + ": " + std::strerror(errno);
        close(fd);
        return false;
    }
    write_all(fd, command + "\n");
    reply = read_some(fd, 1 << 20, 5000, false);
    close(fd);
    while (!reply.empty() && reply.back() == '\n')
        reply.pop_back();
    return true;
}

}  // namespace vecat::faults
