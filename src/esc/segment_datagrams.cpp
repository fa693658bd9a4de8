// Which ESCs each datagram of a frame concerns, and the datagrams handed to them in the order the frame
// passes them (Segment::process_datagrams): the addressing table of every ESC, and its index (AddressIndex)
// for frames of configured-address and logical datagrams only.
#include <algorithm>
#include <functional>

#include "esc/segment.hpp"
#include "protocol/frame.hpp"

namespace vecat::esc {

using protocol::Command;
using protocol::DatagramView;
using protocol::ParsedFrame;

void Segment::refresh_addressing() {
    finish_background_firmware();  // (it reads every ESC)
    addressing_.resize(slaves_.size());
    for (std::size_t k = 0; k < slaves_.size(); ++k)
        addressing_[k] = slaves_[k]->esc().addressing();
    addressed_epoch_ = address_epoch_;
    addressed_slaves_epoch_ = slaves_epoch_;
    index_fresh_ = false;
}

bool Segment::find_candidates(const ParsedFrame& pf, std::size_t intact) {
    for (std::size_t i = 0; i < pf.count; ++i)
        if (reach_[i].reach != Reach::None && reach_[i].reach != Reach::Fixed &&
            reach_[i].reach != Reach::Logical)
            return false;
    if (!index_fresh_) {
        address_index_.rebuild(addressing_);
        index_fresh_ = true;
    }
    // In the frame's order, each once. A datagram adds each slave at most twice (AddressIndex::logical), so
    // the list stays within three times the line's length when it is made unique whenever it grows past the
    // length (no allocation once the line had this many slaves).
    const auto in_order = [&] {
        // (Strictly rising already, the usual case: a line's process image mapped in the line's order.)
        if (std::adjacent_find(candidates_.begin(), candidates_.end(), std::greater_equal<>()) ==
            candidates_.end())
            return;
        std::sort(candidates_.begin(), candidates_.end());
        candidates_.erase(std::unique(candidates_.begin(), candidates_.end()), candidates_.end());
    };
    candidates_.clear();
    candidates_.reserve(3 * slaves_.size());
    for (std::size_t i = 0; i < pf.count; ++i) {
        const DatagramReach& r = reach_[i];
        if (r.reach == Reach::Fixed)
            address_index_.fixed(r.adp, candidates_);
        else if (r.reach == Reach::Logical)
            address_index_.logical(r.first_bit, r.last_bit, candidates_);
        if (candidates_.size() > slaves_.size()) in_order();
    }
    in_order();
    // Only those it reaches.
    std::erase_if(candidates_, [&](std::uint32_t k) { return k >= intact || !reached_[k]; });
    return true;
}

namespace {

bool reads_memory(Command c) {
    switch (c) {
        case Command::APRD:
        case Command::APRW:
        case Command::FPRD:
        case Command::FPRW:
        case Command::BRD:
        case Command::BRW:
        case Command::ARMW:
        case Command::FRMW:
        case Command::LRD:
        case Command::LRW:
            return true;
        default:
            return false;
    }
}

}  // namespace

void Segment::process_datagrams(Bytes frame, const ParsedFrame& pf, std::size_t intact, std::size_t latch_pos,
                                std::uint64_t now_ns) {
    if (addressed_epoch_ != address_epoch_ || addressed_slaves_epoch_ != slaves_epoch_) refresh_addressing();
    // What each datagram can reach (ETG.1000.4 5.4: the addressing modes).
    bool auto_increment = false;
    bool any_reads = false;
    for (std::size_t i = 0; i < pf.count; ++i) {
        const DatagramView d = pf.datagram(frame, i);
        DatagramReach& r = reach_[i];
        r.adp = d.adp();
        switch (d.command()) {
            case Command::APRD:
            case Command::APWR:
            case Command::APRW:
                r.reach = Reach::Position;
                auto_increment = true;
                break;
            case Command::FPRD:
            case Command::FPWR:
            case Command::FPRW:
                r.reach = Reach::Fixed;
                break;
            case Command::BRD:
            case Command::BWR:
            case Command::BRW:
            case Command::ARMW:  // the ESC at the position reads, every other one writes
            case Command::FRMW:  // the ESC of the address reads, every other one writes
                r.reach = Reach::All;
                break;
            case Command::LRD:
            case Command::LWR:
            case Command::LRW:
                r.reach = d.length() ? Reach::Logical : Reach::None;
                r.first_bit = static_cast<std::uint64_t>(d.logical_address()) * 8;
                r.last_bit = r.first_bit + d.length() * 8 - 1;
                break;
            default:  // NOP and unknown commands pass every ESC unchanged
                r.reach = Reach::None;
                break;
        }
        const bool dc_time_only =
            r.reach != Reach::Logical && d.length() > 0 &&
            Esc::dc_time_registers(d.ado(), static_cast<std::uint32_t>(d.ado()) + d.length() - 1);
        r.reads = r.reach != Reach::None && !dc_time_only && reads_memory(d.command());
        any_reads |= r.reads;
    }
    // position: the ESCs the frame has passed so far (each counts up the ADP of auto-increment commands).
    const auto concerns = [](const DatagramReach& r, const Esc::Addressing& a, std::uint16_t position) {
        switch (r.reach) {
            case Reach::None:
                return false;
            case Reach::All:
                return true;
            case Reach::Position:
                return static_cast<std::uint16_t>(r.adp + position) == 0;
            case Reach::Fixed:
                return a.fixed(r.adp);
            case Reach::Logical:
                return a.logical(r.first_bit, r.last_bit);
        }
        return false;
    };
    // A slave the frame reads catches up with its own cycle first (see set_local_cycle_ns), or posts the
    // mailbox message it has for the master (one that arrived between its runs: an EoE frame from the host,
    // an emergency of an injected fault). All of them run before the frame reaches the first ESC: a slave's
    // run depends on its own ESC and on the slaves it shares state with (which run in order, see
    // set_firmware_threads), not on what the frame does at the ESCs before it, so this is the same as each
    // running as the frame reaches it, and the runs can go to several threads as one batch.
    // A frame of configured-address and logical datagrams only goes to the slaves the index names (the
    // candidates, in the frame's order); any other frame to every slave. A datagram that changes a slave's
    // addressing (an FMMU or its station address written) changes which of the frame's later datagrams
    // concern that slave, and no other: each candidate looks at every datagram with its addressing as it is
    // then (pass), so the candidates found before the frame stay right.
    bool indexed = find_candidates(pf, intact);
    // On a line too large for a core's cache the frame's slaves are asked for all at once, not found cold
    // one after the other (Slave::prefetch_for_frame; on a small line that is only overhead).
    if (indexed && slaves_.size() >= kPrefetchSlaves)
        for (const std::uint32_t k : candidates_)
            slaves_[k]->prefetch_for_frame();
    // The deferred frames' firmware runs first if this frame may see what it does (set_deferred_firmware),
    // and then the deadlines those runs set that are due at this frame's time (a watchdog shorter than the
    // time since the deferred frames), as the catch-up before the frame would have taken them.
    if (deferred_count_ != 0 && (!indexed || candidates_share_deferred_groups())) {
        run_deferred_firmware();
        catch_up_deadlines(now_ns);
    }
    if (deferred_count_ != 0) ++counters_.past_deferred_firmware;
    if (any_reads) {
        const auto pick_if_read = [&](std::size_t k, std::uint16_t position) {
            const Esc::Addressing& a = addressing_[k];
            for (std::size_t i = 0; i < pf.count; ++i) {
                const DatagramReach& r = reach_[i];
                if (!r.reads || !concerns(r, a, position)) continue;
                if (r.reach == Reach::Logical && !a.logical_read(r.first_bit, r.last_bit)) continue;
                if (stale(k, now_ns) || slaves_[k]->mailbox_output_pending()) pick(k);
                return;
            }
        };
        if (indexed) {
            for (const std::uint32_t k : candidates_)
                pick_if_read(k, 0);
        } else {
            std::uint16_t position = 0;
            for (std::size_t k = 0; k < intact; ++k) {
                if (!reached_[k]) continue;
                pick_if_read(k, position);
                ++position;
            }
        }
        const std::uint64_t epoch = address_epoch_;
        run_picked(now_ns);
        if (address_epoch_ != epoch) {
            refresh_addressing();
            indexed = find_candidates(pf, intact);
        }
    }
    if (background_) ++counters_.beside_firmware;
    // The datagrams at slave k.
    const auto pass = [&](std::size_t k, std::uint16_t position) {
        Esc* esc = nullptr;
        FrameTiming t{};
        for (std::size_t i = 0; i < pf.count; ++i) {
            const DatagramReach& r = reach_[i];
            if (!concerns(r, addressing_[k], position)) continue;
            if (!esc) {
                esc = &slaves_[k]->esc();
                const FrameTiming& rel = timing_[k];
                t = FrameTiming{now_ns + rel.port0_ns, now_ns + rel.port1_ns, now_ns + rel.port2_ns,
                                now_ns + rel.port3_ns};
            }
            DatagramView d = pf.datagram(frame, i);
            if (r.reach == Reach::Position) d.set_adp(0);  // as the ESCs before this one left it
            const std::uint64_t epoch = address_epoch_;
            const bool took = esc->process(d, t);
            if (address_epoch_ != epoch) {
                addressing_[k] = esc->addressing();  // for its next datagrams
                index_fresh_ = false;
            }
            if (i == latch_pos && took) latched_[k] = 1;
        }
        // Marks the slave for its firmware run (0: run now) if the frame gave it work.
        if (esc && esc->take_firmware_work()) mark_for_run(k);
    };
    std::uint16_t position = 0;
    if (indexed) {
        for (const std::uint32_t k : candidates_)
            pass(k, 0);
    } else {
        for (std::size_t k = 0; k < intact; ++k) {
            if (!reached_[k]) continue;
            pass(k, position);
            ++position;
        }
    }
    // Each ESC passed counted up the ADP of the auto-increment and broadcast commands; the ESCs that the
    // loop above did not hand an auto-increment datagram to count here.
    if (auto_increment)
        for (std::size_t i = 0; i < pf.count; ++i)
            if (reach_[i].reach == Reach::Position)
                pf.datagram(frame, i).set_adp(static_cast<std::uint16_t>(reach_[i].adp + position));
    addressed_epoch_ = address_epoch_;  // the entries of the ESCs that changed were taken again above
}

}  // namespace vecat::esc
