// PDO mapping and assignment (ETG.1000.6 5.6.7.4, ETG.1020 section 6): the objects 0x16xx/0x1Axx and
// 0x1C12/0x1C13 with the rules for changing them in PREOP, and the process image they define.
#pragma once

#include <array>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "coe/object_dictionary.hpp"
#include "common/bytes.hpp"
#include "device/device_description.hpp"
#include "protocol/al_status.hpp"

namespace vecat::coe {

// One mapped field of the process image: an entry (nullptr for a gap) at a bit offset.
struct MappedField {
    Entry* entry = nullptr;
    std::uint32_t bit_offset = 0;
    std::uint16_t bits = 0;
};

// The decoded mapping value of a 0x16xx/0x1Axx subindex.
struct MappingValue {
    std::uint16_t index;
    std::uint8_t subindex;
    std::uint8_t bits;
    static MappingValue decode(std::uint32_t v) {
        return {static_cast<std::uint16_t>(v >> 16), static_cast<std::uint8_t>(v >> 8),
                static_cast<std::uint8_t>(v)};
    }
    // Index 0 and the data type indexes below 0x1000 are gaps ("dummy entries", CiA 301 7.4.8).
    bool is_gap() const { return index < 0x1000; }
};

// Aligned to a cache line so that what every firmware run reads (the fields first in the class, below)
// lies in the fewest lines: a run of a large line finds them out of the caches.
class alignas(64) ProcessDataMap {
  public:
    // Installs the SDO rules on the mapping and assignment objects of od.
    ProcessDataMap(ObjectDictionary& od, const device::DeviceDescription& desc);
    ProcessDataMap(const ProcessDataMap&) = delete;
    ProcessDataMap& operator=(const ProcessDataMap&) = delete;

    unsigned output_bytes() const { return out_bytes_; }
    unsigned input_bytes() const { return in_bytes_; }
    // Largest process image per direction the SyncManager layout allows (3 buffers must fit).
    unsigned max_output_bytes() const { return max_out_; }
    unsigned max_input_bytes() const { return max_in_; }
    const std::vector<MappedField>& outputs() const { return out_; }
    const std::vector<MappedField>& inputs() const { return in_; }

    // NoError, or 0x0024/0x0025 when the current mapping cannot be used (checked at PREOP -> SAFEOP).
    protocol::AlStatusCode validate() const;

    // Copies received outputs into the mapped entries, and the mapped entries into the inputs image.
    void copy_outputs(ConstBytes image);
    void copy_inputs(Bytes image) const;
    bool is_rx_mapped(const Entry& e) const;

    // Re-reads the objects (called after each change through SDO).
    void rebuild();
    // Counters for a device that caches values of its entries: mapping rebuilds, and copies of the outputs
    // that changed a mapped entry (which write them without Entry::set, see EntryHooks::writes). A copy
    // that the fast plan cannot take counts whether or not it changed a byte.
    std::uint64_t mapping_changes() const { return mapping_changes_; }
    std::uint64_t outputs_changed() const { return outputs_changed_; }

  private:
    struct Direction {
        std::uint16_t assign_index = 0;  // 0x1C12 / 0x1C13
        std::uint16_t first_pdo = 0;     // 0x1600 / 0x1A00
        bool rx = true;
        unsigned max_bytes = 0;
    };
    void install(const Direction& d);
    bool is_assigned(const Direction& d, std::uint16_t pdo) const;
    SdoAbort check_mapping_entry(const Direction& d, std::uint32_t value) const;
    // Bits of the PDO mapping object `pdo` with count entries (or its current count), or nullopt if invalid.
    bool pdo_bits(const Direction& d, std::uint16_t pdo, int count, unsigned& bits) const;
    bool assigned_bits(const Direction& d, std::uint16_t changed_pdo, int changed_count, int assign_count,
                       unsigned& bits) const;
    bool build(const Direction& d, std::vector<MappedField>& fields, unsigned& bytes);

    // The copy plan of a direction whose fields are all whole objects of 1, 2, 4 or 8 bytes at byte
    // offsets (nearly every mapping): value pointers and image offsets resolved once per mapping, so the
    // cyclic copy is one fixed-size copy per field. The fields are grouped by size (they never overlap, so
    // their order does not matter): one loop per size, no branch on the size per field. Empty `ok` means
    // the general bit copy is used.
    struct FastField {
        std::uint8_t* value;
        std::uint32_t byte;
    };
    struct Plan {
        bool ok = false;
        std::vector<FastField> fields;       // 1-byte fields first, then 2, 4 and 8
        std::array<std::uint32_t, 5> end{};  // end[k + 1]: end of the fields of 1 << k bytes; end[0] = 0
    };
    template <bool ToImage>
    using ImagePtr = std::conditional_t<ToImage, std::uint8_t*, const std::uint8_t*>;
    // Copies the fields; to the entries (not ToImage): true if any entry's bytes changed.
    template <bool ToImage>
    static bool run_plan(const Plan& p, ImagePtr<ToImage> image);
    static Plan make_plan(const std::vector<MappedField>& fields);

    // What every run reads first, together: the counts the device watches, the image sizes and the plans.
    std::uint64_t mapping_changes_ = 0;
    std::uint64_t outputs_changed_ = 0;
    unsigned out_bytes_ = 0, in_bytes_ = 0;
    bool out_valid_ = true, in_valid_ = true;
    Plan out_plan_, in_plan_;
    ObjectDictionary& od_;
    Direction rx_, tx_;
    std::vector<MappedField> out_, in_;
    unsigned max_out_ = 0, max_in_ = 0;
    // When a mapping object's entries may be written (device_description.hpp).
    device::PdoRemapping remapping_ = device::PdoRemapping::Subindex0Zero;
};

}  // namespace vecat::coe
