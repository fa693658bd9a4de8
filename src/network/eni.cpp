#include "network/eni.hpp"

#include <pugixml.hpp>

#include <algorithm>
#include <fstream>
#include <limits>
#include <sstream>

#include "common/file.hpp"
#include "device/device_description.hpp"

namespace vecat::network {

namespace {

std::string trim(std::string s) {
    const auto space = [](unsigned char c) { return std::isspace(c) != 0; };
    s.erase(s.begin(), std::find_if_not(s.begin(), s.end(), space));
    s.erase(std::find_if_not(s.rbegin(), s.rend(), space).base(), s.end());
    return s;
}

// The largest datagram an InitCmd can carry (one frame: ETG.1000.4, 1486 bytes of datagram data).
constexpr std::size_t kMaxDatagramData = 1486;

// Mailbox/Protocol names (ETG.2100 MailboxType) and their SII mailbox protocol bits.
struct ProtocolName {
    std::string_view name;
    std::uint16_t bit;
};
constexpr ProtocolName kProtocols[] = {
    {"AoE", device::mbx_proto::AoE}, {"EoE", device::mbx_proto::EoE}, {"CoE", device::mbx_proto::CoE},
    {"FoE", device::mbx_proto::FoE}, {"SoE", device::mbx_proto::SoE}, {"VoE", device::mbx_proto::VoE},
};

class Reader {
  public:
    Reader(const std::string& text, std::string name) : name_(std::move(name)) {
        for (std::size_t i = 0; i < text.size(); ++i)
            if (text[i] == '\n') line_starts_.push_back(i + 1);
    }

    const std::string& name() const { return name_; }

    unsigned line_of(std::ptrdiff_t offset) const {
        if (offset < 0) return 0;
        const auto it =
            std::upper_bound(line_starts_.begin(), line_starts_.end(), static_cast<std::size_t>(offset));
        return static_cast<unsigned>(it - line_starts_.begin());
    }

    // "EtherCATConfig/Config/Slave[2]/Info": the element's path, with the 1-based index among same-named
    // siblings when there are several.
    static std::string path_of(pugi::xml_node n) {
        std::string path;
        for (; n && n.type() == pugi::node_element; n = n.parent()) {
            std::string part = n.name();
            unsigned index = 1, count = 0;
            for (auto s = n.parent().child(n.name()); s; s = s.next_sibling(n.name())) {
                ++count;
                if (s == n) index = count;
            }
            if (count > 1) part += "[" + std::to_string(index) + "]";
            path = path.empty() ? part : part + "/" + path;
        }
        return path;
    }

    EniWhere where(pugi::xml_node n) const { return {line_of(n.offset_debug()), path_of(n)}; }

    [[noreturn]] void fail(pugi::xml_node n, const std::string& what) const {
        const EniWhere w = where(n);
        throw EniError(name_ + ":" + std::to_string(w.line) + ": " + w.path + ": " + what);
    }

    pugi::xml_node require(pugi::xml_node parent, const char* child) const {
        const pugi::xml_node c = parent.child(child);
        if (!c) fail(parent, std::string("no <") + child + ">");
        return c;
    }

    static std::string text(pugi::xml_node n) {
        std::string s;
        for (auto c : n.children())
            if (c.type() == pugi::node_pcdata || c.type() == pugi::node_cdata) s += c.value();
        return trim(s);
    }

    // An ETG.2100 HexDecValue in [lo, hi]: "#x1A00", "0x1A00", "6656", "-1".
    std::int64_t number(pugi::xml_node n, const std::string& s, std::int64_t lo, std::int64_t hi) const {
        std::string t = s;
        bool negative = false;
        if (!t.empty() && t[0] == '-') {
            negative = true;
            t.erase(0, 1);
        }
        int base = 10;
        if (t.size() > 2 && ((t[0] == '#' && (t[1] == 'x' || t[1] == 'X')) ||
                             (t[0] == '0' && (t[1] == 'x' || t[1] == 'X')))) {
            base = 16;
            t.erase(0, 2);
        }
        if (t.empty() || t.size() > 20 || !std::all_of(t.begin(), t.end(), [&](char c) {
                return base == 16 ? std::isxdigit(static_cast<unsigned char>(c)) != 0
                                  : std::isdigit(static_cast<unsigned char>(c)) != 0;
            }))
            fail(n, "\"" + s + "\" is not a number");
        std::uint64_t v = 0;
        try {
            v = std::stoull(t, nullptr, base);
        } catch (const std::exception&) {
            fail(n, "\"" + s + "\" is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
        }
        const auto limit = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
        if (v > limit) fail(n, "\"" + s + "\" is out of range");
        const std::int64_t r = negative ? -static_cast<std::int64_t>(v) : static_cast<std::int64_t>(v);
        if (r < lo || r > hi)
            fail(n, s + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
        return r;
    }

    // An unsigned value of `bits` bits.
    std::uint64_t value(pugi::xml_node n, unsigned bits) const {
        return static_cast<std::uint64_t>(number(n, text(n), 0, (std::int64_t{1} << bits) - 1));
    }
    // An identifier or address the schema types xs:int: its bit pattern, also written negative.
    std::uint64_t pattern(pugi::xml_node n, unsigned bits) const {
        const std::int64_t v =
            number(n, text(n), -(std::int64_t{1} << (bits - 1)), (std::int64_t{1} << bits) - 1);
        return static_cast<std::uint64_t>(v) & ((std::uint64_t{1} << bits) - 1);
    }
    template <class T>
    T child_value(pugi::xml_node parent, const char* child) const {
        return static_cast<T>(value(require(parent, child), sizeof(T) * 8));
    }
    template <class T>
    std::optional<T> optional_value(pugi::xml_node parent, const char* child) const {
        const auto c = parent.child(child);
        if (!c) return std::nullopt;
        return static_cast<T>(value(c, sizeof(T) * 8));
    }

    bool boolean(pugi::xml_node n, const std::string& s) const {
        if (s == "1" || s == "true") return true;
        if (s == "0" || s == "false") return false;
        fail(n, "\"" + s + "\" is not a boolean (true, false, 1, 0)");
    }
    bool bool_attr(pugi::xml_node n, const char* a) const {
        const auto at = n.attribute(a);
        return at && boolean(n, trim(at.value()));
    }
    bool bool_child(pugi::xml_node n, const char* c) const {
        const auto ch = n.child(c);
        return ch && boolean(ch, text(ch));
    }

    // hexBinary: two hex digits a byte.
    std::vector<std::uint8_t> hex(pugi::xml_node n) const {
        const std::string s = text(n);
        if (s.size() % 2) fail(n, "hexBinary of odd length " + std::to_string(s.size()));
        if (s.size() / 2 > kMaxDatagramData)
            fail(n, std::to_string(s.size() / 2) + " bytes do not fit in a frame (at most " +
                        std::to_string(kMaxDatagramData) + ")");
        std::vector<std::uint8_t> out;
        for (std::size_t i = 0; i < s.size(); i += 2) {
            const auto nib = [&](char c) -> unsigned {
                if (c >= '0' && c <= '9') return static_cast<unsigned>(c - '0');
                if (c >= 'a' && c <= 'f') return static_cast<unsigned>(c - 'a' + 10);
                if (c >= 'A' && c <= 'F') return static_cast<unsigned>(c - 'A' + 10);
                fail(n, "\"" + s + "\" is not hexBinary");
            };
            out.push_back(static_cast<std::uint8_t>(nib(s[i]) << 4 | nib(s[i + 1])));
        }
        return out;
    }

    EniTransitions transitions(pugi::xml_node cmd) const {
        EniTransitions t = 0;
        for (auto tr : cmd.children("Transition")) {
            const std::string s = text(tr);
            const auto* it = std::find(kEniTransitionNames.begin(), kEniTransitionNames.end(), s);
            if (it == kEniTransitionNames.end())
                fail(tr, "unknown transition \"" + s + "\" (II, IP, PI, PS, SP, SO, OS, OP, ...)");
            t = static_cast<EniTransitions>(t | (1u << (it - kEniTransitionNames.begin())));
        }
        return t;
    }

  private:
    std::string name_;
    std::vector<std::size_t> line_starts_{0};
};

EniInitCmd init_cmd(const Reader& r, pugi::xml_node n) {
    EniInitCmd c;
    c.where = r.where(n);
    c.transitions = r.transitions(n);
    c.before_slave = r.bool_child(n, "BeforeSlave");
    c.comment = Reader::text(n.child("Comment"));
    const auto cmd = r.require(n, "Cmd");
    c.cmd = static_cast<std::uint8_t>(r.value(cmd, 8));
    if (c.cmd > 14) r.fail(cmd, "unknown datagram command " + std::to_string(c.cmd) + " (0-14)");
    if (const auto a = n.child("Addr")) {
        if (n.child("Adp") || n.child("Ado")) r.fail(a, "<Addr> together with <Adp>/<Ado>");
        c.addr = static_cast<std::uint32_t>(r.pattern(a, 32));
    } else {
        c.ado = static_cast<std::uint16_t>(r.value(r.require(n, "Ado"), 16));
        if (const auto p = n.child("Adp")) c.adp = static_cast<std::uint16_t>(r.pattern(p, 16));
    }
    const auto data = n.child("Data");
    const auto length = n.child("DataLength");
    if (data && length) r.fail(length, "<DataLength> together with <Data>");
    if (data) c.data = r.hex(data);
    if (length) {
        const auto len = r.value(length, 16);
        if (len > kMaxDatagramData) r.fail(length, std::to_string(len) + " bytes do not fit in a frame");
        c.data.assign(len, 0);
    }
    c.cnt = r.optional_value<std::uint16_t>(n, "Cnt");
    c.retries = r.optional_value<std::uint16_t>(n, "Retries").value_or(0);
    return c;
}

std::vector<EniInitCmd> init_cmds(const Reader& r, pugi::xml_node parent) {
    std::vector<EniInitCmd> out;
    for (auto c : parent.child("InitCmds").children("InitCmd"))
        out.push_back(init_cmd(r, c));
    return out;
}

EniCoeInitCmd coe_init_cmd(const Reader& r, pugi::xml_node n) {
    EniCoeInitCmd c;
    c.where = r.where(n);
    c.transitions = r.transitions(n);
    if (!c.transitions) r.fail(n, "no <Transition>");
    c.comment = Reader::text(n.child("Comment"));
    const auto ccs = r.require(n, "Ccs");
    c.ccs = static_cast<std::uint8_t>(r.value(ccs, 8));
    if (c.ccs != 1 && c.ccs != 2) r.fail(ccs, "Ccs is 1 (download) or 2 (upload)");
    c.index = r.child_value<std::uint16_t>(n, "Index");
    c.subindex = r.child_value<std::uint8_t>(n, "SubIndex");
    c.complete_access = r.bool_attr(n, "CompleteAccess");
    c.disabled = r.bool_child(n, "Disabled");
    if (const auto d = n.child("Data")) c.data = r.hex(d);
    return c;
}

EniMailboxArea area(const Reader& r, pugi::xml_node n) {
    return {r.child_value<std::uint16_t>(n, "Start"), r.child_value<std::uint16_t>(n, "Length")};
}

std::optional<EniMailbox> mailbox(const Reader& r, pugi::xml_node slave) {
    const auto n = slave.child("Mailbox");
    if (!n) return std::nullopt;
    EniMailbox m;
    m.where = r.where(n);
    m.send = area(r, r.require(n, "Send"));
    // ETG.2100 names it Recv; SOEM's sample ENI writes Receive.
    pugi::xml_node recv = n.child("Recv");
    if (!recv) recv = n.child("Receive");
    if (!recv) r.fail(n, "no <Recv>");
    m.recv = area(r, recv);
    if (const auto b = n.child("BootStrap")) {
        m.boot_send = area(r, r.require(b, "Send"));
        pugi::xml_node br = b.child("Recv");
        if (!br) br = b.child("Receive");
        if (!br) r.fail(b, "no <Recv>");
        m.boot_recv = area(r, br);
    }
    for (auto p : n.children("Protocol")) {
        const std::string s = Reader::text(p);
        const auto* it = std::find_if(std::begin(kProtocols), std::end(kProtocols),
                                      [&](const ProtocolName& k) { return k.name == s; });
        if (it == std::end(kProtocols))
            r.fail(p, "unknown mailbox protocol \"" + s + "\" (AoE, EoE, CoE, FoE, SoE, VoE)");
        m.protocols = static_cast<std::uint16_t>(m.protocols | it->bit);
    }
    for (auto c : n.child("CoE").child("InitCmds").children("InitCmd"))
        m.coe_init_cmds.push_back(coe_init_cmd(r, c));
    return m;
}

EniPdo pdo(const Reader& r, pugi::xml_node n) {
    EniPdo p;
    p.where = r.where(n);
    p.index = r.child_value<std::uint16_t>(n, "Index");
    p.name = Reader::text(n.child("Name"));
    if (const auto sm = n.attribute("Sm")) {
        const auto v = r.number(n, trim(sm.value()), 0, 15);
        p.sm = static_cast<std::uint8_t>(v);
    }
    p.fixed = r.bool_attr(n, "Fixed");
    p.mandatory = r.bool_attr(n, "Mandatory");
    for (auto e : n.children("Entry")) {
        EniPdoEntry x;
        x.where = r.where(e);
        x.index = r.child_value<std::uint16_t>(e, "Index");
        x.subindex = r.optional_value<std::uint8_t>(e, "SubIndex").value_or(0);
        x.bit_length = r.child_value<std::uint8_t>(e, "BitLen");
        if (x.bit_length == 0) r.fail(e.child("BitLen"), "BitLen 0");
        x.name = Reader::text(e.child("Name"));
        x.data_type = Reader::text(e.child("DataType"));
        p.entries.push_back(std::move(x));
    }
    return p;
}

void process_data(const Reader& r, pugi::xml_node slave, EniSlave& s) {
    const auto n = slave.child("ProcessData");
    if (!n) return;
    for (auto c : n.children()) {
        const std::string name = c.name();
        if (name.size() == 3 && name.rfind("Sm", 0) == 0 && name[2] >= '0' && name[2] <= '9') {
            EniSyncManager sm;
            sm.where = r.where(c);
            sm.number = static_cast<unsigned>(name[2] - '0');
            if (sm.number > 3) r.fail(c, "ETG.2100 names Sm0 to Sm3");
            const auto type = r.require(c, "Type");
            const std::string t = Reader::text(type);
            if (t != "Inputs" && t != "Outputs") r.fail(type, "\"" + t + "\" is neither Inputs nor Outputs");
            sm.outputs = t == "Outputs";
            sm.default_size = r.optional_value<std::uint16_t>(c, "DefaultSize").value_or(0);
            sm.start = r.child_value<std::uint16_t>(c, "StartAddress");
            sm.control = r.child_value<std::uint8_t>(c, "ControlByte");
            sm.enable = r.bool_child(c, "Enable");
            for (auto p : c.children("Pdo"))
                sm.pdos.push_back(static_cast<std::uint16_t>(r.value(p, 16)));
            for (const auto& other : s.sync_managers)
                if (other.number == sm.number) r.fail(c, "a second " + name);
            s.sync_managers.push_back(std::move(sm));
        } else if (name == "RxPdo") {
            s.rx_pdos.push_back(pdo(r, c));
        } else if (name == "TxPdo") {
            s.tx_pdos.push_back(pdo(r, c));
        }
    }
}

EniSlave slave(const Reader& r, pugi::xml_node n) {
    EniSlave s;
    s.where = r.where(n);
    const auto info = r.require(n, "Info");
    s.name = Reader::text(info.child("Name"));
    if (s.name.empty()) r.fail(info, "no <Name>");
    s.phys_addr = r.optional_value<std::uint16_t>(info, "PhysAddr");
    if (const auto a = info.child("AutoIncAddr"))
        s.auto_inc_addr = static_cast<std::uint16_t>(r.pattern(a, 16));
    s.physics = info.child("Physics").text().get();  // spaces count: a port without physics
    if (s.physics.size() > kPorts) r.fail(info.child("Physics"), "more than four ports");
    for (char c : s.physics)
        if (c != 'Y' && c != 'H' && c != 'K' && c != ' ')
            r.fail(info.child("Physics"), std::string("port physics '") + c + "' (Y, H, K or a space)");
    s.vendor_id = static_cast<std::uint32_t>(r.pattern(r.require(info, "VendorId"), 32));
    s.product_code = static_cast<std::uint32_t>(r.pattern(r.require(info, "ProductCode"), 32));
    s.revision = static_cast<std::uint32_t>(r.pattern(r.require(info, "RevisionNo"), 32));
    if (const auto sn = info.child("SerialNo")) s.serial = static_cast<std::uint32_t>(r.pattern(sn, 32));
    s.mailbox = mailbox(r, n);
    process_data(r, n, s);
    s.init_cmds = init_cmds(r, n);
    for (auto p : n.children("PreviousPort")) {
        EniPreviousPort pp;
        pp.where = r.where(p);
        pp.selected = r.bool_attr(p, "Selected");
        const auto port = r.require(p, "Port");
        const std::string letter = Reader::text(port);
        if (letter.size() != 1 || letter[0] < 'A' || letter[0] > 'D')
            r.fail(port, "\"" + letter + "\": A, B, C or D");
        pp.port = static_cast<unsigned>(letter[0] - 'A');
        pp.phys_addr = r.optional_value<std::uint16_t>(p, "PhysAddr");
        s.previous_ports.push_back(pp);
    }
    return s;
}

}  // namespace

std::string eni_message(const Eni& eni, const EniWhere& at, const std::string& what) {
    return eni.file + ":" + std::to_string(at.line) + ": " + at.path + ": " + what;
}

Eni parse_eni(const std::string& text, const std::string& name) {
    const Reader r(text, name);
    pugi::xml_document doc;
    const pugi::xml_parse_result ok = doc.load_buffer(text.data(), text.size(), pugi::parse_default);
    if (!ok)
        throw EniError(name + ":" + std::to_string(r.line_of(ok.offset)) + ": not XML: " + ok.description());
    const auto root = doc.document_element();
    if (std::string_view(root.name()) != "EtherCATConfig")
        throw EniError(name + ":" + std::to_string(r.line_of(root.offset_debug())) + ": <" + root.name() +
                       "> is no ENI (the root element of an ENI is <EtherCATConfig>, ETG.2100)");
    Eni eni;
    eni.file = name;
    const auto config = root.child("Config");
    if (!config)
        throw EniError(name + ":" + std::to_string(r.line_of(root.offset_debug())) +
                       ": EtherCATConfig: no <Config>");
    if (const auto master = config.child("Master")) {
        eni.master_name = Reader::text(master.child("Info").child("Name"));
        eni.master_init_cmds = init_cmds(r, master);
    }
    for (auto s : config.children("Slave"))
        eni.slaves.push_back(slave(r, s));
    if (eni.slaves.empty()) r.fail(config, "no <Slave>");
    return eni;
}

Eni read_eni_file(const std::string& path) {
    std::string why;
    const auto text = read_whole_file(path, kMaxXmlFileBytes, why);
    if (!text) throw EniError(path + ": " + why);
    return parse_eni(*text, path);
}

}  // namespace vecat::network
