// SDO abort codes (ETG.1000.6 Table 41, CiA 301 7.2.4.3.17).
#pragma once

#include <cstdint>
#include <string_view>

namespace vecat::protocol {

enum class SdoAbort : std::uint32_t {
    None = 0x00000000,
    ToggleBit = 0x05030000,
    Timeout = 0x05040000,
    UnknownCommand = 0x05040001,
    InvalidBlockSize = 0x05040002,
    OutOfMemory = 0x05040005,
    UnsupportedAccess = 0x06010000,
    WriteOnly = 0x06010001,
    ReadOnly = 0x06010002,
    Subindex0NotZero = 0x06010003,
    CompleteAccessNotSupported = 0x06010004,
    ObjectTooLongForMailbox = 0x06010005,
    MappedToRxPdo = 0x06010006,
    ObjectDoesNotExist = 0x06020000,
    NotMappable = 0x06040041,
    PdoLengthExceeded = 0x06040042,
    ParameterIncompatible = 0x06040043,
    DeviceIncompatible = 0x06040047,
    HardwareError = 0x06060000,
    LengthMismatch = 0x06070010,
    LengthTooHigh = 0x06070012,
    LengthTooLow = 0x06070013,
    SubindexDoesNotExist = 0x06090011,
    ValueRange = 0x06090030,
    ValueTooHigh = 0x06090031,
    ValueTooLow = 0x06090032,
    MaxLessThanMin = 0x06090036,
    GeneralError = 0x08000000,
    CannotTransfer = 0x08000020,
    LocalControl = 0x08000021,
    WrongState = 0x08000022,
    NoObjectDictionary = 0x08000023,
};

constexpr std::string_view describe(SdoAbort a) noexcept {
    switch (a) {
        case SdoAbort::None:
            return "No error";
        case SdoAbort::ToggleBit:
            return "Toggle bit not changed";
        case SdoAbort::Timeout:
            return "SDO protocol timeout";
        case SdoAbort::UnknownCommand:
            return "Client/Server command specifier not valid or unknown";
        case SdoAbort::InvalidBlockSize:
            return "Invalid block size";
        case SdoAbort::OutOfMemory:
            return "Out of memory";
        case SdoAbort::UnsupportedAccess:
            return "Unsupported access to an object";
        case SdoAbort::WriteOnly:
            return "Attempt to read a write only object";
        case SdoAbort::ReadOnly:
            return "Attempt to write a read only object";
        case SdoAbort::Subindex0NotZero:
            return "Subindex cannot be written, SI0 must be 0 for write access";
        case SdoAbort::CompleteAccessNotSupported:
            return "SDO Complete access not supported for objects of variable length";
        case SdoAbort::ObjectTooLongForMailbox:
            return "Object length exceeds mailbox size";
        case SdoAbort::MappedToRxPdo:
            return "Object mapped to RxPDO, SDO Download blocked";
        case SdoAbort::ObjectDoesNotExist:
            return "The object does not exist in the object dictionary";
        case SdoAbort::NotMappable:
            return "The object can not be mapped into the PDO";
        case SdoAbort::PdoLengthExceeded:
            return "The number and length of the objects to be mapped would exceed the PDO length";
        case SdoAbort::ParameterIncompatible:
            return "General parameter incompatibility reason";
        case SdoAbort::DeviceIncompatible:
            return "General internal incompatibility in the device";
        case SdoAbort::HardwareError:
            return "Access failed due to a hardware error";
        case SdoAbort::LengthMismatch:
            return "Data type does not match, length of service parameter does not match";
        case SdoAbort::LengthTooHigh:
            return "Data type does not match, length of service parameter too high";
        case SdoAbort::LengthTooLow:
            return "Data type does not match, length of service parameter too low";
        case SdoAbort::SubindexDoesNotExist:
            return "Subindex does not exist";
        case SdoAbort::ValueRange:
            return "Value range of parameter exceeded";
        case SdoAbort::ValueTooHigh:
            return "Value of parameter written too high";
        case SdoAbort::ValueTooLow:
            return "Value of parameter written too low";
        case SdoAbort::MaxLessThanMin:
            return "Maximum value is less than minimum value";
        case SdoAbort::GeneralError:
            return "General error";
        case SdoAbort::CannotTransfer:
            return "Data cannot be transferred or stored to the application";
        case SdoAbort::LocalControl:
            return "Data cannot be transferred or stored to the application because of local control";
        case SdoAbort::WrongState:
            return "Data cannot be transferred or stored to the application because of the present device "
                   "state";
        case SdoAbort::NoObjectDictionary:
            return "Object dictionary dynamic generation fails or no object dictionary is present";
    }
    return "Unknown abort code";
}

}  // namespace vecat::protocol
