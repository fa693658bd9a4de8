// The master side of EoE (ETG.1000.6 5.7): Ethernet frames sent to a slave in fragments and received from
// it reassembled, the set/get IP parameter and set/get address filter services, over the mailbox of the
// project's Master (CoeClient's mailbox level), on the wire layout of protocol/eoe.hpp. Frames that arrive
// while a service waits for its response are kept for receive_frame().
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "protocol/eoe.hpp"
#include "protocol/mailbox.hpp"

namespace vecat::master {

struct EoeServiceResult {
    bool transport_ok = false;                            // the request went out and a response came
    std::optional<protocol::MailboxError> mailbox_error;  // the slave answered with a mailbox error
    std::optional<std::uint16_t> result;                  // the EoE result code of the response
    bool unexpected = false;                              // a response of another type or malformed
    std::optional<protocol::EoeIpParameters> ip;          // get IP parameter: what the slave has
    std::optional<protocol::EoeAddressFilter> filter;     // get address filter: what the slave has
    bool ok() const { return transport_ok && !mailbox_error && !unexpected && result == std::uint16_t{0}; }
};

class EoeClient {
  public:
    // The slave's mailbox as configured now (SM0/SM1 read from the ESC, as CoeClient).
    EoeClient(Master& m, std::uint16_t station);

    // Sends one Ethernet frame in as many fragments as the mailbox needs (ETG.1000.6 5.7). False when a
    // fragment could not be written or the frame is larger than 63 blocks.
    bool send_frame(ConstBytes frame, std::uint8_t port = 0);
    // The next frame from the slave: one kept from before, else read from the mailbox until a frame is
    // complete or the timeout passes.
    std::optional<std::vector<std::uint8_t>> receive_frame(std::chrono::milliseconds timeout);

    EoeServiceResult set_ip(const protocol::EoeIpParameters& p, std::uint8_t port = 0);
    EoeServiceResult get_ip(std::uint8_t port = 0);
    EoeServiceResult set_filter(const protocol::EoeAddressFilter& f, std::uint8_t port = 0);
    EoeServiceResult get_filter(std::uint8_t port = 0);
    // Any EoE message (for tests that send their own headers): waits for a response of response_type.
    EoeServiceResult service(ConstBytes payload, protocol::EoeFrameType response_type);

    // The mailbox level, for tests that send messages of their own.
    CoeClient& mailbox() { return mbx_; }
    // Mailbox errors that arrived while waiting for frames (a fragment the slave refused).
    std::vector<protocol::MailboxError>& mailbox_errors() { return mailbox_errors_; }
    // Fragments that did not fit the frame being reassembled (dropped, as the slave side does).
    std::uint64_t bad_fragments() const { return bad_fragments_; }

    std::chrono::milliseconds timeout{700};

  private:
    // Takes one message from the mailbox: fragments into the reassembly, mailbox errors into the list.
    // Returns the message when it is neither (a service response).
    std::optional<MailboxMessage> take(std::chrono::milliseconds timeout);
    void take_fragment(const protocol::EoeHeader& h, ConstBytes data);
    CoeClient mbx_;
    std::uint8_t tx_frame_ = 0;
    std::vector<std::uint8_t> rx_;
    std::size_t rx_size_ = 0;
    std::uint8_t rx_next_ = 0;
    std::uint8_t rx_frame_ = 0;
    std::deque<std::vector<std::uint8_t>> frames_;
    std::vector<protocol::MailboxError> mailbox_errors_;
    std::uint64_t bad_fragments_ = 0;
};

}  // namespace vecat::master
