// The master side of the mailbox and of CoE: SDO upload/download (expedited, normal, segmented,
// complete access), SDO information and emergency collection, over the project's Master.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/bytes.hpp"
#include "master/master.hpp"
#include "protocol/coe.hpp"
#include "protocol/mailbox.hpp"
#include "protocol/sdo_abort.hpp"

namespace vecat::master {

struct MailboxMessage {
    protocol::MailboxHeader header;
    std::vector<std::uint8_t> payload;  // header.length bytes after the 6-byte header
};

struct SdoResult {
    bool transport_ok = false;  // a reply came at all
    protocol::SdoAbort abort = protocol::SdoAbort::None;
    std::vector<std::uint8_t> data;  // uploaded value
    std::uint8_t command = 0;        // command byte of the (first) response, for layout checks
    bool ok() const { return transport_ok && abort == protocol::SdoAbort::None; }
};

struct ObjectInfo {
    std::uint16_t index = 0;
    std::uint16_t data_type = 0;
    std::uint8_t max_subindex = 0;
    std::uint8_t object_code = 0;
    std::string name;
};

struct EntryInfo {
    std::uint16_t index = 0;
    std::uint8_t subindex = 0;
    std::uint8_t value_info = 0;
    std::uint16_t data_type = 0;
    std::uint16_t bit_length = 0;
    std::uint16_t access = 0;
    std::vector<std::uint8_t> values;  // default/min/max as requested, concatenated
    std::string name;
};

class CoeClient {
  public:
    CoeClient(Master& m, std::uint16_t station);

    // Mailbox level: writes one message into SM0 (waits while it is full) / reads one from SM1.
    bool send(protocol::MailboxType type, ConstBytes payload, std::uint8_t counter);
    std::optional<MailboxMessage> receive(std::chrono::milliseconds timeout = std::chrono::milliseconds(700));
    // Sends and waits for the reply; emergencies that arrive in between are collected.
    std::optional<MailboxMessage> request(protocol::MailboxType type, ConstBytes payload,
                                          std::chrono::milliseconds timeout = std::chrono::milliseconds(700));
    std::uint8_t next_counter();
    // The mailbox repeat (ETG.1000.4 5.6.3; ESC datasheet section II 0x0806/0x0807): a reply lost on its way
    // to the master is asked for again. Toggles the repeat request bit of SM1's activate register and waits
    // until the slave acknowledges it in SM1's PDI control register, having written its last reply into
    // SM1 again; receive() then reads it. False when no acknowledge came within timeout.
    bool repeat(std::chrono::milliseconds timeout = std::chrono::milliseconds(100));

    SdoResult upload(std::uint16_t index, std::uint8_t sub, bool complete = false);
    // Chooses expedited (<= 4 bytes), normal or segmented transfer by size unless forced.
    enum class Transfer { Auto, Expedited, Normal, Segmented };
    SdoResult download(std::uint16_t index, std::uint8_t sub, ConstBytes data, bool complete = false,
                       Transfer how = Transfer::Auto);
    template <class T>
    SdoResult download_value(std::uint16_t index, std::uint8_t sub, T v) {
        std::uint8_t b[sizeof(T)];
        for (std::size_t i = 0; i < sizeof(T); ++i)
            b[i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * i));
        return download(index, sub, ConstBytes(b, sizeof(T)));
    }

    // SDO information. nullopt on transport errors or an SDO info error (then last_abort() says which).
    std::optional<std::vector<std::uint16_t>> od_list(std::uint16_t list_type);
    std::optional<ObjectInfo> object_description(std::uint16_t index);
    std::optional<EntryInfo> entry_description(std::uint16_t index, std::uint8_t sub,
                                               std::uint8_t value_info);
    protocol::SdoAbort last_abort() const { return last_abort_; }
    int last_fragments() const { return last_fragments_; }

    std::vector<protocol::Emergency>& emergencies() { return emergencies_; }
    std::size_t mailbox_size_out() const { return sm0_len_; }
    std::size_t mailbox_size_in() const { return sm1_len_; }

  private:
    std::optional<MailboxMessage> info_request(std::uint8_t opcode, ConstBytes args, std::size_t min_len);
    Master& m_;
    std::uint16_t station_;
    std::uint16_t sm0_ = 0, sm0_len_ = 0, sm1_ = 0, sm1_len_ = 0;
    std::uint8_t own_counter_ = 0;
    std::uint8_t* counter_ = &own_counter_;  // the slave's counter in the master's list when known
    std::vector<protocol::Emergency> emergencies_;
    protocol::SdoAbort last_abort_ = protocol::SdoAbort::None;
    int last_fragments_ = 0;
};

}  // namespace vecat::master
