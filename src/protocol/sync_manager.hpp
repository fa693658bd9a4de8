// The SyncManager configuration block (ETG.1000.4 6.7; ESC datasheet section II, registers 0x0800 + 8 n):
// the physical area a SyncManager guards, its mode and direction, and its status and activation bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "common/bytes.hpp"

namespace vecat::protocol {

inline constexpr unsigned kSmSize = 8;
inline constexpr unsigned kMaxSms = 16;

// Offsets inside one SyncManager block and their bits.
namespace sm {
inline constexpr unsigned PhysicalStart = 0;  // u16
inline constexpr unsigned Length = 2;         // u16
inline constexpr unsigned Control = 4;
inline constexpr unsigned Status = 5;
inline constexpr unsigned Activate = 6;
inline constexpr unsigned PdiControl = 7;

inline constexpr std::uint8_t CtrlModeMask = 0x03;  // 00 buffered (3 buffers), 10 mailbox
inline constexpr std::uint8_t CtrlModeBuffered = 0x00;
inline constexpr std::uint8_t CtrlModeMailbox = 0x02;
inline constexpr std::uint8_t CtrlDirMask = 0x0C;  // 00 ECAT reads, 01 ECAT writes
inline constexpr std::uint8_t CtrlDirRead = 0x00;
inline constexpr std::uint8_t CtrlDirWrite = 0x04;
inline constexpr std::uint8_t CtrlIrqEcat = 0x10;
inline constexpr std::uint8_t CtrlIrqPdi = 0x20;
inline constexpr std::uint8_t CtrlWatchdog = 0x40;

inline constexpr std::uint8_t StatusIrqWrite = 0x01;
inline constexpr std::uint8_t StatusIrqRead = 0x02;
inline constexpr std::uint8_t StatusMailboxFull = 0x08;
inline constexpr std::uint8_t StatusBufferShift = 4;  // bits 4-5: last written buffer
inline constexpr std::uint8_t StatusReadBufferInUse = 0x40;
inline constexpr std::uint8_t StatusWriteBufferInUse = 0x80;

inline constexpr std::uint8_t ActEnable = 0x01;
inline constexpr std::uint8_t ActRepeatRequest = 0x02;
inline constexpr std::uint8_t PdiDeactivate = 0x01;
inline constexpr std::uint8_t PdiRepeatAck = 0x02;
}  // namespace sm

struct SmConfig {
    static constexpr std::size_t kSize = kSmSize;
    std::uint16_t physical_start = 0;
    std::uint16_t length = 0;
    std::uint8_t control = 0;      // sm::Ctrl*
    std::uint8_t status = 0;       // sm::Status* (read-only for the master)
    std::uint8_t activate = 0;     // sm::Act*
    std::uint8_t pdi_control = 0;  // sm::Pdi* (written by the slave application)

    // What a master writes to configure a SyncManager: enabled when it has a length.
    static constexpr SmConfig master(std::uint16_t start, std::uint16_t len, std::uint8_t ctrl) noexcept {
        return {start, len, ctrl, 0, static_cast<std::uint8_t>(len ? sm::ActEnable : 0), 0};
    }

    bool mailbox() const noexcept { return (control & sm::CtrlModeMask) == sm::CtrlModeMailbox; }
    bool ecat_writes() const noexcept { return (control & sm::CtrlDirMask) == sm::CtrlDirWrite; }
    bool enabled() const noexcept { return (activate & sm::ActEnable) != 0; }
    bool repeat_request() const noexcept { return (activate & sm::ActRepeatRequest) != 0; }
    bool pdi_deactivated() const noexcept { return (pdi_control & sm::PdiDeactivate) != 0; }

    void pack(std::span<std::uint8_t, kSize> out) const noexcept {
        std::uint8_t* p = out.data();
        st_le16(p + sm::PhysicalStart, physical_start);
        st_le16(p + sm::Length, length);
        p[sm::Control] = control;
        p[sm::Status] = status;
        p[sm::Activate] = activate;
        p[sm::PdiControl] = pdi_control;
    }

    static SmConfig unpack(std::span<const std::uint8_t, kSize> in) noexcept {
        const std::uint8_t* p = in.data();
        return {ld_le16(p + sm::PhysicalStart),
                ld_le16(p + sm::Length),
                p[sm::Control],
                p[sm::Status],
                p[sm::Activate],
                p[sm::PdiControl]};
    }

    friend bool operator==(const SmConfig&, const SmConfig&) = default;
};

}  // namespace vecat::protocol
