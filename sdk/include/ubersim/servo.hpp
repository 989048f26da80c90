// SPDX-License-Identifier: Apache-2.0
#pragma once
// Velocity-setpoint shaping for drive plugins: the local servo loop the robots' firmware runs
// between a radio command and the wheel motors. Header-only.

#include <algorithm>
#include <cmath>

#include <Eigen/Core>

#include "ubersim/events.hpp"
#include "ubersim/params.hpp"
#include "ubersim/scene.hpp"

namespace ubersim {
inline namespace v1 {

/// Moves `value` toward `target` by at most accel·dt when speeding up and brake·dt when slowing
/// down or reversing. Speeds in m/s (or rad/s), accel and brake in m/s² (or rad/s²), dt in s.
inline double RampScalar(double value, double target, double accel, double brake, double dt) {
  const bool slowing = std::abs(target) < std::abs(value) || target * value < 0;
  const double step = (slowing ? brake : accel) * dt;
  return value + std::clamp(target - value, -step, step);
}

/// Moves the 2-D velocity `value` toward `target` along their difference, by at most accel·dt
/// when speeding up and brake·dt when slowing down or reversing. m/s, m/s², s.
inline Eigen::Vector2d RampVector(const Eigen::Vector2d& value, const Eigen::Vector2d& target,
                                  double accel, double brake, double dt) {
  const Eigen::Vector2d diff = target - value;
  const bool slowing = target.norm() < value.norm() || target.dot(value) < 0;
  const double max_step = (slowing ? brake : accel) * dt;
  const double length = diff.norm();
  return length <= max_step ? target : Eigen::Vector2d(value + diff * (max_step / length));
}

/// Limits of a planar velocity servo. Linear in m/s and m/s², angular in rad/s and rad/s².
struct ServoLimits {
  double max_speed = 3.0;           ///< largest linear speed, m/s
  double max_accel = 3.0;           ///< linear speed-up limit, m/s²
  double max_brake = 6.0;           ///< linear slow-down limit, m/s²
  double max_angular_speed = 10.0;  ///< largest angular speed, rad/s
  double max_angular_accel = 50.0;  ///< angular speed-up limit, rad/s²
  double max_angular_brake = 50.0;  ///< angular slow-down limit, rad/s²
};

/// Reads a `limits:` block (keys as the ServoLimits members, SI) over `defaults`; absent keys keep theirs.
inline ServoLimits ReadServoLimits(const ParamView& limits, ServoLimits defaults) {
  defaults.max_speed = limits.GetDouble("max_speed", defaults.max_speed);
  defaults.max_accel = limits.GetDouble("max_accel", defaults.max_accel);
  defaults.max_brake = limits.GetDouble("max_brake", defaults.max_brake);
  defaults.max_angular_speed = limits.GetDouble("max_angular_speed", defaults.max_angular_speed);
  defaults.max_angular_accel = limits.GetDouble("max_angular_accel", defaults.max_angular_accel);
  defaults.max_angular_brake = limits.GetDouble("max_angular_brake", defaults.max_angular_brake);
  return defaults;
}

/// A planar velocity in the robot frame: linear (forward, left) in m/s, angular (ccw) in rad/s.
struct PlanarVelocity {
  Eigen::Vector2d linear = Eigen::Vector2d::Zero();  ///< forward (x), left (y), m/s
  double angular = 0.0;                              ///< counter-clockwise, rad/s
};

/// A world-frame planar vector (x, y) in the frame of a robot heading `yaw` (rad): (forward, left).
inline Eigen::Vector2d ToRobotFrame(double yaw, double x, double y) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return {c * x + s * y, -s * x + c * y};
}

/// The heading of a frame turned by `orientation`, as the unit vector (cos yaw, sin yaw) its
/// forward axis points along in the carpet plane: (1, 0) when it points straight up or down
/// (as atan2(0, 0) = 0). Exact where cos and sin of Pose::Yaw() round: no trigonometry.
inline Eigen::Vector2d HeadingOf(const Quat& orientation) {
  const Vec3 forward = Rotate(orientation, Vec3::UnitX());
  const double length = std::sqrt(forward.x() * forward.x() + forward.y() * forward.y());
  if (!(length > 0.0)) return Eigen::Vector2d(1.0, 0.0);
  return Eigen::Vector2d(forward.x() / length, forward.y() / length);
}

/// A world-frame planar vector (x, y) in the frame of a robot whose heading is the unit vector
/// `heading` (HeadingOf): (forward, left).
inline Eigen::Vector2d ToRobotFrame(const Eigen::Vector2d& heading, double x, double y) {
  const double c = heading.x(), s = heading.y();
  return {c * x + s * y, -s * x + c * y};
}

/// A robot-frame velocity setpoint (m/s) turned into the frame the robot will have at the end of
/// a step of dt (s) turning at `spin` (rad/s): what its wheels must drive now so that, having
/// turned, it moves as asked. Without it a robot driving while turning drifts across its command
/// by speed·spin·dt (10 mm/s at 1 m/s, 2 rad/s and 5 ms steps).
inline Eigen::Vector2d AheadOfTheTurn(const Eigen::Vector2d& setpoint, double spin, double dt) {
  return ToRobotFrame(-spin * dt, setpoint.x(), setpoint.y());  // turned by +spin·dt
}

/// The chassis' velocity as a drive's speed loop sees it: (forward, left) in the robot's heading
/// frame and the turn rate about the vertical, from the body's world pose and velocity.
inline PlanarVelocity LocalPlanarVelocity(const Body& chassis) {
  const Twist t = chassis.GetTwist();
  return {ToRobotFrame(HeadingOf(chassis.GetPose().orientation), t.linear.x(), t.linear.y()), t.angular.z()};
}

/// What a velocity command asks of a robot whose heading is the unit vector `heading`
/// (HeadingOf), in its own frame: a local command as it is, a global one turned by the heading;
/// wheel speeds ask no velocity (zero).
inline PlanarVelocity CommandedVelocity(const MoveCommand& command, const Eigen::Vector2d& heading) {
  if (const auto* l = std::get_if<LocalVelocityCommand>(&command)) {
    return {Eigen::Vector2d(l->forward, l->left), l->angular};
  }
  if (const auto* g = std::get_if<GlobalVelocityCommand>(&command)) {
    return {ToRobotFrame(heading, g->x, g->y), g->angular};
  }
  return {};
}

/// What a velocity command asks of the robot, in its own frame, with the chassis' heading now.
inline PlanarVelocity CommandedVelocity(const MoveCommand& command, const Body& chassis) {
  if (std::holds_alternative<GlobalVelocityCommand>(command)) {
    return CommandedVelocity(command, HeadingOf(chassis.GetPose().orientation));
  }
  return CommandedVelocity(command, Eigen::Vector2d(1.0, 0.0));
}

/// The velocity setpoint a drive follows: targets are clamped to the speed limits, and the
/// setpoint moves toward them within the acceleration and brake limits, step by step.
class VelocityServo {
 public:
  /// A servo at rest with the given limits.
  explicit VelocityServo(const ServoLimits& limits = {}) : limits_(limits) {}

  /// Replaces the limits; the setpoint stays.
  void SetLimits(const ServoLimits& limits) { limits_ = limits; }
  /// The limits in use.
  const ServoLimits& Limits() const { return limits_; }

  /// `target` with its linear speed scaled down to max_speed (direction kept) and its angular
  /// speed clamped to ±max_angular_speed.
  PlanarVelocity ClampToLimits(PlanarVelocity target) const {
    // Not std::hypot: its overflow guard costs ten times the arithmetic, for speeds of m/s.
    const double speed = std::sqrt(target.linear.x() * target.linear.x() + target.linear.y() * target.linear.y());
    if (speed > limits_.max_speed) {
      target.linear.x() *= limits_.max_speed / speed;
      target.linear.y() *= limits_.max_speed / speed;
    }
    target.angular = std::clamp(target.angular, -limits_.max_angular_speed, limits_.max_angular_speed);
    return target;
  }

  /// Moves the setpoint one step of dt (s) toward `target` (clamp it first) and returns it.
  const PlanarVelocity& Step(const PlanarVelocity& target, double dt) {
    setpoint_.linear = RampVector(setpoint_.linear, target.linear, limits_.max_accel, limits_.max_brake, dt);
    setpoint_.angular = RampScalar(setpoint_.angular, target.angular, limits_.max_angular_accel,
                                   limits_.max_angular_brake, dt);
    return setpoint_;
  }

  /// Sets the setpoint directly (e.g. from wheel-speed commands that bypass the loop).
  void Set(const PlanarVelocity& setpoint) { setpoint_ = setpoint; }
  /// The current setpoint.
  const PlanarVelocity& Setpoint() const { return setpoint_; }
  /// Back to rest.
  void Reset() { setpoint_ = PlanarVelocity{}; }

 private:
  ServoLimits limits_;
  PlanarVelocity setpoint_;
};

/// The heading hold a robot's firmware runs with its gyro: the turn rate asked of the wheels is
/// the setpoint plus the integral of the rate error (setpoint − measured) times a gain, so a robot
/// told to drive straight keeps its heading wherever its wheels leave it turning (slip, unequal
/// wheels, a physics step that does not converge them), and a turn ends at the heading the
/// setpoint integrates to. rad/s, s.
class GyroRateLoop {
 public:
  /// `gain` 1/s (10: a heading error is taken out with a 0.1 s time constant; 0: no gyro, the
  /// setpoint passes unchanged); the correction is at most ±`max_correction` rad/s.
  explicit GyroRateLoop(double gain = 10.0, double max_correction = 2.0)
      : gain_(gain), max_correction_(max_correction) {}

  /// The turn rate to ask of the wheels this step, rad/s, given the setpoint's and the measured
  /// rate (rad/s) and the step dt (s).
  double Correct(double setpoint, double measured, double dt) {
    if (gain_ <= 0.0) return setpoint;  // no gyro
    const double limit = max_correction_ / gain_;
    heading_error_ = std::clamp(heading_error_ + (setpoint - measured) * dt, -limit, limit);
    return setpoint + gain_ * heading_error_;
  }
  /// The heading the robot lags its setpoint by, rad (what the loop corrects).
  double HeadingError() const { return heading_error_; }
  /// Sets the heading error (restoring a saved state), rad.
  void SetHeadingError(double e) { heading_error_ = e; }
  /// Forgets the error (a reset, a robot put down).
  void Reset() { heading_error_ = 0.0; }

 private:
  double gain_;
  double max_correction_;
  double heading_error_ = 0.0;  // rad
};

/// Command-timeout bookkeeping: a command is fresh for `timeout` seconds after it arrived; after
/// that the drive should brake to a stop. Times in s (simulated).
class CommandWatchdog {
 public:
  /// A watchdog with no command yet and the given timeout, s.
  explicit CommandWatchdog(double timeout = 0.1) : timeout_(timeout) {}

  /// Sets the timeout, s.
  void SetTimeout(double timeout) { timeout_ = timeout; }
  /// The timeout, s.
  double Timeout() const { return timeout_; }
  /// Records that a command arrived at time `now`, s.
  void Feed(double now) {
    last_ = now;
    has_command_ = true;
  }
  /// True when a command arrived no more than the timeout before `now`, s.
  bool Fresh(double now) const { return has_command_ && now - last_ <= timeout_; }
  /// Forgets the last command.
  void Reset() { has_command_ = false; }
  /// When the last command arrived, s (meaningful while HasCommand()).
  double LastFeed() const { return last_; }
  /// True once a command arrived (since the last Reset).
  bool HasCommand() const { return has_command_; }
  /// Puts back what LastFeed and HasCommand returned (a restored snapshot).
  void Restore(double last_feed, bool has_command) {
    last_ = last_feed;
    has_command_ = has_command;
  }

 private:
  double timeout_;
  double last_ = 0.0;
  bool has_command_ = false;
};

}  // namespace v1
}  // namespace ubersim
