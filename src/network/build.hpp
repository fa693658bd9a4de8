// A checked network file (network_file.hpp) made into slaves: each device from its source (the vecat drive,
// an ESI file, an SII dump, a built-in simple device) with its overrides, in the order the frame reaches
// them, in one esc::Segment.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "esc/segment.hpp"
#include "io/terminals.hpp"
#include "network/dictionary_file.hpp"
#include "network/network_file.hpp"

namespace vecat::network {

struct BuiltNetwork {
    std::unique_ptr<esc::Segment> segment;
    // What the I/O terminals share (wires, forced inputs); the handler of the fault set_input goes with it.
    std::shared_ptr<io::IoBus> io;
    std::vector<std::string> notes;  // "FILE:LINE: NAME: ..." what was guessed or left out per device
};

// Throws NetworkFileError ("FILE:LINE: ...") for a device that cannot be made (an ESI without the named
// device, an SII dump that cannot be read, a port cabled that the device does not have). file: the name
// used in the messages.
BuiltNetwork build_network(const NetworkFile& f, const std::string& file);

// A device made from an SII EEPROM image (a dump, or one recovered from a capture): the image served byte
// for byte, the description its categories give (adjust: overrides applied to it), a CoE application when
// the image names CoE (else a bare process image), and the ports of its General category. Throws
// NetworkFileError when the bytes are no SII image.
struct DeviceParts {
    esc::DeviceModel model;
    esc::ApplicationFactory factory;
    esc::EscConfig esc;
};
// Where a device's outputs go for wires (io::OutputsOnBus): this output slot of the bus; none: nowhere.
struct OutputTap {
    std::shared_ptr<io::IoBus> bus;
    std::size_t slot = io::IoBus::kNone;
};
// dictionary: the object dictionary read from the device (a dictionary file) served instead of the
// generated one: exactly its objects, starting at its values, SDO information refused if it says so.
// tap: its outputs shown on the bus (a wire takes one).
DeviceParts device_from_sii(std::vector<std::uint8_t> image, std::vector<std::string>& notes,
                            const std::function<void(device::DeviceDescription&)>& adjust = {},
                            std::shared_ptr<const DeviceDictionary> dictionary = {}, OutputTap tap = {});

// The ESC registers of a network file's esc: key applied to a configuration.
void apply_esc(esc::EscConfig& cfg, const EscOverride& o);

// The ports a device has (bit p: port p), as its ESC's port descriptor (0x0007) says.
std::uint8_t ports_of(const esc::EscConfig& cfg) noexcept;

}  // namespace vecat::network
