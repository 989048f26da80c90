// SPDX-License-Identifier: Apache-2.0
// The simulated vision system: cameras sampling the ground truth, with noise and latency.
#pragma once

#include <cstdint>
#include <deque>
#include <random>
#include <utility>
#include <vector>

#include "ubersim/world_state.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/snapshot.hpp"

namespace ubersim::kernel {

/// Samples the ground truth as the cameras see it: at each camera's frame rate (each on its own
/// phase when unsynchronised, with capture jitter), with noise (growing away from the camera's
/// nadir), drop-outs, systematic offsets, a ball hidden by robots (ray-cast) or smeared by its
/// motion, false ball detections at dribblers, an airborne ball projected onto the carpet, and
/// holds each frame for the latency. Deterministic for a seed.
class PerceptionPipeline {
 public:
  PerceptionPipeline(PerceptionModel model, std::uint64_t seed);

  /// True when a camera is due to capture at `now_ns` (so the caller takes the ground truth only then).
  bool CaptureDue(std::int64_t now_ns) const;
  /// Captures one frame for every camera due at the ground truth's time. `front_distances`
  /// (robot centre to its flat front, m, in truth.robots' order) places false ball detections at
  /// the dribblers' corners; empty when none are modelled.
  void Capture(const WorldSnapshot& truth, const std::vector<double>& front_distances = {});
  /// Frames whose send time has come (t_sent <= now), oldest first.
  std::vector<VisionFrame> Release(std::int64_t now_ns);
  /// Forgets queued frames and restarts the schedule (world reset).
  void Reset();
  /// Reset with another seed (the world reset with a new seed).
  void Reset(std::uint64_t seed);
  /// Changes noise, drop-outs, overlap and latency while running; frame rate and cameras stay.
  void Configure(const PerceptionModel& model);
  /// Other cameras (another field): a camera id kept keeps its frame numbers and schedule, a new
  /// one starts with the others' next capture; frames in flight still leave.
  void SetCameras(std::vector<CameraModel> cameras);
  /// The configuration.
  const PerceptionModel& model() const { return model_; }
  /// Everything it carries between steps.
  PerceptionState SaveState() const;
  /// Puts back what SaveState returned; throws std::invalid_argument when the cameras differ.
  void RestoreState(const PerceptionState& state);

 private:
  VisionFrame Frame(std::size_t camera, const WorldSnapshot& truth, const std::vector<double>& front_distances);
  bool Sees(const CameraModel& c, double x, double y) const;
  // The next capture of camera `c` after `now_ns`: its phase's next frame, with jitter.
  std::int64_t NextCapture(std::size_t c, std::int64_t now_ns);
  // Where camera `cam` reports a ball whose visible part is centred at `at` (field frame): along
  // its ray onto the carpet, shifted by the object offset.
  Vec3 Reported(const CameraModel& cam, const Vec3& at, double radius) const;

  PerceptionModel model_;
  std::uint64_t seed_;
  std::int64_t period_ns_;
  std::int64_t latency_ns_;
  std::vector<std::int64_t> next_capture_ns_;
  std::vector<std::int64_t> phase_ns_;  // per camera: its frames' offset (from the seed alone)
  std::vector<std::uint32_t> frame_numbers_;
  std::deque<VisionFrame> in_flight_;
  std::mt19937_64 rng_;
};

/// Where the geometry reports `camera`: its position with the league's camera_position_error
/// (projection uses the true one).
Vec3 ReportedCameraPosition(const PerceptionModel& model, const CameraModel& camera);

}  // namespace ubersim::kernel
