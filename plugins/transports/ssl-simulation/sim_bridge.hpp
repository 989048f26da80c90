// SPDX-License-Identifier: Apache-2.0
// What the transport's network threads learn from the simulation thread: the robots that exist,
// their dribbler contact and drive feedback (and whether the radio lost it), the step length,
// and (for synchronous mode) the camera frames that leave the perception pipeline while a
// requested number of steps runs.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <vector>

#include <ubersim/world_state.hpp>

#include "mapping.hpp"

namespace ubersim::ssl_simulation {

/// Camera frames released during a run of steps, and where the run ended.
struct StepResult {
  std::vector<VisionFrame> frames;  ///< in release order
  std::int64_t step = 0;            ///< physics steps since start, after the run
  std::int64_t sim_time_ns = 0;     ///< simulated time after the run
};

/// Thread-safe meeting point: the simulation thread writes, network threads read and wait.
class SimBridge {
 public:
  // --- simulation thread ---
  /// Keeps the frame when a run is armed.
  void OnVisionFrame(const VisionFrame& frame);
  /// Records the state after a step; completes an armed run after its last step.
  void OnPublish(const WorldSnapshot& snapshot);

  // --- any thread ---
  /// True once a step has been published.
  bool HasState() const;
  /// Whether the robot exists (false before any state).
  bool Exists(const RobotId& id) const;
  /// Whether the robot is on the field (false before any state).
  bool OnField(const RobotId& id) const;
  /// The robot's dribbler contact and drive feedback; nullopt when it is not on the field or no
  /// state is known yet.
  std::optional<RobotReport> Report(const RobotId& id) const;
  /// Ball radius, m (the kernel default until a state is known).
  double BallRadius() const;
  /// Length of a physics step, ns; 0 until a step has been published.
  std::int64_t StepNs() const;

  // --- the synchronous worker ---
  /// Starts collecting frames; the run completes after `steps` more published steps.
  void Arm(std::int64_t steps);
  /// Waits until the armed run completes; disarms and returns nullopt on timeout or Cancel.
  std::optional<StepResult> Wait(std::chrono::steady_clock::duration timeout);
  /// Wakes a waiting worker for good (shutdown).
  void Cancel();

 private:
  struct RobotEntry {
    RobotId id;
    bool present = true;
    RobotReport report;
  };
  const RobotEntry* Find(const RobotId& id) const;  // under mutex_
  mutable std::mutex mutex_;
  std::condition_variable done_;
  std::vector<RobotEntry> robots_;
  bool has_state_ = false;
  double ball_radius_ = 0.0215;
  std::int64_t step_ns_ = 0;
  std::int64_t result_step_ = 0;     // where the armed run ended
  std::int64_t result_time_ns_ = 0;
  bool armed_ = false;
  bool complete_ = false;
  bool cancelled_ = false;
  std::int64_t remaining_ = 0;
  std::vector<VisionFrame> frames_;
};

}  // namespace ubersim::ssl_simulation
