// The master against an ENI's InitCmds (src/report/init_cmd_check): the ENI's register writes per slave
// position and transition, and the project master's start-up compared with an expectation: silent when the
// expectation is what the master does, one "missing" for a command it does not send and one "not in the
// ENI" for a write the expectation lacks.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "esi/esi_writer.hpp"

#include "master/master.hpp"
#include "network/build.hpp"
#include "network/eni.hpp"
#include "network/eni_network.hpp"
#include "report/init_cmd_check.hpp"
#include "serve/in_process_link.hpp"

namespace vecat::report {
namespace {

const std::string kEni = std::string(VECAT_SOURCE_DIR) + "/tests/network/data/line.eni.xml";

constexpr Transition kIP{1, 2};

TEST(InitCmdCheck, TheEnisWritesPerSlaveAndTransition) {
    const auto eni = network::read_eni_file(kEni);
    const auto n = network::network_from_eni(eni);
    const auto w = expected_writes(eni, n);
    // Coupler: "set physical address" (IP), "clear sm" (PI, SI, OI); drive (position 3): its address.
    ASSERT_EQ(w.size(), 3u);
    EXPECT_EQ(w[0].slave, 0u);
    EXPECT_EQ(w[0].transitions, (std::vector<Transition>{kIP}));
    EXPECT_EQ(w[0].ado, 0x0010);
    EXPECT_EQ(w[0].data, (std::vector<std::uint8_t>{0xE9, 0x03}));
    EXPECT_NE(w[0].label.find("line.eni.xml:28: EtherCATConfig/Config/Slave[1]/InitCmds/InitCmd[1]"),
              std::string::npos)
        << w[0].label;
    EXPECT_EQ(w[1].transitions.size(), 3u);
    EXPECT_EQ(w[1].data.size(), 32u);
    EXPECT_EQ(w[2].slave, 3u);
    EXPECT_EQ(w[2].data, (std::vector<std::uint8_t>{0xEC, 0x03}));
}

// The network of line.eni.xml (the drive from its ESI, the others from the ENI alone).
network::BuiltNetwork line() {
    const auto dir = std::filesystem::temp_directory_path() / "vecat-initcmd-esi";
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "vecat-drive.xml") << esi::write_esi(device::default_drive());
    auto built = network::build_network(
        network::network_from_eni(network::read_eni_file(kEni), {dir.string()}).file, "line");
    std::filesystem::remove_all(dir);
    return built;
}

// The line brought to OP by the project master with the check watching.
struct Watched {
    explicit Watched(std::vector<ExpectedWrite> expected)
        : built(line()), check(*built.segment, std::move(expected)), link(*built.segment), master(link) {
        link.set_observer(&check);
        std::string why;
        EXPECT_TRUE(master.startup(protocol::AlState::Op, &why)) << why;
    }
    network::BuiltNetwork built;
    InitCmdCheck check;
    net::InProcessLink link;
    master::Master master;
};

std::size_t count(const InitCmdCheck& c, bool missing) {
    return static_cast<std::size_t>(
        std::count_if(c.differences().begin(), c.differences().end(),
                      [&](const CommandDifference& d) { return d.missing == missing; }));
}

TEST(InitCmdCheck, ReportsTheMissingAndTheExtraCommandsOfTheMaster) {
    // Nothing expected: everything the master writes in the register space is "not in the ENI".
    Watched first({});
    const auto observed = first.check.observed();
    ASSERT_FALSE(observed.empty());
    EXPECT_EQ(count(first.check, true), 0u);
    EXPECT_GT(count(first.check, false), 0u);
    // Expecting what it does: silent.
    Watched same(observed);
    EXPECT_TRUE(same.check.differences().empty()) << same.check.summary();
    // One of its writes left out of the expectation, one command it never sends added.
    auto expected = observed;
    const auto dropped = std::find_if(expected.begin(), expected.end(), [](const ExpectedWrite& w) {
        return w.slave == 4 && w.transitions[0] == kIP && w.ado == protocol::addr(protocol::Reg::Sm0);
    });
    ASSERT_NE(dropped, expected.end());
    expected.erase(dropped);
    expected.push_back(
        {2, {kIP}, 0x0F80, {0x12, 0x34}, "m.xml:9: EtherCATConfig/Config/Slave[3]/InitCmds/InitCmd"});
    Watched changed(expected);
    ASSERT_EQ(changed.check.differences().size(), 2u) << changed.check.summary();
    const auto summary = changed.check.summary();
    EXPECT_NE(summary.find("slave 2 IP: missing: 0x0F80 1234 not written (m.xml:9: "), std::string::npos)
        << summary;
    EXPECT_NE(summary.find("slave 4 IP: not in the ENI: BWR 0x0800 0000"), std::string::npos) << summary;
    EXPECT_NE(summary.find("1 expected command(s) the master did not send, 1 write(s) the ENI does not have"),
              std::string::npos)
        << summary;
}

}  // namespace
}  // namespace vecat::report
