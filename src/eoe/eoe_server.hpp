// The EoE server of a slave (ETG.1000.6 5.7, Ethernet over EtherCAT): Ethernet frames from the master in
// fragments, reassembled in one bounded buffer; frames to the master fragmented to the mailbox size; the
// set/get IP parameter and set/get address filter services with their result codes; the device's own
// small IP stack (ARP and ICMP echo for the address the master set, src/eoe/ip_responder.hpp); and the
// device's Ethernet side (an EthernetPort, e.g. a TAP interface: src/eoe/tap.hpp) that gets every frame not
// for the device itself and whose frames go to the master when the address filter lets them pass. What
// each case answers: src/eoe/README.md.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "esc/mailbox.hpp"
#include "esc/segment.hpp"
#include "esc/slave.hpp"
#include "protocol/eoe.hpp"

namespace vecat::eoe {

struct EoeOptions {
    // The device has an IP stack: set/get IP parameter work. false: both answer 0x0201 "no IP support".
    bool ip_support = true;
    // The device filters frames to the master: set/get address filter work. false: 0x0401 "no filter
    // support".
    bool filter_support = true;
    // Frames waiting to go to the master (from the Ethernet side and the device's own answers); more are
    // dropped and counted. The memory is taken at construction.
    std::size_t queue_frames = 16;
};

struct EoeCounters {
    std::uint64_t fragments_in = 0;   // fragments from the master taken into a frame
    std::uint64_t frames_in = 0;      // complete frames from the master
    std::uint64_t fragments_out = 0;  // fragments sent to the master
    std::uint64_t frames_out = 0;     // complete frames sent to the master
    std::uint64_t to_ethernet = 0;    // frames from the master passed to the Ethernet side
    std::uint64_t no_ethernet = 0;    // frames from the master for others, with no Ethernet side attached
    std::uint64_t from_ethernet = 0;  // frames from the Ethernet side queued for the master
    std::uint64_t arp_replies = 0;    // the device's own answers
    std::uint64_t echo_replies = 0;
    // Dropped fragments and frames (each counted once):
    std::uint64_t out_of_sequence = 0;  // a fragment that is not the next of the frame (gap, overlap, other
                                        // frame number): answered with mailbox error 0x0005
    std::uint64_t oversize = 0;         // a frame larger than the buffer, or data past the announced size
    std::uint64_t incomplete = 0;       // half frames given up (a new frame began, the mailbox was reset)
    std::uint64_t filtered = 0;         // frames from the Ethernet side the address filter kept back
    std::uint64_t queue_full = 0;       // frames for the master that found the queue full
    std::uint64_t not_running = 0;      // frames from the Ethernet side while the mailbox does not run, and
                                        // frames still queued when the mailbox was reset
    std::uint64_t results_sent = 0;     // service responses with a result other than success
    std::uint64_t mailbox_errors = 0;   // mailbox error answers (ETG.1000.4 Table 30)
};

// Where the frames for the device's Ethernet side go (a TAP interface, a test).
class EthernetPort {
  public:
    virtual ~EthernetPort() = default;
    // Sends one Ethernet frame (without FCS); must not block.
    virtual void send(ConstBytes frame) = 0;
};

class EoeServer final : public esc::MailboxProtocol {
  public:
    // mac: the device's MAC address until the master sets one (set IP parameter with MAC).
    EoeServer(esc::Slave& slave, EoeOptions options, protocol::MacAddress mac);

    protocol::MailboxType type() const override { return protocol::MailboxType::EoE; }
    void handle(const protocol::MailboxHeader& h, ConstBytes payload, esc::MailboxReplySink& out) override;
    void poll(esc::MailboxReplySink& out) override;
    bool has_output() const override { return q_count_ > 0; }
    void reset() override;

    // The device's Ethernet side (nullptr: none; frames for others are then dropped and counted).
    void attach(EthernetPort* port) { port_ = port; }
    // A frame from the device's Ethernet side: queued for the master when the address filter lets it
    // pass. False when dropped (filtered, too large, queue full, mailbox not running).
    bool from_ethernet(ConstBytes frame);

    const protocol::MacAddress& mac() const { return params_.mac.value(); }
    const protocol::EoeIpParameters& ip_parameters() const { return params_; }
    // The address filter the master set (nullopt: none set, every frame passes).
    const std::optional<protocol::EoeAddressFilter>& filter() const { return filter_; }
    const EoeCounters& counters() const { return counters_; }
    // Bytes of the frame being reassembled (at most the buffer's size).
    std::size_t reassembling() const { return rx_len_; }
    std::size_t queued() const { return q_count_; }
    // The reassembly buffer: the largest Ethernet frame rounded up to whole blocks, and a time stamp.
    static constexpr std::size_t kRxBufferSize =
        protocol::eoe_size_blocks(protocol::kEthernetMaxFrame) * protocol::kEoeBlockSize +
        protocol::kEoeTimestampSize;

  private:
    void take_fragment(const protocol::EoeHeader& h, ConstBytes data, esc::MailboxReplySink& out);
    void deliver(ConstBytes frame);  // a whole frame from the master
    void set_ip(const protocol::EoeHeader& h, ConstBytes block, esc::MailboxReplySink& out);
    void get_ip(const protocol::EoeHeader& h, esc::MailboxReplySink& out);
    void set_filter(const protocol::EoeHeader& h, ConstBytes block, esc::MailboxReplySink& out);
    void get_filter(const protocol::EoeHeader& h, esc::MailboxReplySink& out);
    void respond(protocol::EoeFrameType type, std::uint8_t port, protocol::EoeResult r,
                 esc::MailboxReplySink& out, ConstBytes block = {});
    void mailbox_error(protocol::MailboxError e, esc::MailboxReplySink& out);
    bool enqueue(ConstBytes frame);
    void drop_rx();   // forgets the half frame
    void clear_rx();  // after a whole frame

    esc::Slave& slave_;
    EoeOptions options_;
    EthernetPort* port_ = nullptr;
    protocol::EoeIpParameters params_;
    std::optional<protocol::EoeAddressFilter> filter_;
    EoeCounters counters_;

    // Reassembly of the frame from the master (one at a time, ETG.1000.6 5.7: fragments in order).
    std::array<std::uint8_t, kRxBufferSize> rx_{};
    std::size_t rx_len_ = 0;     // bytes received so far
    std::size_t rx_size_ = 0;    // the complete size announced by fragment 0 (whole blocks)
    std::uint8_t rx_next_ = 0;   // the fragment number expected next (0: no frame in progress)
    std::uint8_t rx_frame_ = 0;  // the frame number of the frame in progress

    // Frames to the master: a ring of fixed slots, the head one being sent in fragments.
    std::vector<std::array<std::uint8_t, protocol::kEthernetMaxFrame>> q_;
    std::vector<std::uint16_t> q_len_;
    std::size_t q_head_ = 0;
    std::size_t q_count_ = 0;
    std::size_t tx_off_ = 0;        // bytes of the head frame sent
    std::uint8_t tx_fragment_ = 0;  // its next fragment number
    std::uint8_t tx_frame_ = 0;     // the frame number of the head frame (1..15, then 0 again)
    std::array<std::uint8_t, protocol::kEthernetMaxFrame> answer_{};  // the device's own reply
};

// Gives every slave of the segment whose device declares EoE (mailbox protocols word, ESI <EoE/>) an EoE
// server. Slave N's MAC address until the master sets one: 02:00:00:45:xx:yy with xxyy = N + 1 (locally
// administered). Returns how many.
std::size_t attach_eoe(esc::Segment& seg, const EoeOptions& options = {});
// The EoE server of a slave, nullptr when it has none.
EoeServer* eoe_server(esc::Slave& slave);
// The default MAC address of slave N (see attach_eoe).
protocol::MacAddress default_mac(std::size_t slave_index);

}  // namespace vecat::eoe
