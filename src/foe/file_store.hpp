// Where a device's FoE files live: a directory of the host (vecat run --foe-dir DIR: DIR/slave-N for the
// slave at position N), or memory when no directory is given. Names are checked before they reach the file
// system; files are bounded by a size limit, and memory by a number of files.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "common/bytes.hpp"

namespace vecat::foe {

// An FoE file name vecat accepts: 1..kFoeMaxFileName bytes of printable ASCII without '/', '\\' or "..",
// and not "." (a name cannot leave the device's directory or name a directory). Trailing NUL bytes, which
// some masters send, are not part of the name (see trim_file_name).
bool valid_file_name(std::string_view name) noexcept;
std::string_view trim_file_name(std::string_view raw) noexcept;

enum class StoreStatus : std::uint8_t {
    Ok,
    NotFound,      // no such file
    AccessDenied,  // a directory, or the host refuses it
    TooLarge,      // larger than the size limit
    Full,          // memory: too many files
    IoError,       // the host could not write it (detail in the message)
};

class FileStore {
  public:
    // dir empty: the files are kept in memory (at most kMaxMemoryFiles). The directory is created at the
    // first write.
    FileStore(std::string dir, std::size_t max_file_size);

    // The whole file into out (at most the size limit).
    StoreStatus read(std::string_view name, std::vector<std::uint8_t>& out, std::string* why = nullptr) const;
    // Replaces the file (written to a temporary file, then renamed: a reader never sees half a file).
    StoreStatus write(std::string_view name, ConstBytes data, std::string* why = nullptr);
    bool exists(std::string_view name) const;

    std::size_t max_file_size() const { return max_file_size_; }
    const std::string& dir() const { return dir_; }

    static constexpr std::size_t kMaxMemoryFiles = 32;

  private:
    std::string dir_;
    std::size_t max_file_size_;
    std::map<std::string, std::vector<std::uint8_t>, std::less<>> memory_;
};

}  // namespace vecat::foe
