// SPDX-License-Identifier: Apache-2.0
#include "ubersim/validation/result.hpp"

#include <cmath>
#include <stdexcept>

namespace ubersim::validation {

bool Metric::Pass() const { return std::isfinite(value) && value >= low && value <= high; }

bool ScenarioResult::Pass() const {
  for (const Metric& m : metrics) {
    if (!m.Pass()) return false;
  }
  return true;
}

const Metric& ScenarioResult::Get(const std::string& name) const {
  for (const Metric& m : metrics) {
    if (m.name == name) return m;
  }
  throw std::out_of_range("scenario '" + id + "' has no metric '" + name + "'");
}

}  // namespace ubersim::validation
