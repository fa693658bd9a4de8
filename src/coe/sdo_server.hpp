// The CoE mailbox protocol of a slave: SDO server (expedited, normal, segmented, complete access), SDO
// information (OD list, object and entry descriptions, fragmented) and emergency messages.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
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

class SdoServer final : public esc::MailboxProtocol {
  public:
    // state tells the current AL state (access rights depend on it).
    SdoServer(ObjectDictionary& od, std::function<AlState()> state);

    protocol::MailboxType type() const override { return protocol::MailboxType::CoE; }
    void handle(const protocol::MailboxHeader& h, ConstBytes payload, esc::MailboxReplySink& out) override;
    void poll(esc::MailboxReplySink& out) override;
    void reset() override;

    // Queues an emergency (sent when the reply mailbox is free). False when the queue is full.
    bool emergency(const protocol::Emergency& e);
    const CoeCounters& counters() const { return counters_; }
    bool transfer_in_progress() const { return up_.active || down_.active || info_.active; }

    static constexpr std::size_t kEmergencySlots = 8;

  private:
    void sdo_request(ConstBytes p, esc::MailboxReplySink& out);
    void initiate_download(std::uint8_t cmd, std::uint16_t index, std::uint8_t sub, ConstBytes p,
                           esc::MailboxReplySink& out);
    void download_segment(std::uint8_t cmd, ConstBytes p, esc::MailboxReplySink& out);
    void initiate_upload(std::uint8_t cmd, std::uint16_t index, std::uint8_t sub, esc::MailboxReplySink& out);
    void upload_segment(std::uint8_t cmd, esc::MailboxReplySink& out);
    template <class Transfer>
    bool segment_acceptable(Transfer& t, std::uint8_t cmd, esc::MailboxReplySink& out);
    void abort(std::uint16_t index, std::uint8_t sub, SdoAbort code, esc::MailboxReplySink& out);

    void sdo_info(ConstBytes p, esc::MailboxReplySink& out);
    void info_error(SdoAbort code, esc::MailboxReplySink& out);
    void od_list(std::uint16_t list_type, esc::MailboxReplySink& out);
    void object_description(std::uint16_t index, esc::MailboxReplySink& out);
    void entry_description(std::uint16_t index, std::uint8_t sub, std::uint8_t value_info,
                           esc::MailboxReplySink& out);
    bool send_info_fragment(esc::MailboxReplySink& out);

    ObjectDictionary& od_;
    std::function<AlState()> state_;
    std::vector<std::uint8_t> buf_;  // transfer buffer, sized once from the dictionary

    struct Upload {
        bool active = false;
        std::uint16_t index = 0;
        std::uint8_t sub = 0;
        std::size_t total = 0, offset = 0;
        std::uint8_t toggle = 0;
    } up_;
    struct Download {
        bool active = false;
        bool complete = false;
        std::uint16_t index = 0;
        std::uint8_t sub = 0;
        std::size_t total = 0, received = 0;
        std::uint8_t toggle = 0;
    } down_;
    // A fragmented SDO information response being sent (OD lists).
    struct Info {
        bool active = false;
        std::uint8_t opcode = 0;
        std::size_t total = 0, offset = 0;
        std::uint16_t fragments_left = 0;
    } info_;
    std::vector<std::uint8_t> info_buf_;

    std::array<protocol::Emergency, kEmergencySlots> emcy_{};
    std::size_t emcy_head_ = 0, emcy_count_ = 0;
    CoeCounters counters_;
};

}  // namespace vecat::coe
