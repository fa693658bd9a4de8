// One EtherCAT slave: the ESC plus the firmware that a real device runs on its PDI side: the AL state
// machine (a table, ETG.1000.6 6.4), the mailbox layer and the process data exchange with the
// application (the drive).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "device/device_description.hpp"
#include "esc/esc.hpp"
#include "esc/mailbox.hpp"
#include "esc/sii_image.hpp"
#include "protocol/al_status.hpp"

namespace vecat::esc {

class Slave;

// Whether the application lets a waiting SAFEOP -> OP transition complete (see Application::op_readiness).
struct OpReadiness {
    bool ready = true;                                               // false: keep waiting
    protocol::AlStatusCode error = protocol::AlStatusCode::NoError;  // not NoError: refuse with this code
};

// What the application behind the PDI provides. The slave calls it from the frame-processing thread.
class Application {
  public:
    virtual ~Application() = default;
    // Current process data sizes in bytes (they follow the PDO assignment).
    virtual unsigned output_bytes() const = 0;
    virtual unsigned input_bytes() const = 0;
    // Application-specific checks of a transition (PDO mapping, sync configuration...). NoError allows it.
    virtual protocol::AlStatusCode check_transition(protocol::AlState /*from*/, protocol::AlState /*to*/) {
        return protocol::AlStatusCode::NoError;
    }
    virtual void on_state_change(protocol::AlState /*from*/, protocol::AlState /*to*/) {}
    // The slave signalled an AL error (code), or the master acknowledged it (NoError).
    virtual void on_al_error(protocol::AlStatusCode /*code*/) {}
    // One process data exchange. outputs is empty when no valid outputs exist (below OP they are not
    // applied).
    virtual void exchange(std::uint64_t now_ns, ConstBytes outputs, bool apply_outputs, Bytes inputs) = 0;
    // The outputs must go to their safe state (watchdog expired, left OP).
    virtual void outputs_safe_state() {}
    // The protocol of the application serving a type (nullptr: none). The slave asks for its CoE once, when
    // it is made: that protocol stays the same object for the application's life.
    virtual MailboxProtocol* mailbox_protocol(protocol::MailboxType) { return nullptr; }
    // Called regularly, also without frames (time-driven behaviour).
    virtual void tick(std::uint64_t /*now_ns*/) {}
    // One SYNC pulse of the DC unit (signal 0 = SYNC0, 1 = SYNC1), with its time on the host clock. Called
    // for every pulse, in time order, before tick(); pulses the firmware could not take are counted by the
    // ESC.
    virtual void sync_event(unsigned /*signal*/, std::uint64_t /*now_ns*/) {}
    // After SYNC events: new inputs to publish at once (true if written into inputs), so the master's next
    // frame reads what the application computed at the SYNC event.
    virtual bool refresh_inputs(Bytes /*inputs*/) { return false; }
    // The slave gives itself once, at construction: the PDI view of the ESC (DC registers, SyncManager
    // counters) and raise_error() for errors the application detects (sync loss...).
    virtual void attach(Slave& /*slave*/) {}
    // SAFEOP -> OP waits until the outputs are valid and the application is ready (e.g. SYNC0 running);
    // called at the request and on every run while the transition waits (waiting since since_ns).
    virtual OpReadiness op_readiness(std::uint64_t /*now_ns*/, std::uint64_t /*since_ns*/) { return {}; }
    // A firmware update took effect (Slave::apply_firmware_revision): the device now reports this revision
    // (a CoE device in 0x1018:03).
    virtual void on_revision_change(std::uint32_t /*revision*/) {}
    // Its own cycles also run another slave's application (drives coupled by TWINsync step in lockstep):
    // the segment then hands out the SYNC pulses of such slaves in time order across them, so that neither
    // steps the other past a pulse the other has not taken yet.
    virtual bool coupled() const { return false; }
    // State this application shares with other slaves' applications, as keys (a TWINsync partner, the
    // output image a wire reads): slaves that name a common key run on one thread, one after the other in
    // the slaves' order (Segment::set_firmware_threads). Asked when the slaves change, never cyclically.
    virtual void shared_state(std::vector<const void*>& /*keys*/) const {}
    // The host time by which the firmware must run even without a frame, for a deadline of the
    // application's own (a timeout, a loss of SYNC events), or DistributedClock::kNever. Its own cycle
    // needs none: it catches up at every run (Segment::set_local_cycle_ns). Asked after each run.
    virtual std::uint64_t next_event_ns() const { return DistributedClock::kNever; }
    // The host time of the application's next own cycle (a drive's servo period): a frame that reads the
    // slave at or after it finds the slave caught up first, so that it reads every cycle up to its own time.
    // 0: the application does not say; the segment then takes a run a local cycle old as stale
    // (Segment::set_local_cycle_ns). DistributedClock::kNever: what it makes does not change with time (a
    // change from outside the frames wakes it, Segment::wake_slave). Asked after each run.
    virtual std::uint64_t next_cycle_ns() const { return 0; }
};

// A process image without behaviour: keeps the last outputs and serves inputs set from outside.
class ProcessImageApplication : public Application {
  public:
    ProcessImageApplication(unsigned out_bytes, unsigned in_bytes) : outputs_(out_bytes), inputs_(in_bytes) {}
    unsigned output_bytes() const override { return static_cast<unsigned>(outputs_.size()); }
    unsigned input_bytes() const override { return static_cast<unsigned>(inputs_.size()); }
    void exchange(std::uint64_t, ConstBytes out, bool apply, Bytes in) override;
    void outputs_safe_state() override;
    std::vector<std::uint8_t>& inputs() { return inputs_; }
    const std::vector<std::uint8_t>& outputs() const { return outputs_; }
    std::uint64_t exchanges() const { return exchanges_; }

  private:
    std::vector<std::uint8_t> outputs_;
    std::vector<std::uint8_t> inputs_;
    std::uint64_t exchanges_ = 0;
};

// Sees every mailbox request before its protocol does (fault injection: aborts, lost replies). Returns
// true when it took the request over (answered it through the sink, or dropped it).
class MailboxInterceptor {
  public:
    virtual ~MailboxInterceptor() = default;
    virtual bool intercept(Slave& slave, const protocol::MailboxHeader& h, ConstBytes payload,
                           MailboxProtocol* protocol, MailboxReplySink& sink) = 0;
};

// The AL state machine as a table: what a request from one state to another does.
enum class AlAction : std::uint8_t {
    Stay,              // requested state == current state
    Down,              // allowed without checks
    CheckMailbox,      // INIT -> PREOP
    CheckBoot,         // INIT -> BOOT: bootstrap supported, SM0/SM1 as the SII's bootstrap mailbox
    CheckProcessData,  // PREOP -> SAFEOP
    CheckOutputs,      // SAFEOP -> OP: waits for valid outputs
    Refuse,            // 0x0011 invalid requested state change
};
AlAction al_transition(protocol::AlState from, protocol::AlState to) noexcept;

struct SlaveCounters {
    std::uint64_t mailbox_requests = 0;
    std::uint64_t mailbox_errors = 0;
    std::uint64_t mailbox_repeats = 0;
    std::uint64_t mailbox_duplicates = 0;
    std::uint64_t mailbox_replies_dropped = 0;
    std::uint64_t mailbox_replies_lost = 0;  // quirk mailbox_drop_every: lost until a repeat request
    std::uint64_t watchdog_expiries = 0;
};

// What every slave of one device shares, built once: the description and what is generated from it, the
// SII image and the objects of the CoE dictionary (a segment of 128 drives, or a fuzz target building a
// segment per input, neither copies the description nor generates these per slave). Each slave's ESC gets
// its own copy of the image (writable EEPROM), each CoE application its own values.
struct DeviceModel {
    std::shared_ptr<const device::DeviceDescription> description;
    std::shared_ptr<const std::vector<std::uint8_t>> sii_image;
    std::shared_ptr<const std::vector<device::ObjectDescription>> dictionary;  // device::dictionary_objects
    static DeviceModel of(const device::DeviceDescription& d);
};

class Slave {
  public:
    Slave(const DeviceModel& model, EscConfig esc_cfg, std::unique_ptr<Application> app);
    Slave(const device::DeviceDescription& desc, EscConfig esc_cfg, std::unique_ptr<Application> app);
    ~Slave();
    Slave(const Slave&) = delete;
    Slave& operator=(const Slave&) = delete;

    Esc& esc() { return esc_; }
    const Esc& esc() const { return esc_; }
    Application& app() { return *app_; }
    const Application& app() const { return *app_; }
    const device::DeviceDescription& description() const { return *model_.description; }
    const DeviceModel& model() const { return model_; }

    // Firmware step after a frame went through the ESC, and on timer ticks.
    void run(std::uint64_t now_ns);
    // Whether the firmware has a mailbox message for the master (a queued reply, an emergency, an EoE frame
    // from the host) and SM1 is free to take it: a run would post it.
    bool mailbox_output_pending() const;
    // Asks the caches for what a process data frame reads and writes of this slave: its ESC's state
    // (Esc::prefetch_for_frame) and the first lines of this object.
    void prefetch_for_frame() const {
        __builtin_prefetch(this);
        __builtin_prefetch(reinterpret_cast<const char*>(this) + 64);
        esc_.prefetch_for_frame();
    }
    // The host time by which run() must be called again without a frame (after a run; see
    // Segment::next_firmware_ns): the process data watchdog's expiry, SYNC pulses about to pile up beyond
    // what one run takes, the AL control read after its latency, the application's deadlines; poll_ns
    // while a transition waits on conditions that are polled (SAFEOP -> OP).
    std::uint64_t next_event_ns(std::uint64_t poll_ns) const;
    std::uint64_t next_cycle_ns() const { return app_->next_cycle_ns(); }  // Application::next_cycle_ns
    // The SYNC pulses up to until_ns to the application, in time order (run() does this first; the segment
    // calls it ahead for coupled applications).
    void deliver_sync_pulses(std::uint64_t until_ns);

    protocol::AlState state() const { return state_; }
    bool error() const { return error_; }
    protocol::AlStatusCode status_code() const { return code_; }
    // Forces an error as the application would (fault injection, sync loss...): falls back to target.
    void raise_error(protocol::AlStatusCode code, protocol::AlState fallback);
    const SlaveCounters& counters() const { return counters_; }
    void set_mailbox_interceptor(MailboxInterceptor* i) { interceptor_ = i; }

    // A mailbox protocol of the slave's own firmware beside the application's (FoE and the bootloader,
    // src/foe): asked first for its type. The slave owns it.
    void add_mailbox_protocol(std::unique_ptr<MailboxProtocol> p);
    // The protocol serving a type: the slave's own, else the application's; nullptr when none.
    MailboxProtocol* mailbox_protocol(protocol::MailboxType t);
    // The firmware update: the revision in the SII (words 0x000C/0x000D of the EEPROM) becomes revision, and
    // the application is told (Application::on_revision_change). Called by the bootloader on BOOT -> INIT.
    void apply_firmware_revision(std::uint32_t revision);
    // The revision the SII holds now.
    std::uint32_t sii_revision() const;

    // How long the firmware takes to read AL control after the master wrote it (default 0: at its next
    // run). Without device emulation a second write before that read is not accepted (ESC datasheet section
    // II 0x0120), as real devices show to masters that write AL control twice (docs/replay.md).
    void set_al_control_latency(std::uint64_t ns) { al_control_latency_ns_ = ns; }

    static constexpr std::uint64_t kOutputsValidTimeoutNs = 1'000'000'000;  // SAFEOP -> OP wait

  private:
    void handle_al_control(std::uint64_t now_ns);
    void enter(protocol::AlState to, std::uint64_t now_ns);
    void set_error(protocol::AlStatusCode code, protocol::AlState stay, std::uint64_t now_ns);
    void clear_error();
    bool outputs_valid() const;
    void publish_status();
    protocol::AlStatusCode check_mailbox_config() const;
    protocol::AlStatusCode check_boot_mailbox_config() const;
    void reset_mailbox();
    protocol::AlStatusCode check_process_data_config() const;
    // The process data of this direction goes through its SyncManager; false: through an FMMU alone (the
    // SM is virtual, or declared not enabled and left off by the master). may_bypass: out_may_bypass_ or
    // in_may_bypass_.
    bool through_sm(int smi, bool may_bypass) const {
        return !may_bypass || esc_.sm_ecat_enabled(static_cast<unsigned>(smi));
    }
    bool read_outputs(unsigned len);
    void write_inputs(unsigned len);
    void service_mailbox();
    void send_pending_replies();
    void post_replies();  // the protocols' own messages (emergencies, SDO information) and queued replies
    // Calls f(protocol) for each protocol that has a message of its own to send now (has_output).
    template <class F>
    void for_each_sending_protocol(F&& f) const;
    void exchange_process_data(std::uint64_t now_ns);
    void try_enter_op(std::uint64_t now_ns);
    void set_sm_group(bool mailbox, bool active);

    DeviceModel model_;
    const device::DeviceDescription& desc_;  // *model_.description
    // What every run and every frame's question for mailbox output read comes first, together (a line of
    // hundreds of slaves runs each of them out of the caches, and each line read is a miss).
    std::unique_ptr<Application> app_;
    // The application's CoE (Application::mailbox_protocol, asked once when the slave is made), and the
    // slave's own protocols.
    MailboxProtocol* coe_ = nullptr;
    std::vector<std::unique_ptr<MailboxProtocol>> own_protocols_;
    protocol::AlState state_ = protocol::AlState::Init;
    bool error_ = false;
    bool op_pending_ = false;
    bool lost_reply_waiting_ = false;
    int sm_mbx_out_ = -1, sm_mbx_in_ = -1, sm_out_ = -1, sm_in_ = -1;
    std::uint64_t now_ns_ = 0;  // of the current run
    std::uint64_t al_control_latency_ns_ =
        0;  // AL status written once at power-up, also under device emulation
    std::size_t q_head_ = 0, q_count_ = 0;
    std::vector<std::uint8_t> outputs_, inputs_;
    Esc esc_;
    protocol::AlStatusCode code_ = protocol::AlStatusCode::NoError;
    bool ident_ = false;
    std::uint64_t op_pending_since_ = 0;
    std::uint64_t outputs_at_safeop_ = 0;
    // The process data SyncManagers as the description declares them (nullptr: none), looked up once, and
    // whether the data of that direction may bypass it: declared virtual, or not enabled (the master may
    // leave it off).
    const device::SyncManagerConfig* decl_out_ = nullptr;
    const device::SyncManagerConfig* decl_in_ = nullptr;
    bool out_may_bypass_ = false, in_may_bypass_ = false;
    std::uint8_t last_counter_ = 0;
    std::uint8_t reply_counter_ = 0;
    std::unique_ptr<MailboxReplySink> sink_;
    // Mailbox buffers, allocated once.
    std::vector<std::uint8_t> rx_;
    std::vector<std::uint8_t> last_reply_;
    std::size_t last_reply_len_ = 0;
    static constexpr std::size_t kReplySlots = 8;
    std::array<std::vector<std::uint8_t>, kReplySlots> queue_;
    std::array<std::size_t, kReplySlots> queue_len_{};
    // Quirk mailbox_delay_ms: when each queued reply may enter the mailbox-in SyncManager.
    std::array<std::uint64_t, kReplySlots> queue_due_{};
    // Quirk mailbox_drop_every: replies that left the queue, and a lost one waiting for the repeat request.
    std::uint64_t replies_out_ = 0;
    static constexpr unsigned kMaxPulsesPerRun = 16;  // SYNC pulses taken per firmware run; more are missed
    std::array<SyncPulse, kMaxPulsesPerRun> pulses_{};
    SlaveCounters counters_;
    MailboxInterceptor* interceptor_ = nullptr;
    friend class SlaveReplySink;
};

}  // namespace vecat::esc
