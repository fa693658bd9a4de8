#include "serve/server.hpp"

#include <poll.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <utility>
#include <vector>

namespace vecat::net {

namespace {

// Every frame to the master side goes out here: sent, counted, captured, observed.
void send_to_master(RawSocket& sock, const ServeOptions& opt, ConstBytes frame, ServeStats& st,
                    std::uint64_t now_ns) {
    if (sock.send(frame))
        ++st.sent;
    else
        ++st.send_errors;
    if (opt.pcap) opt.pcap->write(frame, realtime_ns(), PcapngWriter::kOutbound);
    if (opt.observer) opt.observer->on_reply(frame, now_ns);
}

// Sends the replies a fault held back whose time has come; shortens the wait to the next one.
void send_due_replies(RawSocket& sock, const ServeOptions& opt, std::array<std::uint8_t, 2048>& buf,
                      ServeStats& st, std::int64_t& wait_us) {
    const std::uint64_t t = monotonic_ns();
    while (const std::size_t n = opt.filter->take_due(t, Bytes(buf.data(), buf.size())))
        send_to_master(sock, opt, ConstBytes(buf.data(), n), st, t);
    const std::uint64_t due = opt.filter->next_due_ns();
    if (due != ~std::uint64_t{0})
        wait_us = std::min<std::int64_t>(wait_us, due > t ? static_cast<std::int64_t>((due - t) / 1000) : 0);
}

// Chained segments: waits for a frame on the master side (sock) or back from the next segment (down).
// from_down tells where it came from. Cable redundancy: down is the master's second port.
long receive_either(RawSocket& sock, RawSocket& down, Bytes buf, std::int64_t wait_us, bool spin,
                    bool& from_down) {
    for (int pass = 0; pass < 2; ++pass) {
        // Returning frames first: they complete a frame the master already waits for.
        if (long n = down.try_receive(buf); n != 0) {
            from_down = true;
            return n;
        }
        if (long n = sock.try_receive(buf); n != 0) {
            from_down = false;
            return n;
        }
        if (pass == 1 || spin) return 0;
        pollfd p[2] = {{sock.fd(), POLLIN, 0}, {down.fd(), POLLIN, 0}};
        const std::int64_t us = wait_us <= 0 ? 0 : wait_us;
        const timespec ts{static_cast<time_t>(us / 1'000'000), static_cast<long>((us % 1'000'000) * 1000)};
        if (::ppoll(p, 2, &ts, nullptr) <= 0) return 0;
    }
    return 0;
}

// Waits for a frame on the socket or for one of the side channel's descriptors to become readable (then
// services it). p: the socket's pollfd followed by the side channel's, made before the loop.
long receive_or_side(RawSocket& sock, SideChannel& side, std::vector<pollfd>& p, Bytes buf,
                     std::int64_t wait_us) {
    if (long n = sock.try_receive(buf); n != 0) return n;
    for (auto& x : p)
        x.revents = 0;
    const std::int64_t us = wait_us <= 0 ? 0 : wait_us;
    const timespec ts{static_cast<time_t>(us / 1'000'000), static_cast<long>((us % 1'000'000) * 1000)};
    if (::ppoll(p.data(), p.size(), &ts, nullptr) <= 0) return 0;
    if (std::any_of(p.begin() + 1, p.end(), [](const pollfd& x) { return x.revents != 0; }))
        side.service(monotonic_ns());
    return (p[0].revents & POLLIN) ? sock.try_receive(buf) : 0;
}

// A frame counts as of its kernel receive time (on the monotonic clock).
std::uint64_t frame_time(const RawSocket& sock, std::uint64_t now) {
    const std::uint64_t real = realtime_ns();
    const std::uint64_t rx_real = sock.last_receive_realtime_ns();
    if (rx_real != 0 && rx_real <= real && real - rx_real < 10'000'000) return now - (real - rx_real);
    return now;
}

// Slaves per part of a tick on a line longer than this (Segment::tick_part): a few tens of microseconds.
constexpr std::size_t kTickPart = 32;

// How often the serve loop looks at the link of the downstream interface.
constexpr std::uint64_t kLinkCheckNs = 10'000'000;

// How long the firmware may go without a run when no frame comes (ServeOptions::catch_up_budget_us). The
// work a run does grows with the time since the last one (the slaves' cycles to catch up); work_ns took
// gap_ns of backlog. The period follows the estimate that keeps that work at the budget, smoothed.
//
// The budget is at least the frame's own time on a real line: at 100 Mbit/s each byte takes 80 ns on the
// wire, and a frame 20 bytes more (preamble and inter-frame gap, IEEE 802.3). A real line cannot answer a
// frame before that time has passed, so work up to it in the reply path leaves vecat's answer no later
// than hardware's, and the loop need not wake up between frames for it: a full frame of process data
// (1,514 bytes) allows 123 us. A small frame (a few drives) keeps the configured budget.
class CatchUp {
  public:
    explicit CatchUp(const ServeOptions& opt)
        : min_ns_(static_cast<std::uint64_t>(std::max<std::int64_t>(opt.tick_us, 1)) * 1000),
          max_ns_(std::max(min_ns_, static_cast<std::uint64_t>(ServeOptions::kMaxCatchUpUs) * 1000)),
          budget_ns_(static_cast<std::uint64_t>(std::max<std::int64_t>(opt.catch_up_budget_us, 0)) * 1000),
          period_ns_(min_ns_) {}
    std::uint64_t period_ns() const { return period_ns_; }
    // After a frame of frame_bytes (0: a tick; it is held to the last frame's budget).
    void learn(std::uint64_t gap_ns, std::uint64_t work_ns, std::size_t frame_bytes) {
        if (frame_bytes != 0)
            frame_budget_ns_ = std::max(budget_ns_, (frame_bytes + kFrameOverheadBytes) * kWireNsPerByte);
        if (gap_ns < min_ns_) return;  // runs close together say little of the backlog
        const std::uint64_t estimate = work_ns == 0 ? max_ns_ : gap_ns / work_ns * frame_budget_ns_;
        period_ns_ = std::clamp((3 * period_ns_ + std::min(estimate, max_ns_)) / 4, min_ns_, max_ns_);
    }

  private:
    static constexpr std::uint64_t kWireNsPerByte = 80;       // 100 Mbit/s
    static constexpr std::uint64_t kFrameOverheadBytes = 20;  // preamble, start delimiter, inter-frame gap
    std::uint64_t min_ns_, max_ns_, budget_ns_, period_ns_;
    std::uint64_t frame_budget_ns_ = budget_ns_;
};

}  // namespace

ServeStats serve(esc::Segment& seg, RawSocket& sock, const ServeOptions& opt, const std::atomic<bool>& stop) {
    ServeStats st;
    std::array<std::uint8_t, 2048> buf{};
    std::uint64_t last_tick = monotonic_ns();  // the last firmware run: a frame's or a tick's
    std::uint64_t last_time = 0;               // latest time given to the segment
    const std::uint64_t tick_ns = static_cast<std::uint64_t>(std::max<std::int64_t>(opt.tick_us, 1)) * 1000;
    const std::uint64_t was_local_cycle = seg.local_cycle_ns();
    seg.set_local_cycle_ns(tick_ns);
    CatchUp catch_up(opt);
    std::uint64_t last_link_check = monotonic_ns();
    if (opt.downstream) seg.set_downstream_link(opt.downstream->carrier());
    if (opt.secondary) seg.set_secondary_link(opt.secondary->carrier());
    RawSocket* const other = opt.downstream ? opt.downstream : opt.secondary;
    std::vector<pollfd> side_fds;  // the socket, then the side channel's descriptors
    if (opt.side) {
        side_fds.push_back({sock.fd(), POLLIN, 0});
        for (const int fd : opt.side->fds())
            side_fds.push_back({fd, POLLIN, 0});
    }
    // The reply goes out before the firmware of the slaves runs (see Segment::set_deferred_firmware).
    const bool was_deferred = seg.deferred_firmware();
    seg.set_deferred_firmware(true);
    seg.set_firmware_threads(opt.firmware_threads);
    // Only this thread writes the counters: a relaxed load and store each, no locked instruction.
    const auto bump = [](std::atomic<std::uint64_t>& c, std::uint64_t by = 1) {
        c.store(c.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
    };
    // A frame waiting in the socket when a reply has gone out is answered before the firmware of the frames
    // before it runs (the segment runs that firmware first where the frame could see what it does,
    // Segment::firmware_deferred): a cycle's frames, sent back to back, come back back to back, and their
    // firmware runs once they are answered. The frames' observer calls wait for it too. Only on the plain
    // path (one socket, no side channel that could reach the slaves in between).
    std::array<std::uint64_t, esc::Segment::kMaxDeferredFrames> deferred_at{};
    std::size_t deferred = 0;
    std::uint64_t tick_end = 0;  // when the last tick ended (ServeCounters::frames_behind_tick)
    long held = 0;               // a frame received while a tick ran in parts: handled next
    std::size_t tick_from = 0;   // the slave the next tick in parts starts with
    const auto run_deferred = [&] {
        seg.run_deferred_firmware();
        if (opt.after_frame)
            for (std::size_t i = 0; i < deferred; ++i)
                opt.after_frame(opt.after_frame_context, deferred_at[i]);
        deferred = 0;
    };
    while (!stop.load(std::memory_order_relaxed)) {
        const bool spin = opt.busy_poll && !(opt.park && opt.park->load(std::memory_order_relaxed));
        const bool plain = !other && !opt.side;
        long n = std::exchange(held, 0);
        if (deferred != 0 && n == 0) {
            n = sock.try_receive(Bytes(buf.data(), buf.size()));
            if (n <= 0) {
                n = 0;
                run_deferred();
            }
        }
        if (opt.counters && n == 0) bump(opt.counters->wakeups);
        // Wake up for the next deadline of the firmware or the faults' timeline, or to catch up. (Only when
        // no frame is at hand: the deferred firmware has run then, Segment::start_deferred_firmware.)
        std::uint64_t due = ~std::uint64_t{0};
        std::int64_t wait_us = 0;
        if (n == 0) {
            due = std::min(seg.next_firmware_ns(), last_tick + catch_up.period_ns());
            if (opt.filter) due = std::min(due, opt.filter->next_event_ns());
            if (const std::uint64_t t = monotonic_ns(); due > t)  // rounded up: not awake before it is due
                wait_us =
                    static_cast<std::int64_t>(std::min<std::uint64_t>((due - t + 999) / 1000, 1'000'000));
        }
        if (opt.filter && n == 0) send_due_replies(sock, opt, buf, st, wait_us);
        bool from_down = false;
        if (n != 0) {
            // (a frame that waited: received above)
        } else if (other) {
            if (opt.side) opt.side->service(monotonic_ns());
            n = receive_either(sock, *other, Bytes(buf.data(), buf.size()), wait_us, spin, from_down);
        } else if (opt.side && !spin) {
            n = receive_or_side(sock, *opt.side, side_fds, Bytes(buf.data(), buf.size()), wait_us);
        } else {
            if (opt.side) opt.side->service(monotonic_ns());
            n = spin ? sock.try_receive(Bytes(buf.data(), buf.size()))
                     : sock.receive(Bytes(buf.data(), buf.size()), wait_us);
        }
        const std::uint64_t now = monotonic_ns();
        if (opt.downstream && now - last_link_check >= kLinkCheckNs) {
            last_link_check = now;
            if (const bool up = opt.downstream->carrier(); up != seg.downstream_link())
                seg.set_downstream_link(up);
        }
        if (opt.secondary && now - last_link_check >= kLinkCheckNs) {
            last_link_check = now;
            seg.set_secondary_link(opt.secondary->carrier());
        }
        if (n > 0 && opt.secondary) {
            // Cable redundancy: in at either master port, out of the one the ring leads the frame to.
            const unsigned from = from_down ? 1 : 0;
            RawSocket& in = from ? *opt.secondary : sock;
            ++st.received;
            if (from) ++st.received_secondary;
            if (opt.counters) bump(opt.counters->frames);
            std::size_t len = static_cast<std::size_t>(n);
            const std::uint64_t at = std::max(frame_time(in, now), last_time);
            last_time = at;
            if (opt.pcap) opt.pcap->write(ConstBytes(buf.data(), len), realtime_ns(), PcapngWriter::kInbound);
            if (opt.observer && from == 0) opt.observer->on_request(ConstBytes(buf.data(), len), at);
            unsigned to = 0;
            bool reply = false;
            if (opt.filter) {
                reply = opt.filter->process_frame_at(Bytes(buf.data(), buf.size()), len, at, from, to);
            } else {
                reply = seg.process_frame(Bytes(buf.data(), buf.size()), len, at, esc::FrameDamage{},
                                          from ? esc::MasterPort::Secondary : esc::MasterPort::Primary);
                to = seg.reply_port() == esc::MasterPort::Secondary ? 1 : 0;
            }
            // The reply path's work, the slaves' catch-up before the frame included (not the send).
            catch_up.learn(at - std::min(at, last_tick), monotonic_ns() - now, len);
            if (reply) {
                if (to) ++st.sent_secondary;
                send_to_master(to ? *opt.secondary : sock, opt, ConstBytes(buf.data(), len), st, at);
            }
            seg.run_deferred_firmware();
            if (opt.after_frame) opt.after_frame(opt.after_frame_context, at);
            last_tick = now;
        } else if (n > 0 && from_down) {
            // Back from the next segment: through the ESCs' port 1 -> port 0 path to the master side.
            std::size_t len = static_cast<std::size_t>(n);
            if (seg.return_frame(Bytes(buf.data(), buf.size()), len, now)) {
                ++st.returned;
                send_to_master(sock, opt, ConstBytes(buf.data(), len), st, now);
            }
        } else if (n > 0) {
            ++st.received;
            if (opt.counters) bump(opt.counters->frames);
            std::size_t len = static_cast<std::size_t>(n);
            // The frame counts as of its kernel receive time (on the monotonic clock), never before what
            // the segment has already seen: a SYNC pulse that fell due while the frame waited in the
            // socket is then handled after it, as on an ESC.
            const std::uint64_t real = realtime_ns();
            const std::uint64_t rx_real = sock.last_receive_realtime_ns();
            std::uint64_t at = frame_time(sock, now);
            if (opt.counters && at < tick_end) {
                bump(opt.counters->frames_behind_tick);
                bump(opt.counters->behind_tick_ns, tick_end - at);
            }
            at = std::max(at, last_time);
            last_time = at;
            if (opt.pcap)
                opt.pcap->write(ConstBytes(buf.data(), len), rx_real ? rx_real : real,
                                PcapngWriter::kInbound);
            if (opt.observer) opt.observer->on_request(ConstBytes(buf.data(), len), at);
            const bool reply = opt.filter ? opt.filter->process_frame(Bytes(buf.data(), buf.size()), len, at)
                                          : seg.process_frame(Bytes(buf.data(), buf.size()), len, at);
            // The reply path's work, the slaves' catch-up before the frame included (not the send).
            catch_up.learn(at - std::min(at, last_tick), monotonic_ns() - now, len);
            if (reply && opt.downstream && seg.frame_goes_downstream()) {
                // Port 1 of the last slave has a link: the frame goes on along the line.
                if (opt.downstream->send(ConstBytes(buf.data(), len)))
                    ++st.sent_downstream;
                else
                    ++st.send_errors;
            } else if (reply) {
                send_to_master(sock, opt, ConstBytes(buf.data(), len), st, at);
            }
            if (plain && seg.firmware_deferred() && deferred < deferred_at.size()) {
                deferred_at[deferred++] = at;  // runs when no frame waits (above)
                // On the firmware threads meanwhile, if nothing but the segment looks at the slaves before
                // the next frame (the observer looks before the segment does, the filter around it).
                if (!opt.observer && !opt.filter) seg.start_deferred_firmware();
            } else {
                run_deferred();  // this frame's firmware, and any before it
                if (opt.after_frame) opt.after_frame(opt.after_frame_context, at);
            }
            last_tick = now;
        } else if (n == 0 && now >= due) {
            if (plain && seg.size() > kTickPart) {
                // In parts, each followed by a look at the socket: a frame that comes is not kept waiting
                // behind the tick (it would be for hundreds of microseconds on a large line). Parts at this
                // tick's time; the next tick starts where this one stopped.
                for (std::size_t ran = 0; ran < seg.size(); ran += kTickPart) {
                    seg.tick_part(now, tick_from, kTickPart);
                    tick_from = (tick_from + kTickPart) % seg.size();
                    if (ran + kTickPart >= seg.size()) break;
                    if ((held = std::max(sock.try_receive(Bytes(buf.data(), buf.size())), 0L)) > 0) break;
                }
            } else {
                seg.tick(now);
            }
            tick_end = monotonic_ns();
            if (opt.counters) bump(opt.counters->ticks);
            if (opt.filter) opt.filter->tick(now);
            catch_up.learn(now - std::min(now, last_tick), monotonic_ns() - now, 0);
            last_tick = now;
            last_time = std::max(last_time, now);
        }
        if (opt.counters) opt.counters->catch_up_ns.store(catch_up.period_ns(), std::memory_order_relaxed);
    }
    run_deferred();
    seg.set_firmware_threads(nullptr);
    seg.set_deferred_firmware(was_deferred);
    seg.set_local_cycle_ns(was_local_cycle);
    if (opt.pcap) opt.pcap->flush();
    return st;
}

}  // namespace vecat::net
