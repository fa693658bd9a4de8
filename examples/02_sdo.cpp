// 02_sdo: read and write dictionary objects over CoE (SDO upload/download) and browse the dictionary
// with SDO information, as a configuration tool does in PREOP.
#include <cstdio>

#include "master/coe_client.hpp"
#include "protocol/cia402_objects.hpp"
#include "testing/virtual_segment.hpp"

using namespace vecat;

int main() {
    // One drive, stopped in PREOP (mailbox running, no process data yet).
    testing::VirtualSegment vs({.drives = 1, .target = protocol::AlState::PreOp});
    master::CoeClient coe(vs.master(), vs.station(0));

    // Upload: the device name 0x1008 (a string, longer than 4 bytes: a normal transfer). The object
    // catalogue names the objects (protocol/objects.hpp, protocol/cia402_objects.hpp).
    namespace od = vecat::protocol::obj;
    const auto name = coe.upload(od::device_name.index, 0);
    if (!name.ok()) return 1;
    std::printf("0x1008 device name: %.*s\n", static_cast<int>(name.data.size()),
                reinterpret_cast<const char*>(name.data.data()));

    // Download then upload: the profile velocity 0x6081 (expedited, 4 bytes).
    if (!coe.download_value<std::uint32_t>(od::profile_velocity.index, 0, 123456).ok()) return 1;
    const auto v = coe.upload(od::profile_velocity.index, 0);
    if (!v.ok() || v.data.size() != 4) return 1;
    const std::uint32_t back = vecat::ld_le32(v.data.data());
    std::printf("0x6081 profile velocity written 123456, read back %u\n", back);
    if (back != 123456) return 1;

    // A write the drive refuses: the statusword 0x6041 is read-only (an SDO abort, not a transport error).
    const auto refused = coe.download_value<std::uint16_t>(od::statusword.index, 0, 0);
    std::printf("write 0x6041: abort code 0x%08X\n", static_cast<unsigned>(refused.abort));
    if (!refused.transport_ok || refused.ok()) return 1;

    // SDO information: the list of all objects, then the description of one and of its entry.
    const auto list = coe.od_list(0x01);
    if (!list) return 1;
    std::printf("SDO information: %zu objects in the dictionary\n", list->size());
    const auto obj = coe.object_description(od::position_actual_value.index);
    const auto entry = coe.entry_description(od::position_actual_value.index, 0, 0);
    if (!obj || !entry) return 1;
    std::printf("0x6064 \"%s\": data type 0x%04X, %u bits, access 0x%04X\n", obj->name.c_str(),
                obj->data_type, entry->bit_length, entry->access);
    return list->size() > 10 ? 0 : 1;
}
