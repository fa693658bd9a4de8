// The master side of FoE (ETG.1000.6 5.8): read and write a file, with packet numbers and busy, over the
// mailbox of the project's Master (CoeClient's mailbox level), on the wire layout of protocol/foe.hpp. And
// the BOOT state's mailbox: SM0/SM1 from the SII's bootstrap mailbox words (0x0014-0x0017), as SOEM's
// firm_update does.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "protocol/foe.hpp"
#include "protocol/mailbox.hpp"

namespace vecat::master {

struct FoeResult {
    bool transport_ok = false;                            // every request got a reply
    std::optional<protocol::FoeError> error;              // the slave answered with this FoE error
    std::string error_text;                               // ... and this text
    std::optional<protocol::MailboxError> mailbox_error;  // the slave answered with a mailbox error
    bool unexpected = false;         // an answer FoE does not allow here (wrong opcode/number)
    std::vector<std::uint8_t> data;  // read: the file
    unsigned packets = 0;            // data packets sent or received
    unsigned busy = 0;               // busy answers seen
    bool ok() const { return transport_ok && !error && !mailbox_error && !unexpected; }
};

class FoeClient {
  public:
    // The slave's mailbox as configured now (SM0/SM1 read from the ESC, as CoeClient).
    FoeClient(Master& m, std::uint16_t station);

    FoeResult read(std::string_view name, std::uint32_t password = 0, std::size_t max_size = 8u << 20);
    FoeResult write(std::string_view name, ConstBytes data, std::uint32_t password = 0);

    // The mailbox level, for tests that send messages of their own.
    CoeClient& mailbox() { return mbx_; }

    // How long one answer may take (a slave programming flash takes a while).
    std::chrono::milliseconds timeout{700};
    // Busy answers taken before a write gives up.
    unsigned max_busy = 100;

  private:
    // Sends one FoE message and waits for the answer; fills r.transport_ok/mailbox_error.
    std::optional<protocol::FoeMessage> exchange(ConstBytes request, FoeResult& r);
    std::optional<protocol::FoeMessage> answer(FoeResult& r);
    CoeClient mbx_;
    std::optional<MailboxMessage> last_;  // the message last received (FoeMessage views point into it)
};

// SM0/SM1 of a slave as the SII's bootstrap mailbox (words 0x0014-0x0017), with the control bytes of its SII
// SyncM category, each disabled before it is written (the ESC ignores a new configuration of an enabled SM).
// False without bootstrap mailbox.
bool configure_boot_mailbox(Master& m, const SlaveInfo& s);

}  // namespace vecat::master
