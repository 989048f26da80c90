// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <string>

#include "ubersim/validation/scenarios.hpp"

namespace ubersim::validation::detail {

/// An omni robot model the robot scenarios drive: the drive plugin it names, which is also the
/// scenario ids' prefix ("omni_steady_velocity", "omni_force_steady_velocity"), and its file
/// (relative to the models folder).
struct OmniModel {
  const char* drive;
  const char* file;
};
/// The modern four-wheel robot on the omni drive: a body per wheel on a motorised hinge.
inline constexpr OmniModel kWheelBodyOmni{"omni", "robots/ssl-omni-2026.yaml"};
/// The same robot on the omni_force drive: one rigid body, the wheel forces applied to it.
inline constexpr OmniModel kForceOmni{"omni_force", "robots/ssl-omni-2026-force.yaml"};

/// The modern four-wheel omni robot holds commanded velocities: forward, sideways, diagonal, turning.
ScenarioResult OmniSteadyVelocity(const Environment& env, const OmniModel& model = kWheelBodyOmni);
/// The omni robot speeds up at its configured acceleration limit.
ScenarioResult OmniAcceleration(const Environment& env, const OmniModel& model = kWheelBodyOmni);

}  // namespace ubersim::validation::detail
