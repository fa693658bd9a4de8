#include "eoe/eoe_bridge.hpp"

namespace vecat::eoe {

namespace {
// Frames taken from one TAP per service() call: the serve loop gets back to its socket soon; the rest waits
// in the kernel's queue for the next call.
constexpr int kFramesPerService = 16;
}  // namespace

EoeBridge::EoeBridge(esc::Segment& seg, const std::string& prefix) {
    for (std::size_t i = 0; i < seg.size(); ++i) {
        EoeServer* s = eoe_server(seg.slave(i));
        if (!s) continue;
        auto p = std::make_unique<Port>();
        p->tap = std::make_unique<Tap>(prefix + std::to_string(i));
        p->server = s;
        s->attach(p.get());
        fds_.push_back(p->tap->fd());
        ports_.push_back(std::move(p));
    }
}

EoeBridge::~EoeBridge() {
    for (auto& p : ports_)
        p->server->attach(nullptr);
}

void EoeBridge::service(std::uint64_t) {
    for (auto& p : ports_) {
        for (int k = 0; k < kFramesPerService; ++k) {
            const long n = p->tap->read(Bytes(buf_.data(), buf_.size()));
            if (n <= 0) break;
            p->server->from_ethernet(ConstBytes(buf_.data(), static_cast<std::size_t>(n)));
        }
    }
}

std::uint64_t EoeBridge::write_errors() const {
    std::uint64_t n = 0;
    for (const auto& p : ports_)
        n += p->write_errors;
    return n;
}

}  // namespace vecat::eoe
