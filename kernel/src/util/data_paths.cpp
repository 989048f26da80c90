// SPDX-License-Identifier: Apache-2.0
#include "ubersim/kernel/data_paths.hpp"

#include <cstdlib>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace ubersim::kernel {

std::filesystem::path ExecutableDir() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : exe.parent_path();
}

std::filesystem::path DataDir() {
  std::vector<std::filesystem::path> candidates;
  if (const char* env = std::getenv("UBERSIM_DATA_DIR"); env && *env) candidates.emplace_back(env);
  const auto exe_dir = ExecutableDir();
  if (!exe_dir.empty()) candidates.push_back(exe_dir / ".." / UBERSIM_DATA_INSTALL_DIR);
  candidates.emplace_back(UBERSIM_SOURCE_DIR);
  std::string tried;
  for (const auto& c : candidates) {
    std::error_code ec;
    if (std::filesystem::is_directory(c / "models", ec)) {
      return std::filesystem::weakly_canonical(c, ec);
    }
    tried += (tried.empty() ? "" : ", ") + c.string();
  }
  throw std::runtime_error("cannot find the models/ folder; tried " + tried +
                           " (set UBERSIM_DATA_DIR)");
}

std::filesystem::path DefaultWorldFile() { return DataDir() / "models" / "worlds" / "div-b.yaml"; }

}  // namespace ubersim::kernel
