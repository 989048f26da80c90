// SPDX-License-Identifier: Apache-2.0
// Logging: the kernel's implementations of the SDK's Log (a stream with a minimum level, and a
// prefix for each plugin).
#pragma once

#include <mutex>
#include <ostream>
#include <string>

#include "ubersim/log.hpp"

namespace ubersim::kernel {

/// Writes "[level] message" lines to a stream, at or above a minimum level; thread-safe.
class StreamLog final : public Log {
 public:
  /// Logs to `out` (kept by reference) from `min_level` up.
  explicit StreamLog(std::ostream& out, LogLevel min_level = LogLevel::kInfo)
      : out_(out), min_level_(min_level) {}
  void Write(LogLevel level, std::string_view message) override;
  /// Lines written at each level so far (tests and status).
  int count(LogLevel level) const { return counts_[static_cast<int>(level)]; }

 private:
  std::ostream& out_;
  LogLevel min_level_;
  std::mutex mutex_;
  int counts_[4] = {0, 0, 0, 0};
};

/// Prefixes every line with a name ("blue/3 omni: ") and forwards it.
class PrefixedLog final : public Log {
 public:
  /// Forwards to `target` with "prefix: ".
  PrefixedLog(Log& target, std::string prefix) : target_(target), prefix_(std::move(prefix)) {}
  void Write(LogLevel level, std::string_view message) override {
    target_.Write(level, prefix_ + ": " + std::string(message));
  }

 private:
  Log& target_;
  std::string prefix_;
};

}  // namespace ubersim::kernel
