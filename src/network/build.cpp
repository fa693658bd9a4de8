#include "network/build.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <type_traits>

#include "cia402/drive.hpp"
#include "coe/coe_application.hpp"
#include "common/file.hpp"
#include "device/from_sii.hpp"
#include "device/hiwin_d2.hpp"
#include "device/simple_devices.hpp"
#include "device/soe_drive.hpp"
#include "esi/esi_reader.hpp"
#include "network/wire_point.hpp"
#include "protocol/data_type.hpp"
#include "protocol/sii.hpp"
#include "soe/soe_drive.hpp"

namespace vecat::network {

namespace {

// Port descriptor 0x0007 (ESC datasheet section II): two bits per port, 00 not implemented, 10 EBUS, 11 MII.
constexpr std::uint8_t kPortMii = 0x3;
constexpr std::uint8_t kPortEbus = 0x2;

std::uint8_t descriptor(std::uint8_t ports, std::uint8_t kind = kPortMii) {
    std::uint8_t d = 0;
    for (unsigned p = 0; p < kPorts; ++p)
        if ((ports >> p) & 1u) d = static_cast<std::uint8_t>(d | (kind << (2 * p)));
    return d;
}

// The ports of an SII device from its General category (ETG.2010: one nibble per port, 0 not used, 1 MII,
// 3 EBUS, 4 fast hot connect); two MII ports when the image has none.
std::uint8_t sii_descriptor(const protocol::SiiInfo& sii) {
    if (!sii.has_general || sii.physical_ports == 0) return descriptor(0b0011);
    std::uint8_t d = 0;
    for (unsigned p = 0; p < kPorts; ++p) {
        const unsigned kind = (sii.physical_ports >> (4 * p)) & 0xF;
        if (kind == 1 || kind == 4)
            d = static_cast<std::uint8_t>(d | (kPortMii << (2 * p)));
        else if (kind == 3)
            d = static_cast<std::uint8_t>(d | (kPortEbus << (2 * p)));
    }
    return d;
}

void apply(device::DeviceDescription& d, const DeviceEntry& e) {
    if (e.identity.vendor_id) d.identity.vendor_id = *e.identity.vendor_id;
    if (e.identity.product_code) d.identity.product_code = *e.identity.product_code;
    if (e.identity.revision) d.identity.revision = *e.identity.revision;
    if (e.identity.serial) d.identity.serial = *e.identity.serial;
    if (e.station_alias) d.station_alias = *e.station_alias;
}

// The overrides written into a dump: identity words 0x08-0x0F and the alias word 0x04, with the
// configuration area's checksum (word 7) made again (ETG.2010).
void patch(std::vector<std::uint8_t>& img, const DeviceEntry& e) {
    if (img.size() < 0x20) return;
    const auto put32 = [&](unsigned word, std::optional<std::uint32_t> v) {
        if (v) st_le32(img.data() + 2 * word, *v);
    };
    put32(protocol::sii::VendorId, e.identity.vendor_id);
    put32(protocol::sii::ProductCode, e.identity.product_code);
    put32(protocol::sii::RevisionNo, e.identity.revision);
    put32(protocol::sii::SerialNo, e.identity.serial);
    if (e.station_alias) {
        st_le16(img.data() + 2 * protocol::sii::StationAlias, *e.station_alias);
        img[2 * protocol::sii::Checksum] = protocol::sii_config_crc(ConstBytes(img.data(), 14));
    }
}

// The CoE details byte of the dump's General category (ETG.2010) as the description has it after its
// quirks: a master that reads the SII learns that the device lacks SDO information or complete access.
void patch_coe_details(std::vector<std::uint8_t>& img, std::uint8_t coe_details) {
    namespace sii = protocol::sii;
    std::size_t at = 2 * sii::FirstCategory;
    while (at + sii::kCategoryHeaderSize <= img.size()) {
        const std::uint16_t id = ld_le16(img.data() + at);
        const std::size_t len = 2u * ld_le16(img.data() + at + 2);
        if (id == sii::kEndMarker) return;
        const std::size_t data = at + sii::kCategoryHeaderSize;
        if ((id & sii::kCategoryIdMask) == static_cast<std::uint16_t>(sii::Category::General)) {
            if (data + sii::general::CoeDetails < img.size() && len > sii::general::CoeDetails)
                img[data + sii::general::CoeDetails] = coe_details;
            return;
        }
        at = data + len;
    }
}

// The device's quirks (quirks:) on its description; a device that cannot have them is refused, naming the
// line of quirks: (at).
void apply_quirks(device::DeviceDescription& d, const DeviceEntry& e, const std::string& at) {
    if (!e.quirks.any()) return;
    if (const std::string why = device::apply_quirks(d, e.quirks); !why.empty())
        throw NetworkFileError(at + "quirks: " + why);
}

std::unique_ptr<esc::Application> process_image(const device::DeviceDescription& d) {
    return std::make_unique<esc::ProcessImageApplication>(d.output_bytes(), d.input_bytes());
}

// Where a CoE application holds an output PDO entry: the value of its object in the dictionary, which the
// process data write wherever the master mapped the entry (coe::ProcessDataMap::copy_outputs) and an SDO
// download where it mapped it nowhere. nullptr when the dictionary has no such entry or it is shorter than
// the point (a wire then reads the entry's place in the image of the default mapping).
template <class App>
const std::uint8_t* object_value(App& app, const io::ImagePoint& p) {
    coe::Entry* e = app.dictionary().find(p.index, p.subindex);
    if (!e || e->capacity() * 8 < p.bit_length) return nullptr;
    return e->storage().data();
}

// An application of type App for a device description, its outputs on the bus when a wire takes them: the
// objects of a CoE application, the image of another.
template <class App, class... Args>
std::unique_ptr<App> make_app(const OutputTap& tap, const device::DeviceDescription& d, Args&&... args) {
    if (tap.slot == io::IoBus::kNone) return std::make_unique<App>(std::forward<Args>(args)...);
    io::ObjectLocator<App> locate = nullptr;
    if constexpr (std::is_base_of_v<coe::CoeApplication, App>) locate = &object_value<App>;
    return std::make_unique<io::OutputsOnBus<App>>(tap.bus, tap.slot, d.output_bytes(), locate,
                                                   std::forward<Args>(args)...);
}

using Made = DeviceParts;

// file: the network file's name, for messages on other lines than the device's (modules:).
Made make_device(const DeviceEntry& e, const std::string& file, const std::string& at,
                 const std::string& quirks_at, std::vector<std::string>& notes, const OutputTap& tap) {
    Made m;
    device::DeviceDescription d;
    bool drive = false;
    switch (e.source) {
        case Source::Drive:
            d = device::default_drive();
            drive = true;
            break;
        case Source::HiwinD2:
            d = device::hiwin_d2();
            drive = true;
            break;
        case Source::SoeDrive:
            d = device::soe_drive();
            break;
        case Source::SoeDrive2:
            d = device::soe_drive(2);
            break;
        case Source::Esi: {
            esi::DeviceSelector sel;
            sel.type = e.esi_type;
            sel.product_code = e.esi_product;
            sel.revision = e.esi_revision;
            if (e.modules_line) {
                sel.modules.emplace();
                for (const auto& chosen : e.modules)
                    sel.modules->push_back(chosen.module);
            }
            try {
                auto r = esi::import_esi_file(e.path, sel);
                for (const auto& n : r.notes)
                    notes.push_back(at + e.path + ": " + n);
                for (const auto& n : esi::complete_for_emulation(r.desc))
                    notes.push_back(at + e.path + ": " + n);
                if (auto b = device::adopt_builtin_rules(r.desc))
                    notes.push_back(at + e.path + ": the built-in " + std::string(*b) +
                                    " by its identity: its behaviour and PDO rules");
                d = std::move(r.desc);
            } catch (const esi::ModuleError& x) {
                // The line of the refused entry of modules:, or of modules: itself.
                const unsigned line =
                    x.entry && *x.entry < e.modules.size() ? e.modules[*x.entry].line : e.modules_line;
                throw NetworkFileError(file + ":" + std::to_string(line) + ": " + e.name +
                                       ": modules: " + x.what());
            } catch (const std::exception& x) {
                throw NetworkFileError(at + e.path + ": " + x.what());
            }
            drive = true;  // as vecat run --esi: the drive core behind the vendor's dictionary
            break;
        }
        case Source::Sii: {
            std::vector<std::uint8_t> img;
            if (e.sii_image) {
                img = *e.sii_image;
            } else {
                std::string why;
                const auto bytes = read_whole_file(e.path, kMaxSiiFileBytes, why);
                if (!bytes) throw NetworkFileError(at + e.path + ": " + why);
                img.assign(bytes->begin(), bytes->end());
            }
            patch(img, e);
            std::shared_ptr<const DeviceDictionary> dict;
            if (!e.dictionary.empty()) {
                try {
                    dict = std::make_shared<const DeviceDictionary>(read_dictionary_file(e.dictionary));
                } catch (const DictionaryFileError& x) {
                    throw NetworkFileError(at + x.what());
                }
            }
            std::vector<std::string> n;
            std::string quirk_error;
            std::uint8_t coe_details = 0;
            const auto adjust = [&](device::DeviceDescription& dd) {
                apply(dd, e);
                if (e.quirks.any()) quirk_error = device::apply_quirks(dd, e.quirks);
                coe_details = dd.coe_details;
            };
            try {
                m = device_from_sii(std::move(img), n, adjust, dict, tap);
            } catch (const NetworkFileError& x) {
                throw NetworkFileError(at + e.path + ": " + x.what());
            }
            if (!quirk_error.empty()) throw NetworkFileError(quirks_at + "quirks: " + quirk_error);
            if (e.quirks.any()) {
                auto patched = *m.model.sii_image;
                patch_coe_details(patched, coe_details);
                m.model.sii_image = std::make_shared<const std::vector<std::uint8_t>>(std::move(patched));
            }
            for (const auto& x : n)
                notes.push_back(at + e.path + ": " + x);
            return m;
        }
        case Source::Coupler:
            d = device::coupler();
            break;
        case Source::Junction:
            d = device::junction();
            break;
        case Source::DigitalIn:
            d = device::digital_input_terminal(channels_of(e));
            break;
        case Source::DigitalOut:
            d = device::digital_output_terminal(channels_of(e));
            break;
        case Source::AnalogIn:
            d = device::analog_input_terminal(channels_of(e));
            break;
        case Source::AnalogOut:
            d = device::analog_output_terminal(channels_of(e));
            break;
    }
    apply(d, e);
    apply_quirks(d, e, quirks_at);
    m.model = esc::DeviceModel::of(d);
    m.esc.port_descriptor =
        descriptor(default_ports(e.source), e.source == Source::Drive || e.source == Source::HiwinD2 ||
                                                    e.source == Source::SoeDrive ||
                                                    e.source == Source::SoeDrive2 || e.source == Source::Esi
                                                ? kPortMii
                                                : kPortEbus);
    if (drive)
        m.factory = [objects = m.model.dictionary, tap](const device::DeviceDescription& dd) {
            return std::unique_ptr<esc::Application>(make_app<cia402::Drive>(tap, dd, dd, objects));
        };
    else if (e.source == Source::SoeDrive || e.source == Source::SoeDrive2)
        m.factory = soe::make_soe_drive;
    else
        m.factory = process_image;
    return m;
}

}  // namespace

DeviceParts device_from_sii(std::vector<std::uint8_t> img, std::vector<std::string>& notes,
                            const std::function<void(device::DeviceDescription&)>& adjust,
                            std::shared_ptr<const DeviceDictionary> dictionary, OutputTap tap) {
    const protocol::SiiInfo sii = protocol::parse_sii(img);
    if (img.size() < 0x80 || !sii.checksum_ok || sii.identity.vendor_id == 0)
        throw NetworkFileError("not an SII image (" + std::to_string(img.size()) + " bytes, checksum " +
                               (sii.checksum_ok ? "right" : "wrong") + ", vendor " +
                               std::to_string(sii.identity.vendor_id) + ")");
    DeviceParts m;
    device::DeviceDescription d = device::description_from_sii(sii, &notes);
    d.eeprom_size_bytes = static_cast<std::uint32_t>(img.size());
    if (adjust) adjust(d);
    const bool coe = (d.mailbox_protocols & device::mbx_proto::CoE) != 0;
    if (dictionary && !coe) {
        notes.push_back("dictionary: not used, the SII names no CoE mailbox");
        dictionary.reset();
    }
    if (dictionary) d.objects = dictionary->objects;
    m.model = esc::DeviceModel::of(d);
    m.model.sii_image = std::make_shared<const std::vector<std::uint8_t>>(std::move(img));
    m.esc.port_descriptor = sii_descriptor(sii);
    if (dictionary) {
        // Exactly the objects read, none generated; the values uploaded set after the dictionary is made,
        // so that SDO information still reports the described defaults. The mapping is read again from them.
        m.model.dictionary =
            std::make_shared<const std::vector<device::ObjectDescription>>(dictionary->objects);
        m.factory = [objects = m.model.dictionary, dictionary, tap](const device::DeviceDescription& dd) {
            auto app = make_app<coe::CoeApplication>(tap, dd, dd, objects);
            for (const auto& [at, bytes] : dictionary->values)
                if (coe::Entry* e = app->dictionary().find(at.first, at.second))
                    e->assign(ConstBytes(bytes.data(), bytes.size()));
            app->process_data().rebuild();
            if (!dictionary->sdo_information) app->sdo_server().set_information_served(false);
            return std::unique_ptr<esc::Application>(std::move(app));
        };
    } else if (coe)
        m.factory = [objects = m.model.dictionary, tap](const device::DeviceDescription& dd) {
            return std::unique_ptr<esc::Application>(make_app<coe::CoeApplication>(tap, dd, dd, objects));
        };
    else
        m.factory = [tap](const device::DeviceDescription& dd) {
            return std::unique_ptr<esc::Application>(
                make_app<esc::ProcessImageApplication>(tap, dd, dd.output_bytes(), dd.input_bytes()));
        };
    return m;
}

void apply_esc(esc::EscConfig& cfg, const EscOverride& o) {
    if (o.type) cfg.type = *o.type;
    if (o.revision) cfg.revision = *o.revision;
    if (o.build) cfg.build = *o.build;
    if (o.fmmus) cfg.fmmu_count = *o.fmmus;
    if (o.syncmanagers) cfg.sm_count = *o.syncmanagers;
    if (o.ram_kib) cfg.ram_bytes = 1024u * *o.ram_kib;
    if (o.port_descriptor) cfg.port_descriptor = *o.port_descriptor;
    if (o.features) cfg.features = *o.features;
    if (o.sii_read_bytes) cfg.sii_read_8_bytes = *o.sii_read_bytes == 8;
}

std::uint8_t ports_of(const esc::EscConfig& cfg) noexcept {
    std::uint8_t ports = 0;
    for (unsigned p = 0; p < kPorts; ++p)
        if ((cfg.port_descriptor >> (2 * p)) & 0x3) ports = static_cast<std::uint8_t>(ports | (1u << p));
    return ports;
}

// A vecat drive of a network file: its touch probe inputs follow their sources (inputs: on a drive) each
// servo period and can be forced (fault set_input, ForceableInputs), and its digital outputs 0x60FE show on
// the bus when a wire takes one.
class WiredDrive final : public cia402::Drive, public io::ForceableInputs {
  public:
    WiredDrive(const device::DeviceDescription& d,
               std::shared_ptr<const std::vector<device::ObjectDescription>> objects,
               std::vector<io::InputSource> probes, std::shared_ptr<io::IoBus> bus, std::size_t input_slot,
               std::size_t output_slot)
        : Drive(d, std::move(objects)),
          probes_(std::move(probes)),
          bus_(std::move(bus)),
          input_slot_(input_slot),
          slot_(output_slot) {
        if (slot_ != io::IoBus::kNone) {
            publish_digital_outputs();
            bus_->publish(slot_, &digital_output_image());
        }
    }
    ~WiredDrive() override {
        if (slot_ != io::IoBus::kNone) bus_->withdraw(slot_, &digital_output_image());
    }
    WiredDrive(const WiredDrive&) = delete;
    WiredDrive& operator=(const WiredDrive&) = delete;
    std::size_t input_slot() const override { return input_slot_; }
    unsigned input_channels() const override { return kDriveProbeInputs; }
    // Its digital outputs when a wire takes them, and the outputs its touch probe inputs are wired to.
    void shared_state(std::vector<const void*>& keys) const override {
        Drive::shared_state(keys);
        if (slot_ != io::IoBus::kNone) keys.push_back(bus_->output_key(slot_));
        for (const io::InputSource& s : probes_)
            if (s.wire_slot != io::IoBus::kNone) keys.push_back(bus_->output_key(s.wire_slot));
    }

  protected:
    // A forced input reads its value; the others their sources (none: 0). The drive ORs them with 0x2100:6.
    std::optional<std::uint8_t> wired_probe_inputs(std::uint64_t sim_ns) override {
        std::uint8_t bits = 0;
        if (probes_.empty() && !bus_->any_forced()) return bits;
        for (unsigned c = 0; c < kDriveProbeInputs; ++c) {
            double v = 0;
            if (!bus_->forced(input_slot_, c, v) && !probes_.empty()) {
                const io::InputSource& s = probes_[c];
                v = s.wire_slot != io::IoBus::kNone ? bus_->output(s.wire_slot, s.signal.channel)
                                                    : io::value_at(s.signal, sim_ns);
            }
            if (v > 0.5) bits = static_cast<std::uint8_t>(bits | (1u << c));
        }
        return bits;
    }

  private:
    std::vector<io::InputSource> probes_;  // touch probe inputs 1 and 2 (empty: not wired)
    std::shared_ptr<io::IoBus> bus_;
    std::size_t input_slot_;  // its touch probe inputs on the bus (forced values)
    std::size_t slot_;        // the output slot of its digital outputs (kNone: no wire takes them)
};

// The built-in I/O terminals get their behaviour (src/io): output terminals show their outputs on the bus,
// input terminals read their signals, wires and forced values. So does a vecat drive that has wires.
void attach_io(const DeviceEntry& e, Made& m, BuiltNetwork& b) {
    if (e.source == Source::Drive) {
        const std::size_t slot = b.io->output_slot(e.name);
        const std::size_t input_slot = b.io->add_input(e.name, kDriveProbeInputs);
        std::vector<io::InputSource> probes;
        if (!e.inputs.empty()) probes.resize(kDriveProbeInputs);
        for (const auto& in : e.inputs) {
            probes[in.channel].signal = in.signal;
            if (in.signal.kind == io::SignalKind::Wire)
                probes[in.channel].wire_slot = b.io->output_slot(in.signal.device);
        }
        m.factory = [objects = m.model.dictionary, probes, bus = b.io, input_slot,
                     slot](const device::DeviceDescription& d) -> std::unique_ptr<esc::Application> {
            return std::make_unique<WiredDrive>(d, objects, probes, bus, input_slot, slot);
        };
        return;
    }
    const bool digital = e.source == Source::DigitalIn || e.source == Source::DigitalOut;
    const io::ChannelKind kind = digital ? io::ChannelKind::Digital : io::ChannelKind::Analog;
    const unsigned channels = channels_of(e);
    if (e.source == Source::DigitalOut || e.source == Source::AnalogOut) {
        const std::size_t slot = b.io->output_slot(e.name);
        m.factory = [bus = b.io,
                     slot](const device::DeviceDescription& d) -> std::unique_ptr<esc::Application> {
            return std::make_unique<io::OutputTerminal>(d.output_bytes(), d.input_bytes(), bus, slot);
        };
    } else if (e.source == Source::DigitalIn || e.source == Source::AnalogIn) {
        std::vector<io::InputSource> sources(channels);
        for (const auto& in : e.inputs) {
            sources[in.channel].signal = in.signal;
            if (in.signal.kind == io::SignalKind::Wire)
                sources[in.channel].wire_slot = b.io->output_slot(in.signal.device);
        }
        const std::size_t slot = b.io->add_input(e.name, channels);
        m.factory = [bus = b.io, slot, kind,
                     sources](const device::DeviceDescription& d) -> std::unique_ptr<esc::Application> {
            return std::make_unique<io::InputTerminal>(d.output_bytes(), d.input_bytes(), kind, sources, bus,
                                                       slot);
        };
    }
}

BuiltNetwork build_network(const NetworkFile& f, const std::string& file) {
    BuiltNetwork b;
    b.segment = std::make_unique<esc::Segment>();
    b.io = std::make_shared<io::IoBus>();
    for (const DeviceEntry& e : f.devices)
        if (e.source == Source::DigitalOut || e.source == Source::AnalogOut)
            b.io->add_output(
                e.name, e.source == Source::DigitalOut ? io::ChannelKind::Digital : io::ChannelKind::Analog,
                channels_of(e));
    // A drive's digital outputs are on the bus when a wire takes one of them.
    for (const DeviceEntry& e : f.devices)
        if (e.source == Source::Drive && b.io->output_slot(e.name) == io::IoBus::kNone)
            for (const DeviceEntry& other : f.devices)
                for (const auto& in : other.inputs)
                    if (in.signal.kind == io::SignalKind::Wire && in.signal.device == e.name &&
                        b.io->output_slot(e.name) == io::IoBus::kNone)
                        b.io->add_output(e.name, io::ChannelKind::Digital, kDriveDigitalOutputs);
    // A device of an ESI file or SII dump shows its outputs on the bus when a wire takes one of them.
    const auto from_file = [](const DeviceEntry& e) {
        return e.source == Source::Esi || e.source == Source::Sii;
    };
    for (const DeviceEntry& e : f.devices)
        if (from_file(e))
            for (const DeviceEntry& other : f.devices)
                for (const auto& in : other.inputs)
                    if (in.signal.kind == io::SignalKind::Wire && in.signal.device == e.name &&
                        b.io->output_slot(e.name) == io::IoBus::kNone)
                        b.io->add_output(e.name, io::ChannelKind::Entries, 0);
    std::vector<Made> made;
    for (const DeviceEntry& e : f.devices) {
        const std::string at = file + ":" + std::to_string(e.line) + ": " + e.name + ": ";
        const std::string quirks_at = file + ":" + std::to_string(e.quirks_line) + ": " + e.name + ": ";
        const OutputTap tap{b.io, from_file(e) ? b.io->output_slot(e.name) : io::IoBus::kNone};
        made.push_back(make_device(e, file, at, quirks_at, b.notes, tap));
    }
    // The wires to them: each its point of the device's image, the channel the reading device asks the bus.
    std::vector<DeviceEntry> wired = f.devices;
    for (DeviceEntry& e : wired)
        for (auto& in : e.inputs) {
            if (in.signal.kind != io::SignalKind::Wire) continue;
            const auto target = std::find_if(f.devices.begin(), f.devices.end(), [&](const DeviceEntry& o) {
                return o.name == in.signal.device;
            });
            if (target == f.devices.end() || !from_file(*target)) continue;
            const Made& t = made[static_cast<std::size_t>(target - f.devices.begin())];
            const auto& d = *t.model.description;
            // A CoE mailbox: a master may assign other RxPDOs, whose objects the device's application holds.
            const bool coe = (d.mailbox_protocols & device::mbx_proto::CoE) != 0;
            const std::string at = file + ":" + std::to_string(in.line) + ": " + e.name + ": ";
            in.signal.channel = b.io->add_point(
                b.io->output_slot(target->name),
                wire_point(d, coe ? t.model.dictionary.get() : nullptr, target->name, in.signal, at));
        }
    std::vector<std::uint8_t> ports;
    for (std::size_t i = 0; i < wired.size(); ++i) {
        const DeviceEntry& e = wired[i];
        const std::string at = file + ":" + std::to_string(e.line) + ": " + e.name + ": ";
        Made& m = made[i];
        attach_io(e, m, b);
        apply_esc(m.esc, e.esc);
        if (e.esc.ram_kib && *e.esc.ram_kib == 0)
            b.notes.push_back(
                at + "esc: ram_kib 0: the emulated ESC has at least 1 KiB of process RAM and reports 1");
        ports.push_back(ports_of(m.esc));
        b.segment->add(std::make_unique<esc::Slave>(m.model, m.esc, m.factory(*m.model.description)),
                       m.factory);
    }
    // The cabling: the segment routes the frame through the tree.
    std::vector<std::uint8_t> up_ports;
    std::vector<std::uint32_t> delays;
    for (const DeviceEntry& e : f.devices) {
        up_ports.push_back(static_cast<std::uint8_t>(e.upstream_port));
        delays.push_back(e.cable_delay_ns);
    }
    std::string why;
    if (!b.segment->set_topology(f.parent, up_ports, delays, &why))
        throw NetworkFileError(file + ": " + why);  // the reader's order is the segment's: not expected
    for (std::size_t i = 0; i < f.devices.size(); ++i)
        if (!f.devices[i].hot_connect.empty()) b.segment->add_hot_connect_group(f.devices[i].hot_connect, i);
    if (f.redundancy_device >= 0) {
        const auto i = static_cast<std::size_t>(f.redundancy_device);
        if (!((ports[i] >> f.redundancy_port) & 1u) || !b.segment->set_redundancy(i, f.redundancy_port, &why))
            throw NetworkFileError(file + ":" + std::to_string(f.redundancy_line) + ": redundancy: " +
                                   f.devices[i].name + " has no port " + std::to_string(f.redundancy_port));
    }
    // The cabling against the ports each device turned out to have.
    for (std::size_t i = 0; i < f.devices.size(); ++i)
        for (unsigned p = 1; p < kPorts; ++p)
            if (const int c = f.children[i][p]; c >= 0 && !((ports[i] >> p) & 1u)) {
                const DeviceEntry& child = f.devices[static_cast<std::size_t>(c)];
                throw NetworkFileError(file + ":" + std::to_string(child.line) + ": " + child.name + ": " +
                                       f.devices[i].name + " has no port " + std::to_string(p));
            }
    return b;
}

}  // namespace vecat::network
