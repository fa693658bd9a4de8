// The IDNs of one SoE drive (IEC 61800-7-204, the SERCOS parameter model; ETG.1000.6 5.6): each with its
// elements (name, attribute, unit, minimum, maximum, value, default, data state), and the rules every IDN
// follows whatever it means: how each element reads on the wire and which error a write gets before the
// drive looks at the value (read only, write protected in this phase, length, minimum and maximum).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/bytes.hpp"
#include "protocol/al_status.hpp"
#include "protocol/soe.hpp"

namespace vecat::soe {

using protocol::Idn;
using protocol::SoeAttribute;
using protocol::SoeError;

// Data state of a procedure command (the command acknowledgment, IEC 61800-7-204): bit 0 set, bit 1
// execution enabled, bit 2 not yet executed (in progress), bit 3 error.
namespace command_state {
inline constexpr std::uint16_t NotSet = 0x0000;
inline constexpr std::uint16_t Executed = 0x0003;     // set, enabled, done without error
inline constexpr std::uint16_t Interrupted = 0x0005;  // set, not enabled, not done
inline constexpr std::uint16_t InProgress = 0x0007;
inline constexpr std::uint16_t Error = 0x000F;  // could not be executed
}  // namespace command_state

// The values a procedure command's operation data takes (the master's input): bit 0 set, bit 1 enable.
namespace command_input {
inline constexpr std::uint16_t Cancel = 0x0000;
inline constexpr std::uint16_t SetNotEnabled = 0x0001;
inline constexpr std::uint16_t SetAndEnable = 0x0003;
}  // namespace command_input

struct IdnEntry {
    Idn idn;
    std::string name;  // empty: the IDN has no name (0x2001 on read)
    SoeAttribute attribute;
    std::string unit;  // empty: no unit (0x4001)
    // Limits of a fixed-length value, as its bit pattern (signed when the attribute says so); none: 0x5001,
    // 0x6001 on read, no check on write.
    std::optional<std::uint64_t> min;
    std::optional<std::uint64_t> max;
    // The operation data: a fixed value of attribute.element_size() bytes, or the elements of a list.
    std::vector<std::uint8_t> value;
    std::optional<std::vector<std::uint8_t>> default_value;  // same form as value; none: 0x8001
    std::size_t max_list_bytes = 0;                          // a list: its maximum length in bytes
    bool read_only = false;                                  // 0x7004 on a write of the value
    std::uint16_t data_state = 0;                            // a command: its acknowledgment

    // The value as an unsigned number (a fixed value up to 8 bytes, little endian); 0 for a list.
    std::uint64_t number() const noexcept;
    void set_number(std::uint64_t v) noexcept;
    // A list's elements as 16-bit numbers (an IDN list).
    std::vector<std::uint16_t> words() const;
    void set_words(const std::vector<std::uint16_t>& w);
};

// The IDNs of one drive, sorted by number. Built once: entries do not move afterwards (the process data
// keeps pointers to them).
class IdnTable {
  public:
    IdnTable() = default;
    explicit IdnTable(std::vector<IdnEntry> entries);
    IdnTable(const IdnTable&) = delete;
    IdnTable& operator=(const IdnTable&) = delete;

    IdnEntry* find(Idn idn);
    const IdnEntry* find(Idn idn) const;
    const std::vector<IdnEntry>& entries() const { return entries_; }
    // S-0-0017, the IDN list of all operation data, as it should read: every IDN of the table.
    std::vector<std::uint16_t> all_idns() const;

    // Appends the requested elements of an IDN in wire order (data state first, default last; ETG.1000.6
    // 5.6.3). Returns the error of the first element the IDN cannot give.
    static std::optional<SoeError> read(const IdnEntry& e, std::uint8_t elements,
                                        std::vector<std::uint8_t>& out);
    // The checks of a write every IDN gets, before the drive's own (SoeDevice::write_value): only the value
    // is written (another element: its "read only" or "no ..." error), read only, write protected in this
    // phase (CP2 = PREOP, CP3 = SAFEOP, CP4 = OP), the length (a list: current length against the data and
    // the maximum, whole elements), minimum and maximum.
    static std::optional<SoeError> check_write(const IdnEntry& e, std::uint8_t elements, ConstBytes data,
                                               protocol::AlState phase);
    // The value a checked write carries: a list's elements without its current and maximum length.
    static ConstBytes value_of(const IdnEntry& e, ConstBytes data);

  private:
    std::vector<IdnEntry> entries_;
};

}  // namespace vecat::soe
