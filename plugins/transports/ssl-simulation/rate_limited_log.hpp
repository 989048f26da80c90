// SPDX-License-Identifier: Apache-2.0
// Counts refused input and writes at most one line per interval, so a client flooding bad
// datagrams cannot flood the log.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

#include <ubersim/log.hpp>

namespace ubersim::ssl_simulation {

/// A counter of refused messages with a rate-limited warning. Thread-safe.
class RateLimitedLog {
 public:
  /// Writes to `log` at most once per `interval`.
  RateLimitedLog(Log& log, std::chrono::steady_clock::duration interval) : log_(log), interval_(interval) {}

  /// Counts one refused message; logs it (with how many were refused meanwhile) when the interval allows.
  void Count(const std::string& what) {
    std::lock_guard lock(mutex_);
    ++total_;
    ++unreported_;
    const auto now = std::chrono::steady_clock::now();
    if (reported_once_ && now - last_ < interval_) return;
    log_.Warning(what + " (" + std::to_string(unreported_) + " refused since the last report, " +
                 std::to_string(total_) + " in all)");
    unreported_ = 0;
    last_ = now;
    reported_once_ = true;
  }
  /// Messages refused since start.
  std::uint64_t Total() const {
    std::lock_guard lock(mutex_);
    return total_;
  }

 private:
  Log& log_;
  std::chrono::steady_clock::duration interval_;
  mutable std::mutex mutex_;
  std::uint64_t total_ = 0;
  std::uint64_t unreported_ = 0;
  std::chrono::steady_clock::time_point last_{};
  bool reported_once_ = false;
};

}  // namespace ubersim::ssl_simulation
