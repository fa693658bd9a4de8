// The built-in I/O terminals with behaviour (network files, docs/network-file.md): an input terminal's
// channels follow their signal sources (signal.hpp) or are wired to a channel of an output terminal, and any
// input can be forced at run time through the control socket (fault set_input, src/faults) until the fault
// is cleared; a wire may also take an output PDO entry of a device of an ESI file or SII dump (OutputsOnBus).
// The terminals of one network share an IoBus: the output images for the wires, resolved to
// slots once when the network is built, and the forced inputs, which outlive a restart of their terminal.
// Nothing on the cyclic path allocates or looks anything up by name: the objects a wire reads of a device
// with a dictionary are found once, when its application is made.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "esc/slave.hpp"
#include "faults/injector.hpp"
#include "io/signal.hpp"

namespace vecat::esc {
class Segment;
}

namespace vecat::io {

// A digital channel is one bit (an input reads 1 when its signal is above 0.5), an analog one a 16-bit
// signed integer (the signal rounded and limited to -32768..32767). Entries: the outputs of a device of an
// ESI file or SII dump, each channel one output PDO entry of its image (IoBus::add_point).
enum class ChannelKind : std::uint8_t { Digital, Analog, Entries };

// An output PDO entry of a device: index:subindex, 1 to 32 bits; signed: an INTEGER type, its value
// sign-extended. Its place in the device's output image in the default mapping: bits [bit_offset,
// bit_offset + bit_length), little-endian (ETG.1000.6 5.6.7.4.7: entries packed in mapping order). A device
// that holds its outputs as objects (a CoE dictionary) shows the object's value instead (ObjectOutputs).
// in_image false: an entry of an RxPDO the default assignment leaves out (a master may assign it by SDO); it
// has no place in the image (bit_offset means nothing) and reads only its object, 0 where there is none.
struct ImagePoint {
    std::uint32_t bit_offset = 0;
    std::uint8_t bit_length = 1;
    bool is_signed = false;
    std::uint16_t index = 0;
    std::uint8_t subindex = 0;
    bool in_image = true;
};

// The outputs of a device that holds them as objects (its RxPDOs are mapped into a dictionary, which a master
// may remap): for each point of its Entries slot the object's value, wherever the master mapped it or if it
// mapped it at all. Set up once when the application is made; the device's application owns it.
struct ObjectOutputs {
    // Point c's object value: its bytes, little-endian, the value from bit 0 (as a mapped entry is stored,
    // coe::ProcessDataMap); nullptr: the device has no such object, the point's place in the image is read
    // (0 for a point with no place in it).
    std::vector<const std::uint8_t*> values;
    // In OP. Below OP the outputs are in their safe state (ETG.1000.6, the AL state machine: SAFEOP keeps
    // them there): every point reads 0, whatever its object holds (an object no RxPDO maps keeps a value
    // written by SDO).
    bool in_op = false;
};

class IoBus {
  public:
    static constexpr std::size_t kNone = ~std::size_t{0};
    // Slots, made while the network is built; names are the devices' names in the network file.
    std::size_t add_output(std::string name, ChannelKind kind, unsigned channels);
    std::size_t add_input(std::string name, unsigned channels);
    std::size_t output_slot(std::string_view name) const;  // kNone when there is none
    // A point of the image of an Entries output slot: its channel (the same point given again: its channel).
    unsigned add_point(std::size_t slot, ImagePoint p);
    const std::vector<ImagePoint>& points(std::size_t slot) const { return outputs_.at(slot).points; }
    // The output terminal of a slot shows its image there while it exists, a device with a dictionary also
    // its objects (objects: values for every point of the slot). A restarted terminal's new application
    // publishes before the old one goes: withdrawing takes the image away only if it is still the one shown.
    void publish(std::size_t slot, const std::vector<std::uint8_t>* image,
                 const ObjectOutputs* objects = nullptr) {
        outputs_.at(slot).image = image;
        outputs_[slot].objects = objects;
    }
    void withdraw(std::size_t slot, const std::vector<std::uint8_t>* image) {
        if (outputs_.at(slot).image != image) return;
        outputs_[slot].image = nullptr;
        outputs_[slot].objects = nullptr;
    }
    // The state an output slot stands for, as a key of esc::Application::shared_state: its device writes
    // the image that wired inputs read, so they run on one firmware thread.
    const void* output_key(std::size_t slot) const { return &outputs_.at(slot); }
    // Channel c of the output terminal in slot s: 0 or 1, or the 16-bit value, or the value of the entry
    // (0 when it is gone).
    double output(std::size_t slot, unsigned channel) const noexcept;
    ChannelKind output_kind(std::size_t slot) const { return outputs_.at(slot).kind; }
    unsigned output_channels(std::size_t slot) const { return outputs_.at(slot).channels; }
    // Forced inputs of input slot s.
    void force(std::size_t slot, unsigned channel, double v);
    void release(std::size_t slot, unsigned channel);
    bool forced(std::size_t slot, unsigned channel, double& v) const noexcept;
    // Whether any input channel of the bus is forced (a cheap test before looking at each channel).
    bool any_forced() const noexcept { return forced_channels_ != 0; }
    // Counts every force and release (a terminal that saw the same count needs no look at its channels that
    // do not change with time).
    std::uint64_t forcing_changes() const noexcept { return forcing_changes_; }

  private:
    struct Output {
        std::string name;
        ChannelKind kind = ChannelKind::Digital;
        unsigned channels = 0;
        const std::vector<std::uint8_t>* image = nullptr;
        const ObjectOutputs* objects = nullptr;  // Entries of a device with a dictionary
        std::vector<ImagePoint> points;          // Entries: channel c is points[c]
    };
    struct Input {
        std::string name;
        std::vector<double> value;
        std::vector<std::uint8_t> forced;
    };
    std::vector<Output> outputs_;
    std::vector<Input> inputs_;
    std::size_t forced_channels_ = 0;
    std::uint64_t forcing_changes_ = 0;
};

// What one input channel reads when it is not forced.
struct InputSource {
    Signal signal;                         // Constant 0 unless given
    std::size_t wire_slot = IoBus::kNone;  // a wire: this output slot and channel (signal.channel)
};

// An application whose inputs the fault set_input can force: an input terminal, and a vecat drive in a
// network file (its touch probe inputs 1 and 2, network/build.cpp).
class ForceableInputs {
  public:
    virtual ~ForceableInputs() = default;
    virtual std::size_t input_slot() const = 0;  // its input slot on the IoBus
    virtual unsigned input_channels() const = 0;
};

class InputTerminal final : public esc::ProcessImageApplication, public ForceableInputs {
  public:
    InputTerminal(unsigned output_bytes, unsigned input_bytes, ChannelKind kind,
                  std::vector<InputSource> sources, std::shared_ptr<IoBus> bus, std::size_t slot);
    void exchange(std::uint64_t now_ns, ConstBytes outputs, bool apply, Bytes inputs) override;
    std::size_t slot() const { return slot_; }
    unsigned channels() const { return static_cast<unsigned>(sources_.size()); }
    std::size_t input_slot() const override { return slot_; }
    unsigned input_channels() const override { return channels(); }
    ChannelKind kind() const { return kind_; }
    void shared_state(std::vector<const void*>& keys) const override;  // the outputs it is wired to
    // Inputs that are all constant (no wire, no signal that changes with time) need no run of their own:
    // a frame reads what the last run wrote, and a forced input wakes the terminal (InputForcing).
    std::uint64_t next_cycle_ns() const override {
        return changing_.empty() ? esc::DistributedClock::kNever : 0;
    }

  private:
    ChannelKind kind_;
    std::vector<InputSource> sources_;
    std::shared_ptr<IoBus> bus_;
    std::size_t slot_;
    bool started_ = false;
    std::uint64_t origin_ns_ = 0;
    // The channels whose value changes with time (a wire, a periodic signal, a table): the others are written
    // into the image at the first exchange and after a force or release only.
    std::vector<unsigned> changing_;
    std::uint64_t forcing_seen_ = 0;
    void put(unsigned c, double v, std::vector<std::uint8_t>& img) const;
};

class OutputTerminal final : public esc::ProcessImageApplication {
  public:
    OutputTerminal(unsigned output_bytes, unsigned input_bytes, std::shared_ptr<IoBus> bus, std::size_t slot);
    ~OutputTerminal() override;
    OutputTerminal(const OutputTerminal&) = delete;
    OutputTerminal& operator=(const OutputTerminal&) = delete;
    ChannelKind kind() const { return bus_->output_kind(slot_); }
    unsigned channels() const { return bus_->output_channels(slot_); }
    void shared_state(std::vector<const void*>& keys) const override {
        keys.push_back(bus_->output_key(slot_));
    }

  private:
    std::shared_ptr<IoBus> bus_;
    std::size_t slot_;
};

// Where an application holds the value of an output PDO entry: its object's bytes (ObjectOutputs::values),
// or nullptr when it has none. Called once per point when the application is made.
template <class App>
using ObjectLocator = const std::uint8_t* (*)(App& app, const ImagePoint& point);

// The outputs of a device of an ESI file or SII dump on the bus, for wires (App: its application, a
// coe::CoeApplication, a drive, a bare process image): after each exchange that applies outputs, the image
// the master wrote (as long as the default mapping's image; a longer one is cut) is copied into a buffer made
// once, which the bus shows; the safe state clears it. With a locator (a device with a CoE dictionary, filled
// in by src/network, which may know src/coe) each point reads its object where the locator finds one, in OP:
// the master may map the entry elsewhere or not at all (ETG.1000.6 5.6.7.4), the object is the output. A
// subclass, so that whoever looks for the application's own type (CoE faults, telemetry) still finds it.
template <class App>
class OutputsOnBus final : public App {
  public:
    template <class... Args>
    OutputsOnBus(std::shared_ptr<IoBus> bus, std::size_t slot, unsigned image_bytes,
                 ObjectLocator<App> locate, Args&&... args)
        : App(std::forward<Args>(args)...), bus_(std::move(bus)), slot_(slot), image_(image_bytes, 0) {
        bool any = false;
        if (locate) {
            for (const ImagePoint& p : bus_->points(slot_)) {
                objects_.values.push_back(locate(*this, p));
                any |= objects_.values.back() != nullptr;
            }
        }
        bus_->publish(slot_, &image_, any ? &objects_ : nullptr);
    }
    ~OutputsOnBus() override { bus_->withdraw(slot_, &image_); }
    OutputsOnBus(const OutputsOnBus&) = delete;
    OutputsOnBus& operator=(const OutputsOnBus&) = delete;
    void exchange(std::uint64_t now_ns, ConstBytes outputs, bool apply, Bytes inputs) override {
        App::exchange(now_ns, outputs, apply, inputs);
        if (apply) std::copy_n(outputs.begin(), std::min(outputs.size(), image_.size()), image_.begin());
    }
    void outputs_safe_state() override {
        App::outputs_safe_state();
        std::fill(image_.begin(), image_.end(), 0);
    }
    void on_state_change(protocol::AlState from, protocol::AlState to) override {
        App::on_state_change(from, to);
        objects_.in_op = to == protocol::AlState::Op;
    }
    // Wired inputs read its outputs: they run on one firmware thread with it.
    void shared_state(std::vector<const void*>& keys) const override {
        App::shared_state(keys);
        keys.push_back(bus_->output_key(slot_));
    }

  private:
    std::shared_ptr<IoBus> bus_;
    std::size_t slot_;
    std::vector<std::uint8_t> image_;
    ObjectOutputs objects_;
};

// The fault set_input slave=N channel=C value=V: the input reads V until the fault ends. Registered with the
// injector for a network file (vecat run); the slave is an input terminal or a vecat drive (ForceableInputs).
class InputForcing final : public faults::FaultHandler {
  public:
    InputForcing(esc::Segment& seg, std::shared_ptr<IoBus> bus) : seg_(seg), bus_(std::move(bus)) {}
    void start(const faults::FaultSpec& f, std::uint64_t now_ns) override;
    void stop(const faults::FaultSpec& f, std::uint64_t now_ns) override;
    static constexpr const char* kKind = "set_input";

  private:
    // The input slot and channel a fault names; throws std::invalid_argument.
    std::pair<std::size_t, unsigned> target(const faults::FaultSpec& f) const;
    esc::Segment& seg_;
    std::shared_ptr<IoBus> bus_;
};

}  // namespace vecat::io
