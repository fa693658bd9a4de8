// The CoE mailbox protocol of a slave: SDO server (expedited, normal, segmented, complete access), SDO
// information (OD list, object and entry descriptions, fragmented) and emergency messages.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <variant>
#include <vector>

#include "coe/object_dictionary.hpp"
#include "esc/mailbox.hpp"
#include "protocol/coe.hpp"

namespace vecat::coe {

struct CoeCounters {
    std::uint64_t sdo_uploads = 0;
    std::uint64_t sdo_downloads = 0;
    std::uint64_t sdo_aborts_sent = 0;
    std::uint64_t sdo_aborts_received = 0;
    std::uint64_t info_requests = 0;
    std::uint64_t emergencies_sent = 0;
    std::uint64_t emergencies_dropped = 0;
};

// The SDO server of one slave. It serves one transfer at a time, the state below: a segmented upload or
// download (ETG.1000.6 5.6.2.3-5.6.2.6) or a fragmented SDO information response (5.6.3). A new request
// ends the transfer in progress. A transfer the master leaves alone for kSdoTimeoutNs is dropped (CiA 301
// 7.2.4.3: the SDO protocol timeout, abort code 0x05040000); a late segment request is then answered with
// that abort.
// On a cache line of its own, as the fields every firmware run asks (has_output: the emergencies and the
// transfer's kind, below) are with the vtable pointer: a run of a large line asks them out of the caches.
class alignas(64) SdoServer final : public esc::MailboxProtocol {
  public:
    // The timeout of a transfer left alone: 1 s, the SDO server timeout real CANopen devices use (the
    // SDOserverTimeoutTime_ms of CANopenNode's configurations); well above a master's time between two
    // segments (each is one mailbox round trip, milliseconds), well below a master's own SDO timeout.
    static constexpr std::uint64_t kSdoTimeoutNs = 1'000'000'000;

    // state tells the current AL state (access rights depend on it).
    SdoServer(ObjectDictionary& od, std::function<AlState()> state);

    protocol::MailboxType type() const override { return protocol::MailboxType::CoE; }
    void handle(const protocol::MailboxHeader& h, ConstBytes payload, esc::MailboxReplySink& out) override;
    void poll(esc::MailboxReplySink& out) override;
    bool has_output() const override {
        return emcy_count_ > 0 || std::holds_alternative<InfoResponse>(transfer_);
    }
    void reset() override;
    // The time (ns, the segment's clock): a transfer left alone for kSdoTimeoutNs is dropped.
    void tick(std::uint64_t now_ns);
    // When tick() has something to do: the timeout of the transfer in progress (0: the tick that starts
    // its clock), ~0 without one.
    std::uint64_t next_deadline_ns() const;

    // Queues an emergency (sent when the reply mailbox is free). False when the queue is full.
    bool emergency(const protocol::Emergency& e);
    const CoeCounters& counters() const { return counters_; }
    bool transfer_in_progress() const {
        return std::holds_alternative<Upload>(transfer_) || std::holds_alternative<Download>(transfer_) ||
               std::holds_alternative<InfoResponse>(transfer_);
    }

    static constexpr std::size_t kEmergencySlots = 8;

    // A device without SDO information (SII CoE details without it, ETG.2010): its requests are answered
    // with the mailbox error "service not supported" (ETG.1000.4 Table 30), as such devices do. A copy of
    // one made by vecat clone is served so. Served by default.
    void set_information_served(bool served) { info_served_ = served; }
    // Quirk sdo_download_echo: the initiate download response repeats the request's data field in its
    // reserved bytes 4-7 (ETG.1000.6 5.6.2) instead of zeros.
    void set_download_echo(bool echo) { download_echo_ = echo; }
    // A device without complete access (SII CoE details bit 5 clear, ETG.2010; quirk no_complete_access):
    // a complete access upload or download is aborted with 0x06010000 "unsupported access to an object"
    // (ETG.1000.6 Table 41), as such devices answer. Served by default.
    void set_complete_access_served(bool served) { complete_access_served_ = served; }

  private:
    struct Idle {};
    struct Upload {
        std::uint16_t index = 0;
        std::uint8_t sub = 0;
        std::size_t total = 0, offset = 0;
        std::uint8_t toggle = 0;
    };
    struct Download {
        bool complete = false;
        std::uint16_t index = 0;
        std::uint8_t sub = 0;
        std::size_t total = 0, received = 0;
        std::uint8_t toggle = 0;
    };
    // A fragmented SDO information response being sent (OD lists).
    struct InfoResponse {
        std::uint8_t opcode = 0;
        std::size_t total = 0, offset = 0;
        std::uint16_t fragments_left = 0;
    };
    // A segmented transfer dropped by the timeout: its next segment request is told so.
    struct TimedOut {
        std::uint16_t index = 0;
        std::uint8_t sub = 0;
    };
    using Transfer = std::variant<Idle, Upload, Download, InfoResponse, TimedOut>;

    // Every change of the transfer goes through here: it restarts the timeout.
    void set_transfer(Transfer t) {
        transfer_ = t;
        quiet_since_ns_ = kNotYet;
    }

    void sdo_request(ConstBytes p, esc::MailboxReplySink& out);
    void initiate_download(const protocol::SdoHeader& h, ConstBytes p, esc::MailboxReplySink& out);
    void download_segment(std::uint8_t cmd, ConstBytes p, esc::MailboxReplySink& out);
    void initiate_upload(const protocol::SdoHeader& h, esc::MailboxReplySink& out);
    void upload_segment(std::uint8_t cmd, esc::MailboxReplySink& out);
    template <class T>
    T* segment_acceptable(std::uint8_t cmd, esc::MailboxReplySink& out);
    void abort(std::uint16_t index, std::uint8_t sub, SdoAbort code, esc::MailboxReplySink& out);

    void sdo_info(ConstBytes p, esc::MailboxReplySink& out);
    void info_error(SdoAbort code, esc::MailboxReplySink& out);
    void od_list(std::uint16_t list_type, esc::MailboxReplySink& out);
    void object_description(std::uint16_t index, esc::MailboxReplySink& out);
    void entry_description(std::uint16_t index, std::uint8_t sub, std::uint8_t value_info,
                           esc::MailboxReplySink& out);
    bool send_info_fragment(esc::MailboxReplySink& out);

    // What each firmware run asks (has_output, tick) first, together: a line of hundreds of drives asks it
    // out of the caches.
    std::size_t emcy_count_ = 0, emcy_head_ = 0;
    Transfer transfer_ = Idle{};
    // Since when the transfer has not moved: set by the first tick() after a change (the server has no
    // clock of its own), so that a transfer is dropped kSdoTimeoutNs after its last request at the latest.
    static constexpr std::uint64_t kNotYet = ~std::uint64_t{0};
    std::uint64_t quiet_since_ns_ = kNotYet;
    ObjectDictionary& od_;
    std::function<AlState()> state_;
    std::vector<std::uint8_t> buf_;  // transfer buffer, sized once from the dictionary
    std::vector<std::uint8_t> info_buf_;
    bool info_served_ = true;
    bool complete_access_served_ = true;
    bool download_echo_ = false;

    std::array<protocol::Emergency, kEmergencySlots> emcy_{};
    CoeCounters counters_;
};

}  // namespace vecat::coe
