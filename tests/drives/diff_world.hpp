// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/world.hpp"

// The paper's differential robot alone in the 2003 world (its materials, physics and ball) at a
// chosen physics profile, on the Div B field so that long runs fit, driven by commands at 100 Hz
// over an ideal radio.
namespace ubersim::kernel {

inline constexpr const char* kDiffRobot = UBERSIM_SOURCE_DIR "/models/robots/cmdragons-2003-diff.yaml";

struct DiffWorld {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kWarning};
  PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  std::unique_ptr<World> world;

  explicit DiffWorld(const std::string& profile, double x = -3.0, double y = 0.0, double yaw = 0.0,
                     const std::string& robot_file = kDiffRobot) {
    const ModelLoader loader(ModelLoader::DefaultSchemaDir(),
                             [this](PluginKind k, const std::string& id) {
                               return registry.Find(k, id).schema_json;
                             });
    WorldModel model = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/ssl-2003.yaml");
    PhysicsOverrides o;
    o.profile = profile;
    o.ApplyTo(model.physics);
    model.field = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml").field;
    model.radio = RadioModel{};  // ideal: commands take effect at once, none lost
    model.robots.clear();
    model.robots.push_back(RobotPlacement{{Team::kBlue, 0}, loader.LoadRobot(robot_file), x, y, yaw, true});
    model.ball_start = Vec3(3.5, 2.5, 0);  // out of the way
    world = std::make_unique<World>(model, registry, log, false);
  }
  RobotState Robot() const { return world->GroundTruth().robots.at(0); }
  double Dt() const { return world->model().physics.step; }
  int Steps(double seconds) const { return static_cast<int>(std::lround(seconds / Dt())); }
  // Steps for `seconds` without commands.
  void Run(double seconds) {
    for (int i = Steps(seconds); i > 0; --i) world->Step();
  }
  // Sends the command every 10 ms (a 100 Hz radio) for `seconds`.
  void Drive(const MoveCommand& c, double seconds) {
    const int steps = Steps(seconds);
    const int every = std::max(1, Steps(0.01));
    for (int i = 0; i < steps; ++i) {
      if (i % every == 0) world->events().Post(CommandEvent{{Team::kBlue, 0}, c, {}, {}});
      world->Step();
    }
  }
  // Velocity in the robot frame: forward, left, m/s.
  Vec3 LocalVelocity() const {
    const RobotState r = Robot();
    return r.pose.orientation.conjugate() * r.twist.linear;
  }
};

}  // namespace ubersim::kernel
