#include "faults/scenario.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/file.hpp"

namespace vecat::faults {
namespace {

std::string where(const YAML::Node& n) {
    return "line " + std::to_string(n.Mark().line + 1) + ": ";
}

TimelineEvent parse_event(const YAML::Node& n) {
    if (!n.IsMap()) throw std::invalid_argument(where(n) + "an event is a map (at:, start: or stop:, ...)");
    TimelineEvent e;
    e.line = n.Mark().line + 1;
    bool have_at = false, have_action = false;
    std::string kind;
    KeyValues kv;
    for (const auto& item : n) {
        const std::string key = item.first.as<std::string>();
        if (!item.second.IsScalar())
            throw std::invalid_argument(where(item.second) + key + ": expected a single value");
        const std::string value = item.second.as<std::string>();
        if (key == "at" || key == "at_cycle") {
            if (have_at) throw std::invalid_argument(where(n) + "give one of at: and at_cycle:");
            have_at = true;
            e.by_cycle = key == "at_cycle";
            try {
                e.at = e.by_cycle ? std::stoull(value) : parse_duration_ns(value);
            } catch (const std::exception&) {
                throw std::invalid_argument(where(item.second) + key + ": bad value " + value);
            }
        } else if (key == "start" || key == "stop") {
            if (have_action) throw std::invalid_argument(where(n) + "give one of start: and stop:");
            have_action = true;
            e.start = key == "start";
            (e.start ? kind : e.target) = value;
        } else {
            kv.emplace_back(key, value);
        }
    }
    if (!have_at) throw std::invalid_argument(where(n) + "event without at: or at_cycle:");
    if (!have_action) throw std::invalid_argument(where(n) + "event without start: or stop:");
    if (e.start) {
        try {
            e.fault = make_fault(kind, kv);
        } catch (const std::invalid_argument& x) {
            throw std::invalid_argument(where(n) + x.what());
        }
    } else if (!kv.empty()) {
        throw std::invalid_argument(where(n) + "stop: takes no parameters");
    }
    return e;
}

}  // namespace

Scenario parse_scenario(const std::string& yaml_text) {
    YAML::Node root;
    try {
        root = YAML::Load(yaml_text);
    } catch (const YAML::Exception& x) {
        throw std::invalid_argument(x.what());
    }
    if (!root.IsMap()) throw std::invalid_argument("a scenario is a map with events: (and seed:)");
    Scenario s;
    try {
        for (const auto& item : root) {
            const std::string key = item.first.as<std::string>();
            if (key == "seed") {
                s.seed = item.second.as<std::uint64_t>();
            } else if (key == "events") {
                if (!item.second.IsSequence())
                    throw std::invalid_argument(where(item.second) + "events: a list");
                for (const auto& ev : item.second)
                    s.events.push_back(parse_event(ev));
            } else {
                throw std::invalid_argument(where(item.first) + "unknown key " + key + " (seed, events)");
            }
        }
    } catch (const YAML::Exception& x) {
        throw std::invalid_argument(x.what());
    }
    return s;
}

Scenario load_scenario(const std::string& path) {
    std::string why;
    const auto text = read_whole_file(path, kMaxTextFileBytes, why);
    if (!text) throw std::invalid_argument(path + ": " + why);
    try {
        return parse_scenario(*text);
    } catch (const std::invalid_argument& x) {
        throw std::invalid_argument(path + ": " + x.what());
    }
}

}  // namespace vecat::faults
