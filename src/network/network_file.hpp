// The network description file (vecat run --network FILE): the devices of a machine and how their ports
// are cabled, a tree rooted at the master. YAML; examples in examples/networks/, the format in
// docs/network-file.md. This part only reads and checks the file; build.hpp makes the slaves.
//
//   devices:
//     - name: coupler
//       device: coupler              # built in: drive, coupler, junction, digital-in, digital-out,
//     - name: io1                    #   analog-in, analog-out
//       device: digital-out
//       channels: 8
//       upstream: coupler:3          # this device's port 0 is cabled to port 3 of coupler
//     - name: axis                   # without upstream: the device before it in the list, port 1
//       esi: drives/vendor.xml       # or sii: dumps/el2004.bin
//       type: VENDOR-DRIVE-1
//       modules: [0x110, empty]      # a modular device: the module of each slot (Type or ModuleIdent)
//     - name: copy                   # a device read by vecat clone: its SII, its dictionary, its ESC
//       sii: copy.sii.bin
//       dictionary: copy.dictionary.yaml
//       esc: {type: 0x11, port_descriptor: 0x0f}
//       quirks: [no_sdo_info, max_pdo_entries=8]   # device/quirks.hpp
//   redundancy: axis:1               # optional: this port cabled back to the master's second port
//
// Every problem is reported with the line of the file it is on; nothing half-checked is returned.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "device/quirks.hpp"
#include "io/signal.hpp"

namespace vecat::network {

// Where a device comes from.
enum class Source : std::uint8_t {
    Drive,       // the built-in vecat CiA 402 drive
    HiwinD2,     // built in: the HIWIN D2 CoE drive (device/hiwin_d2.hpp) on the vecat drive core
    SoeDrive,    // built in: the AX5000-like SoE drive (device/soe_drive.hpp, src/soe)
    SoeDrive2,   // built in: the same with two axes, drive numbers 0 and 1 (AX5206-like)
    Esi,         // a device of a vendor ESI file (type / product / revision)
    Sii,         // a raw SII EEPROM dump, with the process data its categories describe
    Coupler,     // built in: EK1100-like coupler without PDI
    Junction,    // built in: EK1122-like 4-port junction without PDI
    DigitalIn,   // built in: digital input terminal
    DigitalOut,  // built in: digital output terminal
    AnalogIn,    // built in: analog input terminal (16-bit channels)
    AnalogOut,   // built in: analog output terminal (16-bit channels)
};
std::string_view to_string(Source s) noexcept;

inline constexpr unsigned kPorts = 4;
inline constexpr unsigned kMaxChannels = 64;
inline constexpr std::uint32_t kDefaultCableDelayNs = 500;  // esc::Segment::hop_delay_ns

struct IdentityOverride {
    std::optional<std::uint32_t> vendor_id, product_code, revision, serial;
};

// The ESC's own registers 0x0000-0x0009 (type, revision, build, FMMU and SyncManager counts, RAM size, port
// descriptor, features) and the SII read size (0x0502 bit 6), when a device's must be those of a real one
// (vecat clone writes them): every one given replaces the default of the device's source.
struct EscOverride {
    std::optional<std::uint8_t> type, revision;
    std::optional<std::uint16_t> build;
    std::optional<std::uint8_t> fmmus, syncmanagers, ram_kib, port_descriptor;
    std::optional<std::uint16_t> features;
    std::optional<unsigned> sii_read_bytes;  // 4 or 8
    bool any() const {
        return type || revision || build || fmmus || syncmanagers || ram_kib || port_descriptor || features ||
               sii_read_bytes;
    }
};

struct DeviceEntry {
    unsigned line = 0;  // of the entry in the file
    std::string name;
    Source source = Source::Drive;
    std::string path;  // esi: / sii: file, relative paths resolved against the file's folder
    std::optional<std::string> esi_type;
    std::optional<std::uint32_t> esi_product, esi_revision;
    // esi: of a modular device (modules:): the module of each slot in slot order, a module Type or
    // ModuleIdent; nullopt: the slot empty. Checked against the ESI file when the device is built.
    struct SlotModule {
        std::optional<std::string> module;
        unsigned line = 0;
    };
    std::vector<SlotModule> modules;
    unsigned modules_line = 0;  // of modules: (0: not given, every slot its default module)
    unsigned channels = 0;      // built-in I/O terminals (0: the kind's default)
    // Cabling: this device's port 0 to port upstream_port of upstream (empty: the master).
    std::string upstream;
    unsigned upstream_port = 1;
    std::uint32_t cable_delay_ns = kDefaultCableDelayNs;  // of the cable into port 0
    std::optional<std::uint16_t> station_alias;
    IdentityOverride identity;
    // sii: the object dictionary from a dictionary file (dictionary_file.hpp) instead of the one generated
    // from the SII's PDOs; empty: none. Resolved like path.
    std::string dictionary;
    unsigned dictionary_line = 0;
    EscOverride esc;
    // Hot connect: this device and everything downstream of it form the group of this name, which can be
    // unplugged and plugged back at run time (fault unplug group=NAME). Empty: none.
    std::string hot_connect;
    unsigned hot_connect_line = 0;
    // Built-in input terminals: what a channel reads (inputs:, docs/network-file.md); channels not named read
    // 0. A wire names an output terminal of the file (io::Signal::device, channel).
    struct Input {
        unsigned channel = 0;
        io::Signal signal;
        unsigned line = 0;
    };
    std::vector<Input> inputs;
    unsigned inputs_line = 0;
    // What the device does less completely (quirks:, device/quirks.hpp); applied when it is made.
    device::Quirks quirks;
    unsigned quirks_line = 0;
    // An sii: device whose image is given here instead of a file (a device made from an ENI alone,
    // network/eni_network.hpp); path is then only its name in messages.
    std::shared_ptr<const std::vector<std::uint8_t>> sii_image;
};

// The checked file. devices are in the order the frame reaches them (the first is cabled to the master,
// then depth first through each device's ports in the ESC's order 0 -> 3 -> 1 -> 2): the slaves' positions.
struct NetworkFile {
    std::string folder;  // of the file, for relative paths
    std::vector<DeviceEntry> devices;
    std::vector<int> parent;  // per device: index of its upstream device, -1: the master
    std::vector<std::array<int, kPorts>> children;  // per device and port: the device cabled there, -1: none
    // Cable redundancy (top-level `redundancy: NAME:PORT`): this free port of this device is cabled back
    // to the master's second port (vecat run --redundant-iface). -1: no redundancy cable.
    int redundancy_device = -1;
    unsigned redundancy_port = 1;
    unsigned redundancy_line = 0;
};

// The channels of a built-in I/O terminal: channels:, or its kind's default (8 digital, 4 analog).
unsigned channels_of(const DeviceEntry& d) noexcept;
// The vecat drive in wires: its touch probe inputs 1 and 2 are its input channels 0 and 1 (inputs:), the 32
// bits of its digital outputs 0x60FE (CiA 402 6.3.9) its output channels.
inline constexpr unsigned kDriveProbeInputs = 2;
inline constexpr unsigned kDriveDigitalOutputs = 32;
// Channels an inputs: entry may name on the device, and a wire may take from it (0: none).
unsigned input_channels(const DeviceEntry& d) noexcept;
unsigned output_channels(const DeviceEntry& d) noexcept;

class NetworkFileError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// Reads and checks a file, or the text of one (folder: where relative paths start). Throws NetworkFileError
// with "FILE:LINE: what is wrong".
NetworkFile read_network_file(const std::string& path);
NetworkFile parse_network(const std::string& yaml_text, const std::string& name = "<network>",
                          const std::string& folder = ".");

// The cabling and the order of devices already read (by the YAML reader, or from an ENI): each device's
// upstream (name) and upstream_port where explicit_upstream[i], the device before it, port 1, otherwise.
// Checks names, ports, double cabling and loops; refusals are "NAME:LINE: ..." with the device's line.
NetworkFile arrange_network(std::vector<DeviceEntry> devices, const std::vector<bool>& explicit_upstream,
                            const std::string& name, const std::string& folder = ".");

// The ports a device of this source has (bit p: port p), before its SII or ESI is read: a drive and the
// I/O terminals 0 and 1, the coupler 0, 1 and 3 (E-bus), the junction all four. ESI and SII devices: all
// four here; the build checks the cabling against the ports the device describes.
std::uint8_t default_ports(Source s) noexcept;

}  // namespace vecat::network
