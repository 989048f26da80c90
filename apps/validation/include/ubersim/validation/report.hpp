// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "ubersim/validation/result.hpp"

namespace ubersim::validation {

/// Writes `dir`/README.md (a table of every metric with its band and verdict, the setups, the
/// figures) and one SVG per plot; `command` is the command line that produced it.
void WriteReport(const std::filesystem::path& dir, const std::vector<ScenarioResult>& results,
                 const std::string& command);

}  // namespace ubersim::validation
