// The project's master (about 900 lines): one start-up sequence in the order of the masters' checklist
// (scan, SII, topology, mailboxes, PDO sizes and mapped entries by CoE, SoE or SII, FMMUs per SyncManager, DC
// on a tree, state changes) and the cyclic exchange (its frames back to back, Master::transact_frames), each
// step a function that builds on the SlaveInfo the steps before filled; one sequence, so one file. The
// mailbox protocols' clients are beside it (coe_client.cpp, foe_client.cpp, eoe_client.cpp, soe_client.cpp).
#include "master/master.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>

#include "master/coe_client.hpp"
#include "master/soe_client.hpp"
#include "protocol/fmmu.hpp"
#include "protocol/registers.hpp"
#include "protocol/sync_manager.hpp"
#include "protocol/topology.hpp"

namespace vecat::master {

using protocol::AlState;
using protocol::Command;
using protocol::DatagramHeader;
using protocol::FmmuConfig;
using protocol::Reg;
using protocol::SmConfig;

namespace {
// Broadcast, from a unicast, locally administered source address (the ESC sets bit 0x02 of the first byte
// on return).
constexpr protocol::EthernetHeader kFrameHeader{protocol::kBroadcastMac,
                                                {0x10, 0x10, 0x10, 0x10, 0x10, 0x10}};
std::uint16_t ra(Reg r) {
    return protocol::addr(r);
}
}  // namespace

Master::Master(net::Link& link, MasterOptions opt) : link_(link), opt_(opt) {}

std::size_t Master::build_frame(std::span<DatagramRequest> dgs, std::uint8_t first_index) {
    kFrameHeader.pack(std::span(tx_).first<protocol::kEthHeaderSize>());
    std::size_t off = protocol::kEthHeaderSize + protocol::kEcatHeaderSize;
    std::size_t total = off;
    for (const auto& d : dgs)
        total += protocol::kDatagramHeaderSize + d.data.size() + protocol::kWkcSize;
    if (total > protocol::kMaxEthFrame || dgs.size() > protocol::kMaxDatagramsPerFrame) return 0;
    for (std::size_t i = 0; i < dgs.size(); ++i) {
        auto& d = dgs[i];
        std::uint8_t* p = tx_.data() + off;
        const DatagramHeader h{d.cmd,     static_cast<std::uint8_t>(first_index + i),
                               d.address, static_cast<std::uint16_t>(d.data.size()),
                               false,     i + 1 < dgs.size(),
                               0};
        h.pack(std::span<std::uint8_t, DatagramHeader::kSize>(p, DatagramHeader::kSize));
        std::memcpy(p + protocol::kDatagramHeaderSize, d.data.data(), d.data.size());
        st_le16(p + protocol::kDatagramHeaderSize + d.data.size(), 0);
        off += protocol::kDatagramHeaderSize + d.data.size() + protocol::kWkcSize;
    }
    const std::size_t ecat_len = off - protocol::kEthHeaderSize - protocol::kEcatHeaderSize;
    protocol::EcatHeader{static_cast<std::uint16_t>(ecat_len)}.pack(
        std::span(tx_).subspan<protocol::kEthHeaderSize, protocol::kEcatHeaderSize>());
    return std::max(off, protocol::kMinEthFrame);
}

// A reply is the frame sent when it has as many datagrams, each with the index, command and length sent.
bool Master::take_reply(Bytes buf, const protocol::ParsedFrame& pf, std::span<DatagramRequest> dgs,
                        std::uint8_t first_index) {
    if (pf.count != dgs.size()) return false;
    for (std::size_t i = 0; i < dgs.size(); ++i) {
        auto d = pf.datagram(buf, i);
        if (d.index() != static_cast<std::uint8_t>(first_index + i) || d.command() != dgs[i].cmd ||
            d.length() != dgs[i].data.size())
            return false;
    }
    for (std::size_t i = 0; i < dgs.size(); ++i) {
        auto d = pf.datagram(buf, i);
        std::memcpy(dgs[i].data.data(), d.data(), dgs[i].data.size());
        dgs[i].wkc = d.wkc();
    }
    return true;
}

std::uint32_t Master::wait_replies(std::span<const std::span<DatagramRequest>> frames,
                                   const std::uint8_t* first, std::uint32_t pending) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::microseconds(opt_.reply_timeout_us);
    // Past the deadline the replies that are already there are still taken (a few, without waiting), as
    // SOEM's ecx_waitinframe looks once more before it gives up: a master thread that the scheduler kept
    // from running for longer than the timeout must not count replies that came in time as lost.
    std::size_t late_looks = 2 * kMaxFramesInFlight;
    while (pending != 0) {
        const auto left =
            std::chrono::duration_cast<std::chrono::microseconds>(deadline - std::chrono::steady_clock::now())
                .count();
        if (left <= 0 && late_looks-- == 0) break;
        const long n = link_.receive(Bytes(rx_.data(), rx_.size()), std::max<std::int64_t>(left, 0));
        if (n < 0) break;
        if (n == 0) {
            if (left <= 0) break;
            continue;
        }
        const Bytes reply(rx_.data(), static_cast<std::size_t>(n));
        const auto pf = protocol::parse_frame(reply);
        if (pf.error != protocol::FrameError::None) continue;
        // Any frame of the batch; none: a late reply to an earlier one.
        for (std::size_t k = 0; k < frames.size(); ++k)
            if (((pending >> k) & 1u) && take_reply(reply, pf, frames[k], first[k])) {
                pending &= ~(1u << k);
                break;
            }
    }
    return pending;
}

bool Master::transact_frames(std::span<const std::span<DatagramRequest>> frames) {
    for (std::size_t k = 0; k < frames.size(); k += kMaxFramesInFlight)
        if (!transact_batch(frames.subspan(k, std::min(kMaxFramesInFlight, frames.size() - k)))) return false;
    return true;
}

bool Master::transact_batch(std::span<const std::span<DatagramRequest>> frames) {
    // The datagrams of all frames take consecutive indexes, so that each reply names its frame.
    std::array<std::uint8_t, kMaxFramesInFlight> first{};
    std::array<std::size_t, kMaxFramesInFlight> length{};
    std::size_t datagrams = 0;
    bool fits = frames.size() <= kMaxFramesInFlight;
    for (std::size_t k = 0; fits && k < frames.size(); ++k) {
        first[k] = static_cast<std::uint8_t>(index_ + datagrams);
        datagrams += frames[k].size();
        length[k] = build_frame(frames[k], first[k]);  // (here only to check that it fits)
        fits = length[k] != 0;
    }
    if (!fits || datagrams > 0xFF) return false;
    // One bit per frame (a shift by 32 is undefined: all bits then).
    static_assert(kMaxFramesInFlight <= 32);
    std::uint32_t pending = frames.size() == 32 ? ~0u : (1u << frames.size()) - 1u;
    for (int attempt = 0; attempt <= opt_.retries && pending != 0; ++attempt) {
        std::uint32_t sent = 0;
        for (std::size_t k = 0; k < frames.size(); ++k)
            if ((pending >> k) & 1u) {
                build_frame(frames[k], first[k]);
                if (link_.send(ConstBytes(tx_.data(), length[k]))) sent |= 1u << k;
            }
        // (A frame the link refused is not waited for: the next attempt sends it again at once.)
        if (sent != 0) pending = wait_replies(frames, first.data(), pending & sent) | (pending & ~sent);
    }
    index_ = static_cast<std::uint8_t>(index_ + datagrams);
    return pending == 0;
}

bool Master::transact_frame(std::span<DatagramRequest> dgs) {
    const std::span<DatagramRequest> one[1] = {dgs};
    return transact_batch(one);
}

std::optional<std::uint16_t> Master::transact(Command cmd, std::uint16_t adp, std::uint16_t ado, Bytes data) {
    DatagramRequest r{cmd, protocol::datagram::address(adp, ado), data};
    if (!transact_frame(std::span<DatagramRequest>(&r, 1))) return std::nullopt;
    return r.wkc;
}

std::optional<std::uint16_t> Master::transact_logical(Command cmd, std::uint32_t laddr, Bytes data) {
    DatagramRequest r{cmd, laddr, data};
    if (!transact_frame(std::span<DatagramRequest>(&r, 1))) return std::nullopt;
    return r.wkc;
}

std::optional<std::uint16_t> Master::read16(std::uint16_t station, std::uint16_t ado) {
    std::uint8_t b[2] = {};
    auto w = fprd(station, ado, b);
    if (!w || *w != 1) return std::nullopt;
    return ld_le16(b);
}
std::optional<std::uint32_t> Master::read32(std::uint16_t station, std::uint16_t ado) {
    std::uint8_t b[4] = {};
    auto w = fprd(station, ado, b);
    if (!w || *w != 1) return std::nullopt;
    return ld_le32(b);
}
bool Master::write8(std::uint16_t station, std::uint16_t ado, std::uint8_t v) {
    auto w = fpwr(station, ado, Bytes(&v, 1));
    return w && *w == 1;
}
bool Master::write16(std::uint16_t station, std::uint16_t ado, std::uint16_t v) {
    std::uint8_t b[2];
    st_le16(b, v);
    auto w = fpwr(station, ado, b);
    return w && *w == 1;
}
bool Master::write32(std::uint16_t station, std::uint16_t ado, std::uint32_t v) {
    std::uint8_t b[4];
    st_le32(b, v);
    auto w = fpwr(station, ado, b);
    return w && *w == 1;
}

int Master::count_slaves() {
    std::uint8_t b[2] = {};
    auto w = brd(ra(Reg::Type), b);
    return w ? static_cast<int>(*w) : -1;
}

bool Master::reset_slaves() {
    auto bw = [&](std::uint16_t ado, std::size_t n, std::uint8_t v) {
        std::vector<std::uint8_t> b(n, v);
        return bwr(ado, b).has_value();
    };
    std::uint8_t init[2] = {
        static_cast<std::uint8_t>(static_cast<unsigned>(AlState::Init) | protocol::kAlErrorFlag), 0};
    return bw(ra(Reg::DlControl) + 3, 1, 0) &&                            // no alias addressing
           bwr(ra(Reg::AlControl), init).has_value() &&                   // INIT with acknowledge
           bw(ra(Reg::DlControl), 1, 0) &&                                // forwarding rule
           bw(ra(Reg::RxErrorCounter), 8, 0) &&                           // clear error counters
           bw(ra(Reg::Fmmu0), 16 * 3, 0) &&                               // FMMUs off
           bw(ra(Reg::Sm0), 8 * 4, 0) &&                                  // SyncManagers off
           bw(ra(Reg::DcActivation), 1, 0) &&                             // SYNC off
           bw(ra(Reg::SiiConfig), 1, 2) && bw(ra(Reg::SiiConfig), 1, 0);  // EEPROM to the master
}

bool Master::assign_station_addresses(std::uint16_t first) {
    const int n = count_slaves();
    if (n < 0) return false;
    slaves_.clear();
    for (int i = 0; i < n; ++i) {
        SlaveInfo s;
        s.position = static_cast<std::uint16_t>(i);
        s.station = static_cast<std::uint16_t>(first + i);
        std::uint8_t b[2];
        st_le16(b, s.station);
        auto w = apwr(s.position, ra(Reg::StationAddress), b);
        if (!w || *w != 1) return false;
        slaves_.push_back(std::move(s));
    }
    return true;
}

std::optional<Master::SiiBlock> Master::read_sii_block(std::uint16_t station, std::uint32_t word) {
    namespace ctl = protocol::sii_ctrl;
    // Control/status, address and data in one read: registers 0x0502-0x050F of the ESC datasheet.
    const std::uint16_t first = ra(Reg::SiiControl);
    const std::size_t at_address = ra(Reg::SiiAddress) - first, at_data = ra(Reg::SiiData) - first;
    std::array<std::uint8_t, 14> regs{};
    // The status once the interface is idle (a busy one is polled every 50 us); nullopt: no answer, or busy
    // for 5 ms.
    const auto idle_status = [&]() -> std::optional<std::uint16_t> {
        for (int i = 0; i < 100; ++i) {
            const auto w = fprd(station, first, regs);
            if (!w || *w != 1) return std::nullopt;
            const std::uint16_t st = ld_le16(regs.data());
            if (!(st & (ctl::Busy | ctl::CmdMask))) return st;
            std::this_thread::sleep_for(std::chrono::microseconds(50));
        }
        return std::nullopt;
    };
    for (int attempt = 0; attempt < 3; ++attempt) {
        if (attempt > 0) {
            // The command before was refused or not taken: wait until the interface is idle, clear its error
            // bits, then command again.
            const auto st = idle_status();
            if (!st) return std::nullopt;
            if (*st & (ctl::ErrorAck | ctl::ErrorWriteEnable)) write16(station, first, 0);
        }
        // The command at once (a new command clears the error bits of the one before), then its result: one
        // frame each while the ESC is quick.
        std::uint8_t cmd[6];
        st_le16(cmd, ctl::CmdRead);
        st_le32(cmd + 2, word);
        const auto w = fpwr(station, first, cmd);
        if (!w || *w != 1) return std::nullopt;
        const auto st = idle_status();
        if (!st) return std::nullopt;
        if (*st & ctl::ErrorAck) continue;  // NACK: again
        // An interface busy with something else when the command came did not take it: its address tells.
        if (ld_le32(regs.data() + at_address) != word) continue;
        SiiBlock b;
        b.size = (*st & ctl::Read8Bytes) ? 8 : 4;
        std::copy_n(regs.begin() + static_cast<std::ptrdiff_t>(at_data), b.size, b.bytes.begin());
        return b;
    }
    return std::nullopt;
}

std::optional<std::uint32_t> Master::read_sii_dword(std::uint16_t station, std::uint32_t word) {
    const auto b = read_sii_block(station, word);
    if (!b) return std::nullopt;
    return ld_le32(b->bytes.data());
}

std::optional<std::vector<std::uint8_t>> Master::read_sii_image(std::uint16_t station) {
    std::vector<std::uint8_t> img;
    // The image in double words; an ESC that reads 8 bytes a command gives two of them (the category
    // header and the first double word of its data, or two of the data).
    SiiBlock last;
    std::uint32_t last_word = 0;
    auto read_words = [&](std::uint32_t word, std::size_t nwords) -> bool {
        for (std::size_t k = 0; k < nwords; k += 2) {
            const auto w = static_cast<std::uint32_t>(word + k);
            if (!(last.size != 0 && w >= last_word && 2 * (w - last_word) + 4 <= last.size)) {
                const auto b = read_sii_block(station, w);
                if (!b) return false;
                last = *b;
                last_word = w;
            }
            const std::size_t pos = 2 * static_cast<std::size_t>(w);
            if (img.size() < pos + 4) img.resize(pos + 4, 0xFF);
            std::copy_n(last.bytes.begin() + 2 * (w - last_word), 4,
                        img.begin() + static_cast<std::ptrdiff_t>(pos));
        }
        return true;
    };
    if (!read_words(0, protocol::sii::FirstCategory)) return std::nullopt;
    std::uint32_t word = protocol::sii::FirstCategory;
    for (int guard = 0; guard < 256; ++guard) {
        if (!read_words(word, 2)) return std::nullopt;
        const std::uint16_t type = ld_le16(img.data() + 2 * word);
        if (type == protocol::sii::kEndMarker) break;
        const std::uint16_t len = ld_le16(img.data() + 2 * word + 2);
        if (word + 2 + len > 0x8000) return std::nullopt;
        if (len && !read_words(word + 2, len)) return std::nullopt;
        word += 2u + len;
    }
    img.resize(std::min<std::size_t>(img.size(), 2 * word + 2));
    return img;
}

bool Master::read_slave_information() {
    for (auto& s : slaves_) {
        std::uint8_t info[10] = {};
        auto w = fprd(s.station, ra(Reg::Type), info);
        if (!w || *w != 1) return false;
        s.esc_type = info[0];
        s.fmmu_count = info[4];
        s.sm_count = info[5];
        s.features = ld_le16(info + 8);
        auto dl = read16(s.station, ra(Reg::DlStatus));
        if (!dl) return false;
        s.dl_status = *dl;
        s.open_ports = protocol::open_ports(s.dl_status);
        // The outcome of reset_slaves()' INIT request (SOEM's ecx_config_init reads it per slave too): a
        // master learns a state request's result from the AL status before it requests the next state.
        if (!read_al_status(s.station).ok) return false;
        auto img = read_sii_image(s.station);
        if (!img) return false;
        s.sii_image = *img;
        s.sii = protocol::parse_sii(s.sii_image);
        // Process data: the PDOs of the SII assigned to the output / input SyncManagers.
        // Each SyncManager's area starts on a byte; the areas follow each other in SyncManager order.
        std::uint32_t out_bits = 0, in_bits = 0;
        s.out_entries.clear();
        s.in_entries.clear();
        s.pd_sms.clear();
        for (std::size_t i = 0; i < s.sii.sync_managers.size(); ++i) {
            const auto& sm = s.sii.sync_managers[i];
            const bool outputs = sm.type == protocol::sii::SmTypeOutputs;
            if (!outputs && sm.type != protocol::sii::SmTypeInputs) continue;
            auto& bits = outputs ? out_bits : in_bits;
            const std::uint32_t first = bits;
            for (const auto& p : outputs ? s.sii.rx_pdos : s.sii.tx_pdos)
                if (p.sm == i)
                    for (const auto& e : p.entries) {
                        (outputs ? s.out_entries : s.in_entries)
                            .push_back(MappedEntry{e.index, e.subindex, e.bit_length, bits});
                        bits += e.bit_length;
                    }
            bits = (bits + 7) / 8 * 8;
            s.pd_sms.push_back(
                {static_cast<std::uint8_t>(i), outputs, static_cast<std::uint16_t>((bits - first) / 8)});
        }
        s.out_bytes = out_bits / 8;
        s.in_bytes = in_bits / 8;
    }
    compute_topology();
    return true;
}

void Master::compute_topology() {
    std::vector<std::uint8_t> open;
    for (const auto& s : slaves_)
        open.push_back(s.open_ports);
    const auto up = protocol::topology_from_open_ports(open);
    for (std::size_t i = 0; i < slaves_.size(); ++i) {
        slaves_[i].parent = up[i].parent;
        slaves_[i].parent_port = up[i].port;
    }
}

bool Master::configure_mailboxes() {
    for (auto& s : slaves_) {
        if (!s.sii.std_rx_mbx_size) continue;
        for (std::size_t i = 0; i < s.sii.sync_managers.size() && i < 2; ++i) {
            const auto& sm = s.sii.sync_managers[i];
            std::uint8_t b[SmConfig::kSize];
            SmConfig::master(sm.start, sm.length, sm.control).pack(b);
            auto w = fpwr(s.station, protocol::sm_addr(static_cast<unsigned>(i)), b);
            if (!w || *w != 1) return false;
        }
    }
    return true;
}

bool Master::read_pdo_sizes_coe(SlaveInfo& s) {
    // Like SOEM's ecx_readPDOmap: 0x1C00 gives each SM's type, 0x1C1n the PDOs, 0x16xx/0x1Axx the entries.
    CoeClient c(*this, s.station);
    auto u = [&](std::uint16_t idx, std::uint8_t sub) -> std::optional<std::uint32_t> {
        auto r = c.upload(idx, sub);
        if (!r.ok() || r.data.empty()) return std::nullopt;
        std::uint32_t v = 0;
        for (std::size_t i = 0; i < r.data.size() && i < 4; ++i)
            v |= static_cast<std::uint32_t>(r.data[i]) << (8 * i);
        return v;
    };
    auto nsm = u(0x1C00, 0);
    if (!nsm || *nsm <= 2) return false;
    std::uint32_t out_bits = 0, in_bits = 0;
    std::vector<MappedEntry> out_entries, in_entries;
    std::vector<SlaveInfo::ProcessDataSm> sms;
    for (std::uint32_t sm = 2; sm < *nsm; ++sm) {
        auto type = u(0x1C00, static_cast<std::uint8_t>(sm + 1));
        if (!type || (*type != 3 && *type != 4)) continue;
        const std::uint32_t first = *type == 3 ? out_bits : in_bits;
        const auto assign = static_cast<std::uint16_t>(0x1C10 + sm);
        auto npdo = u(assign, 0);
        if (!npdo) return false;
        for (std::uint32_t i = 1; i <= *npdo; ++i) {
            auto pdo = u(assign, static_cast<std::uint8_t>(i));
            if (!pdo) return false;
            auto nent = u(static_cast<std::uint16_t>(*pdo), 0);
            if (!nent) return false;
            for (std::uint32_t k = 1; k <= *nent; ++k) {
                auto m = u(static_cast<std::uint16_t>(*pdo), static_cast<std::uint8_t>(k));
                if (!m) return false;
                const bool outputs = *type == 3;
                auto& bits = outputs ? out_bits : in_bits;
                // The mapping entry (ETG.1000.6 5.6.7.4.7): index << 16 | subindex << 8 | length in bits.
                (outputs ? out_entries : in_entries)
                    .push_back(MappedEntry{static_cast<std::uint16_t>(*m >> 16),
                                           static_cast<std::uint8_t>(*m >> 8),
                                           static_cast<std::uint8_t>(*m & 0xFF), bits});
                bits += *m & 0xFF;
            }
        }
        auto& bits = *type == 3 ? out_bits : in_bits;
        bits = (bits + 7) / 8 * 8;  // the next SyncManager's area starts on a byte
        sms.push_back(
            {static_cast<std::uint8_t>(sm), *type == 3, static_cast<std::uint16_t>((bits - first) / 8)});
    }
    s.out_bytes = out_bits / 8;
    s.in_bytes = in_bits / 8;
    s.out_entries = std::move(out_entries);
    s.in_entries = std::move(in_entries);
    s.pd_sms = std::move(sms);
    return true;
}

const MappedEntry* find_entry(const std::vector<MappedEntry>& entries, std::uint16_t index,
                              std::uint8_t subindex) {
    for (const auto& e : entries)
        if (e.index == index && e.subindex == subindex) return &e;
    return nullptr;
}

bool Master::read_pdo_sizes_soe(SlaveInfo& s) {
    // Like SOEM's ecx_readIDNmap: for each drive number 0-7, S-0-0024 lists the IDNs of its MDT, S-0-0016
    // those of its AT; the attribute of each gives its length; the control and status word (16 bits each)
    // are not listed. A drive that answers with an error (0x800A: no such drive) adds nothing; the blocks
    // of the drives follow one another in the SyncManagers.
    SoeClient c(*this, s.station);
    auto bytes_of = [&](std::uint8_t drive, protocol::Idn list, unsigned& bytes) {
        const auto r = c.read(drive, protocol::soe_element::Value, list);
        if (!r.ok() || r.data.size() < protocol::kSoeListHeaderSize) return false;
        const std::size_t current = ld_le16(r.data.data());
        bytes += 2;
        for (std::size_t i = 0; i + 1 < current && protocol::kSoeListHeaderSize + i + 1 < r.data.size();
             i += 2) {
            const protocol::Idn idn{ld_le16(r.data.data() + protocol::kSoeListHeaderSize + i)};
            const auto a = c.read(drive, protocol::soe_element::Attribute, idn);
            if (!a.ok() || a.data.size() < 4) return false;
            const auto attr = protocol::SoeAttribute::unpack(ld_le32(a.data.data()));
            if (!attr.list) bytes += static_cast<unsigned>(attr.element_size());
        }
        return true;
    };
    constexpr std::uint8_t kDrives = 8;  // the 3-bit drive number of the SoE header
    s.out_bytes = 0;
    s.in_bytes = 0;
    bool any = false;
    for (std::uint8_t d = 0; d < kDrives; ++d) {
        unsigned out = 0, in = 0;
        if (!bytes_of(d, protocol::s_idn(24), out) || !bytes_of(d, protocol::s_idn(16), in)) continue;
        s.out_bytes += out;
        s.in_bytes += in;
        any = true;
    }
    if (!any) return false;
    // The MDT goes through the SII's output SyncManager, the AT through its input one.
    s.out_entries.clear();
    s.in_entries.clear();
    s.pd_sms.clear();
    bool out_done = false, in_done = false;
    for (std::size_t i = 0; i < s.sii.sync_managers.size(); ++i) {
        const auto type = s.sii.sync_managers[i].type;
        if (type == protocol::sii::SmTypeOutputs && !out_done) {
            s.pd_sms.push_back({static_cast<std::uint8_t>(i), true, static_cast<std::uint16_t>(s.out_bytes)});
            out_done = true;
        } else if (type == protocol::sii::SmTypeInputs && !in_done) {
            s.pd_sms.push_back({static_cast<std::uint8_t>(i), false, static_cast<std::uint16_t>(s.in_bytes)});
            in_done = true;
        }
    }
    return true;
}

bool Master::configure_process_data() {
    for (auto& s : slaves_) {
        if (!s.sii.std_rx_mbx_size) continue;
        if (s.sii.mailbox_protocols & protocol::sii::MailboxCoE) {
            if (!read_pdo_sizes_coe(s)) return false;
        } else if (s.sii.mailbox_protocols & protocol::sii::MailboxSoE) {
            if (!read_pdo_sizes_soe(s)) return false;
        }
    }
    std::uint32_t laddr = opt_.logical_base;
    std::size_t off = 0;
    unsigned n_out = 0, n_in = 0;
    for (auto& s : slaves_) {
        s.out_logical = laddr;
        s.out_offset = off;
        laddr += s.out_bytes;
        off += s.out_bytes;
    }
    out_total_ = off;
    for (auto& s : slaves_) {
        s.in_logical = laddr;
        s.in_offset = off;
        laddr += s.in_bytes;
        off += s.in_bytes;
    }
    image_.assign(off, 0);
    // Frames of at most kMaxLrwBytes, cut only between two slaves' areas: every FMMU lies in one frame.
    chunks_.clear();
    cyclic_frames_.clear();
    auto add_area = [&](std::size_t o, std::size_t n) {
        if (n == 0) return;
        if (chunks_.empty() || chunks_.back().size + n > kMaxLrwBytes)
            chunks_.push_back({o, n});
        else
            chunks_.back().size += n;
    };
    for (const auto& s : slaves_)
        add_area(s.out_offset, s.out_bytes);
    for (const auto& s : slaves_)
        add_area(s.in_offset, s.in_bytes);
    for (auto& s : slaves_) {
        unsigned fmmu = 0;
        std::uint32_t out_at = 0, in_at = 0;  // where the next SyncManager's area starts in the slave's
        for (const auto& pd : s.pd_sms) {
            // A SyncManager of 0x1C00 that the SII does not describe has no start address to configure: left
            // alone, as the SII's own list was walked before.
            if (pd.sm >= s.sii.sync_managers.size()) continue;
            const auto& sm = s.sii.sync_managers[pd.sm];
            std::uint8_t b[SmConfig::kSize];
            auto c = SmConfig::master(sm.start, pd.bytes, sm.control);
            // Activated as the SII's enable byte says (as SOEM does): a SyncManager declared not enabled or
            // virtual stays off, and the FMMU reads or writes the memory (ETG.2010 SyncM). One without
            // process data stays off too.
            if (!(sm.enable & protocol::sii::sm_enable::Enable) || pd.bytes == 0) c.activate = 0;
            c.pack(b);
            auto w = fpwr(s.station, protocol::sm_addr(pd.sm), b);
            if (!w || *w != 1) return false;
            if (!pd.bytes) continue;
            // Outputs: the master writes the logical range (the FMMU writes into the ESC); inputs: it reads.
            auto& at = pd.outputs ? out_at : in_at;
            std::uint8_t f[FmmuConfig::kSize];
            FmmuConfig::bytes((pd.outputs ? s.out_logical : s.in_logical) + at, pd.bytes, sm.start,
                              !pd.outputs, pd.outputs)
                .pack(f);
            at += pd.bytes;
            w = fpwr(s.station, protocol::fmmu_addr(fmmu++), f);
            if (!w || *w != 1) return false;
        }
        // A slave counts once per datagram in which it reads and twice in which it writes, however many
        // FMMUs take part (ESC datasheet section I, 3.3: working counter).
        n_out += out_at > 0;
        n_in += in_at > 0;
    }
    expected_wkc_ = static_cast<std::uint16_t>(2 * n_out + n_in);
    return true;
}

AlStatusReading Master::read_al_status(std::uint16_t station) {
    std::uint8_t b[6] = {};
    AlStatusReading r;
    auto w = fprd(station, ra(Reg::AlStatus), b);
    if (!w || *w != 1) return r;
    r.status = b[0];
    r.code = ld_le16(b + 4);
    r.ok = true;
    return r;
}

bool Master::acknowledge_error(std::uint16_t station, AlState s) {
    return write16(station, ra(Reg::AlControl),
                   static_cast<std::uint16_t>(static_cast<unsigned>(s) | protocol::kAlErrorFlag));
}

bool Master::request_state(AlState s, std::chrono::milliseconds timeout) {
    std::uint8_t b[2];
    st_le16(b, static_cast<std::uint16_t>(s));
    if (!bwr(ra(Reg::AlControl), b)) return false;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    last_states_.assign(slaves_.size(), {});
    while (true) {
        if (s == AlState::Op || s == AlState::SafeOp) exchange_process_data();
        // One broadcast read first (as SOEM does): the slaves OR their AL status into it, so every slave
        // answering with the requested state and no error flag means all are there. Only an error flag or the
        // deadline asks each slave, so that the process data above keep flowing on a large network.
        std::uint8_t all_status[2] = {0, 0};
        const auto answered = brd(ra(Reg::AlStatus), all_status);
        const bool error_seen = answered && (all_status[0] & protocol::kAlErrorFlag);
        if (answered == slaves_.size() && !error_seen && all_status[0] == static_cast<std::uint8_t>(s)) {
            for (auto& r : last_states_)
                r = AlStatusReading{all_status[0], 0, true};
            return true;
        }
        const bool late = std::chrono::steady_clock::now() > deadline;
        if (error_seen || late || !answered) {
            bool all = true, failed = false;
            for (std::size_t i = 0; i < slaves_.size(); ++i) {
                last_states_[i] = read_al_status(slaves_[i].station);
                const auto& r = last_states_[i];
                if (!r.ok || r.error()) failed |= r.ok && r.error();
                if (!r.ok || r.state() != s || r.error()) all = false;
            }
            if (all) return true;
            if (failed || late) return false;
        }
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
}

bool Master::request_state(std::uint16_t station, AlState s, std::chrono::milliseconds timeout) {
    if (!write16(station, ra(Reg::AlControl), static_cast<std::uint16_t>(s))) return false;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
        if (s == AlState::Op || s == AlState::SafeOp) exchange_process_data();
        const auto r = read_al_status(station);
        if (r.ok && r.error()) return false;
        if (r.ok && r.state() == s) return true;
        if (std::chrono::steady_clock::now() > deadline) return false;
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
}

std::optional<std::uint16_t> Master::exchange_process_data() {
    if (image_.empty()) return std::nullopt;
    // All frames of the cycle go out back to back before the first reply is awaited, as SOEM
    // (ecx_send_processdata) and IgH (ecrt_master_send) put a cycle's frames on the wire. The requests are
    // laid out at the first exchange after the image or the reference clock changed (no allocation after it).
    const bool dc = dc_ref_ != 0;
    if (cyclic_frames_.empty() || cyclic_image_ != image_.data() || cyclic_dc_ref_ != dc_ref_) {
        cyclic_image_ = image_.data();
        cyclic_dc_ref_ = dc_ref_;
        cyclic_dgs_.resize(chunks_.size() + (dc ? 1 : 0));
        cyclic_frames_.clear();
        std::size_t at = 0;
        for (std::size_t c = 0; c < chunks_.size(); ++c) {
            const Bytes part(image_.data() + chunks_[c].offset, chunks_[c].size);
            const std::uint32_t laddr = opt_.logical_base + static_cast<std::uint32_t>(chunks_[c].offset);
            const std::size_t first = at;
            cyclic_dgs_[at++] = {Command::LRW, laddr, part};
            // Reference clock distribution in the cyclic frame, after the LRW (as SOEM does).
            if (c == 0 && dc)
                cyclic_dgs_[at++] = {Command::FRMW,
                                     static_cast<std::uint32_t>(dc_ref_) |
                                         (static_cast<std::uint32_t>(ra(Reg::DcSystemTime)) << 16),
                                     Bytes(dc_buf_.data(), dc_buf_.size())};
            cyclic_frames_.emplace_back(cyclic_dgs_.data() + first, at - first);
        }
    }
    dc_buf_.fill(0);
    std::uint16_t wkc = 0;
    if (!transact_frames(cyclic_frames_)) return std::nullopt;
    for (const auto& f : cyclic_frames_)
        wkc = static_cast<std::uint16_t>(wkc + f[0].wkc);
    if (dc && cyclic_frames_[0].size() > 1 && cyclic_frames_[0][1].wkc) dc_time_ = ld_le64(dc_buf_.data());
    return wkc;
}

// ---------------------------------------------------------------------------------------------
// Distributed clocks

bool Master::configure_dc() {
    // EtherCAT system time counts from 2000-01-01 00:00 UTC.
    constexpr std::uint64_t kEpoch2000 = 946'684'800ull * 1'000'000'000ull;
    const auto now = std::chrono::system_clock::now().time_since_epoch();
    const auto ns =
        static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(now).count());
    return configure_dc(ns > kEpoch2000 ? ns - kEpoch2000 : ns);
}

namespace {

// A slave's round trip: from its arrival at port 0 to the return through its last open port (0 for a slave
// whose other ports are closed), from its latched receive times.
std::int64_t round_trip(const SlaveInfo& x) {
    std::int64_t last = 0;
    for (unsigned p : protocol::kPortsAfterPort0)
        if ((x.open_ports >> p) & 1u) last = static_cast<std::int32_t>(x.dc_port_time[p] - x.dc_port_time[0]);
    return last;
}

}  // namespace

// The time from the parent's arrival at port 0 until the frame leaves it through port `port`: the return
// time of the open port before it in the order 3, 1, 2 (0 when it is the first).
std::int64_t Master::departure(const SlaveInfo& up, unsigned port) {
    std::int64_t t = 0;
    for (unsigned p : protocol::kPortsAfterPort0) {
        if (p == port) break;
        if ((up.open_ports >> p) & 1u) t = static_cast<std::int32_t>(up.dc_port_time[p] - up.dc_port_time[0]);
    }
    return t;
}

// The cable between a slave and its parent: half of what the frame's way out and back through the parent's
// port takes beyond the slave's own round trip.
std::int64_t Master::cable_delay(const SlaveInfo& up, const SlaveInfo& s) {
    const std::int64_t back = static_cast<std::int32_t>(up.dc_port_time[s.parent_port] - up.dc_port_time[0]);
    return (back - departure(up, s.parent_port) - round_trip(s)) / 2;
}

bool Master::configure_dc(std::uint64_t master_time_ns) {
    dc_ref_ = 0;
    std::uint8_t zero[4] = {};
    if (!bwr(ra(Reg::DcRecvTimePort0), zero)) return false;  // every slave latches its receive times
    SlaveInfo* parent = nullptr;
    for (auto& s : slaves_) {
        s.has_dc = (s.features & protocol::feature::DcAvailable) != 0;
        if (!s.has_dc) continue;
        std::uint8_t times[16] = {};
        std::uint8_t pu[8] = {};
        auto w1 = fprd(s.station, ra(Reg::DcRecvTimePort0), times);
        auto w2 = fprd(s.station, ra(Reg::DcRecvTimeEcatPu), pu);
        if (!w1 || *w1 != 1 || !w2 || *w2 != 1) return false;
        for (unsigned p = 0; p < 4; ++p)
            s.dc_port_time[p] = ld_le32(times + 4 * p);
        s.dc_recv_time = ld_le64(pu);
        // Propagation delay (ETG.1000.4, DC): the frame leaves the parent towards this slave when it comes
        // back through the parent's open port before this one (or at its arrival at port 0), and it is back
        // at the parent's port after twice the cable and this slave's own round trip through its ports.
        if (s.parent < 0 || !parent) {
            s.dc_delay_ns = 0;
            dc_ref_ = s.station;
        } else {
            const SlaveInfo& up = slaves_[static_cast<std::size_t>(s.parent)];
            const std::int64_t d = up.has_dc ? cable_delay(up, s) : 0;
            s.dc_delay_ns =
                static_cast<std::uint32_t>((up.has_dc ? up.dc_delay_ns : parent->dc_delay_ns) +
                                           (d > 0 ? d : 0) + (up.has_dc ? departure(up, s.parent_port) : 0));
            if (!write32(s.station, ra(Reg::DcSystemTimeDelay), s.dc_delay_ns)) return false;
        }
        // Offset: the system time of every slave reads the master's time at the moment the latching frame
        // left the reference clock (this slave latched dc_delay_ns later), so all agree at once.
        s.dc_offset = master_time_ns + s.dc_delay_ns - s.dc_recv_time;
        std::uint8_t off[8];
        st_le64(off, s.dc_offset);
        auto w3 = fpwr(s.station, ra(Reg::DcSystemTimeOffset), off);
        if (!w3 || *w3 != 1) return false;
        parent = &s;
    }
    return true;
}

std::optional<std::uint64_t> Master::distribute_reference_clock() {
    if (dc_ref_ == 0) return std::nullopt;
    dc_buf_.fill(0);
    auto w = transact(Command::FRMW, dc_ref_, ra(Reg::DcSystemTime), Bytes(dc_buf_.data(), dc_buf_.size()));
    if (!w || *w == 0) return std::nullopt;
    dc_time_ = ld_le64(dc_buf_.data());
    return dc_time_;
}

bool Master::compensate_static_drift(unsigned frames) {
    for (unsigned i = 0; i < frames; ++i)
        if (!distribute_reference_clock()) return false;
    return true;
}

std::optional<std::uint32_t> Master::max_system_time_difference() {
    std::uint32_t worst = 0;
    for (const auto& s : slaves_) {
        if (!s.has_dc || s.station == dc_ref_) continue;
        auto v = read32(s.station, ra(Reg::DcSystemTimeDifference));
        if (!v) return std::nullopt;
        worst = std::max(worst, *v & 0x7FFFFFFFu);  // bit 31 is the sign
    }
    return worst;
}

bool Master::stop_sync(std::uint16_t station) {
    return write8(station, ra(Reg::DcActivation), 0);
}

bool Master::start_sync(std::uint16_t station, std::uint32_t cycle0_ns, std::int32_t shift_ns,
                        std::uint64_t start_delay_ns, std::optional<std::uint32_t> cycle1_ns) {
    if (!stop_sync(station) || !write8(station, ra(Reg::DcCyclicUnitControl), 0)) return false;
    std::uint8_t b[8] = {};
    auto w = fprd(station, ra(Reg::DcSystemTime), b);
    if (!w || *w != 1) return false;
    const std::uint64_t now = ld_le64(b);
    // The true cycle with SYNC1: SYNC1 follows every (cycle1 / cycle0 + 1)-th SYNC0.
    const std::uint64_t period = cycle1_ns && cycle0_ns
                                     ? (static_cast<std::uint64_t>(*cycle1_ns / cycle0_ns) + 1) * cycle0_ns
                                     : cycle0_ns;
    std::uint64_t start = now + start_delay_ns;
    if (period) start = (start / period) * period + period;
    start += static_cast<std::uint64_t>(static_cast<std::int64_t>(shift_ns));
    st_le64(b, start);
    auto w2 = fpwr(station, ra(Reg::DcStartTimeCyclic), b);
    if (!w2 || *w2 != 1) return false;
    if (!write32(station, ra(Reg::DcSync0CycleTime), cycle0_ns)) return false;
    if (cycle1_ns && !write32(station, ra(Reg::DcSync1CycleTime), *cycle1_ns)) return false;
    const std::uint8_t act = cycle1_ns ? 0x07 : 0x03;  // cyclic operation + SYNC0 (+ SYNC1)
    return write8(station, ra(Reg::DcActivation), act);
}

Bytes Master::outputs(std::size_t i) {
    const auto& s = slaves_.at(i);
    return Bytes(image_.data() + s.out_offset, s.out_bytes);
}

ConstBytes Master::inputs(std::size_t i) const {
    const auto& s = slaves_.at(i);
    return ConstBytes(image_.data() + s.in_offset, s.in_bytes);
}

bool Master::startup(AlState target, std::string* why) {
    auto fail = [&](const std::string& m) {
        if (why) *why = m;
        return false;
    };
    // A state the slaves did not all reach: the first that did not, and why (request_state's readings).
    const auto refused = [&](AlState s) {
        std::string m = std::string(protocol::to_string(s)) + " refused";
        std::size_t others = 0;
        std::string first;
        for (std::size_t i = 0; i < last_states_.size() && i < slaves_.size(); ++i) {
            const AlStatusReading& r = last_states_[i];
            if (r.ok && r.state() == s && !r.error()) continue;
            if (!first.empty()) {
                ++others;
                continue;
            }
            char b[200];
            if (!r.ok)
                std::snprintf(b, sizeof b, ": slave %zu (station 0x%04X) does not answer", i,
                              slaves_[i].station);
            else
                std::snprintf(
                    b, sizeof b, ": slave %zu (station 0x%04X) is in %s%s, AL status code 0x%04X (%s)", i,
                    slaves_[i].station, std::string(protocol::to_string(r.state())).c_str(),
                    r.error() ? " with the error flag" : "", r.code,
                    std::string(protocol::describe(static_cast<protocol::AlStatusCode>(r.code))).c_str());
            first = b;
        }
        if (others) first += " (and " + std::to_string(others) + " more)";
        return fail(m + first);
    };
    const int n = count_slaves();
    if (n <= 0) return fail("no slaves found");
    if (!reset_slaves()) return fail("bus reset failed");
    if (!assign_station_addresses()) return fail("station address assignment failed");
    if (!read_slave_information()) return fail("reading ESC information / SII failed");
    if (target == AlState::Init) return true;
    if (!configure_mailboxes()) return fail("mailbox SyncManager configuration failed");
    if (!request_state(AlState::PreOp)) return refused(AlState::PreOp);
    if (target == AlState::PreOp) return true;
    if (!configure_process_data()) return fail("process data configuration failed");
    if (opt_.dc.enable) {
        // IgH/TwinCAT order: delays and offsets, static drift compensation, wait for the system time
        // difference to be small, then SYNC0 on every DC slave before SAFEOP.
        if (!configure_dc()) return fail("DC configuration failed");
        if (dc_ref_ != 0) {
            if (!compensate_static_drift(opt_.dc.static_drift_frames))
                return fail("DC drift compensation failed");
            const auto deadline = std::chrono::steady_clock::now() + opt_.dc.sync_wait;
            while (true) {
                distribute_reference_clock();
                auto d = max_system_time_difference();
                if (d && *d <= opt_.dc.max_sync_diff_ns) break;
                if (std::chrono::steady_clock::now() > deadline)
                    return fail("DC system time difference stays large");
            }
            if (opt_.dc.sync0_cycle_ns)
                for (const auto& s : slaves_)
                    if (s.has_dc && !start_sync(s.station, opt_.dc.sync0_cycle_ns, opt_.dc.shift_ns,
                                                opt_.dc.start_delay_ns))
                        return fail("SYNC0 activation failed");
        }
    }
    if (!request_state(AlState::SafeOp)) return refused(AlState::SafeOp);
    if (target == AlState::SafeOp) return true;
    exchange_process_data();
    if (!request_state(AlState::Op)) return refused(AlState::Op);
    return true;
}

}  // namespace vecat::master
