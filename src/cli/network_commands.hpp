// `vecat network check FILE` (a network file or an ENI) and `vecat network from-eni FILE`: the devices a
// network file or an ENI makes, in the order the frame reaches them, and the network file of an ENI
// (docs/network-file.md, docs/eni.md).
#pragma once

#include <string>

namespace vecat::cli {

// Lists the devices, where each is cabled and what was guessed; 1 with the file's line when something is
// wrong. An ENI (a file whose first character is '<') is read as vecat run --eni, with esi_dir.
int cmd_network_check(const std::string& file, const std::string& esi_dir);
// Writes the network file out (and the SII images it names beside it); 1 when the ENI is refused.
int cmd_network_from_eni(const std::string& eni_file, const std::string& out, const std::string& esi_dir);

}  // namespace vecat::cli
