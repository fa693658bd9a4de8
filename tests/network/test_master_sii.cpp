// The project master reads a slave's SII image with one command and one read of the SII registers per
// command (ETG.1000.4 6.4; ESC datasheet section II, 0x0502-0x050F: control/status, address and data read
// together), and as many bytes a command as the ESC reads (0x0502 bit 6: 4 or 8).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "network_support.hpp"

namespace vecat::network {
namespace {

constexpr const char* kDrives = R"(
devices:
  - {name: reads-8, device: drive}
  - {name: reads-4, device: drive, esc: {sii_read_bytes: 4}}
)";

// The two slaves found, reset and given station addresses: the start-up up to the SII reads.
bool addressed(master::Master& m) {
    return m.count_slaves() == 2 && m.reset_slaves() && m.assign_station_addresses();
}

TEST(MasterSii, TheImageIsReadAsTheEscHoldsItWithTwoFramesACommand) {
    test::ServedNetwork n(kDrives);
    master::Master& m = n.master;
    ASSERT_TRUE(addressed(m));
    std::vector<std::uint64_t> frames;
    for (std::size_t k = 0; k < 2; ++k) {
        const std::uint64_t before = n.built.segment->counters().frames;
        const auto img = m.read_sii_image(m.slaves()[k].station);
        frames.push_back(n.built.segment->counters().frames - before);
        ASSERT_TRUE(img) << "slave " << k;
        // The image up to its end marker, byte for byte (the EEPROM behind it may be longer).
        const std::vector<std::uint8_t>& eeprom = n.built.segment->slave(k).esc().eeprom();
        ASSERT_LE(img->size(), eeprom.size());
        EXPECT_TRUE(std::equal(img->begin(), img->end(), eeprom.begin())) << "slave " << k;
        // A command and a read of its result for every 4 (8) bytes, and little more (a category that starts
        // 2 bytes into a block of the one before; a vecat drive's image is about 1 KB: 272 frames with 8
        // bytes a command, 542 with 4; the master before read 4 bytes with 4 frames).
        const std::size_t per_command = k == 0 ? 8 : 4;
        const std::size_t commands = img->size() / per_command;
        EXPECT_GE(frames[k], 2 * commands) << "slave " << k;
        EXPECT_LE(frames[k], 2 * commands + 2 * 16) << "slave " << k;
    }
    // Reading 8 bytes a command takes about half the frames.
    EXPECT_LT(frames[0] * 10, frames[1] * 6);
}

// read_sii_dword, as vecat clone uses it on a real device: the double word at any word address.
TEST(MasterSii, ADoubleWordAtAnyWordAddress) {
    test::ServedNetwork n(kDrives);
    master::Master& m = n.master;
    ASSERT_TRUE(addressed(m));
    for (std::size_t k = 0; k < 2; ++k) {
        const std::vector<std::uint8_t>& eeprom = n.built.segment->slave(k).esc().eeprom();
        for (const std::uint32_t word : {0u, 1u, 7u, 8u, 0x41u}) {
            const auto v = m.read_sii_dword(m.slaves()[k].station, word);
            ASSERT_TRUE(v) << "slave " << k << " word " << word;
            EXPECT_EQ(*v, ld_le32(eeprom.data() + 2 * word)) << "slave " << k << " word " << word;
        }
        // Past the EEPROM's end: the ESC refuses the command (an acknowledge error), and so does the master.
        EXPECT_FALSE(m.read_sii_dword(m.slaves()[k].station, static_cast<std::uint32_t>(eeprom.size())));
    }
}

}  // namespace
}  // namespace vecat::network
