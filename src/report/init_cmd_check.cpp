#include "report/init_cmd_check.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>

#include "protocol/al_status.hpp"
#include "protocol/frame.hpp"
#include "protocol/registers.hpp"

namespace vecat::report {

using protocol::addr;
using protocol::Command;
using protocol::Reg;

namespace {

// The register space (ESC datasheet section II: 0x0000-0x0FFF); above it the process RAM, where the
// mailbox and process data go.
constexpr std::uint32_t kRegisterSpaceEnd = 0x1000;
// Writes kept per slave between two state requests (a master polling in a loop must not grow them).
constexpr std::size_t kMaxPending = 512;

// AL state of a transition letter (ETG.2100 InitCmd/Transition: I, P, B, S, O).
std::uint8_t state_of(char c) {
    switch (c) {
        case 'I':
            return static_cast<std::uint8_t>(protocol::AlState::Init);
        case 'P':
            return static_cast<std::uint8_t>(protocol::AlState::PreOp);
        case 'B':
            return static_cast<std::uint8_t>(protocol::AlState::Boot);
        case 'S':
            return static_cast<std::uint8_t>(protocol::AlState::SafeOp);
        default:
            return static_cast<std::uint8_t>(protocol::AlState::Op);
    }
}
char letter_of(std::uint8_t s) {
    switch (s) {
        case 1:
            return 'I';
        case 2:
            return 'P';
        case 3:
            return 'B';
        case 4:
            return 'S';
        case 8:
            return 'O';
        default:
            return '?';
    }
}

bool is_physical_write(std::uint8_t cmd) {
    return protocol::physical_write(static_cast<Command>(cmd));
}

// The SII EEPROM interface (0x0500-0x050F, ESC datasheet section II): the master reading the SII, no
// configuration.
constexpr std::uint32_t kSiiInterfaceSize = 16;

bool overlaps(std::uint32_t a, std::uint32_t a_end, std::uint32_t b, std::uint32_t b_end) {
    return a < b_end && b < a_end;
}

// A write the check compares: in the register space, not touching AL control or the SII interface.
bool compared(std::uint16_t ado, std::size_t len) {
    if (len == 0 || len > kRegisterSpaceEnd) return false;
    const auto end = static_cast<std::uint32_t>(ado + len);
    const std::uint32_t al = addr(Reg::AlControl);
    const std::uint32_t sii = addr(Reg::SiiConfig);
    return len > 0 && end <= kRegisterSpaceEnd && !overlaps(ado, end, al, al + 2) &&
           !overlaps(ado, end, sii, sii + kSiiInterfaceSize);
}

std::string bytes(const std::vector<std::uint8_t>& d) {
    std::string s;
    for (std::size_t i = 0; i < d.size() && i < 16; ++i)
        s += fmt::format("{:02x}", d[i]);
    if (d.size() > 16) s += fmt::format("... ({} bytes)", d.size());
    return s;
}

}  // namespace

std::string to_string(Transition t) {
    return {letter_of(t.from), letter_of(t.to)};
}

std::vector<ExpectedWrite> expected_writes(const network::Eni& eni, const network::EniNetwork& n) {
    std::vector<ExpectedWrite> out;
    const auto add = [&](std::size_t position, const network::EniInitCmd& c) {
        if (!is_physical_write(c.cmd) || c.addr || !compared(c.ado, c.data.size())) return;
        ExpectedWrite w;
        w.slave = position;
        for (unsigned t = 0; t < network::kEniTransitionNames.size(); ++t)
            if (c.transitions & (1u << t)) {
                const auto name = network::kEniTransitionNames[t];
                w.transitions.push_back({state_of(name[0]), state_of(name[1])});
            }
        w.ado = c.ado;
        w.data = c.data;
        w.label = network::eni_message(eni, c.where, c.comment.empty() ? "" : "\"" + c.comment + "\"");
        out.push_back(std::move(w));
    };
    for (std::size_t k = 0; k < n.file.devices.size(); ++k)
        for (const auto& c : eni.slaves[n.slave[k]].init_cmds)
            add(k, c);
    // The master's own broadcast writes apply to every slave.
    for (const auto& c : eni.master_init_cmds)
        if (static_cast<Command>(c.cmd) == Command::BWR || static_cast<Command>(c.cmd) == Command::BRW)
            for (std::size_t k = 0; k < n.file.devices.size(); ++k)
                add(k, c);
    return out;
}

InitCmdCheck::InitCmdCheck(const esc::Segment& seg, std::vector<ExpectedWrite> expected)
    : seg_(seg), expected_(std::move(expected)), pending_(seg.size()) {
    buf_.resize(2048);
}

void InitCmdCheck::on_request(ConstBytes frame, std::uint64_t) {
    const std::size_t len = std::min(frame.size(), buf_.size());
    std::copy(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(len), buf_.begin());
    const Bytes b(buf_.data(), len);
    seg_.reachable();
    const protocol::ParsedFrame pf = protocol::parse_frame(b);
    if (pf.error != protocol::FrameError::None) return;
    for (std::size_t k = 0; k < pf.count; ++k) {
        const protocol::DatagramView d = pf.datagram(b, k);
        if (!is_physical_write(d.raw_command())) continue;
        // The slaves it addresses (ETG.1000.4: auto-increment, configured address, broadcast).
        std::vector<std::size_t> to;
        const Command c = d.command();
        if (c == Command::APWR || c == Command::APRW) {
            std::size_t p = static_cast<std::uint16_t>(0u - d.adp());
            for (std::size_t i = 0; i < seg_.size(); ++i)
                if (seg_.reached(i) && p-- == 0) {
                    to.push_back(i);
                    break;
                }
        } else if (c == Command::FPWR || c == Command::FPRW) {
            for (std::size_t i = 0; i < seg_.size(); ++i)
                if (seg_.reached(i) && seg_.slave(i).esc().addressed_fixed(d.adp())) to.push_back(i);
        } else {
            for (std::size_t i = 0; i < seg_.size(); ++i)
                if (seg_.reached(i)) to.push_back(i);
        }
        const std::uint32_t al = addr(Reg::AlControl);
        const bool request = d.ado() <= al && al < std::uint32_t{d.ado()} + d.length();
        for (std::size_t i : to) {
            if (request) {
                on_state_request(i, d.data()[al - d.ado()]);
            } else if (compared(d.ado(), d.length())) {
                on_write(i, {d.ado(), std::vector<std::uint8_t>(d.data(), d.data() + d.length()),
                             d.raw_command()});
            }
        }
    }
}

void InitCmdCheck::on_write(std::size_t slave, const Write& w) {
    auto& p = pending_[slave];
    if (p.size() < kMaxPending) p.push_back(w);
}

void InitCmdCheck::report(bool missing, std::size_t slave, Transition t, std::string what) {
    for (auto& d : differences_)
        if (d.missing == missing && d.slave == slave && d.transition == t && d.what == what) {
            ++d.count;
            return;
        }
    differences_.push_back({missing, slave, t, std::move(what), 1});
}

void InitCmdCheck::on_state_request(std::size_t slave, std::uint8_t requested) {
    const Transition t{static_cast<std::uint8_t>(seg_.slave(slave).esc().al_status() & 0x0F),
                       static_cast<std::uint8_t>(requested & 0x0F)};
    std::vector<Write> sent = std::move(pending_[slave]);
    pending_[slave].clear();
    // What the master wrote (the last write of a byte counts), and what the ENI's commands write.
    // Each byte with each value written to it (a register written several times, e.g. to step through
    // something, is expected or sent with each of its values).
    std::set<std::pair<std::uint16_t, std::uint8_t>> wrote, expected;
    for (const auto& w : sent)
        for (std::size_t k = 0; k < w.data.size(); ++k)
            wrote.emplace(static_cast<std::uint16_t>(w.ado + k), w.data[k]);
    std::vector<const ExpectedWrite*> mine;
    for (const auto& e : expected_)
        if (e.slave == slave &&
            std::find(e.transitions.begin(), e.transitions.end(), t) != e.transitions.end()) {
            mine.push_back(&e);
            for (std::size_t k = 0; k < e.data.size(); ++k)
                expected.emplace(static_cast<std::uint16_t>(e.ado + k), e.data[k]);
        }
    for (const auto* e : mine) {
        bool done = true;
        for (std::size_t k = 0; k < e->data.size() && done; ++k)
            done = wrote.count({static_cast<std::uint16_t>(e->ado + k), e->data[k]}) > 0;
        if (!done)
            report(true, slave, t,
                   fmt::format("0x{:04X} {} not written ({})", e->ado, bytes(e->data), e->label));
    }
    for (const auto& w : sent) {
        bool known = true;
        for (std::size_t k = 0; k < w.data.size() && known; ++k)
            known = expected.count({static_cast<std::uint16_t>(w.ado + k), w.data[k]}) > 0;
        if (!known)
            report(false, slave, t,
                   fmt::format("{} 0x{:04X} {}", protocol::to_string(static_cast<Command>(w.command)), w.ado,
                               bytes(w.data)));
        ExpectedWrite o;
        o.slave = slave;
        o.transitions = {t};
        o.ado = w.ado;
        o.data = w.data;
        if (observed_.size() < 4096) observed_.push_back(std::move(o));
    }
}

std::string InitCmdCheck::summary() const {
    std::string s;
    std::size_t missing = 0;
    for (const auto& d : differences_) {
        missing += d.missing;
        s += fmt::format("slave {} {}: {} {}{}\n", d.slave, to_string(d.transition),
                         d.missing ? "missing:" : "not in the ENI:", d.what,
                         d.count > 1 ? fmt::format(" ({} times)", d.count) : "");
    }
    s += fmt::format(
        "InitCmds: {} expected command(s) the master did not send, {} write(s) the ENI does not "
        "have\n",
        missing, differences_.size() - missing);
    return s;
}

}  // namespace vecat::report
