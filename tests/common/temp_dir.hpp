// SPDX-License-Identifier: Apache-2.0
// A test binary's own temporary directory (its name and process id), removed when its tests end.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>

#include <gtest/gtest.h>

namespace ubersim::testing {

/// <temp>/<name>_<pid>, created.
inline std::filesystem::path ProcessTempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

/// Removes a directory when the test binary's tests end (register it with
/// ::testing::AddGlobalTestEnvironment at static initialisation).
class RemoveDirAtEnd : public ::testing::Environment {
 public:
  explicit RemoveDirAtEnd(std::filesystem::path dir) : dir_(std::move(dir)) {}
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }

 private:
  std::filesystem::path dir_;
};

}  // namespace ubersim::testing
