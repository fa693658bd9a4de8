#include "testing/virtual_segment.hpp"

#include <unistd.h>

#include <stdexcept>

#include "common/bytes.hpp"
#include "net/netns.hpp"
#include "net/raw_socket.hpp"
#include "serve/server.hpp"

namespace vecat::testing {
namespace {

std::unique_ptr<esc::Segment> make_segment(const SegmentOptions& o) {
    if (o.drives == 0) throw std::invalid_argument("vecat::testing: a segment needs at least one drive");
    if (o.twinsync != cia402::TwinsyncPreset::None) {
        if (o.drives < 2) throw std::invalid_argument("vecat::testing: TWINsync needs two drives");
        return cia402::make_drive_segment(o.device, o.drives, o.esc, o.twinsync);
    }
    return cia402::make_drive_segment(o.device, o.drives, o.esc);
}

master::MasterOptions master_options(const SegmentOptions& o) {
    master::MasterOptions m;
    m.reply_timeout_us = o.master_reply_timeout_us;
    return m;
}

}  // namespace

// ---- VirtualSegment

VirtualSegment::VirtualSegment(SegmentOptions opt)
    : opt_(std::move(opt)),
      seg_(make_segment(opt_)),
      link_(*seg_),
      injector_(*seg_, opt_.fault_seed),
      twinsync_faults_(*seg_),
      master_(link_, master_options(opt_)) {
    faults::register_twinsync_faults(injector_, twinsync_faults_);
    link_.set_time(now_);
    link_.set_filter(&injector_);
    if (opt_.target != protocol::AlState::Init) {
        std::string why;
        if (!master_.startup(opt_.target, &why))
            throw std::runtime_error("vecat::testing: master start-up failed: " + why);
    }
}

VirtualSegment::~VirtualSegment() {
    link_.set_filter(nullptr);
}

cia402::Drive& VirtualSegment::drive(std::size_t i) {
    return dynamic_cast<cia402::Drive&>(seg_->slave(i).app());
}

void VirtualSegment::advance(std::uint64_t ns) {
    now_ += ns;
    link_.set_time(now_);
    seg_->tick(now_);
    injector_.tick(now_);
}

bool VirtualSegment::cycle() {
    const auto wkc = master_.exchange_process_data();
    last_wkc_ = wkc.value_or(0);
    if (sampler_) {
        sampler_->on_frame(now_);
        drain();
    }
    advance(opt_.cycle_ns);
    return wkc && *wkc == master_.expected_wkc();
}

bool VirtualSegment::cycles(unsigned n) {
    bool ok = true;
    for (unsigned k = 0; k < n; ++k)
        ok = cycle() && ok;
    return ok;
}

void VirtualSegment::set_controlword(std::size_t i, std::uint16_t cw) {
    st_le16(master_.outputs(i).data() + csp::kControlword, cw);
}
void VirtualSegment::set_mode(std::size_t i, std::int8_t mode) {
    master_.outputs(i)[csp::kMode] = static_cast<std::uint8_t>(mode);
}
void VirtualSegment::set_target_position(std::size_t i, std::int32_t p) {
    st_le32(master_.outputs(i).data() + csp::kTargetPosition, static_cast<std::uint32_t>(p));
}
std::uint16_t VirtualSegment::statusword(std::size_t i) const {
    return ld_le16(master_.inputs(i).data() + csp::kStatusword);
}
std::int32_t VirtualSegment::position(std::size_t i) const {
    return static_cast<std::int32_t>(ld_le32(master_.inputs(i).data() + csp::kPositionActual));
}
std::int32_t VirtualSegment::velocity(std::size_t i) const {
    return static_cast<std::int32_t>(ld_le32(master_.inputs(i).data() + csp::kVelocityActual));
}

bool VirtualSegment::enable(std::size_t i, unsigned max_cycles) {
    set_mode(i, 8);
    for (std::uint16_t cw : {std::uint16_t{0x06}, std::uint16_t{0x07}, std::uint16_t{0x0F}}) {
        set_controlword(i, cw);
        for (unsigned k = 0; k < 5; ++k) {
            set_target_position(i, position(i));  // hold where the axis stands
            cycle();
        }
    }
    for (unsigned k = 0; k < max_cycles; ++k) {
        if (drive(i).cia402_state() == cia402::State::OperationEnabled) return true;
        set_target_position(i, position(i));
        cycle();
    }
    return drive(i).cia402_state() == cia402::State::OperationEnabled;
}

std::string VirtualSegment::fault(std::string_view command) {
    return injector_.execute(command, now_);
}

void VirtualSegment::start_recording(telemetry::SamplerOptions o) {
    sampler_.reset();
    queue_ = std::make_unique<telemetry::TelemetryQueue>();
    sampler_ = std::make_unique<telemetry::Sampler>(*seg_, *queue_, o);
    rec_ = {};
}

telemetry::Recording VirtualSegment::stop_recording() {
    if (sampler_) drain();
    sampler_.reset();
    queue_.reset();
    return std::move(rec_);
}

void VirtualSegment::drain() {
    telemetry::Record r;
    while (queue_->pop(r))
        rec_.add(r);
}

// ---- VethSegment

bool veth_available() {
    return geteuid() == 0;
}

VethSegment::VethSegment(VethOptions opt) : opt_(std::move(opt)) {
    std::string why;
    if (opt_.enter_netns && !net::enter_private_netns(&why))
        throw std::runtime_error("vecat::testing: no private network namespace: " + why);
    if (!net::create_veth_pair(opt_.master_interface, opt_.slave_interface, &why))
        throw std::runtime_error("vecat::testing: no veth pair: " + why);
    seg_ = make_segment(opt_.segment);
    injector_ = std::make_unique<faults::FaultInjector>(*seg_, opt_.segment.fault_seed);
    twinsync_faults_ = std::make_unique<faults::TwinsyncFaults>(*seg_);
    faults::register_twinsync_faults(*injector_, *twinsync_faults_);
    // The socket is opened here so that a bad interface fails in the constructor, not in the thread.
    auto sock = std::make_shared<net::RawSocket>(opt_.slave_interface);
    sock->set_busy_poll(opt_.busy_poll);
    thread_ = std::thread([this, sock] {
        net::ServeOptions so;
        so.busy_poll = opt_.busy_poll;
        so.filter = injector_.get();
        so.after_frame = [](void* self, std::uint64_t) {
            static_cast<VethSegment*>(self)->received_.fetch_add(1, std::memory_order_relaxed);
        };
        so.after_frame_context = this;
        net::serve(*seg_, *sock, so, stop_);
    });
}

VethSegment::~VethSegment() {
    stop();
}

void VethSegment::stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
}

std::string VethSegment::fault(const std::string& command) {
    return injector_->submit(command, std::chrono::milliseconds(1000));
}

}  // namespace vecat::testing
