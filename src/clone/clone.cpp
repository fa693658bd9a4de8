#include "clone/clone.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/bytes.hpp"
#include "device/device_description.hpp"
#include "device/from_sii.hpp"
#include "master/coe_client.hpp"
#include "protocol/coe.hpp"
#include "protocol/registers.hpp"
#include "protocol/sii.hpp"

namespace vecat::clone {

namespace {

using device::DataType;
using protocol::Reg;

std::string hex(unsigned v, int digits) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "0x%0*x", digits, v);
    return buf;
}

std::string where(std::uint16_t index, std::uint8_t sub) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "0x%04x:%02x", index, sub);
    return buf;
}

std::string why_refused(const master::SdoResult& r) {
    if (!r.transport_ok) return "no reply";
    return hex(static_cast<std::uint32_t>(r.abort), 8) + " " + std::string(protocol::describe(r.abort));
}

std::string why_info_refused(const master::CoeClient& c) {
    if (c.last_abort() == protocol::SdoAbort::None) return "no answer, or a mailbox error";
    return "abort " + hex(static_cast<std::uint32_t>(c.last_abort()), 8) + " " +
           std::string(protocol::describe(c.last_abort()));
}

// Text from the device (its SII strings) on one comment line: control characters become spaces.
std::string comment(std::string s) {
    for (char& c : s)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) c = ' ';
    return s;
}

// A name for the network file: letters, digits, '-', '_' and '.'.
std::string device_name(std::size_t position, const std::string& sii_name) {
    std::string s = "slave" + std::to_string(position);
    std::string tail;
    for (const char c : sii_name) {
        if (tail.size() >= 24) break;
        if (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')
            tail += c;
        else if (!tail.empty() && tail.back() != '-')
            tail += '-';
    }
    while (!tail.empty() && tail.back() == '-')
        tail.pop_back();
    return tail.empty() ? s : s + "-" + tail;
}

// The whole EEPROM through the ESC's SII interface (ETG.1000.4 6.4.6): as many bytes as its size word
// (0x003E: KiBit - 1) says; the bytes after the categories too, so that the copy serves them alike. A read
// that fails ends the image there (noted).
std::vector<std::uint8_t> read_whole_sii(master::Master& m, const master::SlaveInfo& s,
                                         std::vector<std::string>& missing) {
    std::vector<std::uint8_t> img = s.sii_image;
    std::size_t size = img.size();
    if (img.size() >= 2 * protocol::sii::Size + 2) {
        const unsigned kibit = ld_le16(img.data() + 2 * protocol::sii::Size) + 1u;
        size = std::min<std::size_t>(128u * kibit, 0x10000);
    }
    size = std::max(size, img.size());
    img.resize(size, 0xFF);
    // The master read up to the end marker; the rest dword by dword.
    const std::size_t have = s.sii_image.size() & ~std::size_t{3};
    for (std::size_t at = have; at < size; at += 4) {
        const auto v = m.read_sii_dword(s.station, static_cast<std::uint32_t>(at / 2));
        if (!v) {
            missing.push_back("SII: bytes from " + hex(static_cast<unsigned>(at), 4) +
                              " could not be read; " + "the copy has the " + std::to_string(at) +
                              " bytes before");
            img.resize(at);
            break;
        }
        std::uint8_t b[4];
        st_le32(b, *v);
        for (std::size_t k = 0; k < 4 && at + k < size; ++k)
            img[at + k] = b[k];
    }
    return img;
}

// A fixed-size type of this many bytes, for a value whose size is not the described one's.
DataType type_of_size(std::size_t n) {
    switch (n) {
        case 1:
            return DataType::Unsigned8;
        case 2:
            return DataType::Unsigned16;
        case 3:
            return DataType::Unsigned24;
        case 4:
            return DataType::Unsigned32;
        case 8:
            return DataType::Unsigned64;
        default:
            return DataType::OctetString;
    }
}

// Keeps an uploaded value in the dictionary, the entry made to hold it: a string or domain longer than its
// bit length gets the room; a fixed-size entry of another size is kept as a type of the value's size
// (noted), as the reader of the file would refuse it otherwise.
void keep_value(network::DeviceDictionary& d, device::ObjectDescription& o, device::EntryDescription& e,
                std::vector<std::uint8_t> value, std::vector<std::string>& missing) {
    const std::size_t room = (e.bit_length + 7u) / 8u;
    if (device::is_variable_length(e.type)) {
        if (value.size() > room) e.bit_length = static_cast<std::uint16_t>(8 * value.size());
    } else if (value.size() != room) {
        missing.push_back(where(o.index, e.subindex) + ": the value has " + std::to_string(value.size()) +
                          " bytes for an entry of " + std::to_string(e.bit_length) + " bits: kept as " +
                          std::string(device::type_name(type_of_size(value.size()))));
        e.type = type_of_size(value.size());
        e.bit_length = static_cast<std::uint16_t>(8 * value.size());
        e.default_value.clear();
        e.minimum.clear();
        e.maximum.clear();
    }
    d.values[{o.index, e.subindex}] = std::move(value);
}

// Uploads every entry readable in PREOP (as a master reads a dictionary: entry by entry, segmented for long
// values). Entries readable only in SAFEOP or OP keep no value.
void upload_all(master::CoeClient& c, network::DeviceDictionary& d, std::vector<std::string>& missing) {
    for (auto& o : d.objects)
        for (auto& e : o.entries) {
            if (!(e.access & device::access::ReadAll)) continue;  // write only
            if (!(e.access & device::access::ReadPreop)) {
                missing.push_back(where(o.index, e.subindex) +
                                  ": readable only in SAFEOP/OP, value not read");
                continue;
            }
            auto r = c.upload(o.index, e.subindex);
            if (!r.ok()) {
                missing.push_back(where(o.index, e.subindex) + ": upload refused (" + why_refused(r) + ")");
                continue;
            }
            keep_value(d, o, e, std::move(r.data), missing);
        }
}

// The dictionary through SDO information (ETG.1000.6 5.6.3): the list of all objects, each object's
// description, each entry's description with default, minimum and maximum. False when the device refuses
// the object list (no SDO information).
bool describe_all(master::CoeClient& c, network::DeviceDictionary& d, std::vector<std::string>& missing) {
    const auto list = c.od_list(protocol::sdo_info::ListAll);
    if (!list) {
        missing.push_back("SDO information refused (" + why_info_refused(c) + ")");
        return false;
    }
    namespace si = protocol::sdo_info;
    for (const std::uint16_t index : *list) {
        const auto info = c.object_description(index);
        if (!info) {
            missing.push_back(hex(index, 4) + ": object description refused (" + why_info_refused(c) +
                              "): object left out");
            continue;
        }
        device::ObjectDescription o;
        o.index = index;
        o.name = info->name;
        o.code = static_cast<device::ObjectCode>(info->object_code);
        o.type = static_cast<DataType>(info->data_type);
        // Every subindex up to the one reported, a VAR's too (a vendor's VAR may have more than subindex 0).
        const unsigned last = info->max_subindex;
        for (unsigned sub = 0; sub <= last; ++sub) {
            const auto s8 = static_cast<std::uint8_t>(sub);
            auto ed = c.entry_description(index, s8, si::ValueDefault | si::ValueMinimum | si::ValueMaximum);
            if (!ed && c.last_abort() == protocol::SdoAbort::ObjectTooLongForMailbox) {
                // A long string or domain: its default, minimum and maximum do not fit one mailbox message.
                ed = c.entry_description(index, s8, 0);
                if (ed)
                    missing.push_back(where(index, s8) +
                                      ": default, minimum and maximum too long for the mailbox: not read");
            }
            if (!ed) {
                // A record's gap (no such subindex) is no loss; anything else is.
                if (c.last_abort() != protocol::SdoAbort::SubindexDoesNotExist)
                    missing.push_back(where(index, s8) + ": entry description refused (" +
                                      why_info_refused(c) + "): entry left out");
                continue;
            }
            device::EntryDescription e;
            e.subindex = s8;
            e.name = ed->name;
            e.type = static_cast<DataType>(ed->data_type);
            e.bit_length = ed->bit_length;
            e.access = ed->access;
            const std::size_t n = (e.bit_length + 7u) / 8u;
            std::size_t at = 0;
            for (auto [bit, field] :
                 {std::pair{si::ValueDefault, &e.default_value}, std::pair{si::ValueMinimum, &e.minimum},
                  std::pair{si::ValueMaximum, &e.maximum}}) {
                if (!(ed->value_info & bit) || at + n > ed->values.size()) continue;
                field->assign(ed->values.begin() + static_cast<std::ptrdiff_t>(at),
                              ed->values.begin() + static_cast<std::ptrdiff_t>(at + n));
                at += n;
            }
            o.entries.push_back(std::move(e));
        }
        if (o.entries.empty()) {
            missing.push_back(hex(index, 4) + ": no entry could be described: object left out");
            continue;
        }
        if (info->max_subindex > o.entries.back().subindex) o.declared_max_subindex = info->max_subindex;
        d.objects.push_back(std::move(o));
    }
    std::sort(d.objects.begin(), d.objects.end(),
              [](const auto& a, const auto& b) { return a.index < b.index; });
    return true;
}

// Without SDO information: the objects the SII lets us know (the communication objects generated from its
// SyncManagers and PDOs, the application objects its PDO entries map), each entry uploaded. An object the
// device does not have (abort "object does not exist") is left out.
void guess_from_sii(master::CoeClient& c, const protocol::SiiInfo& sii, network::DeviceDictionary& d,
                    std::vector<std::string>& missing) {
    const device::DeviceDescription desc = device::description_from_sii(sii);
    d.objects = device::dictionary_objects(desc);
    d.sdo_information = false;
    missing.push_back(
        "names, data types and access rights of every object: guessed from the SII (PDO "
        "entries) and the standard communication objects, not read");
    std::vector<device::ObjectDescription> kept;
    for (auto& o : d.objects) {
        bool exists = false;
        for (auto& e : o.entries) {
            auto r = c.upload(o.index, e.subindex);
            if (r.ok()) {
                exists = true;
                keep_value(d, o, e, std::move(r.data), missing);
                continue;
            }
            if (r.abort == protocol::SdoAbort::ObjectDoesNotExist) break;
            exists = exists || r.abort != protocol::SdoAbort::SubindexDoesNotExist;
            missing.push_back(where(o.index, e.subindex) + ": upload refused (" + why_refused(r) + ")");
        }
        if (exists)
            kept.push_back(std::move(o));
        else
            missing.push_back(hex(o.index, 4) + ": not in the device (its upload refused): left out");
    }
    d.objects = std::move(kept);
    // Values of entries now gone stay out of the file.
    std::erase_if(d.values, [&](const auto& kv) {
        return std::none_of(d.objects.begin(), d.objects.end(), [&](const auto& o) {
            return o.index == kv.first.first && o.entry(kv.first.second) != nullptr;
        });
    });
}

}  // namespace

network::DeviceDictionary read_dictionary(master::Master& m, std::size_t slave,
                                          std::vector<std::string>& missing) {
    const master::SlaveInfo& s = m.slaves().at(slave);
    master::CoeClient c(m, s.station);
    network::DeviceDictionary d;
    std::vector<std::string> own;
    if (describe_all(c, d, own))
        upload_all(c, d, own);
    else
        guess_from_sii(c, s.sii, d, own);
    d.missing = own;
    missing.insert(missing.end(), own.begin(), own.end());
    return d;
}

CloneResult read_line(master::Master& m, const CloneOptions& opt) {
    const auto say = [&](const std::string& line) {
        if (opt.progress) opt.progress(line);
    };
    std::string why;
    if (!m.startup(protocol::AlState::PreOp, &why)) throw std::runtime_error("start-up to PREOP: " + why);
    auto& slaves = m.slaves();
    say(std::to_string(slaves.size()) + " devices in PREOP");
    CloneResult r;
    // Cable delays from the receive times (ETG.1000.4 DC): the master latches and reads them.
    const bool dc = m.configure_dc(0);
    if (!dc) r.notes.push_back("DC receive times could not be read: cable delays not measured");
    for (std::size_t i = 0; i < slaves.size(); ++i) {
        const master::SlaveInfo& s = slaves[i];
        ClonedDevice d;
        d.description = s.sii.device_name();
        d.name = device_name(i, d.description);
        d.parent = s.parent;
        d.parent_port = s.parent_port;
        if (dc && s.parent >= 0) {
            const auto& up = slaves[static_cast<std::size_t>(s.parent)];
            if (up.has_dc && s.has_dc) {
                const std::int64_t delay = master::Master::cable_delay(up, s);
                d.cable_delay_ns = static_cast<std::uint32_t>(std::max<std::int64_t>(delay, 0));
            } else {
                d.missing.push_back(
                    "cable delay: not measured (no DC at this device or its upstream device)");
            }
        }
        std::uint8_t regs[10] = {};
        if (const auto w = m.fprd(s.station, protocol::addr(Reg::Type), regs); w && *w == 1) {
            d.esc.type = regs[0];
            d.esc.revision = regs[1];
            d.esc.build = ld_le16(regs + 2);
            d.esc.fmmus = regs[4];
            d.esc.syncmanagers = regs[5];
            d.esc.ram_kib = regs[6];
            d.esc.port_descriptor = regs[7];
            d.esc.features = ld_le16(regs + 8);
        } else {
            d.missing.push_back("ESC registers 0x0000-0x0009: not read");
        }
        if (const auto c = m.read16(s.station, protocol::addr(Reg::SiiControl)))
            d.esc.sii_read_bytes = (*c & protocol::sii_ctrl::Read8Bytes) ? 8u : 4u;
        if (const auto a = m.read16(s.station, protocol::addr(Reg::StationAlias))) d.station_alias = *a;
        d.sii = read_whole_sii(m, s, d.missing);
        say(d.name + ": SII " + std::to_string(d.sii.size()) + " bytes");
        if ((s.sii.mailbox_protocols & protocol::sii::MailboxCoE) && s.sii.std_rx_mbx_size) {
            d.dictionary = read_dictionary(m, i, d.missing);
            say(d.name + ": " + std::to_string(d.dictionary->objects.size()) + " objects, " +
                std::to_string(d.dictionary->values.size()) + " values" +
                (d.dictionary->sdo_information ? "" : " (no SDO information)"));
        }
        r.devices.push_back(std::move(d));
    }
    return r;
}

std::string network_text(const CloneResult& r) {
    std::ostringstream o;
    o << "# Made by vecat clone from a line of " << r.devices.size() << " devices; served by\n"
      << "#   vecat run --network network.yaml\n";
    for (const auto& n : r.notes)
        o << "# " << comment(n) << "\n";
    o << "devices:\n";
    for (const auto& d : r.devices) {
        o << "  - name: " << d.name << "\n";
        if (!d.description.empty())
            o << "    # " << comment(d.description) << ", station alias " << d.station_alias << "\n";
        for (const auto& m : d.missing)
            o << "    # missing: " << comment(m) << "\n";
        o << "    sii: " << d.name << ".sii.bin\n";
        if (d.dictionary) o << "    dictionary: " << d.name << ".dictionary.yaml\n";
        if (d.parent >= 0)
            o << "    upstream: " << r.devices.at(static_cast<std::size_t>(d.parent)).name << ":"
              << d.parent_port << "\n";
        if (d.cable_delay_ns) o << "    cable_delay_ns: " << *d.cable_delay_ns << "\n";
        const auto& e = d.esc;
        if (e.any()) {
            o << "    esc: {";
            const char* sep = "";
            // digits 0: decimal; else hexadecimal of that many digits.
            const auto field = [&](const char* key, const auto& v, int digits) {
                if (!v) return;
                o << sep << key << ": ";
                if (digits)
                    o << hex(static_cast<unsigned>(*v), digits);
                else
                    o << static_cast<unsigned>(*v);
                sep = ", ";
            };
            field("type", e.type, 2);
            field("revision", e.revision, 2);
            field("build", e.build, 4);
            field("fmmus", e.fmmus, 0);
            field("syncmanagers", e.syncmanagers, 0);
            field("ram_kib", e.ram_kib, 0);
            field("port_descriptor", e.port_descriptor, 2);
            field("features", e.features, 4);
            field("sii_read_bytes", e.sii_read_bytes, 0);
            o << "}\n";
        }
    }
    return o.str();
}

std::string write_clone(const CloneResult& r, const std::string& dir) {
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw std::runtime_error(dir + ": " + ec.message());
    const auto write = [&](const std::string& name, const std::string& bytes) {
        const fs::path p = fs::path(dir) / name;
        std::ofstream f(p, std::ios::binary);
        f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        if (!f) throw std::runtime_error(p.string() + ": cannot be written");
    };
    for (const auto& d : r.devices) {
        write(d.name + ".sii.bin", std::string(d.sii.begin(), d.sii.end()));
        if (d.dictionary)
            write(d.name + ".dictionary.yaml",
                  network::write_dictionary(*d.dictionary, {"The object dictionary of " + d.name + " (" +
                                                                d.description + "), read by vecat clone",
                                                            "The format: docs/clone.md"}));
    }
    write("network.yaml", network_text(r));
    return (fs::path(dir) / "network.yaml").string();
}

}  // namespace vecat::clone
