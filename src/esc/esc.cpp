// The ESC silicon as one unit (about 800 lines): a datagram's way through the register space, the FMMUs
// and the SII interface is one piece of logic that each part must see whole. The SyncManagers (their
// state, their ECAT accesses and the PDI side) are in esc_sync_managers.cpp, the DC unit in
// distributed_clock, the wire layouts in src/protocol. The access rules are listed in README.md.
#include "esc/esc.hpp"

#include <algorithm>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <tuple>

#include "common/bits.hpp"
#include "esc/sii_image.hpp"
#include "protocol/al_status.hpp"

namespace vecat::esc {

using protocol::addr;
using protocol::AlState;
using protocol::Command;
using protocol::DatagramView;
using protocol::fmmu_addr;
using protocol::FmmuConfig;
using protocol::kFmmuSize;
using protocol::kMaxFmmus;
using protocol::kMaxSms;
using protocol::kRegisterSpaceSize;
using protocol::kSmSize;
using protocol::make_write_mask_table;
using protocol::Reg;
using protocol::sii_config_crc;
using protocol::sm_addr;
using protocol::SmConfig;
namespace al_event = protocol::al_event;
namespace dl_status = protocol::dl_status;
namespace fmmu = protocol::fmmu;
namespace sii = protocol::sii;
namespace sii_ctrl = protocol::sii_ctrl;
namespace sm = protocol::sm;
namespace {

constexpr std::uint16_t kDefaultWatchdogDivider = 2498;  // (2498 + 2) x 40 ns = 100 us
constexpr std::uint16_t kDefaultWatchdogTime = 1000;     // 1000 x 100 us = 100 ms
constexpr std::uint16_t kDcFirst = 0x0900;               // the DC unit's registers: 0x0900-0x09FF
constexpr std::uint16_t kDcSize = 0x0100;
constexpr std::uint16_t kDcSystemTimeFirst = 0x0910;  // the system time unit: 0x0910-0x09FF
constexpr std::uint16_t kDcEnd = kDcFirst + kDcSize;
constexpr std::uint8_t kSiiStatusBits = 0x3E;  // 0x0502 bits 1-5 (see EscConfig::sii_status_bits)

bool overlaps(std::uint32_t lo, std::uint32_t hi, std::uint32_t a, std::uint32_t len) {
    return lo < a + len && hi >= a;  // hi inclusive
}

void saturating_inc(std::uint8_t& c) {
    if (c != 0xFF) ++c;
}

// The ECAT write masks of an ESC (protocol::WriteMaskTable, 4.5 KiB) follow from its FMMU and SyncManager
// counts, its system time unit and whether its PDI has the digital output register (-1: as made, before
// the EEPROM is read): ESCs alike share one table, made once, which then stays in the cache for a line of
// a thousand slaves instead of a table of each. The tables live as long as the process.
const protocol::WriteMaskTable* shared_write_masks(unsigned fmmus, unsigned sms, bool system_time_unit,
                                                   int digital_io) {
    using Key = std::tuple<unsigned, unsigned, bool, int>;
    static std::mutex guard;
    static auto* tables = new std::map<Key, std::unique_ptr<const protocol::WriteMaskTable>>;
    const std::lock_guard lock(guard);
    auto& table = (*tables)[Key{fmmus, sms, system_time_unit, digital_io}];
    if (!table) {
        auto t = std::make_unique<protocol::WriteMaskTable>(make_write_mask_table(fmmus, sms));
        if (!system_time_unit)
            for (unsigned a = kDcSystemTimeFirst; a < kDcEnd; ++a)
                t->set(a, 0, false);
        // The digital output register exists with a digital I/O PDI only (section II 0x0F00).
        if (digital_io >= 0)
            for (unsigned k = 0; k < protocol::kDigitalOutputSize; ++k)
                t->set(addr(Reg::DigitalOutputData) + k, 0xFF, digital_io == 1);
        table = std::move(t);
    }
    return table.get();
}

}  // namespace

Esc::Esc(const EscConfig& cfg, std::vector<std::uint8_t> eeprom)
    : mem_(kRegisterSpaceSize + std::max<std::uint32_t>(cfg.ram_bytes, kMinRamBytes), 0),
      cfg_(cfg),
      dc_(mem_.data(), cfg.dc_drift_ppm, cfg.dc_initial_ns),
      eeprom_(std::move(eeprom)) {
    cfg_.fmmu_count = static_cast<std::uint8_t>(std::min<unsigned>(cfg_.fmmu_count, kMaxFmmus));
    cfg_.sm_count = static_cast<std::uint8_t>(std::min<unsigned>(cfg_.sm_count, kMaxSms));
    cfg_.ram_bytes = static_cast<std::uint32_t>(mem_.size() - kRegisterSpaceSize);
    wmask_ = shared_write_masks(cfg_.fmmu_count, cfg_.sm_count, cfg_.dc_system_time_unit, -1);
    if (eeprom_.size() % 2) eeprom_.push_back(0xFF);

    mem_[addr(Reg::Type)] = cfg_.type;
    mem_[addr(Reg::Revision)] = cfg_.revision;
    st_le16(&mem_[addr(Reg::Build)], cfg_.build);
    mem_[addr(Reg::FmmuCount)] = cfg_.fmmu_count;
    mem_[addr(Reg::SmCount)] = cfg_.sm_count;
    mem_[addr(Reg::RamSize)] = static_cast<std::uint8_t>(std::min<std::uint32_t>(cfg_.ram_bytes / 1024, 255));
    mem_[addr(Reg::PortDescriptor)] = cfg_.port_descriptor;
    st_le16(&mem_[addr(Reg::Features)], cfg_.features);
    st_le32(&mem_[addr(Reg::DlControl)], cfg_.dl_control);
    st_le16(&mem_[addr(Reg::AlStatus)], static_cast<std::uint16_t>(AlState::Init));
    st_le32(&mem_[addr(Reg::AlEventMask)], 0x00FFFF0F);
    st_le16(&mem_[addr(Reg::WatchdogDivider)], kDefaultWatchdogDivider);
    st_le16(&mem_[addr(Reg::WatchdogTimePdi)], kDefaultWatchdogTime);
    st_le16(&mem_[addr(Reg::WatchdogTimeProcessData)], kDefaultWatchdogTime);
    update_watchdog_time();
    mem_[addr(Reg::WatchdogStatusProcessData)] = 0x01;
    std::uint16_t sii = 0;
    if (cfg_.sii_read_8_bytes) sii |= sii_ctrl::Read8Bytes;
    sii |= cfg_.sii_status_bits & kSiiStatusBits;
    if (eeprom_.size() > 2048) sii |= sii_ctrl::TwoAddressBytes;
    st_le16(&mem_[addr(Reg::SiiControl)], sii);
    reload_eeprom();
}

unsigned Esc::pdi_take_sync_pulses(std::uint64_t now_ns, SyncPulse* out, unsigned max) {
    // (Asked first: a device outside DC mode then reads one line of the DC unit, not its counters too.)
    if (!dc_.cyclic_active()) return 0;
    const std::uint64_t before0 = dc_.counters().sync_pulses[0], before1 = dc_.counters().sync_pulses[1];
    const unsigned n = dc_.advance(now_ns, out, max);
    if (dc_.counters().sync_pulses[0] != before0) set_al_event(al_event::Sync0);
    if (dc_.counters().sync_pulses[1] != before1) set_al_event(al_event::Sync1);
    return n;
}

bool Esc::pdi_use_eeprom() {
    constexpr std::uint8_t kOfferedToPdi = 0x01;  // 0x0500 bit 0
    if (!(mem_[addr(Reg::SiiConfig)] & kOfferedToPdi)) return false;
    // The PDI's commands and their data are not kept for EtherCAT to see (the firmware releases the
    // interface, 0x0501 reads 0 again); what stays is bit 4 of 0x0502, cleared.
    const std::uint16_t ctrl = ld_le16(&mem_[addr(Reg::SiiControl)]);
    st_le16(&mem_[addr(Reg::SiiControl)],
            static_cast<std::uint16_t>(ctrl & ~sii_ctrl::ReservedUntilPdiAccess));
    return true;
}

void Esc::pdi_write_eeprom_word(unsigned word, std::uint16_t value) {
    if (2 * word + 1 < eeprom_.size()) st_le16(&eeprom_[2 * word], value);
}

void Esc::reload_eeprom() {
    auto word = [&](unsigned w) -> std::uint16_t {
        return 2 * w + 1 < eeprom_.size() ? ld_le16(&eeprom_[2 * w]) : 0xFFFF;
    };
    std::uint16_t ctrl = ld_le16(&mem_[addr(Reg::SiiControl)]);
    const bool crc_ok =
        eeprom_.size() >= 16 && sii_config_crc(ConstBytes(eeprom_.data(), 14)) == eeprom_[2 * sii::Checksum];
    if (crc_ok) {
        st_le16(&mem_[addr(Reg::PdiControl)], word(sii::PdiControl));
        // The digital output register exists with a digital I/O PDI only (section II 0x0F00).
        wmask_ = shared_write_masks(cfg_.fmmu_count, cfg_.sm_count, cfg_.dc_system_time_unit,
                                    has_digital_io() ? 1 : 0);
        st_le16(&mem_[addr(Reg::PdiConfiguration)], word(sii::PdiConfig));
        st_le16(&mem_[addr(Reg::ExtendedPdiConfiguration)], word(sii::PdiConfig2));
        st_le16(&mem_[addr(Reg::StationAlias)], word(sii::StationAlias));
        st_le16(&mem_[addr(Reg::DcPulseLength)], word(sii::SyncImpulseLen));
        ctrl = static_cast<std::uint16_t>(ctrl & ~(sii_ctrl::ChecksumError | sii_ctrl::NotLoaded));
    } else {
        ctrl |= sii_ctrl::ChecksumError | sii_ctrl::NotLoaded;
    }
    st_le16(&mem_[addr(Reg::SiiControl)], ctrl);
    update_dl_status();
    address_changed();  // the alias
}

namespace {
// DL control loop setting of a port (0x0100 bits 8+2p..9+2p; ESC datasheet section II).
enum class Loop : std::uint8_t { Auto = 0, AutoClose = 1, Open = 2, Closed = 3 };
}  // namespace

bool Esc::port_open(unsigned port) const {
    if (port > 3 || ((cfg_.port_descriptor >> (2 * port)) & 0x3) == 0) return false;
    switch (static_cast<Loop>((mem_[addr(Reg::DlControl) + 1] >> (2 * port)) & 0x3)) {
        case Loop::Auto:
            return port_link(port);
        case Loop::AutoClose:
            return port_link(port) && !((auto_closed_ >> port) & 1u);
        case Loop::Open:
            return true;
        case Loop::Closed:
            return false;
    }
    return false;
}

void Esc::set_port_link(unsigned port, bool up) {
    if (port > 3) return;
    if (!up && port_link(port)) {
        saturating_inc(mem_[addr(Reg::LostLinkCounter) + port]);
        // Auto close: closed at the link loss, opened again only by the master (a write of the setting).
        auto_closed_ = static_cast<std::uint8_t>(auto_closed_ | (1u << port));
    }
    if (up)
        link_mask_ = static_cast<std::uint8_t>(link_mask_ | (1u << port));
    else
        link_mask_ = static_cast<std::uint8_t>(link_mask_ & ~(1u << port));
    update_dl_status();
}

void Esc::update_dl_status() {
    if (port_changes_)
        port_changes_->fetch_add(
            1, std::memory_order_relaxed);  // links or loop settings may have changed: the way of frames too
    const std::uint16_t ctrl = ld_le16(&mem_[addr(Reg::SiiControl)]);
    std::uint16_t v = 0;
    if (!(ctrl & sii_ctrl::NotLoaded)) v |= dl_status::PdiOperational;
    // Without a PDI (0x0140 = 0, e.g. an EK1100) nothing reloads the PDI watchdog: it shows expired
    // (ESC datasheet section II 0x0110 bit 1; the EK1100 of ../shared/data/pcap reads 0x..31).
    if (mem_[addr(Reg::PdiControl)] != 0) v |= dl_status::PdiWatchdogOk;
    // Enhanced link detection activated for at least one port (0x0141 bits 1, 4-7; section II 0x0110 bit 2).
    if (mem_[addr(Reg::EscConfiguration)] & protocol::esc_config::EnhancedLinkDetection)
        v |= dl_status::EnhancedLinkDetection;
    std::uint8_t open = 0;
    for (unsigned p = 0; p < 4; ++p) {
        const bool implemented = ((cfg_.port_descriptor >> (2 * p)) & 0x3) != 0;
        if (implemented && port_link(p))
            v |= static_cast<std::uint16_t>(dl_status::link(p) | dl_status::communication(p));
        if (port_open(p))
            open = static_cast<std::uint8_t>(open | (1u << p));
        else
            v |= dl_status::loop_closed(p);
    }
    open_ports_ = open;
    st_le16(&mem_[addr(Reg::DlStatus)], v);
}

void Esc::count_invalid_frame(unsigned port) {
    if (port > 3) return;
    saturating_inc(mem_[addr(Reg::RxErrorCounter) + 2 * port]);
    ++counters_.dropped_frames;
}

void Esc::count_forwarded_error(unsigned port) {
    if (port > 3) return;
    saturating_inc(mem_[addr(Reg::FwdRxErrorCounter) + port]);
}

void Esc::count_processing_unit_error() {
    saturating_inc(mem_[addr(Reg::EcatProcessingUnitErrorCounter)]);
}

void Esc::address_changed() {
    station_ = ld_le16(&mem_[addr(Reg::StationAddress)]);
    alias_ = ld_le16(&mem_[addr(Reg::StationAlias)]);
    alias_enabled_ = (mem_[addr(Reg::DlControl) + 3] & 0x01) != 0;
    if (address_changes_) address_changes_->fetch_add(1, std::memory_order_relaxed);
}

Esc::Addressing Esc::addressing() const {
    Addressing a;
    a.station = station_;
    a.alias = alias_;
    a.alias_enabled = alias_enabled_;
    a.log_read_first_bit = fmmu_log_read_first_bit_;
    a.log_read_last_bit = fmmu_log_read_last_bit_;
    a.log_write_first_bit = fmmu_log_write_first_bit_;
    a.log_write_last_bit = fmmu_log_write_last_bit_;
    return a;
}

// ---------------------------------------------------------------------------------------------
// Datagram dispatch (ETG.1000.4 5.4, working counter rules of Table 13)

bool Esc::process(DatagramView d, const FrameTiming& t) {
    ++counters_.datagrams;
    last_host_ns_ = t.port0_ns;
    unsigned wkc = 0;
    const auto inc_adp = [&] { d.set_adp(static_cast<std::uint16_t>(d.adp() + 1)); };
    switch (d.command()) {
        case Command::NOP:
            break;
        case Command::APRD:
            if (d.adp() == 0) physical(d, d.ado(), true, false, false, t, wkc);
            inc_adp();
            break;
        case Command::APWR:
            if (d.adp() == 0) physical(d, d.ado(), false, true, false, t, wkc);
            inc_adp();
            break;
        case Command::APRW:
            if (d.adp() == 0) physical(d, d.ado(), true, true, false, t, wkc);
            inc_adp();
            break;
        case Command::FPRD:
            if (addressed_fixed(d.adp())) physical(d, d.ado(), true, false, false, t, wkc);
            break;
        case Command::FPWR:
            if (addressed_fixed(d.adp())) physical(d, d.ado(), false, true, false, t, wkc);
            break;
        case Command::FPRW:
            if (addressed_fixed(d.adp())) physical(d, d.ado(), true, true, false, t, wkc);
            break;
        case Command::BRD:
            physical(d, d.ado(), true, false, true, t, wkc);
            inc_adp();
            break;
        case Command::BWR:
            physical(d, d.ado(), false, true, false, t, wkc);
            inc_adp();
            break;
        case Command::BRW:
            physical(d, d.ado(), true, true, true, t, wkc);
            inc_adp();
            break;
        case Command::LRD:
            logical(d, true, false, t, wkc);
            break;
        case Command::LWR:
            logical(d, false, true, t, wkc);
            break;
        case Command::LRW:
            logical(d, true, true, t, wkc);
            break;
        case Command::ARMW:
            if (d.adp() == 0)
                physical(d, d.ado(), true, false, false, t, wkc);
            else
                physical(d, d.ado(), false, true, false, t, wkc);
            inc_adp();
            break;
        case Command::FRMW:
            if (addressed_fixed(d.adp()))
                physical(d, d.ado(), true, false, false, t, wkc);
            else
                physical(d, d.ado(), false, true, false, t, wkc);
            break;
        default:
            // Unknown commands pass the ESC unchanged, like a NOP.
            break;
    }
    if (wkc) d.add_wkc(wkc);
    return wkc != 0;
}

void Esc::physical(DatagramView d, std::uint16_t ado, bool do_read, bool do_write, bool or_read,
                   const FrameTiming& t, unsigned& wkc_add) {
    const std::size_t n = d.length();
    if (n == 0) return;
    std::uint8_t* data = d.data();
    if (do_read && do_write) {
        // Read-write: the frame leaves with the old memory content; memory takes the incoming data.
        std::memcpy(scratch_.data(), data, n);
        const bool r = ecat_read(ado, data, n, or_read, t);
        const bool w = ecat_write(ado, scratch_.data(), n, t);
        wkc_add += (r ? 1u : 0u) + (w ? 2u : 0u);
    } else if (do_read) {
        wkc_add += ecat_read(ado, data, n, or_read, t) ? 1u : 0u;
    } else {
        wkc_add += ecat_write(ado, data, n, t) ? 1u : 0u;
    }
}

void Esc::logical(DatagramView d, bool do_read, bool do_write, const FrameTiming& t, unsigned& wkc_add) {
    const std::size_t dlen = d.length();
    if (dlen == 0) return;
    std::uint8_t* data = d.data();
    const std::uint64_t dfirst = static_cast<std::uint64_t>(d.logical_address()) * 8;
    const std::uint64_t dlast = dfirst + dlen * 8 - 1;
    const bool near_read = dlast >= fmmu_log_read_first_bit_ && dfirst <= fmmu_log_read_last_bit_;
    const bool near_write = dlast >= fmmu_log_write_first_bit_ && dfirst <= fmmu_log_write_last_bit_;
    if (!near_read && !near_write) return;  // no FMMU maps any of it
    bool any_read = false, any_write = false;
    // Writes take the incoming frame data, so all writes happen before any read replaces it.
    for (int pass = 0; pass < 2; ++pass) {
        const bool writing = pass == 0;
        if (writing ? !do_write : !do_read) continue;
        // The active FMMUs of this direction, in index order.
        for (std::uint32_t m = writing ? fmmu_write_mask_ : fmmu_read_mask_; m; m &= m - 1) {
            const unsigned i = static_cast<unsigned>(__builtin_ctz(m));
            const FmmuState& f = fmmu_[i];
            const std::uint64_t first = std::max(f.log_first_bit, dfirst);
            const std::uint64_t last = std::min(f.log_last_bit, dlast);
            if (first > last) continue;
            const std::uint64_t pfirst = f.phys_first_bit + (first - f.log_first_bit);
            const std::uint64_t nbits = last - first + 1;
            bool ok = false;
            if (f.byte_aligned) {
                const std::uint64_t pbyte = pfirst / 8;
                if (pbyte > 0xFFFF) continue;
                const std::size_t doff = static_cast<std::size_t>((first - dfirst) / 8);
                const std::size_t nbytes = static_cast<std::size_t>(nbits / 8);
                ok = writing ? ecat_write(static_cast<std::uint16_t>(pbyte), data + doff, nbytes, t)
                             : ecat_read(static_cast<std::uint16_t>(pbyte), data + doff, nbytes, false, t);
            } else {
                const std::uint64_t p0 = pfirst / 8;
                const std::uint64_t p1 = (pfirst + nbits - 1) / 8;
                if (p0 > 0xFFFF) continue;
                const std::size_t np = static_cast<std::size_t>(std::min<std::uint64_t>(p1, 0xFFFF) - p0 + 1);
                const unsigned pshift = static_cast<unsigned>(pfirst % 8);
                const std::uint64_t dbit0 = first - dfirst;
                // The bits that lie inside the physical address space (the bytes np covers).
                const std::size_t n =
                    static_cast<std::size_t>(std::min<std::uint64_t>(nbits, np * 8 - pshift));
                if (writing) {
                    // Read-modify-write of the covered bytes: the bits outside the mapping keep their value.
                    for (std::size_t k = 0; k < np; ++k) {
                        const std::uint8_t* cur = ecat_write_target(static_cast<std::uint32_t>(p0 + k));
                        scratch_[k] = cur ? *cur : 0;
                    }
                    copy_bits(scratch_.data(), pshift, data, static_cast<std::size_t>(dbit0), n);
                    ok = ecat_write(static_cast<std::uint16_t>(p0), scratch_.data(), np, t);
                } else {
                    ok = ecat_read(static_cast<std::uint16_t>(p0), scratch_.data(), np, false, t);
                    if (ok) copy_bits(data, static_cast<std::size_t>(dbit0), scratch_.data(), pshift, n);
                }
            }
            (writing ? any_write : any_read) |= ok;
        }
    }
    if (any_read) wkc_add += 1;
    if (any_write) wkc_add += do_read ? 2 : 1;
}

// ---------------------------------------------------------------------------------------------
// Memory access with ECAT semantics

std::uint8_t* Esc::ecat_write_target(std::uint32_t a) {
    if (a >= mem_.size()) return nullptr;
    if (a >= kRegisterSpaceSize) {
        const int i = sm_covering(a);
        if (i >= 0 && sm_[i].active && !sm_[i].mailbox && sm_[i].ecat_writes)
            return &mem_[sm_[i].start + static_cast<std::size_t>(sm_[i].buf_ecat) * sm_[i].length +
                         (a - sm_[i].start)];
    }
    return &mem_[a];
}

void Esc::refresh_dynamic_registers(std::uint16_t first, std::uint16_t last, const FrameTiming& t) {
    if (overlaps(first, last, kDcFirst, kDcSize)) dc_.before_read(first, last, t.port0_ns);
}

bool Esc::ecat_read(std::uint16_t a, std::uint8_t* dst, std::size_t n, bool or_into, const FrameTiming& t) {
    bool counted = false;
    std::size_t pos = 0;
    while (pos < n) {
        const std::uint32_t cur = static_cast<std::uint32_t>(a) + static_cast<std::uint32_t>(pos);
        const std::size_t rem = n - pos;
        std::size_t run;
        if (cur > 0xFFFF) break;  // past the 16-bit address space: nothing there
        if (cur < kRegisterSpaceSize && absent_dc_unit(cur)) {
            run = std::min<std::size_t>(rem, kDcEnd - cur);  // not there: the frame keeps its data
        } else if (cur < kRegisterSpaceSize) {
            run = std::min<std::size_t>(rem, kRegisterSpaceSize - cur);
            if (!cfg_.dc_system_time_unit && cur < kDcSystemTimeFirst)
                run = std::min<std::size_t>(run, kDcSystemTimeFirst - cur);
            refresh_dynamic_registers(static_cast<std::uint16_t>(cur),
                                      static_cast<std::uint16_t>(cur + run - 1), t);
            copy_out(dst + pos, &mem_[cur], run, or_into);
            if (overlaps(cur, cur + static_cast<std::uint32_t>(run) - 1, kDcFirst, kDcSize))
                dc_.after_read(static_cast<std::uint16_t>(cur), static_cast<std::uint16_t>(cur + run - 1));
            counted = true;
        } else if (cur < mem_.size()) {
            const int s = sm_covering(cur);
            if (s >= 0) {
                run = std::min<std::size_t>(rem, sm_[s].start + sm_[s].length - cur);
                if (!sm_[s].locked)  // locked: the frame keeps its data, nothing is counted
                    counted |=
                        sm_ecat_read(static_cast<unsigned>(s), cur - sm_[s].start, dst + pos, run, or_into);
            } else {
                run = std::min<std::size_t>(rem, next_sm_start(cur) - cur);
                copy_out(dst + pos, &mem_[cur], run, or_into);
                counted = true;
            }
        } else {
            run = std::min<std::size_t>(rem, 0x10000 - cur);
            if (!or_into) std::memset(dst + pos, 0, run);
            counted = true;
        }
        pos += run;
    }
    return counted;
}

bool Esc::plain_register_write(std::uint32_t first, std::uint32_t last) const {
    return !overlaps(first, last, addr(Reg::AlControl), 2) &&
           !overlaps(first, last, sm_addr(0), kSmSize * cfg_.sm_count) &&
           !(overlaps(first, last, addr(Reg::DigitalOutputData), protocol::kDigitalOutputSize) &&
             has_digital_io()) &&
           (cfg_.dc_system_time_unit ||
            !overlaps(first, last, kDcSystemTimeFirst, kDcEnd - kDcSystemTimeFirst));
}

bool Esc::write_registers_masked(std::uint32_t a, const std::uint8_t* src, std::size_t n) {
    std::uint8_t* mem = mem_.data() + a;
    const std::uint8_t* mask = wmask_->mask.data() + a;
    std::size_t k = 0;
    for (; k + 8 <= n; k += 8) {  // eight bytes at a time (the system time, a DC start time, an FMMU)
        std::uint64_t m, v, old;
        std::memcpy(&m, mask + k, 8);
        std::memcpy(&v, src + k, 8);
        std::memcpy(&old, mem + k, 8);
        old = (old & ~m) | (v & m);
        std::memcpy(mem + k, &old, 8);
    }
    for (; k < n; ++k)
        mem[k] = static_cast<std::uint8_t>((mem[k] & ~mask[k]) | (src[k] & mask[k]));
    // Counted when one byte lies in a register the master may write, even if its value is ignored
    // (reserved bits); read-only and absent registers are not written (ESC datasheet section I 2.4,
    // section II 1).
    for (std::size_t j = 0; j < n; ++j)
        if (wmask_->writable(static_cast<std::uint16_t>(a + j))) return true;
    return false;
}

bool Esc::write_registers_bytewise(std::uint32_t a, const std::uint8_t* src, std::size_t n,
                                   bool& al_control_written) {
    const bool al_control_refused = al_control_refuses_writes();
    bool counted = false;
    for (std::size_t k = 0; k < n; ++k) {
        const std::uint32_t ad = a + static_cast<std::uint32_t>(k);
        if (absent_dc_unit(ad)) continue;  // not there: not written, not counted
        std::uint8_t m = wmask_->mask[ad];
        if (ad - addr(Reg::AlControl) < 2u) {
            if (al_control_refused) continue;  // still unread by the PDI: not written, not counted
            al_control_written = true;
        }
        if (ad - addr(Reg::DigitalOutputData) < protocol::kDigitalOutputSize && has_digital_io()) {
            // A SyncManager on the digital output register guards it like RAM.
            if (const int si = sm_covering(ad); si >= 0) {
                const auto i = static_cast<unsigned>(si);
                if (!sm_[i].locked && sm_ecat_write(i, ad - sm_[i].start, src + k, 1)) counted = true;
                continue;
            }
        }
        if (ad >= 0x0800 && ad < sm_addr(cfg_.sm_count) && (ad & 7) < 5 &&
            (mem_[(ad & ~7u) + sm::Activate] & sm::ActEnable))
            m = 0;  // SyncManager configuration is locked while the SM is enabled
        mem_[ad] = static_cast<std::uint8_t>((mem_[ad] & ~m) | (src[k] & m));
        // Counted as in write_registers_masked, also when the SM configuration is locked.
        counted |= wmask_->writable(static_cast<std::uint16_t>(ad));
    }
    return counted;
}

bool Esc::ecat_write(std::uint16_t a, const std::uint8_t* src, std::size_t n, const FrameTiming& t) {
    bool counted = false;
    std::uint32_t reg_lo = 0xFFFF, reg_hi = 0;
    bool sii_cmd_written = false;
    std::array<std::uint8_t, 8> systime{};
    std::uint8_t systime_bytes = 0;
    const std::uint8_t activation_before = mem_[addr(Reg::DcActivation)];
    bool al_control_written = false;
    std::size_t pos = 0;
    while (pos < n) {
        const std::uint32_t cur = static_cast<std::uint32_t>(a) + static_cast<std::uint32_t>(pos);
        const std::size_t rem = n - pos;
        std::size_t run;
        if (cur > 0xFFFF) break;
        if (cur < kRegisterSpaceSize) {
            run = std::min<std::size_t>(rem, kRegisterSpaceSize - cur);
            const std::uint32_t last = cur + static_cast<std::uint32_t>(run) - 1;
            const std::uint8_t* v = src + pos;
            // Most writes (the system time of the cyclic FRMW, error counters, FMMUs, SII address) touch
            // none of the registers with rules of their own: those take the masked copy of the whole run.
            const bool c = plain_register_write(cur, last)
                               ? write_registers_masked(cur, v, run)
                               : write_registers_bytewise(cur, v, run, al_control_written);
            counted |= c;
            if (c && !dc_time_registers(cur, last)) firmware_work_ = true;
            // What a write starts acts on the value the master sent: the SII command byte, the system time
            // (only where the ESC has the system time unit).
            constexpr std::uint32_t sii_cmd = addr(Reg::SiiControl) + 1;
            if (overlaps(cur, last, sii_cmd, 1)) {
                written_sii_cmd_ = v[sii_cmd - cur];
                sii_cmd_written = true;
            }
            constexpr std::uint32_t st = addr(Reg::DcSystemTime);
            if (cfg_.dc_system_time_unit && overlaps(cur, last, st, 8)) {
                const std::uint32_t lo = std::max(cur, st), hi = std::min(last, st + 7);
                std::memcpy(&systime[lo - st], v + (lo - cur), hi - lo + 1);
                systime_bytes |= static_cast<std::uint8_t>(((1u << (hi - lo + 1)) - 1) << (lo - st));
            }
            reg_lo = std::min(reg_lo, cur);
            reg_hi = std::max(reg_hi, last);
        } else if (cur < mem_.size()) {
            const int s = sm_covering(cur);
            if (s >= 0) {
                run = std::min<std::size_t>(rem, sm_[s].start + sm_[s].length - cur);
                if (!sm_[s].locked &&
                    sm_ecat_write(static_cast<unsigned>(s), cur - sm_[s].start, src + pos, run))
                    counted = firmware_work_ = true;
            } else {
                run = std::min<std::size_t>(rem, next_sm_start(cur) - cur);
                std::memcpy(&mem_[cur], src + pos, run);
                counted = firmware_work_ = true;
            }
        } else {
            run = std::min<std::size_t>(rem, 0x10000 - cur);  // past the process RAM: nothing to write
        }
        pos += run;
    }
    if (al_control_written) {
        al_control_unread_ = true;
        al_control_written_ns_ = t.port0_ns;
        set_al_event(al_event::AlControl);
        // Device emulation: the ESC itself sets AL status to the value written to AL control (ESC
        // datasheet section II 0x0130, 0x0141 bit 0); an acknowledge (bit 4) shows as the error indication.
        if (device_emulation()) std::memcpy(&mem_[addr(Reg::AlStatus)], &mem_[addr(Reg::AlControl)], 2);
    }
    if (reg_lo <= reg_hi) {
        if (sii_cmd_written) sii_command(written_sii_cmd_);
        // A write of the system time feeds the time control loop (0x092C, the local clock's rate).
        if (systime_bytes) dc_.system_time_written(systime, systime_bytes, t.port0_ns);
        after_register_write(static_cast<std::uint16_t>(reg_lo), static_cast<std::uint16_t>(reg_hi), t);
        if (overlaps(reg_lo, reg_hi, kDcFirst, kDcSize))
            dc_.after_write(static_cast<std::uint16_t>(reg_lo), static_cast<std::uint16_t>(reg_hi), t,
                            open_ports_, activation_before);
    }
    return counted;
}

// ---------------------------------------------------------------------------------------------
// Register side effects

bool Esc::absent_dc_unit(std::uint32_t a) const {
    return !cfg_.dc_system_time_unit && a >= kDcSystemTimeFirst && a < kDcEnd;
}

bool Esc::device_emulation() const {
    return (mem_[addr(Reg::EscConfiguration)] & protocol::esc_config::DeviceEmulation) != 0;
}

bool Esc::al_control_refuses_writes() const {
    return al_control_unread_ && !device_emulation();
}

void Esc::after_register_write(std::uint16_t lo, std::uint16_t hi, const FrameTiming& /*t*/) {
    if (overlaps(lo, hi, addr(Reg::DlControl) + 1, 1)) {
        // Writing "auto close" again opens a port that has its link back.
        auto_closed_ = static_cast<std::uint8_t>(auto_closed_ & ~link_mask_);
        update_dl_status();
    }
    if (overlaps(lo, hi, addr(Reg::RxErrorCounter), 12))
        std::memset(&mem_[addr(Reg::RxErrorCounter)], 0, 12);  // any write clears 0x0300-0x030B
    if (overlaps(lo, hi, addr(Reg::EcatProcessingUnitErrorCounter), 1))
        mem_[addr(Reg::EcatProcessingUnitErrorCounter)] = 0;
    if (overlaps(lo, hi, addr(Reg::PdiErrorCounter), 1)) mem_[addr(Reg::PdiErrorCounter)] = 0;
    if (overlaps(lo, hi, addr(Reg::LostLinkCounter), 4)) std::memset(&mem_[addr(Reg::LostLinkCounter)], 0, 4);
    if (overlaps(lo, hi, addr(Reg::WatchdogDivider), 2) ||
        overlaps(lo, hi, addr(Reg::WatchdogTimeProcessData), 2))
        update_watchdog_time();
    if (overlaps(lo, hi, addr(Reg::WatchdogCounterProcessData), 1))
        mem_[addr(Reg::WatchdogCounterProcessData)] = 0;
    if (overlaps(lo, hi, addr(Reg::WatchdogCounterPdi), 1)) mem_[addr(Reg::WatchdogCounterPdi)] = 0;
    if (overlaps(lo, hi, addr(Reg::StationAddress), 2) || overlaps(lo, hi, addr(Reg::StationAlias), 2) ||
        overlaps(lo, hi, addr(Reg::DlControl) + 3, 1) ||
        overlaps(lo, hi, 0x0600, kFmmuSize * cfg_.fmmu_count))
        address_changed();
    if (overlaps(lo, hi, 0x0600, kFmmuSize * cfg_.fmmu_count)) {
        const unsigned f0 = lo < 0x0600 ? 0 : (lo - 0x0600u) / kFmmuSize;
        for (unsigned f = f0; f < cfg_.fmmu_count && fmmu_addr(f) <= hi; ++f)
            update_fmmu(f);
    }
    if (overlaps(lo, hi, 0x0800, kSmSize * cfg_.sm_count)) {
        const unsigned s0 = lo < 0x0800 ? 0 : (lo - 0x0800u) / kSmSize;
        for (unsigned s = s0; s < cfg_.sm_count && sm_addr(s) <= hi; ++s)
            update_sm(s);
    }
}

void Esc::update_fmmu(unsigned i) {
    const FmmuConfig c =
        FmmuConfig::unpack(std::span<const std::uint8_t, kFmmuSize>(&mem_[fmmu_addr(i)], kFmmuSize));
    FmmuState& f = fmmu_[i];
    const std::uint16_t len = c.length;
    f.read = c.read;
    f.write = c.write;
    f.log_first_bit = static_cast<std::uint64_t>(c.logical_start) * 8 + c.logical_start_bit;
    f.log_last_bit =
        (static_cast<std::uint64_t>(c.logical_start) + (len ? len - 1 : 0)) * 8 + c.logical_stop_bit;
    f.phys_first_bit = static_cast<std::uint32_t>(c.physical_start) * 8 + c.physical_start_bit;
    f.byte_aligned = c.logical_start_bit == 0 && c.logical_stop_bit == 7 && c.physical_start_bit == 0;
    f.active = c.active && (f.read || f.write) && len > 0 && f.log_last_bit >= f.log_first_bit;
    static_assert(kMaxFmmus <= 32);
    fmmu_read_mask_ = fmmu_write_mask_ = 0;
    fmmu_log_read_first_bit_ = ~std::uint64_t{0};
    fmmu_log_read_last_bit_ = 0;
    fmmu_log_write_first_bit_ = ~std::uint64_t{0};
    fmmu_log_write_last_bit_ = 0;
    for (unsigned k = 0; k < cfg_.fmmu_count; ++k) {
        const FmmuState& g = fmmu_[k];
        if (!g.active) continue;
        if (g.read) {
            fmmu_read_mask_ |= 1u << k;
            fmmu_log_read_first_bit_ = std::min(fmmu_log_read_first_bit_, g.log_first_bit);
            fmmu_log_read_last_bit_ = std::max(fmmu_log_read_last_bit_, g.log_last_bit);
        }
        if (g.write) {
            fmmu_write_mask_ |= 1u << k;
            fmmu_log_write_first_bit_ = std::min(fmmu_log_write_first_bit_, g.log_first_bit);
            fmmu_log_write_last_bit_ = std::max(fmmu_log_write_last_bit_, g.log_last_bit);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// AL registers (PDI side)

std::uint16_t Esc::pdi_read_al_control() {
    clear_al_event(al_event::AlControl);
    al_control_unread_ = false;  // the "mailbox" is empty again: the master may write
    return ld_le16(&mem_[addr(Reg::AlControl)]);
}

void Esc::pdi_write_al_status(std::uint8_t status, std::uint16_t code) {
    st_le16(&mem_[addr(Reg::AlStatus)], status);
    st_le16(&mem_[addr(Reg::AlStatusCode)], code);
}

// ---------------------------------------------------------------------------------------------
// SII EEPROM interface (ETG.1000.4 6.4, registers 0x0500-0x050F)

void Esc::sii_command(std::uint8_t cmd_byte) {
    std::uint16_t ctrl = ld_le16(&mem_[addr(Reg::SiiControl)]);
    const bool write_enable = ctrl & sii_ctrl::WriteEnable;
    // A new command (or a write of 0) clears the error bits of the previous one.
    ctrl = static_cast<std::uint16_t>(ctrl & ~(sii_ctrl::ErrorAck | sii_ctrl::ErrorWriteEnable |
                                               sii_ctrl::CmdMask | sii_ctrl::WriteEnable | sii_ctrl::Busy));
    const unsigned cmd = cmd_byte & 0x07;
    const std::uint32_t word_addr = ld_le32(&mem_[addr(Reg::SiiAddress)]);
    const std::size_t words = eeprom_.size() / 2;
    switch (cmd) {
        case 0:
            break;
        case 1: {  // read 4 or 8 bytes
            if (word_addr >= words) {
                ctrl |= sii_ctrl::ErrorAck;
                break;
            }
            const unsigned n = (ctrl & sii_ctrl::Read8Bytes) ? 8 : 4;
            for (unsigned k = 0; k < n; ++k) {
                const std::size_t b = 2 * static_cast<std::size_t>(word_addr) + k;
                mem_[addr(Reg::SiiData) + k] = b < eeprom_.size() ? eeprom_[b] : 0xFF;
            }
            break;
        }
        case 2:  // write one word
            if (!write_enable) {
                ctrl |= sii_ctrl::ErrorWriteEnable;
                break;
            }
            if (word_addr >= words) {
                ctrl |= sii_ctrl::ErrorAck;
                break;
            }
            eeprom_[2 * word_addr] = mem_[addr(Reg::SiiData)];
            eeprom_[2 * word_addr + 1] = mem_[addr(Reg::SiiData) + 1];
            break;
        case 4:  // reload
            st_le16(&mem_[addr(Reg::SiiControl)], ctrl);
            reload_eeprom();
            return;
        default:
            ctrl |= sii_ctrl::ErrorAck;  // invalid command
            break;
    }
    st_le16(&mem_[addr(Reg::SiiControl)], ctrl);
}

// ---------------------------------------------------------------------------------------------
// Watchdogs

void Esc::update_watchdog_time() {
    const std::uint64_t divider = ld_le16(&mem_[addr(Reg::WatchdogDivider)]);
    wd_time_ns_ = ld_le16(&mem_[addr(Reg::WatchdogTimeProcessData)]) * (divider + 2) * 40;
}

std::uint64_t Esc::watchdog_deadline_ns() const {
    if (wd_time_ns_ == 0 || !wd_armed_) return DistributedClock::kNever;
    return wd_last_trigger_ns_ + wd_time_ns_ + 1;
}

void Esc::prefetch_for_frame() const {
    // This object's cyclic part (it comes first, see esc.hpp), the AL event request and the SyncManagers'
    // registers that a buffer access updates, and of each process data SyncManager its state and its three
    // buffers. Only the first line is read here (mem_ and the plan beside it, prefetch_sms_): the loads of
    // a frame's slaves do not wait for one another.
    const auto* self = reinterpret_cast<const char*>(this);
    for (std::size_t b = 0; b < 4 * 64; b += 64)
        __builtin_prefetch(self + b);
    const std::uint8_t* m = mem_.data();
    __builtin_prefetch(m + addr(Reg::AlEventRequest));
    __builtin_prefetch(m + protocol::sm_addr(0));
    for (unsigned k = 0; k < prefetch_sm_count_; ++k) {
        const PrefetchSm& p = prefetch_sms_[k];
        __builtin_prefetch(&sm_[p.index]);
        for (std::size_t b = 0; b < p.span; b += 64)
            __builtin_prefetch(m + p.start + b);
    }
}

void Esc::tick(std::uint64_t now_ns) {
    last_host_ns_ = now_ns;
    const std::uint64_t deadline = watchdog_deadline_ns();
    if (deadline == DistributedClock::kNever) return;
    if (now_ns >= deadline) {
        wd_armed_ = false;
        mem_[addr(Reg::WatchdogStatusProcessData)] &= static_cast<std::uint8_t>(~0x01);
        saturating_inc(mem_[addr(Reg::WatchdogCounterProcessData)]);
        set_al_event(al_event::WatchdogProcessData);
    }
}

}  // namespace vecat::esc
