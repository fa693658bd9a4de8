// The built-in I/O terminals with behaviour (src/io, network files' inputs:): signal sources, wires from an
// output terminal to an input terminal, inputs forced through the fault injector (set_input), as the
// project's master sees them in its process data; and the network file's refusals of bad inputs: entries.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>

#include "cia402/drive.hpp"
#include "common/bytes.hpp"
#include "faults/injector.hpp"
#include "io/signal.hpp"
#include "io/terminals.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "network/build.hpp"
#include "network/network_file.hpp"
#include "protocol/cia402_objects.hpp"
#include "serve/in_process_link.hpp"
#include "shared_data.hpp"
#include "telemetry/plot.hpp"
#include "telemetry/recording.hpp"
#include "telemetry/sampler.hpp"

namespace vecat {
namespace {

using protocol::AlState;

TEST(Signals, EachKindAtItsTimes) {
    io::Signal s;
    s.kind = io::SignalKind::Square;
    s.period_ns = 100;
    s.low = 2;
    s.high = 5;
    EXPECT_EQ(io::value_at(s, 0), 2);
    EXPECT_EQ(io::value_at(s, 49), 2);
    EXPECT_EQ(io::value_at(s, 50), 5);
    EXPECT_EQ(io::value_at(s, 150), 5);
    s.phase_ns = 50;
    EXPECT_EQ(io::value_at(s, 0), 5);
    s = {};
    s.kind = io::SignalKind::Sine;
    s.period_ns = 400;
    s.amplitude = 10;
    s.offset = 1;
    EXPECT_NEAR(io::value_at(s, 100), 11, 1e-9);
    EXPECT_NEAR(io::value_at(s, 300), -9, 1e-9);
    s = {};
    s.kind = io::SignalKind::Ramp;
    s.period_ns = 100;
    s.from = 0;
    s.to = 1000;
    EXPECT_NEAR(io::value_at(s, 25), 250, 1e-9);
    EXPECT_NEAR(io::value_at(s, 125), 250, 1e-9);
    s = {};
    s.kind = io::SignalKind::Table;
    s.table = io::parse_table("# t,v\n0,1\n10,2.5\n\n30,-4\n");
    s.period_ns = 0;
    EXPECT_EQ(io::value_at(s, 5'000'000), 1);
    EXPECT_EQ(io::value_at(s, 10'000'000), 2.5);
    EXPECT_EQ(io::value_at(s, 99'000'000), -4);  // the last value holds
    s.period_ns = 40'000'000;
    EXPECT_EQ(io::value_at(s, 45'000'000), 1);  // ... or the table starts again
}

TEST(Signals, ATableThatIsNoTableSaysWhichLine) {
    const auto refused = [](const std::string& csv) {
        try {
            io::parse_table(csv);
        } catch (const std::invalid_argument& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    EXPECT_EQ(refused("0,1\n5\n"), "2: expected time_ms,value");
    EXPECT_NE(refused("0,1\n5,x\n").find("2: the value \"x\""), std::string::npos);
    EXPECT_NE(refused("0,1\n-5,2\n").find("2: the time"), std::string::npos);
    EXPECT_EQ(refused("0,1\n0,2\n"), "2: the times must rise");
    EXPECT_EQ(refused("# nothing\n"), "1: no rows (time_ms,value)");
    EXPECT_NE(refused("0,nan\n").find("1: the value"), std::string::npos);
}

// An output terminal wired to a digital input terminal and an analog input terminal with signals; the
// time of the line is the link's, 1 ms per cycle.
constexpr const char* kIo = R"(
devices:
  - name: outs
    device: digital-out
    channels: 4
  - name: ins
    device: digital-in
    channels: 4
    inputs:
      0: {wire: outs:2}
      1: {signal: square, period_ms: 10}
      3: {signal: constant, value: 1}
  - name: levels
    device: analog-in
    channels: 2
    inputs:
      0: {signal: ramp, period_ms: 100, from: 0, to: 1000}
      1: {wire: aouts:1}
  - name: aouts
    device: analog-out
    channels: 2
)";

struct IoLine {
    IoLine()
        : built(network::build_network(network::parse_network(kIo, "io.yaml"), "io.yaml")),
          link(*built.segment),
          inj(*built.segment),
          forcing(*built.segment, built.io),
          m(link) {
        link.set_time(now);
        link.set_filter(&inj);
        inj.register_handler(io::InputForcing::kKind, forcing);
    }
    void cycle() {
        now += 1'000'000;
        link.set_time(now);
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
    }
    // An output reaches its terminal with one frame and is copied out after it; an input is sampled after a
    // frame and read with the next one: three cycles bring an output through a wire to the master in any
    // order of the terminals on the line.
    void settle() {
        for (int i = 0; i < 3; ++i)
            cycle();
    }
    std::uint8_t digital() const { return m.inputs(1)[0] & 0x0F; }
    std::int16_t analog(unsigned c) const {
        return static_cast<std::int16_t>(ld_le16(m.inputs(2).data() + 2 * c));
    }
    network::BuiltNetwork built;
    net::InProcessLink link;
    faults::FaultInjector inj;
    io::InputForcing forcing;
    master::Master m;
    std::uint64_t now = 1'000'000'000;
};

TEST(IoTerminals, InputsFollowTheirSignalsAndWires) {
    IoLine l;
    std::string why;
    ASSERT_TRUE(l.m.startup(AlState::Op, &why)) << why;
    // The output terminal's channel 2 drives input 0; input 3 is constantly on; input 2 has no source.
    l.m.outputs(0)[0] = 0x04;
    st_le16(l.m.outputs(3).data() + 2, static_cast<std::uint16_t>(-1234));
    l.settle();
    EXPECT_EQ(l.digital() & 0x09, 0x09);
    EXPECT_EQ(l.analog(1), -1234);
    l.m.outputs(0)[0] = 0x00;
    l.settle();
    EXPECT_EQ(l.digital() & 0x0D, 0x08);
    // The output terminal restarts (power off and on: a new application); the wire follows the new one once
    // the master has brought the line to OP again.
    ASSERT_TRUE(l.built.segment->restart_slave(0));
    ASSERT_TRUE(l.m.startup(AlState::Op, &why)) << why;
    l.m.outputs(0)[0] = 0x04;
    l.settle();
    EXPECT_EQ(l.digital() & 0x01, 0x01);
    l.m.outputs(0)[0] = 0x00;
    l.settle();
    EXPECT_EQ(l.digital() & 0x01, 0x00);
    // Input 1: a 10 ms square: five cycles low, five high.
    unsigned high = 0, changes = 0;
    std::uint8_t last = l.digital() & 0x02;
    for (int i = 0; i < 40; ++i) {
        l.cycle();
        high += (l.digital() & 0x02) != 0;
        changes += (l.digital() & 0x02) != last;
        last = l.digital() & 0x02;
    }
    EXPECT_EQ(high, 20u);
    EXPECT_GE(changes, 7u);
    // The ramp rises 10 per ms.
    const std::int16_t a = l.analog(0);
    l.cycle();
    EXPECT_EQ((l.analog(0) - a + 1000) % 1000, 10);
}

TEST(IoTerminals, AnInputForcedThroughTheControlSocketUntilTheFaultIsCleared) {
    IoLine l;
    std::string why;
    ASSERT_TRUE(l.m.startup(AlState::Op, &why)) << why;
    l.cycle();
    EXPECT_EQ(l.digital() & 0x04, 0);
    EXPECT_EQ(l.inj.execute("inject set_input slave=1 channel=2 value=1 id=f", l.now).rfind("ok", 0), 0u);
    EXPECT_EQ(l.inj.execute("inject set_input slave=2 channel=0 value=-70000 id=g", l.now).rfind("ok", 0),
              0u);
    l.settle();
    EXPECT_EQ(l.digital() & 0x04, 0x04);
    EXPECT_EQ(l.analog(0), -32768);  // limited to 16 bits
    EXPECT_EQ(l.inj.execute("clear f", l.now).rfind("ok", 0), 0u);
    l.settle();
    EXPECT_EQ(l.digital() & 0x04, 0);
    EXPECT_EQ(l.analog(0), -32768);
    // With nothing forced any more, a constant input forced and released: it reads its constant again (the
    // channels that do not change with time are written again after a release only).
    EXPECT_EQ(l.inj.execute("clear g", l.now).rfind("ok", 0), 0u);
    l.settle();
    EXPECT_NE(l.analog(0), -32768);
    EXPECT_EQ(l.digital() & 0x08, 0x08);
    EXPECT_EQ(l.inj.execute("inject set_input slave=1 channel=3 value=0 id=h", l.now).rfind("ok", 0), 0u);
    l.settle();
    EXPECT_EQ(l.digital() & 0x08, 0);
    EXPECT_EQ(l.inj.execute("clear h", l.now).rfind("ok", 0), 0u);
    l.settle();
    EXPECT_EQ(l.digital() & 0x08, 0x08);
    // Refused: no input terminal, a channel it lacks, no value.
    EXPECT_EQ(l.inj.execute("inject set_input slave=0 channel=0 value=1", l.now).rfind("error", 0), 0u);
    EXPECT_EQ(l.inj.execute("inject set_input slave=1 channel=4 value=1", l.now).rfind("error", 0), 0u);
    EXPECT_EQ(l.inj.execute("inject set_input slave=1 channel=0", l.now).rfind("error", 0), 0u);
}

// An input terminal whose inputs are all constant has no cycle of its own (InputTerminal::next_cycle_ns): a
// frame reads what its last run wrote, and it runs only within the segment's lag bound (16 local cycles),
// not before every frame that reads it. An input forced or released wakes it (InputForcing,
// Segment::wake_slave): the very next frame reads the forced value. (The fault injector's start and stop
// also reset every slave's schedule; the handler is called here without it, as a timeline could.)
TEST(IoTerminals, AConstantInputTerminalRunsOnlyWhenWokenAndShowsAForcedInputAtOnce) {
    network::BuiltNetwork built = network::build_network(
        network::parse_network(
            "devices:\n  - {name: ins, device: digital-in, channels: 4, inputs: {3: {signal: "
            "constant, value: 1}}}\n",
            "c.yaml"),
        "c.yaml");
    net::InProcessLink link(*built.segment);
    io::InputForcing forcing(*built.segment, built.io);
    std::uint64_t now = 1'000'000'000;
    link.set_time(now);
    master::Master m(link);
    std::string why;
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    const auto cycle = [&] {
        now += 1'000'000;
        link.set_time(now);
        EXPECT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
        return m.inputs(0)[0] & 0x0F;
    };
    cycle();
    const std::uint64_t before = built.segment->counters().firmware_runs;
    for (int i = 0; i < 8; ++i)
        EXPECT_EQ(cycle(), 0x08);
    EXPECT_LE(built.segment->counters().firmware_runs - before, 2u);  // 8 ms: its lag bound twice at most
    // Each change just after a lag-bound run of the terminal (the cycle in which the run count moves), so
    // that only the wake can bring it to the next frame.
    const auto just_after_its_run = [&] {
        const std::uint64_t r = built.segment->counters().firmware_runs;
        for (int i = 0; i < 20 && built.segment->counters().firmware_runs == r; ++i)
            cycle();
    };
    const faults::FaultSpec f = faults::parse_fault("set_input slave=0 channel=1 value=1");
    just_after_its_run();
    forcing.start(f, now);
    EXPECT_EQ(cycle(), 0x0A) << "forced";
    just_after_its_run();
    forcing.stop(f, now);
    EXPECT_EQ(cycle(), 0x08) << "released";
}

// A vecat drive of a network file has inputs to force too: its touch probe inputs 1 and 2 (0x60FD bits 16
// and 17), without any inputs: entry in the file.
TEST(IoTerminals, ADrivesTouchProbeInputForcedThroughTheControlSocket) {
    network::BuiltNetwork built = network::build_network(
        network::parse_network("devices:\n  - {name: axis, device: drive}\n", "d.yaml"), "d.yaml");
    net::InProcessLink link(*built.segment);
    faults::FaultInjector inj(*built.segment);
    io::InputForcing forcing(*built.segment, built.io);
    inj.register_handler(io::InputForcing::kKind, forcing);
    std::uint64_t now = 1'000'000'000;
    link.set_time(now);
    link.set_filter(&inj);
    master::Master m(link);
    std::string why;
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    auto probe_inputs = [&] {
        for (int i = 0; i < 3; ++i) {
            now += 1'000'000;
            link.set_time(now);
            EXPECT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
        }
        master::CoeClient c(m, m.slaves()[0].station);
        const auto r = c.upload(protocol::obj::digital_inputs.index, 0);
        EXPECT_TRUE(r.ok());
        return r.ok() && r.data.size() >= 4 ? (ld_le32(r.data.data()) >> 16) & 3u : 99u;
    };
    EXPECT_EQ(probe_inputs(), 0u);
    EXPECT_EQ(inj.execute("inject set_input slave=0 channel=1 value=1 id=p", now).rfind("ok", 0), 0u);
    EXPECT_EQ(probe_inputs(), 2u);
    EXPECT_EQ(inj.execute("clear p", now).rfind("ok", 0), 0u);
    EXPECT_EQ(probe_inputs(), 0u);
    // The drive has two probe inputs.
    EXPECT_EQ(inj.execute("inject set_input slave=0 channel=2 value=1", now).rfind("error", 0), 0u);
}

// A vecat drive at rest settles and skips its servo periods (DriveCore, Drive::advance), but a touch probe
// input wired to a signal is still sampled at every servo period, also between two frames. The ramp
// -99 + 100 * phase is above 0.5 in the last 0.5 ms of every 100 ms, where a single servo period ends (at
// 99.75 ms: the periods end every 250 us from the first frame at 1 s), the third of the four periods that
// the frame at 100 ms brings: the probe latches that pulse.
TEST(IoTerminals, ASettledDrivesTouchProbeSeesAPulseBetweenTwoFrames) {
    const char* kFile =
        "devices:\n  - name: axis\n    device: drive\n    inputs:\n"
        "      0: {signal: ramp, from: -99, to: 1, period_ms: 100}\n";
    network::BuiltNetwork built = network::build_network(network::parse_network(kFile, "d.yaml"), "d.yaml");
    net::InProcessLink link(*built.segment);
    std::uint64_t now = 1'000'000'000;
    link.set_time(now);
    master::Master m(link);
    std::string why;
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    const auto* drive = dynamic_cast<const cia402::Drive*>(&built.segment->slave(0).app());
    ASSERT_NE(drive, nullptr);
    auto frames_until = [&](std::uint64_t t) {
        while (now + 1'000'000 <= t) {
            now += 1'000'000;
            link.set_time(now);
            ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
        }
    };
    master::CoeClient c(m, m.slaves()[0].station);
    auto probe_status = [&] {
        const auto r = c.upload(protocol::obj::touch_probe_status.index, 0);
        EXPECT_TRUE(r.ok());
        return r.ok() && r.data.size() >= 2 ? ld_le16(r.data.data()) & 0x0003u : 99u;
    };
    // After the pulse at 1.09975 s, probe 1 on (0x60B8 in the default RxPDO): single trigger, input 1, its
    // positive edge.
    frames_until(1'105'000'000);
    const master::MappedEntry* function =
        master::find_entry(m.slaves()[0].out_entries, protocol::obj::touch_probe_function.index);
    ASSERT_NE(function, nullptr);
    st_le16(m.outputs(0).data() + function->bit_offset / 8, 0x0011);
    frames_until(1'190'000'000);
    EXPECT_EQ(probe_status(), 0x0001u) << "on, nothing latched before the pulse";
    const std::uint64_t skipped = drive->skipped_servo_steps();
    frames_until(1'199'000'000);
    EXPECT_GE(drive->skipped_servo_steps() - skipped, 30u) << "the drive skips its periods before the pulse";
    frames_until(1'202'000'000);
    EXPECT_EQ(probe_status(), 0x0003u) << "the pulse at 1.19975 s latched";
}

// The telemetry samples every I/O terminal (IoSample): the output terminals' channels as the master wrote
// them, the input terminals' as they are sent, here following a wire and a ramp; the recording reads back
// from CSV and its picture has one lane per channel asked for, digital ones drawn as steps.
TEST(IoTerminals, TheScopeSamplesTheChannelsOfEachTerminal) {
    IoLine l;
    std::string why;
    ASSERT_TRUE(l.m.startup(AlState::Op, &why)) << why;
    auto q = std::make_unique<telemetry::TelemetryQueue>();
    telemetry::Sampler sampler(*l.built.segment, *q);
    auto run = [&](int cycles) {
        for (int i = 0; i < cycles; ++i) {
            l.cycle();
            sampler.on_frame(l.now);
        }
    };
    l.m.outputs(0)[0] = 0x04;  // outs channel 2: wired to ins channel 0
    st_le16(l.m.outputs(3).data() + 2, static_cast<std::uint16_t>(-1234));  // aouts channel 1 -> levels 1
    run(4);
    l.m.outputs(0)[0] = 0x00;
    run(4);
    telemetry::Recording r;
    telemetry::Record rec;
    while (q->pop(rec))
        r.add(rec);
    EXPECT_GT(sampler.stats().io_samples, 0u);
    auto of = [&](std::uint16_t slave) {
        std::vector<telemetry::IoSample> v;
        for (const auto& s : r.io)
            if (s.slave == slave) v.push_back(s);
        return v;
    };
    const auto outs = of(0), ins = of(1), levels = of(2), aouts = of(3);
    ASSERT_EQ(outs.size(), 8u);  // one per exchange (decimation 1)
    ASSERT_EQ(ins.size(), 8u);
    ASSERT_FALSE(levels.empty());
    ASSERT_FALSE(aouts.empty());
    EXPECT_EQ(outs[0].out_channels, 4);
    EXPECT_EQ(outs[0].in_channels, 0);
    EXPECT_FALSE(outs[0].analog);
    EXPECT_EQ(ins[0].in_channels, 4);
    EXPECT_TRUE(levels[0].analog);
    // The output as written, every sample of the first half; then low.
    for (std::size_t i = 0; i < 4; ++i)
        EXPECT_EQ(outs[i].out[2], 1) << i;
    EXPECT_EQ(outs.back().out[2], 0);
    // The wired input rises behind the output and falls behind it; input 3 is a constant 1.
    EXPECT_EQ(ins[3].in[0], 1);
    EXPECT_EQ(ins.back().in[0], 0);
    EXPECT_EQ(ins.back().in[3], 1);
    EXPECT_EQ(aouts.back().out[1], -1234);
    EXPECT_EQ(levels.back().in[1], -1234);
    // The ramp: 10 per ms.
    EXPECT_EQ((levels.back().in[0] - levels[levels.size() - 2].in[0] + 1000) % 1000, 10);

    const auto dir = std::filesystem::temp_directory_path() / ("vecat-ioscope-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "rec.csv").string();
    ASSERT_TRUE(telemetry::write_csv(r, path, &why)) << why;
    EXPECT_TRUE(std::filesystem::exists(dir / "rec-io.csv"));
    telemetry::Recording back;
    ASSERT_TRUE(telemetry::read_csv(path, back, &why)) << why;
    std::filesystem::remove_all(dir);
    ASSERT_EQ(back.io.size(), r.io.size());
    for (std::size_t i = 0; i < r.io.size(); ++i) {
        EXPECT_EQ(back.io[i].time_ns, r.io[i].time_ns);
        EXPECT_EQ(back.io[i].slave, r.io[i].slave);
        EXPECT_EQ(back.io[i].analog, r.io[i].analog);
        EXPECT_EQ(back.io[i].in_channels, r.io[i].in_channels);
        EXPECT_EQ(back.io[i].out, r.io[i].out);
        EXPECT_EQ(back.io[i].in, r.io[i].in);
    }

    const auto groups = telemetry::parse_signal_groups("io.out2,io.in0,io.in1", &why);
    ASSERT_EQ(groups.size(), 3u) << why;
    EXPECT_TRUE(telemetry::parse_signal_groups("io.in16", &why).empty());  // beyond kIoChannels
    EXPECT_TRUE(telemetry::parse_signal_groups("io.cycle", &why).empty());
    const telemetry::Plot p = telemetry::make_plot(back, groups, "io");
    ASSERT_EQ(p.panels.size(), 3u);
    ASSERT_EQ(p.panels[0].series.size(), 1u);  // only outs has a digital output channel 2 (aouts has 2)
    EXPECT_EQ(p.panels[0].series[0].label, "slave 0 io.out2");
    EXPECT_TRUE(p.panels[0].series[0].step);
    ASSERT_EQ(p.panels[2].series.size(), 2u);  // ins (digital) and levels (analog) have an input 1
    EXPECT_TRUE(p.panels[2].series[0].step);
    EXPECT_FALSE(p.panels[2].series[1].step);
    const std::string svg = telemetry::render_svg(p);
    EXPECT_NE(svg.find("slave 1 io.in0"), std::string::npos);
    EXPECT_NE(svg.find("slave 2 io.in1"), std::string::npos);
    bool listed = false;
    for (const auto& sig : telemetry::signal_list())
        listed = listed || sig.name == "io.out15";
    EXPECT_TRUE(listed);
}

// Wires from the outputs of devices of SII dumps and ESI files (docs/network-file.md, Inputs): a real
// Beckhoff EL2004 from its SII dump (four one-bit RxPDOs 0x1600-0x1603 mapping 0x7000:1 ... 0x7030:1) drives
// a digital input terminal by channel and by entry; the modular device of examples/networks drives an analog
// input terminal with its 8-bit output 0x7000:0.
std::string el2004_line() {
    return "devices:\n"
           "  - name: el2004\n"
           "    sii: " +
           test::shared_data("sii/beckhoff-el2004.bin") +
           "\n"
           "  - name: ins\n"
           "    device: digital-in\n"
           "    channels: 4\n"
           "    inputs:\n"
           "      0: {wire: el2004:0}\n"
           "      1: {wire: el2004:3}\n"
           "      2: {wire: el2004:0x7010:1}\n"
           "  - name: mod\n"
           "    esi: " VECAT_SOURCE_DIR
           "/examples/networks/modular-io.xml\n"
           "    type: VECAT-MOD-3\n"
           "  - name: level\n"
           "    device: analog-in\n"
           "    channels: 1\n"
           "    inputs:\n"
           "      0: {wire: mod:0x7000:0}\n";
}

TEST(IoTerminals, AWireTakesAnOutputOfADeviceOfAnSiiDumpOrEsiFile) {
    VECAT_REQUIRE_SHARED_DATA("sii/beckhoff-el2004.bin");
    auto built = network::build_network(network::parse_network(el2004_line(), "el.yaml"), "el.yaml");
    net::InProcessLink link(*built.segment);
    master::Master m(link);
    std::uint64_t now = 1'000'000'000;
    link.set_time(now);
    std::string why;
    ASSERT_TRUE(m.startup(AlState::Op, &why)) << why;
    ASSERT_EQ(m.outputs(0).size(), 1u) << "the EL2004's four output bits";
    const auto cycle = [&] {
        now += 1'000'000;
        link.set_time(now);
        ASSERT_EQ(m.exchange_process_data().value_or(0), m.expected_wkc());
    };
    const auto inputs = [&] { return m.inputs(1)[0] & 0x07; };
    // The master writes outputs 1 and 4 of the EL2004: with this frame the EL2004 takes them, the input
    // terminal samples them after it, and the master reads them with the next frame: one cycle later.
    m.outputs(0)[0] = 0x09;
    cycle();
    cycle();
    EXPECT_EQ(inputs(), 0x03) << "channel 0 (bit 0) and channel 3 (bit 3) on, 0x7010:1 off";
    m.outputs(0)[0] = 0x02;
    cycle();
    cycle();
    EXPECT_EQ(inputs(), 0x04) << "0x7010:1 (output 2) on";
    // The modular device's DO8 output 0x7000:0 (USINT) on the analog input.
    m.outputs(2)[0] = 0xC8;
    cycle();
    cycle();
    EXPECT_EQ(static_cast<std::int16_t>(ld_le16(m.inputs(3).data())), 200);
    // Below OP the outputs go to their safe state: the wire reads 0.
    ASSERT_TRUE(m.request_state(m.slaves().at(0).station, AlState::SafeOp));
    cycle();
    cycle();
    EXPECT_EQ(inputs(), 0x00);
}

TEST(IoTerminals, AWireToAnOutputTheDeviceLacksIsRefusedNamingTheLine) {
    VECAT_REQUIRE_SHARED_DATA("sii/beckhoff-el2004.bin");
    const auto refused = [](const std::string& text) {
        try {
            (void)network::build_network(network::parse_network(text, "net.yaml"), "net.yaml");
        } catch (const network::NetworkFileError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    const auto with = [](const std::string& from, const std::string& to) {
        std::string t = el2004_line();
        t.replace(t.find(from), from.size(), to);
        return t;
    };
    EXPECT_EQ(refused(el2004_line()), "accepted");
    EXPECT_EQ(
        refused(with("el2004:3}", "el2004:4}")),
        "net.yaml:9: ins: wire: el2004 has one-bit outputs 0-3 (its RxPDO entries of one bit, in order)");
    EXPECT_EQ(refused(with("el2004:0x7010:1", "el2004:0x7010:2")),
              "net.yaml:10: ins: wire: el2004 maps no output PDO entry 0x7010:2 (its default RxPDOs map "
              "0x7000:1, 0x7010:1, 0x7020:1, 0x7030:1)");
    EXPECT_EQ(refused(with("mod:0x7000:0", "mod:0")),
              "net.yaml:18: level: wire: mod has no one-bit outputs in its default RxPDOs; name an entry: "
              "mod:0xINDEX:SUB");
    // The reader checks the syntax, and that an entry is named only on a device of a file.
    EXPECT_EQ(refused(with("el2004:0x7010:1", "el2004:7010:1")),
              "net.yaml:10: wire: DEVICE:0xINDEX:SUB, the entry's index in hexadecimal (0x7000)");
    EXPECT_EQ(refused(with("el2004:0x7010:1", "el2004:0x7010:256")),
              "net.yaml:10: wire: DEVICE:0xINDEX:SUB, the subindex 0-255 after the index");
    EXPECT_EQ(
        refused(with("el2004:0x7010:1", "level:0x7010:1")),
        "net.yaml:10: ins: wire: level is a built-in device: a wire names its channel (DEVICE:CHANNEL); "
        "DEVICE:0xINDEX:SUB is for devices of ESI files and SII dumps");
}

TEST(IoTerminals, TheNetworkFileRefusesBadInputsNamingTheLine) {
    const auto refused = [](const std::string& text) {
        try {
            network::parse_network(text, "net.yaml");
        } catch (const network::NetworkFileError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    const std::string out = "devices:\n  - name: o\n    device: digital-out\n    channels: 2\n";
    EXPECT_EQ(refused(out + "    inputs: {0: {signal: constant}}\n"),
              "net.yaml:5: o: inputs: is for the built-in input terminals (digital-in, analog-in) and the "
              "touch probe "
              "inputs of the vecat drive (device: drive)");
    const std::string in = out + "  - name: i\n    device: digital-in\n    channels: 2\n";
    EXPECT_EQ(refused(in + "    inputs: {2: {signal: constant}}\n"),
              "net.yaml:8: i: inputs: channel 2: it has channels 0-1");
    EXPECT_EQ(refused(in + "    inputs: {0: {wire: nobody:0}}\n"),
              "net.yaml:8: i: wire: no device named nobody");
    EXPECT_EQ(
        refused(in + "    inputs: {0: {wire: i:0}}\n"),
        "net.yaml:8: i: wire: i is no output terminal (digital-out, analog-out) and no vecat drive (device: "
        "drive, its digital outputs 0x60FE)");
    EXPECT_EQ(refused(in + "    inputs: {0: {wire: o:5}}\n"), "net.yaml:8: i: wire: o has channels 0-1");
    EXPECT_EQ(refused(in + "    inputs: {0: {signal: noise}}\n"),
              "net.yaml:8: signal: unknown signal noise (constant, square, sine, ramp, table)");
    EXPECT_EQ(refused(in + "    inputs: {0: {value: 1}}\n"),
              "net.yaml:8: inputs: channel 0: give signal: or wire:");
    EXPECT_EQ(refused(in + "    inputs: {0: {signal: square, period_ms: 0}}\n"),
              "net.yaml:8: period_ms: more than 0");
    EXPECT_EQ(refused(in + "    inputs: {0: {signal: table}}\n"),
              "net.yaml:8: inputs: a table signal takes file: (CSV rows time_ms,value)");
    EXPECT_NE(refused(in + "    inputs: {0: {signal: table, file: /nonexistent.csv}}\n")
                  .find("file: /nonexistent.csv cannot be read"),
              std::string::npos);
    // A device that never ends is no table (nothing hangs reading it).
    EXPECT_EQ(refused(in + "    inputs: {0: {signal: table, file: /dev/zero}}\n"),
              "net.yaml:8: file: /dev/zero is larger than 16 MiB");
    const auto csv = (std::filesystem::temp_directory_path() / "vecat-io-bad.csv").string();
    std::ofstream(csv) << "0,1\n1,oops\n";
    EXPECT_EQ(refused(in + "    inputs: {0: {signal: table, file: " + csv + "}}\n"),
              "net.yaml:8: file: " + csv + ":2: the value \"oops\" is no number");
    std::filesystem::remove(csv);
    EXPECT_EQ(refused(in + "    inputs: {0: {signal: sine, amplitude: x}}\n"),
              "net.yaml:8: amplitude: \"x\" is not a number");
}

}  // namespace
}  // namespace vecat
