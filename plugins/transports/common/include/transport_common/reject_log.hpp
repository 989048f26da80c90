// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <string_view>

#include <ubersim/log.hpp>

namespace ubersim::transport {

/// Counts rejected input (malformed datagrams, unknown robots) or failed sends and logs them
/// without flooding: the first at once, then at most one line per interval with the latest reason
/// and how many came since the last line. Thread-safe.
class RejectLog {
 public:
  /// `what` starts each line ("grSim datagram rejected"); `counted_as` names the count
  /// ("refused": "(3 refused since the last report, …)"; empty: "(3 since the last report, …)").
  RejectLog(Log& log, std::string what, std::chrono::milliseconds interval = std::chrono::seconds(1),
            std::string counted_as = {});
  /// Counts one rejection; may write a warning.
  void Reject(std::string_view reason);
  /// Writes a last line for rejections not yet reported (call from Stop).
  void Flush();
  /// Rejections since construction.
  std::uint64_t Count() const;

 private:
  void WriteLocked(std::string_view reason);

  Log& log_;
  std::string what_;
  std::string counted_as_;  // "" or " refused", as written after the number
  std::chrono::milliseconds interval_;
  mutable std::mutex mutex_;
  std::uint64_t total_ = 0;
  std::uint64_t unreported_ = 0;
  std::string last_reason_;
  std::chrono::steady_clock::time_point last_line_{};
  bool any_line_ = false;
};

}  // namespace ubersim::transport
