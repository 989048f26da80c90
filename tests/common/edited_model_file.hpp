// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <unistd.h>

namespace ubersim::testing {

/// A copy of the model file `source` with its first `from` replaced by `to`, written to the temp
/// directory as `name`-<pid>.yaml (a test's variant of a shipped robot); returns its path.
/// Throws std::runtime_error when `source` has no `from`.
inline std::string EditedModelFile(const std::string& source, const std::string& from, const std::string& to,
                                   const std::string& name) {
  std::ifstream in(source);
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::size_t at = yaml.find(from);
  if (at == std::string::npos) throw std::runtime_error("no '" + from + "' in " + source);
  yaml.replace(at, from.size(), to);
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(out) << yaml;
  return out.string();
}

}  // namespace ubersim::testing
