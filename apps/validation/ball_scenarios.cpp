// SPDX-License-Identifier: Apache-2.0
// The ball: a straight roll that slides then rolls, a chip's flight and bounces, and shots at
// 6.5 m/s against robots and walls that must never pass through.
#include <algorithm>
#include <cmath>
#include <random>

#include "ball_scenarios.hpp"
#include "scenario_world.hpp"

namespace ubersim::validation::detail {
namespace {

constexpr const char* kBallBand = "physics.md §2a acceptance band";

// Speed of the two-phase model (physics.md §2a) at time t.
double TwoPhaseSpeed(double v0, double slide, double roll, double k, double t) {
  const double t_switch = (1 - k) * v0 / slide;
  if (t < t_switch) return v0 - slide * t;
  return std::max(0.0, k * v0 - roll * (t - t_switch));
}

// Stopping distance of the two-phase model.
double TwoPhaseDistance(double v0, double slide, double roll, double k) {
  const double vs = k * v0;
  return (v0 * v0 - vs * vs) / (2 * slide) + vs * vs / (2 * roll);
}

// A ball-only world on the shipped Div B carpet and ball, with the walls moved `half_length` m
// away so a long roll is not stopped.
kernel::WorldModel OpenCarpet(const Environment& env, double half_length) {
  kernel::WorldModel w = LoadWorld(env, "worlds/div-b.yaml");
  w.robots.clear();
  auto field = std::make_shared<kernel::FieldModel>(*w.field);
  field->geometry.carpet_length = 2 * half_length;
  field->geometry.carpet_width = std::max(field->geometry.carpet_width, 12.0);
  w.field = field;
  return w;
}

}  // namespace

ScenarioResult BallRoll(const Environment& env, double v0) {
  const std::string v_text = std::to_string(static_cast<int>(v0));
  ScenarioResult r;
  r.id = "ball_roll_" + v_text;
  r.title = "Ball rolled at " + v_text + " m/s: slides, then rolls";
  r.setup = "The golf ball (models/balls/golf.yaml) on the Div B carpet (models/worlds/div-b.yaml materials, "
            "walls moved out of the way) is set moving at " + v_text + " m/s without spin. The sliding and "
            "rolling decelerations are straight-line fits of speed over time in each phase; the switch is "
            "where the contact point stops slipping (slip below 1 % of v0). The dashed curves are the "
            "two-phase model (physics.md §2a) with the ssl-vision defaults and the ER-Force parameters.";
  Bench bench(env, OpenCarpet(env, 30.0));
  const double rb = bench.world().model().ball->radius;
  const Vec3 start(-25.0, 2.0, rb);
  PositionEvent shot{Target::Ball(), start, {}, Vec3(v0, 0, 0), Vec3::Zero(), {}};
  bench.Apply(shot);

  std::vector<double> t, v, slip;
  double x_end = start.x();
  while (bench.Time() < 30.0) {
    bench.Step();
    const BallState b = bench.Ball();
    const Vec3 contact_velocity = b.twist.linear + b.twist.angular.cross(Vec3(0, 0, -rb));
    t.push_back(bench.Time());
    v.push_back(std::hypot(b.twist.linear.x(), b.twist.linear.y()));
    slip.push_back(std::hypot(contact_velocity.x(), contact_velocity.y()));
    x_end = b.pose.position.x();
    if (v.back() < 1e-3) break;
  }
  std::size_t k_switch = 0;
  while (k_switch < slip.size() && slip[k_switch] > 0.01 * v0) ++k_switch;
  const double t_switch = k_switch < t.size() ? t[k_switch] : t.back();
  std::vector<double> ts, vs, tr, vr;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] > 0.01 && t[i] < t_switch - 0.01) { ts.push_back(t[i]); vs.push_back(v[i]); }
    if (t[i] > t_switch + 0.1 && v[i] > 0.1) { tr.push_back(t[i]); vr.push_back(v[i]); }
  }
  const double slide = -FitLine(ts, vs).slope;
  const double roll = -FitLine(tr, vr).slope;
  const double ratio = k_switch < v.size() ? v[k_switch] / v0 : 0.0;
  const double distance = x_end - start.x();
  r.metrics.push_back(Band("sliding_deceleration", slide, "m/s²", 3.0, 4.0, kBallBand));
  r.metrics.push_back(Band("rolling_deceleration", roll, "m/s²", 0.25, 0.5, kBallBand));
  r.metrics.push_back(Band("switch_ratio", ratio, "v/v0", 0.64, 0.72, kBallBand));
  // Stopping distance of the published parameter sets (ssl-vision, ER-Force, TIGERs) for this v0.
  const double lo = std::min({TwoPhaseDistance(v0, 3.0, 0.4, 0.7), TwoPhaseDistance(v0, 3.9, 0.35, 0.69),
                              TwoPhaseDistance(v0, 3.0, 0.26, 0.64)});
  const double hi = std::max({TwoPhaseDistance(v0, 3.0, 0.4, 0.7), TwoPhaseDistance(v0, 3.9, 0.35, 0.69),
                              TwoPhaseDistance(v0, 3.0, 0.26, 0.64)});
  r.metrics.push_back(Band("stopping_distance", distance, "m", lo, hi,
                           "physics.md §2a parameter sets (ssl-vision, ER-Force, TIGERs)"));
  r.metrics.push_back(Band("stopping_distance_vs_fitted_model", distance / TwoPhaseDistance(v0, slide, roll, ratio),
                           "ratio", 0.97, 1.03, "two-phase model with the fitted numbers"));

  Plot p;
  p.file = "ball-roll-" + v_text + ".svg";
  p.title = "Ball speed, rolled at " + v_text + " m/s without spin";
  p.x_label = "time (s)";
  p.y_label = "speed (m/s)";
  Series sim{"ÜberSim", {}, {}, false}, vision{"ssl-vision defaults", {}, {}, true},
      erforce{"ER-Force parameters", {}, {}, true};
  for (std::size_t i = 0; i < t.size(); i += 10) {
    sim.x.push_back(t[i]);
    sim.y.push_back(v[i]);
    vision.x.push_back(t[i]);
    vision.y.push_back(TwoPhaseSpeed(v0, 3.0, 0.4, 0.7, t[i]));
    erforce.x.push_back(t[i]);
    erforce.y.push_back(TwoPhaseSpeed(v0, 3.9, 0.35, 0.69, t[i]));
  }
  p.series = {sim, vision, erforce};
  r.plots.push_back(p);
  return r;
}

ScenarioResult ChipFlight(const Environment& env) {
  constexpr double kSpeed = 4.0, kAngle = M_PI / 4;  // TIGERs' chip angle (physics.md §2b)
  ScenarioResult r;
  r.id = "chip_flight";
  r.title = "Chipped ball: flight and bounces";
  r.setup = "The ball leaves the carpet at 4 m/s, 45° up (TIGERs' chip angle), without spin: the state a "
            "chip kicker gives it. Apex and first landing are compared with the ballistic values (no air "
            "drag, as in the league's models); each bounce's damping is the ratio of the speeds just after "
            "and just before the bounce, horizontal (xy) and vertical (z), compared with the published "
            "ranges of the fixed-loss chip model (physics.md §2b: ssl-vision, ER-Force, TIGERs, grSim).";
  Bench bench(env, OpenCarpet(env, 30.0));
  const double rb = bench.world().model().ball->radius;
  const double g = -bench.world().model().physics.gravity.z();
  const Vec3 start(-5.0, 2.0, rb);
  bench.Apply(PositionEvent{Target::Ball(), start, {}, Vec3(kSpeed * std::cos(kAngle), 0, kSpeed * std::sin(kAngle)),
                            Vec3::Zero(), {}});
  constexpr double kTouch = 1e-3;  // m above resting height: closer counts as touching the carpet
  double apex = 0, first_landing = -1;
  std::vector<double> xs, zs;
  struct Hop { Vec3 before, after; };
  std::vector<Hop> hops;
  Vec3 last_free = Vec3(kSpeed * std::cos(kAngle), 0, kSpeed * std::sin(kAngle));
  bool touching = false, left_ground = false;
  while (bench.Time() < 4.0 && hops.size() < 5) {
    bench.Step();
    const BallState b = bench.Ball();
    const double h = b.pose.position.z() - rb;
    xs.push_back(b.pose.position.x() - start.x());
    zs.push_back(h);
    apex = std::max(apex, h);
    if (h > kTouch) {
      if (touching && left_ground) hops.back().after = b.twist.linear;
      if (touching && hops.size() && hops.back().after.z() < 0.3) break;  // too low to count as a hop
      touching = false;
      left_ground = true;
      last_free = b.twist.linear;
    } else if (!touching && left_ground) {
      touching = true;
      if (first_landing < 0) first_landing = b.pose.position.x() - start.x();
      hops.push_back(Hop{last_free, Vec3::Zero()});
    }
  }
  const double vz = kSpeed * std::sin(kAngle);
  const double ideal_apex = vz * vz / (2 * g);
  const double ideal_landing = kSpeed * kSpeed * std::sin(2 * kAngle) / g;
  r.metrics.push_back(Band("apex_height_vs_ballistic", apex / ideal_apex, "ratio", 0.95, 1.05, "issue: within 5 %"));
  r.metrics.push_back(Band("first_landing_vs_ballistic", first_landing / ideal_landing, "ratio", 0.95, 1.05,
                           "issue: within 5 %"));
  const std::string sources = "physics.md §2b (ssl-vision, ER-Force, TIGERs, grSim)";
  for (std::size_t i = 0; i < hops.size(); ++i) {
    const Hop& hop = hops[i];
    if (hop.after.z() <= 0) continue;  // the last one never left the ground
    const double xy = std::hypot(hop.after.x(), hop.after.y()) / std::hypot(hop.before.x(), hop.before.y());
    const double z = -hop.after.z() / hop.before.z();
    const std::string n = std::to_string(i + 1);
    if (i == 0) {
      r.metrics.push_back(Band("bounce1_damping_xy", xy, "ratio", 0.6, 0.8, sources + ", first hop"));
    } else {
      r.metrics.push_back(Band("bounce" + n + "_damping_xy", xy, "ratio", 0.85, 1.0, sources + ", later hops"));
    }
    r.metrics.push_back(Band("bounce" + n + "_damping_z", z, "ratio", 0.42, 0.7, sources));
  }
  Plot p;
  p.file = "chip-flight.svg";
  p.title = "Chip at 4 m/s, 45°: height over distance";
  p.x_label = "distance (m)";
  p.y_label = "height of the ball's bottom (m)";
  Series sim{"ÜberSim", {}, {}, false}, ideal{"ballistic first flight", {}, {}, true};
  for (std::size_t i = 0; i < xs.size(); i += 5) {
    sim.x.push_back(xs[i]);
    sim.y.push_back(zs[i]);
  }
  for (int i = 0; i <= 100; ++i) {
    const double x = ideal_landing * i / 100.0, tt = x / (kSpeed * std::cos(kAngle));
    ideal.x.push_back(x);
    ideal.y.push_back(vz * tt - 0.5 * g * tt * tt);
  }
  p.series = {sim, ideal};
  r.plots.push_back(p);
  return r;
}

ScenarioResult NoTunnelling(const Environment& env, int shots, double physics_step) {
  constexpr double kShotSpeed = 6.5;  // m/s, the rules' limit
  ScenarioResult r;
  r.id = "no_tunnelling";
  r.title = "Shots at 6.5 m/s never pass through robots or walls";
  r.setup = std::to_string(shots) + " shots at 6.5 m/s on the Div B world with its 12 robots "
            "(models/worlds/div-b.yaml, its physics step), half aimed at a random robot from 0.25–1 m in a "
            "random direction, half at a random point of the perimeter wall from 0.3–1.5 m; seeded, so every run shoots "
            "the same. Each shot runs 0.35 s (2.3 m of flight); every step the ball's centre is checked against every robot's "
            "outline (the circle cut flat at its front) and against the walls' inner faces and the carpet: "
            "a centre inside counts as a shot gone through. The deepest penetrations show how far one step "
            "of flight (6.5 mm at 1 ms) lets the ball sink in before the contact pushes it back. Robots are "
            "put back between shots.";
  kernel::WorldModel model = LoadWorld(env, "worlds/div-b.yaml");
  if (physics_step > 0) model.physics.step = physics_step;
  Bench bench(env, model);
  const double rb = model.ball->radius;
  const double X = 0.5 * model.field->geometry.carpet_length, Y = 0.5 * model.field->geometry.carpet_width;
  std::mt19937_64 rng(20261122);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int through_robot = 0, through_wall = 0, under_carpet = 0;
  double deepest = 0, deepest_wall = 0, deepest_carpet = 0;  // m, ball into a robot, wall, carpet
  auto robot_gap = [&](const kernel::RobotPlacement& p, const RobotState& s, const Vec3& ball) {
    // Signed distance of the ball centre from the robot's outline (circle ∩ half-plane), m.
    const Vec3 local = s.pose.orientation.conjugate() * (ball - s.pose.position);
    return std::max(std::hypot(local.x(), local.y()) - p.model->body.radius,
                    local.x() - p.model->body.front_distance);
  };
  auto inside_other_robot = [&](const Vec3& p) {
    for (const auto& placement : model.robots) {
      if (std::hypot(p.x() - placement.x, p.y() - placement.y) < placement.model->body.radius + rb + 0.01) return true;
    }
    return false;
  };
  for (int shot = 0; shot < shots; ++shot) {
    for (const auto& p : model.robots) {
      bench.Apply(PositionEvent{Target::Robot(p.id), Vec3(p.x, p.y, 0), p.yaw, Vec3::Zero(), Vec3::Zero(), {}});
    }
    Vec3 from, to;
    do {
      if (shot % 2 == 0) {
        const auto& target = model.robots[static_cast<std::size_t>(unit(rng) * static_cast<double>(model.robots.size())) %
                                          model.robots.size()];
        const double a = 2 * M_PI * unit(rng), d = 0.25 + 0.75 * unit(rng);
        to = Vec3(target.x, target.y, rb) + Vec3(-std::sin(a), std::cos(a), 0) * (0.16 * (unit(rng) - 0.5));
        from = Vec3(target.x + d * std::cos(a), target.y + d * std::sin(a), rb);
      } else {
        // A point on a random wall, shot at from 0.3–1.5 m inside, up to 60° off the wall's normal.
        const int side = static_cast<int>(unit(rng) * 4) % 4;
        const double s = 2 * unit(rng) - 1;
        const Vec3 inward = side == 0 ? Vec3(-1, 0, 0) : side == 1 ? Vec3(1, 0, 0) : side == 2 ? Vec3(0, -1, 0) : Vec3(0, 1, 0);
        to = side == 0 ? Vec3(X, s * Y, rb) : side == 1 ? Vec3(-X, s * Y, rb) : side == 2 ? Vec3(s * X, Y, rb) : Vec3(s * X, -Y, rb);
        const double a = (2 * unit(rng) - 1) * M_PI / 3, d = 0.3 + 1.2 * unit(rng);
        from = to + d * (std::cos(a) * inward + std::sin(a) * Vec3(-inward.y(), inward.x(), 0));
      }
    } while (inside_other_robot(from) || std::abs(from.x()) > X - rb || std::abs(from.y()) > Y - rb);
    const Vec3 dir = (to - from).normalized();
    bench.Apply(PositionEvent{Target::Ball(), from, {}, kShotSpeed * dir, Vec3::Zero(), {}});
    bool robot_hit = false, wall_hit = false, carpet_hit = false;
    const long steps = std::lround(0.35 / bench.world().clock().step_seconds());  // 2.3 m of flight
    for (long step = 0; step < steps; ++step) {
      bench.Step();
      const Vec3 ball = bench.Ball().pose.position;
      const WorldSnapshot snap = bench.world().GroundTruth();
      for (const RobotState& s : snap.robots) {
        if (ball.z() > s.height) continue;  // flying over it
        const auto placement = std::find_if(model.robots.begin(), model.robots.end(),
                                            [&](const kernel::RobotPlacement& p) { return p.id == s.id; });
        const double gap = robot_gap(*placement, s, ball);
        deepest = std::max(deepest, rb - gap);
        robot_hit = robot_hit || gap < 0;
      }
      // The centre past a wall's inner face, or below the carpet, is a ball gone through it.
      const double wall_gap = std::min(X - std::abs(ball.x()), Y - std::abs(ball.y()));
      deepest_wall = std::max(deepest_wall, rb - wall_gap);
      wall_hit = wall_hit || wall_gap < 0;
      deepest_carpet = std::max(deepest_carpet, rb - ball.z());
      carpet_hit = carpet_hit || ball.z() < 0;
    }
    through_robot += robot_hit;
    through_wall += wall_hit;
    under_carpet += carpet_hit;
  }
  r.metrics.push_back(Band("shots", shots, "", shots, shots, "issue: 1000 random shots"));
  r.metrics.push_back(Band("shots_through_a_robot", through_robot, "", 0, 0, "issue: never pass through"));
  r.metrics.push_back(Band("shots_through_a_wall", through_wall, "", 0, 0, "issue: never pass through"));
  r.metrics.push_back(Band("shots_under_the_carpet", under_carpet, "", 0, 0, "issue: never pass through"));
  const std::string centre = "less than the ball's radius: the centre never enters it";
  r.metrics.push_back(Band("deepest_penetration_into_a_robot", 1000 * deepest, "mm", 0, 1000 * rb, centre));
  r.metrics.push_back(Band("deepest_penetration_into_a_wall", 1000 * deepest_wall, "mm", 0, 1000 * rb, centre));
  r.metrics.push_back(Band("deepest_penetration_into_the_carpet", 1000 * deepest_carpet, "mm", 0, 1000 * rb, centre));
  return r;
}

}  // namespace ubersim::validation::detail
