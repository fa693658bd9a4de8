// The slave side of the mailbox (ETG.1000.4 5.6): where a mailbox protocol of the slave application answers.
// The wire layout (header, types, error codes) is in protocol/mailbox.hpp.
#pragma once

#include <cstddef>

#include "common/bytes.hpp"
#include "protocol/al_status.hpp"
#include "protocol/mailbox.hpp"

namespace vecat::esc {

// Where a protocol handler puts its answer. The payload excludes the 6-byte mailbox header.
class MailboxReplySink {
  public:
    virtual ~MailboxReplySink() = default;
    // Space for one reply payload of at most max_payload() bytes; commit() sends it.
    virtual Bytes reply_buffer() = 0;
    virtual void commit(protocol::MailboxType type, std::size_t payload_len) = 0;
    // True when a commit() now would be queued (not dropped).
    virtual bool can_commit() const = 0;
    // Replies committed but not yet read by the master.
    virtual std::size_t pending() const = 0;
    std::size_t max_payload() { return reply_buffer().size(); }
};

// A mailbox protocol served by the slave application (CoE, FoE, ...).
class MailboxProtocol {
  public:
    virtual ~MailboxProtocol() = default;
    virtual protocol::MailboxType type() const = 0;
    // Handles one request. Must answer through the sink (data, abort or mailbox error), never silently.
    virtual void handle(const protocol::MailboxHeader& h, ConstBytes payload, MailboxReplySink& out) = 0;
    // Called while the slave is running so a protocol can send unsolicited messages (emergencies).
    virtual void poll(MailboxReplySink&) {}
    // Whether poll() may have something to send now (false lets the firmware skip it). A protocol that
    // sends from poll() says so here.
    virtual bool has_output() const { return false; }
    // The mailbox was reset (state INIT or BOOT): forget transfers in progress.
    virtual void reset() {}
    // Served in the BOOT state too. ETG.1000.6 6.4 (the BOOT state): only FoE runs there (the bootloader);
    // a request of any other protocol there gets the mailbox error "unsupported protocol".
    virtual bool served_in_boot() const { return false; }
    // The AL state changed (after reset() when the mailbox was reset).
    virtual void on_state_change(protocol::AlState /*from*/, protocol::AlState /*to*/) {}
};

}  // namespace vecat::esc
