// SPDX-License-Identifier: Apache-2.0
// The kernel's state checks: is the world physically sound right now? Each finding names the
// object ("robot blue 3", "ball"), its part, what is wrong and the values, so a soak run, a test
// or a guard against a misbehaving plugin can say exactly what broke.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ubersim/events.hpp"

namespace ubersim::kernel {

class World;

/// What a check found wrong.
enum class StateIssue {
  kNonFinite,     ///< a position, orientation or velocity is NaN or infinite
  kTooFast,       ///< faster than anything on an SSL field moves: the solver is blowing up
  kUnderCarpet,   ///< reaches below the carpet deeper than a contact lets it sink
  kOutsideWalls,  ///< a body's centre is beyond the perimeter walls' outer faces
  kInsideOther,   ///< overlaps another object, a wall or a goal deeper than a contact allows
  kTipped,        ///< a robot's chassis leans past the tilt limit now (the soak counts it when it stays)
};
constexpr int kStateIssues = 6;  ///< number of StateIssue values

/// "non-finite", "too fast", "under the carpet", "outside the walls", "inside another", "tipped".
const char* ToString(StateIssue issue);

/// An object of the world as the checks name it.
struct StateObject {
  /// What kind of object.
  enum class Kind { kBall, kRobot, kField, kOther };
  Kind kind = Kind::kOther;  ///< kind
  RobotId robot;             ///< the robot, for kRobot
  std::string name;          ///< "ball", "robot blue 3", "wall_top" (field), else its scene path
};

/// One finding.
struct StateViolation {
  StateIssue issue = StateIssue::kNonFinite;  ///< what is wrong
  StateObject object;                         ///< where
  std::string part;                  ///< its body or geometry: "chassis", "wheel0/wheel", "shell"
  std::optional<StateObject> other;  ///< kInsideOther: what it is inside
  std::string other_part;            ///< kInsideOther: the other's geometry
  double value = 0;  ///< how bad: m (depth, distance), m/s or rad/s; NaN for kNonFinite
  double limit = 0;  ///< the limit it broke, same unit
  std::string unit = "m";  ///< of value and limit: "m", "m/s" or "rad/s"
  std::string detail;  ///< the values behind it (positions, velocities)
  /// One line, e.g. "robot blue 3 (shell): 35.0 mm inside robot yellow 4 (shell), limit 15.0 mm".
  std::string Describe() const;
};

/// Where sound ends. The defaults suit the shipped worlds (1 ms step, ERP 0.2, 0.5 mm contact
/// layer); docs/reliability.md lists the extremes measured in sound play against them.
struct StateCheckLimits {
  /// Penetration of two robots, or a robot and a wall or goal, m. A contact lets bodies sink a
  /// little (the 0.5 mm surface layer, then ERP removes 20 % of the rest per step), and a 6 m/s
  /// head-on crash closes 6 mm in the step before its contact exists; deeper than this is a
  /// robot inside another, not a contact.
  double robot_penetration = 0.015;
  /// Penetration of the ball into a robot's shell, a wall or a goal, m: half the golf ball's
  /// radius. A 6.5 m/s ball closes 6.5 mm per step; past half its radius it is going through.
  double ball_penetration = 0.0107;
  /// How far a body's geometry may reach below the carpet (z = 0), m. Loaded wheels sink a
  /// fraction of a millimetre; a tipping robot's crash may push one a few millimetres further.
  double carpet_penetration = 0.01;
  /// Slack beyond the walls' outer faces before a body's centre counts as outside, m. Any centre
  /// past the outer face has gone through the wall (nothing can push it back), so none is needed.
  double wall_margin = 0.0;
  /// Linear speed of any body, m/s: twice the fastest legitimate motion (a 6.5 m/s kick from a
  /// robot driving 3 m/s); only an exploding solver goes faster.
  double linear_speed = 20.0;
  /// Angular speed of any body, rad/s: a 9.5 m/s ball rolls at 440 rad/s, wheels and dribbler
  /// bars turn at most at 150 rad/s; several times that is a solver blowing up.
  double angular_speed = 3000.0;
  /// A robot's lean from upright (its chassis' z axis against the world's), rad: 20°. Braking
  /// hard tilts a wheeled robot by up to 8° at the fast profile, and a real SSL robot (centre of
  /// mass 4-5 cm up, wheels 7-8 cm out) has two wheels in the air long before that; a robot
  /// leaning further is falling over, which no crash on a field should make it do.
  double tilt = 0.35;
};

/// Which checks run (all by default; a guard run every step may want only `finite`, the
/// cheapest), and their limits.
struct StateCheckOptions {
  StateCheckLimits limits;  ///< the limits
  bool finite = true;       ///< kNonFinite: every body's pose and velocities
  bool speed = true;        ///< kTooFast
  bool carpet = true;       ///< kUnderCarpet: every geometry that may touch the carpet
  bool walls = true;        ///< kOutsideWalls: every body
  bool overlap = true;      ///< kInsideOther: robot shells, the ball, walls and goals
  bool tilt = true;         ///< kTipped: every robot's own bodies (its chassis)
};

/// Checks the world as it is now. Robots taken off the field are checked only for non-finite
/// values; an object with a non-finite value gets no other finding. At most one finding per
/// object and issue (and other object), the worst one.
std::vector<StateViolation> CheckState(const World& world, const StateCheckOptions& options = {});

}  // namespace ubersim::kernel
