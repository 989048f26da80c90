// SPDX-License-Identifier: Apache-2.0
#include "samples.hpp"

namespace ubersim::calibrate {

std::string RobotName(const RobotKey& robot) {
  return std::string(robot.team == TeamColour::kBlue ? "blue " : "yellow ") + std::to_string(robot.id);
}

}  // namespace ubersim::calibrate
