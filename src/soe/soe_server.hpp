// The SoE server of a slave (ETG.1000.6 5.6, Servo drive profile over EtherCAT): read and write requests
// of IDN elements for each drive of the device, segmented transfers both ways (the incomplete flag with
// the fragments left), the SoE error codes, and notifications of a procedure command's data state. What
// each case answers: src/soe/README.md.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "esc/mailbox.hpp"
#include "protocol/soe.hpp"
#include "soe/idn_table.hpp"

namespace vecat::soe {

// What the server serves: the IDN tables of the device's drives and what writing a value means.
class SoeDevice {
  public:
    virtual ~SoeDevice() = default;
    // Drives 0 .. drives()-1 (a request for another: 0x800A "invalid drive number").
    virtual unsigned drives() const = 0;
    virtual IdnTable& table(unsigned drive) = 0;
    // The communication phase: PREOP = CP2, SAFEOP = CP3, OP = CP4 (write protection of the attribute).
    virtual protocol::AlState phase() const = 0;
    // Makes a value current before it is read (feedback values, S-0-0017).
    virtual void refresh(unsigned /*drive*/, IdnEntry& /*e*/) {}
    // A write of the value that passed the checks every IDN gets (IdnTable::check_write): the drive's own
    // checks, then it stores value (a list: its elements) and acts on it. nullopt: accepted.
    virtual std::optional<SoeError> write_value(unsigned drive, IdnEntry& e, ConstBytes value) = 0;
    // A notification to send (ETG.1000.6 5.6: the data state of a procedure command changed); false when
    // none waits.
    virtual bool take_notification(unsigned& /*drive*/, Idn& /*idn*/) { return false; }
    virtual bool has_notification() const { return false; }
};

struct SoeCounters {
    std::uint64_t reads = 0;               // read requests answered with data
    std::uint64_t writes = 0;              // write requests accepted
    std::uint64_t errors_sent = 0;         // SoE error responses
    std::uint64_t fragments_sent = 0;      // read response fragments with the incomplete flag
    std::uint64_t fragments_received = 0;  // write request fragments with the incomplete flag
    std::uint64_t notifications_sent = 0;
    std::uint64_t transfers_abandoned = 0;  // a segmented read or write ended by another request or a reset
};

class SoeServer final : public esc::MailboxProtocol {
  public:
    // Largest write the server takes, all fragments together (4 KiB: more than any IDN of the drives
    // vecat emulates holds; a longer transfer is answered 0x7003 "too long" at its last fragment).
    static constexpr std::size_t kMaxTransfer = 4096 + protocol::kSoeListHeaderSize;

    explicit SoeServer(SoeDevice& device) : device_(device) {}

    protocol::MailboxType type() const override { return protocol::MailboxType::SoE; }
    void handle(const protocol::MailboxHeader& h, ConstBytes payload, esc::MailboxReplySink& out) override;
    void poll(esc::MailboxReplySink& out) override;
    bool has_output() const override { return fragments_pending() || device_.has_notification(); }
    void reset() override;

    const SoeCounters& counters() const { return counters_; }
    // Bytes held for a segmented transfer in progress (a read's response or a write's fragments).
    std::size_t buffered() const { return read_buf_.size() + write_buf_.size(); }
    bool fragments_pending() const { return read_off_ < read_buf_.size(); }
    // Whether notifications are sent (on by default).
    void set_notifications(bool on) { notifications_ = on; }

  private:
    void read(const protocol::SoeMessage& m, esc::MailboxReplySink& out);
    void write(const protocol::SoeMessage& m, esc::MailboxReplySink& out);
    void send_fragment(esc::MailboxReplySink& out);
    void error(protocol::SoeOpCode response, const protocol::SoeMessage& m, SoeError e,
               esc::MailboxReplySink& out, std::uint16_t idn);
    void end_read();
    void end_write(bool abandoned = true);  // false: the transfer ended with its last fragment

    SoeDevice& device_;
    SoeCounters counters_;
    bool notifications_ = true;
    // A segmented read: the whole response, what was sent of it, and its header fields.
    std::vector<std::uint8_t> read_buf_;
    std::size_t read_off_ = 0;
    std::uint8_t read_drive_ = 0, read_elements_ = 0;
    std::uint16_t read_idn_ = 0;
    // A segmented write: the fragments so far (at most kMaxTransfer; past it only counted).
    bool writing_ = false;
    bool write_overflow_ = false;
    std::uint8_t write_drive_ = 0, write_elements_ = 0;
    std::vector<std::uint8_t> write_buf_;
    std::vector<std::uint8_t> scratch_;  // a read's elements before they are sent
};

}  // namespace vecat::soe
