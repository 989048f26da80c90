// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ubersim/validation/scenarios.hpp"

namespace ubersim::validation::detail {

/// Ball set rolling at v0 m/s without spin on an open carpet: two-phase fit and stopping distance.
ScenarioResult BallRoll(const Environment& env, double v0);
/// Ball launched as a chip: apex, first landing, damping of each bounce.
ScenarioResult ChipFlight(const Environment& env);
/// `shots` seeded shots at 6.5 m/s at robots and walls: none passes through. `physics_step` > 0
/// replaces the world's step (to show what a coarse step lets through).
ScenarioResult NoTunnelling(const Environment& env, int shots, double physics_step = 0);

}  // namespace ubersim::validation::detail
