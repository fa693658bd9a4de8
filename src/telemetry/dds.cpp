// Cyclone DDS (C API) behind the Publisher and Subscriber of dds.hpp; the types come from
// vecat_telemetry.idl through idlc.
#include <dds/dds.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <thread>

#include "telemetry/dds.hpp"
#include "vecat_telemetry.h"

namespace vecat::telemetry {

bool dds_built_in() {
    return true;
}

namespace {

constexpr std::int32_t kEventHistory = 256;
constexpr std::int32_t kSampleHistory = 1000;  // per axis, on the reader: room while the reader sleeps

// QoS of each topic: samples best effort and volatile (a lost sample is replaced by the next one), status
// and events reliable and transient local (a late subscriber gets the last status and recent events).
dds_qos_t* make_qos(bool reliable, std::int32_t depth) {
    dds_qos_t* q = dds_create_qos();
    if (reliable) {
        dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
        dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
    } else {
        dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
        dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
    }
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
    return q;
}

struct TopicSpec {
    const dds_topic_descriptor_t* desc;
    const char* name;
    bool reliable;
    std::int32_t writer_depth;
    std::int32_t reader_depth;
};

constexpr int kTopicCount = 5;
const TopicSpec kTopics[kTopicCount] = {
    {&vecat_telemetry_AxisSample_desc, kAxisTopic, false, 1, kSampleHistory},
    {&vecat_telemetry_SlaveStatus_desc, kStatusTopic, true, 1, 1},
    {&vecat_telemetry_TwinsyncStatus_desc, kTwinsyncTopic, false, 1, kSampleHistory},
    {&vecat_telemetry_Event_desc, kEventTopic, true, kEventHistory, kEventHistory},
    {&vecat_telemetry_IoSample_desc, kIoTopic, false, 1, kSampleHistory},
};

dds_entity_t check(dds_entity_t e, const char* what) {
    if (e < 0) throw std::runtime_error(std::string("DDS: cannot create ") + what + ": " + dds_strretcode(e));
    return e;
}

// Participant with one topic per spec, and a writer or reader on each.
struct Entities {
    dds_entity_t participant = 0;
    dds_entity_t endpoints[kTopicCount] = {};
    Entities(std::uint32_t domain, bool writers) {
        participant = check(dds_create_participant(domain, nullptr, nullptr), "the participant");
        try {
            for (int i = 0; i < kTopicCount; ++i) {
                const TopicSpec& t = kTopics[i];
                dds_qos_t* tq = make_qos(t.reliable, writers ? t.writer_depth : t.reader_depth);
                const dds_entity_t topic =
                    check(dds_create_topic(participant, t.desc, t.name, tq, nullptr), t.name);
                endpoints[i] = writers ? dds_create_writer(participant, topic, tq, nullptr)
                                       : dds_create_reader(participant, topic, tq, nullptr);
                dds_delete_qos(tq);
                check(endpoints[i], writers ? "a writer" : "a reader");
            }
        } catch (...) {
            dds_delete(participant);
            throw;
        }
    }
    ~Entities() { dds_delete(participant); }
};

vecat_telemetry_AxisSample to_dds(const AxisSample& a) {
    return {a.slave,           a.axis,
            a.time_ns,         a.cycle,
            a.cia402_state,    a.mode,
            a.controlword,     a.statusword,
            a.error_code,      a.position_demand,
            a.position_actual, a.velocity_actual,
            a.torque_actual,   a.following_error};
}
AxisSample from_dds(const vecat_telemetry_AxisSample& d) {
    AxisSample a;
    a.slave = d.slave;
    a.axis = d.axis;
    a.time_ns = d.time_ns;
    a.cycle = d.cycle;
    a.cia402_state = d.cia402_state;
    a.mode = d.mode;
    a.controlword = d.controlword;
    a.statusword = d.statusword;
    a.error_code = d.error_code;
    a.position_demand = d.position_demand;
    a.position_actual = d.position_actual;
    a.velocity_actual = d.velocity_actual;
    a.torque_actual = d.torque_actual;
    a.following_error = d.following_error;
    return a;
}
vecat_telemetry_SlaveStatus to_dds(const SlaveStatus& s) {
    return {s.slave,
            s.time_ns,
            s.al_status,
            s.al_status_code,
            s.dc_time_difference_ns,
            s.watchdog_pd_expiries,
            s.watchdog_pdi_expiries,
            s.rx_errors,
            s.lost_links,
            s.frames,
            s.mailbox_errors,
            s.emergencies};
}
SlaveStatus from_dds(const vecat_telemetry_SlaveStatus& d) {
    SlaveStatus s;
    s.slave = d.slave;
    s.time_ns = d.time_ns;
    s.al_status = d.al_status;
    s.al_status_code = d.al_status_code;
    s.dc_time_difference_ns = d.dc_time_difference_ns;
    s.watchdog_pd_expiries = d.watchdog_pd_expiries;
    s.watchdog_pdi_expiries = d.watchdog_pdi_expiries;
    s.rx_errors = d.rx_errors;
    s.lost_links = d.lost_links;
    s.frames = d.frames;
    s.mailbox_errors = d.mailbox_errors;
    s.emergencies = d.emergencies;
    return s;
}
vecat_telemetry_TwinsyncStatus to_dds(const TwinsyncSample& t) {
    return {t.slave,         t.axis,           t.time_ns,        t.mode,
            t.tx_statusword, t.rx_statusword,  t.comm_status,    t.synchronised,
            t.link_ok,       t.error_number,   t.frames_sent,    t.frames_received,
            t.crc_errors,    t.frames_missing, t.sync_offset_ns, t.tracking_error};
}
TwinsyncSample from_dds(const vecat_telemetry_TwinsyncStatus& d) {
    TwinsyncSample t;
    t.slave = d.slave;
    t.axis = d.axis;
    t.time_ns = d.time_ns;
    t.mode = d.mode;
    t.tx_statusword = d.tx_statusword;
    t.rx_statusword = d.rx_statusword;
    t.comm_status = d.comm_status;
    t.synchronised = d.synchronised;
    t.link_ok = d.link_ok;
    t.error_number = d.error_number;
    t.frames_sent = d.frames_sent;
    t.frames_received = d.frames_received;
    t.crc_errors = d.crc_errors;
    t.frames_missing = d.frames_missing;
    t.sync_offset_ns = d.sync_offset_ns;
    t.tracking_error = d.tracking_error;
    return t;
}
vecat_telemetry_Event to_dds(const Event& e) {
    return {e.time_ns, e.slave, e.axis, static_cast<std::uint8_t>(e.kind), e.code, e.old_value, e.new_value};
}
Event from_dds(const vecat_telemetry_Event& d) {
    Event e;
    e.time_ns = d.time_ns;
    e.slave = d.slave;
    e.axis = d.axis;
    e.kind = static_cast<EventKind>(d.kind);
    e.code = d.code;
    e.old_value = d.old_value;
    e.new_value = d.new_value;
    return e;
}

vecat_telemetry_IoSample to_dds(const IoSample& s) {
    static_assert(sizeof(vecat_telemetry_IoSample::inputs) / sizeof(std::int16_t) == kIoChannels);
    vecat_telemetry_IoSample d{};
    d.slave = s.slave;
    d.time_ns = s.time_ns;
    d.cycle = s.cycle;
    d.analog = s.analog;
    d.in_channels = s.in_channels;
    d.out_channels = s.out_channels;
    std::copy(s.in.begin(), s.in.end(), d.inputs);
    std::copy(s.out.begin(), s.out.end(), d.outputs);
    return d;
}
IoSample from_dds(const vecat_telemetry_IoSample& d) {
    IoSample s;
    s.slave = d.slave;
    s.time_ns = d.time_ns;
    s.cycle = d.cycle;
    s.analog = d.analog;
    s.in_channels = std::min<std::uint8_t>(d.in_channels, kIoChannels);
    s.out_channels = std::min<std::uint8_t>(d.out_channels, kIoChannels);
    std::copy(d.inputs, d.inputs + kIoChannels, s.in.begin());
    std::copy(d.outputs, d.outputs + kIoChannels, s.out.begin());
    return s;
}

}  // namespace

// ---- Publisher

struct Publisher::Impl {
    TelemetryQueue& q;
    Entities dds;
    std::thread thread;
    std::atomic<bool> running{false};
    std::atomic<std::uint64_t> written{0}, errors{0};

    Impl(TelemetryQueue& queue, std::uint32_t domain) : q(queue), dds(domain, true) {}

    void write(const Record& r) {
        dds_return_t rc = 0;
        if (const auto* a = std::get_if<AxisSample>(&r)) {
            const auto d = to_dds(*a);
            rc = dds_write(dds.endpoints[0], &d);
        } else if (const auto* s = std::get_if<SlaveStatus>(&r)) {
            const auto d = to_dds(*s);
            rc = dds_write(dds.endpoints[1], &d);
        } else if (const auto* t = std::get_if<TwinsyncSample>(&r)) {
            const auto d = to_dds(*t);
            rc = dds_write(dds.endpoints[2], &d);
        } else if (const auto* e = std::get_if<Event>(&r)) {
            const auto d = to_dds(*e);
            rc = dds_write(dds.endpoints[3], &d);
        } else if (const auto* io = std::get_if<IoSample>(&r)) {
            const auto d = to_dds(*io);
            rc = dds_write(dds.endpoints[4], &d);
        }
        (rc == DDS_RETCODE_OK ? written : errors).fetch_add(1, std::memory_order_relaxed);
    }
    void drain() {
        Record r;
        while (q.pop(r))
            write(r);
    }
    void run() {
        // Polls the queue every millisecond: the cyclic thread never signals (that would be a system call
        // on its path).
        while (running.load(std::memory_order_relaxed)) {
            drain();
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        drain();
    }
};

Publisher::Publisher(TelemetryQueue& q, std::uint32_t domain) : impl_(std::make_unique<Impl>(q, domain)) {}
Publisher::~Publisher() {
    stop();
}
void Publisher::start() {
    if (impl_->running.exchange(true)) return;
    impl_->thread = std::thread([this] { impl_->run(); });
}
void Publisher::stop() {
    impl_->running = false;
    if (impl_->thread.joinable()) impl_->thread.join();
}
PublisherStats Publisher::stats() const {
    return {impl_->written.load(), impl_->errors.load()};
}

// ---- Subscriber

struct Subscriber::Impl {
    Entities dds;
    dds_entity_t waitset;
    explicit Impl(std::uint32_t domain) : dds(domain, false) {
        waitset = check(dds_create_waitset(dds.participant), "a waitset");
        for (dds_entity_t rd : dds.endpoints) {
            dds_set_status_mask(rd, DDS_DATA_AVAILABLE_STATUS);
            dds_waitset_attach(waitset, rd, rd);
        }
    }
    template <class D, class F>
    void take(dds_entity_t rd, F&& add) {
        constexpr std::size_t kBatch = 64;
        D buf[kBatch];
        void* ptrs[kBatch];
        dds_sample_info_t info[kBatch];
        for (std::size_t i = 0; i < kBatch; ++i)
            ptrs[i] = &buf[i];
        for (;;) {
            const dds_return_t n = dds_take(rd, ptrs, info, kBatch, kBatch);
            if (n <= 0) return;
            for (dds_return_t i = 0; i < n; ++i)
                if (info[i].valid_data) add(from_dds(buf[i]));
            if (static_cast<std::size_t>(n) < kBatch) return;
        }
    }
};

Subscriber::Subscriber(std::uint32_t domain) : impl_(std::make_unique<Impl>(domain)) {}
Subscriber::~Subscriber() = default;

void Subscriber::record(Recording& r, double duration_s, const std::atomic<bool>& stop) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(duration_s);
    while (!stop.load()) {
        if (duration_s > 0 && std::chrono::steady_clock::now() >= end) break;
        dds_attach_t triggered[kTopicCount];
        dds_waitset_wait(impl_->waitset, triggered, kTopicCount, DDS_MSECS(20));
        impl_->take<vecat_telemetry_AxisSample>(impl_->dds.endpoints[0],
                                                [&](AxisSample a) { r.axes.push_back(a); });
        impl_->take<vecat_telemetry_SlaveStatus>(impl_->dds.endpoints[1],
                                                 [&](SlaveStatus s) { r.status.push_back(s); });
        impl_->take<vecat_telemetry_TwinsyncStatus>(impl_->dds.endpoints[2],
                                                    [&](TwinsyncSample t) { r.twinsync.push_back(t); });
        impl_->take<vecat_telemetry_Event>(impl_->dds.endpoints[3], [&](Event e) { r.events.push_back(e); });
        impl_->take<vecat_telemetry_IoSample>(impl_->dds.endpoints[4],
                                              [&](IoSample s) { r.io.push_back(s); });
    }
}

}  // namespace vecat::telemetry
