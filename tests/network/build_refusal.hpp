// The refusal of a network file's text, read and its devices made (build_network): the message, "" if
// accepted.
#pragma once

#include <string>

#include "network/build.hpp"
#include "network/network_file.hpp"

namespace vecat::test {

inline std::string build_refusal(const std::string& text) {
    try {
        network::build_network(network::parse_network(text, "net.yaml"), "net.yaml");
    } catch (const network::NetworkFileError& e) {
        return e.what();
    }
    return "";
}

}  // namespace vecat::test
