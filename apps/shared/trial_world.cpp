// SPDX-License-Identifier: Apache-2.0
#include "shared/trial_world.hpp"

namespace ubersim::apps {

using kernel::RobotPlacement;

WorldModel LoadTrialWorld(const ModelLoader& loader, const std::filesystem::path& file,
                          const PhysicsOverrides& physics, const std::optional<std::string>& robot_file) {
  WorldModel model = loader.LoadWorld(file);
  physics.ApplyTo(model.physics);
  if (robot_file) {
    const auto robot = loader.LoadRobot(*robot_file);
    for (RobotPlacement& p : model.robots) p.model = robot;
  }
  return model;
}

}  // namespace ubersim::apps
