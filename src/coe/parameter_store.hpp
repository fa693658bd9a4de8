// Parameter persistence (CiA 301 0x1010 store parameters, 0x1011 restore default parameters): the
// dictionary's parameters saved to one file per slave, written atomically (temporary file in the same
// directory, fsync, rename, fsync of the directory), so a process killed at any moment leaves either the
// old or the new set. The file is versioned and carries a CRC-32; a corrupted or foreign file is reported
// and the defaults stay.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "coe/object_dictionary.hpp"
#include "common/bytes.hpp"
#include "device/device_description.hpp"

namespace vecat::coe {

// Signatures written to 0x1010 / 0x1011 (ASCII "save" / "load", little-endian).
inline constexpr std::uint32_t kStoreSignature = 0x65766173;
inline constexpr std::uint32_t kRestoreSignature = 0x64616F6C;

// Subindexes of 0x1010/0x1011: which parameters.
enum class ParameterGroup : std::uint8_t { All = 1, Communication = 2, Application = 3, Manufacturer = 4 };

struct ParameterRecord {
    std::uint16_t index = 0;
    std::uint8_t subindex = 0;
    std::vector<std::uint8_t> value;
};

struct ParameterSet {
    device::Identity identity;  // of the device that stored it (serial number ignored)
    std::vector<ParameterRecord> records;
};

// The file format: "VECATPRM", version, identity, records, CRC-32 of everything before it.
std::vector<std::uint8_t> encode_parameter_set(const ParameterSet& s);

enum class LoadStatus : std::uint8_t {
    Loaded,
    Missing,      // no file: defaults, nothing to report
    Corrupt,      // bad magic, version, length or CRC
    OtherDevice,  // valid, but stored by a device of another identity
};
std::string_view to_string(LoadStatus s) noexcept;

struct LoadResult {
    LoadStatus status = LoadStatus::Missing;
    ParameterSet set;
    std::string detail;  // why a file was refused
};
LoadResult decode_parameter_set(ConstBytes file);
LoadResult load_parameter_file(const std::string& path);

// Writes path atomically: path.tmp in the same directory, fsync, rename over path, fsync the directory.
bool write_file_atomically(const std::string& path, ConstBytes data, std::string* why = nullptr);
// Removes path durably (unlink, fsync the directory); true also when it did not exist.
bool remove_file_durably(const std::string& path, std::string* why = nullptr);

// Whether an entry is a stored parameter: writable in some state, not PDO-mappable (process values are
// the master's, not settings), not 0x1010/0x1011 themselves.
bool is_stored_parameter(std::uint16_t index, const Entry& e);
bool in_group(std::uint16_t index, ParameterGroup g);

// What restore_at_start did.
struct RestoreReport {
    LoadResult load;
    std::size_t applied = 0;
    std::size_t refused = 0;  // records whose object is gone or whose value the dictionary refused
};

class ParameterStore {
  public:
    ParameterStore(ObjectDictionary& od, device::Identity identity, std::string path);

    // Applies the stored set (SDO download rules and device hooks, as in PREOP). Call once at start.
    RestoreReport restore_at_start();
    // 0x1010:sub written with "save": the group's current values replace its part of the file.
    SdoAbort store(ParameterGroup g);
    // 0x1011:sub written with "load": the group's stored values are dropped; the defaults take effect at
    // the next start (CiA 301: after reset / power cycle).
    SdoAbort restore_defaults(ParameterGroup g);

    const std::string& path() const { return path_; }
    const std::string& last_error() const { return last_error_; }

  private:
    // The stored set without the group's records (the file's, or empty when it is missing/unusable).
    ParameterSet others_than(ParameterGroup g);
    ObjectDictionary& od_;
    device::Identity identity_;
    std::string path_;
    std::string last_error_;
};

// Installs the behaviour of 0x1010/0x1011 in a dictionary: reads give the capability (1 = on command when
// a store is attached, 0 otherwise); writes check the signature and call the store. store may be null.
void install_parameter_objects(ObjectDictionary& od, ParameterStore* store);

}  // namespace vecat::coe
