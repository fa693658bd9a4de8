// AL states (the AL control and AL status registers 0x0120, 0x0130) and AL status codes (0x0134) with their
// messages (ETG.1000.6 clause 5.3, Table 11).
#pragma once

#include <cstdint>
#include <string_view>

namespace vecat::protocol {

enum class AlState : std::uint8_t {
    Init = 0x01,
    PreOp = 0x02,
    Boot = 0x03,
    SafeOp = 0x04,
    Op = 0x08,
};

inline constexpr std::uint8_t kAlStateMask = 0x0F;
inline constexpr std::uint8_t kAlErrorFlag = 0x10;  // AL status: error indication; AL control: acknowledge
inline constexpr std::uint8_t kAlIdentFlag = 0x20;  // device identification request / loaded

constexpr bool is_valid_state(std::uint8_t s) noexcept {
    switch (static_cast<AlState>(s)) {
        case AlState::Init:
        case AlState::PreOp:
        case AlState::Boot:
        case AlState::SafeOp:
        case AlState::Op:
            return true;
    }
    return false;
}

constexpr std::string_view to_string(AlState s) noexcept {
    switch (s) {
        case AlState::Init:
            return "INIT";
        case AlState::PreOp:
            return "PREOP";
        case AlState::Boot:
            return "BOOT";
        case AlState::SafeOp:
            return "SAFEOP";
        case AlState::Op:
            return "OP";
    }
    return "?";
}

enum class AlStatusCode : std::uint16_t {
    NoError = 0x0000,
    Unspecified = 0x0001,
    NoMemory = 0x0002,
    InvalidDeviceSetup = 0x0003,
    InvalidRequestedStateChange = 0x0011,
    UnknownRequestedState = 0x0012,
    BootstrapNotSupported = 0x0013,
    NoValidFirmware = 0x0014,
    InvalidMailboxConfigBoot = 0x0015,
    InvalidMailboxConfigPreOp = 0x0016,
    InvalidSyncManagerConfig = 0x0017,
    NoValidInputs = 0x0018,
    NoValidOutputs = 0x0019,
    SynchronizationError = 0x001A,
    SyncManagerWatchdog = 0x001B,
    InvalidSyncManagerTypes = 0x001C,
    InvalidOutputConfig = 0x001D,
    InvalidInputConfig = 0x001E,
    InvalidWatchdogConfig = 0x001F,
    NeedsColdStart = 0x0020,
    NeedsInit = 0x0021,
    NeedsPreOp = 0x0022,
    NeedsSafeOp = 0x0023,
    InvalidInputMapping = 0x0024,
    InvalidOutputMapping = 0x0025,
    InconsistentSettings = 0x0026,
    FreeRunNotSupported = 0x0027,
    SyncNotSupported = 0x0028,
    FreeRunNeeds3Buffer = 0x0029,
    BackgroundWatchdog = 0x002A,
    NoValidInputsAndOutputs = 0x002B,
    FatalSyncError = 0x002C,
    NoSyncError = 0x002D,
    CycleTimeTooSmall = 0x002E,
    InvalidDcSyncConfig = 0x0030,
    InvalidDcLatchConfig = 0x0031,
    PllError = 0x0032,
    DcSyncIoError = 0x0033,
    DcSyncTimeout = 0x0034,
    DcInvalidSyncCycleTime = 0x0035,
    DcInvalidSync0CycleTime = 0x0036,
    DcInvalidSync1CycleTime = 0x0037,
    MailboxAoe = 0x0041,
    MailboxEoe = 0x0042,
    MailboxCoe = 0x0043,
    MailboxFoe = 0x0044,
    MailboxSoe = 0x0045,
    MailboxVoe = 0x004F,
    EepromNoAccess = 0x0050,
    EepromError = 0x0051,
    RestartedLocally = 0x0060,
    DeviceIdentificationUpdated = 0x0061,
    // A modular device (ETG.5001): the Configured Module Ident List 0xF030 the master wrote differs from the
    // Detected Module Ident List 0xF050.
    ModuleIdentListMismatch = 0x0070,
};

constexpr std::string_view describe(AlStatusCode c) noexcept {
    switch (c) {
        case AlStatusCode::NoError:
            return "No error";
        case AlStatusCode::Unspecified:
            return "Unspecified error";
        case AlStatusCode::NoMemory:
            return "No memory";
        case AlStatusCode::InvalidDeviceSetup:
            return "Invalid device setup";
        case AlStatusCode::InvalidRequestedStateChange:
            return "Invalid requested state change";
        case AlStatusCode::UnknownRequestedState:
            return "Unknown requested state";
        case AlStatusCode::BootstrapNotSupported:
            return "Bootstrap not supported";
        case AlStatusCode::NoValidFirmware:
            return "No valid firmware";
        case AlStatusCode::InvalidMailboxConfigBoot:
            return "Invalid mailbox configuration (BOOT)";
        case AlStatusCode::InvalidMailboxConfigPreOp:
            return "Invalid mailbox configuration (PREOP)";
        case AlStatusCode::InvalidSyncManagerConfig:
            return "Invalid sync manager configuration";
        case AlStatusCode::NoValidInputs:
            return "No valid inputs available";
        case AlStatusCode::NoValidOutputs:
            return "No valid outputs";
        case AlStatusCode::SynchronizationError:
            return "Synchronization error";
        case AlStatusCode::SyncManagerWatchdog:
            return "Sync manager watchdog";
        case AlStatusCode::InvalidSyncManagerTypes:
            return "Invalid sync manager types";
        case AlStatusCode::InvalidOutputConfig:
            return "Invalid output configuration";
        case AlStatusCode::InvalidInputConfig:
            return "Invalid input configuration";
        case AlStatusCode::InvalidWatchdogConfig:
            return "Invalid watchdog configuration";
        case AlStatusCode::NeedsColdStart:
            return "Slave needs cold start";
        case AlStatusCode::NeedsInit:
            return "Slave needs INIT";
        case AlStatusCode::NeedsPreOp:
            return "Slave needs PREOP";
        case AlStatusCode::NeedsSafeOp:
            return "Slave needs SAFEOP";
        case AlStatusCode::InvalidInputMapping:
            return "Invalid input mapping";
        case AlStatusCode::InvalidOutputMapping:
            return "Invalid output mapping";
        case AlStatusCode::InconsistentSettings:
            return "Inconsistent settings";
        case AlStatusCode::FreeRunNotSupported:
            return "Free run not supported";
        case AlStatusCode::SyncNotSupported:
            return "Synchronization not supported";
        case AlStatusCode::FreeRunNeeds3Buffer:
            return "Free run needs 3-buffer mode";
        case AlStatusCode::BackgroundWatchdog:
            return "Background watchdog";
        case AlStatusCode::NoValidInputsAndOutputs:
            return "No valid inputs and outputs";
        case AlStatusCode::FatalSyncError:
            return "Fatal sync error";
        case AlStatusCode::NoSyncError:
            return "No sync error";
        case AlStatusCode::CycleTimeTooSmall:
            return "Cycle time too small";
        case AlStatusCode::InvalidDcSyncConfig:
            return "Invalid DC SYNC configuration";
        case AlStatusCode::InvalidDcLatchConfig:
            return "Invalid DC latch configuration";
        case AlStatusCode::PllError:
            return "PLL error";
        case AlStatusCode::DcSyncIoError:
            return "DC sync IO error";
        case AlStatusCode::DcSyncTimeout:
            return "DC sync timeout error";
        case AlStatusCode::DcInvalidSyncCycleTime:
            return "DC invalid sync cycle time";
        case AlStatusCode::DcInvalidSync0CycleTime:
            return "DC invalid SYNC0 cycle time";
        case AlStatusCode::DcInvalidSync1CycleTime:
            return "DC invalid SYNC1 cycle time";
        case AlStatusCode::MailboxAoe:
            return "Mailbox AoE error";
        case AlStatusCode::MailboxEoe:
            return "Mailbox EoE error";
        case AlStatusCode::MailboxCoe:
            return "Mailbox CoE error";
        case AlStatusCode::MailboxFoe:
            return "Mailbox FoE error";
        case AlStatusCode::MailboxSoe:
            return "Mailbox SoE error";
        case AlStatusCode::MailboxVoe:
            return "Mailbox VoE error";
        case AlStatusCode::EepromNoAccess:
            return "EEPROM no access";
        case AlStatusCode::EepromError:
            return "EEPROM error";
        case AlStatusCode::RestartedLocally:
            return "Slave restarted locally";
        case AlStatusCode::DeviceIdentificationUpdated:
            return "Device identification value updated";
        case AlStatusCode::ModuleIdentListMismatch:
            return "Detected Module Ident List does not match";
    }
    return "Unknown AL status code";
}

}  // namespace vecat::protocol
