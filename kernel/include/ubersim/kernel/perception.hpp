// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <deque>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "ubersim/math.hpp"
#include "ubersim/world_state.hpp"

namespace ubersim::kernel {

/// One overhead camera: where it hangs and the part of the carpet it is responsible for.
struct CameraModel {
  int id = 0;                        ///< camera_id in the packets
  Vec3 position = Vec3(0, 0, 6);     ///< field frame, m
  double x_min = 0, y_min = 0;       ///< its part of the carpet (before overlap), m
  double x_max = 0, y_max = 0;       ///< m
};

/// The vision system a world simulates (the world file's `perception:` block, presets resolved).
struct PerceptionModel {
  std::string preset = "ideal";          ///< ideal, 2003 or realistic: the defaults it started from
  double frame_rate = 60.0;              ///< frames per second per camera, Hz
  double latency = 0.0;                  ///< capture to send (t_sent - t_capture), s
  double ball_position_sigma = 0.0;      ///< Gaussian noise on the ball's x and y, m
  double robot_position_sigma = 0.0;     ///< on robots' x and y, m
  double robot_orientation_sigma = 0.0;  ///< on robots' heading, rad
  double ball_drop = 0.0;                ///< probability a camera frame misses the ball
  double robot_drop = 0.0;               ///< probability a camera frame misses a robot
  double camera_overlap = 0.3;           ///< each camera sees this far past its part, m
  std::vector<CameraModel> cameras;      ///< at least one
};

/// The radio between the teams' software and the robots (the `radio:` block, presets resolved).
struct RadioModel {
  std::string preset = "ideal";  ///< ideal, 2003 or realistic
  double latency = 0.0;          ///< from arrival to taking effect, s
  double loss = 0.0;             ///< probability a command is lost
};

/// What a perception pipeline carries from one step to the next (snapshots).
struct PerceptionState {
  PerceptionModel model;                    ///< as realism events left it (cameras and rate fixed)
  std::vector<std::int64_t> next_capture_ns;  ///< per camera
  std::vector<std::uint32_t> frame_numbers;   ///< per camera
  std::vector<VisionFrame> in_flight;         ///< frames waiting out the latency, oldest first
  std::string rng;                          ///< the noise generator's state (std::mt19937_64's text form)
};

/// What a radio link carries from one step to the next (snapshots).
struct RadioState {
  RadioModel model;                                          ///< as realism events left it
  std::vector<std::pair<std::int64_t, CommandEvent>> queue;  ///< commands in flight: due time, command
  std::string rng;                                           ///< the loss generator's state
};

/// Defaults of a preset ("ideal", "2003", "realistic"); false for an unknown name.
bool PerceptionPreset(const std::string& name, PerceptionModel& model);
/// Defaults of a radio preset; false for an unknown name.
bool RadioPreset(const std::string& name, RadioModel& model);
/// The league's realism presets as the ER-Force simulator names them (None, Friendly, RC2021,
/// Realistic; any case), put over `vision` and `radio`: noise, drop-outs, overlap, latency,
/// command delay and loss. Frame rate and cameras stay. What the preset asks for that ÜberSim does
/// not model goes to `unmodelled`, one entry each. False for an unknown name.
bool LeagueRealismPreset(const std::string& name, PerceptionModel& vision, RadioModel& radio,
                         std::vector<std::string>& unmodelled);
/// The league's preset names, for messages: "None, Friendly, RC2021, Realistic".
const char* LeagueRealismPresetNames();

/// `count` cameras over a carpet of length × width (m): a grid, two rows once there are four or
/// more, each camera above the centre of its cell at `height`.
std::vector<CameraModel> CameraGrid(int count, double length, double width, double height);
/// The cameras `now` laid out anew over another field's carpet: as many (at least one), as high.
std::vector<CameraModel> CamerasOver(const std::vector<CameraModel>& now, const FieldGeometry& field);

/// Samples the ground truth as the cameras see it: at each camera's frame rate, with noise,
/// drop-outs and an airborne ball projected onto the carpet, and holds each frame for the
/// latency. Deterministic for a seed.
class PerceptionPipeline {
 public:
  PerceptionPipeline(PerceptionModel model, std::uint64_t seed);

  /// True when a camera is due to capture at `now_ns` (so the caller builds a snapshot only then).
  bool CaptureDue(std::int64_t now_ns) const;
  /// Captures one frame for every camera due at the snapshot's time.
  void Capture(const WorldSnapshot& truth);
  /// Frames whose send time has come (t_sent <= now), oldest first.
  std::vector<VisionFrame> Release(std::int64_t now_ns);
  /// Forgets queued frames and restarts the schedule (world reset).
  void Reset();
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
  VisionFrame Frame(std::size_t camera, const WorldSnapshot& truth);
  bool Sees(const CameraModel& c, double x, double y) const;

  PerceptionModel model_;
  std::uint64_t seed_;
  std::int64_t period_ns_;
  std::int64_t latency_ns_;
  std::vector<std::int64_t> next_capture_ns_;
  std::vector<std::uint32_t> frame_numbers_;
  std::deque<VisionFrame> in_flight_;
  std::mt19937_64 rng_;
};

/// Delays robot commands by the radio latency and loses some; deterministic for a seed.
class RadioLink {
 public:
  RadioLink(RadioModel model, std::uint64_t seed);
  /// A command arriving at `now_ns`: false when the radio loses it, else it is queued.
  bool Send(CommandEvent command, std::int64_t now_ns);
  /// Commands due by `now_ns`, in arrival order.
  std::vector<CommandEvent> Deliver(std::int64_t now_ns);
  /// Forgets queued commands (world reset).
  void Reset();
  /// Changes latency and loss while running.
  void Configure(const RadioModel& model);
  /// The configuration.
  const RadioModel& model() const { return model_; }
  /// Everything it carries between steps.
  RadioState SaveState() const;
  /// Puts back what SaveState returned; throws std::invalid_argument when it is unreadable.
  void RestoreState(const RadioState& state);

 private:
  RadioModel model_;
  std::uint64_t seed_;
  std::int64_t latency_ns_;
  std::deque<std::pair<std::int64_t, CommandEvent>> queue_;
  std::mt19937_64 rng_;
};

}  // namespace ubersim::kernel
