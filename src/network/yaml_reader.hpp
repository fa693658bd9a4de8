// The value checks shared by the YAML files of this folder (network files, dictionary files): every refusal
// throws Error("FILE:LINE: what is wrong").
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

namespace vecat::network {

template <typename Error>
class YamlReader {
  public:
    explicit YamlReader(std::string name) : name_(std::move(name)) {}

    [[noreturn]] void fail(unsigned line, const std::string& what) const {
        throw Error(name_ + ":" + std::to_string(line) + ": " + what);
    }
    [[noreturn]] void fail(const YAML::Node& n, const std::string& what) const { fail(line(n), what); }
    static unsigned line(const YAML::Node& n) { return static_cast<unsigned>(n.Mark().line + 1); }

    std::string scalar(const YAML::Node& n, const std::string& key) const {
        if (!n.IsScalar()) fail(n, key + ": expected a single value");
        return n.as<std::string>();
    }
    // A number, decimal or 0x-hexadecimal, within [0, max].
    std::uint64_t number(const YAML::Node& n, const std::string& key, std::uint64_t max) const {
        const std::string s = scalar(n, key);
        std::size_t used = 0;
        std::uint64_t v = 0;
        try {
            const bool hex = s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X');
            if (s.empty() || s[0] == '-' || s[0] == '+' || s[0] == ' ') throw std::invalid_argument(s);
            v = std::stoull(hex ? s.substr(2) : s, &used, hex ? 16 : 10);
            if (used != (hex ? s.size() - 2 : s.size())) throw std::invalid_argument(s);
        } catch (const std::exception&) {
            fail(n, key + ": \"" + s + "\" is not a number");
        }
        if (v > max) fail(n, key + ": " + s + " is larger than " + std::to_string(max));
        return v;
    }

  private:
    std::string name_;
};

}  // namespace vecat::network
