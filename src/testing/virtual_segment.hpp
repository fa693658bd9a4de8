// vecat::testing — a virtual EtherCAT segment for a user's own tests (GoogleTest or any other framework;
// nothing here needs GoogleTest).
//
// Two modes:
//
//  * VirtualSegment: in-process. N CiA 402 drives (optionally two coupled by TWINsync) behind an
//    in-process link, the fault injector in between, and the project's master on the other end, brought
//    to OP. Time is simulated: it moves only by advance() and cycle(), so a test is fast and repeatable.
//
//        vecat::testing::VirtualSegment vs({.drives = 2});   // throws std::runtime_error if start-up fails
//        vs.set_controlword(0, 0x06); vs.cycles(5);          // default CSP mapping (RxPDO 0x1600)
//        vs.fault("inject link_down slave=0 port=1");        // the text commands of `vecat fault`
//        vs.start_recording();  vs.cycles(100);  auto rec = vs.stop_recording();   // telemetry
//
//  * VethSegment: the same drives served on one end of a veth pair inside a private network namespace
//    (the whole process moves there: create it before starting threads), in real time, so that a user's
//    own master (SOEM, IgH's userspace tools, ethercrab...) opens master_interface() and talks to it.
//    Faults through fault() as well. Needs root (CAP_NET_ADMIN, CAP_SYS_ADMIN).
//
// Both tear down in their destructors (the serving thread stops; the namespace dies with the process).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <thread>

#include "cia402/drive.hpp"
#include "device/device_description.hpp"
#include "esc/segment.hpp"
#include "faults/injector.hpp"
#include "faults/twinsync_faults.hpp"
#include "master/master.hpp"
#include "serve/in_process_link.hpp"
#include "telemetry/recording.hpp"
#include "telemetry/sampler.hpp"

namespace vecat::testing {

struct SegmentOptions {
    std::size_t drives = 1;
    // Drives 1 and 2 coupled by a TWINsync cable with this preset (needs drives >= 2).
    cia402::TwinsyncPreset twinsync = cia402::TwinsyncPreset::None;
    device::DeviceDescription device = device::default_drive();
    esc::EscConfig esc{};
    // VirtualSegment only: the AL state the master brings the line to (Init: no start-up at all).
    protocol::AlState target = protocol::AlState::Op;
    std::uint64_t cycle_ns = 1'000'000;           // one cycle() of process data
    std::int64_t master_reply_timeout_us = 2000;  // a lost frame costs this much (simulated time is not used)
    std::uint64_t fault_seed = 1;                 // of the fault probabilities
};

// CSP process data of the default mapping (RxPDO 0x1600 / TxPDO 0x1A00), byte offsets in each slave's image.
namespace csp {
inline constexpr std::size_t kControlword = 0, kMode = 2, kTargetPosition = 4, kTargetVelocity = 8;
inline constexpr std::size_t kStatusword = 0, kModeDisplay = 2, kPositionActual = 4, kVelocityActual = 8;
}  // namespace csp

class VirtualSegment {
  public:
    explicit VirtualSegment(SegmentOptions opt = {});
    ~VirtualSegment();
    VirtualSegment(const VirtualSegment&) = delete;
    VirtualSegment& operator=(const VirtualSegment&) = delete;

    // ---- The parts, for anything the helpers below do not cover.
    esc::Segment& segment() { return *seg_; }
    master::Master& master() { return master_; }
    net::InProcessLink& link() { return link_; }
    faults::FaultInjector& injector() { return injector_; }
    cia402::Drive& drive(std::size_t i);
    coe::ObjectDictionary& dictionary(std::size_t i) { return drive(i).dictionary(); }
    std::size_t size() const { return seg_->size(); }
    std::uint16_t station(std::size_t i) const { return static_cast<std::uint16_t>(0x1001 + i); }

    // ---- Simulated time
    std::uint64_t now_ns() const { return now_; }
    // Time passes without frames (firmware, watchdogs, TWINsync, timed faults tick).
    void advance(std::uint64_t ns);
    // One process data cycle: the LRW (and DC FRMW) frame, the sampler if recording, then cycle_ns passes.
    // True when the working counter is the expected one.
    bool cycle();
    // n cycles; true when every working counter was right.
    bool cycles(unsigned n);
    std::uint16_t last_wkc() const { return last_wkc_; }

    // ---- Process data of slave i (default CSP mapping; outputs are sent with the next cycle()).
    void set_controlword(std::size_t i, std::uint16_t cw);
    void set_mode(std::size_t i, std::int8_t mode);
    void set_target_position(std::size_t i, std::int32_t p);
    std::uint16_t statusword(std::size_t i) const;
    std::int32_t position(std::size_t i) const;
    std::int32_t velocity(std::size_t i) const;
    // Controlword 6, 7, 15 in CSP holding the current position until the drive reports Operation enabled
    // (or max_cycles pass). True when it did.
    bool enable(std::size_t i, unsigned max_cycles = 50);

    // ---- Faults: the commands of `vecat fault` ("inject KIND key=value...", "clear ID|KIND|all", "list").
    // Returns "ok ..." or "error ...".
    std::string fault(std::string_view command);

    // ---- Telemetry in-process (no DDS): the sampler runs after each cycle() while recording.
    void start_recording(telemetry::SamplerOptions opt = {});
    telemetry::Recording stop_recording();
    bool recording() const { return sampler_ != nullptr; }

  private:
    void drain();
    SegmentOptions opt_;
    std::unique_ptr<esc::Segment> seg_;
    net::InProcessLink link_;
    faults::FaultInjector injector_;
    faults::TwinsyncFaults twinsync_faults_;
    master::Master master_;
    std::uint64_t now_ = 1'000'000'000;
    std::uint16_t last_wkc_ = 0;
    std::unique_ptr<telemetry::TelemetryQueue> queue_;
    std::unique_ptr<telemetry::Sampler> sampler_;
    telemetry::Recording rec_;
};

struct VethOptions {
    SegmentOptions segment;
    std::string master_interface = "vecat-m";  // the end the user's master opens
    std::string slave_interface = "vecat-s";   // the end the segment serves
    bool enter_netns = true;  // move this process into a private network namespace first (recommended)
    bool busy_poll = false;
};

class VethSegment {
  public:
    // Throws std::runtime_error with the reason when the namespace or the veth pair cannot be made.
    explicit VethSegment(VethOptions opt = {});
    ~VethSegment();
    VethSegment(const VethSegment&) = delete;
    VethSegment& operator=(const VethSegment&) = delete;

    const std::string& master_interface() const { return opt_.master_interface; }
    esc::Segment& segment() { return *seg_; }
    // Fault commands as in VirtualSegment, run by the serving thread at its next frame or tick.
    std::string fault(const std::string& command);
    std::uint64_t frames_received() const { return received_.load(); }
    // Stops the serving thread (the destructor does it as well).
    void stop();

  private:
    VethOptions opt_;
    std::unique_ptr<esc::Segment> seg_;
    std::unique_ptr<faults::FaultInjector> injector_;
    std::unique_ptr<faults::TwinsyncFaults> twinsync_faults_;
    std::atomic<bool> stop_{false};
    std::atomic<std::uint64_t> received_{0};
    std::thread thread_;
};

// Returns true when this process may create network namespaces (root); tests skip the veth mode otherwise.
bool veth_available();

}  // namespace vecat::testing
