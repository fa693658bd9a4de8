#include "report/master_checks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>

#include "protocol/al_status.hpp"
#include "protocol/mailbox.hpp"

namespace vecat::report {

using protocol::addr;
using protocol::AlState;
using protocol::Command;
using protocol::DatagramView;
using protocol::Reg;

namespace {

bool covers(DatagramView d, std::uint16_t a) {
    return d.ado() <= a && a < std::uint32_t{d.ado()} + d.length();
}
std::uint8_t byte_at(DatagramView d, std::uint16_t a) {
    return d.data()[a - d.ado()];
}

std::string state_name(std::uint8_t s) {
    if (protocol::is_valid_state(s)) return std::string(protocol::to_string(static_cast<AlState>(s)));
    return fmt::format("0x{:X}", s);
}

// FNV-1a: tells a repeated mailbox request (the same bytes) from a new one.
std::uint32_t hash(const std::uint8_t* p, std::size_t n) {
    std::uint32_t h = 2166136261u;
    for (std::size_t i = 0; i < n; ++i)
        h = (h ^ p[i]) * 16777619u;
    return h;
}

}  // namespace

MasterChecks::MasterChecks(const esc::Segment& seg) : seg_(seg), slaves_epoch_(seg.slaves_epoch()) {
    for (std::size_t i = 0; i < seg.size(); ++i) {
        track_.push_back(track_of(i));
        slave_of_.push_back(&seg.slave(i));
    }
}

MasterChecks::Track MasterChecks::track_of(std::size_t i) const {
    const esc::Esc& e = seg_.slave(i).esc();
    Track t;
    t.sii = protocol::parse_sii(ConstBytes(e.eeprom().data(), e.eeprom().size()));
    t.write_mask = protocol::make_write_mask_table(e.peek(addr(Reg::FmmuCount)), e.peek(addr(Reg::SmCount)));
    return t;
}

void MasterChecks::follow_slaves() {
    if (seg_.slaves_epoch() == slaves_epoch_) return;
    slaves_epoch_ = seg_.slaves_epoch();
    std::vector<Track> tracks;
    std::vector<const esc::Slave*> slaves;
    for (std::size_t i = 0; i < seg_.size(); ++i) {
        const esc::Slave* s = &seg_.slave(i);
        const auto was = std::find(slave_of_.begin(), slave_of_.end(), s);
        tracks.push_back(was != slave_of_.end()
                             ? std::move(track_[static_cast<std::size_t>(was - slave_of_.begin())])
                             : track_of(i));
        slaves.push_back(s);
    }
    track_ = std::move(tracks);
    slave_of_ = std::move(slaves);
}

template <class F>
void MasterChecks::for_each_addressed(DatagramView d, F&& f) const {
    const std::size_t n = track_.size();
    switch (d.command()) {
        case Command::APRD:
        case Command::APWR:
        case Command::APRW:
        case Command::ARMW: {
            // Auto-increment: the p-th slave the frame reaches sees ADP + p, and is addressed when that is 0.
            std::size_t p = static_cast<std::uint16_t>(0u - d.adp());
            for (std::size_t i = 0; i < n; ++i)
                if (seg_.reached(i) && p-- == 0) {
                    f(i);
                    return;
                }
            return;
        }
        case Command::FPRD:
        case Command::FPWR:
        case Command::FPRW:
        case Command::FRMW:
            for (std::size_t i = 0; i < n; ++i) {
                if (!seg_.reached(i)) continue;
                if (seg_.slave(i).esc().addressed_fixed(d.adp())) f(i);
            }
            return;
        case Command::BRD:
        case Command::BWR:
        case Command::BRW:
            for (std::size_t i = 0; i < n; ++i)
                if (seg_.reached(i)) f(i);
            return;
        default:
            return;
    }
}

int MasterChecks::output_sm(std::size_t i) const {
    const esc::Esc& e = seg_.slave(i).esc();
    const unsigned n = std::min<unsigned>(e.peek(addr(Reg::SmCount)), protocol::kMaxSms);
    for (unsigned k = 0; k < n; ++k) {
        const protocol::SmConfig sm = e.sm_block(k);
        if (!sm.mailbox() && sm.ecat_writes() && sm.enabled() && sm.length > 0) return static_cast<int>(k);
    }
    return -1;
}

void MasterChecks::on_request(ConstBytes frame, std::uint64_t now_ns) {
    follow_slaves();
    if (frames_++ == 0) first_ns_ = now_ns;
    now_ns_ = now_ns;
    const std::size_t len = std::min(frame.size(), buf_.size());
    std::memcpy(buf_.data(), frame.data(), len);
    const Bytes b(buf_.data(), len);
    seg_.reachable();  // which slaves the frame reaches (Segment::reached)
    const protocol::ParsedFrame pf = protocol::parse_frame(b);
    if (pf.error != protocol::FrameError::None) return;
    for (std::size_t k = 0; k < pf.count; ++k) {
        const DatagramView d = pf.datagram(b, k);
        const Command c = d.command();
        if ((c == Command::ARMW || c == Command::FRMW) && covers(d, addr(Reg::DcSystemTime))) ++drift_frames_;
        // In datagram order: a read of the AL status before a state request in the same frame counts.
        if (protocol::physical_read(c) && covers(d, addr(Reg::AlStatus)))
            for_each_addressed(d, [&](std::size_t i) { track_[i].request_unread = false; });
        if (protocol::physical_write(c))
            for_each_addressed(d, [&](std::size_t i) { check_write(i, d, now_ns); });
    }
}

void MasterChecks::check_write(std::size_t i, DatagramView d, std::uint64_t now_ns) {
    Track& t = track_[i];
    const esc::Esc& e = seg_.slave(i).esc();
    if (covers(d, addr(Reg::SiiConfig))) t.eeprom_assigned = true;
    if (covers(d, addr(Reg::SiiControl) + 1) && (byte_at(d, addr(Reg::SiiControl) + 1) & 0x07) != 0 &&
        !t.eeprom_assigned && !found(Rule::EepromNotAssigned, i))
        find(Rule::EepromNotAssigned, i,
             fmt::format("EEPROM command 0x{:02X} written to 0x0502 before the master wrote 0x0500 (EEPROM "
                         "configuration: 0x{:02X}, PDI access state: 0x{:02X})",
                         byte_at(d, addr(Reg::SiiControl) + 1) & 0x07, e.peek(addr(Reg::SiiConfig)),
                         e.peek(addr(Reg::SiiPdiAccess))));
    if (covers(d, addr(Reg::AlControl))) check_al_control(i, byte_at(d, addr(Reg::AlControl)));
    if (covers(d, addr(Reg::DcActivation)) && (byte_at(d, addr(Reg::DcActivation)) & 0x03) == 0x03) {
        t.sync_pending = true;
        t.sync_request_ns = now_ns;
        t.drift_before_sync = drift_frames_;
    }
    // Register space only: process memory (from 0x1000) is the SyncManagers' and free RAM.
    if (d.ado() < protocol::kRegisterSpaceSize &&
        std::uint32_t{d.ado()} + d.length() <= protocol::kRegisterSpaceSize && d.length() > 0) {
        bool any = false;
        for (std::uint32_t a = d.ado(); a < std::uint32_t{d.ado()} + d.length() && !any; ++a)
            any = t.write_mask.writable(static_cast<std::uint16_t>(a));
        if (!any && !found(Rule::ReadOnlyRegisterWrite, i))
            find(
                Rule::ReadOnlyRegisterWrite, i,
                fmt::format("{} of {} bytes at 0x{:04X}: none of them may be written by EtherCAT (a real ESC "
                            "does not count it)",
                            protocol::to_string(d.command()), d.length(), d.ado()));
    }
}

void MasterChecks::check_al_control(std::size_t i, std::uint8_t control) {
    Track& t = track_[i];
    const esc::Esc& e = seg_.slave(i).esc();
    const std::uint8_t state = control & 0x0F;
    const std::uint8_t status = e.al_status();
    const std::uint8_t current = status & 0x0F;
    // Under device emulation the error indication is the echo of an acknowledge the master wrote (the ESC
    // copies AL control to AL status, ESC datasheet section II 0x0130): there is no error to acknowledge.
    if ((status & protocol::kAlErrorFlag) && !(control & protocol::kAlErrorFlag) && !e.device_emulation() &&
        !found(Rule::AlErrorNotAcknowledged, i))
        find(Rule::AlErrorNotAcknowledged, i,
             fmt::format("{} requested (AL control 0x{:02X}) while the AL status 0x{:02X} shows an error (AL "
                         "status code 0x{:04X}), without Error Ind Ack",
                         state_name(state), control, status, e.al_status_code()));
    if (t.request_unread && t.requested >= 0 && t.requested != state && !found(Rule::AlStatusNotRead, i))
        find(Rule::AlStatusNotRead, i,
             fmt::format("{} requested after {} without reading the AL status in between", state_name(state),
                         state_name(static_cast<std::uint8_t>(t.requested))));
    t.requested = state;
    t.request_unread = true;
    if (state != static_cast<std::uint8_t>(AlState::Op)) t.last_output_ns = 0;  // the master ends the cycle
    if (state == static_cast<std::uint8_t>(AlState::PreOp) &&
        current == static_cast<std::uint8_t>(AlState::Init))
        t.mailbox_check_pending = true;
    if (state == static_cast<std::uint8_t>(AlState::SafeOp) &&
        current == static_cast<std::uint8_t>(AlState::PreOp)) {
        t.safeop_check_pending = true;
        t.safeop_requested = true;
        const int k = output_sm(i);
        t.outputs_at_safeop = k >= 0 ? e.sm_buffer_writes(static_cast<unsigned>(k)) : 0;
    }
    if (state == static_cast<std::uint8_t>(AlState::Op) &&
        current == static_cast<std::uint8_t>(AlState::SafeOp))
        t.op_check_pending = true;
}

void MasterChecks::on_reply(ConstBytes frame, std::uint64_t now_ns) {
    follow_slaves();
    const std::size_t len = std::min(frame.size(), buf_.size());
    std::memcpy(buf_.data(), frame.data(), len);
    const Bytes b(buf_.data(), len);
    const protocol::ParsedFrame pf = protocol::parse_frame(b);
    if (pf.error == protocol::FrameError::None)
        for (std::size_t k = 0; k < pf.count; ++k) {
            const DatagramView d = pf.datagram(b, k);
            if ((d.command() == Command::APWR || d.command() == Command::FPWR) && d.wkc() > 0)
                for_each_addressed(d, [&](std::size_t i) { check_mailbox_request(i, d); });
        }
    // The checks a request left for after the frame: the frame itself may have carried what they look at
    // (a SyncManager written in the datagram before the state request, outputs before the OP request).
    for (std::size_t i = 0; i < track_.size(); ++i) {
        Track& t = track_[i];
        if (t.mailbox_check_pending) check_mailbox_configuration(i);
        if (t.safeop_check_pending) check_safeop_configuration(i);
        if (t.op_check_pending) check_op_outputs(i);
        if (t.sync_pending) check_sync_activation(i);
        t.mailbox_check_pending = t.safeop_check_pending = t.op_check_pending = t.sync_pending = false;
        check_cycle(i, now_ns);
    }
}

void MasterChecks::check_mailbox_configuration(std::size_t i) {
    const esc::Esc& e = seg_.slave(i).esc();
    const auto& sms = track_[i].sii.sync_managers;
    for (std::size_t k = 0; k < sms.size() && k < protocol::kMaxSms; ++k) {
        const protocol::SiiSyncManager& s = sms[k];
        if (s.type != protocol::sii::SmTypeMailboxOut && s.type != protocol::sii::SmTypeMailboxIn) continue;
        const protocol::SmConfig sm = e.sm_block(static_cast<unsigned>(k));
        if (sm.enabled() && sm.physical_start == s.start && sm.length == s.length &&
            (sm.control & (protocol::sm::CtrlModeMask | protocol::sm::CtrlDirMask)) ==
                (s.control & (protocol::sm::CtrlModeMask | protocol::sm::CtrlDirMask)))
            continue;
        if (!found(Rule::SmConfiguration, i))
            find(Rule::SmConfiguration, i,
                 fmt::format(
                     "PREOP requested with mailbox SM{} {} at 0x{:04X}, {} bytes, control 0x{:02X}; the "
                     "SII says 0x{:04X}, {} bytes, control 0x{:02X}",
                     k, sm.enabled() ? "enabled" : "disabled", sm.physical_start, sm.length, sm.control,
                     s.start, s.length, s.control));
        return;
    }
}

void MasterChecks::check_safeop_configuration(std::size_t i) {
    const esc::Slave& slave = seg_.slave(i);
    const esc::Esc& e = slave.esc();
    const auto& sms = track_[i].sii.sync_managers;
    const unsigned expected[2] = {slave.app().output_bytes(), slave.app().input_bytes()};
    unsigned configured[2] = {0, 0};
    bool declared[2] = {false, false};
    for (std::size_t k = 0; k < sms.size() && k < protocol::kMaxSms; ++k) {
        const protocol::SiiSyncManager& s = sms[k];
        const bool out = s.type == protocol::sii::SmTypeOutputs;
        if (!out && s.type != protocol::sii::SmTypeInputs) continue;
        declared[out ? 0 : 1] = true;
        const protocol::SmConfig sm = e.sm_block(static_cast<unsigned>(k));
        if (!sm.enabled() || sm.length == 0) continue;
        configured[out ? 0 : 1] += sm.length;
        const std::uint8_t mask = protocol::sm::CtrlModeMask | protocol::sm::CtrlDirMask;
        if ((sm.physical_start != s.start || (sm.control & mask) != (s.control & mask)) &&
            !found(Rule::SmConfiguration, i))
            find(Rule::SmConfiguration, i,
                 fmt::format("SAFEOP requested with {} SM{} at 0x{:04X}, control 0x{:02X}; the SII says "
                             "0x{:04X}, control 0x{:02X}",
                             out ? "output" : "input", k, sm.physical_start, sm.control, s.start, s.control));
        // Its FMMU: one of the direction the SyncManager's data flow needs, covering its first byte.
        bool mapped = false;
        const unsigned fmmus = std::min<unsigned>(e.peek(addr(Reg::FmmuCount)), protocol::kMaxFmmus);
        for (unsigned f = 0; f < fmmus && !mapped; ++f) {
            std::array<std::uint8_t, protocol::kFmmuSize> raw{};
            for (unsigned j = 0; j < raw.size(); ++j)
                raw[j] = e.peek(static_cast<std::uint16_t>(protocol::fmmu_addr(f) + j));
            const auto fm = protocol::FmmuConfig::unpack(raw);
            mapped = fm.active && (out ? fm.write : fm.read) && fm.physical_start <= sm.physical_start &&
                     sm.physical_start < std::uint32_t{fm.physical_start} + fm.length;
        }
        if (!mapped && !found(Rule::FmmuConfiguration, i))
            find(Rule::FmmuConfiguration, i,
                 fmt::format("SAFEOP requested while no active {} FMMU maps {} SM{} at 0x{:04X}",
                             out ? "write" : "read", out ? "output" : "input", k, sm.physical_start));
    }
    for (int dir = 0; dir < 2; ++dir)
        if (declared[dir] && configured[dir] != expected[dir] && !found(Rule::SmConfiguration, i))
            find(Rule::SmConfiguration, i,
                 fmt::format("SAFEOP requested with {} bytes of {} in the SyncManagers; the PDO assignment "
                             "has {} bytes",
                             configured[dir], dir == 0 ? "outputs" : "inputs", expected[dir]));
}

void MasterChecks::check_op_outputs(std::size_t i) {
    const Track& t = track_[i];
    const int k = output_sm(i);
    if (k < 0 || !t.safeop_requested) return;
    if (seg_.slave(i).esc().sm_buffer_writes(static_cast<unsigned>(k)) == t.outputs_at_safeop &&
        !found(Rule::OpWithoutOutputs, i))
        find(Rule::OpWithoutOutputs, i,
             fmt::format("OP requested, but no outputs reached SM{} since SAFEOP was requested", k));
}

void MasterChecks::check_sync_activation(std::size_t i) {
    const Track& t = track_[i];
    const esc::Esc& e = seg_.slave(i).esc();
    const std::uint64_t start = e.peek32(addr(Reg::DcStartTimeCyclic)) |
                                std::uint64_t{e.peek32(addr(Reg::DcStartTimeCyclic) + 4)} << 32;
    const std::uint64_t now = e.dc().system_time(t.sync_request_ns);
    // A 32-bit DC unit compares the low 32 bits (its start time wraps with its system time).
    const bool dc64 = (e.peek16(addr(Reg::Features)) & protocol::feature::Dc64Bit) != 0;
    const std::int64_t ahead = dc64 ? static_cast<std::int64_t>(start - now)
                                    : static_cast<std::int32_t>(static_cast<std::uint32_t>(start - now));
    if (ahead < 0 && !found(Rule::Sync0StartInThePast, i))
        find(Rule::Sync0StartInThePast, i,
             fmt::format("SYNC0 activated with start time {} ns, {} ns behind the slave's system time {} ns",
                         start, -ahead, now));
    if (t.drift_before_sync == 0 && !found(Rule::Sync0BeforeDriftCompensation, i))
        find(Rule::Sync0BeforeDriftCompensation, i,
             "SYNC0 activated before any ARMW/FRMW of the reference clock's system time (0x0910)");
}

void MasterChecks::check_mailbox_request(std::size_t i, DatagramView d) {
    Track& t = track_[i];
    const esc::Esc& e = seg_.slave(i).esc();
    if ((e.al_status() & 0x0F) == static_cast<std::uint8_t>(AlState::Init)) t.mailbox_counter = 0;
    const unsigned n = std::min<unsigned>(e.peek(addr(Reg::SmCount)), protocol::kMaxSms);
    for (unsigned k = 0; k < n; ++k) {
        const protocol::SmConfig sm = e.sm_block(k);
        if (!sm.mailbox() || !sm.ecat_writes() || !sm.enabled()) continue;
        if (d.ado() != sm.physical_start || d.length() < protocol::kMailboxHeaderSize) return;
        // Mailbox header (ETG.1000.4): length(2) address(2) channel/priority(1) type/counter(1).
        const std::uint8_t cnt = (d.data()[5] >> 4) & 0x07;
        const std::size_t used =
            std::min<std::size_t>(d.length(), protocol::kMailboxHeaderSize + ld_le16(d.data()));
        const std::uint32_t h = hash(d.data(), used);
        const std::uint8_t prev = t.mailbox_counter;
        const std::uint8_t next = static_cast<std::uint8_t>(prev % 7 + 1);
        const bool repeat = cnt == prev && h == t.mailbox_hash;
        if (cnt != 0 && prev != 0 && cnt != next && !repeat && !found(Rule::MailboxCounter, i))
            find(Rule::MailboxCounter, i,
                 fmt::format("mailbox request with counter {} after {} (expected {}{})", cnt, prev, next,
                             cnt == prev ? ", or the same request repeated" : ""));
        t.mailbox_counter = cnt;
        t.mailbox_hash = h;
        return;
    }
}

void MasterChecks::check_cycle(std::size_t i, std::uint64_t now_ns) {
    Track& t = track_[i];
    const esc::Esc& e = seg_.slave(i).esc();
    const int k = output_sm(i);
    if (k < 0) return;
    const std::uint64_t writes = e.sm_buffer_writes(static_cast<unsigned>(k));
    if (writes == t.output_writes) return;
    t.output_writes = writes;
    const protocol::SmConfig sm = e.sm_block(static_cast<unsigned>(k));
    // Process data watchdog time: 0x0420 units of (0x0400 + 2) x 40 ns (ESC datasheet section II).
    const std::uint64_t wd_ns = std::uint64_t{e.peek16(addr(Reg::WatchdogTimeProcessData))} *
                                (e.peek16(addr(Reg::WatchdogDivider)) + 2u) * 40u;
    if (t.last_output_ns != 0 && (sm.control & protocol::sm::CtrlWatchdog) && wd_ns > 0 &&
        now_ns - t.last_output_ns > wd_ns && !found(Rule::WatchdogShorterThanCycle, i))
        find(Rule::WatchdogShorterThanCycle, i,
             fmt::format(
                 "{:.3f} ms between two writes of the outputs (SM{}) in OP; the watchdog is {:.3f} ms",
                 static_cast<double>(now_ns - t.last_output_ns) / 1e6, k, static_cast<double>(wd_ns) / 1e6));
    // Measured from a write in OP to the next write, wherever the slave is then (it may have left OP because
    // of the gap); a state request below OP ends the measurement (check_al_control).
    t.last_output_ns = (e.al_status() & 0x0F) == static_cast<std::uint8_t>(AlState::Op) ? now_ns : 0;
}

bool MasterChecks::failed(Rule r) const {
    return std::any_of(findings_.begin(), findings_.end(), [r](const Finding& f) { return f.rule == r; });
}

bool MasterChecks::found(Rule r, std::size_t slave) {
    for (Finding& f : findings_)
        if (f.rule == r && f.slave == slave) {
            ++f.count;
            return true;
        }
    return false;
}

void MasterChecks::find(Rule r, std::size_t slave, std::string message) {
    findings_.push_back({r, slave, frames_, now_ns_ - first_ns_, std::move(message), 1});
}

}  // namespace vecat::report
