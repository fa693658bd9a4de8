// The emulated EtherCAT slave controller: register space, process RAM, SyncManagers, FMMUs, SII EEPROM
// interface, watchdogs and the basic DC time unit. It is the "silicon": it processes datagrams for the
// EtherCAT side and offers a PDI (process data interface) to the slave application (see slave.hpp).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <span>
#include <utility>
#include <vector>

#include "common/bytes.hpp"
#include "esc/distributed_clock.hpp"
#include "protocol/frame.hpp"
#include "protocol/registers.hpp"

namespace vecat::esc {

inline constexpr std::uint32_t kMinRamBytes = 1024;

struct EscConfig {
    std::uint8_t type = 0x11;  // same family code as an ET1100
    std::uint8_t revision = 0x00;
    std::uint16_t build = 0x0002;
    std::uint8_t fmmu_count = 8;
    std::uint8_t sm_count = 8;
    // Process RAM from 0x1000, in whole KiB as 0x0006 reports it: 8 KiB (ET1100), 1 KiB (ET1200, as the EL
    // terminals of ../shared/data/pcap report); at least kMinRamBytes.
    std::uint32_t ram_bytes = 8192;
    std::uint8_t port_descriptor = 0x0F;  // ports 0 and 1: MII; ports 2, 3 not implemented
    std::uint16_t features = protocol::feature::DcAvailable | protocol::feature::Dc64Bit |
                             protocol::feature::EnhancedLinkMii | protocol::feature::SeparateFcsErrors |
                             protocol::feature::EnhancedDcSyncActivation;
    bool sii_read_8_bytes = true;
    // Further read-only bits of SII control/status 0x0502 (bits 1-5: bit 5 EEPROM emulation by the PDI,
    // bits 1-4 reserved, which some ESCs read as 1: an EL2828 shows 0x50).
    std::uint8_t sii_status_bits = 0;
    // DL control (0x0100-0x0103) at power-up (ESC datasheet section II: forwarding rule 1, RX FIFO size 7). A
    // line rebuilt from a capture takes what the real ESC showed before the master wrote it.
    std::uint32_t dl_control = 0x00070001;
    // The DC system time unit (0x0910-0x09FF: system time, offset, delay, time loop, SYNC and latch). Some
    // ESCs that report DC in 0x0008 have the receive times (0x0900-0x090F) only: they neither read nor
    // write the rest, and count no access to it (EL2828, EL1004, EK1914, EL3004 in ../shared/data/pcap).
    bool dc_system_time_unit = true;
    double dc_drift_ppm = 0.0;        // local clock drift against the host clock
    std::uint64_t dc_initial_ns = 0;  // local time at power-on
};

// Where the frame is on the line when it reaches this ESC (nanoseconds on the host clock).
// The frame passes an ESC's ports in the order 0 -> 3 -> 1 -> 2 (ESC datasheet section I, frame
// processing): it arrives at port 0 and comes back through each open port after the devices behind it.
struct FrameTiming {
    std::uint64_t port0_ns = 0;  // arrival at port 0 (forward direction)
    std::uint64_t port1_ns = 0;  // arrival back at port 1 (return direction), if port 1 is open
    std::uint64_t port2_ns = 0;  // ... at port 2
    std::uint64_t port3_ns = 0;  // ... at port 3
    // Ports 1..3 (bits) the frame arrived back at: a frame that leaves the ring (cable redundancy) through a
    // port never comes back through it, and that port keeps its last receive time.
    std::uint8_t returned_ports = 0x0E;
};

struct EscCounters {
    std::uint64_t datagrams = 0;  // handed to process() (a segment hands an ESC those that can concern it)
    std::uint64_t dropped_frames = 0;
};

class Esc {
  public:
    explicit Esc(const EscConfig& cfg, std::vector<std::uint8_t> eeprom);
    Esc(const Esc&) = delete;  // the DC unit points into the register memory
    Esc& operator=(const Esc&) = delete;

    // ---- EtherCAT side
    // Processes one datagram as this ESC; updates data, working counter and (auto-increment) ADP. Returns
    // true when the datagram addressed this ESC (it added to the working counter).
    bool process(protocol::DatagramView d, const FrameTiming& t);
    // Whether the datagrams processed since the last call gave the firmware something to do: the master
    // wrote into the ESC's memory (registers, SyncManager buffers, process RAM), or read a mailbox empty
    // (the firmware may post its next message). Reading process data or registers, and the DC unit's time
    // registers that the ESC keeps by itself (dc_time_registers), give it nothing. Clears the flag.
    bool take_firmware_work() { return std::exchange(firmware_work_, false); }
    // The DC unit's time registers, kept by the ESC alone (ESC datasheet section I, distributed clocks):
    // the receive times of the ports and the system time, 0x0900-0x0917 (the cyclic FRMW of the system
    // time and the BWR that latches the receive times).
    static constexpr bool dc_time_registers(std::uint32_t first, std::uint32_t last) {
        return first >= protocol::addr(protocol::Reg::DcRecvTimePort0) &&
               last < protocol::addr(protocol::Reg::DcRecvTimeEcatPu);
    }
    // A frame this ESC could not parse: counted as a real ESC counts a malformed frame on port 0.
    void count_invalid_frame(unsigned port = 0);
    // A frame already marked invalid by a previous ESC arrived at this port (0x0308 + port).
    void count_forwarded_error(unsigned port);
    // An invalid frame passed the processing unit (0x030C; port 0 to port 1 direction).
    void count_processing_unit_error();
    // Which ports have a link (port 0 unless its cable is broken; port 1 when another ESC follows). A link
    // that goes down counts in the lost link counter (0x0310 + port), as in the ports' auto modes.
    void set_port_link(unsigned port, bool up);
    bool port_link(unsigned port) const { return (link_mask_ >> port) & 1u; }
    // Whether a frame leaves through the port (to the device cabled there) or the port loops it back to the
    // next one: DL control loop setting (0x0100 bits 8+2p..9+2p: auto, auto close, open, closed) and link
    // (ESC datasheet section II, 0x0100 and 0x0110). An unimplemented port is always closed.
    bool port_open(unsigned port) const;
    // Counted up whenever a link or a loop setting may have changed (the segment routes frames anew).
    // Atomic: slaves' firmware may run on several threads (Segment::set_firmware_threads).
    void set_port_change_counter(std::atomic<std::uint64_t>* counter) { port_changes_ = counter; }

    // ---- PDI side (the slave application)
    std::uint32_t al_events() const { return ld_le32(&mem_[protocol::addr(protocol::Reg::AlEventRequest)]); }
    // Reads AL control like a PDI does: clears the AL control event.
    std::uint16_t pdi_read_al_control();
    void pdi_write_al_status(std::uint8_t status, std::uint16_t code);
    // The firmware reads the SII through the PDI (ESC datasheet section I 11.2: EtherCAT has the EEPROM
    // interface at power-up and may offer it to the PDI with 0x0500 bit 0). It may only while the master
    // offers it: then the PDI takes the interface (0x0501 bit 0), issues its commands and releases it, and
    // the ESC clears 0x0502 bit 4 (protocol::sii_ctrl::ReservedUntilPdiAccess). Returns whether it could.
    bool pdi_use_eeprom();
    // Device emulation (0x0141 bit 0, from SII word 0): the ESC sets AL status from AL control itself;
    // devices without a µController (couplers, simple I/O terminals) have it.
    bool device_emulation() const;
    // When the master last wrote AL control (the frame's arrival at port 0, host clock).
    std::uint64_t al_control_written_ns() const { return al_control_written_ns_; }
    std::uint8_t al_status() const { return mem_[protocol::addr(protocol::Reg::AlStatus)]; }
    std::uint16_t al_status_code() const {
        return ld_le16(&mem_[protocol::addr(protocol::Reg::AlStatusCode)]);
    }

    struct SmConfigView {
        std::uint16_t start;
        std::uint16_t length;
        std::uint8_t control;
        bool ecat_enabled;     // enable bit written by the master
        bool pdi_deactivated;  // deactivated by the application
        bool valid;            // the buffers fit the process RAM
    };
    SmConfigView sm_config(unsigned i) const;
    protocol::SmConfig sm_block(unsigned i) const;  // SyncManager i's register block as written
    // The master's enable bit of SyncManager i (0x0806 + 8 i, bit 0): sm_config(i).ecat_enabled without
    // unpacking the block (the firmware asks it at every process data exchange).
    bool sm_ecat_enabled(unsigned i) const {
        return (mem_[protocol::sm_addr(i) + protocol::sm::Activate] & protocol::sm::ActEnable) != 0;
    }
    void pdi_deactivate_sm(unsigned i, bool deactivate);
    // SM activation register changed by the master (enable or repeat request): cleared by this read.
    bool pdi_take_sm_activation_event();
    void pdi_clear_al_event(std::uint32_t bits) { clear_al_event(bits); }

    // Mailbox SyncManagers.
    bool sm_mailbox_full(unsigned i) const { return sm_[i].mbx_full; }
    // Takes the content of a full ECAT-written mailbox (copies sm length bytes); false when empty.
    bool pdi_mailbox_take(unsigned i, Bytes out);
    // Puts a reply into an ECAT-read mailbox (fills the whole SM length); false when still full.
    bool pdi_mailbox_put(unsigned i, ConstBytes data);
    // The PDI writes the first byte of an ECAT-read mailbox that the master has read completely (interrupt
    // read set), and not the last: the buffer is in use, interrupt read cleared (status 0x80), and stays so
    // until pdi_mailbox_put completes it. Nothing happens in any other state.
    void pdi_mailbox_open(unsigned i);
    bool sm_repeat_request(unsigned i) const;
    void pdi_set_repeat_ack(unsigned i, bool ack);

    // Process data SyncManagers: buffered (3 buffers), 1 byte (no buffers) or 1-buffer (mailbox) mode.
    // Latest complete buffer written by the master (ECAT-write SM). Returns false if none was ever written.
    bool pdi_buffer_read(unsigned i, Bytes out);
    std::uint64_t sm_buffer_writes(unsigned i) const { return sm_[i].complete_writes; }
    // Publishes a new buffer for the master to read (ECAT-read SM).
    bool pdi_buffer_write(unsigned i, ConstBytes in);
    // Process data without a SyncManager (the master left it off, or it is virtual): the FMMU reads and
    // writes the memory. Writes reach the process RAM only.
    void pdi_write_memory(std::uint16_t a, ConstBytes in);
    void pdi_read_memory(std::uint16_t a, Bytes out) const;

    // Time: runs the watchdogs. Call regularly with the host clock in ns.
    void tick(std::uint64_t now_ns);
    // The first host time at which tick() finds the process data watchdog expired (it expires when more
    // than its time passed since the last trigger, ESC datasheet section I, watchdogs), or kNever while
    // it is disarmed or off: the firmware need not run before then for the watchdog's sake.
    std::uint64_t watchdog_deadline_ns() const;
    bool pd_watchdog_expired() const {
        return (mem_[protocol::addr(protocol::Reg::WatchdogStatusProcessData)] & 1) == 0;
    }

    // DC local time (ns) at a given host time.
    std::uint64_t local_time(std::uint64_t host_ns) const { return dc_.local_time(host_ns); }
    // The distributed clocks unit (clocks, time control loop, SYNC out unit, latch units).
    DistributedClock& dc() { return dc_; }
    const DistributedClock& dc() const { return dc_; }
    // SYNC pulses due up to now_ns, as the PDI sees its SYNC0/SYNC1 interrupts (sets the AL event bits).
    unsigned pdi_take_sync_pulses(std::uint64_t now_ns, SyncPulse* out, unsigned max);
    // Asks the caches for what a process data datagram reads and writes here (its FMMUs and SyncManagers,
    // their buffers), so that a frame's slaves are fetched together rather than one after the other.
    void prefetch_for_frame() const;
    // What it asks for of the SyncManagers, kept as they change (update_sm): each active process data
    // SyncManager, at most kPrefetchSms of them, with the area of its buffers (three of length bytes, one
    // of a 1-byte SyncManager).
    struct PrefetchSm {
        std::uint8_t index = 0;
        std::uint16_t start = 0, span = 0;
    };
    static constexpr unsigned kPrefetchSms = 4;
    std::span<const PrefetchSm> prefetch_sms() const { return {prefetch_sms_.data(), prefetch_sm_count_}; }

    // ---- Raw access for tests, tools and the application's own registers
    std::uint8_t peek(std::uint16_t a) const { return a < mem_.size() ? mem_[a] : 0; }
    std::uint16_t peek16(std::uint16_t a) const {
        return static_cast<std::uint16_t>(peek(a) | (peek(a + 1) << 8));
    }
    std::uint32_t peek32(std::uint16_t a) const {
        return peek16(a) | (static_cast<std::uint32_t>(peek16(a + 2)) << 16);
    }
    const std::vector<std::uint8_t>& eeprom() const { return eeprom_; }
    const EscConfig& config() const { return cfg_; }
    const EscCounters& counters() const { return counters_; }
    std::uint16_t station_address() const { return peek16(protocol::addr(protocol::Reg::StationAddress)); }
    // A configured-address command (FPxx, FRMW) with this ADP addresses this ESC: its station address, or
    // its alias when DL control enables alias addressing.
    bool addressed_fixed(std::uint16_t adp) const {
        return Addressing{.station = station_, .alias = alias_, .alias_enabled = alias_enabled_}.fixed(adp);
    }

    // What decides whether a datagram can concern this ESC at all (ETG.1000.4 5.4): the configured station
    // address 0x0010, the alias 0x0012 with its enable bit (DL control 0x0100 bit 24), and the logical bit
    // ranges that the active FMMUs cover, those that read and those that write apart (a master that maps
    // every slave's outputs, then every slave's inputs, as SOEM does, leaves the outputs and the inputs of
    // one slave far apart). A segment keeps a copy per ESC, so that a frame visits only the ESCs that a
    // datagram can address (broadcasts and auto-increment commands aside).
    struct Addressing {
        std::uint16_t station = 0;
        std::uint16_t alias = 0;
        bool alias_enabled = false;
        // The bits of the FMMUs that read (logical reads take data from the ESC's memory there); empty:
        // first > last.
        std::uint64_t log_read_first_bit = ~std::uint64_t{0}, log_read_last_bit = 0;
        // The bits of the FMMUs that write.
        std::uint64_t log_write_first_bit = ~std::uint64_t{0}, log_write_last_bit = 0;
        bool fixed(std::uint16_t adp) const { return adp == station || (alias_enabled && adp == alias); }
        bool logical(std::uint64_t first_bit, std::uint64_t last_bit) const {
            return logical_read(first_bit, last_bit) ||
                   (first_bit <= log_write_last_bit && last_bit >= log_write_first_bit);
        }
        bool logical_read(std::uint64_t first_bit, std::uint64_t last_bit) const {
            return first_bit <= log_read_last_bit && last_bit >= log_read_first_bit;
        }
    };
    Addressing addressing() const;
    // Counted up whenever addressing() may have changed (a write to those registers or to an FMMU, an SII
    // reload that brings a new alias). Only process() and reload_eeprom() change it.
    void set_address_change_counter(std::atomic<std::uint64_t>* counter) { address_changes_ = counter; }

    // The slave's firmware writes its own EEPROM (a firmware update writes the new revision into the SII,
    // words 0x000C/0x000D). A word past the EEPROM's end is not written.
    void pdi_write_eeprom_word(unsigned word, std::uint16_t value);

    // Reloads the ESC configuration area from the EEPROM (as at power-on and on an SII reload command).
    void reload_eeprom();

  private:
    struct SmState {
        bool active = false;  // enabled by ECAT, not deactivated by PDI, config valid
        // Enabled by ECAT but deactivated by the PDI: the area is read/write protected (ESC datasheet
        // section I 8.7), no access is counted.
        bool locked = false;
        bool valid = false;
        std::uint16_t start = 0, length = 0;
        std::uint8_t control = 0;
        bool mailbox = false;
        // Buffered mode of 1 byte: no buffer mechanism, accesses pass to the memory (section I 8.5); the
        // SyncManagers on the digital output register are these.
        bool single = false;
        bool ecat_writes = false;
        // mailbox
        bool mbx_full = false;
        // Status 0x0805 bits 0 and 1 (ESC datasheet section II): interrupt write, set when the buffer was
        // completely written, cleared when its first byte is read; interrupt read, set when it was completely
        // read, cleared when its first byte is written. Either side (ECAT or PDI) may be the writer.
        bool irq_write = false, irq_read = false;
        // Status bit 7, write buffer in use: the PDI wrote the first byte of an ECAT-read mailbox and not yet
        // the last (pdi_mailbox_open).
        bool pdi_opened = false;
        // buffered: buffer numbers 0..2 at start + n * length
        std::uint8_t buf_ecat = 0, buf_next = kNone, buf_pdi = 1;
        bool ecat_reading = false;
        bool ever_written = false;
        std::uint64_t complete_writes = 0;
        static constexpr std::uint8_t kNone = 0xFF;
    };
    struct FmmuState {
        bool active = false;
        bool read = false, write = false;
        std::uint64_t log_first_bit = 0, log_last_bit = 0;  // inclusive
        std::uint32_t phys_first_bit = 0;
        bool byte_aligned = false;
    };

    // Copies memory into a datagram, or ORs it in (broadcast reads).
    static void copy_out(std::uint8_t* dst, const std::uint8_t* src, std::size_t n, bool or_into) {
        if (or_into)
            for (std::size_t k = 0; k < n; ++k)
                dst[k] |= src[k];
        else
            std::memcpy(dst, src, n);
    }
    void physical(protocol::DatagramView d, std::uint16_t ado, bool do_read, bool do_write, bool or_read,
                  const FrameTiming& t, unsigned& wkc_add);
    void logical(protocol::DatagramView d, bool do_read, bool do_write, const FrameTiming& t,
                 unsigned& wkc_add);

    // Accesses with full ECAT semantics (masks, SyncManagers, side effects); true if any byte counted.
    bool ecat_read(std::uint16_t a, std::uint8_t* dst, std::size_t n, bool or_into, const FrameTiming& t);
    bool ecat_write(std::uint16_t a, const std::uint8_t* src, std::size_t n, const FrameTiming& t);
    // A write of the registers first..last that touches none of the registers whose write is more than the
    // masked copy (AL control, the SyncManager blocks, the digital output register, an absent DC unit).
    bool plain_register_write(std::uint32_t first, std::uint32_t last) const;
    // The masked copy of n register bytes from a: the bits of the write mask are stored; true if any byte
    // is one the master may write.
    bool write_registers_masked(std::uint32_t a, const std::uint8_t* src, std::size_t n);
    // The same byte by byte with the rules of the registers plain_register_write names; al_control_written
    // is set when AL control took a byte.
    bool write_registers_bytewise(std::uint32_t a, const std::uint8_t* src, std::size_t n,
                                  bool& al_control_written);
    bool al_control_refuses_writes() const;
    bool absent_dc_unit(std::uint32_t a) const;  // in the system time unit of an ESC without one
    // Where a SyncManager of span bytes may lie: in the process RAM, or on the digital output register
    // of an ESC with a digital I/O PDI.
    bool sm_area_exists(std::uint32_t start, std::uint32_t span) const;
    bool has_digital_io() const;
    bool sm_ecat_read(unsigned i, std::size_t off, std::uint8_t* dst, std::size_t n, bool or_into);
    bool sm_ecat_write(unsigned i, std::size_t off, const std::uint8_t* src, std::size_t n);
    // An active or locked SM guarding this byte; -1 if none. Inline (below): every access to the process RAM
    // asks it.
    int sm_covering(std::uint32_t a) const;
    std::uint32_t next_sm_start(std::uint32_t a) const;  // the first guarded area above a (or the end)
    std::uint8_t* ecat_write_target(std::uint32_t a);    // where an ECAT write of this byte lands

    void refresh_dynamic_registers(std::uint16_t first, std::uint16_t last, const FrameTiming& t);
    void after_register_write(std::uint16_t first, std::uint16_t last, const FrameTiming& t);
    void update_sm(unsigned i);
    void update_prefetch_sms();  // prefetch_sms_ from sm_
    void update_sm_status(unsigned i);
    void update_fmmu(unsigned i);
    void sii_command(std::uint8_t cmd_byte);
    void set_al_event(std::uint32_t bits) {
        std::uint8_t* r = &mem_[protocol::addr(protocol::Reg::AlEventRequest)];
        st_le32(r, ld_le32(r) | bits);
    }
    void clear_al_event(std::uint32_t bits) {
        std::uint8_t* r = &mem_[protocol::addr(protocol::Reg::AlEventRequest)];
        st_le32(r, ld_le32(r) & ~bits);
    }
    void update_dl_status();

    // What a cyclic datagram touches comes first, together: a frame of a large network visits hundreds of
    // ESCs, each of them out of the core's caches, and every cache line the visit reads is a miss.
    std::vector<std::uint8_t> mem_;  // 0x0000 .. 0x1000 + ram_bytes
    // prefetch_sms(), beside mem_ in the first line: prefetch_for_frame reads nothing else of this object.
    std::array<PrefetchSm, kPrefetchSms> prefetch_sms_{};
    std::uint8_t prefetch_sm_count_ = 0;
    EscCounters counters_;
    std::uint64_t last_host_ns_ = 0;
    // The process data watchdog (ESC datasheet section II 0x0400, 0x0420, 0x0440): triggered by a write of a
    // process data SyncManager with its watchdog bit, looked at by every run (tick, beside last_host_ns_,
    // which it writes). Its time, 0x0420 x (0x0400 + 2) x 40 ns, is worked out when either register is
    // written (0: off), so that a run need not read them.
    std::uint64_t wd_last_trigger_ns_ = 0;
    std::uint64_t wd_time_ns_ = 0;
    bool wd_armed_ = false;
    // The configured station address 0x0010, the alias 0x0012 and its enable bit (DL control 0x0100 bit
    // 24), as address_changed() last found them in mem_ (addressing(), addressed_fixed()).
    std::uint16_t station_ = 0, alias_ = 0;
    bool alias_enabled_ = false;
    bool firmware_work_ = false;        // see take_firmware_work
    bool sm_activation_event_ = false;  // pdi_take_sm_activation_event, which every run asks
    std::uint32_t sm_guard_mask_ = 0;   // active or locked SMs: the ones that control their memory area
    // Active FMMUs that read / write (a logical datagram outside the ranges below is rejected without
    // looking at each FMMU).
    std::uint32_t fmmu_read_mask_ = 0, fmmu_write_mask_ = 0;
    // The hulls of the logical ranges of the active FMMUs that read and of those that write (addressing()).
    std::uint64_t fmmu_log_read_first_bit_ = ~std::uint64_t{0}, fmmu_log_read_last_bit_ = 0;
    std::uint64_t fmmu_log_write_first_bit_ = ~std::uint64_t{0}, fmmu_log_write_last_bit_ = 0;
    std::array<FmmuState, protocol::kMaxFmmus> fmmu_{};
    std::array<SmState, protocol::kMaxSms> sm_{};
    EscConfig cfg_;
    DistributedClock dc_;  // works on mem_'s DC registers
    std::vector<std::uint8_t> eeprom_;
    const protocol::WriteMaskTable* wmask_ = nullptr;  // shared by the ESCs alike (esc.cpp)
    std::uint32_t repeat_bits_ = 0;
    std::atomic<std::uint64_t>* port_changes_ = nullptr;
    std::atomic<std::uint64_t>* address_changes_ = nullptr;
    void address_changed();
    void update_watchdog_time();    // wd_time_ns_ from 0x0400 and 0x0420
    std::uint8_t auto_closed_ = 0;  // ports that "auto close" closed at a link loss, until the master reopens
    std::uint8_t link_mask_ = 0x01;
    // Bit p: port_open(p), as update_dl_status last found it (it runs whenever a link, the loop setting of
    // DL control or an auto close changes).
    std::uint8_t open_ports_ = 0;
    std::uint8_t written_sii_cmd_ = 0;
    // AL control written by the master and not yet read by the PDI: without device emulation the
    // register then refuses further writes (ESC datasheet section II 0x0120, "behaves like a mailbox").
    bool al_control_unread_ = false;
    std::uint64_t al_control_written_ns_ = 0;
    std::array<std::uint8_t, 2048 + 16> scratch_{};
};

inline int Esc::sm_covering(std::uint32_t a) const {
    for (std::uint32_t m = sm_guard_mask_; m; m &= m - 1) {
        const auto i = static_cast<unsigned>(__builtin_ctz(m));
        const SmState& s = sm_[i];
        if (a >= s.start && a < static_cast<std::uint32_t>(s.start) + s.length) return static_cast<int>(i);
    }
    return -1;
}

inline std::uint32_t Esc::next_sm_start(std::uint32_t a) const {
    auto best = static_cast<std::uint32_t>(mem_.size());
    for (std::uint32_t m = sm_guard_mask_; m; m &= m - 1) {
        const auto i = static_cast<unsigned>(__builtin_ctz(m));
        if (sm_[i].start > a && sm_[i].start < best) best = sm_[i].start;
    }
    return best;
}

}  // namespace vecat::esc
