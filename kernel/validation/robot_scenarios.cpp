// SPDX-License-Identifier: Apache-2.0
// Robots driven through their drive plugins as a team's software drives them: commands at a
// 100 Hz radio rate, ground truth read back.
#include "robot_scenarios.hpp"

#include <cmath>

#include "scenario_world.hpp"

namespace ubersim::validation::detail {
namespace {

constexpr const char* kOmniRobot = "robots/ssl-omni-2026.yaml";

// One robot alone on a field at (-2, 0), the ball in a far corner out of the way.
kernel::WorldModel OneRobot(const Environment& env, const std::string& world, const std::string& robot_file) {
  kernel::WorldModel w = OneRobotWorld(env, world, robot_file, -2.0, 0.0, 0.0);
  const FieldGeometry& g = w.field->geometry;
  w.ball_start = Vec3(0.5 * g.field_length - 0.5, 0.5 * g.field_width - 0.3, 0);
  return w;
}

Vec3 LocalVelocity(const RobotState& r) { return r.pose.orientation.conjugate() * r.twist.linear; }

}  // namespace

ScenarioResult OmniSteadyVelocity(const Environment& env) {
  ScenarioResult r;
  r.id = "omni_steady_velocity";
  r.title = "Omni robot: steady speed follows the command";
  r.setup = "The modern four-wheel robot (models/robots/ssl-omni-2026.yaml: wheels at 60°, 135°, 225°, "
            "300°) alone on the Div B field gets a local velocity command at 100 Hz for 1.5 s; the "
            "measured velocity (ground truth, robot frame) is averaged over the next 0.5 s. Each metric "
            "is the measured over the commanded value.";
  struct Case { const char* name; double forward, left, angular; };
  for (const Case c : {Case{"forward", 1.0, 0, 0}, Case{"fast_forward", 2.5, 0, 0}, Case{"sideways", 0, 1.0, 0},
                       Case{"diagonal", 1.0, -1.0, 0}, Case{"turning", 0, 0, 4.0}}) {
    Bench bench(env, OneRobot(env, "worlds/div-b.yaml", kOmniRobot));
    const LocalVelocityCommand cmd{c.forward, c.left, c.angular};
    bench.Drive(kRobot, cmd, 1.5);
    Vec3 sum = Vec3::Zero();
    double spin = 0;
    for (int k = 0; k < 50; ++k) {
      bench.Drive(kRobot, cmd, 0.01);
      const RobotState s = bench.Robot(kRobot);
      sum += LocalVelocity(s);
      spin += s.twist.angular.z();
    }
    const Vec3 v = sum / 50;
    const std::string name = c.name;
    const char* basis = "issue: within 3 % of the command";
    if (c.angular != 0) {
      r.metrics.push_back(Band(name + "_angular_speed", spin / 50 / c.angular, "ratio", 0.97, 1.03, basis));
    } else {
      const Vec3 want(c.forward, c.left, 0);
      r.metrics.push_back(Band(name + "_speed", v.dot(want) / want.squaredNorm(), "ratio", 0.97, 1.03, basis));
      // Velocity across the commanded direction, relative to the commanded speed.
      const Vec3 across = v - want * (v.dot(want) / want.squaredNorm());
      r.metrics.push_back(Band(name + "_sideslip", across.norm() / want.norm(), "ratio", 0.0, 0.03, basis));
    }
  }
  return r;
}

ScenarioResult OmniAcceleration(const Environment& env) {
  ScenarioResult r;
  r.id = "omni_acceleration";
  r.title = "Omni robot: speed-up follows the acceleration limit";
  r.setup = "The modern four-wheel robot (limit 3 m/s², physics.md §3c) is commanded 2 m/s forward from "
            "rest; the slope of measured speed over time between 20 % and 80 % of the target is fitted.";
  Bench bench(env, OneRobot(env, "worlds/div-b.yaml", kOmniRobot));
  constexpr double kTarget = 2.0, kLimit = 3.0;
  std::vector<double> t, v, ideal;
  for (int k = 0; k < 100; ++k) {
    bench.Drive(kRobot, LocalVelocityCommand{kTarget, 0, 0}, 0.01);
    t.push_back(bench.Time());
    v.push_back(LocalVelocity(bench.Robot(kRobot)).x());
    ideal.push_back(std::min(kTarget, kLimit * t.back()));
  }
  r.metrics.push_back(Band("acceleration_vs_limit", SpeedUpSlope(t, v, kTarget) / kLimit, "ratio", 0.95, 1.05,
                           "issue: within 5 %"));
  r.metrics.push_back(Band("final_speed_vs_command", v.back() / kTarget, "ratio", 0.97, 1.03,
                           "issue: within 3 %"));
  Plot p;
  p.file = "omni-acceleration.svg";
  p.title = "Omni robot: 2 m/s commanded from rest, 3 m/s² limit";
  p.x_label = "time (s)";
  p.y_label = "forward speed (m/s)";
  p.series = {Series{"ÜberSim", t, v, false}, Series{"ideal (limit 3 m/s²)", t, ideal, true}};
  r.plots.push_back(p);
  return r;
}

}  // namespace ubersim::validation::detail
