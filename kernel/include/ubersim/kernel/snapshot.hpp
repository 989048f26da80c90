// SPDX-License-Identifier: Apache-2.0
// Snapshots (saved-state files): a world's full state at a step boundary, and the file that keeps it. Restoring one
// into a world built from the same world file and stepping on gives the trajectory the original
// would have had, bit for bit (docs/reliability.md, "Snapshots").
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ubersim/events.hpp"
#include "ubersim/kernel/fault.hpp"
#include "ubersim/kernel/model.hpp"

namespace ubersim::kernel {

/// A snapshot that cannot be read, or does not fit the world it is restored into. The message
/// names the file (or the world) and the reason.
class SnapshotError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What a perception pipeline carries from one step to the next (saved in snapshots).
struct PerceptionState {
  PerceptionModel model;                    ///< as realism events left it (cameras and rate fixed)
  std::vector<std::int64_t> next_capture_ns;  ///< per camera
  std::vector<std::uint32_t> frame_numbers;   ///< per camera
  std::vector<VisionFrame> in_flight;         ///< frames waiting out the latency, oldest first
  std::string rng;                          ///< the noise generator's state (std::mt19937_64's text form)
};

/// What a radio link carries from one step to the next (saved in snapshots).
struct RadioState {
  RadioModel model;                                          ///< as realism events left it
  std::vector<std::pair<std::int64_t, CommandEvent>> queue;  ///< commands in flight: due time, command
  std::string rng;                                           ///< the loss generator's state
};

/// One ODE body, as ODE keeps it between steps (doubles bit for bit).
struct SavedBody {
  std::string path;                    ///< "blue/3/wheel0/wheel": node path and body name
  std::array<double, 3> position{};    ///< m
  std::array<double, 4> quaternion{};  ///< w, x, y, z
  std::array<double, 12> rotation{};   ///< ODE's 3×4 rotation matrix, kept beside the quaternion
  std::array<double, 3> linear_velocity{};   ///< m/s
  std::array<double, 3> angular_velocity{};  ///< rad/s
  std::array<double, 3> force{};       ///< accumulated for the next step, N
  std::array<double, 3> torque{};      ///< N·m
  bool enabled = true;                 ///< ODE steps it (a robot off the field is disabled)
};

/// One joint: its motor and the forces ODE reported for it in the last step.
struct SavedJoint {
  std::string path;                     ///< node path and joint name
  double motor_velocity = 0;            ///< target rate (hinge, slider, universal)
  double motor_max_effort = 0;          ///< N·m or N
  std::array<double, 12> feedback{};    ///< force and torque on both bodies, last step
};

/// One robot part: its plugin, whether it was switched off, and its own state (SaveState).
struct SavedPart {
  PluginKind kind = PluginKind::kDrive;  ///< drive, dribbler or kicker
  std::string plugin;                    ///< plugin id
  std::string version;                   ///< the plugin's version when saved
  bool failed = false;                   ///< switched off after a fault
  std::string state;                     ///< the component's bytes
};

/// One robot.
struct SavedRobot {
  RobotId id;                     ///< team and id
  bool present = true;            ///< on the field
  std::vector<SavedPart> parts;   ///< in the robot's order (drive, dribbler, kicker)
  std::string model_file;         ///< the robot file it was built from, before robot specs ("" in older snapshots)
  std::optional<std::array<double, 3>> built_at;  ///< x, y, yaw where it was built (m, rad); older snapshots: none
};

/// A model file the world was built from, and a digest of its bytes.
struct ModelFileDigest {
  std::string path;             ///< as the model names it
  std::uint64_t digest = 0;     ///< FNV-1a 64 of the file's bytes
};

/// Everything that decides how a world goes on from a step boundary.
struct SavedState {
  // Whose state.
  std::string world_name;         ///< the world's name
  std::string world_file;         ///< the world file it was built from
  std::uint64_t structure = 0;    ///< WorldStructureDigest: bodies, joints, geometries, robots, physics
  std::vector<ModelFileDigest> model_files;  ///< the files' contents when saved
  std::string ubersim_version;    ///< the program that saved it
  std::string created_utc;        ///< when, ISO 8601
  std::string field_file;         ///< the field it had then ("" in older snapshots: the world file's)

  // Clock and ODE.
  std::int64_t step = 0;          ///< steps taken
  std::int64_t time_ns = 0;       ///< simulated time, ns
  std::int64_t step_ns = 0;       ///< physics step, ns
  std::uint64_t ode_random_seed = 0;  ///< ODE's generator (QuickStep's constraint order)
  std::vector<SavedBody> bodies;      ///< every body, scene-graph order
  std::vector<SavedJoint> joints;     ///< every joint, scene-graph order
  std::vector<bool> geom_collides;    ///< every geometry, scene-graph order
  /// Bodies (indices into `bodies`) in the order ODE last moved them within its collision space;
  /// the space's pair order follows it (kernel/src/state/ode_state.hpp).
  std::vector<std::uint32_t> moved_bodies;

  // Robots, sensors, radio, faults.
  std::vector<SavedRobot> robots;     ///< the world's order
  PerceptionState perception;         ///< cameras' schedule, frames in flight, noise generator
  RadioState radio;                   ///< commands in flight, loss generator
  bool held_ball = false;             ///< dribblers hold the ball (the world file, realism events)
  std::optional<RobotId> ball_held_by;  ///< the robot holding the ball then
  std::vector<PluginFault> faults;    ///< every fault so far
  std::vector<std::pair<RobotId, RobotSpec>> robot_specs;  ///< robot specs announced while running
};

/// The snapshot file's bytes: a checked envelope (magic, format version, CRC-32) around the
/// state, as protobuf messages (kernel/proto/ubersim_snapshot.proto).
std::string EncodeSnapshot(const SavedState& state);
/// Reads EncodeSnapshot's bytes; throws SnapshotError naming `source` and what is wrong
/// (not a snapshot, another format version, truncated, corrupt).
SavedState DecodeSnapshot(std::string_view bytes, const std::string& source);

/// Writes a snapshot file atomically (a temporary beside it, then renamed): a crash while
/// writing never leaves half a file. Throws SnapshotError naming the file.
void WriteSnapshotFile(const std::filesystem::path& file, const SavedState& state);
/// Reads a snapshot file; throws SnapshotError naming the file and the reason.
SavedState ReadSnapshotFile(const std::filesystem::path& file);

/// FNV-1a 64 of a file's bytes; 0 when it cannot be read.
std::uint64_t FileDigest(const std::filesystem::path& file);

}  // namespace ubersim::kernel
