// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/world.hpp"

// One robot of a given model file alone on the Div B field at a chosen physics profile, driven by
// commands at 100 Hz.
namespace ubersim::kernel {

inline constexpr const char* kOmniRobot = UBERSIM_SOURCE_DIR "/models/robots/ssl-omni-2026.yaml";

// Every physics profile a user may choose (precise, the shipped worlds', and fast).
inline auto BothProfiles() { return ::testing::ValuesIn(PhysicsProfileNames()); }
inline std::string ProfileName(const ::testing::TestParamInfo<std::string>& info) { return info.param; }

struct OmniWorld {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kWarning};
  PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  std::unique_ptr<World> world;

  explicit OmniWorld(const std::string& profile, const std::string& robot_file = kOmniRobot) {
    const ModelLoader loader(ModelLoader::DefaultSchemaDir(),
                             [this](PluginKind k, const std::string& id) {
                               return registry.Find(k, id).schema_json;
                             });
    WorldModel model = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml");
    PhysicsOverrides o;
    o.profile = profile;
    o.ApplyTo(model.physics);
    model.robots.clear();
    model.robots.push_back(RobotPlacement{{Team::kBlue, 0}, loader.LoadRobot(robot_file), -2.0, 0.0, 0.0, true});
    model.ball_start = Vec3(3.5, 2.5, 0);  // out of the way
    model.radio = RadioModel{};  // the drive is tested, not the radio: no delay, no loss
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
  Vec3 LocalVelocity() const {
    const RobotState r = Robot();
    return r.pose.orientation.conjugate() * r.twist.linear;
  }
};

}  // namespace ubersim::kernel
