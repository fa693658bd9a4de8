// Fuzz target: the ENI reader and the network made from an ENI (network::parse_eni: pugixml, the ETG.2100
// elements and their numbers; network::network_from_eni: the PreviousPort topology, the devices made from
// the ENI alone and their SII images; build_network for small networks). Input: the text of a file.
// Invariants: the text is accepted or refused with an EniError / NetworkFileError that names the file
// ("fuzz.xml:..."); nothing else is thrown. An accepted network is a tree (one device on the master, every
// other one with a parent before it, cabled to the parent's port and to nothing else); the SII image of a
// device made from the ENI alone is one a master reads back with a right checksum and the ENI's identity;
// the network file `vecat network from-eni` writes for it reads back as the same tree.
#include <cstdint>
#include <cstdio>
#include <string>

#include "fuzz_support.hpp"
#include "network/build.hpp"
#include "network/eni.hpp"
#include "network/eni_network.hpp"
#include "protocol/sii.hpp"

using namespace vecat;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    network::Eni eni;
    network::EniNetwork n;
    try {
        eni = network::parse_eni(text, "fuzz.xml");
        n = network::network_from_eni(eni);
    } catch (const network::NetworkFileError& e) {
        VECAT_FUZZ_CHECK(std::string(e.what()).rfind("fuzz.xml", 0) == 0);
        return 0;
    }
    const network::NetworkFile& f = n.file;
    const std::size_t count = f.devices.size();
    VECAT_FUZZ_CHECK(count == eni.slaves.size() && n.slave.size() == count);
    VECAT_FUZZ_CHECK(f.parent.size() == count && f.children.size() == count && f.parent[0] == -1);
    for (std::size_t i = 1; i < count; ++i) {
        const int p = f.parent[i];
        VECAT_FUZZ_CHECK(p >= 0 && static_cast<std::size_t>(p) < i);
        const unsigned port = f.devices[i].upstream_port;
        VECAT_FUZZ_CHECK(port >= 1 && port < network::kPorts);
        VECAT_FUZZ_CHECK(f.children[static_cast<std::size_t>(p)][port] == static_cast<int>(i));
    }
    for (std::size_t i = 0; i < count; ++i) {
        const auto& d = f.devices[i];
        VECAT_FUZZ_CHECK(d.source == network::Source::Sii && d.sii_image);
        const protocol::SiiInfo sii = protocol::parse_sii(*d.sii_image);
        const network::EniSlave& s = eni.slaves[n.slave[i]];
        VECAT_FUZZ_CHECK(sii.checksum_ok);
        VECAT_FUZZ_CHECK(sii.identity.vendor_id == s.vendor_id &&
                         sii.identity.product_code == s.product_code && sii.identity.revision == s.revision);
    }
    // The network file vecat network from-eni writes reads back as the same tree.
    const auto written = network::network_file_from_eni(eni, n, "/nonexistent");
    network::NetworkFile back;
    try {
        back = network::parse_network(written.yaml, "back.yaml", "/nonexistent");
    } catch (const network::NetworkFileError& e) {
        std::fprintf(stderr, "%s\n", e.what());
        VECAT_FUZZ_CHECK(false && "the written network file is refused");
    }
    VECAT_FUZZ_CHECK(back.parent == f.parent && back.children == f.children && back.devices.size() == count);
    for (std::size_t i = 0; i < count; ++i)
        VECAT_FUZZ_CHECK(back.devices[i].name == f.devices[i].name &&
                         back.devices[i].upstream_port == f.devices[i].upstream_port);
    // Small networks are built: a refusal names the file, anything else is a finding.
    if (count <= 8) {
        try {
            const auto built = network::build_network(f, "fuzz.xml");
            VECAT_FUZZ_CHECK(built.segment->size() == count);
        } catch (const network::NetworkFileError& e) {
            VECAT_FUZZ_CHECK(std::string(e.what()).rfind("fuzz.xml", 0) == 0);
        }
    }
    return 0;
}
