// vecat clone (src/clone): a running network read with the project master and written as a network file;
// the copy, served, answers the project master's start-up and 1,000 cycles of process data with the same
// reply frames as the original, byte for byte. Both are served in-process on the same simulated clock
// (each frame advances it by the same step), so the time-dependent registers agree too. A device that
// refuses SDO information still gives a usable copy and a list of what is missing.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "clone/clone.hpp"
#include "master/coe_client.hpp"
#include "master/master.hpp"
#include "network/build.hpp"
#include "network/network_file.hpp"
#include "serve/in_process_link.hpp"
#include "shared_data.hpp"

namespace vecat::clone {
namespace {

namespace fs = std::filesystem;

// An in-process link on a simulated clock: every frame sent advances it by one step (the same sequence of
// frames sees the same times), and every reply is kept.
class RecordingLink final : public net::Link {
  public:
    explicit RecordingLink(esc::Segment& seg) : inner_(seg) { inner_.set_time(now_); }
    bool send(ConstBytes frame) override {
        now_ += kStepNs;
        inner_.set_time(now_);
        sent_.emplace_back(frame.begin(), frame.end());
        return inner_.send(frame);
    }
    long receive(Bytes out, std::int64_t timeout_us) override {
        const long n = inner_.receive(out, timeout_us);
        if (n > 0) replies_.emplace_back(out.begin(), out.begin() + n);
        return n;
    }
    const std::vector<std::vector<std::uint8_t>>& sent() const { return sent_; }
    const std::vector<std::vector<std::uint8_t>>& replies() const { return replies_; }

  private:
    static constexpr std::uint64_t kStepNs = 50'000;
    net::InProcessLink inner_;
    std::uint64_t now_ = 1'000'000'000;
    std::vector<std::vector<std::uint8_t>> sent_, replies_;
};

// A network served in-process from a file.
struct Served {
    explicit Served(const std::string& file)
        : built(network::build_network(network::read_network_file(file), file)), link(*built.segment) {}
    network::BuiltNetwork built;
    RecordingLink link;
};

fs::path fresh_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("vecat-clone-" + name);
    fs::remove_all(d);
    return d;
}

// Clones the network of `file` into dir; returns the clone's network file.
std::string clone_of(const std::string& file, const fs::path& dir, CloneResult* out = nullptr) {
    Served original(file);
    master::Master m(original.link);
    CloneResult r = read_line(m);
    const std::string written = write_clone(r, dir.string());
    if (out) *out = std::move(r);
    return written;
}

// The project master's start-up to OP and n cycles of process data; the replies it got.
std::vector<std::vector<std::uint8_t>> drive(const std::string& file, unsigned cycles, std::string& why) {
    Served s(file);
    master::Master m(s.link);
    if (!m.startup(protocol::AlState::Op, &why)) {
        for (std::size_t i = 0; i < m.slaves().size(); ++i) {
            const auto st = m.read_al_status(m.slaves()[i].station);
            char buf[64];
            std::snprintf(buf, sizeof buf, "; slave %zu: AL status 0x%02x, code 0x%04x", i, st.status,
                          st.code);
            why += buf;
        }
        return {};
    }
    for (unsigned i = 0; i < cycles; ++i)
        if (m.exchange_process_data().value_or(0) != m.expected_wkc()) {
            why = "cycle " + std::to_string(i) + ": working counter";
            return {};
        }
    return s.link.replies();
}

// The same with distributed clocks, step by step as startup() does them but with a fixed master time (the
// start-up's own configure_dc() takes the host's): delays and offsets, drift compensation, SYNC0 on every
// DC device, then SAFEOP, OP and n cycles, each carrying the FRMW of the reference clock.
std::vector<std::vector<std::uint8_t>> drive_with_dc(const std::string& file, unsigned cycles,
                                                     std::string& why) {
    Served s(file);
    master::Master m(s.link);
    using protocol::AlState;
    if (!m.startup(AlState::PreOp, &why)) return {};
    if (!m.configure_process_data()) return why = "process data", std::vector<std::vector<std::uint8_t>>{};
    if (!m.configure_dc(700'000'000'000'000'000ull) || m.dc_reference() == 0)
        return why = "DC", std::vector<std::vector<std::uint8_t>>{};
    m.compensate_static_drift(100);
    for (const auto& sl : m.slaves())
        if (sl.has_dc && !m.start_sync(sl.station, 1'000'000, 0, 1'000'000))
            return why = "SYNC0", std::vector<std::vector<std::uint8_t>>{};
    if (!m.request_state(AlState::SafeOp)) return why = "SAFEOP", std::vector<std::vector<std::uint8_t>>{};
    m.exchange_process_data();
    if (!m.request_state(AlState::Op)) return why = "OP", std::vector<std::vector<std::uint8_t>>{};
    for (unsigned i = 0; i < cycles; ++i)
        if (m.exchange_process_data().value_or(0) != m.expected_wkc()) {
            why = "cycle " + std::to_string(i) + ": working counter";
            return {};
        }
    return s.link.replies();
}

// The first differences of two reply sequences, readable: frame number, byte offset, both bytes.
std::string differences(const std::vector<std::vector<std::uint8_t>>& a,
                        const std::vector<std::vector<std::uint8_t>>& b) {
    std::string s;
    int shown = 0;
    if (a.size() != b.size())
        s += "frames: " + std::to_string(a.size()) + " from the original, " + std::to_string(b.size()) +
             " from the copy\n";
    for (std::size_t i = 0; i < std::min(a.size(), b.size()) && shown < 10; ++i) {
        if (a[i] == b[i]) continue;
        ++shown;
        s += "frame " + std::to_string(i) + " (" + std::to_string(a[i].size()) + " / " +
             std::to_string(b[i].size()) + " bytes):";
        for (std::size_t k = 0; k < std::max(a[i].size(), b[i].size()); ++k) {
            const int x = k < a[i].size() ? a[i][k] : -1, y = k < b[i].size() ? b[i][k] : -1;
            if (x == y) continue;
            char buf[48];
            std::snprintf(buf, sizeof buf, " @%zu %02x/%02x", k, x & 0xFF, y & 0xFF);
            s += buf;
        }
        s += "\n";
    }
    return s;
}

void expect_byte_equal_copy(const std::string& original_file, const std::string& name) {
    const fs::path dir = fresh_dir(name);
    const std::string copy = clone_of(original_file, dir);
    std::string why;
    const auto a = drive(original_file, 1000, why);
    ASSERT_FALSE(a.empty()) << "original: " << why;
    const auto b = drive(copy, 1000, why);
    ASSERT_FALSE(b.empty()) << "copy: " << why;
    EXPECT_GT(a.size(), 1000u);
    EXPECT_TRUE(a == b) << differences(a, b);
    fs::remove_all(dir);
}

TEST(Clone, ACopyOfTheMixedLineRepliesByteEqualToStartUpAnd1000Cycles) {
    expect_byte_equal_copy(std::string(VECAT_SOURCE_DIR) + "/examples/networks/mixed-line.yaml", "mixed");
}

TEST(Clone, ACopyOfVendorEsiDevicesRepliesByteEqualToStartUpAnd1000Cycles) {
    VECAT_REQUIRE_SHARED_DATA("esi");
    const fs::path dir = fresh_dir("esi-original");
    fs::create_directories(dir);
    const std::string esi = test::shared_data("esi/");
    std::ofstream(dir / "network.yaml")
        << "devices:\n  - name: coupler\n    device: coupler\n"
        << "  - name: sv660n\n    esi: " << esi << "inovance-SV660N.xml\n"
        << "  - name: somanet\n    esi: " << esi << "synapticon-somanet-cia402.xml\n"
        << "  - name: elmo\n    esi: " << esi << "elmo-gold.xml\n";
    expect_byte_equal_copy((dir / "network.yaml").string(), "esi");
    fs::remove_all(dir);
}

TEST(Clone, ACopyRepliesByteEqualWithDistributedClocks) {
    // The receive times, system times and SYNC0 start times in the replies depend on the cable delays and
    // on the clock: the copy has the delays measured, and both run on the same simulated clock.
    const std::string original = std::string(VECAT_SOURCE_DIR) + "/examples/networks/mixed-line.yaml";
    const fs::path dir = fresh_dir("dc");
    const std::string copy = clone_of(original, dir);
    std::string why;
    const auto a = drive_with_dc(original, 1000, why);
    ASSERT_FALSE(a.empty()) << "original: " << why;
    const auto b = drive_with_dc(copy, 1000, why);
    ASSERT_FALSE(b.empty()) << "copy: " << why;
    EXPECT_TRUE(a == b) << differences(a, b);
    fs::remove_all(dir);
}

TEST(Clone, TheCopyAnswersSdoInformationAndUploadsAsTheOriginal) {
    const std::string original = std::string(VECAT_SOURCE_DIR) + "/examples/networks/mixed-line.yaml";
    const fs::path dir = fresh_dir("sdo");
    const std::string copy = clone_of(original, dir);
    Served a(original), b(copy);
    master::Master ma(a.link), mb(b.link);
    std::string why;
    ASSERT_TRUE(ma.startup(protocol::AlState::PreOp, &why)) << why;
    ASSERT_TRUE(mb.startup(protocol::AlState::PreOp, &why)) << why;
    const std::size_t before_a = a.link.replies().size(), before_b = b.link.replies().size();
    // The drive (position 4): every object's description and every entry's description and value.
    master::CoeClient ca(ma, ma.slaves()[4].station), cb(mb, mb.slaves()[4].station);
    const auto list = ca.od_list(protocol::sdo_info::ListAll);
    ASSERT_TRUE(list);
    EXPECT_EQ(cb.od_list(protocol::sdo_info::ListAll), list);
    for (const std::uint16_t index : *list) {
        const auto oa = ca.object_description(index);
        cb.object_description(index);
        if (!oa) continue;
        for (unsigned sub = 0; sub <= oa->max_subindex; ++sub) {
            ca.entry_description(index, static_cast<std::uint8_t>(sub), 0x70);
            cb.entry_description(index, static_cast<std::uint8_t>(sub), 0x70);
            ca.upload(index, static_cast<std::uint8_t>(sub));
            cb.upload(index, static_cast<std::uint8_t>(sub));
        }
    }
    const std::vector<std::vector<std::uint8_t>> ra(a.link.replies().begin() + static_cast<long>(before_a),
                                                    a.link.replies().end());
    const std::vector<std::vector<std::uint8_t>> rb(b.link.replies().begin() + static_cast<long>(before_b),
                                                    b.link.replies().end());
    EXPECT_GT(ra.size(), 1000u);
    EXPECT_TRUE(ra == rb) << differences(ra, rb);
    fs::remove_all(dir);
}

TEST(Clone, TheCopyHasTheTreeTheCableDelaysAndTheWholeSii) {
    CloneResult r;
    const fs::path dir = fresh_dir("tree");
    const std::string original = std::string(VECAT_SOURCE_DIR) + "/examples/networks/mixed-line.yaml";
    clone_of(original, dir, &r);
    const auto f = network::read_network_file((dir / "network.yaml").string());
    const auto o = network::read_network_file(original);
    ASSERT_EQ(f.devices.size(), o.devices.size());
    EXPECT_EQ(f.parent, o.parent);
    for (std::size_t i = 0; i < f.devices.size(); ++i) {
        SCOPED_TRACE(i);
        EXPECT_EQ(f.devices[i].upstream_port, o.devices[i].upstream_port);
        if (i > 0) {
            EXPECT_EQ(f.devices[i].cable_delay_ns, o.devices[i].cable_delay_ns);
        }
    }
    // The SII as large as the EEPROM, not only up to its end marker.
    const auto built = network::build_network(o, original);
    for (std::size_t i = 0; i < r.devices.size(); ++i)
        EXPECT_EQ(r.devices[i].sii, built.segment->slave(i).esc().eeprom()) << i;
    fs::remove_all(dir);
}

TEST(Clone, ADeviceRefusingSdoInformationGivesAUsableCopyAndWhatIsMissing) {
    // Given an original whose drive refuses SDO information: a copy of the default drive whose dictionary
    // file says so (the served device answers SDO information with a mailbox error).
    const fs::path first = fresh_dir("noinfo-first");
    clone_of(std::string(VECAT_SOURCE_DIR) + "/examples/networks/mixed-line.yaml", first);
    const std::string drive_file = "slave4-vecat-CiA402-servo-drive.dictionary.yaml";
    auto dict = network::read_dictionary_file((first / drive_file).string());
    dict.sdo_information = false;
    dict.missing.clear();
    std::ofstream(first / drive_file) << network::write_dictionary(dict);

    // When it is cloned,
    const fs::path second = fresh_dir("noinfo-second");
    CloneResult r;
    const std::string copy = clone_of((first / "network.yaml").string(), second, &r);

    // then the drive's copy says what is missing, in its result and in its files,
    const auto& d = r.devices.at(4);
    ASSERT_TRUE(d.dictionary);
    EXPECT_FALSE(d.dictionary->sdo_information);
    ASSERT_FALSE(d.missing.empty());
    EXPECT_NE(d.missing.front().find("SDO information refused"), std::string::npos) << d.missing.front();
    std::ifstream nf(second / "network.yaml");
    const std::string net((std::istreambuf_iterator<char>(nf)), std::istreambuf_iterator<char>());
    EXPECT_NE(net.find("# missing: SDO information refused"), std::string::npos);
    // it holds the values of the communication objects and of the mapped objects as uploaded,
    for (const auto& [index, sub] : std::vector<std::pair<std::uint16_t, std::uint8_t>>{{0x1000, 0},
                                                                                        {0x1008, 0},
                                                                                        {0x1018, 1},
                                                                                        {0x1018, 2},
                                                                                        {0x1C12, 1},
                                                                                        {0x1C13, 1},
                                                                                        {0x1600, 1},
                                                                                        {0x1A00, 1},
                                                                                        {0x6040, 0},
                                                                                        {0x6041, 0}}) {
        const auto it = d.dictionary->values.find({index, sub});
        ASSERT_NE(it, d.dictionary->values.end()) << std::hex << index << ":" << int{sub};
        EXPECT_EQ(it->second, dict.values.at({index, sub})) << std::hex << index << ":" << int{sub};
    }
    // and it is usable: the project master brings the copy to OP with the original's process data, and
    // its start-up and cycles are answered as the original's.
    std::string why;
    const auto a = drive((first / "network.yaml").string(), 100, why);
    ASSERT_FALSE(a.empty()) << "original: " << why;
    const auto b = drive(copy, 100, why);
    ASSERT_FALSE(b.empty()) << "copy: " << why;
    EXPECT_TRUE(a == b) << differences(a, b);
    fs::remove_all(first);
    fs::remove_all(second);
}

}  // namespace
}  // namespace vecat::clone
