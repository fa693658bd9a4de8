// A segment: N slaves on one line in one process. A frame passes through them in order, each slave
// seeing it as its predecessor left it, then returns to the master (open line: the last slave closes
// the loop on its port 1).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/bytes.hpp"
#include "esc/address_index.hpp"
#include "esc/slave.hpp"
#include "protocol/frame.hpp"

namespace vecat::esc {

class FirmwareThreads;

struct SegmentCounters {
    std::uint64_t frames = 0;
    std::uint64_t replies = 0;
    std::uint64_t dropped = 0;        // malformed EtherCAT frames
    std::uint64_t ignored = 0;        // not EtherCAT
    std::uint64_t lost = 0;           // lost or corrupted on the line, or no link at the master's cable
    std::uint64_t onward = 0;         // passed on to the downstream segment (chained segments)
    std::uint64_t returned = 0;       // came back from the downstream segment, forwarded to the master
    std::uint64_t firmware_runs = 0;  // runs of one slave's firmware (Segment::run), for any reason
    // Frames processed while the firmware of frames before them stayed deferred (set_deferred_firmware)
    std::uint64_t past_deferred_firmware = 0;
    // ... of them, frames whose datagrams the ESCs processed while that firmware ran on the firmware
    // threads (Segment::start_deferred_firmware)
    std::uint64_t beside_firmware = 0;
    // Batches of runs handed to the firmware threads that way, and the frames whose firmware they ran (a
    // batch takes all the frames deferred while the batch before it ran)
    std::uint64_t background_batches = 0;
    std::uint64_t background_frames = 0;
};

// Damage a frame suffers on one cable of the line (fault injection). Cable k joins the master (k == 0) or
// slave k-1's port 1 to slave k's port 0; outbound frames cross it towards slave k, returning ones towards
// the master.
struct FrameDamage {
    enum class Kind : std::uint8_t { None, Lost, Corrupted };
    Kind kind = Kind::None;
    std::size_t cable = 0;
    bool returning = false;
};

// The master's ports (cable redundancy): the primary one feeds port 0 of slave 0, the secondary one (if the
// line is cabled back, Segment::set_redundancy) the port named there.
enum class MasterPort : std::uint8_t { Primary = 0, Secondary = 1 };

// Makes the application of one slave (the CoE stack and drive, or a bare process image).
using ApplicationFactory = std::function<std::unique_ptr<Application>(const device::DeviceDescription&)>;

class Segment {
  public:
    Segment() = default;
    ~Segment();  // (waits for firmware runs on the workers, start_deferred_firmware)
    // The ESCs count their port changes into the segment (port_epoch_): it stays where it was made.
    Segment(const Segment&) = delete;
    Segment& operator=(const Segment&) = delete;
    void add(std::unique_ptr<Slave> s);
    // A slave with its own application factory (a network of mixed devices): restart_slave() rebuilds it
    // with this one instead of the segment's.
    void add(std::unique_ptr<Slave> s, ApplicationFactory own);
    std::size_t size() const { return slaves_.size(); }
    Slave& slave(std::size_t i) { return *slaves_[i]; }
    const Slave& slave(std::size_t i) const { return *slaves_[i]; }

    // Processes a received frame in place. frame must have room for at least kMinEthFrame bytes; len is
    // updated (padding to 60 bytes). Returns true when a reply must be sent.
    bool process_frame(Bytes frame, std::size_t& len, std::uint64_t now_ns);
    // The same with damage on the line: the slaves before the damage process the frame, a corrupted frame
    // is counted in the error counters (0x0300-0x030C) of the ESCs that see it, and no reply comes back.
    bool process_frame(Bytes frame, std::size_t& len, std::uint64_t now_ns, const FrameDamage& damage);
    // The same for a frame the master sent out of one of its ports (cable redundancy). When it returns
    // true, reply_port() tells which master port the frame arrives at.
    bool process_frame(Bytes frame, std::size_t& len, std::uint64_t now_ns, const FrameDamage& damage,
                       MasterPort from);
    MasterPort reply_port() const { return reply_port_; }
    // Runs the slaves' firmware and watchdogs without a frame.
    void tick(std::uint64_t now_ns);
    // A part of a tick, for a server that must not keep a frame waiting behind a long one (on a large line a
    // tick of every slave takes hundreds of microseconds): the firmware of deferred frames, the slaves whose
    // deadlines are due, and `count` slaves from slave `first` on (wrapping around). A tick only saves the
    // catch-up of the slaves' own cycles before a later frame (see set_local_cycle_ns), so a server may stop
    // between parts when a frame comes; the slaves it did not reach catch up before a frame reads them.
    void tick_part(std::uint64_t now_ns, std::size_t first, std::size_t count);

    // Firmware after the reply. By default process_frame() runs the firmware of the slaves the frame
    // addressed before it returns. A server that sends the reply first sets this and calls
    // run_deferred_firmware() after sending: the frame's round trip then holds the ESCs' work only, as on
    // a real line, where the firmware runs beside the wire. A master cannot tell the difference: what the
    // firmware does after a frame (process data exchange, mailbox replies, AL state changes) shows in the
    // next frame either way. Firmware still due runs before the next frame or tick.
    void set_deferred_firmware(bool on) { defer_firmware_ = on; }
    bool deferred_firmware() const { return defer_firmware_; }
    void run_deferred_firmware();
    // A server that finds the next frame already waiting when it has sent a reply may answer it before it
    // runs the deferred firmware (a cycle's frames come back to back, its firmware runs once they are
    // answered): the next frame leaves the firmware of the frames before it deferred when it cannot see what
    // that firmware does, and runs it first otherwise. It cannot see it when its datagrams concern none of
    // those slaves nor any slave that shares state with one of them, no deadline is due at its time and no
    // deferred frame marked a drive coupled to another (keep_deferred, Segment::process_datagrams: the
    // coupled drives' SYNC pulses are handed out before every frame). Each frame's firmware runs at the
    // frame's time, in the frames' order, as if it had run after each frame: the replies are the same.
    bool firmware_deferred() const { return deferred_count_ != 0; }
    static constexpr std::size_t kMaxDeferredFrames = 32;
    // On several firmware threads (set_firmware_threads) such a server may also hand the deferred firmware
    // to the workers when it has sent a reply, and go on beside them: to look for the next frame and answer
    // it. The deferred frames' runs start on the workers (FirmwareThreads::start), each slave at its frame's
    // time as run_deferred_firmware would run it, and the segment waits for them (FirmwareThreads::join)
    // where it would have run them: before a frame that may see what they do, before any other batch of runs
    // (a frame's catch-ups), in run_deferred_firmware, tick and tick_part, and before a change of the slaves
    // or their cabling. A frame that goes on beside them touches none of their slaves nor anything they write
    // (the rule of keep_deferred above: no deadline due, other groups only). While the workers are still at
    // a batch, this returns at once and the frames since stay deferred; the next call once the batch is done
    // hands them over together. Until one of process_frame, run_deferred_firmware, tick, tick_part or this
    // the caller must call nothing else on the segment or its slaves. Starts nothing unless the deferred
    // frames marked kMinParallelRuns slaves or more and nothing else is due at their times; the runs then
    // stay deferred as before.
    void start_deferred_firmware();
    // Host time of the next SYNC pulse of any slave (DistributedClock::kNever if none).
    std::uint64_t next_event_ns() const;

    // ---- Firmware when it is needed. A slave's firmware has three kinds of work: what a frame asked for
    // (it runs after the frame, above), its own cycle (a drive's servo periods, inputs that follow a
    // signal), and deadlines (the process data watchdog, SYNC pulses piling up, the application's
    // timeouts). Its own cycle needs no run of its own: every run catches up with the periods since the
    // last one, and before a frame reaches the ESCs each slave that the frame reads and whose own cycle is
    // due runs (Application::next_cycle_ns; without one, a last run local_cycle_ns or more ago), as do the
    // slaves with a SYNC pulse or a deadline due, so that the frame reads every cycle up to its own time,
    // as if the slaves ran on timers (a SYNC pulse is taken at its own time, whenever the run is). Only
    // deadlines need a run on time: next_firmware_ns() is the earliest, and tick() runs them. A server then
    // wakes up for frames and deadlines, not for every period of every drive.
    void set_local_cycle_ns(std::uint64_t ns) { local_cycle_ns_ = ns ? ns : 1; }
    std::uint64_t local_cycle_ns() const { return local_cycle_ns_; }
    // Host time of the earliest deadline of any slave's firmware (DistributedClock::kNever if none).
    std::uint64_t next_firmware_ns() const;
    // Something outside the frames changed what slave k's firmware makes of its own cycle (an input forced
    // or released on an application whose inputs otherwise do not change with time, which says
    // Application::next_cycle_ns kNever): the next frame that reads it finds it caught up first.
    void wake_slave(std::size_t k) {
        finish_background_firmware();
        if (k < cycle_ns_.size()) cycle_ns_[k] = 0;
    }

    // ---- Firmware on several threads (vecat run --threads N). The runs of one batch (the catch-up of the
    // slaves a frame reads, before the frame is processed; the runs after a frame; a tick) go to the
    // threads by group: slaves whose applications share state (Application::shared_state: drives coupled
    // by TWINsync, I/O wired to each other) form one group, which runs on one thread in the slaves'
    // order; groups share nothing, so they run in any order on any thread with the same results. The
    // serve loop's thread takes part and returns when the batch is done (FirmwareThreads::run), and the
    // frame's datagrams are processed on the serve loop's thread as before (the one exception: the runs after
    // a frame may go on beside the next frame, start_deferred_firmware). Batches of fewer than
    // kMinParallelRuns runs stay on the calling thread. nullptr: one thread.
    void set_firmware_threads(FirmwareThreads* threads);
    static constexpr std::size_t kMinParallelRuns = 4;
    // From this many slaves on, a frame asks the caches for its slaves' ESC state before it passes them
    // (Slave::prefetch_for_frame): BM_CyclicReplyPath/512 140 us against 153 us without (medians of 4
    // alternating runs), BM_Network1000Cycle/1 198 against 213 us. Since the ESC keeps what it asks for
    // beside its first line (Esc::prefetch_sms), asking waits for one line per slave instead of three or
    // four: 128 against 140 us, 172 against 191 us (medians of 6 alternating runs, 2026-11-29). A line of
    // 100 slaves, whose state stays in a core's cache, gains nothing and pays the requests.
    static constexpr std::size_t kPrefetchSlaves = 256;
    // The groups the slaves form now (a figure for tests).
    std::size_t firmware_groups();
    std::uint32_t firmware_group(std::size_t i) {
        firmware_groups();
        return group_of_[i];
    }

    const SegmentCounters& counters() const { return counters_; }

    // ---- Topology: a tree of ESCs (network files). add() makes a line: slave k's port 0 is cabled to port 1
    // of slave k-1. set_topology() cables slave k's port 0 to port ports[k] (1..3) of slave parents[k] (-1:
    // the master; only slave 0) through a cable of delays_ns[k] (0: hop_delay_ns). The slaves must be in
    // the order a frame reaches them: depth first from the master, each ESC's ports in the order
    // 0 -> 3 -> 1 -> 2 (ESC datasheet section I). Returns false, changing nothing, otherwise.
    bool set_topology(const std::vector<int>& parents, const std::vector<std::uint8_t>& ports,
                      const std::vector<std::uint32_t>& delays_ns, std::string* why = nullptr);
    int parent(std::size_t i) const { return i < parent_.size() ? parent_[i] : -1; }
    unsigned parent_port(std::size_t i) const { return i < parent_port_.size() ? parent_port_[i] : 0; }
    // A frame from the master reaches slave i (cables connected, every port on the way open), as of the
    // last frame or the last call of reachable(), which looks again.
    bool reached(std::size_t i) const { return i < reached_.size() && reached_[i] != 0; }

    // ---- Line faults (fault injection, see src/faults)
    // Connects or disconnects cable k (see FrameDamage; k == size(): the redundancy cable): both ports lose
    // their link (DL status, lost link counter) and frames turn back at the last slave before the break.
    void set_cable(std::size_t k, bool connected);
    bool cable(std::size_t k) const {
        return k < cable_up_.size() ? cable_up_[k] != 0 : redundant() && k == slaves_.size() && red_cable_up_;
    }
    // How many slaves a frame reaches from the master now (and reached(i) tells which).
    std::size_t reachable() const;
    // Firmware stopped (hang, or no power): the ESC still forwards and answers, while the AL state, the
    // mailbox and the process data of the application freeze.
    void set_firmware_halted(std::size_t i, bool halted);
    bool firmware_halted(std::size_t i) const { return i < halted_.size() && halted_[i] != 0; }
    // Power-on reset of slave i: a new slave of the same device from the application factory (segments
    // made by make_segment). Its links follow the cables. False without a factory.
    bool restart_slave(std::size_t i);
    // Counts changes of the slaves themselves: a restart (a new Slave object at its position) or a move
    // (hot connect: new positions). Observers that keep something per slave (the report, telemetry) look
    // at it to follow them; the Slave objects stay where they are otherwise.
    std::uint64_t slaves_epoch() const { return slaves_epoch_; }
    void set_application_factory(ApplicationFactory f) { factory_ = std::move(f); }

    // ---- Cable redundancy (a ring). Port `port` (1..3) of slave `slave`, free of other cables, is cabled
    // back to the master's secondary port: cable number size() (see cables()). Frames then take their way
    // through the ring by the ESCs' own rules (ESC datasheet section I, frame processing: a frame received
    // at port p leaves through the next open port in the order 0 -> 3 -> 1 -> 2 -> 0, and only the way
    // from port 0 to port 3 passes the processing unit). With the ring whole, a frame from the primary
    // port is processed by every slave and arrives at the secondary port, a frame from the secondary port
    // passes every ESC unprocessed and arrives at the primary port; with a cable broken (auto loop control
    // closes the ports at the break) each part of the line processes the frame from its own side.
    // Refused (false, why) with chained segments, or for a port that does not exist or is cabled already.
    bool set_redundancy(std::size_t slave, unsigned port, std::string* why = nullptr);
    bool redundant() const { return red_slave_ < slaves_.size(); }
    std::size_t redundancy_slave() const { return red_slave_; }
    unsigned redundancy_port() const { return red_port_; }
    // Whether the master's secondary port has a link (the serve loop follows the interface's carrier).
    void set_secondary_link(bool up);
    // All cables: one into each slave, and the redundancy cable.
    std::size_t cables() const { return slaves_.size() + (redundant() ? 1 : 0); }
    // The cable at port `port` of slave `slave` (its cable number), or kNoCable when nothing is cabled there.
    static constexpr std::size_t kNoCable = ~std::size_t{0};
    std::size_t cable_at(std::size_t slave, unsigned port) const;

    // ---- Hot connect groups (as TwinCAT's): a device and everything downstream of it, which can be
    // unplugged from the line and plugged back at run time (src/faults: unplug). In the slaves' order the
    // group is the range [head, group_end(head)).
    void add_hot_connect_group(std::string name, std::size_t head);
    // The head of the group of that name, or size() when there is none.
    std::size_t hot_connect_head(std::string_view name) const;
    const std::vector<std::pair<std::string, std::size_t>>& hot_connect_groups() const { return groups_; }
    std::size_t group_end(std::size_t head) const;
    // Plugs the group headed by `head` into port `port` (1..3) of slave `parent` instead of where it was
    // (call it while the group is unplugged: its cables are out). The parent must lie outside the group and
    // the port exist and be free (no device, no redundancy cable). The slaves then take the order in which
    // the frame reaches them (their positions change as on hardware): order[new position] = old position.
    // The cable into the group's head keeps its delay. Returns false, changing nothing, with why otherwise.
    bool move_group(std::size_t head, std::size_t parent, unsigned port, std::vector<std::size_t>& order,
                    std::string* why = nullptr);
    // Whether move_group() would take these (the port may be the group's own: plugged back where it was).
    bool can_move_group(std::size_t head, std::size_t parent, unsigned port,
                        std::string* why = nullptr) const;

    // ---- Chained segments (one line over several processes or machines)
    // Port 1 of the last slave has a link to the next segment. process_frame() then lets the frame go on
    // (its true result means "send it downstream" while downstream_link() holds) instead of closing the
    // loop, and the frame comes back through return_frame().
    void set_downstream_link(bool up);
    bool downstream_link() const { return downstream_; }
    // The frame process_frame() last returned true for goes downstream (else back to the master).
    bool frame_goes_downstream() const { return onward_; }
    // A frame back from the downstream segment at port 1 of the last slave. The ESCs forward it unchanged
    // (port 1 -> port 0); a receive-time latch in it (a write to 0x0900) sets the port 1 receive times of
    // the slaves that latched on the way out, from the line model (see return_receive_times()). Returns
    // true when the frame goes on to the master side. now_ns (its arrival) is not used: the port 1 times
    // come from the line model, not from the real transit through the processes behind.
    bool return_frame(Bytes frame, std::size_t len, std::uint64_t now_ns);

    // Line model: delay of a frame per hop (cable + PHY + forwarding) in ns. The cable to the next segment
    // counts as one hop too, so a chained line measures the same delays as one process with all slaves.
    std::uint64_t hop_delay_ns = 500;

  private:
    void run_firmware(std::uint64_t now_ns);
    void run(std::size_t k, std::uint64_t now_ns);  // run_slave, counted
    void run_slave(std::size_t k, std::uint64_t now_ns);
    // Batches: pick() the slaves, run_picked() runs them (on the firmware threads when there are enough).
    void pick(std::size_t k);
    void run_picked(std::uint64_t now_ns);
    static void run_group(void* self, std::size_t item);
    void refresh_groups();
    FirmwareThreads* threads_ = nullptr;
    std::vector<std::uint8_t> picked_;  // per slave: runs in the batch being made
    std::size_t picked_count_ = 0;
    // The slaves picked, in the order they were (capacity: one per slave): a batch of a few slaves on a long
    // line does not look at every slave.
    std::vector<std::uint32_t> picked_list_;
    std::uint64_t batch_now_ns_ = 0;
    std::uint64_t grouped_epoch_ = ~std::uint64_t{0};  // slaves_epoch_ when the groups were made
    std::vector<std::uint32_t> group_of_;              // per slave
    // The members of group g, in the slaves' order: members_[group_begin_[g] .. group_begin_[g + 1]).
    std::vector<std::uint32_t> group_begin_;
    std::vector<std::uint32_t> members_;
    std::vector<std::uint64_t> group_batch_;  // per group: the batch it was last put in
    std::uint64_t batch_serial_ = 0;
    std::vector<std::uint32_t> batch_groups_;  // the groups of the batch being run
    // Batches: the groups of the picked slaves into batch_groups_ (their order: the slaves').
    void make_batch(std::uint64_t now_ns);
    // The runs of the deferred frames on the workers (start_deferred_firmware): the slaves they run
    // (capacity: one per slave), how many of the deferred frames they are, and each slave's time (the
    // time of the frame that marked it; run_group takes it while background_). finish_background_firmware
    // waits for them and takes the frames off the deferred ones.
    bool background_ = false;
    std::size_t background_frames_ = 0;
    std::vector<std::uint32_t> background_list_;
    std::vector<std::uint64_t> run_at_ns_;  // per slave
    void finish_background_firmware();
    void count_corruption(const FrameDamage& d, std::size_t reached);
    void update_links(std::size_t i);
    void return_receive_times(const protocol::ParsedFrame& pf, Bytes frame);
    // The frame's way through the tree, worked out again when a port, cable or the topology changed
    // (port_epoch_): which slaves it reaches (reached_, reached_count_), when it reaches each slave's port 0
    // and comes back through its ports relative to its arrival at the first one (timing_), and how many
    // slaves in order it passes (passed_: all, or fewer when it leaves through an open port without a
    // device behind it and is lost there).
    void refresh_route() const;
    void route() const;
    std::uint64_t cable_delay(std::size_t k) const {
        return k < delay_.size() && delay_[k] ? delay_[k] : hop_delay_ns;
    }
    // Ring walk (redundancy): the way of one frame from a master port through the ESCs' ports, in order
    // (ring_order_: the slaves whose processing unit it passes; ring_timing_: when it arrived at their
    // ports, relative to its arrival at the first ESC). Damage on a cable it crosses ends it there.
    enum class WalkEnd : std::uint8_t { Primary, Secondary, Lost, Damaged };
    WalkEnd walk(MasterPort from, const FrameDamage& damage) const;
    bool process_ring(Bytes frame, std::size_t& len, std::uint64_t now_ns, const FrameDamage& damage,
                      MasterPort from, const protocol::ParsedFrame& pf);
    std::vector<std::pair<std::string, std::size_t>> groups_;
    std::size_t red_slave_ = ~std::size_t{0};
    unsigned red_port_ = 0;
    bool red_cable_up_ = true;
    bool secondary_link_ = true;
    MasterPort reply_port_ = MasterPort::Primary;
    mutable std::vector<std::size_t> ring_order_;
    mutable std::vector<FrameTiming> ring_timing_;
    mutable std::vector<std::uint8_t> ring_seen_;
    mutable std::size_t ring_damaged_receiver_ = ~std::size_t{0};  // the ESC that received a corrupted frame
    mutable unsigned ring_damaged_port_ = 0;

    std::vector<int> parent_;                // per slave: the slave its port 0 is cabled to, -1: master
    std::vector<std::uint8_t> parent_port_;  // ... at this port of it
    std::vector<std::uint32_t> delay_;       // ... through a cable of this delay (0: hop_delay_ns)
    std::vector<std::array<int, 4>> child_;  // per slave and port: the slave cabled there, -1: none
    mutable std::vector<std::uint8_t> reached_;
    mutable std::vector<FrameTiming> timing_;
    mutable std::size_t reached_count_ = 0;
    mutable std::size_t passed_ = 0;
    std::atomic<std::uint64_t> port_epoch_{1};  // counted up by the ESCs and by cabling changes
    std::uint64_t slaves_epoch_ = 0;            // see slaves_epoch()
    mutable std::uint64_t routed_epoch_ = 0;    // ... when the route was worked out
    mutable std::uint64_t routed_hop_ns_ = 0;   // ... with this hop_delay_ns
    struct Visit {
        std::size_t slave;
        unsigned next;    // ports of kPortOrder visited
        std::uint64_t t;  // the frame's time at this slave so far
    };
    mutable std::vector<Visit> stack_;

    // The receive-time latch last sent downstream, until it returns (one slot: masters wait for the reply
    // of the latch frame; a newer latch replaces an unanswered one). Its working counter on return tells
    // how many slaves lie behind this segment.
    struct PendingLatch {
        bool valid = false;
        std::uint8_t index = 0;       // datagram index byte
        std::size_t position = 0;     // datagram number in the frame
        std::uint16_t wkc_after = 0;  // its working counter as it left this segment
        std::uint64_t port0_ns = 0;   // arrival at the first slave
    };
    PendingLatch pending_latch_;
    std::vector<std::uint8_t> latched_;  // per slave: took part in the pending latch
    bool downstream_ = false;
    bool onward_ = false;

    std::vector<std::unique_ptr<Slave>> slaves_;
    std::vector<std::uint8_t> cable_up_;  // cable k into slave k
    std::vector<std::uint8_t> halted_;
    ApplicationFactory factory_;
    std::vector<ApplicationFactory> own_factory_;  // per slave, empty: factory_
    // Per slave: host time of its last firmware run (0: run it after this frame). A frame runs the firmware
    // of the slaves it addressed only; the others catch up before a frame reads them (catch_up) or at their
    // deadlines, so a cycle of several frames does not run every slave once per frame.
    std::vector<std::uint64_t> last_run_ns_;
    // The slaves a frame marked (last_run_ns_ 0) since the last run_due_firmware, so that it and the catch-up
    // before a frame need not look at every slave; marks_valid_ false: look at every slave (after a move of
    // the slaves, or more marks than the capacity, one per slave, holds). An entry may have run since.
    void mark_for_run(std::size_t k);
    std::vector<std::uint32_t> marked_;
    bool marks_valid_ = false;
    // No slave's last run is later than this (a run at an earlier time than a slave's last, as a test's clock
    // may do, is looked for among every slave).
    std::uint64_t latest_run_ns_ = 0;
    // No slave's deadline (deadline_ns_) is earlier than this: until then, the catch-up before a frame has no
    // deadline to look for.
    std::uint64_t earliest_deadline_ns_ = 0;
    // Per slave: its earliest deadline as of its last run (Slave::next_event_ns); 0: run it before the next
    // frame. A frame that moves a deadline earlier (a shorter watchdog) addresses the slave, which then runs
    // after the frame and looks again.
    std::vector<std::uint64_t> deadline_ns_;
    // Per slave: its next SYNC pulse as of its last run (a frame that starts or moves SYNC addresses it).
    std::vector<std::uint64_t> pulse_ns_;
    // Per slave: its application's next own cycle as of its last run (Application::next_cycle_ns), or its
    // last run plus the local cycle; 0: stale now.
    std::vector<std::uint64_t> cycle_ns_;
    std::uint64_t local_cycle_ns_ = 250'000;
    // A slave that no frame reads runs at the latest this many local cycles after its last run: the work
    // of one run (the cycles it catches up) stays bounded, whichever slave a frame then reads.
    static constexpr std::uint64_t kMaxLagCycles = 16;
    // Before a frame: the slaves whose state the frame must find current (see set_local_cycle_ns). The
    // line runs those with a deadline due here (catch_up_deadlines) and, in process_datagrams, those that
    // the frame reads, each just before the frame reaches it; a ring catches every slave up (catch_up).
    void catch_up(std::uint64_t now_ns);
    void catch_up_deadlines(std::uint64_t now_ns);
    bool deadline_due(std::size_t k, std::uint64_t now_ns) const;
    bool stale(std::size_t k, std::uint64_t now_ns) const;
    // Before any run: the SYNC pulses up to now_ns of the slaves whose applications are coupled
    // (Application::coupled), one at a time in time order across them.
    void deliver_coupled_pulses(std::uint64_t now_ns) {
        if (coupled_epoch_ != slaves_epoch_ || !coupled_.empty()) deliver_coupled_pulses_now(now_ns);
    }
    void deliver_coupled_pulses_now(std::uint64_t now_ns);
    std::vector<std::size_t> coupled_;  // those slaves, as of coupled_epoch_
    std::uint64_t coupled_epoch_ = ~std::uint64_t{0};
    void run_due_firmware(std::uint64_t now_ns);

    // ---- Which ESCs a datagram concerns (see Esc::Addressing). A real ESC looks at every datagram in
    // hardware; here a frame of a large network would touch every ESC's memory once per datagram. The
    // segment keeps each ESC's addressing in one compact table instead, and hands a datagram to the ESCs it
    // can concern: all of them for broadcasts and read-multiple-writes, the one at its position for
    // auto-increment commands (whose ADP the segment then counts on for the others), those of that station
    // address or alias, and those whose FMMUs cover some of a logical datagram. The answers are the same as
    // when every ESC looks at every datagram.
    void process_datagrams(Bytes frame, const protocol::ParsedFrame& pf, std::size_t intact,
                           std::size_t latch_pos, std::uint64_t now_ns);
    void refresh_addressing();
    std::vector<Esc::Addressing> addressing_;  // per slave
    // The index of addressing_ (fresh: made from it since it last changed), and the slaves it gives for the
    // frame at hand. find_candidates: false for a frame with other than configured-address and logical
    // datagrams, which goes to every slave.
    AddressIndex address_index_;
    bool index_fresh_ = false;
    std::vector<std::uint32_t> candidates_;
    bool find_candidates(const protocol::ParsedFrame& pf, std::size_t intact);
    std::atomic<std::uint64_t> address_epoch_{1};  // counted up by the ESCs (Esc::set_address_change_counter)
    std::uint64_t addressed_epoch_ = 0;            // ... when addressing_ was last made whole
    std::uint64_t addressed_slaves_epoch_ = ~std::uint64_t{0};
    enum class Reach : std::uint8_t { None, All, Position, Fixed, Logical };
    struct DatagramReach {
        Reach reach = Reach::None;
        std::uint16_t adp = 0;                      // as it arrived at the first ESC
        std::uint64_t first_bit = 0, last_bit = 0;  // Logical: the bits it covers
        // Whether it reads what the slaves' firmware keeps (process data, mailbox, AL status...; not the
        // DC time registers, Esc::dc_time_registers): the slaves it reads catch up first. Logical reads
        // read a slave only through its reading FMMUs. (Which slaves run after the frame their ESCs say,
        // Esc::take_firmware_work.)
        bool reads = false;
    };
    std::array<DatagramReach, protocol::kMaxDatagramsPerFrame> reach_{};

    bool defer_firmware_ = false;
    // The frames whose firmware runs are still to be done (set_deferred_firmware): each frame's time and the
    // end of its marks in marked_ (the first frame's begin at 0).
    struct DeferredFrame {
        std::uint64_t at_ns = 0;
        std::size_t marks_end = 0;
    };
    std::array<DeferredFrame, kMaxDeferredFrames> deferred_{};
    std::size_t deferred_count_ = 0;
    std::size_t deferred_marks_ = 0;             // marked_[0, deferred_marks_) are the deferred frames' marks
    std::vector<std::uint64_t> group_deferred_;  // per group: deferral_serial_ if one of them is marked
    std::uint64_t deferral_serial_ = 0;
    void defer_frame_firmware(std::uint64_t now_ns);
    bool keep_deferred(std::uint64_t now_ns, const FrameDamage& damage) const;
    bool candidates_share_deferred_groups() const;
    bool coupled_deferred() const;
    // Whether one of these slaves shares a group with a slave a deferred frame marked (true while the groups
    // are not known).
    template <class Slaves>
    bool share_deferred_groups(const Slaves& slaves) const;
    SegmentCounters counters_;
};

// Builds a segment of n slaves of the given device, each with an application from the factory (by
// default a ProcessImageApplication without mailbox protocols).
std::unique_ptr<Segment> make_segment(const device::DeviceDescription& d, std::size_t n,
                                      const EscConfig& cfg = {}, const ApplicationFactory& factory = {});
// The same from a model built once (DeviceModel::of): repeated segments of one device share it.
std::unique_ptr<Segment> make_segment(const DeviceModel& model, std::size_t n, const EscConfig& cfg = {},
                                      const ApplicationFactory& factory = {});

// (Inline: a frame marks and picks each slave it gives work.)
inline void Segment::mark_for_run(std::size_t k) {
    if (last_run_ns_[k] == 0) return;  // marked already (or never run: marks_valid_ is false then)
    last_run_ns_[k] = 0;
    if (marked_.size() < slaves_.size())
        marked_.push_back(static_cast<std::uint32_t>(k));
    else
        marks_valid_ = false;
}

inline void Segment::pick(std::size_t k) {
    if (picked_[k]) return;
    picked_[k] = 1;
    ++picked_count_;
    picked_list_.push_back(static_cast<std::uint32_t>(k));  // capacity: one per slave (add)
}

}  // namespace vecat::esc
