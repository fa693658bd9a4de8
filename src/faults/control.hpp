// The control channel: a Unix stream socket on which `vecat fault ...` (or any client) sends one command
// line per connection ("inject KIND key=value...", "clear ID|KIND|all", "list") and reads the reply
// ("ok ..." or "error ...") until the server closes the connection.
#pragma once

#include <atomic>
#include <string>
#include <thread>

namespace vecat::faults {

class FaultInjector;

class ControlServer {
  public:
    // Listens on path (replacing a stale socket file); throws std::runtime_error when it cannot.
    ControlServer(std::string path, FaultInjector& injector);
    ~ControlServer();
    ControlServer(const ControlServer&) = delete;
    ControlServer& operator=(const ControlServer&) = delete;
    const std::string& path() const { return path_; }

    static constexpr std::size_t kMaxCommand = 4096;

  private:
    void serve();
    std::string path_;
    FaultInjector& injector_;
    int fd_ = -1;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

// Sends one command and returns the reply; false (and why) when the socket cannot be reached.
bool send_control_command(const std::string& path, const std::string& command, std::string& reply);

}  // namespace vecat::faults
