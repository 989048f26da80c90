// SPDX-License-Identifier: Apache-2.0
// Robots driven through their drive plugins as a team's software drives them: commands at a
// 100 Hz radio rate, ground truth read back.
#include "robot_scenarios.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "scenario_world.hpp"

namespace ubersim::validation::detail {
namespace {

// One robot alone on a field at (-2, 0), the ball in a far corner out of the way.
kernel::WorldModel OneRobot(const Environment& env, const std::string& world, const std::string& robot_file) {
  kernel::WorldModel w = OneRobotWorld(env, world, robot_file, -2.0, 0.0, 0.0);
  const FieldGeometry& g = w.field->geometry;
  w.ball_start = Vec3(0.5 * g.field_length - 0.5, 0.5 * g.field_width - 0.3, 0);
  return w;
}

Vec3 LocalVelocity(const RobotState& r) { return r.pose.orientation.conjugate() * r.twist.linear; }

bool IsWheelBody(const OmniModel& m) { return m.drive == kWheelBodyOmni.drive && m.name.empty(); }
// "Omni robot" for the wheel-body robot, "Omni robot, omni_force drive" for another drive, or the
// name a team's robot was given.
std::string RobotName(const OmniModel& m) {
  if (!m.name.empty()) return m.name;
  return IsWheelBody(m) ? "Omni robot" : std::string("Omni robot, ") + m.drive + " drive";
}
// The model file and, for another drive, its name.
std::string Which(const OmniModel& m) {
  if (!m.name.empty()) return std::filesystem::path(m.file).is_absolute() ? m.file : "models/" + m.file;
  return std::string("models/") + m.file + (IsWheelBody(m) ? "" : std::string(", the ") + m.drive + " drive");
}

// The robot as the setup text names it.
std::string Subject(const OmniModel& m) {
  if (!m.subject.empty()) return m.subject;
  return "The modern four-wheel robot (" + Which(m) + ": wheels at 60°, 135°, 225°, 300°)";
}

}  // namespace

ScenarioResult OmniSteadyVelocity(const Environment& env, const OmniModel& model) {
  ScenarioResult r;
  r.id = std::string(model.drive) + "_steady_velocity";
  r.title = RobotName(model) + ": steady speed follows the command";
  r.setup = Subject(model) + " alone on the Div B field gets a local velocity command at 100 Hz for 1.5 s; the "
            "measured velocity (ground truth, robot frame) is averaged over the next 0.5 s. Each metric "
            "is the measured over the commanded value.";
  struct Case { const char* name; double forward, left, angular; };
  // Scaled to the robot's limits: 1, 2.5 m/s and 4 rad/s for the shipped robots (3 m/s, 10 rad/s).
  const double v = model.max_speed / 3.0, turn = std::min(4.0, 0.8 * model.max_angular_speed);
  bool holonomic = true;
  for (const Case c : {Case{"forward", v, 0, 0}, Case{"fast_forward", 2.5 * v, 0, 0}, Case{"sideways", 0, v, 0},
                       Case{"diagonal", v, -v, 0}, Case{"turning", 0, 0, turn}}) {
    Bench bench(env, OneRobot(env, "worlds/div-b.yaml", model.file));
    const LocalVelocityCommand cmd{c.forward, c.left, c.angular};
    bench.Drive(kRobot, cmd, 1.5);
    if (bench.world().event_counters().rejected > 0) {
      r.setup += " The drive refuses the '" + std::string(c.name) + "' command: not measured.";
      continue;
    }
    Vec3 sum = Vec3::Zero();
    double spin = 0;
    for (int k = 0; k < 50; ++k) {
      bench.Drive(kRobot, cmd, 0.01);
      const RobotState s = bench.Robot(kRobot);
      sum += LocalVelocity(s);
      spin += s.twist.angular.z();
    }
    const Vec3 measured = sum / 50;
    const std::string name = c.name;
    // A drive that does not move sideways at all (a differential drive drops the lateral part)
    // is not holonomic: said in the report, and its sideways and diagonal cases not measured.
    if (c.left != 0 && c.forward == 0 && std::abs(measured.y()) < 0.05 * std::abs(c.left)) {
      r.setup += " The robot does not move sideways at all (a non-holonomic drive): sideways and diagonal are not "
                 "measured.";
      holonomic = false;
      continue;
    }
    if (c.left != 0 && !holonomic) continue;
    const char* basis = "issue: within 3 % of the command";
    if (c.angular != 0) {
      r.metrics.push_back(Band(name + "_angular_speed", spin / 50 / c.angular, "ratio", 0.97, 1.03, basis));
    } else {
      const Vec3 want(c.forward, c.left, 0);
      r.metrics.push_back(Band(name + "_speed", measured.dot(want) / want.squaredNorm(), "ratio", 0.97, 1.03, basis));
      // Velocity across the commanded direction, relative to the commanded speed.
      const Vec3 across = measured - want * (measured.dot(want) / want.squaredNorm());
      r.metrics.push_back(Band(name + "_sideslip", across.norm() / want.norm(), "ratio", 0.0, 0.03, basis));
    }
  }
  return r;
}

ScenarioResult OmniAcceleration(const Environment& env, const OmniModel& model) {
  ScenarioResult r;
  r.id = std::string(model.drive) + "_acceleration";
  r.title = RobotName(model) + ": speed-up follows the acceleration limit";
  std::ostringstream limit;
  limit << model.max_accel;
  r.setup = (model.subject.empty() ? "The modern four-wheel robot (" +
                                         (IsWheelBody(model) ? std::string() : Which(model) + "; ") +
                                         (model.name.empty() ? std::string("limit 3 m/s², physics.md §3c)")
                                                             : "its limit " + limit.str() + " m/s²)")
                                   : model.subject + ", its limit " + limit.str() + " m/s²,") +
            " is commanded two thirds of its top speed forward from "
            "rest; the slope of measured speed over time between 20 % and 80 % of the target is fitted.";
  Bench bench(env, OneRobot(env, "worlds/div-b.yaml", model.file));
  const double kTarget = model.max_speed * 2.0 / 3.0, kLimit = model.max_accel;
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
  std::string file = model.drive;
  std::replace(file.begin(), file.end(), '_', '-');
  p.file = file + "-acceleration.svg";
  char title[96];
  std::snprintf(title, sizeof title, ": %g m/s commanded from rest, %g m/s² limit", kTarget, kLimit);
  p.title = RobotName(model) + title;
  p.x_label = "time (s)";
  p.y_label = "forward speed (m/s)";
  char ideal_name[64];
  std::snprintf(ideal_name, sizeof ideal_name, "ideal (limit %g m/s²)", kLimit);
  p.series = {Series{"ÜberSim", t, v, false}, Series{ideal_name, t, ideal, true}};
  r.plots.push_back(p);
  return r;
}

ScenarioResult MecanumGripLimit(const Environment& env) {
  ScenarioResult r;
  r.id = "mecanum_grip_limit";
  r.title = "Mecanum robot: a wheel spin-up is grip-limited at μ·g·cos 45°";
  const kernel::WorldModel world = OneRobot(env, "worlds/div-b.yaml", kMecanum.file);
  const kernel::RobotModel& robot = *world.robots.front().model;
  double mu = 0.8;  // the drive's mu_roll: the grip across the rollers
  if (robot.drive && robot.drive->params.Has("surface")) mu = robot.drive->params["surface"].GetDouble("mu_roll", mu);
  constexpr double kG = 9.81;
  const double limit = mu * kG * std::cos(M_PI / 4);
  r.setup = "The mecanum robot (" + Which(kMecanum) + ") alone on the Div B field gets wheel speeds of 100 rad/s "
            "straight ahead at once (front-left and rear-left −100, the right wheels +100; the servo loop "
            "bypassed), more than the carpet can follow: the wheels slip. Each wheel's carpet force acts across "
            "its rollers, 45° from forward, so the robot speeds up at most at μ·g·cos 45° (μ = mu_roll " +
            std::to_string(mu).substr(0, 4) + "), less the free rollers' own drag. The slope of forward speed "
            "over time is fitted over the first 0.25 s.";
  Bench bench(env, world);
  const WheelSpeedCommand spin{{-100.0, -100.0, 100.0, 100.0}};
  std::vector<double> t, v, ideal;
  for (int k = 0; k < 25; ++k) {
    bench.Drive(kRobot, spin, 0.01);
    t.push_back(bench.Time());
    v.push_back(LocalVelocity(bench.Robot(kRobot)).x());
    ideal.push_back(limit * t.back());
  }
  std::vector<double> tf(t.begin() + 2, t.end()), vf(v.begin() + 2, v.end());
  const double slope = FitLine(tf, vf).slope;
  r.metrics.push_back(Band("speed_up_vs_mu_g_cos45", slope / limit, "ratio", 0.85, 1.02,
                           "issue: grip-limited at μ·g·cos 45° (the free rollers' drag, μ 0.05, takes up to 6 %)"));
  Plot p;
  p.file = "mecanum-grip-limit.svg";
  p.title = "Mecanum robot: wheels spun up at once, speed-up limited by grip";
  p.x_label = "time (s)";
  p.y_label = "forward speed (m/s)";
  p.series = {Series{"ÜberSim", t, v, false}, Series{"μ·g·cos 45°", t, ideal, true}};
  r.plots.push_back(p);
  return r;
}

OmniModel RobotUnderTest(const kernel::RobotModel& robot, const std::filesystem::path& file) {
  OmniModel m;
  m.drive = file.stem().string();
  std::replace(m.drive.begin(), m.drive.end(), '-', '_');
  m.file = std::filesystem::absolute(file).lexically_normal().string();
  m.name = "Robot " + robot.name;
  m.subject = "The robot " + robot.name + " (" + m.file + ")";
  if (robot.drive) {
    const ParamView& p = robot.drive->params;
    if (p.Has("limits")) {
      const ParamView limits = p["limits"];
      m.max_speed = limits.GetDouble("max_speed", m.max_speed);
      m.max_accel = limits.GetDouble("max_accel", m.max_accel);
      m.max_angular_speed = limits.GetDouble("max_angular_speed", m.max_angular_speed);
    }
  }
  return m;
}

}  // namespace ubersim::validation::detail
