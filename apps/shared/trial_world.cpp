// SPDX-License-Identifier: Apache-2.0
#include "shared/trial_world.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace ubersim::apps {

using kernel::RobotModel;
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

namespace {

// The model a new robot of `team` takes: the world's first robot of that team (after --robot),
// else the team's model for robots coming on, else any robot's.
std::shared_ptr<const RobotModel> TeamModel(const WorldModel& model, Team team) {
  for (const RobotPlacement& p : model.robots) {
    if (p.id.team == team && p.model) return p.model;
  }
  if (const auto& m = model.team_models[team == Team::kBlue ? 0 : 1]) return m;
  for (const RobotPlacement& p : model.robots) {
    if (p.model) return p.model;
  }
  return nullptr;
}

}  // namespace

void PlaceRobots(WorldModel& model, int count) {
  if (count < 1 || count > kMaxTrialRobots) {
    throw std::invalid_argument("robot count " + std::to_string(count) + " outside 1.." +
                                std::to_string(kMaxTrialRobots) + " (ids 0..15 in each team)");
  }
  const auto blue = TeamModel(model, Team::kBlue);
  const auto yellow = TeamModel(model, Team::kYellow);
  if (!blue || !yellow) throw std::invalid_argument("world " + model.name + " has no robot model to place");
  const FieldGeometry& f = model.field->geometry;
  const double radius = std::max(blue->body.radius, yellow->body.radius);
  // A team's half, kept a robot's width from the touch and goal lines and out of the centre
  // circle, where the ball starts.
  const double x_near = f.center_circle_radius + 2 * radius;
  const double x_far = 0.5 * f.field_length - 2 * radius;
  const double y_span = f.field_width - 4 * radius;
  const int per_team[2] = {(count + 1) / 2, count / 2};
  std::vector<RobotPlacement> placed;
  for (int t = 0; t < 2; ++t) {
    const int k = per_team[t];
    if (k == 0) continue;
    const double x_span = x_far - x_near;
    // As many columns as keep the cells about square.
    const int columns = std::clamp(static_cast<int>(std::ceil(std::sqrt(k * x_span / y_span))), 1, k);
    const int rows = (k + columns - 1) / columns;
    const double dx = x_span / columns, dy = y_span / rows;
    if (x_span <= 0 || std::min(dx, dy) < 2 * radius + 0.05) {
      throw std::invalid_argument(std::to_string(count) + " robots do not fit on field " + f.name +
                                  " without touching");
    }
    const Team team = t == 0 ? Team::kBlue : Team::kYellow;
    const double side = t == 0 ? -1.0 : 1.0;
    for (int i = 0; i < k; ++i) {
      RobotPlacement p;
      p.id = RobotId{team, i};
      p.model = t == 0 ? blue : yellow;
      p.x = side * (x_near + (i % columns + 0.5) * dx);
      p.y = -0.5 * y_span + (i / columns + 0.5) * dy;
      p.yaw = t == 0 ? 0.0 : std::numbers::pi;
      placed.push_back(p);
    }
  }
  model.robots = std::move(placed);
}

}  // namespace ubersim::apps
