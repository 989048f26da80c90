// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "ubersim/component.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"
#include "ubersim/kernel/scene_graph.hpp"
#include "ubersim/world_state.hpp"

namespace ubersim::kernel {

/// Services the world lends its robots.
struct RobotServices {
  BodyImpl* ball = nullptr;      ///< the ball body
  double ball_radius = 0.0215;   ///< m
  Vec3 gravity = Vec3(0, 0, -9.81);
  const std::int64_t* sim_time_ns = nullptr;  ///< the world's clock
};

/// A robot: its node, chassis built from the model's body block, and its drive, dribbler and
/// kicker plugins, each with its own context. A component that throws while stepping is
/// reported once and switched off; the rest of the world carries on.
class Robot {
 public:
  /// Builds the chassis under `team_node` and creates and configures the plugins.
  Robot(const RobotPlacement& placement, NodeImpl& team_node, PluginRegistry& registry, Log& log,
        const RobotServices& services);
  ~Robot();

  const RobotId& id() const { return id_; }         ///< team and id
  BodyImpl& chassis() { return *chassis_; }         ///< chassis body
  NodeImpl& node() { return *node_; }               ///< the robot's node
  bool present() const { return present_; }         ///< on the field

  /// Components' PreStep (drive, dribbler, kicker order).
  void PreStep(const StepInfo& step);
  /// Components' PostStep.
  void PostStep(const StepInfo& step);
  /// Applies a command event's parts to the components it has; false with a reason if a part
  /// has no component to take it.
  bool Command(const CommandEvent& e, std::string& why);
  /// Moves the whole robot (every body of its subtree) rigidly to (x, y, yaw).
  void Teleport(double x, double y, double yaw);
  /// Sets the velocity of every body of the robot (world frame, about the chassis origin).
  void SetVelocity(const Vec3& linear, const Vec3& angular);
  /// Takes the robot off the field (no collisions, frozen) or puts it back.
  void SetPresent(bool present);
  /// Ground truth.
  RobotState State() const;

 private:
  class Context;
  struct Part;
  void RunPhase(bool pre, const StepInfo& step);
  void BuildCylinderChassis(const RobotPlacement& placement);
  void BuildUrdfBodies(const RobotPlacement& placement);

  RobotId id_;
  std::shared_ptr<const RobotModel> model_;
  NodeImpl* node_ = nullptr;
  BodyImpl* chassis_ = nullptr;
  bool present_ = true;
  double rest_height_ = 0.0;
  std::vector<std::unique_ptr<Part>> parts_;  // drive, dribbler, kicker (those present)
  Drive* drive_ = nullptr;
  Dribbler* dribbler_ = nullptr;
  Kicker* kicker_ = nullptr;
};

}  // namespace ubersim::kernel
