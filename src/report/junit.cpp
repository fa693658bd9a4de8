// The report's two forms: JUnit XML for CI (one test case per rule of rules.hpp, failed by its findings;
// the schema CI servers read: testsuites > testsuite > testcase > failure) and lines for a terminal.
#include <fmt/format.h>
#include <pugixml.hpp>

#include <sstream>

#include "report/master_checks.hpp"

namespace vecat::report {

namespace {

std::string where(const Finding& f) {
    std::string s = fmt::format("slave {} (frame {} of the master, {:.3f} s)", f.slave, f.frame,
                                static_cast<double>(f.time_ns) / 1e9);
    if (f.count > 1) s += fmt::format(", {} times", f.count);
    return s;
}

std::size_t failed_rules(const MasterChecks& c) {
    std::size_t n = 0;
    for (const RuleInfo& r : kRules)
        n += c.failed(r.rule) ? 1 : 0;
    return n;
}

}  // namespace

std::string junit_xml(const MasterChecks& c) {
    pugi::xml_document doc;
    auto decl = doc.append_child(pugi::node_declaration);
    decl.append_attribute("version") = "1.0";
    decl.append_attribute("encoding") = "UTF-8";
    const std::string failures = std::to_string(failed_rules(c));
    const std::string tests = std::to_string(kRules.size());
    auto suites = doc.append_child("testsuites");
    suites.append_attribute("name") = "vecat master report";
    suites.append_attribute("tests") = tests.c_str();
    suites.append_attribute("failures") = failures.c_str();
    auto suite = suites.append_child("testsuite");
    suite.append_attribute("name") = "vecat.master";
    suite.append_attribute("tests") = tests.c_str();
    suite.append_attribute("failures") = failures.c_str();
    suite.append_attribute("errors") = "0";
    auto props = suite.append_child("properties");
    const auto prop = [&](const char* name, std::string value) {
        auto p = props.append_child("property");
        p.append_attribute("name") = name;
        p.append_attribute("value") = value.c_str();
    };
    prop("frames", std::to_string(c.frames()));
    prop("slaves", std::to_string(c.slaves()));
    for (const RuleInfo& r : kRules) {
        auto tc = suite.append_child("testcase");
        tc.append_attribute("classname") = "vecat.master";
        tc.append_attribute("name") = fmt::format("{}: {}", r.id, r.what).c_str();
        std::string text;
        std::string first;
        for (const Finding& f : c.findings()) {
            if (f.rule != r.rule) continue;
            const std::string line = fmt::format("{}: {}", where(f), f.message);
            if (first.empty()) first = line;
            text += line + "\n";
        }
        if (first.empty()) continue;
        auto fail = tc.append_child("failure");
        fail.append_attribute("type") = std::string(to_string(r.severity)).c_str();
        fail.append_attribute("message") = first.c_str();
        text += fmt::format("Rule: {}\n", r.source);
        fail.text().set(text.c_str());
    }
    std::ostringstream out;
    doc.save(out, "  ");
    return out.str();
}

std::string summary(const MasterChecks& c) {
    const std::size_t failed = failed_rules(c);
    std::string s =
        fmt::format("vecat: report on the master: {} frames, {} of {} checks {}\n", c.frames(),
                    failed ? failed : kRules.size() - failed, kRules.size(), failed ? "failed" : "passed");
    for (const RuleInfo& r : kRules) {
        if (!c.failed(r.rule)) continue;
        s += fmt::format("  [{}] {}: {}\n", to_string(r.severity), r.id, r.what);
        for (const Finding& f : c.findings())
            if (f.rule == r.rule) s += fmt::format("      {}: {}\n", where(f), f.message);
        s += fmt::format("      rule: {}\n", r.source);
    }
    return s;
}

}  // namespace vecat::report
