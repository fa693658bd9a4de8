// ESI (EtherCAT Slave Information, ETG.2000) XML written from a device description: the dictionary
// (communication area generated + application objects), PDOs, SyncManagers, mailbox, DC and EEPROM data.
#pragma once

#include <string>

#include "device/device_description.hpp"

namespace vecat::esi {

// The whole EtherCATInfo document (UTF-8, tab-indented), valid against the ETG schema 1.17.
std::string write_esi(const device::DeviceDescription& d);

// ESI spelling of an entry's data type: "UINT", "STRING(12)"... (strings carry their byte length).
std::string esi_type_name(device::DataType t, unsigned bit_length);

}  // namespace vecat::esi
