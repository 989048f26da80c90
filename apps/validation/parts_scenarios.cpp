// SPDX-License-Identifier: Apache-2.0
// Dribbler and kicker, driven as a team's software drives them: commands at 100 Hz, the ball's
// ground truth read back.
#include "parts_scenarios.hpp"

#include <cstdio>

#include <algorithm>
#include <cmath>
#include <string>

#include "scenario_world.hpp"

namespace ubersim::validation::detail {
namespace {

constexpr double kRadioPeriod = 0.01;  // s: a 100 Hz radio

struct PartsBench {
  Bench bench;
  const kernel::RobotModel& robot;
  double ball_radius;

  explicit PartsBench(const Environment& env, kernel::WorldModel model)
      : bench(env, model), robot(*model.robots.front().model), ball_radius(model.ball->radius) {}

  // Ball in the robot's frame (x forward, y left), m.
  Vec3 BallLocal() {
    const RobotState r = bench.Robot(kRobot);
    return r.pose.orientation.conjugate() * (bench.Ball().pose.position - r.pose.position);
  }
  // True when the ball sits in the mouth: against the flat front, within the dribbler's width.
  bool Held() {
    const Vec3 b = BallLocal();
    const double front = robot.body.front_distance;
    return b.x() > front && b.x() < front + 2 * ball_radius + 0.01 && std::abs(b.y()) < 0.04;
  }
  // Sends `command` (with the dribbler at `dribbler` rad/s) every radio frame for `seconds`,
  // calling `each` after every step.
  template <typename F>
  void Drive(const MoveCommand& command, double dribbler, double seconds, F&& each) {
    const double dt = bench.world().clock().step_seconds();
    const long steps = std::lround(seconds / dt), every = std::lround(kRadioPeriod / dt);
    for (long i = 0; i < steps; ++i) {
      if (i % every == 0) bench.world().events().Post(CommandEvent{kRobot, command, {}, dribbler});
      bench.Step();
      each();
    }
  }
  // Commands a kick (armed for the radio frames it is sent in) and returns the ball's largest
  // speed in the 50 ms after: the speed it left with.
  double Kick(const KickCommand& kick, Vec3* velocity = nullptr) {
    double best = 0;
    const double dt = bench.world().clock().step_seconds();
    for (long i = 0; i < std::lround(0.05 / dt); ++i) {
      if (i % std::lround(kRadioPeriod / dt) == 0 && i < std::lround(0.02 / dt)) {
        bench.world().events().Post(CommandEvent{kRobot, LocalVelocityCommand{}, kick, 0.0});
      }
      bench.Step();
      const Vec3 v = bench.Ball().twist.linear;
      if (v.norm() > best) {
        best = v.norm();
        if (velocity) *velocity = v;
      }
    }
    return best;
  }
};

// The robot alone on the Div B field at (-2, 0) facing +x, the ball resting against its front.
kernel::WorldModel RobotWithBall(const Environment& env, const std::string& robot_file) {
  kernel::WorldModel w = OneRobotWorld(env, "worlds/div-b.yaml", robot_file, -2.0, 0.0, 0.0);
  const double front = w.robots.front().model->body.front_distance;
  w.ball_start = Vec3(-2.0 + front + w.ball->radius + 0.002, 0.0, 0.0);
  return w;
}

std::string FormatLimit(double v) {
  char text[48];
  std::snprintf(text, sizeof text, "%g m/s", v);
  return text;
}

double KickerParam(const kernel::RobotModel& r, const char* key, double fallback) {
  return r.kicker ? r.kicker->params.GetDouble(key, fallback) : fallback;
}

}  // namespace

ScenarioResult KickerSpeeds(const Environment& env, const std::string& robot_file, const std::string& id) {
  ScenarioResult r;
  r.id = id;
  r.title = "Kicker: flat kicks clamped to the rules' limit, chips at the kicker's angle" +
            (robot_file == kPartsRobot ? std::string() : " (" + robot_file + ")");
  // The robot's own flat limit (6.5 m/s, the rules' ball-speed limit, for the shipped robots),
  // commanded 3.5 m/s above it.
  const double limit = KickerParam(*RobotWithBall(env, robot_file).robots.front().model, "max_flat_speed", 6.5);
  const double commanded = limit + 3.5;
  char number[32];
  std::snprintf(number, sizeof number, "%g", commanded);
  r.setup = "The robot (models/" + robot_file + ", its kicker's flat limit " + FormatLimit(limit) +
            ") stands with the ball resting against its front. A flat kick is "
            "commanded at " + number + " m/s; the ball's speed as it leaves is the largest in the next 50 ms. Then, "
            "with the ball put back, a chip is commanded at 3 m/s: its speed and elevation as it leaves.";
  {
    PartsBench p(env, RobotWithBall(env, robot_file));
    p.Drive(LocalVelocityCommand{}, 0.0, 0.3, [] {});  // the ball settles against the front
    r.metrics.push_back(Band(std::string("flat_kick_commanded_") + number, p.Kick(KickCommand{commanded, 0.0}), "m/s",
                             limit - 0.1, limit + 0.1,
                             std::string("issue: ") + number + " m/s commanded leaves at the limit ± 0.1 m/s"));
  }
  {
    PartsBench p(env, RobotWithBall(env, robot_file));
    p.Drive(LocalVelocityCommand{}, 0.0, 0.3, [] {});
    Vec3 v = Vec3::Zero();
    const double speed = p.Kick(KickCommand{3.0, M_PI / 4}, &v);
    const double angle = std::atan2(v.z(), v.head<2>().norm()) * 180 / M_PI;
    const double configured = KickerParam(p.robot, "chip_angle_deg", 45.0);
    r.metrics.push_back(Band("chip_speed_commanded_3", speed, "m/s", 2.9, 3.1, "issue: leaves at the commanded 3 m/s"));
    r.metrics.push_back(Band("chip_angle_vs_configured", angle - configured, "°", -1.0, 1.0,
                             "issue: leaves at the configured angle"));
  }
  return r;
}

ScenarioResult DribblerHold(const Environment& env, const std::string& robot_file, const std::string& id) {
  constexpr double kDribble = 150.0;  // rad/s: full speed of the modern robot's roller
  ScenarioResult r;
  r.id = id;
  r.title = "Dribbler: holds the ball driving and turning, loses it spinning fast" +
            (robot_file == kPartsRobot ? std::string() : " (" + robot_file + ")");
  r.setup = "The modern robot" + (robot_file == kPartsRobot ? std::string() : " (models/" + robot_file + ")") +
            " with its roller dribbler at 150 rad/s and the ball against its front "
            "drives 1 m forward at 1 m/s (3 m/s² limits), stops, and turns 90° at 2 rad/s, the ball held "
            "through contact friction alone (no glue, no forces on the ball). Every step the ball must sit "
            "in the mouth: against the flat front, within 4 cm of the centre line. Then it kicks at 10 m/s "
            "while dribbling. A second run spins at 8 rad/s, where the ball must get away.";
  std::vector<double> t, gap;
  {
    PartsBench p(env, RobotWithBall(env, robot_file));
    int steps = 0, held = 0;
    double worst_offset = 0;
    const double mouth = p.robot.body.front_distance + p.ball_radius;
    auto watch = [&] {
      ++steps;
      held += p.Held() ? 1 : 0;
      const Vec3 b = p.BallLocal();
      worst_offset = std::max(worst_offset, std::hypot(b.x() - mouth, b.y()));
      t.push_back(p.bench.Time());
      gap.push_back(1000 * (b.x() - mouth));
    };
    p.Drive(LocalVelocityCommand{}, kDribble, 0.3, [] {});  // the roller draws the ball in
    const Vec3 start = p.bench.Robot(kRobot).pose.position;
    // Forward until 1 m is covered (the servo ramps at 3 m/s²), then brake.
    double travelled = 0;
    while (travelled < 1.0 && p.bench.Time() < 5) {
      p.Drive(LocalVelocityCommand{1.0, 0, 0}, kDribble, kRadioPeriod, watch);
      travelled = (p.bench.Robot(kRobot).pose.position - start).head<2>().norm();
    }
    p.Drive(LocalVelocityCommand{}, kDribble, 0.5, watch);
    const double yaw0 = p.bench.Robot(kRobot).pose.Yaw();
    double turned = 0;
    while (turned < M_PI / 2 && p.bench.Time() < 10) {
      p.Drive(LocalVelocityCommand{0, 0, 2.0}, kDribble, kRadioPeriod, watch);
      turned = std::remainder(p.bench.Robot(kRobot).pose.Yaw() - yaw0, 2 * M_PI);
      if (turned < -0.5) turned += 2 * M_PI;
    }
    p.Drive(LocalVelocityCommand{}, kDribble, 0.3, watch);
    r.metrics.push_back(Band("drive_1m_and_turn_90_held_fraction", static_cast<double>(held) / steps, "", 1.0, 1.0,
                             "issue: holds the ball through a 1 m drive and a 90° turn at 2 rad/s"));
    r.metrics.push_back(Band("largest_ball_offset_from_the_mouth", 1000 * worst_offset, "mm", 0.0, 15.0,
                             "the ball stays against the roller (within 15 mm)"));
    r.metrics.push_back(Band("kick_while_dribbling", p.Kick(KickCommand{10.0, 0.0}), "m/s", 6.4, 6.6,
                             "issue: a kick while dribbling still leaves at the clamped speed"));
  }
  {
    PartsBench p(env, RobotWithBall(env, robot_file));
    p.Drive(LocalVelocityCommand{}, kDribble, 0.3, [] {});
    bool lost = false;
    p.Drive(LocalVelocityCommand{0, 0, 8.0}, kDribble, 1.0, [&] { lost = lost || !p.Held(); });
    r.metrics.push_back(Band("fast_spin_8_rad_s_loses_the_ball", lost ? 1.0 : 0.0, "", 1.0, 1.0,
                             "issue: loses it when it turns too fast"));
  }
  Plot plot;
  plot.file = id + ".svg";
  std::replace(plot.file.begin(), plot.file.end(), '_', '-');
  plot.title = "Dribbling: the ball's distance from the roller, 1 m drive then 90° turn" +
               (robot_file == kPartsRobot ? std::string() : " (" + robot_file + ")");
  plot.x_label = "time (s)";
  plot.y_label = "ball ahead of its resting place (mm)";
  plot.series = {Series{"ÜberSim", t, gap, false}};
  r.plots.push_back(plot);
  return r;
}

}  // namespace ubersim::validation::detail
