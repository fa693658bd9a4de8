// The slaves' firmware runs around the frames (Segment, "Firmware when it is needed"), and their batches on
// several threads (Segment::set_firmware_threads).
#include <algorithm>
#include <numeric>
#include <utility>

#include "esc/firmware_threads.hpp"
#include "esc/segment.hpp"

namespace vecat::esc {

void Segment::deliver_coupled_pulses_now(std::uint64_t now_ns) {
    if (coupled_epoch_ != slaves_epoch_) {
        coupled_epoch_ = slaves_epoch_;
        coupled_.clear();
        for (std::size_t k = 0; k < slaves_.size(); ++k)
            if (slaves_[k]->app().coupled()) coupled_.push_back(k);
    }
    for (;;) {
        std::size_t first = slaves_.size();
        std::uint64_t t = DistributedClock::kNever;
        for (const std::size_t k : coupled_)
            if (!halted_[k])
                if (const std::uint64_t p = slaves_[k]->esc().dc().next_pulse_host_ns(); p < t) {
                    t = p;
                    first = k;
                }
        if (first == slaves_.size() || t > now_ns) return;
        slaves_[first]->deliver_sync_pulses(t);
    }
}

void Segment::run_due_firmware(std::uint64_t now_ns) {
    deliver_coupled_pulses(now_ns);
    if (marks_valid_ && now_ns >= latest_run_ns_) {
        for (const std::uint32_t k : marked_)
            if (last_run_ns_[k] == 0) pick(k);
    } else {
        for (std::size_t k = 0; k < slaves_.size(); ++k)
            if (last_run_ns_[k] == 0 || now_ns < last_run_ns_[k]) pick(k);
    }
    // Every marked slave runs now.
    marked_.clear();
    marks_valid_ = true;
    run_picked(now_ns);
}

void Segment::run_deferred_firmware() {
    finish_background_firmware();
    if (deferred_count_ == 0) return;
    const std::size_t count = std::exchange(deferred_count_, 0);
    deferred_marks_ = 0;
    // Each frame's marks at its time, in order; the last frame's as run_due_firmware does (it also finds
    // what a frame that did not keep its marks left: more marks than marked_ holds).
    std::size_t begin = 0;
    for (std::size_t f = 0; f + 1 < count; ++f) {
        for (std::size_t i = begin; i < deferred_[f].marks_end; ++i)
            if (last_run_ns_[marked_[i]] == 0) pick(marked_[i]);
        begin = deferred_[f].marks_end;
        run_picked(deferred_[f].at_ns);
    }
    run_due_firmware(deferred_[count - 1].at_ns);
}

void Segment::start_deferred_firmware() {
    if (background_) {
        // The workers are still at the frames before: the frames since stay deferred until they are done, so
        // that this thread is free for the next frame.
        if (!threads_->finished()) return;
        finish_background_firmware();
    }
    // Only when the marks are all there is to run at the frames' times (run_due_firmware's quick way).
    if (deferred_count_ == 0 || !threads_ || threads_->threads() < 2 || marked_.size() < kMinParallelRuns ||
        !marks_valid_ || deferred_[0].at_ns < latest_run_ns_ || grouped_epoch_ != slaves_epoch_ ||
        picked_count_ != 0)
        return;
    // Each frame's marks at its time. No group has marks of two of the frames (a frame that concerns a group
    // a frame before it marked runs the deferred firmware first: candidates_share_deferred_groups), so one
    // batch of groups runs them all as run_deferred_firmware would, and the frames' order within a group
    // does not arise. A coupled drive can only be among the last frame's marks (keep_deferred): its SYNC
    // pulses up to that frame's time come first, as run_due_firmware hands them out.
    const std::uint64_t last = deferred_[deferred_count_ - 1].at_ns;
    deliver_coupled_pulses(last);
    const auto due =
        std::count_if(marked_.begin(), marked_.end(), [&](std::uint32_t k) { return last_run_ns_[k] == 0; });
    if (static_cast<std::size_t>(due) < kMinParallelRuns) {
        // (Some had run since they were marked: a frame's catch-up.) Few enough for this thread, now.
        run_deferred_firmware();
        return;
    }
    std::size_t begin = 0;
    for (std::size_t f = 0; f < deferred_count_; ++f) {
        const std::size_t end = f + 1 < deferred_count_ ? deferred_[f].marks_end : marked_.size();
        for (std::size_t i = begin; i < end; ++i)
            if (const std::uint32_t k = marked_[i]; last_run_ns_[k] == 0) {
                pick(k);
                run_at_ns_[k] = deferred_[f].at_ns;
            }
        begin = end;
    }
    marked_.clear();
    deferred_marks_ = 0;
    make_batch(last);
    counters_.firmware_runs += picked_count_;
    picked_count_ = 0;
    background_list_.swap(picked_list_);  // (both hold one per slave)
    background_ = true;
    background_frames_ = deferred_count_;
    ++counters_.background_batches;
    counters_.background_frames += deferred_count_;
    threads_->start(batch_groups_.size(), &Segment::run_group, this);
}

void Segment::finish_background_firmware() {
    if (!background_) return;
    threads_->join();
    background_ = false;
    // The deadlines the runs set.
    for (const std::uint32_t k : background_list_)
        earliest_deadline_ns_ = std::min(earliest_deadline_ns_, deadline_ns_[k]);
    background_list_.clear();
    // Its frames are done; the frames deferred beside it move up, their groups marked anew.
    std::copy(deferred_.begin() + background_frames_, deferred_.begin() + deferred_count_, deferred_.begin());
    deferred_count_ -= background_frames_;
    if (deferred_count_ == 0 || grouped_epoch_ != slaves_epoch_) return;
    ++deferral_serial_;
    for (std::size_t i = 0; i < deferred_marks_; ++i)
        group_deferred_[group_of_[marked_[i]]] = deferral_serial_;
}

// (A frame comes here with a place left: keep_deferred let the frames before it stay only then.)
void Segment::defer_frame_firmware(std::uint64_t now_ns) {
    deferred_[deferred_count_++] = DeferredFrame{now_ns, marked_.size()};
    if (deferred_count_ > 1 && grouped_epoch_ != slaves_epoch_) {
        // The slaves changed during the frame: the groups of the frames before are no longer known.
        deferred_marks_ = marked_.size();
        run_deferred_firmware();
        return;
    }
    if (deferred_count_ == 1) ++deferral_serial_;
    if (grouped_epoch_ != slaves_epoch_) refresh_groups();
    for (std::size_t i = deferred_marks_; i < marked_.size(); ++i)
        group_deferred_[group_of_[marked_[i]]] = deferral_serial_;
    deferred_marks_ = marked_.size();
}

// Before the frame: no slave's deadline is due at its time and no deferred frame marked a coupled drive, so
// the catch-up before it (catch_up_deadlines, and the coupled drives' SYNC pulses up to its time, which step
// nothing but those drives) runs no slave the deferred frames marked, and the marks are all in marked_.
// The deferred runs have not set their slaves' next deadlines yet: the frame comes within a local cycle of
// the first deferred frame, before a deadline a run sets a local cycle ahead (a pending state change's poll)
// falls due. Which slaves the frame concerns is known later (candidates_share_deferred_groups). A deadline
// sooner than that (a process data watchdog shorter than the local cycle) is taken before the next frame that
// concerns the slave reads it (process_datagrams), or when the deferred firmware runs: not at the first
// frame past it, as without the deferral, when that frame does not concern the slave. (Knowing it before
// the run would cost each deferred slave a look at its deadlines on the serve loop's thread.)
bool Segment::keep_deferred(std::uint64_t now_ns, const FrameDamage& damage) const {
    return deferred_count_ < kMaxDeferredFrames && now_ns < deferred_[0].at_ns + local_cycle_ns_ &&
           marks_valid_ && now_ns >= latest_run_ns_ && now_ns < earliest_deadline_ns_ &&
           coupled_epoch_ == slaves_epoch_ && !coupled_deferred() && !redundant() && !downstream_ &&
           damage.kind == FrameDamage::Kind::None;
}

template <class Slaves>
bool Segment::share_deferred_groups(const Slaves& slaves) const {
    if (grouped_epoch_ != slaves_epoch_) return true;  // (the groups of the deferred frames are not known)
    return std::any_of(slaves.begin(), slaves.end(),
                       [&](std::size_t k) { return group_deferred_[group_of_[k]] == deferral_serial_; });
}

bool Segment::coupled_deferred() const {
    return !coupled_.empty() && share_deferred_groups(coupled_);
}

bool Segment::candidates_share_deferred_groups() const {
    return share_deferred_groups(candidates_);
}

void Segment::run_firmware(std::uint64_t now_ns) {
    run_deferred_firmware();
    deliver_coupled_pulses(now_ns);
    for (std::size_t k = 0; k < slaves_.size(); ++k)
        pick(k);
    run_picked(now_ns);
}

void Segment::run(std::size_t k, std::uint64_t now_ns) {
    run_slave(k, now_ns);
    ++counters_.firmware_runs;
}

void Segment::run_slave(std::size_t k, std::uint64_t now_ns) {
    if (halted_[k])
        slaves_[k]->esc().tick(now_ns);  // the silicon's watchdogs keep running
    else
        slaves_[k]->run(now_ns);
    last_run_ns_[k] = now_ns == 0 ? 1 : now_ns;
    // A halted firmware has no deadlines but the silicon's watchdog.
    deadline_ns_[k] = halted_[k] ? slaves_[k]->esc().watchdog_deadline_ns()
                                 : std::min(slaves_[k]->next_event_ns(now_ns + local_cycle_ns_),
                                            now_ns + kMaxLagCycles * local_cycle_ns_);
    pulse_ns_[k] = slaves_[k]->esc().dc().next_pulse_host_ns();
    const std::uint64_t cycle = halted_[k] ? 0 : slaves_[k]->next_cycle_ns();
    cycle_ns_[k] = cycle != 0 ? cycle : now_ns + local_cycle_ns_;
}

void Segment::tick(std::uint64_t now_ns) {
    run_firmware(now_ns);
}

void Segment::tick_part(std::uint64_t now_ns, std::size_t first, std::size_t count) {
    run_deferred_firmware();
    const std::size_t n = slaves_.size();
    for (std::size_t i = 0; i < std::min(count, n); ++i)
        pick((first + i) % n);
    catch_up_deadlines(now_ns);  // the deadlines due, and runs the batch
}

bool Segment::deadline_due(std::size_t k, std::uint64_t now_ns) const {
    const std::uint64_t last = last_run_ns_[k];
    return last == 0 || now_ns < last || deadline_ns_[k] <= now_ns;
}

bool Segment::stale(std::size_t k, std::uint64_t now_ns) const {
    // (The pulse as of the last run, with a microsecond to spare for the drift of the DC unit since.)
    return cycle_ns_[k] <= now_ns || pulse_ns_[k] <= now_ns + 1'000;
}

void Segment::catch_up(std::uint64_t now_ns) {
    deliver_coupled_pulses(now_ns);
    for (std::size_t k = 0; k < slaves_.size(); ++k)
        if (deadline_due(k, now_ns) || stale(k, now_ns)) pick(k);
    run_picked(now_ns);
}

void Segment::catch_up_deadlines(std::uint64_t now_ns) {
    deliver_coupled_pulses(now_ns);
    if (now_ns < earliest_deadline_ns_ && now_ns >= latest_run_ns_ && marks_valid_) {
        // No deadline is due: the marked slaves only (not those of deferred frames: they run at their times).
        for (std::size_t i = deferred_marks_; i < marked_.size(); ++i)
            if (last_run_ns_[marked_[i]] == 0) pick(marked_[i]);
    } else {
        // The earliest deadline of the slaves that do not run now (those that do fold theirs in as they run).
        std::uint64_t earliest = DistributedClock::kNever;
        for (std::size_t k = 0; k < slaves_.size(); ++k)
            if (deadline_due(k, now_ns))
                pick(k);
            else
                earliest = std::min(earliest, deadline_ns_[k]);
        earliest_deadline_ns_ = earliest;
    }
    run_picked(now_ns);
}

std::uint64_t Segment::next_event_ns() const {
    std::uint64_t t = DistributedClock::kNever;
    for (const auto& s : slaves_)
        t = std::min(t, s->esc().dc().next_pulse_host_ns());
    return t;
}

std::uint64_t Segment::next_firmware_ns() const {
    std::uint64_t t = DistributedClock::kNever;
    for (const std::uint64_t d : deadline_ns_)
        t = std::min(t, d);
    return t;
}

// ---- Batches on several threads

void Segment::set_firmware_threads(FirmwareThreads* threads) {
    finish_background_firmware();
    threads_ = threads;
}

Segment::~Segment() {
    finish_background_firmware();
}

void Segment::run_picked(std::uint64_t now_ns) {
    if (picked_count_ == 0) return;
    finish_background_firmware();  // (one batch at a time)
    if (!threads_ || threads_->threads() < 2 || picked_count_ < kMinParallelRuns) {
        // In the slaves' order (slaves that share state run in order). Picked in order, mostly.
        if (picked_count_ > 1 && !std::is_sorted(picked_list_.begin(), picked_list_.end()))
            std::sort(picked_list_.begin(), picked_list_.end());
        latest_run_ns_ = std::max(latest_run_ns_, now_ns == 0 ? 1 : now_ns);
        for (const std::uint32_t k : picked_list_) {
            picked_[k] = 0;
            run(k, now_ns);
            earliest_deadline_ns_ = std::min(earliest_deadline_ns_, deadline_ns_[k]);
        }
        picked_list_.clear();
        picked_count_ = 0;
        return;
    }
    make_batch(now_ns);
    threads_->run(batch_groups_.size(), &Segment::run_group, this);
    // The deadlines the workers set.
    for (const std::uint32_t k : picked_list_)
        earliest_deadline_ns_ = std::min(earliest_deadline_ns_, deadline_ns_[k]);
    picked_list_.clear();
    counters_.firmware_runs += picked_count_;
    picked_count_ = 0;
}

void Segment::make_batch(std::uint64_t now_ns) {
    if (picked_count_ > 1 && !std::is_sorted(picked_list_.begin(), picked_list_.end()))
        std::sort(picked_list_.begin(), picked_list_.end());
    latest_run_ns_ = std::max(latest_run_ns_, now_ns == 0 ? 1 : now_ns);
    if (grouped_epoch_ != slaves_epoch_) refresh_groups();
    ++batch_serial_;
    batch_groups_.clear();
    for (const std::uint32_t k : picked_list_) {
        const std::uint32_t g = group_of_[k];
        if (group_batch_[g] != batch_serial_) {
            group_batch_[g] = batch_serial_;
            batch_groups_.push_back(g);  // capacity: one per group (refresh_groups)
        }
    }
    batch_now_ns_ = now_ns;
}

void Segment::run_group(void* self, std::size_t item) {
    Segment& s = *static_cast<Segment*>(self);
    const std::uint32_t g = s.batch_groups_[item];
    for (std::uint32_t m = s.group_begin_[g]; m < s.group_begin_[g + 1]; ++m) {
        const std::uint32_t k = s.members_[m];
        if (!s.picked_[k]) continue;
        s.picked_[k] = 0;
        s.run_slave(k, s.background_ ? s.run_at_ns_[k] : s.batch_now_ns_);
    }
}

void Segment::refresh_groups() {
    grouped_epoch_ = slaves_epoch_;
    const std::size_t n = slaves_.size();
    // Union-find over the slaves: two slaves that name a common key share state.
    std::vector<std::uint32_t> root(n);
    std::iota(root.begin(), root.end(), 0u);
    const auto find = [&](std::uint32_t x) {
        while (root[x] != x)
            x = root[x] = root[root[x]];
        return x;
    };
    std::vector<std::pair<const void*, std::uint32_t>> keys;
    std::vector<const void*> mine;
    for (std::size_t k = 0; k < n; ++k) {
        mine.clear();
        slaves_[k]->app().shared_state(mine);
        for (const void* key : mine)
            keys.emplace_back(key, static_cast<std::uint32_t>(k));
    }
    std::sort(keys.begin(), keys.end());
    for (std::size_t i = 1; i < keys.size(); ++i)
        if (keys[i].first == keys[i - 1].first) {
            const std::uint32_t a = find(keys[i].second), b = find(keys[i - 1].second);
            root[std::max(a, b)] = std::min(a, b);
        }
    // Groups numbered by their first slave; members in the slaves' order.
    group_of_.assign(n, 0);
    std::vector<std::uint32_t> number(n, ~std::uint32_t{0});
    std::uint32_t groups = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const std::uint32_t r = find(static_cast<std::uint32_t>(k));
        if (number[r] == ~std::uint32_t{0}) number[r] = groups++;
        group_of_[k] = number[r];
    }
    group_begin_.assign(groups + 1, 0);
    for (std::size_t k = 0; k < n; ++k)
        ++group_begin_[group_of_[k] + 1];
    for (std::uint32_t g = 0; g < groups; ++g)
        group_begin_[g + 1] += group_begin_[g];
    members_.assign(n, 0);
    std::vector<std::uint32_t> at(group_begin_.begin(), group_begin_.end() - 1);
    for (std::size_t k = 0; k < n; ++k)
        members_[at[group_of_[k]]++] = static_cast<std::uint32_t>(k);
    group_batch_.assign(groups, 0);
    group_deferred_.assign(groups, 0);
    batch_groups_.reserve(groups);
}

std::size_t Segment::firmware_groups() {
    if (grouped_epoch_ != slaves_epoch_) refresh_groups();
    return group_begin_.empty() ? 0 : group_begin_.size() - 1;
}

}  // namespace vecat::esc
