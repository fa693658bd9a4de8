// The FoE server of a slave (ETG.1000.6 5.8, File access over EtherCAT) and its bootloader: read and write
// requests with file name and password, data and acknowledge with packet numbers, busy, and the FoE error
// codes; in the BOOT state the firmware file, applied on BOOT -> INIT (the revision in the SII and 0x1018
// changes). What is allowed in which state, and which error each case gets: src/foe/README.md.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "esc/mailbox.hpp"
#include "esc/segment.hpp"
#include "esc/slave.hpp"
#include "foe/file_store.hpp"
#include "foe/firmware.hpp"
#include "protocol/foe.hpp"

namespace vecat::foe {

struct FoeOptions {
    std::string dir;  // files of slave N in dir/slave-N; empty: in memory
    // Largest file written or read, in bytes. 8 MiB: SOEM's firm_update buffer, more than the firmware of
    // the drives and terminals vecat emulates would have.
    std::size_t max_file_size = 8u << 20;
    // The password every request must carry (0: none, as most devices). A wrong one: 0x800A "no rights".
    std::uint32_t password = 0;
    // The first data packet of a firmware write is answered BUSY once ("erasing flash"; the master sends
    // it again), as bootloaders that erase before they program do.
    bool busy_on_erase = true;
};

struct FoeCounters {
    std::uint64_t reads = 0;             // read requests accepted
    std::uint64_t writes = 0;            // write requests accepted
    std::uint64_t files_written = 0;     // write transfers completed
    std::uint64_t files_read = 0;        // read transfers completed
    std::uint64_t errors_sent = 0;       // FoE error answers
    std::uint64_t busy_sent = 0;         // BUSY answers
    std::uint64_t firmware_updates = 0;  // revisions applied on BOOT -> INIT
};

// The state of the server: one transfer at a time. ETG.1000.6 5.8: a read is answered with DATA packets,
// each acknowledged; a write with ACK 0, then each DATA packet with its ACK. A packet shorter than a full
// mailbox ends the file.
enum class FoeState : std::uint8_t { Idle, Reading, Writing };

class FoeServer final : public esc::MailboxProtocol {
  public:
    FoeServer(esc::Slave& slave, FoeOptions options, std::string dir);

    protocol::MailboxType type() const override { return protocol::MailboxType::FoE; }
    void handle(const protocol::MailboxHeader& h, ConstBytes payload, esc::MailboxReplySink& out) override;
    void reset() override;
    bool served_in_boot() const override { return true; }
    void on_state_change(protocol::AlState from, protocol::AlState to) override;

    FoeState state() const { return state_; }
    const FoeCounters& counters() const { return counters_; }
    const FileStore& store() const { return store_; }
    // Bytes of the transfer in progress held in memory (at most max_file_size).
    std::size_t buffered() const { return buf_.size(); }
    // The revision a firmware file received in BOOT will set on BOOT -> INIT.
    std::optional<std::uint32_t> pending_revision() const { return pending_revision_; }

  private:
    void start_read(std::uint32_t password, std::string_view name, esc::MailboxReplySink& out);
    void start_write(std::uint32_t password, std::string_view name, esc::MailboxReplySink& out);
    void take_data(std::uint32_t packet, ConstBytes data, esc::MailboxReplySink& out);
    void take_ack(std::uint32_t packet, esc::MailboxReplySink& out);
    void finish_write(esc::MailboxReplySink& out);
    void send_data(esc::MailboxReplySink& out);
    // Checks shared by read and write: the name, the state (firmware only in BOOT), the password.
    std::optional<protocol::FoeError> check_request(std::uint32_t password, std::string_view name,
                                                    bool firmware) const;
    void error(protocol::FoeError e, esc::MailboxReplySink& out, std::string_view text = {});
    void idle();
    // Data a packet of the master carries at most: the SM0 length less the two headers.
    std::size_t receive_capacity() const;

    esc::Slave& slave_;
    FoeOptions options_;
    FileStore store_;
    FoeState state_ = FoeState::Idle;
    std::string name_;
    bool firmware_ = false;
    bool busy_pending_ = false;
    std::uint32_t packet_ = 0;       // last packet sent (read) or acknowledged (write)
    std::size_t offset_ = 0;         // read: bytes sent before the last packet
    std::size_t last_len_ = 0;       // read: data bytes of the last packet sent
    bool last_sent_ = false;         // read: the last packet sent was the file's last
    int sm_out_ = -1;                // the SyncManager the master writes (SM0)
    std::vector<std::uint8_t> buf_;  // the file being read or written (at most max_file_size)
    std::optional<std::uint32_t> pending_revision_;
    FoeCounters counters_;
};

// Gives every slave of the segment whose device declares FoE (mailbox protocols word, ESI <FoE/>) an FoE
// server: files of slave N in options.dir/slave-N (in memory without a directory). Returns how many.
std::size_t attach_foe(esc::Segment& seg, const FoeOptions& options);
// The FoE server of a slave, nullptr when it has none.
FoeServer* foe_server(esc::Slave& slave);

}  // namespace vecat::foe
