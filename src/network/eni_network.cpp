#include "network/eni_network.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "common/file.hpp"
#include "esc/sii_image.hpp"
#include "esi/esi_reader.hpp"
#include "protocol/registers.hpp"
#include "protocol/sii.hpp"

namespace vecat::network {

namespace {

namespace fs = std::filesystem;

// ETG.2010 General category, PhysicalPorts: one nibble per port.
constexpr unsigned kPhysMii = 1;
constexpr unsigned kPhysEbus = 3;

// SyncManager control bytes of the mailbox (ESC datasheet section II, 0x0804): SM0 1-buffer write with the
// ECAT interrupt (0x26), SM1 1-buffer read (0x22): what configurators write for the standard mailbox.
constexpr std::uint8_t kMailboxOutControl = 0x26;
constexpr std::uint8_t kMailboxInControl = 0x22;

// PDI control (ESC datasheet section II, 0x0140 bits 0-7): none, digital I/O.
constexpr std::uint16_t kPdiNone = 0x0000;
constexpr std::uint16_t kPdiDigitalIo = 0x0004;

std::string hex(std::uint32_t v) {
    std::ostringstream s;
    s << "0x" << std::hex << v;
    return s.str();
}

// The base type of an ENI entry: its DataType when vecat knows the name, else one of its bit length
// (device_from_sii then keeps the bit length the entry gives).
device::DataType entry_type(const EniPdoEntry& e) {
    if (!e.data_type.empty())
        if (const auto t = esi::parse_esi_type(e.data_type)) return *t;
    switch (e.bit_length) {
        case 1:
            return device::DataType::Boolean;
        case 16:
            return device::DataType::Unsigned16;
        case 24:
            return device::DataType::Unsigned24;
        case 32:
            return device::DataType::Unsigned32;
        case 64:
            return device::DataType::Unsigned64;
        default:
            return device::DataType::Unsigned8;
    }
}

// The ESI files of a folder: the devices each describes, read once.
struct EsiIndex {
    struct Entry {
        std::string path;
        esi::DeviceSummary device;
    };
    std::vector<Entry> entries;
    std::map<std::string, std::uint32_t> vendor;  // per file, from importing one of its devices
};

EsiIndex index_esi_dir(const Eni& eni, const std::string& dir, std::vector<std::string>& notes) {
    EsiIndex idx;
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw EniError(eni.file + ": --esi-dir " + dir + " is no folder");
    std::vector<fs::path> files;
    for (const auto& f : fs::directory_iterator(dir, ec)) {
        std::string ext = f.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
        if (f.is_regular_file() && ext == ".xml") files.push_back(f.path());
    }
    std::sort(files.begin(), files.end());  // the same choice whatever order the folder lists them in
    for (const auto& p : files) {
        std::string why;
        const auto text = read_whole_file(p.string(), kMaxXmlFileBytes, why);
        if (!text) {
            notes.push_back(eni.file + ": " + p.string() + ": not read as an ESI file: it " + why);
            continue;
        }
        try {
            for (auto& d : esi::list_devices_text(*text))
                idx.entries.push_back({p.string(), std::move(d)});
        } catch (const std::exception& x) {
            notes.push_back(eni.file + ": " + p.string() + ": not read as an ESI file: " + x.what());
        }
    }
    return idx;
}

// The ESI device of a slave's identity, or nullopt (with a note when only another revision is there).
std::optional<EsiIndex::Entry> find_esi(EsiIndex& idx, const Eni& eni, const EniSlave& s,
                                        std::vector<std::string>& notes) {
    std::vector<std::string> other_revisions;
    for (const auto& e : idx.entries) {
        if (e.device.product_code != s.product_code) continue;
        if (e.device.revision != s.revision) {
            other_revisions.push_back(e.path + " " + e.device.type + " revision " + hex(e.device.revision));
            continue;
        }
        auto v = idx.vendor.find(e.path);
        if (v == idx.vendor.end()) {
            std::uint32_t vendor = 0;
            try {
                vendor = esi::import_esi_file(e.path,
                                              {e.device.type, e.device.product_code, e.device.revision, {}})
                             .desc.identity.vendor_id;
            } catch (const std::exception&) {
            }
            v = idx.vendor.emplace(e.path, vendor).first;
        }
        if (v->second == s.vendor_id) return e;
    }
    if (!other_revisions.empty()) {
        std::string list;
        for (const auto& o : other_revisions)
            list += (list.empty() ? "" : "; ") + o;
        notes.push_back(eni_message(
            eni, s.where,
            "no ESI of revision " + hex(s.revision) + " (there is " + list + "): made from the ENI alone"));
    }
    return std::nullopt;
}

// The PreviousPort that counts: the selected one, or the only one.
const EniPreviousPort* previous_port(const Eni& eni, const EniSlave& s, std::vector<std::string>& notes) {
    if (s.previous_ports.empty()) return nullptr;
    for (const auto& p : s.previous_ports)
        if (p.selected) return &p;
    if (s.previous_ports.size() > 1)
        notes.push_back(eni_message(eni, s.where, "several PreviousPort, none Selected: the first is taken"));
    return &s.previous_ports.front();
}

}  // namespace

std::string device_name_from_eni(const std::string& eni_name) {
    std::string out;
    for (char c : eni_name) {
        const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
        if (ok)
            out += c;
        else if (!out.empty() && out.back() != '-')
            out += '-';
    }
    while (!out.empty() && out.back() == '-')
        out.pop_back();
    return out.empty() ? "slave" : out;
}

device::DeviceDescription description_from_eni(const Eni& eni, const EniSlave& s,
                                               std::vector<std::string>& notes) {
    device::DeviceDescription d;
    d.identity.vendor_id = s.vendor_id;
    d.identity.product_code = s.product_code;
    d.identity.revision = s.revision;
    d.identity.serial = s.serial.value_or(0);
    d.name = s.name;
    d.order_code.clear();
    d.profile_no = 0;
    d.device_type = 0;
    d.hardware_version.clear();
    d.software_version.clear();
    d.mailbox_protocols = 0;
    d.fmmus.clear();

    unsigned count = s.mailbox ? 2 : 0;
    for (const auto& sm : s.sync_managers)
        count = std::max(count, sm.number + 1);
    d.sync_managers.assign(count, {});
    if (s.mailbox) {
        const EniMailbox& m = *s.mailbox;
        d.sync_managers[0] = {m.send.start, m.send.length, kMailboxOutControl, device::sm_enable::Enable,
                              device::SmType::MailboxOut};
        d.sync_managers[1] = {m.recv.start, m.recv.length, kMailboxInControl, device::sm_enable::Enable,
                              device::SmType::MailboxIn};
        d.mailbox_protocols = m.protocols;
        if (m.protocols & device::mbx_proto::CoE)
            d.coe_details = device::coe_details::Sdo | device::coe_details::SdoInfo |
                            device::coe_details::PdoAssign | device::coe_details::PdoConfig |
                            device::coe_details::CompleteAccess;
        if (m.boot_send && m.boot_recv) {
            d.bootstrap_supported = true;
            d.boot_mailbox = {m.boot_send->start, m.boot_send->length, m.boot_recv->start,
                              m.boot_recv->length};
        }
    }
    bool outputs = false, inputs = false;
    for (const auto& sm : s.sync_managers) {
        if (s.mailbox && sm.number < 2)
            throw EniError(eni_message(
                eni, sm.where,
                "Sm" + std::to_string(sm.number) + " is the mailbox's (the slave has a Mailbox)"));
        d.sync_managers[sm.number] = {sm.start, sm.default_size, sm.control,
                                      sm.enable ? device::sm_enable::Enable : std::uint8_t{0},
                                      sm.outputs ? device::SmType::Outputs : device::SmType::Inputs};
        (sm.outputs ? outputs : inputs) = true;
    }
    // The PDI (SII word 0, ESC register 0x0140): the ENI does not give it. A SyncManager on the digital
    // output register 0x0F00 needs the digital I/O PDI; a slave with neither mailbox nor process data (a
    // coupler) has none; any other keeps the description's (a microcontroller's).
    const bool on_dout =
        std::any_of(s.sync_managers.begin(), s.sync_managers.end(), [](const EniSyncManager& x) {
            return x.start >= protocol::addr(protocol::Reg::DigitalOutputData) &&
                   x.start < protocol::addr(protocol::Reg::DigitalOutputData) + protocol::kDigitalOutputSize;
        });
    if (on_dout)
        d.pdi_control = kPdiDigitalIo;
    else if (!s.mailbox && s.sync_managers.empty())
        d.pdi_control = kPdiNone;
    if (outputs) d.fmmus.push_back(device::FmmuUsage::Outputs);
    if (inputs) d.fmmus.push_back(device::FmmuUsage::Inputs);
    if (s.mailbox) d.fmmus.push_back(device::FmmuUsage::MailboxState);

    const auto convert = [&](const EniPdo& p, bool rx) {
        device::Pdo o;
        o.index = p.index;
        o.name = p.name;
        o.fixed = p.fixed;
        o.mandatory = p.mandatory;
        // Assigned: the Sm attribute, or a process data SyncManager's Pdo list naming it.
        std::optional<unsigned> sm = p.sm;
        for (const auto& x : s.sync_managers)
            if (std::find(x.pdos.begin(), x.pdos.end(), p.index) != x.pdos.end()) sm = sm.value_or(x.number);
        o.assigned = sm.has_value();
        o.sm = static_cast<std::uint8_t>(sm.value_or(0));
        if (sm) {
            if (*sm >= d.sync_managers.size() ||
                d.sync_managers[*sm].type != (rx ? device::SmType::Outputs : device::SmType::Inputs))
                throw EniError(eni_message(eni, p.where,
                                           std::string(rx ? "an RxPdo" : "a TxPdo") + " assigned to Sm" +
                                               std::to_string(*sm) + ", which is no " +
                                               (rx ? "Outputs" : "Inputs") + " SyncManager of this slave"));
        }
        for (const auto& e : p.entries)
            o.entries.push_back({e.index, e.subindex, e.bit_length, entry_type(e), e.name});
        o.capacity = static_cast<std::uint8_t>(std::min<std::size_t>(o.entries.size(), 255));
        if (p.entries.size() > 255) throw EniError(eni_message(eni, p.where, "more than 255 entries"));
        return o;
    };
    for (const auto& p : s.rx_pdos)
        d.rx_pdos.push_back(convert(p, true));
    for (const auto& p : s.tx_pdos)
        d.tx_pdos.push_back(convert(p, false));
    // A SyncManager without DefaultSize: the length of the PDOs assigned to it.
    for (const auto& sm : s.sync_managers) {
        auto& out = d.sync_managers[sm.number];
        if (out.length) continue;
        unsigned bits = 0;
        for (const auto* list : {&d.rx_pdos, &d.tx_pdos})
            for (const auto& p : *list)
                if (p.assigned && p.sm == sm.number) bits += p.bit_length();
        out.length = static_cast<std::uint16_t>((bits + 7) / 8);
        if (bits)
            notes.push_back(eni_message(
                eni, sm.where,
                "no DefaultSize: " + std::to_string(out.length) + " bytes, the length of its PDOs"));
    }
    return d;
}

std::vector<std::uint8_t> sii_image_from_eni(const device::DeviceDescription& d, const std::string& physics,
                                             std::uint8_t ports_used) {
    std::vector<std::uint8_t> img = esc::build_sii_image(d);
    std::uint16_t ports = 0;
    for (unsigned p = 0; p < kPorts; ++p) {
        unsigned kind = 0;
        if (physics.empty())
            kind = (p < 2 || ((ports_used >> p) & 1u)) ? kPhysMii : 0;
        else if (p < physics.size())
            kind = physics[p] == 'K' ? kPhysEbus : physics[p] == ' ' ? 0 : kPhysMii;
        ports = static_cast<std::uint16_t>(ports | (kind << (4 * p)));
    }
    // Walk the categories (ETG.2010: id and length in words after the header) to the General one.
    std::size_t at = 2 * protocol::sii::FirstCategory;
    while (at + protocol::sii::kCategoryHeaderSize <= img.size()) {
        const std::uint16_t id = ld_le16(img.data() + at);
        const std::size_t len = 2u * ld_le16(img.data() + at + 2);
        if (id == protocol::sii::kEndMarker) break;
        at += protocol::sii::kCategoryHeaderSize;
        if ((id & protocol::sii::kCategoryIdMask) ==
                static_cast<std::uint16_t>(protocol::sii::Category::General) &&
            protocol::sii::general::PhysicalPorts + 2 <= len && at + len <= img.size())
            st_le16(img.data() + at + protocol::sii::general::PhysicalPorts, ports);
        at += len;
    }
    return img;
}

EniNetwork network_from_eni(const Eni& eni, const EniOptions& options) {
    EniNetwork out;
    const std::size_t n = eni.slaves.size();
    if (n > 1024) throw EniError(eni.file + ": " + std::to_string(n) + " slaves: vecat serves at most 1024");

    // Station addresses, and the names of the devices (unique).
    std::map<std::uint16_t, std::size_t> by_addr;
    std::map<std::string, unsigned> used_names;  // device name -> its slave
    std::vector<DeviceEntry> devices(n);
    for (std::size_t i = 0; i < n; ++i) {
        const EniSlave& s = eni.slaves[i];
        if (s.phys_addr) {
            const auto [it, fresh] = by_addr.emplace(*s.phys_addr, i);
            if (!fresh)
                throw EniError(eni_message(eni, s.where,
                                           "PhysAddr " + std::to_string(*s.phys_addr) +
                                               " is also that of the slave on line " +
                                               std::to_string(eni.slaves[it->second].where.line)));
        }
        const std::string base = device_name_from_eni(s.name);
        std::string name = base;
        for (unsigned k = 2; used_names.count(name); ++k)
            name = base + "-" + std::to_string(k);
        used_names[name] = static_cast<unsigned>(i);
        devices[i].name = name;
        devices[i].line = s.where.line;
    }

    // The cabling: PreviousPort (ENI port A-D = ESC port 0-3) names the device and port this one's port 0
    // is cabled to; without one, the slave before it in the ENI, port B (a line).
    std::vector<bool> explicit_upstream(n, false);
    std::vector<std::map<unsigned, std::size_t>> taken(n);
    std::vector<std::uint8_t> ports_used(n, 0b0001);
    for (std::size_t i = 0; i < n; ++i) {
        const EniSlave& s = eni.slaves[i];
        const EniPreviousPort* pp = previous_port(eni, s, out.notes);
        if (i == 0) {
            if (pp && pp->phys_addr)
                throw EniError(eni_message(eni, pp->where,
                                           "the first slave is cabled to the master, not to PhysAddr " +
                                               std::to_string(*pp->phys_addr)));
            continue;
        }
        std::size_t up = i - 1;
        unsigned port = 1;
        if (pp) {
            if (!pp->phys_addr)
                throw EniError(eni_message(eni, pp->where, "no <PhysAddr> of the previous slave"));
            const auto it = by_addr.find(*pp->phys_addr);
            if (it == by_addr.end())
                throw EniError(eni_message(
                    eni, pp->where,
                    "PhysAddr " + std::to_string(*pp->phys_addr) + " names no slave of this ENI"));
            if (it->second == i) throw EniError(eni_message(eni, pp->where, "the slave is cabled to itself"));
            if (pp->port == 0)
                throw EniError(eni_message(eni, pp->where,
                                           "port A of a slave leads to the master: no slave is "
                                           "cabled to it"));
            up = it->second;
            port = pp->port;
        }
        if (const auto t = taken[up].find(port); t != taken[up].end())
            throw EniError(eni_message(eni, pp ? pp->where : s.where,
                                       "port " + std::string(1, static_cast<char>('A' + port)) + " of " +
                                           eni.slaves[up].name + " is already cabled to " +
                                           eni.slaves[t->second].name + " (line " +
                                           std::to_string(eni.slaves[t->second].where.line) + ")"));
        taken[up][port] = i;
        ports_used[up] = static_cast<std::uint8_t>(ports_used[up] | (1u << port));
        devices[i].upstream = devices[up].name;
        devices[i].upstream_port = port;
        explicit_upstream[i] = true;  // the upstream is named either way
    }

    // Each slave's device: an ESI's, or one made from the ENI.
    std::optional<EsiIndex> esi;
    if (!options.esi_dir.empty()) esi = index_esi_dir(eni, options.esi_dir, out.notes);
    for (std::size_t i = 0; i < n; ++i) {
        const EniSlave& s = eni.slaves[i];
        DeviceEntry& e = devices[i];
        if (s.vendor_id == 0)
            throw EniError(eni_message(eni, s.where, "VendorId 0: no device can be made without a vendor"));
        if (esi) {
            if (auto found = find_esi(*esi, eni, s, out.notes)) {
                e.source = Source::Esi;
                e.path = found->path;
                e.esi_type = found->device.type;
                e.esi_product = found->device.product_code;
                e.esi_revision = found->device.revision;
                if (s.serial && *s.serial) e.identity.serial = *s.serial;
                continue;
            }
        }
        std::vector<std::string> notes;
        device::DeviceDescription d = description_from_eni(eni, s, notes);
        for (auto& x : notes)
            out.notes.push_back(std::move(x));
        try {
            e.sii_image = std::make_shared<const std::vector<std::uint8_t>>(
                sii_image_from_eni(d, s.physics, ports_used[i]));
        } catch (const std::exception& x) {
            throw EniError(eni_message(eni, s.where, std::string("no SII image can be made: ") + x.what()));
        }
        e.source = Source::Sii;
        e.path = "(ENI " + s.where.path + ")";
    }

    try {
        out.file = arrange_network(std::move(devices), explicit_upstream, eni.file, ".");
    } catch (const NetworkFileError& x) {
        throw EniError(x.what());
    }
    // The slave of each device, and the positions the ENI gives against those of the cabling.
    for (std::size_t k = 0; k < out.file.devices.size(); ++k) {
        const std::size_t idx = used_names.at(out.file.devices[k].name);
        out.slave.push_back(idx);
        const EniSlave& s = eni.slaves[idx];
        const auto expected = static_cast<std::uint16_t>(-static_cast<int>(k));
        if (s.auto_inc_addr && *s.auto_inc_addr != expected)
            throw EniError(
                eni_message(eni, s.where,
                            "AutoIncAddr " + std::to_string(static_cast<std::int16_t>(*s.auto_inc_addr)) +
                                " (position " + std::to_string((0x10000 - *s.auto_inc_addr) & 0xFFFF) +
                                "), but the PreviousPort cabling puts it at position " + std::to_string(k)));
    }
    return out;
}

}  // namespace vecat::network

namespace vecat::network {

namespace {

// A YAML scalar that reads back as the same string (quoted when plain would not).
std::string yaml_string(const std::string& s) {
    const bool plain = !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == '/';
    });
    if (plain) return s;
    std::string q = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') q += '\\';
        q += c;
    }
    return q + "\"";
}

}  // namespace

EniNetworkFile network_file_from_eni(const Eni& eni, const EniNetwork& n, const std::string& out_folder) {
    EniNetworkFile out;
    std::ostringstream y;
    y << "# The network of " << eni.file
      << " (vecat network from-eni): one device per ENI Slave element, in\n"
      << "# the order the frame reaches them. Devices made from the ENI alone are their SII images "
         "(NAME.sii).\n"
      << "devices:\n";
    const fs::path folder = out_folder.empty() ? fs::path(".") : fs::path(out_folder);
    for (std::size_t k = 0; k < n.file.devices.size(); ++k) {
        const DeviceEntry& d = n.file.devices[k];
        const EniSlave& s = eni.slaves[n.slave[k]];
        std::string label = s.name;  // in a comment: one line
        std::replace_if(
            label.begin(), label.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
        y << "  - name: " << d.name << "  # " << s.where.path << " \"" << label << "\", line " << s.where.line
          << "\n";
        if (d.source == Source::Esi) {
            std::error_code ec;
            fs::path rel = fs::relative(fs::absolute(d.path), fs::absolute(folder), ec);
            if (ec || rel.empty()) rel = fs::absolute(d.path);
            y << "    esi: " << yaml_string(rel.generic_string()) << "\n";
            if (d.esi_type) y << "    type: " << yaml_string(*d.esi_type) << "\n";
            if (d.esi_product) y << "    product: " << hex(*d.esi_product) << "\n";
            if (d.esi_revision) y << "    revision: " << hex(*d.esi_revision) << "\n";
        } else {
            const std::string file = d.name + ".sii";
            y << "    sii: " << yaml_string(file) << "\n";
            out.files.emplace_back(file, *d.sii_image);
        }
        if (n.file.parent[k] >= 0)
            y << "    upstream: " << n.file.devices[static_cast<std::size_t>(n.file.parent[k])].name << ":"
              << d.upstream_port << "\n";
        if (d.identity.serial) y << "    identity: {serial: " << *d.identity.serial << "}\n";
    }
    out.yaml = y.str();
    return out;
}

}  // namespace vecat::network
