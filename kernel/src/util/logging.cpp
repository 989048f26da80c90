// SPDX-License-Identifier: Apache-2.0
#include "ubersim/kernel/logging.hpp"

namespace ubersim::kernel {

void StreamLog::Write(LogLevel level, std::string_view message) {
  std::lock_guard lock(mutex_);
  ++counts_[static_cast<int>(level)];
  if (level < min_level_) return;
  out_ << '[' << ToString(level) << "] " << message << '\n';
  out_.flush();
}

}  // namespace ubersim::kernel
