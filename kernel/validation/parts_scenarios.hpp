// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ubersim/validation/scenarios.hpp"

namespace ubersim::validation::detail {

/// The kicker: a flat kick commanded above the limit leaves at the limit; a chip at its angle.
ScenarioResult KickerSpeeds(const Environment& env);
/// The dribbler holds the ball through a 1 m drive and a 90° turn at 2 rad/s, loses it in a fast
/// spin, and a kick while dribbling still leaves at the clamped speed.
ScenarioResult DribblerHold(const Environment& env);

}  // namespace ubersim::validation::detail
