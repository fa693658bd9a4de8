// Telemetry over Cyclone DDS: the publisher (a thread that empties the sampler's queue into DDS writers)
// and the subscriber (readers for `vecat scope`). The interface has no DDS types, so that the program
// builds without Cyclone DDS; then dds_built_in() is false and both refuse with kNotBuiltIn.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "telemetry/recording.hpp"
#include "telemetry/sampler.hpp"

namespace vecat::telemetry {

bool dds_built_in();
inline constexpr const char* kNotBuiltIn =
    "telemetry is not built in: Cyclone DDS (Debian packages cyclonedds-dev and cyclonedds-tools) was not "
    "found when vecat was configured, or -DVECAT_TELEMETRY=OFF was given";

// Topic names (documented in src/telemetry/README.md).
inline constexpr const char* kAxisTopic = "vecat_axis";
inline constexpr const char* kStatusTopic = "vecat_slave_status";
inline constexpr const char* kTwinsyncTopic = "vecat_twinsync";
inline constexpr const char* kEventTopic = "vecat_event";
inline constexpr const char* kIoTopic = "vecat_io";

struct PublisherStats {
    std::uint64_t written = 0;  // records written to DDS
    std::uint64_t write_errors = 0;
};

class Publisher {
  public:
    // Creates the participant and writers in the domain (throws std::runtime_error on failure).
    Publisher(TelemetryQueue& q, std::uint32_t domain);
    ~Publisher();  // stops the thread after emptying the queue
    void start();
    void stop();
    PublisherStats stats() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

class Subscriber {
  public:
    Subscriber(std::uint32_t domain);  // throws std::runtime_error on failure
    ~Subscriber();
    // Takes what arrives into r until stop is true or duration_s passed (0: no limit).
    void record(Recording& r, double duration_s, const std::atomic<bool>& stop);

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace vecat::telemetry
