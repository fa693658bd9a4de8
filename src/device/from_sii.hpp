// A device description from the SII EEPROM image of a real device (a dump): what a network file's sii:
// device is emulated from. The image itself stays what the ESC serves (byte for byte); the description
// gives the slave its SyncManagers, FMMUs, process data and, for a CoE device, the communication objects
// the dictionary generates from them (device::dictionary_objects).
#pragma once

#include <string>
#include <vector>

#include "device/device_description.hpp"
#include "protocol/sii.hpp"

namespace vecat::device {

// What the image describes, and notes on what it leaves out (no PDO of a process data SyncManager, ...).
DeviceDescription description_from_sii(const protocol::SiiInfo& sii,
                                       std::vector<std::string>* notes = nullptr);

}  // namespace vecat::device
