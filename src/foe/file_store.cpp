#include "foe/file_store.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "protocol/foe.hpp"

namespace vecat::foe {

namespace fs = std::filesystem;

namespace {
constexpr char kFirstPrintable = 0x20;
constexpr char kLastPrintable = 0x7E;
}  // namespace

std::string_view trim_file_name(std::string_view raw) noexcept {
    while (!raw.empty() && raw.back() == '\0')
        raw.remove_suffix(1);
    return raw;
}

bool valid_file_name(std::string_view name) noexcept {
    if (name.empty() || name.size() > protocol::kFoeMaxFileName || name == ".") return false;
    if (name.find("..") != std::string_view::npos) return false;
    for (char c : name)
        if (c < kFirstPrintable || c > kLastPrintable || c == '/' || c == '\\') return false;
    return true;
}

FileStore::FileStore(std::string dir, std::size_t max_file_size)
    : dir_(std::move(dir)), max_file_size_(max_file_size) {}

bool FileStore::exists(std::string_view name) const {
    if (dir_.empty()) return memory_.find(name) != memory_.end();
    std::error_code ec;
    return fs::exists(fs::path(dir_) / std::string(name), ec);
}

StoreStatus FileStore::read(std::string_view name, std::vector<std::uint8_t>& out, std::string* why) const {
    out.clear();
    if (!valid_file_name(name)) return StoreStatus::AccessDenied;
    if (dir_.empty()) {
        const auto it = memory_.find(name);
        if (it == memory_.end()) return StoreStatus::NotFound;
        out = it->second;
        return StoreStatus::Ok;
    }
    const fs::path p = fs::path(dir_) / std::string(name);
    std::error_code ec;
    const auto st = fs::status(p, ec);
    if (!fs::exists(st)) return StoreStatus::NotFound;
    if (!fs::is_regular_file(st)) return StoreStatus::AccessDenied;
    const auto size = fs::file_size(p, ec);
    if (ec) return StoreStatus::AccessDenied;
    if (size > max_file_size_) {
        if (why) *why = "larger than the FoE size limit of " + std::to_string(max_file_size_) + " bytes";
        return StoreStatus::TooLarge;
    }
    std::ifstream f(p, std::ios::binary);
    if (!f) return StoreStatus::AccessDenied;
    out.resize(static_cast<std::size_t>(size));
    f.read(reinterpret_cast<char*>(out.data()), static_cast<std::streamsize>(out.size()));
    out.resize(static_cast<std::size_t>(f.gcount()));
    return StoreStatus::Ok;
}

StoreStatus FileStore::write(std::string_view name, ConstBytes data, std::string* why) {
    if (!valid_file_name(name)) return StoreStatus::AccessDenied;
    if (data.size() > max_file_size_) return StoreStatus::TooLarge;
    if (dir_.empty()) {
        auto it = memory_.find(name);
        if (it == memory_.end()) {
            if (memory_.size() >= kMaxMemoryFiles) return StoreStatus::Full;
            it = memory_.emplace(std::string(name), std::vector<std::uint8_t>{}).first;
        }
        it->second.assign(data.begin(), data.end());
        return StoreStatus::Ok;
    }
    std::error_code ec;
    fs::create_directories(dir_, ec);
    const fs::path p = fs::path(dir_) / std::string(name);
    if (fs::exists(p, ec) && !fs::is_regular_file(p, ec)) return StoreStatus::AccessDenied;
    const fs::path tmp = fs::path(dir_) / (".foe-" + std::string(name) + ".part");
    {
        std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
        if (f) f.write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size()));
        if (!f) {
            if (why) *why = "cannot write " + tmp.string() + ": " + std::strerror(errno);
            fs::remove(tmp, ec);
            return StoreStatus::IoError;
        }
    }
    fs::rename(tmp, p, ec);
    if (ec) {
        if (why) *why = "cannot rename to " + p.string() + ": " + ec.message();
        fs::remove(tmp, ec);
        return StoreStatus::IoError;
    }
    return StoreStatus::Ok;
}

}  // namespace vecat::foe
