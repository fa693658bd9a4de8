// What a capture's mailbox traffic tells about a device's CoE object dictionary: the values the master
// uploaded (expedited, normal and segmented transfers, ETG.1000.6 5.6.2), the objects and entries SDO
// information described (5.6.3), the complete object list, and the objects and subindexes the device said
// do not exist (SDO abort 0x06020000 / 0x06090011). The line rebuilt from a capture serves them, so that
// its mailbox answers are the recorded ones and not those of a dictionary generated from the SII alone.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <utility>
#include <vector>

#include "device/object_description.hpp"

namespace vecat::replay {

struct RecoveredDictionary {
    std::map<std::pair<std::uint16_t, std::uint8_t>, std::vector<std::uint8_t>> values;  // uploaded
    std::map<std::uint16_t, device::ObjectDescription> objects;  // described (entries as described)
    std::set<std::uint16_t> absent_objects;
    std::set<std::pair<std::uint16_t, std::uint8_t>> absent_entries;
    // Downloads the device confirmed, with the value when it was expedited (else empty).
    std::map<std::pair<std::uint16_t, std::uint8_t>, std::vector<std::uint8_t>> written;
    std::optional<std::vector<std::uint16_t>> all_objects;  // a complete "all objects" list
    // A download response repeated the request's non-zero data field in its reserved bytes 4-7 (ETG.1000.6
    // 5.6.2): the device has quirk sdo_download_echo (device/quirks.hpp).
    bool download_echo = false;
    // After most of the master's reads of the mailbox-in area, the next read of that SyncManager's status
    // showed the write buffer in use (0x0805 bit 7) and not interrupt read: quirk mailbox_open_early.
    bool open_early = false;
    bool empty() const { return values.empty() && objects.empty() && !all_objects && written.empty(); }
};

// Follows one slave's mailbox: the master's writes of its mailbox-out SyncManager (SM0) area and its reads of
// the mailbox-in (SM1) area, at the addresses the master configured (0x0800, 0x0808).
class MailboxRecoverer {
  public:
    // A write the slave counted, of bytes [ado, ado + data.size()).
    void wrote(std::uint16_t ado, const std::uint8_t* data, std::size_t len);
    // A read the slave counted.
    void read(std::uint16_t ado, const std::uint8_t* data, std::size_t len);
    const RecoveredDictionary& result() const { return dict_; }

  private:
    void reply(const std::uint8_t* msg, std::size_t len);
    void sdo_response(const std::uint8_t* p, std::size_t n);
    void info_response(const std::uint8_t* p, std::size_t n);
    void store(std::uint16_t index, std::uint8_t sub, bool complete_access, std::vector<std::uint8_t> bytes);

    std::optional<std::uint16_t> out_start_, in_start_;
    // The SM1 status read first after each read of the mailbox-in area, and how often it showed it opened.
    bool in_read_ = false;
    std::size_t status_after_read_ = 0, opened_after_read_ = 0;
    // The last SDO request the master sent (command byte, index, subindex).
    std::uint8_t request_cmd_ = 0;
    std::uint16_t request_index_ = 0;
    std::uint8_t request_sub_ = 0;
    std::vector<std::uint8_t> request_value_;  // of an expedited download
    std::uint32_t request_data_ = 0;           // the data field of the SDO header (bytes 4-7)
    // A segmented upload in progress.
    bool segmented_ = false;
    std::uint32_t segmented_size_ = 0;
    std::vector<std::uint8_t> segmented_data_;
    // An object list in fragments.
    std::optional<std::uint16_t> list_type_;
    std::vector<std::uint16_t> list_;
    // An entry's description needs its object's (ETG.1000.6 5.6.3.6: the values are of the entry's size).
    RecoveredDictionary dict_;
};

// The dictionary a device made from an SII image serves (generated: its objects), with what the capture
// recovered laid over it: described objects replace generated ones, uploaded values are set, absent objects
// and entries are removed, a complete object list is the set of objects. Values go to `values`.
std::vector<device::ObjectDescription> merge_dictionary(
    std::vector<device::ObjectDescription> generated, const RecoveredDictionary& r,
    std::map<std::pair<std::uint16_t, std::uint8_t>, std::vector<std::uint8_t>>& values);

}  // namespace vecat::replay
