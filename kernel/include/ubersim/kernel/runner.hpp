// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <atomic>
#include <functional>

#include "ubersim/kernel/world.hpp"

namespace ubersim::kernel {

/// How a run loop goes.
struct RunOptions {
  /// Stop after this much simulated time from the run's start (a restored world's time counts
  /// from its snapshot), s; 0: until stopped.
  double duration = 0.0;
  double speed_factor = 1.0;  ///< sim s per wall s at start; 0: as fast as possible
  bool start_paused = false;  ///< start paused (clock events resume it)
  double status_interval = 0.5;  ///< wall seconds between status callbacks
  /// Called between steps on the run's thread, also while paused (save a snapshot on request,
  /// keep the crash report's copy fresh); may be empty.
  std::function<void()> between_steps;
};

/// What the status callback gets.
struct RunStatus {
  double sim_time = 0.0;          ///< s
  std::int64_t steps = 0;         ///< physics steps
  double real_time_factor = 0.0;  ///< sim s per wall s over the last interval
  bool paused = false;            ///< paused now
  bool finished = false;          ///< last call of the run
};

/// Steps a world against the wall clock (or as fast as possible), obeying pause, single step,
/// speed and reset from clock events, until the duration is reached, `stop` becomes true or a
/// plugin fault stops the world (World::stopped). Returns the final status.
RunStatus RunWorld(World& world, const RunOptions& options, const std::atomic<bool>& stop,
                   const std::function<void(const RunStatus&)>& on_status);

}  // namespace ubersim::kernel
