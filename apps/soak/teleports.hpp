// SPDX-License-Identifier: Apache-2.0
// Seeded random teleports for soak runs: robots and the ball put onto other robots, into walls
// and goals, anywhere on the field, moving fast. What a careless team's software or a test
// harness may send, and what the physics must survive.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "ubersim/kernel/world.hpp"

namespace ubersim::kernel::soak {

/// What a teleport does.
enum class TeleportKind {
  kRobotOntoRobot,  ///< a robot put overlapping another, moving
  kRobotIntoWall,   ///< a robot put overlapping a wall or a goal wall (its centre in front of it), moving
  kRobotAnywhere,   ///< a robot put anywhere between the walls, moving
  kBallOntoRobot,   ///< the ball put overlapping a robot (or inside it), at up to 6.5 m/s
  kBallIntoWall,    ///< the ball put overlapping a wall or a goal wall, at up to 6.5 m/s
  kBallShot,        ///< the ball shot at 6.5 m/s at a robot from anywhere on the field
};
constexpr int kTeleportKinds = 6;  ///< number of TeleportKind values

/// "robot onto robot", "robot into wall", …
const char* ToString(TeleportKind kind);

/// Posts a random teleport now and then (exponentially distributed gaps of a given mean), and
/// remembers when each object was last moved. Deterministic for a seed and world.
class RandomTeleports {
 public:
  /// Teleports in `world`, one every `mean_interval` simulated seconds on average. A robot put
  /// into a wall overlaps it by up to `wall_overlap` of the wall's thickness (at most its radius).
  RandomTeleports(World& world, std::uint64_t seed, double mean_interval, double wall_overlap = 0.5);

  /// Posts the teleport due before the next step, if one is; returns its kind.
  std::optional<TeleportKind> BeforeStep();
  /// Posts a teleport of `kind` now.
  void Teleport(TeleportKind kind);
  /// Puts a robot (or the ball) back at rest somewhere free between the walls, as after a finding.
  void Replace(const Target& target);
  /// Records that something else moved the ball or a robot now (e.g. the random play's ball).
  void MarkMoved(const Target& target);
  /// Sim time the object was last teleported or disturbed by a teleport, ns; never: a very
  /// negative number.
  std::int64_t LastMoved(const Target& target) const;
  /// Also hands every teleport posted to `observer`, with what it was ("robot onto robot", …,
  /// "put back").
  void SetObserver(std::function<void(const char* what, const PositionEvent&)> observer) {
    observer_ = std::move(observer);
  }
  /// Teleports made so far, by kind.
  const std::array<std::int64_t, kTeleportKinds>& counts() const { return counts_; }

 private:
  // A vertical face of a wall or goal box that looks into the walled area.
  struct Face {
    Vec3 centre;          // on the face, at carpet height, m
    Vec3 normal;          // outward, horizontal
    Vec3 along;           // horizontal, along the face
    double half_length;   // m
    double thickness;     // of the wall behind it, m
  };
  // A robot's footprint: a circle cut flat at the front.
  struct Hull {
    RobotId id;
    double radius, front_distance;  // m
  };
  struct Box {
    Pose pose;
    Vec3 half;
  };
  void FindFaces();
  bool Free(const Vec3& p, double radius) const;  // between the walls, not inside a box
  // A robot hull of `radius` at `p` overlaps no wall or goal wall by more than wall_overlap_ of
  // its thickness, and not two goal walls at once (a goal's corner). (A hull is hollow to the
  // collision code: a wall that reaches far into it is held by contacts on both sides.)
  bool Resolvable(const Vec3& p, double radius) const;
  Vec3 RandomFreePoint(double radius);
  Vec3 RandomVelocity(double max_speed, const std::optional<Vec3>& towards);
  void PostRobot(const RobotId& id, const Vec3& position, double yaw, const Vec3& velocity, double spin);
  void PostBall(const Vec3& position, const Vec3& velocity);
  RobotId RandomRobot();
  Vec3 Around(double distance);
  // Centre to hull edge of robot `id` facing `yaw`, along the horizontal direction `direction`, m.
  double HullReach(const RobotId& id, double yaw, double direction) const;
  // Whether the ball's centre would be inside robot `id` standing at `at` facing `yaw`. A hull is
  // hollow to the collision code: a ball wholly inside it is never pushed out.
  bool TrapsBall(const RobotId& id, const Vec3& at, double yaw, const Vec3& ball) const;
  bool InsideARobot(const Vec3& p, const WorldSnapshot& s) const;  // inside any robot's hull

  World& world_;
  std::mt19937_64 rng_;
  double mean_interval_;
  double wall_overlap_;
  std::int64_t next_ns_ = 0;
  std::vector<RobotId> robots_;
  std::vector<Face> faces_;
  std::vector<Box> boxes_;
  std::vector<Hull> hulls_;
  double robot_radius_ = 0.09, ball_radius_ = 0.0215;
  std::map<std::pair<bool, std::pair<int, int>>, std::int64_t> last_moved_;
  std::array<std::int64_t, kTeleportKinds> counts_{};
  const char* doing_ = "";  // what the teleport being posted is, for the observer
  std::function<void(const char*, const PositionEvent&)> observer_;
};

}  // namespace ubersim::kernel::soak
