// SPDX-License-Identifier: Apache-2.0
// Time: the simulated clock (integer nanoseconds), the run controls clock events set (pause,
// speed, single step, reset), and the pacer that holds a run to the wall clock.
#pragma once

#include <chrono>
#include <cstdint>

namespace ubersim::kernel {

/// Simulated time: a step counter and nanoseconds, advanced by a fixed step. Integer time keeps
/// long runs exact and comparisons between runs bit-identical.
class SimClock {
 public:
  /// A clock at 0 with the given step (s, rounded to ns).
  explicit SimClock(double step_seconds)
      : step_ns_(static_cast<std::int64_t>(step_seconds * 1e9 + 0.5)) {}
  /// Moves one step forward.
  void Advance() { ++steps_; time_ns_ += step_ns_; }
  /// Back to 0.
  void Reset() { steps_ = 0; time_ns_ = 0; }
  /// Sets the step count and time (a restored snapshot).
  void Restore(std::int64_t steps, std::int64_t time_ns) { steps_ = steps; time_ns_ = time_ns; }
  std::int64_t steps() const { return steps_; }          ///< steps taken
  std::int64_t time_ns() const { return time_ns_; }      ///< simulated time, ns
  double seconds() const { return 1e-9 * static_cast<double>(time_ns_); }  ///< simulated time, s
  std::int64_t step_ns() const { return step_ns_; }      ///< step length, ns
  double step_seconds() const { return 1e-9 * static_cast<double>(step_ns_); }  ///< step length, s

 private:
  std::int64_t step_ns_;
  std::int64_t steps_ = 0;
  std::int64_t time_ns_ = 0;
};

/// Pause, single step, speed factor, reset: what clock events and the CLI set, and the run loop
/// obeys. speed_factor 0 means as fast as possible.
struct ClockControl {
  bool paused = false;          ///< no steps unless pending_steps > 0
  double speed_factor = 1.0;    ///< simulated seconds per wall second; 0: as fast as possible
  int pending_steps = 0;        ///< single steps requested while paused
  bool reset_requested = false; ///< reset the world to its file's state before the next step
};

/// Paces a loop to a speed factor against the wall clock. Re-anchors whenever the factor
/// changes or the loop falls far behind, so a pause or a slow step never causes a burst.
class Pacer {
 public:
  using Clock = std::chrono::steady_clock;
  /// How long to wait before the step that ends at `sim_time_ns`; zero when due or unpaced.
  Clock::duration WaitBefore(std::int64_t sim_time_ns, double speed_factor);
  /// Forgets the anchor (after a pause or a reset).
  void Reanchor() { anchored_ = false; }

 private:
  bool anchored_ = false;
  double factor_ = 1.0;
  Clock::time_point wall_anchor_;
  std::int64_t sim_anchor_ns_ = 0;
};

}  // namespace ubersim::kernel
