// SPDX-License-Identifier: Apache-2.0
// Warnings a world repeats (a team's software sending a refused command 100 times a second) written
// without flooding: the first at once, then at most one line per interval of simulated time per
// kind, with how many were held back. Simulated time keeps the log the same from run to run.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "ubersim/log.hpp"

namespace ubersim::kernel {

/// Rate-limits warnings by kind ("command refused for robot blue 3").
class RepeatedWarnings {
 public:
  /// Writes to `log`, at most one line per kind every `interval_ns` of simulated time.
  RepeatedWarnings(Log& log, std::int64_t interval_ns) : log_(log), interval_ns_(interval_ns) {}
  /// Warns `message` at simulated time `now_ns`, or counts it when a line of `kind` was written
  /// less than the interval ago; the next line written says how many were held back.
  void Warn(const std::string& kind, const std::string& message, std::int64_t now_ns);
  /// Forgets what was written (a world reset or restore: time starts again).
  void Clear() { kinds_.clear(); }

 private:
  struct Kind {
    std::int64_t last_line_ns = 0;
    std::int64_t held_back = 0;
  };
  Log& log_;
  std::int64_t interval_ns_;
  std::map<std::string, Kind> kinds_;
};

}  // namespace ubersim::kernel
