// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ubersim/validation/scenarios.hpp"

namespace ubersim::validation::detail {

/// The modern four-wheel omni robot holds commanded velocities: forward, sideways, diagonal, turning.
ScenarioResult OmniSteadyVelocity(const Environment& env);
/// The omni robot speeds up at its configured acceleration limit.
ScenarioResult OmniAcceleration(const Environment& env);

}  // namespace ubersim::validation::detail
