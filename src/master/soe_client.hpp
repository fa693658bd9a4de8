// The master side of SoE (ETG.1000.6 5.6): read and write the elements of an IDN, with segmented transfers
// both ways, over the mailbox of the project's Master (CoeClient's mailbox level), on the wire layout of
// protocol/soe.hpp. Notifications the slave sends in between are collected.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <vector>

#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "protocol/mailbox.hpp"
#include "protocol/soe.hpp"

namespace vecat::master {

struct SoeNotification {
    std::uint8_t drive = 0;
    protocol::Idn idn;
    std::uint16_t data_state = 0;
};

struct SoeResult {
    bool transport_ok = false;                            // every request got a reply
    std::optional<std::uint16_t> error;                   // the slave answered with this SoE error code
    std::optional<protocol::MailboxError> mailbox_error;  // the slave answered with a mailbox error
    bool unexpected = false;                              // an answer that does not belong to the request
    std::vector<std::uint8_t> data;                       // read: the elements, all fragments together
    unsigned fragments = 0;  // fragments with the incomplete flag sent (write) or received (read)
    bool ok() const { return transport_ok && !error && !mailbox_error && !unexpected; }
};

class SoeClient {
  public:
    // The slave's mailbox as configured now (SM0/SM1 read from the ESC, as CoeClient).
    SoeClient(Master& m, std::uint16_t station);

    SoeResult read(std::uint8_t drive, std::uint8_t elements, protocol::Idn idn,
                   std::size_t max_size = 65536);
    // Fragments (the incomplete flag, fragments still to come) when data does not fit one mailbox.
    SoeResult write(std::uint8_t drive, std::uint8_t elements, protocol::Idn idn, ConstBytes data);
    // Waits for a notification (those collected so far first).
    std::optional<SoeNotification> notification(std::chrono::milliseconds timeout);

    CoeClient& mailbox() { return mbx_; }
    std::vector<SoeNotification>& notifications() { return notifications_; }
    std::chrono::milliseconds timeout{700};

  private:
    // The next SoE message that is not a notification; fills r on errors.
    std::optional<protocol::SoeMessage> answer(SoeResult& r);
    CoeClient mbx_;
    std::optional<MailboxMessage> last_;  // SoeMessage::data points into it
    std::vector<SoeNotification> notifications_;
};

}  // namespace vecat::master
