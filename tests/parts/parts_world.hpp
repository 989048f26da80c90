// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/world.hpp"
#include "world/world_attorney.hpp"

// One robot with its dribbler and kicker alone on the Div B field at (-2, 0) facing +x, the ball
// anywhere, commands sent at 100 Hz as a team's radio does, at a physics profile each test names.
namespace ubersim::kernel {

inline constexpr const char* kModernRobot = UBERSIM_SOURCE_DIR "/models/robots/ssl-omni-2026.yaml";
inline constexpr const char* kModernUrdfRobot = UBERSIM_SOURCE_DIR "/models/robots/ssl-omni-2026-urdf.yaml";
inline constexpr const char* k2003Robot = UBERSIM_SOURCE_DIR "/models/robots/cmdragons-2003-omni.yaml";

struct PartsWorld {
  static constexpr RobotId kRobot{Team::kBlue, 0};
  std::ostringstream text;
  StreamLog log{text, LogLevel::kWarning};
  PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  std::shared_ptr<const RobotModel> robot_model;
  std::unique_ptr<World> world;

  // `profile`: "precise" or "fast" (PhysicsProfileNames), over the world file's own; `held_ball`:
  // the world's dribblers hold the ball by a constraint (`dribbling: held`).
  explicit PartsWorld(const std::string& profile, const std::string& robot_file = kModernRobot,
                      bool held_ball = false) {
    const ModelLoader loader(ModelLoader::DefaultSchemaDir(),
                             [this](PluginKind k, const std::string& id) {
                               return registry.Find(k, id).schema_json;
                             });
    WorldModel model = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml");
    PhysicsOverrides o;
    o.profile = profile;
    o.ApplyTo(model.physics);
    model.robots.clear();
    model.robots.push_back(RobotPlacement{kRobot, loader.LoadRobot(robot_file), -2.0, 0.0, 0.0, true});
    robot_model = model.robots.back().model;
    model.ball_start = Vec3(3.5, 2.5, 0);  // out of the way until a test places it
    model.held_ball = held_ball;
    world = std::make_unique<World>(model, registry, log, false);
  }

  double Dt() const { return world->model().physics.step; }  // s, one physics step
  // Steps between two commands of a 100 Hz radio.
  long RadioSteps() const { return std::max(1L, std::lround(0.01 / Dt())); }
  // Steps in `seconds`.
  long Steps(double seconds) const { return std::lround(seconds / Dt()); }

  RobotState Robot() const { return world->GroundTruth().robots.at(0); }
  Pose BallPose() { return WorldAttorney::Ball(*world).GetPose(); }
  Twist BallTwist() { return WorldAttorney::Ball(*world).GetTwist(); }
  double BallRadius() const { return world->model().ball->radius; }
  double Front() const { return robot_model->body.front_distance; }

  // The ball's centre in the robot's horizontal frame (x forward, y left), z above the carpet.
  Vec3 BallInRobotFrame() {
    const RobotState r = Robot();
    const double yaw = r.pose.Yaw();
    const Vec3 d = BallPose().position - r.pose.position;
    return Vec3(std::cos(yaw) * d.x() + std::sin(yaw) * d.y(), -std::sin(yaw) * d.x() + std::cos(yaw) * d.y(),
                BallPose().position.z());
  }

  // Puts the ball at rest on the carpet at (x, y) in the robot's frame.
  void PlaceBall(double x, double y) {
    const RobotState r = Robot();
    const double yaw = r.pose.Yaw();
    const Vec3 p = r.pose.position + Vec3(std::cos(yaw) * x - std::sin(yaw) * y, std::sin(yaw) * x + std::cos(yaw) * y, 0);
    world->events().Post(PositionEvent{Target::Ball(), Vec3(p.x(), p.y(), BallRadius()), std::nullopt,
                                       Vec3::Zero(), Vec3::Zero(), std::nullopt});
    world->ProcessEvents();
  }
  // The ball at rest touching the flat front, on the centre line.
  void PlaceBallInMouth(double gap = 0.0) { PlaceBall(Front() + BallRadius() + gap, 0.0); }

  void Send(std::optional<MoveCommand> move, std::optional<KickCommand> kick, std::optional<double> dribble) {
    world->events().Post(CommandEvent{kRobot, std::move(move), kick, dribble});
  }
  // Runs `seconds`, sending the command parts every 10 ms (a 100 Hz radio); `each_step` is
  // called after every step.
  template <typename F>
  void Run(double seconds, std::optional<MoveCommand> move, std::optional<KickCommand> kick,
           std::optional<double> dribble, F&& each_step) {
    const long steps = Steps(seconds), radio = RadioSteps();
    for (long i = 0; i < steps; ++i) {
      if (i % radio == 0) Send(move, kick, dribble);
      world->Step();
      each_step();
    }
  }
  void Run(double seconds, std::optional<MoveCommand> move = std::nullopt,
           std::optional<KickCommand> kick = std::nullopt, std::optional<double> dribble = std::nullopt) {
    Run(seconds, move, kick, dribble, [] {});
  }
};

}  // namespace ubersim::kernel
