// A small EtherCAT master: the start-up sequence of real masters (see shared/docs/masters-checklist.md),
// used by the tests, the demo and as an example of master code.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/bytes.hpp"
#include "net/link.hpp"
#include "protocol/al_status.hpp"
#include "protocol/frame.hpp"
#include "protocol/sii.hpp"

namespace vecat::master {

struct AlStatusReading {
    std::uint8_t status = 0;  // AL status register (state | error flag)
    std::uint16_t code = 0;   // AL status code
    bool ok = false;          // the read itself succeeded
    protocol::AlState state() const {
        return static_cast<protocol::AlState>(status & protocol::kAlStateMask);
    }
    bool error() const { return (status & protocol::kAlErrorFlag) != 0; }
};

// One entry of a slave's process data as the master mapped it: the object, its length, and where it lies in
// the slave's output or input area (bits from the area's start; PDOs in their SyncManager's order, entries in
// their PDO's, gaps (index 0) included, as ETG.1000.6 5.6.7.4 lays them out).
struct MappedEntry {
    std::uint16_t index = 0;
    std::uint8_t subindex = 0;
    std::uint8_t bits = 0;
    std::uint32_t bit_offset = 0;
};
// The entry of object `index` (subindex 0 unless given) in entries, or nullptr.
const MappedEntry* find_entry(const std::vector<MappedEntry>& entries, std::uint16_t index,
                              std::uint8_t subindex = 0);

struct SlaveInfo {
    std::uint16_t position = 0;
    std::uint16_t station = 0;
    std::uint8_t esc_type = 0;
    std::uint8_t fmmu_count = 0;
    std::uint8_t sm_count = 0;
    std::uint16_t features = 0;
    std::uint16_t dl_status = 0;
    std::vector<std::uint8_t> sii_image;
    protocol::SiiInfo sii;
    unsigned out_bytes = 0;
    unsigned in_bytes = 0;
    // The entries of the outputs (RxPDOs) and inputs (TxPDOs): from the PDO assignment read by SDO for CoE
    // slaves (configure_process_data), else from the SII's PDO categories.
    std::vector<MappedEntry> out_entries;
    std::vector<MappedEntry> in_entries;
    // The process data SyncManagers and their lengths, in the order their areas follow each other in the
    // slave's outputs and inputs (a device may have several of each: oversampling terminals).
    struct ProcessDataSm {
        std::uint8_t sm = 0;
        bool outputs = false;
        std::uint16_t bytes = 0;
    };
    std::vector<ProcessDataSm> pd_sms;
    std::uint32_t out_logical = 0;
    std::uint32_t in_logical = 0;
    std::size_t out_offset = 0;  // in the process image
    std::size_t in_offset = 0;
    std::uint8_t mailbox_counter = 0;  // last mailbox counter used (1..7), kept per slave like real masters
    // Topology, from the DL status of every slave (compute_topology): the ports open with communication
    // (bit p), the slave whose port parent_port this slave's port 0 is cabled to (-1: the master).
    std::uint8_t open_ports = 0;
    int parent = -1;
    unsigned parent_port = 0;
    // Distributed clocks (configure_dc)
    bool has_dc = false;
    std::array<std::uint32_t, 4> dc_port_time{};  // receive times latched by the BWR 0x0900
    std::uint64_t dc_recv_time = 0;               // 0x0918
    std::uint32_t dc_delay_ns = 0;                // propagation delay from the reference clock (0x0928)
    std::uint64_t dc_offset = 0;                  // system time offset written (0x0920)
};

// Distributed clocks in startup(): what SOEM's ecx_configdc + ecx_dcsync0 and IgH do.
struct DcOptions {
    bool enable = false;
    std::uint32_t sync0_cycle_ns = 1'000'000;  // 0: measure delays and set offsets only
    std::int32_t shift_ns = 0;
    unsigned static_drift_frames = 15'000;       // FRMW bursts before SYNC0 (IgH/TwinCAT style)
    std::uint32_t max_sync_diff_ns = 10'000;     // wait until 0x092C is below (IgH: 10 us)
    std::chrono::milliseconds sync_wait{5000};   // for at most this long
    std::uint64_t start_delay_ns = 100'000'000;  // first SYNC0 this far after the system time read
};

struct DatagramRequest {
    protocol::Command cmd;
    std::uint32_t address;  // ADP | ADO << 16, or the logical address
    Bytes data;
    std::uint16_t wkc = 0;
};

struct MasterOptions {
    std::int64_t reply_timeout_us = 20'000;
    int retries = 3;
    std::uint32_t logical_base = 0x00010000;
    DcOptions dc;
};

class Master {
  public:
    explicit Master(net::Link& link, MasterOptions opt = {});

    // ---- Datagram services. Return the working counter, nullopt when no reply came.
    std::optional<std::uint16_t> transact(protocol::Command cmd, std::uint16_t adp, std::uint16_t ado,
                                          Bytes data);
    std::optional<std::uint16_t> transact_logical(protocol::Command cmd, std::uint32_t laddr, Bytes data);
    // Several datagrams in one frame; false when no reply.
    bool transact_frame(std::span<DatagramRequest> dgs);
    // Several frames sent back to back before any reply is awaited (kMaxFramesInFlight at a time); each reply
    // is matched to its frame by its datagrams' indexes, in whatever order the replies come. False when a
    // frame got no reply (or a batch does not fit: at most 255 datagrams in all).
    static constexpr std::size_t kMaxFramesInFlight = 32;
    bool transact_frames(std::span<const std::span<DatagramRequest>> frames);

    std::optional<std::uint16_t> brd(std::uint16_t ado, Bytes d) {
        return transact(protocol::Command::BRD, 0, ado, d);
    }
    std::optional<std::uint16_t> bwr(std::uint16_t ado, Bytes d) {
        return transact(protocol::Command::BWR, 0, ado, d);
    }
    std::optional<std::uint16_t> aprd(std::uint16_t pos, std::uint16_t ado, Bytes d) {
        return transact(protocol::Command::APRD, static_cast<std::uint16_t>(-pos), ado, d);
    }
    std::optional<std::uint16_t> apwr(std::uint16_t pos, std::uint16_t ado, Bytes d) {
        return transact(protocol::Command::APWR, static_cast<std::uint16_t>(-pos), ado, d);
    }
    std::optional<std::uint16_t> fprd(std::uint16_t st, std::uint16_t ado, Bytes d) {
        return transact(protocol::Command::FPRD, st, ado, d);
    }
    std::optional<std::uint16_t> fpwr(std::uint16_t st, std::uint16_t ado, Bytes d) {
        return transact(protocol::Command::FPWR, st, ado, d);
    }
    // Typed register helpers (one-slave fixed addressing); nullopt unless WKC == 1.
    std::optional<std::uint16_t> read16(std::uint16_t station, std::uint16_t ado);
    std::optional<std::uint32_t> read32(std::uint16_t station, std::uint16_t ado);
    bool write8(std::uint16_t station, std::uint16_t ado, std::uint8_t v);
    bool write16(std::uint16_t station, std::uint16_t ado, std::uint16_t v);
    bool write32(std::uint16_t station, std::uint16_t ado, std::uint32_t v);

    // ---- Start-up, step by step
    int count_slaves();   // BRD 0x0000 working counter
    bool reset_slaves();  // default register values, like SOEM's ecx_set_slaves_to_default
    bool assign_station_addresses(std::uint16_t first = 0x1001);
    bool read_slave_information();  // ESC info, DL status, topology and the whole SII of every slave
    // Parents and ports from the DL status read (as SOEM's ecx_config_init): the frame passes each ESC's
    // open ports in the order 0 -> 3 -> 1 -> 2, so slave i hangs on the nearest slave before it that still
    // has an open port left, at the next of its ports in that order.
    void compute_topology();
    // What one SII read command returns (ETG.1000.4 6.4; 0x0502 bit 6 says whether the ESC reads 4 or 8
    // bytes): the bytes from the word address on.
    struct SiiBlock {
        std::array<std::uint8_t, 8> bytes{};
        unsigned size = 0;  // 4 or 8
    };
    std::optional<SiiBlock> read_sii_block(std::uint16_t station, std::uint32_t word);
    std::optional<std::uint32_t> read_sii_dword(std::uint16_t station, std::uint32_t word);
    std::optional<std::vector<std::uint8_t>> read_sii_image(std::uint16_t station);
    bool configure_mailboxes();  // SM0/SM1 from the SII
    // SM2/SM3 and FMMUs; lays out the process image. CoE slaves' sizes are read from their PDO assignment.
    bool configure_process_data();
    bool read_pdo_sizes_coe(SlaveInfo& s);
    bool read_pdo_sizes_soe(SlaveInfo& s);
    // Requests a state from all slaves (broadcast) and waits until each has it or reports an error.
    bool request_state(protocol::AlState s,
                       std::chrono::milliseconds timeout = std::chrono::milliseconds(2000));
    bool request_state(std::uint16_t station, protocol::AlState s,
                       std::chrono::milliseconds timeout = std::chrono::milliseconds(2000));
    AlStatusReading read_al_status(std::uint16_t station);
    bool acknowledge_error(std::uint16_t station, protocol::AlState s);
    // Runs the whole sequence up to the target state.
    bool startup(protocol::AlState target, std::string* why = nullptr);

    // ---- Distributed clocks
    // Latches the receive times (BWR 0x0900), reads them, writes each DC slave's system time offset so that
    // its system time reads master_time_ns (ns since 2000-01-01) and its propagation delay from the
    // reference clock (the first DC slave). Line topology. Returns false if a read or write failed.
    bool configure_dc(std::uint64_t master_time_ns);
    bool configure_dc();  // with the host's real time
    // The reference clock's station address (0 without DC slaves).
    std::uint16_t dc_reference() const { return dc_ref_; }
    // One FRMW of the reference clock's system time to all other slaves; the time read (nullopt: no reply).
    std::optional<std::uint64_t> distribute_reference_clock();
    // Static drift compensation: n FRMW frames back to back.
    bool compensate_static_drift(unsigned frames);
    // Largest |system time difference| (0x092C) over the DC slaves but the reference; nullopt if unreadable.
    std::optional<std::uint32_t> max_system_time_difference();
    // Starts SYNC0 (and SYNC1 if cycle1_ns is set) like ecx_dcsync0/ecx_dcsync01: the first pulse on a whole
    // multiple of the cycle at least start_delay_ns after the slave's current system time, plus shift.
    bool start_sync(std::uint16_t station, std::uint32_t cycle0_ns, std::int32_t shift_ns,
                    std::uint64_t start_delay_ns = 100'000'000, std::optional<std::uint32_t> cycle1_ns = {});
    bool stop_sync(std::uint16_t station);
    // The last system time of the reference clock read by the cyclic FRMW.
    std::uint64_t reference_time() const { return dc_time_; }

    // ---- Process data
    // LRW over the image; with DC configured the first frame carries the FRMW of the reference clock. An
    // image larger than one frame holds goes in several frames, split between slaves (so the working
    // counters add up to expected_wkc()); returns their sum, nullopt when a frame got no reply.
    std::optional<std::uint16_t> exchange_process_data();
    // Largest LRW payload per frame (a full frame less the LRW and FRMW headers).
    static constexpr std::size_t kMaxLrwBytes = 1466;
    std::size_t process_image_size() const { return image_.size(); }
    std::size_t process_data_frames() const { return chunks_.size(); }
    std::uint16_t expected_wkc() const { return expected_wkc_; }
    Bytes outputs(std::size_t slave);
    ConstBytes inputs(std::size_t slave) const;

    std::vector<SlaveInfo>& slaves() { return slaves_; }
    const std::vector<AlStatusReading>& last_states() const { return last_states_; }
    // Timeouts and retries may change after start-up (cyclic code wants one try and a deadline).
    MasterOptions& options() { return opt_; }

    // From the receive times configure_dc() latched: the time from the parent's arrival at port 0 until the
    // frame leaves it through `port`, and the propagation delay of the cable between a slave and its parent.
    static std::int64_t departure(const SlaveInfo& up, unsigned port);
    static std::int64_t cable_delay(const SlaveInfo& up, const SlaveInfo& s);

  private:
    std::size_t build_frame(std::span<DatagramRequest> dgs, std::uint8_t first_index);
    bool transact_batch(std::span<const std::span<DatagramRequest>> frames);  // at most kMaxFramesInFlight
    static bool take_reply(Bytes reply, const protocol::ParsedFrame& pf, std::span<DatagramRequest> dgs,
                           std::uint8_t first_index);
    // Receives until the frames whose bits are set in `pending` have their replies or the reply timeout
    // passes; returns the bits of those still without a reply.
    std::uint32_t wait_replies(std::span<const std::span<DatagramRequest>> frames, const std::uint8_t* first,
                               std::uint32_t pending);

    net::Link& link_;
    MasterOptions opt_;
    std::uint8_t index_ = 0;
    std::array<std::uint8_t, 1600> tx_{};
    std::array<std::uint8_t, 1600> rx_{};
    std::vector<SlaveInfo> slaves_;
    std::vector<std::uint8_t> image_;
    struct Chunk {
        std::size_t offset, size;
    };
    std::vector<Chunk> chunks_;  // the image's parts, one LRW frame each
    // The cyclic frames' requests over chunks_ (exchange_process_data)
    std::vector<DatagramRequest> cyclic_dgs_;
    std::vector<std::span<DatagramRequest>> cyclic_frames_;
    const std::uint8_t* cyclic_image_ = nullptr;  // image_ and dc_ref_ when they were laid out
    std::uint16_t cyclic_dc_ref_ = 0;
    std::size_t out_total_ = 0;
    std::uint16_t expected_wkc_ = 0;
    std::vector<AlStatusReading> last_states_;
    std::uint16_t dc_ref_ = 0;
    std::uint64_t dc_time_ = 0;
    std::array<std::uint8_t, 8> dc_buf_{};
};

}  // namespace vecat::master
