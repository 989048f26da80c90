// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <string_view>

#include "ubersim/export.hpp"

namespace ubersim {
inline namespace v1 {

/// Severity of a log line.
enum class LogLevel { kDebug, kInfo, kWarning, kError };

/// A sink for log lines; the kernel gives each plugin one that prefixes the plugin's name.
class UBERSIM_SDK_API Log {
 public:
  virtual ~Log();
  /// Writes one line at the given level.
  virtual void Write(LogLevel level, std::string_view message) = 0;

  /// Writes a debug line.
  void Debug(std::string_view m) { Write(LogLevel::kDebug, m); }
  /// Writes an informational line.
  void Info(std::string_view m) { Write(LogLevel::kInfo, m); }
  /// Writes a warning.
  void Warning(std::string_view m) { Write(LogLevel::kWarning, m); }
  /// Writes an error.
  void Error(std::string_view m) { Write(LogLevel::kError, m); }
};

/// Name of a level ("debug", "info", "warning", "error").
UBERSIM_SDK_API std::string_view ToString(LogLevel level);

}  // namespace v1
}  // namespace ubersim
