// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/world.hpp"
#include "ubersim/validation/scenarios.hpp"

// Shared pieces of the scenarios: building worlds from the shipped model files and fitting lines.
namespace ubersim::validation::detail {

/// Loads a shipped world (path relative to the models folder), with its plugins' schemas checked.
kernel::WorldModel LoadWorld(const Environment& env, const std::string& world);
/// Loads a shipped robot model.
std::shared_ptr<const kernel::RobotModel> LoadRobot(const Environment& env, const std::string& robot);

/// The robot the one-robot scenarios drive.
inline const RobotId kRobot{Team::kBlue, 0};
/// A shipped world with its robots replaced by kRobot, a robot of `robot_file` at (x, y, yaw)
/// (m, rad); the caller places the ball.
kernel::WorldModel OneRobotWorld(const Environment& env, const std::string& world, const std::string& robot_file,
                                 double x, double y, double yaw);

/// A world being measured, stepped with commands sent at a radio rate.
class Bench {
 public:
  Bench(const Environment& env, const kernel::WorldModel& model);
  kernel::World& world() { return *world_; }
  /// Steps `seconds` of simulated time, posting `command` to `robot` every `radio_period` s.
  void Drive(const RobotId& robot, const MoveCommand& command, double seconds, double radio_period = 0.01);
  /// Steps once.
  void Step() { world_->Step(); }
  /// Simulated time, s.
  double Time() const { return 1e-9 * static_cast<double>(world_->clock().time_ns()); }
  /// Ground truth of a robot.
  RobotState Robot(const RobotId& id) const;
  /// Ground truth of the ball.
  BallState Ball() const { return world_->GroundTruth().ball; }
  /// Posts an event and applies it at once.
  void Apply(Event e);

 private:
  std::unique_ptr<kernel::World> world_;
};

/// Least-squares slope and intercept of y over x.
struct Line { double slope = 0, intercept = 0; };
Line FitLine(const std::vector<double>& x, const std::vector<double>& y);

/// Slope of speed over time while the speed is between 20 % and 80 % of `target` (the straight
/// part of a speed-up), m/s², over the first `count` samples (all when 0).
double SpeedUpSlope(const std::vector<double>& t, const std::vector<double>& v, double target, std::size_t count = 0);

/// A metric of value with an inclusive band.
Metric Band(std::string name, double value, std::string unit, double low, double high, std::string basis);

}  // namespace ubersim::validation::detail
