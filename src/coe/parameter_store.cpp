#include "coe/parameter_store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

namespace vecat::coe {
namespace {

constexpr char kMagic[8] = {'V', 'E', 'C', 'A', 'T', 'P', 'R', 'M'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderSize = 8 + 4 + 12 + 4;  // magic, version, identity, record count
constexpr std::size_t kMaxFileSize = 1u << 20;       // far above any dictionary; bounds a corrupt count

std::uint32_t crc32(ConstBytes b) {
    static const auto table = [] {
        std::array<std::uint32_t, 256> t{};
        for (std::uint32_t i = 0; i < 256; ++i) {
            std::uint32_t c = i;
            for (int k = 0; k < 8; ++k)
                c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
            t[i] = c;
        }
        return t;
    }();
    std::uint32_t c = 0xFFFFFFFFu;
    for (auto x : b)
        c = table[(c ^ x) & 0xFF] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}

std::string errno_text(const char* what, const std::string& path) {
    return std::string(what) + " " + path + ": " + std::strerror(errno);
}

std::string directory_of(const std::string& path) {
    const auto slash = path.rfind('/');
    if (slash == std::string::npos) return ".";
    return slash == 0 ? "/" : path.substr(0, slash);
}

bool fsync_directory(const std::string& path, std::string* why) {
    const std::string dir = directory_of(path);
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) {
        if (why) *why = errno_text("cannot open directory", dir);
        return false;
    }
    const bool ok = ::fsync(fd) == 0;
    if (!ok && why) *why = errno_text("fsync of", dir);
    ::close(fd);
    return ok;
}

bool same_device(const device::Identity& a, const device::Identity& b) {
    return a.vendor_id == b.vendor_id && a.product_code == b.product_code && a.revision == b.revision;
}

}  // namespace

std::string_view to_string(LoadStatus s) noexcept {
    switch (s) {
        case LoadStatus::Loaded:
            return "loaded";
        case LoadStatus::Missing:
            return "no stored parameters";
        case LoadStatus::Corrupt:
            return "corrupted";
        case LoadStatus::OtherDevice:
            return "stored by another device";
    }
    return "?";
}

std::vector<std::uint8_t> encode_parameter_set(const ParameterSet& s) {
    std::vector<std::uint8_t> out(kHeaderSize);
    std::memcpy(out.data(), kMagic, 8);
    st_le32(&out[8], kVersion);
    st_le32(&out[12], s.identity.vendor_id);
    st_le32(&out[16], s.identity.product_code);
    st_le32(&out[20], s.identity.revision);
    st_le32(&out[24], static_cast<std::uint32_t>(s.records.size()));
    for (const auto& r : s.records) {
        const std::size_t at = out.size();
        out.resize(at + 5 + r.value.size());
        st_le16(&out[at], r.index);
        out[at + 2] = r.subindex;
        st_le16(&out[at + 3], static_cast<std::uint16_t>(r.value.size()));
        std::copy(r.value.begin(), r.value.end(), out.begin() + static_cast<std::ptrdiff_t>(at + 5));
    }
    const std::uint32_t c = crc32(out);
    out.resize(out.size() + 4);
    st_le32(&out[out.size() - 4], c);
    return out;
}

LoadResult decode_parameter_set(ConstBytes f) {
    LoadResult r;
    r.status = LoadStatus::Corrupt;
    if (f.size() < kHeaderSize + 4 || f.size() > kMaxFileSize) {
        r.detail = "file of " + std::to_string(f.size()) + " bytes";
        return r;
    }
    if (std::memcmp(f.data(), kMagic, 8) != 0) {
        r.detail = "not a vecat parameter file";
        return r;
    }
    const std::uint32_t stored_crc = ld_le32(&f[f.size() - 4]);
    if (crc32(f.first(f.size() - 4)) != stored_crc) {
        r.detail = "checksum mismatch";
        return r;
    }
    if (const auto v = ld_le32(&f[8]); v != kVersion) {
        r.detail = "format version " + std::to_string(v);
        return r;
    }
    r.set.identity.vendor_id = ld_le32(&f[12]);
    r.set.identity.product_code = ld_le32(&f[16]);
    r.set.identity.revision = ld_le32(&f[20]);
    const std::uint32_t n = ld_le32(&f[24]);
    std::size_t at = kHeaderSize;
    const std::size_t end = f.size() - 4;
    for (std::uint32_t i = 0; i < n; ++i) {
        if (end - at < 5) {
            r.detail = "record " + std::to_string(i) + " cut short";
            r.set.records.clear();
            return r;
        }
        ParameterRecord rec;
        rec.index = ld_le16(&f[at]);
        rec.subindex = f[at + 2];
        const std::size_t len = ld_le16(&f[at + 3]);
        at += 5;
        if (end - at < len) {
            r.detail = "record " + std::to_string(i) + " cut short";
            r.set.records.clear();
            return r;
        }
        rec.value.assign(f.begin() + static_cast<std::ptrdiff_t>(at),
                         f.begin() + static_cast<std::ptrdiff_t>(at + len));
        at += len;
        r.set.records.push_back(std::move(rec));
    }
    if (at != end) {
        r.detail = "bytes after the last record";
        r.set.records.clear();
        return r;
    }
    r.status = LoadStatus::Loaded;
    return r;
}

LoadResult load_parameter_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return {};  // Missing
    std::vector<std::uint8_t> data;
    std::array<char, 4096> chunk{};
    while (in && data.size() <= kMaxFileSize) {
        in.read(chunk.data(), chunk.size());
        data.insert(data.end(), chunk.begin(), chunk.begin() + in.gcount());
    }
    auto r = decode_parameter_set(data);
    if (r.status != LoadStatus::Loaded) r.detail = path + ": " + r.detail;
    return r;
}

bool write_file_atomically(const std::string& path, ConstBytes data, std::string* why) {
    const std::string tmp = path + ".tmp";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) {
        if (why) *why = errno_text("cannot create", tmp);
        return false;
    }
    std::size_t done = 0;
    while (done < data.size()) {
        const ssize_t w = ::write(fd, data.data() + done, data.size() - done);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            if (why) *why = errno_text("cannot write", tmp);
            ::close(fd);
            ::unlink(tmp.c_str());
            return false;
        }
        done += static_cast<std::size_t>(w);
    }
    // The data must be on disk before the rename makes it the file: otherwise a crash could leave the new
    // name pointing at an empty or partial file.
    if (::fsync(fd) != 0) {
        if (why) *why = errno_text("fsync of", tmp);
        ::close(fd);
        ::unlink(tmp.c_str());
        return false;
    }
    ::close(fd);
    if (::rename(tmp.c_str(), path.c_str()) != 0) {
        if (why) *why = errno_text("cannot rename onto", path);
        ::unlink(tmp.c_str());
        return false;
    }
    return fsync_directory(path, why);  // the rename itself durable
}

bool remove_file_durably(const std::string& path, std::string* why) {
    if (::unlink(path.c_str()) != 0 && errno != ENOENT) {
        if (why) *why = errno_text("cannot remove", path);
        return false;
    }
    return fsync_directory(path, why);
}

bool in_group(std::uint16_t index, ParameterGroup g) {
    switch (g) {
        case ParameterGroup::All:
            return true;
        case ParameterGroup::Communication:
            return protocol::obj::communication_area.contains(index);
        case ParameterGroup::Application:
            return protocol::obj::profile_area.contains(index);
        case ParameterGroup::Manufacturer:
            return protocol::obj::manufacturer_area.contains(index);
    }
    return false;
}

bool is_stored_parameter(std::uint16_t index, const Entry& e) {
    if (index == 0x1010 || index == 0x1011) return false;
    if (e.rx_mappable() || e.tx_mappable()) return false;
    return (e.access() & device::access::WriteAll) != 0;
}

ParameterStore::ParameterStore(ObjectDictionary& od, device::Identity identity, std::string path)
    : od_(od), identity_(identity), path_(std::move(path)) {}

RestoreReport ParameterStore::restore_at_start() {
    RestoreReport rep;
    rep.load = load_parameter_file(path_);
    if (rep.load.status == LoadStatus::Loaded && !same_device(rep.load.set.identity, identity_)) {
        rep.load.status = LoadStatus::OtherDevice;
        rep.load.detail = path_ + ": stored by vendor 0x" + std::to_string(rep.load.set.identity.vendor_id) +
                          " product " + std::to_string(rep.load.set.identity.product_code);
    }
    if (rep.load.status != LoadStatus::Loaded) return rep;
    const auto& recs = rep.load.set.records;
    // Per object as a master writes a PDO mapping (ETG.1020): subindex 0 := 0, the entries, then subindex 0.
    for (std::size_t i = 0; i < recs.size();) {
        std::size_t j = i;
        while (j < recs.size() && recs[j].index == recs[i].index)
            ++j;
        const std::uint16_t index = recs[i].index;
        const ParameterRecord* sub0 = nullptr;
        for (std::size_t k = i; k < j; ++k)
            if (recs[k].subindex == 0) sub0 = &recs[k];
        auto apply = [&](const ParameterRecord& r) {
            Entry* e = od_.find(index, r.subindex);
            if (!e || !is_stored_parameter(index, *e)) return false;
            for (AlState s : {AlState::PreOp, AlState::SafeOp, AlState::Op})
                if (e->writable(s))
                    return od_.download(index, r.subindex, false, s, r.value) == SdoAbort::None;
            return false;
        };
        if (sub0) {
            const ParameterRecord zero{index, 0, std::vector<std::uint8_t>(sub0->value.size(), 0)};
            apply(zero);
        }
        for (std::size_t k = i; k < j; ++k) {
            if (&recs[k] == sub0) continue;
            (apply(recs[k]) ? rep.applied : rep.refused)++;
        }
        if (sub0) (apply(*sub0) ? rep.applied : rep.refused)++;
        i = j;
    }
    return rep;
}

ParameterSet ParameterStore::others_than(ParameterGroup g) {
    ParameterSet s;
    s.identity = identity_;
    auto old = load_parameter_file(path_);
    if (old.status == LoadStatus::Loaded && same_device(old.set.identity, identity_))
        for (auto& r : old.set.records)
            if (!in_group(r.index, g)) s.records.push_back(std::move(r));
    return s;
}

SdoAbort ParameterStore::store(ParameterGroup g) {
    ParameterSet s = others_than(g);
    for (auto& o : od_.objects()) {
        if (!in_group(o.index(), g)) continue;
        for (auto& e : o.entries()) {
            if (!is_stored_parameter(o.index(), e)) continue;
            e.run_before_upload();
            s.records.push_back({o.index(), e.subindex(), {e.value().begin(), e.value().end()}});
        }
    }
    std::stable_sort(s.records.begin(), s.records.end(),
                     [](const ParameterRecord& a, const ParameterRecord& b) { return a.index < b.index; });
    const auto bytes = encode_parameter_set(s);
    // CiA 301: storing failed -> 0x06060000 (access failed due to a hardware error).
    if (!write_file_atomically(path_, bytes, &last_error_)) return SdoAbort::HardwareError;
    return SdoAbort::None;
}

SdoAbort ParameterStore::restore_defaults(ParameterGroup g) {
    if (g == ParameterGroup::All) {
        if (!remove_file_durably(path_, &last_error_)) return SdoAbort::HardwareError;
        return SdoAbort::None;
    }
    const auto bytes = encode_parameter_set(others_than(g));
    if (!write_file_atomically(path_, bytes, &last_error_)) return SdoAbort::HardwareError;
    return SdoAbort::None;
}

void install_parameter_objects(ObjectDictionary& od, ParameterStore* store) {
    const std::uint32_t capability = store ? 1u : 0u;  // bit 0: on command
    for (const std::uint16_t index : {std::uint16_t{0x1010}, std::uint16_t{0x1011}}) {
        Object* o = od.find(index);
        if (!o) continue;
        const bool storing = index == 0x1010;
        for (auto& e : o->entries()) {
            if (e.subindex() == 0) continue;
            e.set(capability);
            const auto group = static_cast<ParameterGroup>(std::min<unsigned>(e.subindex(), 4));
            e.hooks().on_download = [store, storing, group](const Entry&, ConstBytes v) {
                const std::uint32_t sig = v.size() >= 4 ? ld_le32(v.data()) : 0;
                // CiA 301 7.5.2.13/14: a wrong signature is refused with 0x0800002x.
                if (sig != (storing ? kStoreSignature : kRestoreSignature)) return SdoAbort::CannotTransfer;
                // Without a parameter directory the device stores nothing ("local control").
                if (!store) return SdoAbort::LocalControl;
                return storing ? store->store(group) : store->restore_defaults(group);
            };
            // A read gives the capability again, not the signature.
            e.hooks().after_download = [capability](Entry& x) { x.set(capability); };
        }
    }
}

}  // namespace vecat::coe
