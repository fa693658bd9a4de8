// The replay (about 620 lines): the frames of a capture sent to a line in their recorded order and time,
// each reply datagram judged against the recorded one, and the line rebuilt from the capture that it is
// replayed against (build_recovered_line: device, ESC variant and quirks per recovered slave). The two share
// the rules of what a capture tells; the recovery of those facts from the datagrams is in recover.cpp.
#include "replay/replay.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "device/simple_devices.hpp"
#include "network/build.hpp"
#include "network/dictionary_file.hpp"
#include "protocol/frame.hpp"
#include "protocol/mailbox.hpp"
#include "protocol/registers.hpp"
#include "protocol/sii.hpp"
#include "protocol/sync_manager.hpp"
#include "protocol/topology.hpp"

namespace vecat::replay {

using protocol::Command;

double ReplayReport::wkc_percent() const {
    return datagrams ? 100.0 * static_cast<double>(wkc_same) / static_cast<double>(datagrams) : 100.0;
}

double ReplayReport::data_percent() const {
    return reads ? 100.0 *
                       static_cast<double>(reads_same + reads_time + reads_counter + reads_padding +
                                           reads_timing) /
                       static_cast<double>(reads)
                 : 100.0;
}

namespace {

constexpr std::size_t kSourceMac0 = 6;
constexpr std::uint8_t kForwardedBit = 0x02;
constexpr std::size_t kFramesPerTally = 8;
// A longer pause between two frames is skipped over: the firmware runs as if it had been this long. Whatever
// a device does on its own (watchdogs, EEPROM loads, mailbox answers) is over well before it.
constexpr std::uint64_t kMaxGapNs = 1'000'000'000;
// At most this many firmware passes between two frames; the rest of a longer pause goes in one more pass
// (each run catches up with the time since the last). The replay's work stays bounded by the capture's
// frames whatever the devices' deadlines (a SYNC0 of a short cycle wants a run every 250 us).
constexpr unsigned kMaxTicksPerGap = 64;

bool pure_read(Command c) {
    return c == Command::APRD || c == Command::FPRD || c == Command::BRD || c == Command::LRD;
}
bool pure_write(Command c) {
    return c == Command::APWR || c == Command::FPWR || c == Command::BWR || c == Command::LWR;
}
bool logical(Command c) {
    return c >= Command::LRD && c <= Command::LRW;
}

// The master's frame for a reply whose request the capture lacks: the forwarded bit cleared, the working
// counters 0, auto-increment and broadcast addresses counted back, read data zeroed (masters send reads
// with zeros). Read-write commands keep the reply's data: what was written is unknown (known[i] false).
std::vector<std::uint8_t> rebuild_request(const std::vector<std::uint8_t>& reply, std::size_t slaves,
                                          std::vector<std::uint8_t>& known) {
    std::vector<std::uint8_t> f = reply;
    f[kSourceMac0] = static_cast<std::uint8_t>(f[kSourceMac0] & ~kForwardedBit);
    const protocol::ParsedFrame pf = protocol::parse_frame(f);
    known.assign(pf.count, 1);
    for (std::size_t i = 0; i < pf.count; ++i) {
        protocol::DatagramView d = pf.datagram(f, i);
        d.set_adp(request_adp(d.raw_command(), d.adp(), slaves));
        d.set_wkc(0);
        if (pure_read(d.command()))
            std::fill_n(d.data(), d.length(), 0);
        else if (!pure_write(d.command()))
            known[i] = 0;
    }
    return f;
}

class Replayer {
  public:
    Replayer(const Capture& c, const Pairing& p, esc::Segment& line, const ReplayOptions& o)
        : c_(c), p_(p), line_(line), o_(o) {}

    ReplayReport run() {
        index_reads();
        r_.unanswered = p_.unanswered;
        std::size_t slaves = line_.size();
        for (const Exchange& e : p_.exchanges) {
            current_ = static_cast<std::size_t>(&e - p_.exchanges.data());
            const CapturedFrame& rq = c_.frames[e.request];
            const CapturedFrame& rp = c_.frames[e.reply];
            advance(rq.time_ns);
            std::vector<std::uint8_t> known;
            std::vector<std::uint8_t> frame =
                e.request_recorded ? rq.bytes : rebuild_request(rp.bytes, slaves, known);
            if (e.request_recorded) known.assign(protocol::kMaxDatagramsPerFrame, 1);
            r_.rebuilt_requests += !e.request_recorded;
            ++r_.exchanges;
            std::size_t len = frame.size();
            frame.resize(std::max(len, protocol::kMinEthFrame) + 64);
            const bool replied = line_.process_frame(frame, len, rq.time_ns);
            frame.resize(len);
            compare(rp, replied ? &frame : nullptr, known);
        }
        return std::move(r_);
    }

  private:
    // The same datagram (command, address, length) as recorded in every exchange, for the timing verdict.
    struct Key {
        std::uint8_t cmd;
        std::uint32_t address;
        std::uint16_t length;
        auto operator<=>(const Key&) const = default;
    };
    struct Seen {
        std::size_t exchange;
        const std::uint8_t* datagram;  // in the recorded reply
    };
    static Key key_of(const protocol::DatagramView& d) {
        return {d.raw_command(),
                ld_le32(d.data() - protocol::kDatagramHeaderSize + protocol::datagram::Address), d.length()};
    }
    void index_reads() {
        for (std::size_t x = 0; x < p_.exchanges.size(); ++x) {
            const auto& f = c_.frames[p_.exchanges[x].reply].bytes;
            const protocol::ParsedFrame pf = protocol::parse_frame(f);
            for (std::size_t i = 0; i < pf.count; ++i) {
                const std::uint8_t* h = f.data() + pf.offsets[i];
                protocol::DatagramView d(const_cast<std::uint8_t*>(h));
                seen_[key_of(d)].push_back({x, h});
            }
        }
    }
    // The real device answered the same datagram with this working counter (and data, when data is given)
    // in a nearby exchange.
    bool nearby(const protocol::DatagramView& recorded, std::uint16_t wkc, const std::uint8_t* data) const {
        auto it = seen_.find(key_of(recorded));
        if (it == seen_.end()) return false;
        const std::uint64_t t = c_.frames[p_.exchanges[current_].reply].time_ns;
        for (const Seen& s : it->second) {
            const std::size_t dx = s.exchange > current_ ? s.exchange - current_ : current_ - s.exchange;
            if (dx == 0 || dx > o_.timing_exchanges) continue;
            const std::uint64_t ts = c_.frames[p_.exchanges[s.exchange].reply].time_ns;
            if ((ts > t ? ts - t : t - ts) > o_.timing_ns) continue;
            protocol::DatagramView other(const_cast<std::uint8_t*>(s.datagram));
            if (other.wkc() != wkc) continue;
            if (data && !std::equal(data, data + other.length(), other.data())) continue;
            return true;
        }
        return false;
    }

    // Where the message of a read of a slave's mailbox-in SyncManager area ends (mailbox header and the
    // length it announces, ETG.1000.4 5.6); the whole read for any other datagram.
    std::size_t mailbox_message_end(const protocol::DatagramView& d) const {
        const std::size_t all = d.length();
        const Command cmd = d.command();
        if (d.ado() < protocol::kRegisterSpaceSize || d.length() < protocol::kMailboxHeaderSize ||
            (cmd != Command::FPRD && cmd != Command::APRD))
            return all;
        for (std::size_t k = 0; k < line_.size(); ++k) {
            const esc::Esc& e = line_.slave(k).esc();
            const bool addressed = cmd == Command::FPRD
                                       ? e.peek16(protocol::addr(protocol::Reg::StationAddress)) == d.adp()
                                       : static_cast<std::uint16_t>(0u - d.adp()) == k;
            if (!addressed) continue;
            for (unsigned i = 0; i < e.config().sm_count; ++i) {
                const auto c = e.sm_config(i);
                if (c.start != d.ado() ||
                    (c.control & protocol::sm::CtrlModeMask) != protocol::sm::CtrlModeMailbox ||
                    (c.control & protocol::sm::CtrlDirMask) != protocol::sm::CtrlDirRead)
                    continue;
                const std::size_t end = protocol::kMailboxHeaderSize + ld_le16(d.data());
                return std::min(end, all);
            }
            return all;
        }
        return all;
    }

    // The firmware between two frames runs as the serve loop runs it (Segment, "Firmware when it is
    // needed"): at the slaves' deadlines (Segment::next_firmware_ns), no closer together than tick_ns. Each
    // run catches up with the time since the last one, so a pause costs work by the slaves' deadlines (at
    // most kMaxLagCycles local cycles apart), not by its length; a longer one than kMaxGapNs none more, and
    // past kMaxTicksPerGap passes the rest of it is one pass.
    void advance(std::uint64_t t) {
        if (!started_) {
            started_ = true;
            last_tick_ = t;
            return;
        }
        if (t > last_tick_ + kMaxGapNs) last_tick_ = t - kMaxGapNs;
        for (unsigned ticks = 1;; ++ticks) {
            std::uint64_t next = std::max(last_tick_ + o_.tick_ns, line_.next_firmware_ns());
            if (next > t) return;
            if (ticks == kMaxTicksPerGap) next = t;
            last_tick_ = next;
            line_.tick(last_tick_);
            if (next == t) return;
        }
    }

    void compare(const CapturedFrame& recorded, const std::vector<std::uint8_t>* got,
                 const std::vector<std::uint8_t>& known) {
        const protocol::ParsedFrame pr = protocol::parse_frame(recorded.bytes);
        protocol::ParsedFrame pg;
        if (got) pg = protocol::parse_frame(*got);
        for (std::size_t i = 0; i < pr.count; ++i) {
            protocol::DatagramView want(const_cast<std::uint8_t*>(recorded.bytes.data()) + pr.offsets[i]);
            const Command cmd = want.command();
            ++r_.datagrams;
            Tally& t = r_.by_address[{want.raw_command(), want.ado()}];
            ++t.datagrams;
            Difference d;
            d.frame = recorded.number;
            d.datagram = i;
            d.command = want.raw_command();
            d.adp = want.adp();
            d.ado = want.ado();
            d.recorded_wkc = want.wkc();
            const bool has = got && pg.error == protocol::FrameError::None && i < pg.count;
            const bool data_known = i < known.size() && known[i];
            const bool counted =
                data_known && (protocol::physical_read(cmd) || logical(cmd)) && cmd != Command::LWR;
            if (!has) {
                d.no_reply = d.working_counter = true;
                ++t.wkc_differs;
                if (counted) logical(cmd) ? ++r_.process_reads : ++r_.reads;
                note(t, d);
                continue;
            }
            protocol::DatagramView mine(const_cast<std::uint8_t*>(got->data()) + pg.offsets[i]);
            d.replayed_wkc = mine.wkc();
            if (mine.wkc() != want.wkc()) {
                d.working_counter = true;
                if (nearby(want, mine.wkc(), nullptr)) {
                    d.verdict = Verdict::Timing;
                    ++r_.wkc_timing;
                    ++t.wkc_timing;
                }
                ++t.wkc_differs;
                if (counted) logical(cmd) ? ++r_.process_reads : ++r_.reads;
                note(t, d);
                continue;
            }
            ++r_.wkc_same;
            if (!counted) continue;
            const std::size_t n = std::min<std::size_t>(want.length(), mine.length());
            const std::size_t message_end = mailbox_message_end(want);
            Verdict v = Verdict::Same;
            // The offset of d.first_byte in the data: the address wraps at 16 bits (an ADO near 0xFFFF, a
            // logical address's low half), the offset does not.
            std::size_t first = 0;
            for (std::size_t k = 0; k < n; ++k) {
                if (want.data()[k] == mine.data()[k]) continue;
                const Verdict b = logical(cmd)       ? Verdict::ProcessData
                                  : k >= message_end ? Verdict::MailboxPadding
                                  : want.ado() + k < protocol::kRegisterSpaceSize
                                      ? register_class(static_cast<std::uint16_t>(want.ado() + k))
                                      : Verdict::Differs;
                if (v == Verdict::Same) {
                    first = k;
                    d.first_byte = static_cast<std::uint16_t>(want.ado() + k);
                }
                if (b > v) {
                    v = b;
                    if (b == Verdict::Differs) {
                        first = k;
                        d.first_byte = static_cast<std::uint16_t>(want.ado() + k);
                    }
                }
            }
            if (v > Verdict::Same && v != Verdict::ProcessData && nearby(want, mine.wkc(), mine.data()))
                v = Verdict::Timing;
            if (logical(cmd)) {
                ++r_.process_reads;
                r_.process_same += v == Verdict::Same;
            } else {
                ++r_.reads;
                r_.reads_same += v == Verdict::Same;
                r_.reads_time += v == Verdict::TimeDependent;
                r_.reads_counter += v == Verdict::Counter;
                r_.reads_padding += v == Verdict::MailboxPadding;
                r_.reads_timing += v == Verdict::Timing;
            }
            if (v == Verdict::Same) continue;
            d.verdict = v;
            const std::size_t from = first;
            const std::size_t shown = std::min(Difference::kShownBytes, n - from);
            d.recorded.assign(want.data() + from, want.data() + from + shown);
            d.replayed.assign(mine.data() + from, mine.data() + from + shown);
            (v == Verdict::Differs ? t.data_differs : t.data_excused)++;
            note(t, d);
        }
    }

    void note(Tally& t, const Difference& d) {
        if (t.frames.size() < kFramesPerTally) t.frames.push_back(d.frame);
        if (r_.differences.size() < o_.max_differences) r_.differences.push_back(d);
    }

    const Capture& c_;
    const Pairing& p_;
    esc::Segment& line_;
    const ReplayOptions& o_;
    ReplayReport r_;
    std::map<Key, std::vector<Seen>> seen_;
    std::size_t current_ = 0;
    bool started_ = false;
    std::uint64_t last_tick_ = 0;
};

}  // namespace

namespace {

// The PDI control word (SII word 0: 0x0140 and 0x0141) of a device whose capture does not tell it. Only an
// ESC with a digital I/O PDI has the digital output register 0x0F00-0x0F03, so a SyncManager there says
// digital I/O; a device without SyncManagers and without a mailbox has no PDI at all. Neither has a
// µController to set AL status, so both have device emulation (0x0141 bit 0). Anything else is a device
// with a µController on an SPI PDI (the PDI type is not visible on the wire).
// PDI types (ESC datasheet section II 0x0140).
constexpr std::uint8_t kDigitalIoPdi = 0x04, kSpiPdi = 0x05;

std::uint16_t presumed_pdi_control(const std::vector<std::uint8_t>& img) {
    const protocol::SiiInfo info = protocol::parse_sii(img);
    constexpr std::uint16_t kDeviceEmulation = std::uint16_t{protocol::esc_config::DeviceEmulation} << 8;
    for (const auto& sm : info.sync_managers)
        if (sm.start >= protocol::addr(protocol::Reg::DigitalOutputData) &&
            sm.start < protocol::addr(protocol::Reg::DigitalOutputData) + protocol::kDigitalOutputSize)
            return kDeviceEmulation | kDigitalIoPdi;
    const bool mailbox = (info.std_rx_mbx_size != 0 && info.std_rx_mbx_size != 0xFFFF) ||
                         (info.mailbox_protocols != 0 && info.mailbox_protocols != 0xFFFF);
    if (info.sync_managers.empty() && !mailbox) return kDeviceEmulation;
    return kSpiPdi;
}

}  // namespace

// The SII image of a recovered slave: the words read, 0xFFFF elsewhere (an erased EEPROM), as large as its
// size word (0x003E: (value + 1) kibibits) says, or large enough for the words read. A configuration area
// read without its checksum word gets the checksum it must have had.
std::vector<std::uint8_t> recovered_sii_image(const RecoveredSlave& s) {
    namespace sii = protocol::sii;
    const auto known = [&](unsigned w) { return w < s.known.size() && s.known[w]; };
    std::size_t bytes = std::max<std::size_t>(2 * s.sii.size(), 2 * sii::FirstCategory);
    if (known(sii::Size)) bytes = std::max<std::size_t>(bytes, (std::size_t{s.sii[sii::Size]} + 1) * 128);
    // An ESC that reports two address bytes (0x0502 bit 7) has an EEPROM larger than 16 Kbit.
    if (s.sii_two_address_bytes.value_or(false)) bytes = std::max<std::size_t>(bytes, 4096);
    bytes = (bytes + 127) / 128 * 128;
    std::vector<std::uint8_t> img(bytes, 0xFF);
    for (std::size_t w = 0; w < s.sii.size(); ++w)
        if (s.known[w]) st_le16(img.data() + 2 * w, s.sii[w]);
    // Configuration words neither read nor loaded into a register the master read: 0, as on most devices;
    // the PDI control word from what the device must have (ESC datasheet section II 0x0140, 0x0F00).
    for (unsigned w = sii::PdiConfig; w < sii::Checksum; ++w)
        if (!known(w)) st_le16(img.data() + 2 * w, 0);
    if (!known(sii::PdiControl)) st_le16(img.data() + 2 * sii::PdiControl, presumed_pdi_control(img));
    if (!known(sii::Checksum)) img[2 * sii::Checksum] = protocol::sii_config_crc(ConstBytes(img.data(), 14));
    return img;
}

namespace {

// The known words of s over an SII image (grown to hold them, in whole 128-byte blocks). An ESC whose first
// DL status read showed its PDI watchdog reloaded has a PDI (ESC datasheet section II 0x0110 bit 1): one of
// digital I/O, as the EL terminals that show it, when the image has none and the capture did not read the
// PDI control word. The checksum of the configuration words made again when the capture did not hold it
// (ETG.2010, word 7).
std::vector<std::uint8_t> sii_laid_over(std::vector<std::uint8_t> img, const RecoveredSlave& s) {
    namespace sii = protocol::sii;
    const auto known = [&](unsigned w) { return w < s.known.size() && s.known[w]; };
    const std::size_t bytes = (std::max(img.size(), 2 * s.sii.size()) + 127) / 128 * 128;
    img.resize(bytes, 0xFF);
    for (std::size_t w = 0; w < s.sii.size(); ++w)
        if (s.known[w]) st_le16(img.data() + 2 * w, s.sii[w]);
    if (!known(sii::PdiControl) && s.dl_status && (*s.dl_status & protocol::dl_status::PdiWatchdogOk) &&
        img[2 * sii::PdiControl] == 0)
        img[2 * sii::PdiControl] = kDigitalIoPdi;
    if (!known(sii::Checksum)) img[2 * sii::Checksum] = protocol::sii_config_crc(ConstBytes(img.data(), 14));
    return img;
}

// The application of a device rebuilt from a capture, which refuses the state changes the real device
// refused there (RefusedTransition); everything else is the wrapped application's.
class RefusingApplication final : public esc::Application {
  public:
    RefusingApplication(std::unique_ptr<esc::Application> inner, std::vector<RefusedTransition> refused)
        : inner_(std::move(inner)), refused_(std::move(refused)) {}
    unsigned output_bytes() const override { return inner_->output_bytes(); }
    unsigned input_bytes() const override { return inner_->input_bytes(); }
    protocol::AlStatusCode check_transition(protocol::AlState from, protocol::AlState to) override {
        for (const auto& r : refused_)
            if (r.from == static_cast<std::uint8_t>(from) && r.to == static_cast<std::uint8_t>(to))
                return static_cast<protocol::AlStatusCode>(r.code);
        return inner_->check_transition(from, to);
    }
    void on_state_change(protocol::AlState from, protocol::AlState to) override {
        inner_->on_state_change(from, to);
    }
    void on_al_error(protocol::AlStatusCode code) override { inner_->on_al_error(code); }
    void exchange(std::uint64_t now_ns, ConstBytes outputs, bool apply, Bytes inputs) override {
        inner_->exchange(now_ns, outputs, apply, inputs);
    }
    void outputs_safe_state() override { inner_->outputs_safe_state(); }
    esc::MailboxProtocol* mailbox_protocol(protocol::MailboxType t) override {
        return inner_->mailbox_protocol(t);
    }
    void tick(std::uint64_t now_ns) override { inner_->tick(now_ns); }
    void sync_event(unsigned signal, std::uint64_t now_ns) override { inner_->sync_event(signal, now_ns); }
    bool refresh_inputs(Bytes inputs) override { return inner_->refresh_inputs(inputs); }
    void attach(esc::Slave& slave) override { inner_->attach(slave); }
    esc::OpReadiness op_readiness(std::uint64_t now_ns, std::uint64_t since_ns) override {
        return inner_->op_readiness(now_ns, since_ns);
    }
    void on_revision_change(std::uint32_t revision) override { inner_->on_revision_change(revision); }

  private:
    std::unique_ptr<esc::Application> inner_;
    std::vector<RefusedTransition> refused_;
};

esc::EscConfig recovered_config(const RecoveredSlave& s, esc::EscConfig cfg) {
    const auto byte = [&](std::size_t a) { return s.esc_info[a]; };
    if (byte(0)) cfg.type = *byte(0);
    if (byte(1)) cfg.revision = *byte(1);
    if (byte(2) && byte(3)) cfg.build = static_cast<std::uint16_t>(*byte(2) | *byte(3) << 8);
    if (s.fmmus_from_writes) cfg.fmmu_count = *s.fmmus_from_writes;
    if (s.sms_from_writes) cfg.sm_count = *s.sms_from_writes;
    if (byte(4)) cfg.fmmu_count = *byte(4);
    if (byte(5)) cfg.sm_count = *byte(5);
    if (byte(6) && *byte(6) > 0) cfg.ram_bytes = std::uint32_t{*byte(6)} * 1024;
    if (byte(7)) cfg.port_descriptor = *byte(7);
    if (byte(8) && byte(9)) cfg.features = static_cast<std::uint16_t>(*byte(8) | *byte(9) << 8);
    if (s.sii_read_8_bytes) cfg.sii_read_8_bytes = *s.sii_read_8_bytes;
    if (s.dc_system_time_unit) cfg.dc_system_time_unit = *s.dc_system_time_unit;
    if (s.sii_status_bits) cfg.sii_status_bits = *s.sii_status_bits;
    for (unsigned b = 0; b < 4; ++b)
        if (s.dl_control[b])
            cfg.dl_control =
                (cfg.dl_control & ~(0xFFu << (8 * b))) | (std::uint32_t{*s.dl_control[b]} << (8 * b));
    return cfg;
}

}  // namespace

ReplayReport replay(const Capture& capture, const Pairing& pairing, esc::Segment& line,
                    const ReplayOptions& options) {
    return Replayer(capture, pairing, line, options).run();
}

std::unique_ptr<esc::Segment> build_recovered_line(const RecoveredLine& line,
                                                   std::vector<std::string>& notes) {
    auto seg = std::make_unique<esc::Segment>();
    for (std::size_t i = 0; i < line.slaves.size(); ++i) {
        const RecoveredSlave& s = line.slaves[i];
        const std::string at = "slave " + std::to_string(i) + ": ";
        network::DeviceParts parts;
        bool made = false;
        if (s.sii_words_known() > 0) {
            std::vector<std::string> n;
            try {
                // The device's quirks the capture shows: a download response that echoed the request's
                // data, a mailbox-in buffer opened as soon as the master emptied it.
                const bool echoes = s.coe.download_echo, opens = s.coe.open_early;
                const std::function<void(device::DeviceDescription&)> echo =
                    echoes || opens ? std::function<void(device::DeviceDescription&)>(
                                          [echoes, opens](device::DeviceDescription& d) {
                                              d.quirks.sdo_download_echo = echoes;
                                              d.quirks.mailbox_open_early = opens;
                                          })
                                    : nullptr;
                parts = network::device_from_sii(recovered_sii_image(s), n, echo);
                if (echoes)
                    notes.push_back(at +
                                    "quirk sdo_download_echo: its SDO download responses repeat the "
                                    "request's data in their reserved bytes");
                if (opens)
                    notes.push_back(
                        at +
                        "quirk mailbox_open_early: its SM1 status reads 0x80 (write buffer in use) "
                        "right after the master read a message");
                if (!s.coe.empty() && parts.model.dictionary) {
                    // The mailbox answers the capture shows, over the dictionary generated from the SII.
                    auto dict = std::make_shared<network::DeviceDictionary>();
                    dict->objects = merge_dictionary(*parts.model.dictionary, s.coe, dict->values);
                    n.clear();
                    parts = network::device_from_sii(recovered_sii_image(s), n, echo, dict);
                    notes.push_back(at + fmt::format("CoE: {} objects, {} values from the capture's mailbox",
                                                     s.coe.objects.size(), s.coe.values.size()));
                }
                made = true;
                notes.push_back(at + "from " + std::to_string(s.sii_words_known()) +
                                " SII words of the capture");
            } catch (const std::exception& x) {
                notes.push_back(at + "the SII words of the capture make no device (" + x.what() + ")");
            }
            for (const auto& x : n)
                notes.push_back(at + x);
        } else {
            notes.push_back(at + "the capture holds no SII read: a bare device without PDI");
        }
        if (!made) {
            const device::DeviceDescription d = device::coupler();
            parts.model = esc::DeviceModel::of(d);
            parts.factory = [](const device::DeviceDescription& dd) {
                return std::unique_ptr<esc::Application>(
                    std::make_unique<esc::ProcessImageApplication>(dd.output_bytes(), dd.input_bytes()));
            };
            // The words the capture holds, laid over the bare device's image: the master reads back what it
            // read from the real device (TwinCAT's scan reads the identity words only).
            if (s.sii_words_known() > 0) {
                parts.model.sii_image = std::make_shared<const std::vector<std::uint8_t>>(
                    sii_laid_over(*parts.model.sii_image, s));
                notes.push_back(
                    at + fmt::format("a bare device, with the {} SII words of the capture in its image",
                                     s.sii_words_known()));
            }
        }
        parts.esc = recovered_config(s, parts.esc);
        if (!s.refused.empty()) {
            parts.factory = [inner = parts.factory,
                             refused = s.refused](const device::DeviceDescription& dd) {
                return std::unique_ptr<esc::Application>(
                    std::make_unique<RefusingApplication>(inner(dd), refused));
            };
            for (const auto& r : s.refused)
                notes.push_back(
                    at + fmt::format("refuses {} -> {} with AL status code 0x{:04X}, as the capture "
                                     "shows (the reason is the device's)",
                                     protocol::to_string(static_cast<protocol::AlState>(r.from)),
                                     protocol::to_string(static_cast<protocol::AlState>(r.to)), r.code));
        }
        const std::size_t info = static_cast<std::size_t>(
            std::count_if(s.esc_info.begin(), s.esc_info.end(), [](const auto& b) { return b.has_value(); }));
        notes.push_back(
            at +
            fmt::format("ESC type 0x{:02X} rev {} build {}, {} FMMUs, {} SMs, {} KiB, ports 0x{:02X}, "
                        "features 0x{:04X} ({} of {} information bytes from the capture{})",
                        parts.esc.type, parts.esc.revision, parts.esc.build, parts.esc.fmmu_count,
                        parts.esc.sm_count, parts.esc.ram_bytes / 1024, parts.esc.port_descriptor,
                        parts.esc.features, info, kEscInfoBytes,
                        s.esc_info_from_broadcast == 0
                            ? std::string()
                            : fmt::format(", {} of them from a broadcast read", s.esc_info_from_broadcast)));
        auto slave =
            std::make_unique<esc::Slave>(parts.model, parts.esc, parts.factory(*parts.model.description));
        if (s.al_control_latency_ns) {
            slave->set_al_control_latency(*s.al_control_latency_ns);
            notes.push_back(at +
                            fmt::format("reads AL control {} us after the master wrote it (a second write "
                                        "in between was refused in the capture)",
                                        *s.al_control_latency_ns / 1000));
        }
        seg->add(std::move(slave), parts.factory);
    }
    // The tree, when the DL status of every slave was read; else a line.
    const bool all = !line.slaves.empty() && std::all_of(line.slaves.begin(), line.slaves.end(),
                                                         [](const auto& s) { return s.dl_status; });
    if (all) {
        std::vector<std::uint8_t> open;
        for (const auto& s : line.slaves)
            open.push_back(protocol::open_ports(*s.dl_status));
        const auto up = protocol::topology_from_open_ports(open);
        std::vector<int> parents;
        std::vector<std::uint8_t> ports;
        std::vector<std::uint32_t> delays(up.size(), 0);
        for (const auto& u : up) {
            parents.push_back(u.parent);
            ports.push_back(static_cast<std::uint8_t>(u.parent < 0 ? 1 : u.port));
        }
        std::string why;
        if (!seg->set_topology(parents, ports, delays, &why))
            notes.push_back("the DL status of the slaves gives no tree (" + why + "): a line");
    }
    return seg;
}

std::string format_report(const ReplayReport& r) {
    std::string s;
    s += fmt::format(
        "exchanges: {} ({} with the request rebuilt from the reply), {} master frames without reply\n",
        r.exchanges, r.rebuilt_requests, r.unanswered);
    s += fmt::format(
        "working counter as recorded: {} of {} datagrams ({:.2f} %); {} more as the device gave it "
        "to the same datagram shortly before or after (timing)\n",
        r.wkc_same, r.datagrams, r.wkc_percent(), r.wkc_timing);
    s += fmt::format(
        "register and memory reads: {} of {} as recorded ({:.2f} %): {} same, {} differ in time-dependent "
        "values, {} in counters, {} in mailbox padding, {} by timing\n",
        r.reads_same + r.reads_time + r.reads_counter + r.reads_padding + r.reads_timing, r.reads,
        r.data_percent(), r.reads_same, r.reads_time, r.reads_counter, r.reads_padding, r.reads_timing);
    s += fmt::format("process data reads: {} of {} with the recorded inputs\n", r.process_same,
                     r.process_reads);
    bool header = false;
    for (const auto& [key, t] : r.by_address) {
        if (!t.wkc_differs && !t.data_differs && !t.data_excused) continue;
        if (!header) {
            s += "differences by command and address:\n";
            header = true;
        }
        const auto cmd = static_cast<Command>(key.first);
        std::string frames;
        for (std::size_t f : t.frames)
            frames += (frames.empty() ? "" : ", ") + std::to_string(f);
        s += fmt::format(
            "  {:<4} 0x{:04X} {:<22} {:>5} datagrams: working counter {:>4}, data {:>4} (+{} excused); "
            "frames {}\n",
            protocol::to_string(cmd), key.second,
            logical(cmd) ? std::string("logical") : area_name(key.second), t.datagrams, t.wkc_differs,
            t.data_differs, t.data_excused, frames);
    }
    return s;
}

}  // namespace vecat::replay
