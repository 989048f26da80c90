// SPDX-License-Identifier: Apache-2.0
#include "transport_common/reject_log.hpp"

#include <utility>

namespace ubersim::transport {

RejectLog::RejectLog(Log& log, std::string what, std::chrono::milliseconds interval, std::string counted_as)
    : log_(log),
      what_(std::move(what)),
      counted_as_(counted_as.empty() ? std::string() : " " + counted_as),
      interval_(interval) {}

void RejectLog::Reject(std::string_view reason) {
  std::lock_guard lock(mutex_);
  ++total_;
  ++unreported_;
  last_reason_ = reason;
  const auto now = std::chrono::steady_clock::now();
  if (!any_line_ || now - last_line_ >= interval_) {
    last_line_ = now;
    any_line_ = true;
    WriteLocked(reason);
  }
}

void RejectLog::Flush() {
  std::lock_guard lock(mutex_);
  if (unreported_ > 0) WriteLocked(last_reason_);
}

std::uint64_t RejectLog::Count() const {
  std::lock_guard lock(mutex_);
  return total_;
}

void RejectLog::WriteLocked(std::string_view reason) {
  log_.Warning(what_ + ": " + std::string(reason) + " (" + std::to_string(unreported_) + counted_as_ +
               " since the last report, " + std::to_string(total_) + " in total)");
  unreported_ = 0;
}

}  // namespace ubersim::transport
