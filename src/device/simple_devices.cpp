#include "device/simple_devices.hpp"

#include <string>

namespace vecat::device {

namespace {

constexpr std::uint32_t kVendor = 0x00000A3C;  // vecat, as default_drive()

DeviceDescription base(std::uint32_t product, std::string name, std::string order, std::string group_type,
                       std::string group_name) {
    DeviceDescription d;
    d.identity = {kVendor, product, 0x00010000, 0x00000001};
    d.vendor_name = "vecat";
    d.name = std::move(name);
    d.order_code = std::move(order);
    d.group_type = std::move(group_type);
    d.group_name = std::move(group_name);
    d.profile_no = 0;
    d.mailbox_protocols = 0;
    d.coe_details = 0;
    d.dc_modes.clear();
    d.objects.clear();
    d.eeprom_size_bytes = 2048;
    return d;
}

// A device without PDI (ESC datasheet section I: PDI control 0x0140 = 0x00, "interface deactivated"):
// the ESC forwards and answers registers and the SII, nothing else. With no µController to set AL status,
// the ESC does it itself: device emulation, 0x0141 bit 0 (a real EK1100's SII word 0 is 0x0D00).
DeviceDescription no_pdi(std::uint32_t product, std::string name, std::string order) {
    DeviceDescription d = base(product, std::move(name), std::move(order), "SystemBk", "System couplers");
    d.pdi_control = 0x0100;
    d.ebus_current_ma = -2000;  // what a coupler feeds into the E-bus (negative: supply)
    return d;
}

// An I/O terminal: one SyncManager at 0x1000 with the process data and one FMMU for it. ETG.2010: SyncM
// control 0x64 (3 buffers, written by EtherCAT, PDI interrupt, watchdog) for outputs, 0x20 for inputs.
DeviceDescription io(std::uint32_t product, bool outputs, bool analog, unsigned channels) {
    const std::string what = std::string(analog ? "analog" : "digital") + (outputs ? " output" : " input");
    DeviceDescription d =
        base(product | channels, "vecat " + std::to_string(channels) + "-channel " + what + " terminal",
             "VECAT-" + std::string(analog ? "A" : "D") + (outputs ? "O" : "I") + std::to_string(channels),
             outputs ? (analog ? "AnaOut" : "DigOut") : (analog ? "AnaIn" : "DigIn"), what + " terminals");
    d.pdi_control = 0x0004;  // digital I/O
    d.ebus_current_ma = 100;
    Pdo pdo;
    pdo.index = outputs ? 0x1600 : 0x1A00;
    pdo.name = outputs ? "Outputs" : "Inputs";
    pdo.sm = 0;
    pdo.fixed = true;
    pdo.mandatory = true;
    // Objects of the I/O profile (ETG.5001 MDP: inputs 0x6000 + 0x10 n, outputs 0x7000 + 0x10 n).
    const std::uint16_t area = outputs ? 0x7000 : 0x6000;
    unsigned bits = 0;
    for (unsigned c = 0; c < channels; ++c) {
        const auto index = static_cast<std::uint16_t>(area + 0x10 * (analog ? c : c / 8));
        if (analog)
            pdo.entries.push_back({index, 0x11, 16, DataType::Integer16, "Value " + std::to_string(c + 1)});
        else
            pdo.entries.push_back({index, static_cast<std::uint8_t>(c % 8 + 1), 1, DataType::Boolean,
                                   (outputs ? "Output " : "Input ") + std::to_string(c + 1)});
        bits += analog ? 16 : 1;
    }
    if (bits % 8)
        pdo.entries.push_back({0x0000, 0, static_cast<std::uint8_t>(8 - bits % 8), DataType::Unsigned8, ""});
    pdo.capacity = static_cast<std::uint8_t>(pdo.entries.size());
    (outputs ? d.rx_pdos : d.tx_pdos).push_back(pdo);
    const auto bytes = static_cast<std::uint16_t>((bits + 7) / 8);
    d.sync_managers = {{0x1000, bytes, static_cast<std::uint8_t>(outputs ? 0x64 : 0x20), 0x01,
                        outputs ? SmType::Outputs : SmType::Inputs}};
    d.fmmus = {outputs ? FmmuUsage::Outputs : FmmuUsage::Inputs};
    return d;
}

}  // namespace

DeviceDescription coupler() {
    return no_pdi(simple_product::Coupler, "vecat EtherCAT coupler", "VECAT-CPL");
}

DeviceDescription junction() {
    DeviceDescription d = no_pdi(simple_product::Junction, "vecat 2-port EtherCAT junction", "VECAT-JCT");
    d.ebus_current_ma = 220;
    return d;
}

DeviceDescription digital_input_terminal(unsigned channels) {
    return io(simple_product::DigitalIn, false, false, channels);
}
DeviceDescription digital_output_terminal(unsigned channels) {
    return io(simple_product::DigitalOut, true, false, channels);
}
DeviceDescription analog_input_terminal(unsigned channels) {
    return io(simple_product::AnalogIn, false, true, channels);
}
DeviceDescription analog_output_terminal(unsigned channels) {
    return io(simple_product::AnalogOut, true, true, channels);
}

}  // namespace vecat::device
