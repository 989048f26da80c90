// SPDX-License-Identifier: Apache-2.0
#include "ubersim/kernel/clock.hpp"

namespace ubersim::kernel {

Pacer::Clock::duration Pacer::WaitBefore(std::int64_t sim_time_ns, double speed_factor) {
  if (speed_factor <= 0.0) {
    anchored_ = false;
    return Clock::duration::zero();
  }
  const auto now = Clock::now();
  if (!anchored_ || factor_ != speed_factor) {
    anchored_ = true;
    factor_ = speed_factor;
    wall_anchor_ = now;
    sim_anchor_ns_ = sim_time_ns;
    return Clock::duration::zero();
  }
  const double wall_ns = static_cast<double>(sim_time_ns - sim_anchor_ns_) / speed_factor;
  const auto due = wall_anchor_ + std::chrono::nanoseconds(static_cast<std::int64_t>(wall_ns));
  if (due <= now) {
    // More than 100 ms behind: we cannot catch up without a burst, so start afresh.
    if (now - due > std::chrono::milliseconds(100)) {
      wall_anchor_ = now;
      sim_anchor_ns_ = sim_time_ns;
    }
    return Clock::duration::zero();
  }
  return due - now;
}

}  // namespace ubersim::kernel
