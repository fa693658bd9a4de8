// The built-in simple devices of network files (src/network): a coupler and a junction without PDI, and
// digital and analog I/O terminals without mailbox, like the Beckhoff EK1100, EK1122, EL1xxx, EL2xxx,
// EL3xxx and EL4xxx, with vecat's vendor ID and their own product codes. Their process data sit in one
// SyncManager each (SM0 outputs, or SM0 inputs; an I/O terminal without mailbox starts at SM0, as the
// EL2004's SII does), mapped by one FMMU.
#pragma once

#include "device/device_description.hpp"

namespace vecat::device {

// Product codes of the built-in devices (vendor 0x00000A3C, as default_drive()).
namespace simple_product {
inline constexpr std::uint32_t Coupler = 0x00001100;
inline constexpr std::uint32_t Junction = 0x00001122;
inline constexpr std::uint32_t DigitalIn = 0x00001000;
inline constexpr std::uint32_t DigitalOut = 0x00002000;
inline constexpr std::uint32_t AnalogIn = 0x00003000;
inline constexpr std::uint32_t AnalogOut = 0x00004000;
}  // namespace simple_product

DeviceDescription coupler();
DeviceDescription junction();
// channels: 1 bit each (digital), 16-bit signed each (analog).
DeviceDescription digital_input_terminal(unsigned channels);
DeviceDescription digital_output_terminal(unsigned channels);
DeviceDescription analog_input_terminal(unsigned channels);
DeviceDescription analog_output_terminal(unsigned channels);

}  // namespace vecat::device
