// The report on the master (vecat run --report): watches every frame the master sends and every reply,
// next to the state of the emulated slaves, and records where the master breaks a rule of rules.hpp.
// A finding is kept once per rule and slave (the first time, with its frame number) and counted after
// that; nothing is allocated per frame otherwise.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "esc/segment.hpp"
#include "net/frame_observer.hpp"
#include "protocol/frame.hpp"
#include "protocol/registers.hpp"
#include "protocol/sii.hpp"
#include "report/rules.hpp"

namespace vecat::report {

struct Finding {
    Rule rule;
    std::size_t slave = 0;      // position on the line
    std::uint64_t frame = 0;    // the master's frame (1 = the first frame vecat received)
    std::uint64_t time_ns = 0;  // since the first frame
    std::string message;        // what happened, with the values
    std::uint64_t count = 1;    // times it happened
};

class MasterChecks final : public net::FrameObserver {
  public:
    explicit MasterChecks(const esc::Segment& seg);

    void on_request(ConstBytes frame, std::uint64_t now_ns) override;
    void on_reply(ConstBytes frame, std::uint64_t now_ns) override;

    const std::vector<Finding>& findings() const { return findings_; }
    bool failed(Rule r) const;
    std::uint64_t frames() const { return frames_; }
    std::size_t slaves() const { return seg_.size(); }

  private:
    // What the checks remember of one slave.
    struct Track {
        protocol::SiiInfo sii;                  // parsed once from the slave's EEPROM
        protocol::WriteMaskTable write_mask{};  // which register bytes EtherCAT may write
        int requested = -1;                     // the state last requested in AL control (-1: none yet)
        bool request_unread = false;            // ... and its outcome not read from AL status since
        std::uint64_t outputs_at_safeop = 0;    // output SyncManager writes when SAFEOP was requested
        bool safeop_requested = false;
        std::uint8_t mailbox_counter = 0;  // of the last mailbox request the slave took
        std::uint32_t mailbox_hash = 0;    // ... and a hash of its content (a repeat is the same)
        bool eeprom_assigned = false;      // the master wrote 0x0500
        std::uint64_t output_writes = 0;   // output SyncManager writes last seen
        std::uint64_t last_output_ns = 0;  // when they last grew while the slave was in OP
        // Checks a request leaves for after its frame (the frame may carry what they look at).
        bool mailbox_check_pending = false;   // PREOP requested from INIT
        bool safeop_check_pending = false;    // SAFEOP requested from PREOP
        bool op_check_pending = false;        // OP requested from SAFEOP
        bool sync_pending = false;            // SYNC0 activated (0x0981)
        std::uint64_t sync_request_ns = 0;    // ... at this time
        std::uint64_t drift_before_sync = 0;  // ... after this many drift compensation datagrams
    };

    // The slaves a datagram addresses at the time of the request (physical and broadcast commands).
    template <class F>
    void for_each_addressed(protocol::DatagramView d, F&& f) const;
    // Output SyncManager of slave i (buffered, written by EtherCAT, enabled), or -1.
    int output_sm(std::size_t i) const;

    void check_write(std::size_t i, protocol::DatagramView d, std::uint64_t now_ns);
    void check_al_control(std::size_t i, std::uint8_t control);
    void check_safeop_configuration(std::size_t i);
    void check_mailbox_configuration(std::size_t i);
    void check_op_outputs(std::size_t i);
    void check_sync_activation(std::size_t i);
    void check_mailbox_request(std::size_t i, protocol::DatagramView d);
    void check_cycle(std::size_t i, std::uint64_t now_ns);

    void find(Rule r, std::size_t slave, std::string message);
    bool found(Rule r, std::size_t slave);  // counts it when already found; true then

    // A fresh track for the slave at position i, from its EEPROM and register counts.
    Track track_of(std::size_t i) const;
    // The slaves changed (restarted, or moved by hot connect: Segment::slaves_epoch): each track follows its
    // slave to its position; a slave that is new (restarted, plugged back) starts a fresh one.
    void follow_slaves();

    const esc::Segment& seg_;
    std::vector<Track> track_;
    std::vector<const esc::Slave*> slave_of_;  // per track: the slave it belongs to
    std::uint64_t slaves_epoch_ = 0;
    std::vector<Finding> findings_;
    std::array<std::uint8_t, protocol::kMaxEthFrame> buf_{};
    std::uint64_t frames_ = 0;
    std::uint64_t first_ns_ = 0;
    std::uint64_t now_ns_ = 0;
    std::uint64_t drift_frames_ = 0;  // ARMW/FRMW of the system time (0x0910) seen
};

// The report as JUnit XML (one test case per rule; a finding fails it) and as lines for a terminal.
std::string junit_xml(const MasterChecks& c);
std::string summary(const MasterChecks& c);

}  // namespace vecat::report
