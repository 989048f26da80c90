// SPDX-License-Identifier: Apache-2.0
#include "world/repeated_warnings.hpp"

namespace ubersim::kernel {

void RepeatedWarnings::Warn(const std::string& kind, const std::string& message, std::int64_t now_ns) {
  const auto [it, first] = kinds_.try_emplace(kind);
  Kind& k = it->second;
  if (!first && now_ns - k.last_line_ns < interval_ns_) {
    ++k.held_back;
    return;
  }
  if (k.held_back > 0) {
    log_.Warning(message + " (and " + std::to_string(k.held_back) + " more like it held back since the last line)");
  } else {
    log_.Warning(message);
  }
  k.last_line_ns = now_ns;
  k.held_back = 0;
}

}  // namespace ubersim::kernel
