// The phases of `vecat demo` on the project's master: on its own line of drives (scan, PREOP with homing
// set-up, PDO mapping by SDO, DC, SAFEOP, OP, enable, CSP move, homing, an injected fault, disable, INIT),
// and on a network file (the mapping the devices have, the drives found in it, the I/O terminals exercised).
#include "cli/demo_session.hpp"

namespace vecat::cli::demo_detail {

bool Demo::scan() {
    const int n = master_.count_slaves();
    if (n <= 0) return fail("no slave answered the BRD");
    if (!master_.reset_slaves() || !master_.assign_station_addresses() || !master_.read_slave_information())
        return fail("station addresses or SII could not be read");
    for (const auto& s : master_.slaves()) {
        note(
            "       slave {} @0x{:04X} \"{}\": vendor 0x{:08X} product 0x{:08X} revision 0x{:08X}, {} FMMUs, "
            "{} SMs, DC {}",
            s.position, s.station, s.sii.device_name(), s.sii.identity.vendor_id, s.sii.identity.product_code,
            s.sii.identity.revision, s.fmmu_count, s.sm_count,
            (s.features & protocol::feature::DcAvailable) ? "yes" : "no");
        // A tree: the parent each slave hangs on (from the DL status of every slave, as SOEM computes it).
        if (on_network_)
            note("         {}", s.parent < 0 ? std::string("on the master")
                                             : fmt::format("on slave {} port {}", s.parent, s.parent_port));
    }
    if (!on_network_) {
        axes_.clear();
        for (std::size_t i = 0; i < master_.slaves().size(); ++i)
            axes_.push_back(Axis{fixed_layout(i)});
    }
    return true;
}

bool Demo::preop() {
    if (!master_.configure_mailboxes()) return fail("mailbox SyncManagers could not be written");
    if (!master_.request_state(AlState::PreOp)) return fail("the slaves refused PREOP");
    set_al(AlState::PreOp);
    if (on_network_) return true;
    // Drive 1's machine has its home switch at kHomeSwitch; the homing phase searches it.
    if (!sdo(0, mfr::machine::home_switch.index, mfr::machine::home_switch.subindex,
             static_cast<std::uint32_t>(kHomeSwitch), 4) ||
        !sdo(0, obj::homing_method.index, 0, static_cast<std::uint8_t>(kHomingMethod), 1) ||
        !sdo(0, obj::homing_speeds::index, obj::homing_speeds::search_for_switch.subindex,
             static_cast<std::uint32_t>(kRev / 2), 4) ||  // search the switch at 0.5 rev/s
        !sdo(0, obj::homing_speeds::index, obj::homing_speeds::search_for_zero.subindex,
             static_cast<std::uint32_t>(kRev / 16), 4) ||  // the edge at 1/16 rev/s
        !sdo(0, obj::homing_acceleration.index, 0, static_cast<std::uint32_t>(4 * kRev), 4) ||
        !sdo(0, obj::home_offset.index, 0, static_cast<std::uint32_t>(kHomeSwitch), 4))
        return false;
    note(
        "       drive 1: home switch 0x{:04X}:{:02X} = {}, method 0x{:04X} = {}, speeds 0x{:04X} = {} / {}, "
        "home offset 0x{:04X} = {}",
        mfr::machine::home_switch.index, mfr::machine::home_switch.subindex, kHomeSwitch,
        obj::homing_method.index, kHomingMethod, obj::homing_speeds::index, kRev / 2, kRev / 16,
        obj::home_offset.index, kHomeSwitch);
    return true;
}

bool Demo::map_pdos() {
    auto map = [&](std::size_t s, std::uint16_t assign, std::uint16_t pdo,
                   std::span<const PdoEntry> entries) {
        if (!sdo(s, assign, 0, 0, 1) || !sdo(s, pdo, 0, 0, 1)) return false;
        std::uint8_t sub = 0;
        for (const auto& e : entries)
            if (!sdo(s, pdo, ++sub, static_cast<std::uint32_t>(e.index) << 16 | e.bits, 4)) return false;
        return sdo(s, pdo, 0, sub, 1) && sdo(s, assign, 1, pdo, 2) && sdo(s, assign, 0, 1, 1);
    };
    for (std::size_t s = 0; s < master_.slaves().size(); ++s)
        if (!map(s, 0x1C12, 0x1600, kRxPdo) || !map(s, 0x1C13, 0x1A00, kTxPdo)) return false;
    auto describe = [](std::span<const PdoEntry> entries) {
        std::string d;
        for (const auto& e : entries)
            d += e.index ? fmt::format("{}0x{:04X} {}", d.empty() ? "" : ", ", e.index, e.name)
                         : fmt::format("{}{}-bit gap", d.empty() ? "" : ", ", e.bits);
        return d;
    };
    note("       RxPDO 0x1600: {}", describe(kRxPdo));
    note("       TxPDO 0x1A00: {}", describe(kTxPdo));
    // The master reads the sizes back from 0x1C12/0x1C13 and sets SM2/SM3 and the FMMUs.
    if (!master_.configure_process_data()) return fail("SM2/SM3 and FMMUs could not be configured");
    for (const auto& s : master_.slaves())
        if (s.out_bytes != rx::kSize || s.in_bytes != tx::kSize)
            return fail(fmt::format("slave {} reads back {} / {} bytes instead of {} / {}", s.position,
                                    s.out_bytes, s.in_bytes, rx::kSize, tx::kSize));
    note("       process image: {} bytes in {} LRW frame(s), expected working counter {}",
         master_.process_image_size(), master_.process_data_frames(), master_.expected_wkc());
    return true;
}

bool Demo::process_data() {
    // The master reads each CoE device's PDO assignment and mapping (0x1C12/0x1C13, 0x16xx/0x1Axx) and the
    // others' from their SII, and sets SM2/SM3 and the FMMUs.
    if (!master_.configure_process_data()) return fail("SM2/SM3 and FMMUs could not be configured");
    std::vector<std::string> lines;
    axes_ = find_drives(master_, lines);
    io_ = IoExercise(master_, axes_);
    for (const auto& l : lines)
        note("       {}", l);
    note("       {} drive(s) to move, {} I/O device(s) with process data", axes_.size(), io_.size());
    note("       process image: {} bytes in {} LRW frame(s), expected working counter {}",
         master_.process_image_size(), master_.process_data_frames(), master_.expected_wkc());
    return true;
}

bool Demo::io() {
    if (io_.empty()) {
        note("       no I/O device with process data");
        return true;
    }
    io_running_ = true;
    const std::uint64_t before = io_.input_changes();
    cycle_until([] { return false; }, std::max(opt_.cycles / 3, 800u));
    io_running_ = false;
    if (interrupted()) return fail("interrupted");
    for (const auto& l : io_.report(master_))
        note("       {}", l);
    note("       inputs changed {} times in the phase", io_.input_changes() - before);
    return true;
}

bool Demo::dc() {
    // Sync mode DC SYNC0. The sync error limit 0x10F1:02 goes from 4 to kSyncErrorLimit (no limit): this
    // master runs on an ordinary (not real-time) host, where a wake-up a millisecond late now and then, or a
    // stall of several milliseconds under load (a limit of 100 was exceeded in CI), would otherwise stop the
    // line with 0x002C. The init phase reports what was missed (0x1C32:0B).
    // On a network only the drives get SYNC0; a device that refuses these objects keeps its own settings.
    for (const auto& a : axes_) {
        const std::size_t s = a.layout.slave;
        if (!sdo(s, 0x1C32, 1, 2, 2) || !sdo(s, 0x10F1, 2, kSyncErrorLimit, 2)) {
            if (!on_network_) return false;
            note("       slave {}: {}; its sync mode stays as it is", s, why_);
        }
    }
    if (!master_.configure_dc() || master_.dc_reference() == 0)
        return fail("propagation delays / system time offsets could not be set");
    for (const auto& s : master_.slaves())
        note("       slave {}: propagation delay {} ns{}", s.position, s.dc_delay_ns,
             s.station == master_.dc_reference() ? " (reference clock)" : "");
    for (unsigned sent = 0; sent < kDriftFrames; sent += 500) {
        if (interrupted()) return fail("interrupted");
        if (!master_.compensate_static_drift(500)) return fail("drift compensation frames got no reply");
    }
    const auto deadline = Clock::now() + milliseconds(5000);
    std::optional<std::uint32_t> diff;
    while (!interrupted()) {
        master_.distribute_reference_clock();
        diff = master_.max_system_time_difference();
        if (diff && *diff <= 10'000) break;
        if (Clock::now() > deadline) return fail("the system time difference stays above 10 us");
    }
    if (!diff) return fail("interrupted");
    dc_difference_ns_ = *diff;
    for (const auto& a : axes_) {
        const auto& s = master_.slaves()[a.layout.slave];
        if ((s.features & protocol::feature::DcAvailable) && !master_.start_sync(s.station, kCycleNs, 0))
            return fail(fmt::format("slave {}: SYNC0 could not be started", s.position));
    }
    note(
        "       {} FRMW frames; largest system time difference 0x092C: {} ns; SYNC0 every {} us from 100 ms "
        "on",
        kDriftFrames, *diff, kCycleNs / 1000);
    dc_running_ = true;
    return true;
}

bool Demo::safeop() {
    if (!master_.request_state(AlState::SafeOp)) {
        const auto& st = master_.last_states();
        std::string codes;
        for (std::size_t i = 0; i < st.size(); ++i)
            codes += fmt::format(" slave {}: 0x{:02X} code 0x{:04X}", i, st[i].status, st[i].code);
        return fail("the slaves refused SAFEOP:" + codes);
    }
    set_al(AlState::SafeOp);
    // Lock the loop on SYNC0 before OP: 200 cycles.
    next_ = Clock::now();
    cycle_until([] { return false; }, 200);
    note("       master loop locked: frames at {} us after SYNC0, phase error rms {:.1f} us, max {:.1f} us",
         kSendPhaseNs / 1000, stats_.phase_rms_us(), stats_.phase_max_us);
    return !interrupted() || fail("interrupted");
}

bool Demo::op() {
    for (auto& a : axes_) {
        a.target = a.position;
        a.mode = kCsp;
    }
    cycle();
    if (!master_.request_state(AlState::Op)) return fail("the slaves refused OP");
    set_al(AlState::Op);
    stats_ = {};  // statistics of the cyclic phases in OP
    return true;
}

bool Demo::enable_drives() {
    for (auto& a : axes_) {
        a.target = a.position;
        a.mode = kCsp;
    }
    auto all = [&](DriveState s) {
        return [this, s] {
            return std::all_of(axes_.begin(), axes_.end(), [s](const Axis& a) { return a.state() == s; });
        };
    };
    const std::pair<std::uint16_t, DriveState> steps[] = {{kShutdown, DriveState::ReadyToSwitchOn},
                                                          {kSwitchOn, DriveState::SwitchedOn},
                                                          {kEnable, DriveState::OperationEnabled}};
    for (const auto& [cw, state] : steps) {
        for (std::size_t i = 0; i < axes_.size(); ++i)
            axes_[i].controlword = cw;
        if (!cycle_until(all(state), 500))
            return fail(
                fmt::format("drives did not reach \"{}\" (controlword 0x{:02X})", short_name(state), cw));
    }
    for (auto& a : axes_)
        a.target = a.position;
    return true;
}

bool Demo::enable() {
    if (axes_.empty()) {
        note("       no drive to enable");
        return true;
    }
    if (!enable_drives()) return false;
    note("       all drives enabled{}", gantry_ ? " (drive 2 by drive 1's controlword over TWINsync)" : "");
    return true;
}

// A jerk-limited move of drive 1 to target; drives 3.. (not coupled) make the same move from where they are.
bool Demo::move_to(std::int32_t target, double limit_rev_s) {
    const cia402::ProfileLimits limits{limit_rev_s * kRev, 10 * kRev, 10 * kRev, 100 * kRev};
    const double from = axes_[0].position;
    cia402::ProfileGenerator gen;
    gen.reset({from, 0, 0});
    gen.move_to(target, limits);
    std::vector<std::int32_t> start(axes_.size());
    for (std::size_t i = 0; i < axes_.size(); ++i)
        start[i] = axes_[i].position;
    for (unsigned c = 0; c < 20000 && !gen.done() && !interrupted(); ++c) {
        const double p = gen.step(1e-3).p;
        for (std::size_t i = 0; i < axes_.size(); ++i)
            if (!follows_twinsync(i))
                axes_[i].target = start[i] + static_cast<std::int32_t>(std::lround(p - from));
        cycle();
        if (axes_[0].state() != DriveState::OperationEnabled) return fail(left_enabled());
    }
    // Settle: drive 1 within 1/1000 revolution of the target.
    cycle_until([&] { return std::abs(axes_[0].position - target) < kRev / 1000; }, 500);
    return !interrupted() || fail("interrupted");
}

bool Demo::csp_move() {
    if (axes_.empty()) {
        note("       no drive to move");
        return true;
    }
    constexpr double kOut = kRev;
    const cia402::ProfileLimits limits{kRev, 10 * kRev, 10 * kRev, 100 * kRev};
    std::vector<cia402::ProfileGenerator> gen(axes_.size());
    std::vector<double> start(axes_.size());
    for (std::size_t i = 0; i < axes_.size(); ++i) {
        start[i] = axes_[i].position;
        gen[i].reset({start[i], 0, 0});
        gen[i].move_to(start[i] + (i % 2 ? -kOut : kOut), limits);
    }
    double worst_ferr = 0;
    tracking_ = true;
    const auto t0 = Clock::now();
    unsigned c = 0;
    for (; !interrupted(); ++c) {
        if (c == opt_.cycles / 2)
            for (std::size_t i = 0; i < axes_.size(); ++i)
                gen[i].move_to(start[i], limits);
        bool done = c >= opt_.cycles / 2;
        for (std::size_t i = 0; i < axes_.size(); ++i) {
            // Drive 2 of the gantry takes its set-points over TWINsync; the master commands the others.
            if (follows_twinsync(i)) continue;
            axes_[i].target = static_cast<std::int32_t>(std::lround(gen[i].step(1e-3).p));
            done = done && gen[i].done();
        }
        cycle();
        worst_ferr = std::max(worst_ferr, std::abs(static_cast<double>(axes_[0].following_error)));
        if (axes_[0].state() != DriveState::OperationEnabled) return fail(left_enabled());
        if (done && c >= opt_.cycles) break;
        if (c > opt_.cycles + 20000) return fail("the move did not end");
    }
    tracking_ = false;
    if (interrupted()) return fail("interrupted");
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    note(
        "       {} cycles in {:.0f} ms; drive 1 back at {} (started at {:.0f}); largest following error "
        "{:.0f} "
        "increments",
        c + 1, ms, axes_[0].position, start[0], worst_ferr);
    if (gantry_)
        note(
            "       gantry: largest difference drive 1 - drive 2 read over EtherCAT: {:.0f} increments "
            "({:.3f} % of "
            "a revolution)",
            worst_gantry_, worst_gantry_ / kRev * 100.0);
    return true;
}

bool Demo::homing() {
    auto& d1 = axes_[0];
    const std::int32_t before = d1.position;
    d1.target = d1.position;
    d1.mode = kHoming;
    d1.controlword = kEnable;
    if (!cycle_until([&] { return d1.mode_display == kHoming; }, 100))
        return fail("drive 1 did not enter HM");
    d1.controlword = kEnable | kHomingStart;
    tracking_ = true;
    const auto t0 = Clock::now();
    const bool ended = cycle_until(
        [&] {
            return (d1.statusword & (kSwHomingError | kSwFault)) ||
                   ((d1.statusword & kSwHomingAttained) && (d1.statusword & kSwTargetReached));
        },
        15000);
    tracking_ = false;
    if (!ended) return fail(interrupted() ? "interrupted" : "homing did not end within 15 s");
    if (d1.statusword & kSwFault) return fail(left_enabled());
    if (d1.statusword & kSwHomingError)
        return fail(fmt::format("homing error, statusword 0x{:04X}", d1.statusword));
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    // Back to CSP, holding the position.
    d1.controlword = kEnable;
    d1.target = d1.position;
    d1.mode = kCsp;
    if (!cycle_until([&] { return d1.mode_display == kCsp; }, 100))
        return fail("drive 1 did not return to CSP");
    note(
        "       homing attained (statusword 0x{:04X}) after {:.0f} ms: the switch edge now reads {} "
        "(0x{:04X}); drive 1 "
        "stopped at {}, {} beyond it (it started at {})",
        d1.statusword, ms, kHomeSwitch, obj::home_offset.index, d1.position, kHomeSwitch - d1.position,
        before);
    if (gantry_)
        note(
            "       drive 2 followed the search over TWINsync and is at {} (difference {}); the home offset "
            "keeps "
            "the gantry's coordinates, drive 2 does not home itself",
            axes_[1].position, d1.position - axes_[1].position);
    return true;
}

bool Demo::fault() {
    auto& d1 = axes_[0];
    const auto injected =
        injector_.submit("inject following_error slave=0 id=demo-fault", milliseconds(1000));
    if (injected.rfind("ok", 0) != 0) return fail("fault injection: " + injected);
    note("       injector: {} (drive 1's simulated fault 0x2101 = 0x8611)", injected);
    unsigned seen_after = 0;
    if (!cycle_until([&] { return ++seen_after, (d1.statusword & kSwFault) != 0; }, 500))
        return fail("drive 1 did not report the fault");
    // A reset is only taken once the fault reaction is over: wait for it (drive 2's monitoring reacts to
    // its partner's fault over TWINsync a few cycles later).
    cycle_until([] { return false; }, 20);
    cycle_until(
        [&] {
            return std::none_of(axes_.begin(), axes_.end(),
                                [](const Axis& a) { return a.state() == DriveState::FaultReactionActive; });
        },
        2000);
    for (std::size_t i = 0; i < axes_.size() && i < 2; ++i)
        note("       drive {}: statusword 0x{:04X} ({}), error code 0x{:04X} = 0x{:04X}{}", i + 1,
             axes_[i].statusword, short_name(axes_[i].state()), obj::error_code.index, axes_[i].error_code,
             i == 0 ? fmt::format(", seen {} cycles after the injection", seen_after) : "");
    for (std::size_t i = 0; i < axes_.size() && i < 2; ++i) {
        master::CoeClient c(master_, master_.slaves()[i].station);
        for (int k = 0; k < 8; ++k) {
            cycle();  // the cycle goes on between the mailbox reads
            const auto msg = c.receive(milliseconds(0));
            if (!msg) break;
            if (msg->payload.size() >= 10 &&
                protocol::coe_service(ld_le16(msg->payload.data())) == protocol::CoeService::Emergency)
                note("       drive {}: emergency 0x{:04X}, error register 0x{:02X}", i + 1,
                     ld_le16(msg->payload.data() + 2), msg->payload[4]);
        }
    }
    const auto cleared = injector_.submit("clear demo-fault", milliseconds(1000));
    // Fault reset: bit 7 rising (drive 2 gets it over TWINsync); pulsed again if a drive missed the edge.
    auto no_fault = [&] {
        return std::none_of(axes_.begin(), axes_.end(),
                            [](const Axis& a) { return a.statusword & kSwFault; });
    };
    bool reset = false;
    for (int pulse = 0; pulse < 5 && !reset && !interrupted(); ++pulse) {
        for (auto& a : axes_)
            a.controlword = 0;
        cycle_until([] { return false; }, 5);
        for (auto& a : axes_)
            a.controlword = kFaultReset;
        reset = cycle_until(no_fault, 200);
    }
    if (!reset)
        return fail(
            interrupted()
                ? "interrupted"
                : fmt::format("the fault reset did not clear the fault: statuswords 0x{:04X} 0x{:04X}, "
                              "error codes 0x{:04X} 0x{:04X}",
                              axes_[0].statusword, axes_.back().statusword, axes_[0].error_code,
                              axes_.back().error_code));
    note(
        "       injector: clear demo-fault: {}; fault reset (controlword 0x80) cleared both drives; enabling "
        "again",
        cleared);
    if (!enable_drives()) return false;
    const std::int32_t from = d1.position;
    tracking_ = true;
    const bool moved = move_to(0, 1.0);
    tracking_ = false;
    if (!moved) return false;
    note("       moved again: drive 1 from {} to {}", from, d1.position);
    return true;
}

bool Demo::disable() {
    for (auto& a : axes_)
        a.controlword = kShutdown;
    const bool ready = cycle_until(
        [&] {
            return std::all_of(axes_.begin(), axes_.end(),
                               [](const Axis& a) { return a.state() == DriveState::ReadyToSwitchOn; });
        },
        500);
    if (!ready) return fail(interrupted() ? "interrupted" : "drives did not reach \"ready\"");
    for (auto& a : axes_)
        a.controlword = 0;
    cycle_until([] { return false; }, 10);
    return !interrupted() || fail("interrupted");
}

bool Demo::init() {
    // The drives' own count of SYNC0 events without new outputs (0x1C32:0B), read while still in OP.
    std::string missed;
    for (const auto& a : axes_) {
        const std::size_t i = a.layout.slave;
        master::CoeClient c(master_, master_.slaves()[i].station);
        const auto r = c.upload(0x1C32, 0x0B);
        missed += fmt::format("{}slave {}: {}", missed.empty() ? "" : ", ", i,
                              r.ok() && r.data.size() >= 2 ? std::to_string(ld_le16(r.data.data())) : "?");
    }
    if (!axes_.empty()) note("       SYNC0 events without new outputs (0x1C32:0B): {}", missed);
    for (const auto& s : master_.slaves())
        if (s.has_dc) master_.stop_sync(s.station);
    dc_running_ = false;
    if (!master_.request_state(AlState::Init)) return fail("the slaves did not go back to INIT");
    set_al(AlState::Init);
    return true;
}

// After a failure or a signal: drives off, SYNC0 off, INIT; each step bounded.

}  // namespace vecat::cli::demo_detail
