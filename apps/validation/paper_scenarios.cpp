// SPDX-License-Identifier: Apache-2.0
// The two experiments of the 2003 ÜberSim paper (§4): a differential robot accelerating along a
// straight line at 2 m/s², and the same robot driving a figure-8 at about 0.8 m/s under a simple
// waypoint controller. The paper plotted simulation against the real robot; with no robot here,
// each is plotted against the commanded (ideal) profile and path.
#include "paper_scenarios.hpp"

#include <algorithm>
#include <cmath>

#include "scenario_world.hpp"

namespace ubersim::validation::detail {
namespace {

constexpr const char* kDiffRobot = "robots/cmdragons-2003-diff.yaml";
kernel::WorldModel PaperWorld(const Environment& env, double x, double y, double yaw) {
  kernel::WorldModel w = OneRobotWorld(env, "worlds/ssl-2003.yaml", kDiffRobot, x, y, yaw);
  w.ball_start = Vec3(0.5 * w.field->geometry.field_length - 0.2, 0.5 * w.field->geometry.field_width - 0.2, 0);
  return w;
}

// A figure-8 of two circles of radius r touching at the origin, as a dense polyline: first the
// right circle counter-clockwise, then the left one clockwise, both leaving the origin heading -y.
std::vector<Vec3> FigureEight(double r, int points_per_circle) {
  std::vector<Vec3> path;
  for (int i = 0; i < points_per_circle; ++i) {
    const double a = M_PI + 2 * M_PI * i / points_per_circle;
    path.emplace_back(r + r * std::cos(a), r * std::sin(a), 0);
  }
  for (int i = 0; i < points_per_circle; ++i) {
    const double a = -2 * M_PI * i / points_per_circle;
    path.emplace_back(-r + r * std::cos(a), r * std::sin(a), 0);
  }
  return path;
}

// Distance from p to the closed polyline.
double DistanceToPath(const std::vector<Vec3>& path, const Vec3& p) {
  double best = 1e9;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const Vec3& a = path[i];
    const Vec3& b = path[(i + 1) % path.size()];
    const Vec3 ab = b - a;
    const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * ab - p).norm());
  }
  return best;
}

// Pure pursuit, the simplest waypoint follower: steer along the arc through a point `lookahead`
// metres further along the path than the closest point, at constant speed.
class PurePursuit {
 public:
  PurePursuit(std::vector<Vec3> path, double speed, double lookahead, double max_turn_rate)
      : path_(std::move(path)), speed_(speed), lookahead_(lookahead), max_turn_rate_(max_turn_rate) {}

  LocalVelocityCommand Command(const Pose& pose) {
    const Vec3 p(pose.position.x(), pose.position.y(), 0);
    // Closest point, searched a little ahead of the last one so the crossing does not confuse it.
    std::size_t best = index_;
    double best_d = 1e9;
    for (std::size_t k = 0; k < 40; ++k) {
      const std::size_t i = (index_ + k) % path_.size();
      const double d = (path_[i] - p).norm();
      if (d < best_d) { best_d = d; best = i; }
    }
    index_ = best;
    std::size_t target = index_;
    double along = 0;
    while (along < lookahead_) {
      const std::size_t next = (target + 1) % path_.size();
      along += (path_[next] - path_[target]).norm();
      target = next;
    }
    const Vec3 local = pose.orientation.conjugate() * (path_[target] - p);
    const double alpha = std::atan2(local.y(), local.x());
    const double curvature = 2 * std::sin(alpha) / local.head<2>().norm();
    return LocalVelocityCommand{speed_, 0, std::clamp(speed_ * curvature, -max_turn_rate_, max_turn_rate_)};
  }

 private:
  std::vector<Vec3> path_;
  double speed_, lookahead_, max_turn_rate_;
  std::size_t index_ = 0;
};

}  // namespace

ScenarioResult PaperAcceleration(const Environment& env) {
  constexpr double kTarget = 1.6, kLimit = 2.0;  // m/s, m/s²: the paper's test rate
  ScenarioResult r;
  r.id = "paper_acceleration";
  r.title = "2003 paper: straight-line acceleration of the differential robot at 2 m/s²";
  r.setup = "The paper's CMDragons-2003 differential robot (models/robots/cmdragons-2003-diff.yaml, "
            "acceleration limit 2 m/s²) on the 2003 field is commanded 1.6 m/s straight ahead from rest at "
            "a 100 Hz radio rate, then 0 after 1.5 s. The paper plotted speed against time for five runs "
            "of the real robot and the simulator; ÜberSim is deterministic, so one run stands for five, "
            "and it is plotted against the commanded profile (a 2 m/s² ramp to 1.6 m/s, then the "
            "robot's braking limit).";
  Bench bench(env, PaperWorld(env, -1.0, 0.0, 0.0));
  std::vector<double> t, v, ideal;
  for (int k = 0; k < 250; ++k) {
    const bool go = k < 150;
    bench.Drive(kRobot, LocalVelocityCommand{go ? kTarget : 0.0, 0, 0}, 0.01);
    const RobotState s = bench.Robot(kRobot);
    t.push_back(bench.Time());
    v.push_back((s.pose.orientation.conjugate() * s.twist.linear).x());
    ideal.push_back(std::min(kTarget, kLimit * t.back()));
  }
  const double brake = bench.world().model().robots.front().model->drive->params["limits"].GetDouble("max_brake", 4.0);
  // Braking starts when the stop command was sent: 1.5 s at the shipped step; a step that does
  // not divide the 10 ms radio period makes each command period a little shorter or longer.
  const double stop = t[149];
  for (std::size_t i = 150; i < t.size(); ++i) ideal[i] = std::max(0.0, kTarget - brake * (t[i] - stop));
  double sq = 0;
  for (std::size_t i = 0; i < t.size(); ++i) sq += (v[i] - ideal[i]) * (v[i] - ideal[i]);
  r.metrics.push_back(Band("acceleration_vs_2_m_s2", SpeedUpSlope(t, v, kTarget, 150) / kLimit, "ratio", 0.95, 1.05,
                           "issue: within 5 % of the limit"));
  r.metrics.push_back(Band("speed_at_1_5_s_vs_command", v[149] / kTarget, "ratio", 0.97, 1.03, "issue: within 3 %"));
  r.metrics.push_back(Band("rms_deviation_from_profile", std::sqrt(sq / static_cast<double>(t.size())), "m/s", 0.0,
                           0.05, "the servo follows its profile to within 3 % of the top speed"));
  Plot p;
  p.file = "paper-acceleration.svg";
  p.title = "Differential robot: 1.6 m/s commanded, 2 m/s² limit (paper §4)";
  p.x_label = "time (s)";
  p.y_label = "forward speed (m/s)";
  p.series = {Series{"ÜberSim", t, v, false}, Series{"commanded profile", t, ideal, true}};
  r.plots.push_back(p);
  return r;
}

ScenarioResult PaperFigureEight(const Environment& env) {
  constexpr double kRadius = 0.5, kSpeed = 0.8;  // m, m/s
  ScenarioResult r;
  r.id = "paper_figure_eight";
  r.title = "2003 paper: figure-8 at 0.8 m/s with a waypoint controller";
  r.setup = "The differential robot drives two laps of a figure-8 (two 0.5 m circles touching at the "
            "field centre) at 0.8 m/s. The controller is the simplest waypoint follower a team would "
            "write, pure pursuit with a 0.2 m look-ahead: it sends (v, ω) at 100 Hz from the robot's "
            "true pose, as the paper's did from vision. The path driven is plotted over the ideal one; "
            "the numbers are the distance from the ideal path and the speed held.";
  Bench bench(env, PaperWorld(env, 0.0, 0.0, -M_PI / 2));
  const std::vector<Vec3> path = FigureEight(kRadius, 400);
  PurePursuit controller(path, kSpeed, 0.2, 6.0);
  const double lap = 2 * (2 * M_PI * kRadius) / kSpeed;
  std::vector<double> xs, ys, errors;
  double distance = 0;
  Vec3 last = bench.Robot(kRobot).pose.position;
  last.z() = 0;
  while (bench.Time() < 2 * lap) {
    const RobotState s = bench.Robot(kRobot);
    bench.Drive(kRobot, controller.Command(s.pose), 0.01);
    const Vec3 p = bench.Robot(kRobot).pose.position;
    const Vec3 now(p.x(), p.y(), 0.0);  // on the carpet: the path has no height
    if (bench.Time() > 1.0) {  // after the start-up ramp
      errors.push_back(DistanceToPath(path, now));
      distance += (now - last).head<2>().norm();
    }
    last = now;
    xs.push_back(now.x());
    ys.push_back(now.y());
  }
  double sq = 0, worst = 0;
  for (double e : errors) {
    sq += e * e;
    worst = std::max(worst, e);
  }
  r.metrics.push_back(Band("mean_speed_vs_0_8", distance / (2 * lap - 1.0) / kSpeed, "ratio", 0.95, 1.05,
                           "issue: about 0.8 m/s"));
  r.metrics.push_back(Band("rms_distance_from_path", std::sqrt(sq / static_cast<double>(errors.size())), "m", 0.0,
                           0.02, "tracks within a ball's width"));
  r.metrics.push_back(Band("largest_distance_from_path", worst, "m", 0.0, 0.045, "within a quarter of the robot's diameter"));
  Plot p;
  p.file = "paper-figure-eight.svg";
  p.title = "Differential robot: figure-8 at 0.8 m/s (paper §4)";
  p.x_label = "x (m)";
  p.y_label = "y (m)";
  p.equal_axes = true;
  Series ideal{"ideal path", {}, {}, true};
  for (std::size_t i = 0; i <= path.size(); ++i) {
    ideal.x.push_back(path[i % path.size()].x());
    ideal.y.push_back(path[i % path.size()].y());
  }
  p.series = {Series{"ÜberSim, two laps", xs, ys, false}, ideal};
  r.plots.push_back(p);
  return r;
}

}  // namespace ubersim::validation::detail
