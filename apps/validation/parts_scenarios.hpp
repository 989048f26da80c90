// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <string>

#include "ubersim/validation/scenarios.hpp"

namespace ubersim::validation::detail {

/// The robot the parts scenarios use: the modern four-wheel robot, and `robot_file` (relative
/// to the models folder) for the same parts on another model, under the scenario id `id`.
inline constexpr const char* kPartsRobot = "robots/ssl-omni-2026.yaml";

/// The kicker: a flat kick commanded above the limit leaves at the limit; a chip at its angle.
ScenarioResult KickerSpeeds(const Environment& env, const std::string& robot_file = kPartsRobot,
                            const std::string& id = "kicker_speeds");
/// The dribbler holds the ball through a 1 m drive and a 90° turn at 2 rad/s, loses it in a fast
/// spin, and a kick while dribbling still leaves at the clamped speed. Its plot is `id`.svg with
/// dashes for underscores.
ScenarioResult DribblerHold(const Environment& env, const std::string& robot_file = kPartsRobot,
                            const std::string& id = "dribbler_hold");

}  // namespace ubersim::validation::detail
