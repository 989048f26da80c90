// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "ubersim/validation/scenarios.hpp"

namespace ubersim::validation::detail {

/// A robot model the robot scenarios drive: the scenario ids' prefix (the drive plugin for the
/// shipped robots: "omni_steady_velocity", "omni_force_steady_velocity"), its file (relative to
/// the models folder, or absolute), and the limits the commands and bands are scaled to.
struct OmniModel {
  std::string drive;               ///< id prefix
  std::string file;                ///< robot model file
  double max_speed = 3.0;          ///< m/s, the drive's limits.max_speed
  double max_accel = 3.0;          ///< m/s², the drive's limits.max_accel
  double max_angular_speed = 10.0; ///< rad/s, the drive's limits.max_angular_speed
  std::string name = {};           ///< in titles; empty: "Omni robot"
  std::string subject = {};        ///< how the setup text names it; empty: the modern four-wheel robot
};
/// The modern four-wheel robot on the omni drive: a body per wheel on a motorised hinge.
inline const OmniModel kWheelBodyOmni{"omni", "robots/ssl-omni-2026.yaml"};
/// The same robot on the omni_force drive: one rigid body, the wheel forces applied to it.
inline const OmniModel kForceOmni{"omni_force", "robots/ssl-omni-2026-force.yaml"};
/// The same body on four mecanum wheels, rollers at 45° to the axles.
inline const OmniModel kMecanum{"mecanum", "robots/ssl-mecanum-2026.yaml", 3.0, 3.0, 10.0, "Mecanum robot",
                                "The mecanum robot (models/robots/ssl-mecanum-2026.yaml: wheels at the corners, "
                                "rollers at 45° to the axles)"};

/// The modern four-wheel omni robot holds commanded velocities: forward, sideways, diagonal, turning.
ScenarioResult OmniSteadyVelocity(const Environment& env, const OmniModel& model = kWheelBodyOmni);
/// The omni robot speeds up at its configured acceleration limit.
ScenarioResult OmniAcceleration(const Environment& env, const OmniModel& model = kWheelBodyOmni);

/// The mecanum robot's wheels driven straight ahead faster than the carpet can follow: the
/// speed-up is grip-limited at μ·g·cos 45° (each wheel's carpet force acts across its rollers).
ScenarioResult MecanumGripLimit(const Environment& env);

/// A team's robot, loaded from `file`, as the robot scenarios drive it: its drive's limits read
/// from the model (schema defaults where the file leaves them out), ids prefixed with the file's stem.
OmniModel RobotUnderTest(const kernel::RobotModel& robot, const std::filesystem::path& file);

}  // namespace ubersim::validation::detail
