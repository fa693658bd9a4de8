// vecat clone: a line read with the project's master (real hardware, or another vecat) and written as a
// network file that `vecat run --network` serves as a copy: per device its whole SII image, its ESC
// registers, its place in the tree and the delay of its cable, and for a CoE device its object dictionary
// with the values read (SDO information and uploads, in PREOP). docs/clone.md describes what is read and
// what is not.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "master/master.hpp"
#include "network/dictionary_file.hpp"
#include "network/network_file.hpp"

namespace vecat::clone {

struct ClonedDevice {
    std::string name;               // in the network file; the files are NAME.sii.bin, NAME.dictionary.yaml
    std::string description;        // the SII's device name, for the comments
    std::vector<std::uint8_t> sii;  // the whole EEPROM, as large as its word 0x003E says
    network::EscOverride esc;       // the ESC's registers 0x0000-0x0009 and its SII read size
    std::uint16_t station_alias = 0;
    int parent = -1;  // position of the upstream device, -1: the master
    unsigned parent_port = 1;
    std::optional<std::uint32_t> cable_delay_ns;          // measured with DC; none without
    std::optional<network::DeviceDictionary> dictionary;  // CoE devices
    std::vector<std::string> missing;  // what could not be read (also in dictionary->missing)
};

struct CloneResult {
    std::vector<ClonedDevice> devices;  // in line order (positions)
    std::vector<std::string> notes;     // about the line
};

struct CloneOptions {
    // Progress lines ("slave 3: 212 objects"); none when empty.
    std::function<void(const std::string&)> progress;
};

// Reads the line behind the master's link: start-up to PREOP, then every device. Throws std::runtime_error
// when the line cannot be brought to PREOP (no device, a device refusing PREOP); a device that refuses
// part of what is read (SDO information, an upload) is copied with what could be read and says what is
// missing.
CloneResult read_line(master::Master& m, const CloneOptions& opt = {});

// One device's dictionary through the master's CoE client (SDO information, then uploads; without SDO
// information the objects generated from its SII and the standard ones, uploaded). For tests too.
network::DeviceDictionary read_dictionary(master::Master& m, std::size_t slave,
                                          std::vector<std::string>& missing);

// Writes DIR/network.yaml, DIR/NAME.sii.bin and DIR/NAME.dictionary.yaml (the folder is made). Throws
// std::runtime_error when a file cannot be written. Returns the path of the network file.
std::string write_clone(const CloneResult& r, const std::string& dir);

// The network file's text alone (relative file names).
std::string network_text(const CloneResult& r);

}  // namespace vecat::clone
