#include "device/soe_drive.hpp"

namespace vecat::device {

namespace {
constexpr std::uint32_t kVendor = 0x00000A3C;  // vecat, as default_drive()
constexpr std::uint16_t kMailboxLength = 128;
// The default telegram's process data: control (status) word and one 4-byte IDN each way.
constexpr std::uint16_t kMdtBytes = 2 + 4;
constexpr std::uint16_t kAtBytes = 2 + 4;
}  // namespace

DeviceDescription soe_drive(unsigned axes) {
    axes = axes < 1 ? 1 : axes;
    DeviceDescription d;
    d.identity = {kVendor, axes == 1 ? kSoeDriveProduct : kSoeDrive2Product, 0x00010000, 0x00000001};
    d.vendor_name = "vecat";
    d.name = axes == 1 ? "vecat SoE drive (AX5000-like)" : "vecat SoE drive, two axes (AX5206-like)";
    d.order_code = axes == 1 ? "VECAT-SOE" : "VECAT-SOE-2";
    d.group_type = "Drive";
    d.group_name = "Drives";
    // No CiA profile: the drive is described by its IDNs (IEC 61800-7-204), not by a CoE dictionary.
    d.profile_no = 0;
    d.device_type = 0;
    d.software_version = "vecat 0.1.0 SoE";
    d.mailbox_protocols = mbx_proto::SoE;
    d.soe_channels = static_cast<std::uint8_t>(axes);
    d.coe_details = 0;
    d.sync_managers = {
        {0x1800, kMailboxLength, 0x26, 0x01, SmType::MailboxOut},
        {0x1880, kMailboxLength, 0x22, 0x01, SmType::MailboxIn},
        {0x1000, static_cast<std::uint16_t>(kMdtBytes * axes), 0x64, 0x01, SmType::Outputs},
        {0x1100, static_cast<std::uint16_t>(kAtBytes * axes), 0x20, 0x01, SmType::Inputs},
    };
    d.fmmus = {FmmuUsage::Outputs, FmmuUsage::Inputs, FmmuUsage::MailboxState};
    d.dc_modes.clear();
    d.objects.clear();
    d.eeprom_size_bytes = 2048;
    return d;
}

}  // namespace vecat::device
