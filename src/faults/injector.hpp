// The fault injector: stands between the transport and the segment (net::FrameFilter) and in each slave's
// mailbox (esc::MailboxInterceptor), starts and stops faults by hand, from a scenario's timeline or from
// the control channel, and makes each fault look to the master as the real one would.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "esc/segment.hpp"
#include "faults/fault.hpp"
#include "faults/scenario.hpp"
#include "net/frame_filter.hpp"

namespace vecat::faults {

// A fault the injector does not model itself, served by the part of vecat that owns the behaviour (the
// TWINsync port: twinsync_cable_break, twinsync_crc_errors, twinsync_sync_loss). Register it with
// FaultInjector::register_handler under the fault's kind name. Both calls come from the serving thread.
class FaultHandler {
  public:
    virtual ~FaultHandler() = default;
    // Starts the fault (f.slave, f.probability, f.count and every key in f.params); throw
    // std::invalid_argument to refuse it.
    virtual void start(const FaultSpec& f, std::uint64_t now_ns) = 0;
    // Ends it (stop command, duration over, or the injector going away).
    virtual void stop(const FaultSpec& f, std::uint64_t now_ns) = 0;
};

struct InjectorCounters {
    std::uint64_t frames = 0;
    std::uint64_t frames_dropped = 0;
    std::uint64_t frames_corrupted = 0;
    std::uint64_t replies_delayed = 0;
    std::uint64_t delayed_overflow = 0;  // more replies held back than slots: dropped
    std::uint64_t sdo_aborts = 0;
    std::uint64_t mailbox_replies_lost = 0;
    std::uint64_t faults_started = 0;
    std::uint64_t faults_ended = 0;
};

class FaultInjector final : public net::FrameFilter, public esc::MailboxInterceptor {
  public:
    explicit FaultInjector(esc::Segment& seg, std::uint64_t seed = 1);
    ~FaultInjector() override;
    FaultInjector(const FaultInjector&) = delete;
    FaultInjector& operator=(const FaultInjector&) = delete;

    void register_handler(const std::string& kind, FaultHandler& h);
    // Takes a timeline; its times count from the first frame (or idle tick) after this call.
    void load(const Scenario& s);

    // Starts a fault now; returns its id. Throws std::invalid_argument when it cannot be started.
    std::string start(FaultSpec f, std::uint64_t now_ns);
    // Ends the faults with this id or kind name, or "all"; returns how many.
    std::size_t stop(std::string_view which, std::uint64_t now_ns);
    // The active faults, one line each (id, kind, parameters).
    std::vector<std::string> active() const;
    const InjectorCounters& counters() const { return counters_; }
    // Called with a line for each fault started or ended and each timeline error.
    std::function<void(const std::string&)> on_event;

    // A control command, in the serving thread: "inject KIND key=value...", "clear ID|KIND|all", "list".
    // Returns "ok ..." or "error ...".
    std::string execute(std::string_view command, std::uint64_t now_ns);
    // The same from another thread (the control channel): runs at the next frame or tick of the serving
    // thread and waits for the result at most timeout.
    std::string submit(const std::string& command, std::chrono::milliseconds timeout);

    // net::FrameFilter
    bool process_frame(Bytes frame, std::size_t& len, std::uint64_t now_ns) override;
    // Cable redundancy. A reply held back by a delay fault leaves through the primary port (take_due).
    bool process_frame_at(Bytes frame, std::size_t& len, std::uint64_t now_ns, unsigned from_port,
                          unsigned& to_port) override;
    void tick(std::uint64_t now_ns) override;
    std::size_t take_due(std::uint64_t now_ns, Bytes out) override;
    std::uint64_t next_due_ns() const override;
    std::uint64_t next_event_ns() const override;

    // esc::MailboxInterceptor
    bool intercept(esc::Slave& slave, const protocol::MailboxHeader& h, ConstBytes payload,
                   esc::MailboxProtocol* protocol, esc::MailboxReplySink& sink) override;

    static constexpr std::size_t kHeldReplies = 64;  // replies a delay fault can hold at once
    static constexpr std::size_t kMaxFrame = 1600;

  private:
    struct Active {
        FaultSpec spec;
        std::uint64_t started_ns = 0;
        std::uint64_t until_ns = 0;  // 0: until stopped
        std::uint64_t hits = 0;
        bool done = false;  // count reached: ends at the next check
        FaultHandler* handler = nullptr;
        double saved_ppm = 0.0;
    };
    struct Held {
        bool used = false;
        std::uint64_t due_ns = 0;
        std::size_t len = 0;
    };
    struct Request {
        std::string command;
        std::string result;
        bool done = false;
    };

    void advance(std::uint64_t now_ns);
    void drain_requests(std::uint64_t now_ns);
    void end(Active& a, std::uint64_t now_ns, const char* why);
    void apply_line_state();
    // The slaves moved (a hot connect group plugged back elsewhere; order[new] = old): the faults follow
    // them.
    void follow_slaves(const std::vector<std::size_t>& order);
    void set_drive_fault(std::size_t slave, std::uint16_t code);
    bool roll(double p);
    bool hit(Active& a);
    void note(const std::string& s);
    std::size_t slave_index(const esc::Slave& s) const;

    esc::Segment& seg_;
    std::mt19937_64 rng_;
    std::uniform_real_distribution<double> uniform_{0.0, 1.0};
    std::vector<std::unique_ptr<Active>> active_;
    std::map<std::string, FaultHandler*> handlers_;
    std::uint64_t next_id_ = 1;
    // Timeline.
    Scenario scenario_;
    std::vector<bool> fired_;
    bool origin_set_ = false;
    std::uint64_t origin_ns_ = 0;
    std::uint64_t frames_seen_ = 0;
    // Held-back replies (delay), allocated once.
    std::vector<Held> held_;
    std::vector<std::uint8_t> held_data_;
    // Control channel.
    std::mutex mutex_;
    std::condition_variable cv_;
    std::vector<std::shared_ptr<Request>> requests_;
    std::atomic<bool> requests_pending_{false};
    InjectorCounters counters_;
};

}  // namespace vecat::faults
