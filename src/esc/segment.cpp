#include "esc/segment.hpp"

#include <algorithm>
#include <cstring>

#include "esc/datagram.hpp"

namespace vecat::esc {

void Segment::add(std::unique_ptr<Slave> s) {
    slaves_.push_back(std::move(s));
    last_run_ns_.push_back(0);
    // Port 1 of every slave but the last one has a link to its successor.
    for (std::size_t i = 0; i < slaves_.size(); ++i)
        slaves_[i]->esc().set_port_link(1, i + 1 < slaves_.size());
}

bool Segment::process_frame(Bytes frame, std::size_t& len, std::uint64_t now_ns) {
    if (len > frame.size()) len = frame.size();
    ConstBytes in(frame.data(), len);
    const ParsedFrame pf = parse_frame(in);
    if (pf.error == FrameError::NotEtherCat || (pf.error == FrameError::TooShort && len < kEthHeaderSize)) {
        ++counters_.ignored;
        return false;
    }
    ++counters_.frames;
    if (pf.error == FrameError::NotCommands) {
        // Other EtherCAT frame types pass the ESCs unprocessed.
    } else if (pf.error != FrameError::None) {
        ++counters_.dropped;
        if (!slaves_.empty()) slaves_.front()->esc().count_invalid_frame(0);
        return false;
    } else {
        const std::size_t n = slaves_.size();
        // SYNC pulses that fell due before this frame arrived happen first (the server may be late).
        for (std::size_t k = 0; k < n; ++k)
            if (slaves_[k]->esc().dc().next_pulse_host_ns() <= now_ns) run(k, now_ns);
        for (std::size_t k = 0; k < n; ++k) {
            FrameTiming t;
            t.port0_ns = now_ns + k * hop_delay_ns;
            // Back at port 1 after the slaves behind it (same delay per hop both ways; the last slave loops
            // the frame back through its closed port 1 without delay), so masters compute exact delays.
            t.port1_ns = now_ns + (2 * (n - 1) - k) * hop_delay_ns;
            Esc& esc = slaves_[k]->esc();
            bool addressed = false;
            for (std::size_t i = 0; i < pf.count; ++i)
                addressed |= esc.process(pf.datagram(frame, i), t);
            // Marks the slave for its firmware run below (0: run now).
            if (addressed) last_run_ns_[k] = 0;
        }
        for (std::size_t k = 0; k < n; ++k)
            if (last_run_ns_[k] == 0 || now_ns - last_run_ns_[k] >= kMaxRunGapNs || now_ns < last_run_ns_[k])
                run(k, now_ns);
    }
    frame[6] |= 0x02;  // the ESC marks the frame as processed in the source address
    if (len < kMinEthFrame && frame.size() >= kMinEthFrame) {
        std::memset(frame.data() + len, 0, kMinEthFrame - len);
        len = kMinEthFrame;
    }
    ++counters_.replies;
    return true;
}

void Segment::run(std::size_t k, std::uint64_t now_ns) {
    slaves_[k]->run(now_ns);
    last_run_ns_[k] = now_ns == 0 ? 1 : now_ns;
}

void Segment::tick(std::uint64_t now_ns) {
    for (std::size_t k = 0; k < slaves_.size(); ++k)
        run(k, now_ns);
}

std::uint64_t Segment::next_event_ns() const {
    std::uint64_t t = DistributedClock::kNever;
    for (const auto& s : slaves_)
        t = std::min(t, s->esc().dc().next_pulse_host_ns());
    return t;
}

std::unique_ptr<Segment> make_segment(const device::DeviceDescription& d, std::size_t n, const EscConfig& cfg,
                                      const ApplicationFactory& factory) {
    auto seg = std::make_unique<Segment>();
    for (std::size_t i = 0; i < n; ++i) {
        std::unique_ptr<Application> app;
        if (factory)
            app = factory(d);
        else
            app = std::make_unique<ProcessImageApplication>(d.output_bytes(), d.input_bytes());
        seg->add(std::make_unique<Slave>(d, cfg, std::move(app)));
    }
    return seg;
}

}  // namespace vecat::esc
