#include "io/terminals.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/bytes.hpp"
#include "common/rounding.hpp"
#include "esc/segment.hpp"

namespace vecat::io {

std::size_t IoBus::add_output(std::string name, ChannelKind kind, unsigned channels) {
    outputs_.push_back(Output{std::move(name), kind, channels, nullptr, nullptr, {}});
    return outputs_.size() - 1;
}

std::size_t IoBus::add_input(std::string name, unsigned channels) {
    inputs_.push_back(
        Input{std::move(name), std::vector<double>(channels, 0.0), std::vector<std::uint8_t>(channels, 0)});
    return inputs_.size() - 1;
}

std::size_t IoBus::output_slot(std::string_view name) const {
    for (std::size_t i = 0; i < outputs_.size(); ++i)
        if (outputs_[i].name == name) return i;
    return kNone;
}

unsigned IoBus::add_point(std::size_t slot, ImagePoint p) {
    Output& o = outputs_.at(slot);
    for (std::size_t i = 0; i < o.points.size(); ++i)
        if (const ImagePoint& q = o.points[i];
            q.in_image == p.in_image && q.bit_length == p.bit_length &&
            (p.in_image ? q.bit_offset == p.bit_offset : q.index == p.index && q.subindex == p.subindex))
            return static_cast<unsigned>(i);
    o.points.push_back(p);
    o.channels = static_cast<unsigned>(o.points.size());
    return o.channels - 1;
}

namespace {

// The value of bit_length bits from bit `from` of bytes, little-endian; sign-extended when the point is
// signed.
double bits_value(const std::uint8_t* bytes, std::uint32_t from, const ImagePoint& p) noexcept {
    std::uint64_t raw = 0;
    for (unsigned b = 0; b < p.bit_length; ++b) {
        const std::uint32_t at = from + b;
        raw |= static_cast<std::uint64_t>((bytes[at / 8] >> (at % 8)) & 1u) << b;
    }
    if (p.is_signed && p.bit_length > 0 && ((raw >> (p.bit_length - 1)) & 1u))
        return static_cast<double>(static_cast<std::int64_t>(raw) - (std::int64_t{1} << p.bit_length));
    return static_cast<double>(raw);
}

// The value of an entry at its place in an image; 0 where the image is shorter or the entry has no place.
double point_value(const std::vector<std::uint8_t>& img, const ImagePoint& p) noexcept {
    if (!p.in_image || p.bit_length == 0 || (p.bit_offset + p.bit_length - 1) / 8 >= img.size()) return 0;
    return bits_value(img.data(), p.bit_offset, p);
}

}  // namespace

double IoBus::output(std::size_t slot, unsigned channel) const noexcept {
    if (slot >= outputs_.size()) return 0;
    const Output& o = outputs_[slot];
    if (!o.image || channel >= o.channels) return 0;
    const std::vector<std::uint8_t>& img = *o.image;
    if (o.kind == ChannelKind::Entries) {
        // A device with a dictionary: the object, in OP (ObjectOutputs); else the place in the image.
        if (o.objects && channel < o.objects->values.size() && o.objects->values[channel])
            return o.objects->in_op ? bits_value(o.objects->values[channel], 0, o.points[channel]) : 0.0;
        return point_value(img, o.points[channel]);
    }
    if (o.kind == ChannelKind::Digital)
        return channel / 8 < img.size() ? static_cast<double>((img[channel / 8] >> (channel % 8)) & 1u) : 0.0;
    return 2 * channel + 1 < img.size()
               ? static_cast<double>(static_cast<std::int16_t>(ld_le16(&img[2 * channel])))
               : 0.0;
}

void IoBus::force(std::size_t slot, unsigned channel, double v) {
    Input& in = inputs_.at(slot);
    in.value.at(channel) = v;
    if (!in.forced.at(channel)) ++forced_channels_;
    in.forced[channel] = 1;
    ++forcing_changes_;
}

void IoBus::release(std::size_t slot, unsigned channel) {
    if (slot < inputs_.size() && channel < inputs_[slot].forced.size() && inputs_[slot].forced[channel]) {
        inputs_[slot].forced[channel] = 0;
        --forced_channels_;
        ++forcing_changes_;
    }
}

bool IoBus::forced(std::size_t slot, unsigned channel, double& v) const noexcept {
    if (slot >= inputs_.size() || channel >= inputs_[slot].forced.size() || !inputs_[slot].forced[channel])
        return false;
    v = inputs_[slot].value[channel];
    return true;
}

InputTerminal::InputTerminal(unsigned output_bytes, unsigned input_bytes, ChannelKind kind,
                             std::vector<InputSource> sources, std::shared_ptr<IoBus> bus, std::size_t slot)
    : ProcessImageApplication(output_bytes, input_bytes),
      kind_(kind),
      sources_(std::move(sources)),
      bus_(std::move(bus)),
      slot_(slot) {
    for (unsigned c = 0; c < sources_.size(); ++c) {
        const InputSource& s = sources_[c];
        const bool constant = s.signal.kind == SignalKind::Constant || s.signal.kind == SignalKind::Wire;
        if (s.wire_slot != IoBus::kNone || !constant) changing_.push_back(c);
    }
}

void InputTerminal::shared_state(std::vector<const void*>& keys) const {
    for (const InputSource& s : sources_)
        if (s.wire_slot != IoBus::kNone) keys.push_back(bus_->output_key(s.wire_slot));
}

void InputTerminal::put(unsigned c, double v, std::vector<std::uint8_t>& img) const {
    if (kind_ == ChannelKind::Digital) {
        if (c / 8 >= img.size()) return;
        const auto bit = static_cast<std::uint8_t>(1u << (c % 8));
        img[c / 8] = static_cast<std::uint8_t>(v > 0.5 ? img[c / 8] | bit : img[c / 8] & ~bit);
    } else {
        if (2 * c + 1 >= img.size()) return;
        const double r = std::isfinite(v) ? round_half_away(std::clamp(v, -32768.0, 32767.0)) : 0.0;
        st_le16(&img[2 * c], static_cast<std::uint16_t>(static_cast<std::int16_t>(r)));
    }
}

void InputTerminal::exchange(std::uint64_t now_ns, ConstBytes outputs, bool apply, Bytes in) {
    const bool first = !started_;
    if (first) {
        started_ = true;
        origin_ns_ = now_ns;
    }
    const std::uint64_t t = now_ns >= origin_ns_ ? now_ns - origin_ns_ : 0;
    std::vector<std::uint8_t>& img = inputs();
    const auto source_value = [&](unsigned c) {
        const InputSource& s = sources_[c];
        return s.wire_slot != IoBus::kNone ? bus_->output(s.wire_slot, s.signal.channel)
                                           : value_at(s.signal, t);
    };
    if (first || bus_->any_forced() || bus_->forcing_changes() != forcing_seen_) {
        forcing_seen_ = bus_->forcing_changes();
        for (unsigned c = 0; c < sources_.size(); ++c) {
            double v = 0;
            if (!bus_->forced(slot_, c, v)) v = source_value(c);
            put(c, v, img);
        }
    } else {
        for (const unsigned c : changing_)
            put(c, source_value(c), img);
    }
    ProcessImageApplication::exchange(now_ns, outputs, apply, in);
}

OutputTerminal::OutputTerminal(unsigned output_bytes, unsigned input_bytes, std::shared_ptr<IoBus> bus,
                               std::size_t slot)
    : ProcessImageApplication(output_bytes, input_bytes), bus_(std::move(bus)), slot_(slot) {
    bus_->publish(slot_, &outputs());
}

OutputTerminal::~OutputTerminal() {
    bus_->withdraw(slot_, &outputs());
}

std::pair<std::size_t, unsigned> InputForcing::target(const faults::FaultSpec& f) const {
    if (f.slave >= seg_.size())
        throw std::invalid_argument("set_input: slave " + std::to_string(f.slave) + " is not on the line");
    const auto* t = dynamic_cast<const ForceableInputs*>(&seg_.slave(f.slave).app());
    if (!t)
        throw std::invalid_argument(
            "set_input: slave " + std::to_string(f.slave) +
            " has no inputs to force (an input terminal, or a drive's touch probe inputs)");
    const auto ch = f.params.find("channel");
    if (ch == f.params.end()) throw std::invalid_argument("set_input: give channel=N");
    unsigned c = 0;
    try {
        std::size_t used = 0;
        const unsigned long v = std::stoul(ch->second, &used, 0);
        if (used != ch->second.size() || v >= t->input_channels()) throw std::out_of_range(ch->second);
        c = static_cast<unsigned>(v);
    } catch (const std::exception&) {
        throw std::invalid_argument("set_input: channel " + ch->second + ": the device has channels 0-" +
                                    std::to_string(t->input_channels() - 1));
    }
    return {t->input_slot(), c};
}

void InputForcing::start(const faults::FaultSpec& f, std::uint64_t) {
    const auto [slot, channel] = target(f);
    const auto v = f.params.find("value");
    if (v == f.params.end()) throw std::invalid_argument("set_input: give value=V");
    double value = 0;
    try {
        std::size_t used = 0;
        value = std::stod(v->second, &used);
        if (used != v->second.size() || !std::isfinite(value)) throw std::invalid_argument(v->second);
    } catch (const std::exception&) {
        throw std::invalid_argument("set_input: value " + v->second + " is no number");
    }
    bus_->force(slot, channel, value);
    seg_.wake_slave(f.slave);
}

void InputForcing::stop(const faults::FaultSpec& f, std::uint64_t) {
    try {
        const auto [slot, channel] = target(f);
        bus_->release(slot, channel);
        seg_.wake_slave(f.slave);
    } catch (const std::invalid_argument&) {
        // The terminal went (a restart keeps its slot: the next start of the fault finds it again).
    }
}

}  // namespace vecat::io
