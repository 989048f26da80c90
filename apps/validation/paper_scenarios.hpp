// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ubersim/validation/scenarios.hpp"

namespace ubersim::validation::detail {

/// The 2003 paper's straight-line acceleration test: the differential robot at 2 m/s².
ScenarioResult PaperAcceleration(const Environment& env);
/// The 2003 paper's figure-8 at about 0.8 m/s, driven by a simple waypoint controller.
ScenarioResult PaperFigureEight(const Environment& env);

}  // namespace ubersim::validation::detail
