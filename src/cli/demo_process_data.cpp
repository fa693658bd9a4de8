#include "cli/demo_process_data.hpp"

#include <fmt/core.h>

#include "common/bytes.hpp"
#include "master/coe_client.hpp"
#include "protocol/cia402_objects.hpp"
#include "protocol/objects.hpp"

namespace vecat::cli {
namespace {

namespace obj = protocol::obj;

// CiA 402's device profile number in the low word of the device type (CiA 301 7.5.2.1).
constexpr std::uint32_t kProfile402 = 402;

template <class Object>
int byte_offset(const std::vector<master::MappedEntry>& entries, Object o) {
    const master::MappedEntry* e = master::find_entry(entries, o.index, o.subindex);
    const unsigned bits = protocol::fixed_bit_length(o.type);
    if (!e || e->bit_offset % 8 != 0 || e->bits != bits) return -1;
    return static_cast<int>(e->bit_offset / 8);
}

bool fits(int offset, std::size_t bytes, std::size_t size) {
    return offset >= 0 && static_cast<std::size_t>(offset) + bytes <= size;
}

}  // namespace

DriveLayout layout_from_entries(const master::SlaveInfo& s, std::size_t slave) {
    DriveLayout l;
    l.slave = slave;
    l.controlword = byte_offset(s.out_entries, obj::controlword);
    l.mode = byte_offset(s.out_entries, obj::modes_of_operation);
    l.target = byte_offset(s.out_entries, obj::target_position);
    l.statusword = byte_offset(s.in_entries, obj::statusword);
    l.mode_display = byte_offset(s.in_entries, obj::modes_of_operation_display);
    l.position = byte_offset(s.in_entries, obj::position_actual_value);
    l.velocity = byte_offset(s.in_entries, obj::velocity_actual_value);
    l.following_error = byte_offset(s.in_entries, obj::following_error_actual_value);
    l.error_code = byte_offset(s.in_entries, obj::error_code);
    return l;
}

void Axis::write_outputs(Bytes o) const {
    const auto& l = layout;
    if (fits(l.controlword, 2, o.size())) st_le16(o.data() + l.controlword, controlword);
    if (fits(l.mode, 1, o.size())) o[static_cast<std::size_t>(l.mode)] = static_cast<std::uint8_t>(mode);
    if (fits(l.target, 4, o.size())) st_le32(o.data() + l.target, static_cast<std::uint32_t>(target));
}

void Axis::read_inputs(ConstBytes in) {
    const auto& l = layout;
    if (fits(l.statusword, 2, in.size())) statusword = ld_le16(in.data() + l.statusword);
    if (fits(l.mode_display, 1, in.size()))
        mode_display = static_cast<std::int8_t>(in[static_cast<std::size_t>(l.mode_display)]);
    if (fits(l.position, 4, in.size())) position = static_cast<std::int32_t>(ld_le32(in.data() + l.position));
    if (fits(l.velocity, 4, in.size())) velocity = static_cast<std::int32_t>(ld_le32(in.data() + l.velocity));
    if (fits(l.following_error, 4, in.size()))
        following_error = static_cast<std::int32_t>(ld_le32(in.data() + l.following_error));
    if (fits(l.error_code, 2, in.size())) error_code = ld_le16(in.data() + l.error_code);
}

std::vector<Axis> find_drives(master::Master& m, std::vector<std::string>& notes) {
    std::vector<Axis> drives;
    auto& slaves = m.slaves();
    for (std::size_t i = 0; i < slaves.size(); ++i) {
        const auto& s = slaves[i];
        if (!(s.sii.mailbox_protocols & protocol::sii::MailboxCoE) || !s.sii.std_rx_mbx_size) continue;
        master::CoeClient c(m, s.station);
        const auto r = c.upload(obj::device_type.index, 0);
        if (!r.ok() || r.data.size() < 4 || (ld_le32(r.data.data()) & 0xFFFF) != kProfile402) continue;
        Axis a;
        a.layout = layout_from_entries(s, i);
        if (!a.layout.movable()) {
            notes.push_back(
                fmt::format("slave {} \"{}\": a CiA 402 drive, not moved: its PDOs lack the controlword, "
                            "target position, "
                            "statusword or position actual value",
                            i, s.sii.device_name()));
            continue;
        }
        // Without the mode in the PDOs the mode is set once by SDO (CSP).
        if (a.layout.mode < 0) {
            const std::uint8_t csp = static_cast<std::uint8_t>(a.mode);
            const auto w = c.download(obj::modes_of_operation.index, 0, ConstBytes(&csp, 1));
            if (!w.ok()) {
                notes.push_back(fmt::format(
                    "slave {} \"{}\": a CiA 402 drive, not moved: the mode (0x{:04X}) is not in its PDOs and "
                    "the SDO that sets it failed",
                    i, s.sii.device_name(), obj::modes_of_operation.index));
                continue;
            }
        }
        notes.push_back(
            fmt::format("slave {} \"{}\": CiA 402 drive; controlword at output byte {}, target at {}, "
                        "statusword at input "
                        "byte {}, position at {}{}",
                        i, s.sii.device_name(), a.layout.controlword, a.layout.target, a.layout.statusword,
                        a.layout.position, a.layout.mode < 0 ? "; mode CSP set by SDO" : ""));
        drives.push_back(a);
    }
    return drives;
}

IoExercise::IoExercise(master::Master& m, const std::vector<Axis>& drives) {
    const auto& slaves = m.slaves();
    for (std::size_t i = 0; i < slaves.size(); ++i) {
        bool drive = false;
        for (const auto& d : drives)
            drive = drive || d.layout.slave == i;
        if (!drive && (slaves[i].out_bytes || slaves[i].in_bytes))
            slaves_.push_back(Terminal{i, {}, 0, false});
    }
}

void IoExercise::write_outputs(master::Master& m, unsigned step) const {
    for (const auto& t : slaves_) {
        auto out = m.outputs(t.slave);
        const auto& entries = m.slaves()[t.slave].out_entries;
        // The walking bit moves every 100 cycles over the 1-bit entries; 16-bit entries count up.
        std::size_t bit_index = 0, bit_count = 0;
        for (const auto& e : entries)
            bit_count += e.bits == 1 && e.index != 0;
        for (const auto& e : entries) {
            if (e.index == 0) continue;
            const std::size_t byte = e.bit_offset / 8;
            if (e.bits == 1 && byte < out.size()) {
                const bool on = bit_count && (step / 100) % bit_count == bit_index++;
                const auto mask = static_cast<std::uint8_t>(1u << (e.bit_offset % 8));
                out[byte] = static_cast<std::uint8_t>(on ? out[byte] | mask : out[byte] & ~mask);
            } else if (e.bits == 16 && e.bit_offset % 8 == 0 && byte + 2 <= out.size()) {
                st_le16(out.data() + byte, static_cast<std::uint16_t>(step * 64));
            }
        }
    }
}

void IoExercise::read_inputs(master::Master& m) {
    for (auto& t : slaves_) {
        const auto in = m.inputs(t.slave);
        if (t.seen && !std::equal(in.begin(), in.end(), t.last_inputs.begin(), t.last_inputs.end()))
            ++t.changes;
        t.last_inputs.assign(in.begin(), in.end());
        t.seen = true;
    }
}

std::uint64_t IoExercise::input_changes() const {
    std::uint64_t n = 0;
    for (const auto& t : slaves_)
        n += t.changes;
    return n;
}

std::vector<std::string> IoExercise::report(master::Master& m) const {
    auto hex = [](ConstBytes b) {
        std::string s;
        for (std::size_t i = 0; i < b.size() && i < 16; ++i)
            s += fmt::format("{:02X}", b[i]);
        return b.size() > 16 ? s + "..." : s;
    };
    std::vector<std::string> lines;
    for (const auto& t : slaves_) {
        const auto& s = m.slaves()[t.slave];
        std::string line = fmt::format("slave {} \"{}\":", t.slave, s.sii.device_name());
        if (s.out_bytes)
            line += fmt::format(" outputs {} ({} bytes written)", hex(m.outputs(t.slave)), s.out_bytes);
        if (s.in_bytes)
            line += fmt::format(" inputs {} ({} bytes), changed in {} cycles", hex(m.inputs(t.slave)),
                                s.in_bytes, t.changes);
        lines.push_back(std::move(line));
    }
    return lines;
}

}  // namespace vecat::cli
