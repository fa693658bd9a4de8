// Test data from outside the project: ../shared/data beside the clone (real captures, SII dumps of real
// devices, vendor ESI files, the ETG schema; see its README). It is read from there, never copied in.
// A clone without it still passes: the tests that need it are skipped with a message naming what is
// missing, so the run says what it could not check.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <string_view>

namespace vecat::test {

// The path of a file or folder under ../shared/data, e.g. shared_data("sii/beckhoff-el2004.bin").
inline std::string shared_data(std::string_view relative) {
    return std::string(VECAT_SHARED_DIR) + "/data/" + std::string(relative);
}

}  // namespace vecat::test

// Skips the current test when shared_data(relative) does not exist. In a TEST body (GTEST_SKIP returns).
#define VECAT_REQUIRE_SHARED_DATA(relative)                                                        \
    do {                                                                                           \
        const auto vecat_required_ = ::vecat::test::shared_data(relative);                         \
        if (!std::filesystem::exists(vecat_required_))                                             \
            GTEST_SKIP() << "test data missing: " << vecat_required_                               \
                         << " (the ../shared folder is not beside this clone; see README, Tests)"; \
    } while (0)
