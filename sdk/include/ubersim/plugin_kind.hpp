// SPDX-License-Identifier: Apache-2.0
// The kinds of plugin a library can provide. Its own header so that the kernel's model and
// registry headers name a kind without pulling in Boost.DLL (plugin.hpp's export macros).
#pragma once

#include <cstdint>

namespace ubersim {
inline namespace v1 {

/// What a plugin library provides.
enum class PluginKind : std::uint32_t { kDrive = 1, kDribbler = 2, kKicker = 3, kTransport = 4 };

/// "drive", "dribbler", "kicker", "transport" or "unknown".
inline const char* ToString(PluginKind k) {
  switch (k) {
    case PluginKind::kDrive: return "drive";
    case PluginKind::kDribbler: return "dribbler";
    case PluginKind::kKicker: return "kicker";
    case PluginKind::kTransport: return "transport";
  }
  return "unknown";
}

}  // namespace v1
}  // namespace ubersim
