// SPDX-License-Identifier: MIT
// Test data location: ctest sets IMPACT_DATA_DIR from the CMake cache variable of the same name.
// Tests that need data call IMPACT_REQUIRE_DATA(path) which skips (GTEST_SKIP) when it is absent,
// except in CI (environment variable CI = "true", set by CI runners): there a missing data folder or
// file fails the test, so a data-driven oracle cannot silently stop running.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <string>

namespace impact::test {

/// The data folder, or "" when not configured.
inline std::string data_dir() {
  const char* d = std::getenv("IMPACT_DATA_DIR");
  return d ? std::string(d) : std::string();
}

/// Full path of a file under the data folder, or "" when the folder is not configured or the
/// file is not there.
inline std::string data_file(const std::string& rel) {
  const std::string dir = data_dir();
  if (dir.empty()) return {};
  const std::string p = dir + "/" + rel;
  std::ifstream f(p);
  return f.good() ? p : std::string();
}

/// True when the environment variable CI is "true" (GitHub Actions, GitLab CI and others set it).
inline bool in_ci() {
  const char* ci = std::getenv("CI");
  return ci && std::string(ci) == "true";
}

}  // namespace impact::test

/// Declares `var` as the path of `rel` under IMPACT_DATA_DIR, or skips the test without it (fails
/// it in CI).
#define IMPACT_REQUIRE_DATA(var, rel)                                                           \
  const std::string var = ::impact::test::data_file(rel);                                       \
  if (var.empty() && ::impact::test::in_ci())                                                   \
    FAIL() << "CI=true: IMPACT_DATA_DIR not set or " << (rel) << " missing (data-driven oracle)"; \
  if (var.empty()) GTEST_SKIP() << "IMPACT_DATA_DIR not set or " << (rel) << " missing"
