#include "replay/recover.hpp"

#include <algorithm>
#include <map>
#include <optional>

#include "protocol/fmmu.hpp"
#include "protocol/frame.hpp"
#include "protocol/registers.hpp"
#include "protocol/sii.hpp"
#include "protocol/sync_manager.hpp"

namespace vecat::replay {

using protocol::addr;
using protocol::Command;
using protocol::Reg;

std::size_t RecoveredSlave::sii_words_known() const {
    return static_cast<std::size_t>(std::count_if(known.begin(), known.end(), [](auto k) { return k != 0; }));
}

namespace {

// SII control/status (0x0502, ESC datasheet section II): bit 6 read size 8 bytes, bit 8 read command,
// bit 15 busy.
constexpr std::uint16_t kSiiRead8Bytes = 0x0040;
constexpr std::uint16_t kSiiTwoAddressBytes = 0x0080;
constexpr std::uint16_t kSiiReadCommand = 0x0100;
constexpr std::uint16_t kSiiBusy = 0x8000;
constexpr std::size_t kMaxSiiWords = 0x8000;  // 64 KiB: the largest EEPROM with 32-bit addressing used

// Registers an ESC loads from the SII configuration area at power-on (ESC datasheet section II, "EEPROM
// content"; ETG.2010): a read of one of them, before the master wrote it, tells the word when the master did
// not read the word itself.
struct LoadedFromSii {
    Reg reg;
    unsigned word;
};
constexpr LoadedFromSii kLoadedFromSii[] = {
    {Reg::PdiControl, protocol::sii::PdiControl},
    {Reg::PdiConfiguration, protocol::sii::PdiConfig},
    {Reg::DcPulseLength, protocol::sii::SyncImpulseLen},
    {Reg::ExtendedPdiConfiguration, protocol::sii::PdiConfig2},
    {Reg::StationAlias, protocol::sii::StationAlias},
};

bool auto_increment(Command c) {
    return c == Command::APRD || c == Command::APWR || c == Command::APRW || c == Command::ARMW;
}
bool broadcast(Command c) {
    return c == Command::BRD || c == Command::BWR || c == Command::BRW;
}
bool fixed(Command c) {
    return c == Command::FPRD || c == Command::FPWR || c == Command::FPRW || c == Command::FRMW;
}

// A datagram's bytes [ado, ado + len) seen as register space: the byte at register a, if covered.
struct Window {
    std::uint16_t ado = 0;
    std::size_t len = 0;
    const std::uint8_t* data = nullptr;
    bool covers(std::uint16_t a, std::size_t n = 1) const { return a >= ado && a + n <= ado + len; }
    std::uint8_t at(std::uint16_t a) const { return data[a - ado]; }
    std::uint16_t u16(std::uint16_t a) const { return ld_le16(data + (a - ado)); }
    std::uint32_t u32(std::uint16_t a) const { return ld_le32(data + (a - ado)); }
};

// The AL state machine as the master sees it: the last state read, the last request written.
struct AlTracker {
    std::uint8_t state = 0x01;  // INIT at power-up
    std::optional<std::uint8_t> requested;
    std::optional<RefusedTransition> pending;  // refused, waiting for a read of its AL status code
    // The AL control mailbox (ESC datasheet section II 0x0120): when the last accepted write happened, the
    // longest gap after it that saw a write refused, the shortest that saw one accepted.
    std::optional<std::uint64_t> accepted_ns;
    std::uint64_t longest_refused_ns = 0;
    std::optional<std::uint64_t> shortest_accepted_ns;
    void write(std::uint64_t t, bool accepted) {
        if (accepted_ns && t >= *accepted_ns) {
            const std::uint64_t gap = t - *accepted_ns;
            if (!accepted)
                longest_refused_ns = std::max(longest_refused_ns, gap);
            else
                shortest_accepted_ns = std::min(shortest_accepted_ns.value_or(gap), gap);
        }
        if (accepted) accepted_ns = t;
    }
};
constexpr std::uint8_t kAlStateBits = 0x0F, kAlErrorBit = 0x10;

struct SiiTracker {
    std::uint32_t address = 0;
    bool reading = false;  // the last command written was a read
    // Per kLoadedFromSii entry: the master wrote the register (its value no longer tells the SII word).
    std::array<bool, std::size(kLoadedFromSii)> written{};
};

class Recoverer {
  public:
    Recoverer(const Capture& c, const Pairing& p) : c_(c), p_(p) {}

    RecoveredLine run() {
        line_.slave_count = count_slaves();
        line_.slaves.resize(line_.slave_count);
        sii_.resize(line_.slave_count);
        dl_control_written_.resize(line_.slave_count);
        mailbox_.resize(line_.slave_count);
        al_.resize(line_.slave_count);
        for (const Exchange& e : p_.exchanges)
            exchange(e);
        for (std::size_t s = 0; s < line_.slave_count; ++s) {
            line_.slaves[s].coe = mailbox_[s].result();
            const AlTracker& t = al_[s];
            if (t.pending) refuse(s, *t.pending);
            if (t.longest_refused_ns > 0) {
                // Just past the longest gap that saw a write refused (an eighth more), below the shortest
                // that saw one accepted: the device reacts to a state request as soon as the capture allows.
                std::uint64_t latency = t.longest_refused_ns + t.longest_refused_ns / 8;
                if (t.shortest_accepted_ns && *t.shortest_accepted_ns > t.longest_refused_ns)
                    latency = std::min(latency, *t.shortest_accepted_ns - 1);
                line_.slaves[s].al_control_latency_ns = latency;
            }
        }
        blocks_from_writes(fmmu_wkc_, kFmmuBlocks, true);
        blocks_from_writes(sm_wkc_, kSmBlocks, false);
        info_from_broadcast();
        dc_units_from_broadcasts();
        // Configuration words the master did not read, from the registers the ESC loaded them into.
        for (const Loaded& l : loaded_) {
            RecoveredSlave& rs = line_.slaves[l.slave];
            if (rs.sii.size() <= l.word) {
                rs.sii.resize(l.word + 1, 0xFFFF);
                rs.known.resize(l.word + 1, 0);
            }
            if (!rs.known[l.word]) {
                rs.sii[l.word] = l.value;
                rs.known[l.word] = 2;  // from a register
            }
        }
        share_sii_of_same_identity();
        return std::move(line_);
    }

    // Masters read the whole SII of the first device of an identity and little of the next ones (SOEM takes
    // the configuration of an identical device found before). Devices of one vendor, product and revision
    // carry one SII content, but for their alias, checksum and serial number: the words a slave's capture
    // lacks come from an earlier slave of its identity (known = 3).
    void share_sii_of_same_identity() {
        namespace sii = protocol::sii;
        constexpr unsigned kIdentityFirst = sii::VendorId, kIdentityEnd = sii::SerialNo;
        const auto identity_known = [](const RecoveredSlave& rs) {
            for (unsigned w = kIdentityFirst; w < kIdentityEnd; ++w)
                if (w >= rs.known.size() || !rs.known[w]) return false;
            return true;
        };
        const auto own = [](std::size_t w) {
            return w == sii::StationAlias || w == sii::Checksum || w == sii::SerialNo ||
                   w == sii::SerialNo + 1;
        };
        for (std::size_t b = 1; b < line_.slaves.size(); ++b) {
            RecoveredSlave& rs = line_.slaves[b];
            if (!identity_known(rs)) continue;
            for (std::size_t a = 0; a < b; ++a) {
                const RecoveredSlave& from = line_.slaves[a];
                if (!identity_known(from) ||
                    !std::equal(rs.sii.begin() + kIdentityFirst, rs.sii.begin() + kIdentityEnd,
                                from.sii.begin() + kIdentityFirst))
                    continue;
                if (rs.sii.size() < from.sii.size()) {
                    rs.sii.resize(from.sii.size(), 0xFFFF);
                    rs.known.resize(from.sii.size(), 0);
                }
                for (std::size_t w = 0; w < from.sii.size(); ++w)
                    if (!rs.known[w] && from.known[w] && !own(w)) {
                        rs.sii[w] = from.sii[w];
                        rs.known[w] = 3;
                    }
                break;
            }
        }
    }

  private:
    // The slaves of the line: every ESC counts a broadcast read of its registers, and a broadcast write of
    // its DL control (0x0100-0x0103, writable on every ESC; ESC datasheet section II), so the largest such
    // working counter is their number (a capture of TwinCAT's device scan holds only the latter).
    std::size_t count_slaves() const {
        std::size_t n = 0;
        constexpr std::uint16_t kDlControl = addr(Reg::DlControl), kDlControlEnd = kDlControl + 4;
        for (const Exchange& e : p_.exchanges) {
            const auto& f = c_.frames[e.reply].bytes;
            const protocol::ParsedFrame pf = protocol::parse_frame(f);
            for (std::size_t i = 0; i < pf.count; ++i) {
                protocol::DatagramView d(const_cast<std::uint8_t*>(f.data()) + pf.offsets[i]);
                const bool counted_by_all =
                    (d.command() == Command::BRD && d.ado() < protocol::kRegisterSpaceSize) ||
                    (d.command() == Command::BWR && d.length() > 0 && d.ado() >= kDlControl &&
                     d.ado() + d.length() <= kDlControlEnd);
                if (counted_by_all)
                    n = std::max<std::size_t>(n, std::min<std::size_t>(d.wkc(), kMaxRecoveredSlaves));
            }
        }
        return n;
    }

    std::optional<std::size_t> position(Command cmd, std::uint16_t adp) const {
        if (auto_increment(cmd)) {
            const std::size_t pos = static_cast<std::uint16_t>(0u - adp);
            if (pos < line_.slave_count) return pos;
        } else if (fixed(cmd)) {
            if (auto it = station_.find(adp); it != station_.end()) return it->second;
        }
        return std::nullopt;
    }

    void exchange(const Exchange& e) {
        const auto& rq = c_.frames[e.request].bytes;
        const auto& rp = c_.frames[e.reply].bytes;
        const protocol::ParsedFrame pq = protocol::parse_frame(rq);
        const protocol::ParsedFrame pr = protocol::parse_frame(rp);
        for (std::size_t i = 0; i < pr.count && i < pq.count; ++i) {
            protocol::DatagramView q(const_cast<std::uint8_t*>(rq.data()) + pq.offsets[i]);
            protocol::DatagramView r(const_cast<std::uint8_t*>(rp.data()) + pr.offsets[i]);
            const Command cmd = r.command();
            if (cmd >= Command::LRD && cmd <= Command::LRW) continue;
            const std::uint16_t adp =
                e.request_recorded ? q.adp() : request_adp(r.raw_command(), r.adp(), line_.slave_count);
            const Window written{q.ado(), q.length(), e.request_recorded ? q.data() : r.data()};
            const Window read{r.ado(), r.length(), r.data()};
            if (cmd == Command::BWR) count_block_write(r);
            if (protocol::physical_write(cmd) && r.wkc() > 0) {
                if (broadcast(cmd)) {
                    for (std::size_t s = 0; s < line_.slave_count; ++s)
                        wrote(s, written);
                } else if (auto s = position(cmd, adp)) {
                    wrote(*s, written);
                    mailbox_[*s].wrote(written.ado, written.data, written.len);
                    al_control_written(*s, written);
                }
            }
            if (protocol::physical_write(cmd) && written.covers(addr(Reg::AlControl))) {
                const std::uint64_t t = c_.frames[e.request_recorded ? e.request : e.reply].time_ns;
                if (broadcast(cmd)) {
                    // All refused or all accepted; a count in between does not say which slave refused.
                    if (r.wkc() == 0 || r.wkc() == line_.slave_count)
                        for (std::size_t s = 0; s < line_.slave_count; ++s)
                            al_[s].write(t, r.wkc() != 0);
                } else if (auto s = position(cmd, adp)) {
                    al_[*s].write(t, r.wkc() != 0);
                }
            }
            if (cmd == Command::BRD && r.wkc() == 1 && line_.slave_count == 1) al_status_read(0, read);
            if (cmd == Command::BRD && r.wkc() == line_.slave_count)
                for (std::uint16_t a = 0; a < kEscInfoBytes; ++a)
                    if (read.covers(a) && !broadcast_info_[a] &&
                        (!e.request_recorded || (written.covers(a) && written.at(a) == 0)))
                        broadcast_info_[a] = read.at(a);
            if ((cmd == Command::APRD || cmd == Command::FPRD || cmd == Command::APRW ||
                 cmd == Command::FPRW) &&
                r.wkc() >= 1)
                if (auto s = position(cmd, adp)) {
                    was_read(*s, read);
                    mailbox_[*s].read(read.ado, read.data, read.len);
                    al_status_read(*s, read);
                }
            if (cmd == Command::BWR && in_dc_system_time_unit(r))
                dc_broadcast_wkc_ = std::max<std::size_t>(dc_broadcast_wkc_.value_or(0), r.wkc());
            if (!broadcast(cmd) && in_dc_system_time_unit(r))
                if (auto s = position(cmd, adp)) {
                    auto& unit = line_.slaves[*s].dc_system_time_unit;
                    unit = unit.value_or(false) || r.wkc() > 0;
                }
        }
    }

    void al_control_written(std::size_t s, const Window& w) {
        if (!w.covers(addr(Reg::AlControl))) return;
        AlTracker& t = al_[s];
        if (t.pending) refuse(s, *t.pending);
        t.pending.reset();
        t.requested = static_cast<std::uint8_t>(w.at(addr(Reg::AlControl)) & kAlStateBits);
    }
    void al_status_read(std::size_t s, const Window& w) {
        AlTracker& t = al_[s];
        if (t.pending && w.covers(addr(Reg::AlStatusCode), 2)) {
            t.pending->code = w.u16(addr(Reg::AlStatusCode));
            refuse(s, *t.pending);
            t.pending.reset();
        }
        if (!w.covers(addr(Reg::AlStatus))) return;
        const std::uint8_t status = w.at(addr(Reg::AlStatus));
        const std::uint8_t state = status & kAlStateBits;
        if (t.requested && (status & kAlErrorBit) && state != *t.requested && state == t.state) {
            t.pending = RefusedTransition{t.state, *t.requested, 0x0001};
            if (w.covers(addr(Reg::AlStatusCode), 2)) {
                t.pending->code = w.u16(addr(Reg::AlStatusCode));
                refuse(s, *t.pending);
                t.pending.reset();
            }
        }
        if (t.requested && state == *t.requested) t.requested.reset();
        if (!(status & kAlErrorBit) || !t.requested) t.state = state;
    }
    void refuse(std::size_t s, const RefusedTransition& r) {
        auto& v = line_.slaves[s].refused;
        for (const auto& x : v)
            if (x.from == r.from && x.to == r.to) return;
        v.push_back(r);
    }

    static bool in_dc_system_time_unit(const protocol::DatagramView& r) {
        constexpr std::uint16_t first = addr(Reg::DcSystemTime), end = 0x0A00;
        return r.length() > 0 && r.ado() >= first && r.ado() + r.length() <= end;
    }

    // The working counter of a broadcast write to each whole FMMU (SyncManager) block.
    void count_block_write(const protocol::DatagramView& r) {
        const std::uint16_t a = r.ado();
        if (a >= protocol::fmmu_addr(0) && a < protocol::fmmu_addr(kFmmuBlocks) &&
            (a - protocol::fmmu_addr(0)) % protocol::kFmmuSize == 0 && r.length() >= protocol::kFmmuSize)
            note_block(fmmu_wkc_[(a - protocol::fmmu_addr(0)) / protocol::kFmmuSize], r.wkc());
        if (a >= protocol::sm_addr(0) && a < protocol::sm_addr(kSmBlocks) &&
            (a - protocol::sm_addr(0)) % protocol::kSmSize == 0 && r.length() >= protocol::kSmSize)
            note_block(sm_wkc_[(a - protocol::sm_addr(0)) / protocol::kSmSize], r.wkc());
    }
    static void note_block(std::optional<std::uint16_t>& slot, std::uint16_t wkc) {
        slot = std::max<std::uint16_t>(slot.value_or(0), wkc);
    }

    template <std::size_t N>
    void blocks_from_writes(const std::array<std::optional<std::uint16_t>, N>& wkc, std::size_t blocks,
                            bool fmmu) {
        const std::size_t n = line_.slave_count;
        if (n == 0) return;
        // Every block written, counts not growing, all slaves counted at block 0.
        for (std::size_t k = 0; k < blocks; ++k)
            if (!wkc[k] || *wkc[k] > n || (k > 0 && *wkc[k] > *wkc[k - 1])) return;
        if (*wkc[0] != n) return;
        std::vector<std::uint8_t> counts;  // largest first
        for (std::size_t c = blocks; c > 0; --c) {
            const std::size_t with = *wkc[c - 1] - (c < blocks ? *wkc[c] : 0);  // slaves with exactly c
            counts.insert(counts.end(), with, static_cast<std::uint8_t>(c));
        }
        for (std::size_t k = 0; k < n; ++k) {
            auto& rs = line_.slaves[k];
            (fmmu ? rs.fmmus_from_writes : rs.sms_from_writes) = counts[k];
        }
    }

    void wrote(std::size_t s, const Window& w) {
        for (std::uint16_t b = 0; b < 4; ++b)
            if (w.covers(static_cast<std::uint16_t>(addr(Reg::DlControl) + b)))
                dl_control_written_[s][b] = true;
        if (w.covers(addr(Reg::StationAddress), 2)) {
            const std::uint16_t station = w.u16(addr(Reg::StationAddress));
            line_.slaves[s].station = station;
            station_[station] = s;
        }
        SiiTracker& t = sii_[s];
        if (w.covers(addr(Reg::SiiAddress), 4)) t.address = w.u32(addr(Reg::SiiAddress));
        if (w.covers(addr(Reg::SiiControl), 2))
            t.reading = (w.u16(addr(Reg::SiiControl)) & kSiiReadCommand) != 0;
    }

    // ESC information that no datagram to the slave alone read, from a broadcast read that every slave of
    // the line counted (and the master sent with zeros there): each ESC ORs its bytes into a BRD's data
    // (ETG.1000.4 5.4; esc::Esc::ecat_read). On a line of one that is the slave's own data, every
    // byte of it. On a longer line it is the OR of all: each slave whose byte is unknown gets that OR for the
    // ESC type, revision and build (0x0000-0x0003), the one value that leaves the broadcast read as the
    // master saw it whatever the others hold; the FMMU and SyncManager counts, RAM size, ports and features
    // shape the ESC and stay as they are.
    void info_from_broadcast() {
        const std::size_t n = line_.slave_count;
        constexpr std::uint16_t kIdentityBytes = 4;
        for (std::uint16_t a = 0; a < kEscInfoBytes; ++a) {
            if (!broadcast_info_[a] || (n > 1 && a >= kIdentityBytes)) continue;
            for (std::size_t s = 0; s < n; ++s) {
                RecoveredSlave& rs = line_.slaves[s];
                if (rs.esc_info[a]) continue;
                rs.esc_info[a] = broadcast_info_[a];
                ++rs.esc_info_from_broadcast;
            }
        }
    }

    // The DC system time unit of slaves no datagram of their own tells about: a broadcast write into it
    // counted by c of the line's slaves says c of them have it (ESC datasheet section II 0x0910: an ESC
    // without it does not count those registers). Which ones it does not say; as with the FMMU counts, the
    // first slaves get it (couplers come first and have it, the EL terminals of ../shared/data/pcap lack it).
    void dc_units_from_broadcasts() {
        if (!dc_broadcast_wkc_ || *dc_broadcast_wkc_ > line_.slave_count) return;
        std::size_t left = *dc_broadcast_wkc_;
        for (const auto& rs : line_.slaves)
            if (rs.dc_system_time_unit.value_or(false)) left = left ? left - 1 : 0;
        for (auto& rs : line_.slaves) {
            if (rs.dc_system_time_unit) continue;
            rs.dc_system_time_unit = left > 0;
            left -= left > 0;
        }
    }

    void was_read(std::size_t s, const Window& w) {
        RecoveredSlave& rs = line_.slaves[s];
        for (std::uint16_t b = 0; b < 4; ++b) {
            const auto a = static_cast<std::uint16_t>(addr(Reg::DlControl) + b);
            if (w.covers(a) && !rs.dl_control[b] && !dl_control_written_[s][b]) rs.dl_control[b] = w.at(a);
        }
        for (std::uint16_t a = 0; a < kEscInfoBytes; ++a)
            if (w.covers(a) && !rs.esc_info[a]) rs.esc_info[a] = w.at(a);
        if (w.covers(addr(Reg::DlStatus), 2) && !rs.dl_status) rs.dl_status = w.u16(addr(Reg::DlStatus));
        SiiTracker& t = sii_[s];
        for (std::size_t k = 0; k < std::size(kLoadedFromSii); ++k)
            if (w.covers(addr(kLoadedFromSii[k].reg), 2) && !t.written[k])
                loaded_.push_back({s, kLoadedFromSii[k].word, w.u16(addr(kLoadedFromSii[k].reg))});
        bool busy = false;
        if (w.covers(addr(Reg::SiiControl), 2)) {
            const std::uint16_t ctl = w.u16(addr(Reg::SiiControl));
            busy = (ctl & kSiiBusy) != 0;
            if (!rs.sii_read_8_bytes) rs.sii_read_8_bytes = (ctl & kSiiRead8Bytes) != 0;
            if (!rs.sii_two_address_bytes) rs.sii_two_address_bytes = (ctl & kSiiTwoAddressBytes) != 0;
            if (!rs.sii_status_bits) rs.sii_status_bits = static_cast<std::uint8_t>(ctl & 0x3E);
        }
        if (w.covers(addr(Reg::SiiAddress), 4)) t.address = w.u32(addr(Reg::SiiAddress));
        if (!t.reading || busy || !w.covers(addr(Reg::SiiData), 4)) return;
        const std::size_t bytes =
            rs.sii_read_8_bytes.value_or(true) && w.covers(addr(Reg::SiiData), 8) ? 8 : 4;
        for (std::size_t k = 0; k < bytes / 2; ++k) {
            const std::size_t word = t.address + k;
            if (word >= kMaxSiiWords) break;
            if (rs.sii.size() <= word) {
                rs.sii.resize(word + 1, 0xFFFF);
                rs.known.resize(word + 1, 0);
            }
            rs.sii[word] = w.u16(static_cast<std::uint16_t>(addr(Reg::SiiData) + 2 * k));
            rs.known[word] = 1;
        }
    }

    const Capture& c_;
    const Pairing& p_;
    RecoveredLine line_;
    std::vector<SiiTracker> sii_;
    std::vector<std::array<bool, 4>> dl_control_written_;  // per slave: DL control bytes the master wrote
    std::vector<MailboxRecoverer> mailbox_;
    std::vector<AlTracker> al_;
    static constexpr std::size_t kFmmuBlocks = 16, kSmBlocks = 16;  // the register space's blocks
    std::array<std::optional<std::uint16_t>, kFmmuBlocks> fmmu_wkc_{};
    std::array<std::optional<std::uint16_t>, kSmBlocks> sm_wkc_{};
    std::array<std::optional<std::uint8_t>, kEscInfoBytes> broadcast_info_{};  // a BRD every slave counted
    std::optional<std::size_t> dc_broadcast_wkc_;  // the largest of BWRs into the DC system time unit
    struct Loaded {
        std::size_t slave;
        unsigned word;
        std::uint16_t value;
    };
    std::vector<Loaded> loaded_;
    std::map<std::uint16_t, std::size_t> station_;
};

}  // namespace

std::uint16_t request_adp(std::uint8_t command, std::uint16_t reply_adp, std::size_t slave_count) noexcept {
    const auto c = static_cast<Command>(command);
    if (auto_increment(c) || broadcast(c)) return static_cast<std::uint16_t>(reply_adp - slave_count);
    return reply_adp;
}

RecoveredLine recover_line(const Capture& c, const Pairing& p) {
    return Recoverer(c, p).run();
}

}  // namespace vecat::replay
