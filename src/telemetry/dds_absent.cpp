// The Publisher and Subscriber when vecat is built without Cyclone DDS: they refuse with kNotBuiltIn.
#include <stdexcept>

#include "telemetry/dds.hpp"

namespace vecat::telemetry {

bool dds_built_in() {
    return false;
}

struct Publisher::Impl {};
Publisher::Publisher(TelemetryQueue&, std::uint32_t) {
    throw std::runtime_error(kNotBuiltIn);
}
Publisher::~Publisher() = default;
void Publisher::start() {}
void Publisher::stop() {}
PublisherStats Publisher::stats() const {
    return {};
}

struct Subscriber::Impl {};
Subscriber::Subscriber(std::uint32_t) {
    throw std::runtime_error(kNotBuiltIn);
}
Subscriber::~Subscriber() = default;
void Subscriber::record(Recording&, double, const std::atomic<bool>&) {}

}  // namespace vecat::telemetry
