// An ENI (eni.hpp) made into a network: each Slave element one device entry, cabled as its PreviousPort
// says, so that build_network serves it like a network file (docs/eni.md).
//
// A slave whose identity (vendor, product, revision) a vendor ESI file in the ESI folder describes is that
// ESI's device (dictionary included); any other is made from the ENI alone: a device description with its
// identity, mailbox SyncManagers and protocols, process data SyncManagers, PDOs and entries, from which its
// SII image is generated, and the device is then built from that image as an sii: device is (so a network
// file naming the image, as `vecat network from-eni` writes it, builds the same device).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "device/device_description.hpp"
#include "network/eni.hpp"
#include "network/network_file.hpp"

namespace vecat::network {

struct EniOptions {
    std::string esi_dir;  // vendor ESI files (*.xml) looked up by identity; empty: none
};

struct EniNetwork {
    NetworkFile file;                // device entries in the order the frame reaches them
    std::vector<std::size_t> slave;  // per device: the index of its Slave element in the ENI
    std::vector<std::string> notes;  // "FILE:LINE: PATH: ..." what was guessed or left out
};

// Throws EniError naming the element for a topology that cannot be (a PreviousPort naming no slave, port A,
// two slaves at one port, a loop, an AutoIncAddr the cabling contradicts) and a slave that cannot be made.
EniNetwork network_from_eni(const Eni& eni, const EniOptions& options = {});

// The device description of a slave from its ENI elements alone (what its SII image is generated from).
device::DeviceDescription description_from_eni(const Eni& eni, const EniSlave& s,
                                               std::vector<std::string>& notes);

// The SII image of that description, with the ports of the slave's Physics (ETG.2010 General category,
// PhysicalPorts: one nibble per port, 1 MII, 3 E-bus); ports_used: ports the cabling uses (bit p), made MII
// when the ENI gives no Physics.
std::vector<std::uint8_t> sii_image_from_eni(const device::DeviceDescription& d, const std::string& physics,
                                             std::uint8_t ports_used);

// A network file name for a slave: its Name with what a network file does not allow replaced by '-'.
std::string device_name_from_eni(const std::string& eni_name);

}  // namespace vecat::network

namespace vecat::network {

// `vecat network from-eni`: the network file equivalent to an ENI's network, and the files it names that
// must be written beside it (the SII image of each device made from the ENI alone, NAME.sii). out_folder:
// where the network file goes (ESI paths are written relative to it).
struct EniNetworkFile {
    std::string yaml;
    std::vector<std::pair<std::string, std::vector<std::uint8_t>>> files;  // name in out_folder, bytes
};
EniNetworkFile network_file_from_eni(const Eni& eni, const EniNetwork& n, const std::string& out_folder);

}  // namespace vecat::network
