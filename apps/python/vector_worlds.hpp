// SPDX-License-Identifier: Apache-2.0
// K copies of one world stepped by one call: the C++ side of ubersim.VectorEnv and
// ubersim.ParallelEnv (docs/python.md). Actions are read from one float32 array and
// observations written into another, preallocated by the caller; no Python between the worlds.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "shared/random_play.hpp"
#include "shared/world_loading.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/world.hpp"
#include "scripted_team.hpp"

namespace ubersim::python {

using kernel::World;

/// Who moves a team's robots.
enum class TeamDriver {
  kAgent,     ///< the caller's actions
  kIdle,      ///< nobody: the robots stand (commands time out)
  kScripted,  ///< ScriptedTeam, the baseline opponent
  kRandom,    ///< the bench's random play (apps/shared/random_play.hpp)
};

/// What every world of a VectorWorlds is.
struct VectorWorldsOptions {
  int count = 1;                   ///< K, the number of worlds
  int frame_skip = 1;              ///< physics steps per env step
  std::array<TeamDriver, 2> drivers{TeamDriver::kAgent, TeamDriver::kIdle};  ///< [blue, yellow]
  bool camera_features = false;    ///< add what the cameras reported to each robot's row
};

/// The observation's features of one robot row (docs/python.md, Observation).
namespace feature {
constexpr int kPresent = 0, kX = 1, kY = 2, kCosYaw = 3, kSinYaw = 4, kVx = 5, kVy = 6, kOmega = 7,
              kKickerReady = 8, kBallContact = 9, kBallX = 10, kBallY = 11, kBallZ = 12, kBallVx = 13,
              kBallVy = 14, kBallVz = 15;
constexpr int kBase = 16;  ///< features without the cameras
constexpr int kSeen = 16, kSeenX = 17, kSeenY = 18, kSeenCos = 19, kSeenSin = 20, kBallSeen = 21, kBallSeenX = 22,
              kBallSeenY = 23;
constexpr int kWithCameras = 24;  ///< features with the cameras
}  // namespace feature

/// The action's components of one controlled robot.
namespace action {
constexpr int kForward = 0, kLeft = 1, kAngular = 2, kKickSpeed = 3, kChipAngle = 4, kDribbler = 5;
constexpr int kCount = 6;
}  // namespace action

/// Where a task puts things at the start of an episode (one world).
struct EpisodeStart {
  std::vector<double> robot_pose;      ///< robots × 3: x, y (m), yaw (rad), in slot order; empty: the file's
  std::vector<std::uint8_t> present;   ///< robots: on the field
  std::array<double, 6> ball{};        ///< x, y, z (m), vx, vy, vz (m/s)
  bool has_ball = false;               ///< else the world file's ball
};

/// K worlds of one world file, stepped together.
class VectorWorlds {
 public:
  /// Builds K worlds of `loaded` (its transports left out: the caller drives the worlds).
  VectorWorlds(apps::LoadedWorld loaded, const VectorWorldsOptions& options);
  ~VectorWorlds();

  int count() const { return options_.count; }
  int robots() const { return static_cast<int>(slots_.size()); }
  int features() const { return options_.camera_features ? feature::kWithCameras : feature::kBase; }
  /// Robots the actions move, in slot order (the agent teams' slots).
  int controlled() const { return static_cast<int>(controlled_.size()); }
  /// Slot of each robot row: its id.
  const std::vector<RobotId>& slots() const { return slots_; }
  /// Slot index of each controlled robot.
  const std::vector<int>& controlled_slots() const { return controlled_; }
  /// The world file's model (field, robots, physics in force).
  const kernel::WorldModel& model() const { return loaded_.model; }
  /// Action bounds of a slot's robot: low and high of each action component.
  std::array<std::array<double, action::kCount>, 2> ActionBounds(int slot) const;
  /// Physics step, s.
  double step_seconds() const;

  /// Starts world `index`'s next episode: the world rebuilt with `seed` for its random processes,
  /// then `start` applied; writes its observation row into `obs` (robots × features).
  void Reset(int index, std::uint64_t seed, const EpisodeStart& start, float* obs);
  /// One env step of every world: `actions` (K × controlled × action::kCount) sent as robot
  /// commands, frame_skip physics steps, observations into `obs` (K × robots × features).
  void Step(const float* actions, float* obs);
  /// The observation of every world now, into `obs`.
  void Observe(float* obs);

  /// Reads again which robots of world `index` are on the field (after a restore: the actions are
  /// sent only to those, by what the last observation saw).
  void RefreshPresence(int index);
  /// World `index` (its state hash, ground truth, save, restore).
  World& world(int index) { return *worlds_[static_cast<std::size_t>(index)]->world; }
  /// Physics steps taken by all worlds together since construction.
  std::int64_t physics_steps() const { return physics_steps_; }

 private:
  struct Seen {
    bool seen = false;
    double x = 0, y = 0, yaw = 0;
  };
  struct Instance {
    std::unique_ptr<World> world;
    std::unique_ptr<apps::RandomPlay> random_play;
    std::vector<ScriptedTeam> scripted;
    std::vector<bool> present;      // per slot, as the last observation saw it
    std::vector<Seen> robots_seen;  // per slot, since the last observation
    Seen ball_seen;
    std::vector<Seen> robots_last;  // the last report of each slot
    Seen ball_last;
  };
  void StartDrivers(Instance& w, std::uint64_t seed);
  void RefreshPresence(Instance& w);
  void ObserveOne(Instance& w, float* obs);
  void SendActions(Instance& w, const float* actions);

  apps::LoadedWorld loaded_;
  std::ostringstream log_text_;
  kernel::StreamLog log_;
  VectorWorldsOptions options_;
  std::vector<RobotId> slots_;
  std::vector<int> controlled_;
  std::vector<std::unique_ptr<Instance>> worlds_;
  std::int64_t physics_steps_ = 0;
};

/// "blue"/"yellow" → Team; throws std::invalid_argument otherwise.
Team TeamNamed(const std::string& name);
/// "agent", "idle", "scripted", "random" → TeamDriver; throws std::invalid_argument otherwise.
TeamDriver DriverNamed(const std::string& name);

}  // namespace ubersim::python
