// The built-in SoE drive (device kind soe-drive of network files, `vecat run --device soe-drive`): a servo
// drive served through SoE (ETG.1000.6 5.6) like a Beckhoff AX5000, under vecat's vendor ID. Its IDNs and
// behaviour are src/soe's (soe::SoeDrive); this is what the SII and the ESI say about it: SoE alone in the
// mailbox protocols word (0x0010), one SoE channel per axis, mailbox SM0/SM1 of 128 bytes (so that long IDNs
// travel in fragments), process data in SM2 (MDT) and SM3 (AT).
#pragma once

#include "device/device_description.hpp"

namespace vecat::device {

// Product codes of the SoE drive (vendor 0x00000A3C, as default_drive()): one axis, two axes.
inline constexpr std::uint32_t kSoeDriveProduct = 0x00005000;
inline constexpr std::uint32_t kSoeDrive2Product = 0x00005002;

// The SyncManagers: SM0 mailbox out 0x1800 (128 bytes), SM1 mailbox in 0x1880 (128 bytes), SM2 MDT
// 0x1000, SM3 AT 0x1100; the process data lengths are those of the default telegram (S-0-0015 = 4:
// control word + S-0-0047 position command, status word + S-0-0051 position feedback value 1) for each
// axis. axes = 2: a two-channel drive like an AX5206 ("vecat SoE drive, two axes"; SII: two SoE channels),
// drive numbers 0 and 1, their MDT/AT blocks one after the other in SM2/SM3.
DeviceDescription soe_drive(unsigned axes = 1);

}  // namespace vecat::device
