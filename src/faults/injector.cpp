#include "faults/injector.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "coe/coe_application.hpp"
#include "faults/status.hpp"
#include "protocol/coe.hpp"

namespace vecat::faults {
namespace {

constexpr std::uint8_t kCoeServiceSdoRequest = 2;

bool line_fault(FaultKind k) {
    return k == FaultKind::Drop || k == FaultKind::Corrupt || k == FaultKind::Delay;
}
bool mailbox_fault(FaultKind k) {
    return k == FaultKind::SdoAbort || k == FaultKind::MailboxLostReply;
}
std::uint16_t drive_code(FaultKind k) {
    switch (k) {
        case FaultKind::EncoderFault:
            return 0x7305;
        case FaultKind::OverCurrent:
            return 0x2310;
        case FaultKind::FollowingError:
            return 0x8611;
        default:
            return 0;
    }
}

// A reply sink that loses what is committed: the request was executed, its reply never shows up in SM1.
class LosingSink final : public esc::MailboxReplySink {
  public:
    explicit LosingSink(esc::MailboxReplySink& inner) : inner_(inner) {}
    Bytes reply_buffer() override { return inner_.reply_buffer(); }
    void commit(protocol::MailboxType, std::size_t) override { ++lost; }
    bool can_commit() const override { return inner_.can_commit(); }
    std::size_t pending() const override { return inner_.pending(); }
    std::uint64_t lost = 0;

  private:
    esc::MailboxReplySink& inner_;
};

}  // namespace

FaultInjector::FaultInjector(esc::Segment& seg, std::uint64_t seed)
    : seg_(seg), rng_(seed), held_(kHeldReplies), held_data_(kHeldReplies * kMaxFrame) {
    for (std::size_t i = 0; i < seg_.size(); ++i)
        seg_.slave(i).set_mailbox_interceptor(this);
}

FaultInjector::~FaultInjector() {
    for (auto& a : active_)
        if (a->handler) a->handler->stop(a->spec, 0);
    for (std::size_t i = 0; i < seg_.size(); ++i)
        seg_.slave(i).set_mailbox_interceptor(nullptr);
}

void FaultInjector::register_handler(const std::string& kind, FaultHandler& h) {
    handlers_[kind] = &h;
}

void FaultInjector::load(const Scenario& s) {
    scenario_ = s;
    fired_.assign(s.events.size(), false);
    origin_set_ = false;
    frames_seen_ = 0;
    if (s.seed != 0) rng_.seed(s.seed);
}

void FaultInjector::note(const std::string& s) {
    if (on_event) on_event(s);
}

bool FaultInjector::roll(double p) {
    if (p >= 1.0) return true;
    if (p <= 0.0) return false;
    return uniform_(rng_) < p;
}

bool FaultInjector::hit(Active& a) {
    if (a.done) return false;
    ++a.hits;
    if (a.spec.count != 0 && a.hits >= a.spec.count) a.done = true;
    return true;
}

std::size_t FaultInjector::slave_index(const esc::Slave& s) const {
    for (std::size_t i = 0; i < seg_.size(); ++i)
        if (&seg_.slave(i) == &s) return i;
    return seg_.size();
}

std::string FaultInjector::start(FaultSpec f, std::uint64_t now_ns) {
    const std::size_t n = seg_.size();
    const bool per_slave = !line_fault(f.kind);
    if (per_slave && f.slave >= n)
        throw std::invalid_argument(f.name + ": slave " + std::to_string(f.slave) + " is not on the line (" +
                                    std::to_string(n) + " slaves)");
    if ((f.kind == FaultKind::Drop || f.kind == FaultKind::Corrupt) && f.cable >= seg_.cables())
        throw std::invalid_argument(f.name + ": cable " + std::to_string(f.cable) + " does not exist (0-" +
                                    std::to_string(seg_.cables() - 1) + ")");
    if (f.kind == FaultKind::LinkDown && seg_.cable_at(f.slave, f.port) == esc::Segment::kNoCable)
        throw std::invalid_argument("link_down: port " + std::to_string(f.port) + " of slave " +
                                    std::to_string(f.slave) + " has no link to lose");
    if (f.kind == FaultKind::Unplug) {
        // Hot connect: the group by its name, or the one headed by the slave.
        if (!f.group.empty()) {
            f.slave = seg_.hot_connect_head(f.group);
            if (f.slave >= n) throw std::invalid_argument("unplug: no hot connect group named " + f.group);
        }
        if (std::string why; f.elsewhere && !seg_.can_move_group(f.slave, f.to_slave, f.to_port, &why))
            throw std::invalid_argument("unplug: to=" + std::to_string(f.to_slave) + ":" +
                                        std::to_string(f.to_port) + ": " + why);
        const std::size_t end = seg_.group_end(f.slave);
        for (const auto& a : active_)
            if (!a->done && a->spec.kind == FaultKind::Unplug && a->spec.slave < end &&
                f.slave < seg_.group_end(a->spec.slave))
                throw std::invalid_argument("unplug: slave " + std::to_string(f.slave) +
                                            " is unplugged already (" + a->spec.id + ")");
    }
    if (f.id.empty()) f.id = f.name + "#" + std::to_string(next_id_++);
    for (const auto& a : active_)
        if (a->spec.id == f.id) throw std::invalid_argument("a fault with id " + f.id + " is already active");

    auto a = std::make_unique<Active>();
    a->started_ns = now_ns;
    a->until_ns = f.duration_ns ? now_ns + f.duration_ns : 0;
    switch (f.kind) {
        case FaultKind::AlError:
            // An event, not a state: the slave stays in error until the master acknowledges it.
            seg_.slave(f.slave).raise_error(static_cast<protocol::AlStatusCode>(f.code), f.state);
            ++counters_.faults_started;
            note("fault " + describe(f) + ": AL error raised");
            return f.id;
        case FaultKind::EncoderFault:
        case FaultKind::OverCurrent:
        case FaultKind::FollowingError: {
            auto* app = dynamic_cast<coe::CoeApplication*>(&seg_.slave(f.slave).app());
            if (!app || !app->simulates_faults())
                throw std::invalid_argument(f.name + ": slave " + std::to_string(f.slave) +
                                            " is not a drive (no object 0x2101)");
            break;
        }
        case FaultKind::DcDrift: {
            auto& dc = seg_.slave(f.slave).esc().dc();
            a->saved_ppm = dc.drift_ppm();
            dc.set_drift_ppm(f.ppm_is_step ? a->saved_ppm + f.ppm : f.ppm, now_ns);
            break;
        }
        case FaultKind::External: {
            const auto it = handlers_.find(f.name);
            if (it == handlers_.end())
                throw std::invalid_argument(f.name + ": unknown fault, or no handler registered for it");
            it->second->start(f, now_ns);
            a->handler = it->second;
            break;
        }
        default:
            break;
    }
    a->spec = std::move(f);
    const std::string id = a->spec.id;
    active_.push_back(std::move(a));
    apply_line_state();
    if (const std::uint16_t code = drive_code(active_.back()->spec.kind))
        set_drive_fault(active_.back()->spec.slave, code);
    ++counters_.faults_started;
    note("fault started: " + describe(active_.back()->spec));
    return id;
}

void FaultInjector::set_drive_fault(std::size_t slave, std::uint16_t code) {
    auto* app = dynamic_cast<coe::CoeApplication*>(&seg_.slave(slave).app());
    if (!app) return;
    app->simulate_fault(code);
}

void FaultInjector::end(Active& a, std::uint64_t now_ns, const char* why) {
    a.done = true;
    switch (a.spec.kind) {
        case FaultKind::DcDrift:
            seg_.slave(a.spec.slave).esc().dc().set_drift_ppm(a.saved_ppm, now_ns);
            break;
        case FaultKind::External:
            if (a.handler) a.handler->stop(a.spec, now_ns);
            break;
        case FaultKind::EncoderFault:
        case FaultKind::OverCurrent:
        case FaultKind::FollowingError:
            // The cause is gone; the drive keeps its fault until the master resets it (controlword bit 7).
            set_drive_fault(a.spec.slave, 0);
            break;
        case FaultKind::PowerOff:
            // Power is back: the device boots again (INIT, station address 0, fresh dictionary).
            if (seg_.restart_slave(a.spec.slave)) seg_.slave(a.spec.slave).set_mailbox_interceptor(this);
            break;
        case FaultKind::Unplug:
            // Plugged back (where it was, or into another free port: the slaves' positions then change, and
            // the faults follow their slaves): every device of the group starts as after power-up (INIT,
            // station address 0, its alias loaded from the SII again).
            if (a.spec.elsewhere) {
                std::vector<std::size_t> order;
                std::string refused;
                if (seg_.move_group(a.spec.slave, a.spec.to_slave, a.spec.to_port, order, &refused))
                    follow_slaves(order);
                else
                    note("unplug: " + refused + "; plugged back where it was");
            }
            for (std::size_t k = a.spec.slave; k < seg_.group_end(a.spec.slave); ++k)
                if (seg_.restart_slave(k)) seg_.slave(k).set_mailbox_interceptor(this);
            break;
        default:
            break;
    }
    ++counters_.faults_ended;
    note(std::string("fault ended (") + why + "): " + a.spec.id);
}

void FaultInjector::follow_slaves(const std::vector<std::size_t>& order) {
    std::vector<std::size_t> now(order.size());  // now[old position] = new position
    for (std::size_t k = 0; k < order.size(); ++k)
        now[order[k]] = k;
    for (auto& a : active_) {
        FaultSpec& f = a->spec;
        if (f.slave < now.size()) f.slave = now[f.slave];
        if (f.cable < now.size()) f.cable = now[f.cable];  // cable k leads into slave k (the ring's stays)
        if (f.elsewhere && f.to_slave < now.size()) f.to_slave = now[f.to_slave];
    }
}

void FaultInjector::apply_line_state() {
    // Cables and firmware follow the active faults, so that overlapping faults end cleanly.
    const std::size_t n = seg_.size();
    std::vector<bool> cable_down(seg_.cables(), false), halted(n, false);
    for (const auto& a : active_) {
        if (a->done) continue;
        const auto& f = a->spec;
        if (f.kind == FaultKind::LinkDown) {
            if (const std::size_t c = seg_.cable_at(f.slave, f.port); c < cable_down.size())
                cable_down[c] = true;
        } else if (f.kind == FaultKind::PowerOff) {
            // A slave without power has no link on any port.
            for (unsigned p = 0; p < 4; ++p)
                if (const std::size_t c = seg_.cable_at(f.slave, p); c < cable_down.size())
                    cable_down[c] = true;
            halted[f.slave] = true;
        } else if (f.kind == FaultKind::Unplug) {
            // Every cable between the group and the rest (into its head; in a ring, also the one out of its
            // far end) is out; the group has no power.
            const std::size_t end = seg_.group_end(f.slave);
            for (std::size_t k = f.slave; k < end; ++k) {
                halted[k] = true;
                for (unsigned p = 0; p < 4; ++p) {
                    const std::size_t c = seg_.cable_at(k, p);
                    if (c >= cable_down.size()) continue;
                    const bool inside = p != 0 ? c >= f.slave && c < end : k != f.slave;
                    if (!inside) cable_down[c] = true;
                }
            }
        } else if (f.kind == FaultKind::FirmwareHang) {
            halted[f.slave] = true;
        }
    }
    for (std::size_t k = 0; k < cable_down.size(); ++k)
        if (seg_.cable(k) == cable_down[k]) seg_.set_cable(k, !cable_down[k]);
    for (std::size_t k = 0; k < n; ++k)
        seg_.set_firmware_halted(k, halted[k]);
}

std::size_t FaultInjector::stop(std::string_view which, std::uint64_t now_ns) {
    std::size_t count = 0;
    for (auto& a : active_) {
        if (a->done) continue;
        if (which == "all" || a->spec.id == which || a->spec.name == which) {
            end(*a, now_ns, "stopped");
            ++count;
        }
    }
    std::erase_if(active_, [](const auto& a) { return a->done; });
    apply_line_state();
    return count;
}

std::vector<std::string> FaultInjector::active() const {
    std::vector<std::string> out;
    for (const auto& a : active_)
        if (!a->done) out.push_back(describe(a->spec));
    return out;
}

void FaultInjector::advance(std::uint64_t now_ns) {
    if (requests_pending_.load(std::memory_order_acquire)) drain_requests(now_ns);
    if (!origin_set_) {
        origin_set_ = true;
        origin_ns_ = now_ns;
    }
    for (std::size_t i = 0; i < scenario_.events.size(); ++i) {
        if (fired_[i]) continue;
        const TimelineEvent& e = scenario_.events[i];
        const bool due = e.by_cycle ? frames_seen_ >= e.at : now_ns - origin_ns_ >= e.at;
        if (!due) continue;
        fired_[i] = true;
        try {
            if (e.start)
                start(e.fault, now_ns);
            else
                stop(e.target, now_ns);
        } catch (const std::invalid_argument& x) {
            note("scenario line " + std::to_string(e.line) + ": " + x.what());
        }
    }
    // Faults that ran their time or their count.
    bool ended = false;
    for (auto& a : active_) {
        if (!a->done && a->until_ns != 0 && now_ns >= a->until_ns) {
            end(*a, now_ns, "duration over");
            ended = true;
        } else if (a->done) {
            end(*a, now_ns, "count reached");
            ended = true;
        }
    }
    if (ended) {
        std::erase_if(active_, [](const auto& a) { return a->done; });
        apply_line_state();
    }
}

bool FaultInjector::process_frame(Bytes frame, std::size_t& len, std::uint64_t now_ns) {
    unsigned to = 0;
    return process_frame_at(frame, len, now_ns, 0, to);
}

bool FaultInjector::process_frame_at(Bytes frame, std::size_t& len, std::uint64_t now_ns, unsigned from_port,
                                     unsigned& to_port) {
    advance(now_ns);
    if (from_port == 0) ++frames_seen_;  // at_cycle counts the master's frames, not the redundant copies
    ++counters_.frames;
    esc::FrameDamage damage;
    std::uint64_t delay = 0;
    for (auto& a : active_) {
        const auto& f = a->spec;
        if (a->done || !line_fault(f.kind)) continue;
        if (f.kind == FaultKind::Delay) {
            if (roll(f.probability) && hit(*a)) delay = std::max(delay, f.delay_ns);
        } else if (damage.kind == esc::FrameDamage::Kind::None && roll(f.probability) && hit(*a)) {
            damage.kind =
                f.kind == FaultKind::Drop ? esc::FrameDamage::Kind::Lost : esc::FrameDamage::Kind::Corrupted;
            damage.cable = f.cable;
            damage.returning = f.returning;
        }
    }
    const std::uint64_t lost_before = seg_.counters().lost;
    bool reply = seg_.process_frame(frame, len, now_ns, damage,
                                    from_port ? esc::MasterPort::Secondary : esc::MasterPort::Primary);
    to_port = seg_.reply_port() == esc::MasterPort::Secondary ? 1 : 0;
    if (seg_.counters().lost != lost_before && damage.kind != esc::FrameDamage::Kind::None) {
        if (damage.kind == esc::FrameDamage::Kind::Lost)
            ++counters_.frames_dropped;
        else
            ++counters_.frames_corrupted;
    }
    if (reply && delay != 0) {
        reply = false;
        auto slot = std::find_if(held_.begin(), held_.end(), [](const Held& h) { return !h.used; });
        if (slot == held_.end() || len > kMaxFrame) {
            ++counters_.delayed_overflow;
        } else {
            const auto k = static_cast<std::size_t>(slot - held_.begin());
            std::memcpy(&held_data_[k * kMaxFrame], frame.data(), len);
            *slot = Held{true, now_ns + delay, len};
            ++counters_.replies_delayed;
        }
    }
    return reply;
}

void FaultInjector::tick(std::uint64_t now_ns) {
    advance(now_ns);
}

std::size_t FaultInjector::take_due(std::uint64_t now_ns, Bytes out) {
    // The earliest due reply first: replies leave in the order they were held.
    Held* best = nullptr;
    for (auto& h : held_)
        if (h.used && h.due_ns <= now_ns && (!best || h.due_ns < best->due_ns)) best = &h;
    if (!best) return 0;
    best->used = false;
    const auto k = static_cast<std::size_t>(best - held_.data());
    const std::size_t n = std::min(best->len, out.size());
    std::memcpy(out.data(), &held_data_[k * kMaxFrame], n);
    return n;
}

std::uint64_t FaultInjector::next_due_ns() const {
    std::uint64_t t = ~std::uint64_t{0};
    for (const auto& h : held_)
        if (h.used) t = std::min(t, h.due_ns);
    return t;
}

std::uint64_t FaultInjector::next_event_ns() const {
    if (requests_pending_.load(std::memory_order_acquire) || !origin_set_) return 0;
    std::uint64_t t = ~std::uint64_t{0};
    for (std::size_t i = 0; i < scenario_.events.size(); ++i)
        if (!fired_[i] && !scenario_.events[i].by_cycle) t = std::min(t, origin_ns_ + scenario_.events[i].at);
    for (const auto& a : active_) {
        if (a->done) return 0;
        if (a->until_ns != 0) t = std::min(t, a->until_ns);
    }
    return t;
}

bool FaultInjector::intercept(esc::Slave& slave, const protocol::MailboxHeader& h, ConstBytes payload,
                              esc::MailboxProtocol* protocol, esc::MailboxReplySink& sink) {
    if (active_.empty()) return false;
    const std::size_t idx = slave_index(slave);
    for (auto& a : active_) {
        const auto& f = a->spec;
        if (a->done || !mailbox_fault(f.kind) || f.slave != idx) continue;
        if (f.kind == FaultKind::SdoAbort) {
            // SDO initiate requests (they name the object) of the chosen object, answered with an abort.
            if (h.type != static_cast<std::uint8_t>(protocol::MailboxType::CoE) ||
                payload.size() < protocol::kCoeHeaderSize + 4)
                continue;
            if ((ld_le16(payload.data()) >> 12) != kCoeServiceSdoRequest) continue;
            const std::uint8_t ccs = protocol::sdo::ccs(payload[2]);
            if (ccs != protocol::sdo::CcsInitiateDownload && ccs != protocol::sdo::CcsInitiateUpload)
                continue;
            const std::uint16_t index = ld_le16(payload.data() + 3);
            const std::uint8_t sub = payload[5];
            if ((f.index != 0 && f.index != index) || (f.subindex >= 0 && f.subindex != sub)) continue;
            if (!roll(f.probability) || !hit(*a)) continue;
            Bytes out = sink.reply_buffer();
            if (out.size() < protocol::kCoeHeaderSize + protocol::kSdoHeaderSize) return false;
            st_le16(out.data(), static_cast<std::uint16_t>(kCoeServiceSdoRequest << 12));
            out[2] = protocol::sdo::AbortCommand;
            st_le16(out.data() + 3, index);
            out[5] = sub;
            st_le32(out.data() + 6, f.code);
            sink.commit(protocol::MailboxType::CoE, protocol::kCoeHeaderSize + protocol::kSdoHeaderSize);
            ++counters_.sdo_aborts;
            return true;
        }
        if (f.kind == FaultKind::MailboxLostReply) {
            if (!roll(f.probability) || !hit(*a)) continue;
            LosingSink losing(sink);
            if (protocol) protocol->handle(h, payload, losing);
            counters_.mailbox_replies_lost += std::max<std::uint64_t>(losing.lost, 1);
            return true;
        }
    }
    return false;
}

std::string FaultInjector::execute(std::string_view command, std::uint64_t now_ns) {
    while (!command.empty() && (command.back() == '\n' || command.back() == '\r' || command.back() == ' '))
        command.remove_suffix(1);
    const auto sp = command.find(' ');
    const std::string_view verb = command.substr(0, sp);
    const std::string_view rest = sp == std::string_view::npos ? std::string_view{} : command.substr(sp + 1);
    try {
        if (verb == "inject") return "ok " + start(parse_fault(rest), now_ns);
        if (verb == "clear") {
            if (rest.empty()) return "error clear what? an id, a kind or all";
            return "ok " + std::to_string(stop(rest, now_ns)) + " cleared";
        }
        if (verb == "list") {
            std::string s = "ok " + std::to_string(active().size()) + " active";
            for (const auto& a : active())
                s += "\n" + a;
            return s;
        }
        if (verb == "status") return line_status(seg_);
        return "error unknown command '" + std::string(verb) + "' (inject, clear, list, status)";
    } catch (const std::invalid_argument& x) {
        return std::string("error ") + x.what();
    }
}

std::string FaultInjector::submit(const std::string& command, std::chrono::milliseconds timeout) {
    auto r = std::make_shared<Request>();
    r->command = command;
    std::unique_lock lock(mutex_);
    requests_.push_back(r);
    requests_pending_.store(true, std::memory_order_release);
    if (!cv_.wait_for(lock, timeout, [&] { return r->done; })) {
        std::erase(requests_, r);
        return "error the serving thread did not take the command (is the line running?)";
    }
    return r->result;
}

void FaultInjector::drain_requests(std::uint64_t now_ns) {
    std::lock_guard lock(mutex_);
    for (auto& r : requests_) {
        r->result = execute(r->command, now_ns);
        r->done = true;
    }
    requests_.clear();
    requests_pending_.store(false, std::memory_order_release);
    cv_.notify_all();
}

}  // namespace vecat::faults
