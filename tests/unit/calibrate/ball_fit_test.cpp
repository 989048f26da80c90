// SPDX-License-Identifier: Apache-2.0
// The ball fit against synthetic logs made from known parameters far from the defaults: kicks from
// a robot that stays by the ball, walls that turn the ball back, two cameras with their own rates
// and phases, noise, drop-outs and a few stray detections; chips seen through a camera 6 m up.
#include "ball_fit.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <vector>

namespace ubersim::calibrate {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr double kG = 9.81;
constexpr double kHalfLength = 4.5, kHalfWidth = 3.0;  // m, the walls

// The parameters the synthetic ball obeys.
struct Truth {
  double acc_slide = -2.4, acc_roll = -0.55, k_switch = 0.66;
  double damping_z = 0.5, damping_first = 0.7, damping_other = 0.9;
  double min_hop_height = 0.01;
};

// The two-phase law along a line, written here again so the test does not trust the code it tests.
double Along(double tau, double u, double slide, const Truth& law) {
  if (tau <= slide) return u * tau + 0.5 * law.acc_slide * tau * tau;
  const double vs = u + law.acc_slide * slide;
  const double rolled = std::min(tau - slide, vs / -law.acc_roll);
  return u * slide + 0.5 * law.acc_slide * slide * slide + vs * rolled + 0.5 * law.acc_roll * rolled * rolled;
}

double SpeedAt(double tau, double u, double slide, const Truth& law) {
  if (tau <= slide) return u + law.acc_slide * tau;
  return std::max(0.0, u + law.acc_slide * slide + law.acc_roll * (tau - slide));
}

// A piece of the ball's true motion: on the carpet (the two-phase law) or in flight.
struct Piece {
  double t0 = 0, t1 = 0;
  Vector2d p0 = Vector2d::Zero(), dir = Vector2d::UnitX();
  double u = 0, slide = 0;  // carpet: speed at t0, slide time
  Vector2d vh = Vector2d::Zero();
  double vz = 0;            // flight
  bool flight = false;
};

// One kick or chip: the robot by the ball, the ball at rest, the kick, its motion, rest again.
struct Episode {
  double t_begin = 0, t_end = 0;
  Vector2d robot = Vector2d::Zero();
  bool hidden_at_robot = false;  // the cameras lose the ball while it touches the robot
  std::vector<Piece> pieces;
};

struct Camera {
  int id = 0;
  double rate = 60, phase = 0, x_min = -10, x_max = 10;
  Vector3d position = Vector3d(0, 0, 6);
};

bool Inside(const Vector2d& p) { return std::abs(p.x()) < kHalfLength && std::abs(p.y()) < kHalfWidth; }

// The time a carpet piece leaves the field, or +inf when it stops inside.
double WallTime(const Piece& piece, const Truth& law) {
  const double stop = piece.slide + SpeedAt(piece.slide, piece.u, piece.slide, law) / -law.acc_roll;
  auto at = [&](double tau) { return piece.p0 + piece.dir * Along(tau, piece.u, piece.slide, law); };
  for (double tau = 0.002; tau < stop; tau += 0.002) {
    if (Inside(at(tau))) continue;
    double lo = tau - 0.002, hi = tau;
    for (int k = 0; k < 40; ++k) (Inside(at(0.5 * (lo + hi))) ? lo : hi) = 0.5 * (lo + hi);
    return piece.t0 + lo;
  }
  return std::numeric_limits<double>::infinity();
}

// Carpet motion from (t, p) at speed u along dir, sliding for `slide`, bouncing off up to two walls.
double Roll(Episode& e, double t, Vector2d p, Vector2d dir, double u, double slide, const Truth& law,
            std::mt19937& rng) {
  for (int bounce = 0;; ++bounce) {
    Piece piece;
    piece.t0 = t;
    piece.p0 = p;
    piece.dir = dir;
    piece.u = u;
    piece.slide = std::min(slide, u / -law.acc_slide);
    const double stop = t + piece.slide + SpeedAt(piece.slide, u, piece.slide, law) / -law.acc_roll;
    const double wall = WallTime(piece, law);
    piece.t1 = std::min(stop, wall);
    e.pieces.push_back(piece);
    if (wall >= stop || bounce == 2) return piece.t1;
    // Off the wall: the normal speed turned back and lost, the ball sliding again for a while.
    const double tau = wall - t;
    const Vector2d v = dir * SpeedAt(tau, u, piece.slide, law);
    p += dir * Along(tau, u, piece.slide, law);
    Vector2d after = v;
    if (std::abs(p.x()) >= kHalfLength - 1e-6) after.x() = -0.6 * v.x();
    if (std::abs(p.y()) >= kHalfWidth - 1e-6) after.y() = -0.6 * v.y();
    after.y() *= std::abs(p.x()) >= kHalfLength - 1e-6 ? 0.9 : 1.0;
    t = wall;
    u = after.norm();
    if (u < 0.2) return t;
    dir = after / u;
    slide = std::uniform_real_distribution<double>(0.05, 0.25)(rng);
  }
}

// A chip's flights, then its roll on the carpet from the last landing.
double Chip(Episode& e, double t, Vector2d p, Vector2d vh, double vz, const Truth& law, std::mt19937& rng) {
  const double vz_min = std::sqrt(2 * kG * law.min_hop_height);
  for (int hop = 0;; ++hop) {
    Piece flight;
    flight.flight = true;
    flight.t0 = t;
    flight.p0 = p;
    flight.vh = vh;
    flight.vz = vz;
    flight.t1 = t + 2 * vz / kG;
    e.pieces.push_back(flight);
    p += vh * (flight.t1 - t);
    t = flight.t1;
    vz *= law.damping_z;
    vh *= hop == 0 ? law.damping_first : law.damping_other;
    if (vz < vz_min) break;
  }
  const double u = vh.norm();
  return Roll(e, t, p, vh / u, u, u * (1 - law.k_switch) / -law.acc_slide, law, rng);
}

// The ball's position and height at t, or nothing between episodes.
std::optional<Vector3d> BallAt(const Episode& e, double t, const Truth& law) {
  if (t < e.t_begin || t > e.t_end) return std::nullopt;
  const Piece* last = nullptr;
  for (const Piece& piece : e.pieces) {
    if (t < piece.t0) break;
    last = &piece;
  }
  if (!last) {
    const Vector2d p = e.pieces.front().p0;
    return Vector3d(p.x(), p.y(), 0);
  }
  const double tau = std::min(t, last->t1) - last->t0;
  if (last->flight) {
    const Vector2d p = last->p0 + last->vh * tau;
    return Vector3d(p.x(), p.y(), std::max(0.0, last->vz * tau - 0.5 * kG * tau * tau));
  }
  const Vector2d p = last->p0 + last->dir * Along(tau, last->u, last->slide, law);
  return Vector3d(p.x(), p.y(), 0);
}

// The episode going on at t, if any (episodes are in time order).
const Episode* EpisodeAt(const std::vector<Episode>& episodes, double t) {
  const auto after = std::upper_bound(episodes.begin(), episodes.end(), t,
                                      [](double v, const Episode& e) { return v < e.t_begin; });
  if (after == episodes.begin()) return nullptr;
  const Episode& e = *(after - 1);
  return t <= e.t_end ? &e : nullptr;
}

// A synthetic log: episodes one after another, seen by the cameras.
struct Log {
  Truth truth;
  std::vector<Episode> episodes;
  std::vector<Camera> cameras;
  double noise = 0.0025, dropout = 0.08;
  int strays = 6;
  std::uint32_t seed = 1;

  BallFitInput Input() const;
};

BallFitInput Log::Input() const {
  std::mt19937 rng(seed * 7919u + 17u);
  std::normal_distribution<double> gauss(0, noise);
  std::uniform_real_distribution<double> unit(0, 1);
  BallFitInput input;
  input.source = "synthetic";
  const double t_end = episodes.empty() ? 0 : episodes.back().t_end;
  for (const Camera& cam : cameras) {
    input.cameras[cam.id] = cam.position;
    for (double t = cam.phase; t < t_end; t += 1 / cam.rate) {
      const Episode* e = EpisodeAt(episodes, t);
      const auto ball = e ? BallAt(*e, t, truth) : std::nullopt;
      if (!ball || (e->hidden_at_robot && (ball->head<2>() - e->robot).norm() < 0.13)) continue;
      // The camera reports the carpet point on its ray through the ball.
      const double h = std::min(ball->z(), 0.9 * cam.position.z());
      const Vector2d seen = cam.position.head<2>() + (ball->head<2>() - cam.position.head<2>()) *
                                                          (cam.position.z() / (cam.position.z() - h));
      if (seen.x() < cam.x_min || seen.x() > cam.x_max || unit(rng) < dropout) continue;
      input.ball.push_back({t, seen.x() + gauss(rng), seen.y() + gauss(rng), 0, cam.id});
    }
  }
  std::stable_sort(input.ball.begin(), input.ball.end(),
                   [](const TrackPoint& a, const TrackPoint& b) { return a.t < b.t; });
  for (int k = 0; k < strays && !input.ball.empty(); ++k) {
    TrackPoint& p = input.ball[rng() % input.ball.size()];
    const double angle = 2 * M_PI * unit(rng), distance = 0.15 + 0.35 * unit(rng);
    p.x += distance * std::cos(angle);
    p.y += distance * std::sin(angle);
  }
  input.robot_distance = [eps = episodes](double t, double x, double y) {
    const Episode* e = EpisodeAt(eps, t);
    return e ? (Vector2d(x, y) - e->robot).norm() : std::numeric_limits<double>::infinity();
  };
  return input;
}

std::vector<Camera> TwoCameras() {
  return {{0, 62.5, 0.003, -10, 0.3, Vector3d(-2.25, 0, 6)}, {1, 73.0, 0.011, -0.3, 10, Vector3d(2.25, 0, 6)}};
}

std::vector<Camera> OneCamera() { return {{0, 70.0, 0.004, -10, 10, Vector3d(0, 0, 6)}}; }

// A kick (or chip) episode starting at t from a random spot, the ball resting 0.5 s by the robot
// (a quarter of them hidden by it there, unless `always_hidden`).
Episode Kick(double t, bool chip, std::mt19937& rng, const Truth& truth, bool always_hidden = false) {
  std::uniform_real_distribution<double> unit(0, 1);
  Episode e;
  e.t_begin = t;
  // Each draw its own statement: the order of a call's arguments is the compiler's choice, and the
  // log must be the same whichever compiler built the test.
  const double from_x = -3.5 + 7 * unit(rng);
  const double from_y = -2.2 + 4.4 * unit(rng);
  const Vector2d from(from_x, from_y);
  // Chips go towards the middle so that their flights stay on the field.
  const double to_middle = std::atan2(-from.y(), -from.x());
  const double angle = chip ? to_middle + 0.5 * (unit(rng) - 0.5) : 2 * M_PI * unit(rng);
  const Vector2d dir(std::cos(angle), std::sin(angle));
  e.robot = from - 0.1 * dir;
  e.hidden_at_robot = unit(rng) < 0.25 || always_hidden;
  const double t_kick = t + 0.5;
  Piece rest;
  rest.t0 = t;
  rest.t1 = t_kick;
  rest.p0 = from;
  rest.dir = dir;
  e.pieces.push_back(rest);
  double stopped = 0;
  if (chip) {
    const double speed = 1.5 + 1.5 * unit(rng);
    const double vz = 2.2 + 1.5 * unit(rng);
    stopped = Chip(e, t_kick, from, dir * speed, vz, truth, rng);
  } else {
    const double v = 2 + 3.5 * unit(rng);
    stopped = Roll(e, t_kick, from, dir, v, v * (1 - truth.k_switch) / -truth.acc_slide, truth, rng);
  }
  e.t_end = stopped + 0.3;
  return e;
}

Log MakeLog(int kicks, int chips, std::uint32_t seed, std::vector<Camera> cameras = TwoCameras(),
            bool always_hidden = false) {
  Log log;
  log.seed = seed;
  log.cameras = std::move(cameras);
  std::mt19937 rng(seed);
  double t = 0.2;
  for (int k = 0; k < kicks + chips; ++k) {
    log.episodes.push_back(Kick(t, k % 3 == 2 && chips > k / 3, rng, log.truth, always_hidden));
    t = log.episodes.back().t_end + 1.0;  // the ball is carried to the next spot, unseen
  }
  return log;
}

bool Covers(const Estimate& e, double truth) { return e.ok() && e.low <= truth && truth <= e.high; }

TEST(BallFit, RecoversTheTwoPhaseModelFromKicks) {
  const Log log = MakeLog(16, 0, 3);
  const BallFitInput input = log.Input();
  const BallFit fit = FitBall(input);
  ASSERT_TRUE(fit.enough_data) << (fit.problems.empty() ? "" : fit.problems.front());
  const Truth& truth = log.truth;
  EXPECT_NEAR(fit.acc_slide.value, truth.acc_slide, 0.05 * std::abs(truth.acc_slide));
  EXPECT_NEAR(fit.acc_roll.value, truth.acc_roll, 0.08 * std::abs(truth.acc_roll));
  EXPECT_NEAR(fit.k_switch.value, truth.k_switch, 0.03);
  EXPECT_TRUE(Covers(fit.acc_slide, truth.acc_slide)) << fit.acc_slide.low << " " << fit.acc_slide.high;
  EXPECT_TRUE(Covers(fit.acc_roll, truth.acc_roll)) << fit.acc_roll.low << " " << fit.acc_roll.high;
  EXPECT_TRUE(Covers(fit.k_switch, truth.k_switch)) << fit.k_switch.low << " " << fit.k_switch.high;
  // The intervals say something: narrower than the tolerances above.
  EXPECT_LT(fit.acc_slide.high - fit.acc_slide.low, 0.1 * std::abs(truth.acc_slide));
  EXPECT_LT(fit.k_switch.high - fit.k_switch.low, 0.06);
  // The ÜberSim parameters that give these: acc_slide = −μg, k_switch = 1/(1+k), acc_roll = −ρg/((1+k)r).
  EXPECT_NEAR(fit.mu.value, -fit.acc_slide.value / kG, 1e-12);
  EXPECT_NEAR(fit.inertia_factor.value, 1 / fit.k_switch.value - 1, 1e-12);
  EXPECT_NEAR(fit.rolling_friction.value,
              -fit.acc_roll.value * (1 + fit.inertia_factor.value) * input.ball_radius / kG, 1e-12);
  EXPECT_TRUE(Covers(fit.mu, -truth.acc_slide / kG));
  EXPECT_TRUE(Covers(fit.inertia_factor, 1 / truth.k_switch - 1));
  EXPECT_TRUE(Covers(fit.rolling_friction, -truth.acc_roll * input.ball_radius / (kG * truth.k_switch)));
  // Runs: the kicks are found and dated, the bounces cut them, nothing airborne.
  int used = 0, dated = 0, after_wall = 0;
  for (const BallRun& r : fit.runs) {
    EXPECT_FALSE(r.airborne && r.used);
    used += r.used;
    dated += r.used && r.kick_seen;
    after_wall += r.used && r.begins == "turn";
  }
  EXPECT_GE(dated, 12);
  EXPECT_GE(after_wall, 3);
  EXPECT_GE(used, 16);
  EXPECT_NEAR(fit.noise, log.noise, 0.0007);
  EXPECT_LT(fit.rms_residual, 1.3 * log.noise);
  EXPECT_FALSE(fit.damping_z.ok());
}

TEST(BallFit, IntervalsShrinkWithMoreData) {
  const BallFit few = FitBall(MakeLog(6, 0, 11).Input());
  const BallFit many = FitBall(MakeLog(24, 0, 12).Input());
  ASSERT_TRUE(few.enough_data);
  ASSERT_TRUE(many.enough_data);
  auto width = [](const Estimate& e) { return e.high - e.low; };
  EXPECT_LT(width(many.acc_slide), width(few.acc_slide));
  EXPECT_LT(width(many.acc_roll), width(few.acc_roll));
  EXPECT_LT(width(many.k_switch), width(few.k_switch));
  const Truth truth;
  EXPECT_TRUE(Covers(many.acc_slide, truth.acc_slide));
  EXPECT_TRUE(Covers(many.acc_roll, truth.acc_roll));
  EXPECT_TRUE(Covers(many.k_switch, truth.k_switch));
}

// Over several seeded logs, the 95 % intervals hold the truth nearly always.
TEST(BallFit, IntervalsCoverTheTruth) {
  const Truth truth;
  int covered[3] = {0, 0, 0}, fits = 0;
  for (std::uint32_t seed = 100; seed < 108; ++seed) {
    const BallFit fit = FitBall(MakeLog(5, 0, seed).Input());
    if (!fit.enough_data) continue;
    ++fits;
    covered[0] += Covers(fit.acc_slide, truth.acc_slide);
    covered[1] += Covers(fit.acc_roll, truth.acc_roll);
    covered[2] += Covers(fit.k_switch, truth.k_switch);
  }
  ASSERT_EQ(fits, 8);
  for (int j = 0; j < 3; ++j) EXPECT_GE(covered[j], 7) << "parameter " << j;
}

TEST(BallFit, RecoversChipDampingsWithoutSpoilingTheRoll) {
  const Log log = MakeLog(10, 5, 5, OneCamera());
  const BallFit fit = FitBall(log.Input());
  ASSERT_TRUE(fit.enough_data);
  const Truth& truth = log.truth;
  int chips = 0;
  for (const BallRun& r : fit.runs) chips += r.used && r.airborne;
  EXPECT_GE(chips, 4);
  EXPECT_NEAR(fit.damping_z.value, truth.damping_z, 0.05);
  EXPECT_NEAR(fit.damping_xy_first_hop.value, truth.damping_first, 0.05);
  EXPECT_NEAR(fit.damping_xy_other_hops.value, truth.damping_other, 0.05);
  EXPECT_TRUE(Covers(fit.damping_z, truth.damping_z));
  EXPECT_TRUE(Covers(fit.damping_xy_first_hop, truth.damping_first));
  EXPECT_TRUE(Covers(fit.damping_xy_other_hops, truth.damping_other));
  EXPECT_EQ(fit.damping_z.samples, chips);
  EXPECT_NEAR(fit.acc_slide.value, truth.acc_slide, 0.05 * std::abs(truth.acc_slide));
  EXPECT_NEAR(fit.acc_roll.value, truth.acc_roll, 0.08 * std::abs(truth.acc_roll));
  EXPECT_NEAR(fit.k_switch.value, truth.k_switch, 0.03);
}

TEST(BallFit, ChipsWithoutCameraPositionsAreRejectedWithAReason) {
  BallFitInput input = MakeLog(10, 5, 5, OneCamera()).Input();
  input.cameras.clear();
  const BallFit fit = FitBall(input);
  ASSERT_TRUE(fit.enough_data);
  int unfitted = 0;
  for (const BallRun& r : fit.runs) {
    EXPECT_FALSE(r.airborne && r.used);
    unfitted += r.airborne && r.reason.find("no position for camera 0") != std::string::npos;
  }
  EXPECT_GE(unfitted, 4);
  EXPECT_FALSE(fit.damping_z.ok());
  EXPECT_NEAR(fit.acc_slide.value, Truth{}.acc_slide, 0.05 * 2.4);
}

// With no kick in view and no robots known, no run starts at a kick the fit can date: the
// decelerations come from the runs alone, the switch is not estimated, and the report says so.
TEST(BallFit, WithoutDatedKicksTheSwitchIsNotEstimated) {
  BallFitInput input = MakeLog(14, 0, 31, TwoCameras(), true).Input();
  input.robot_distance = nullptr;
  const BallFit fit = FitBall(input);
  ASSERT_TRUE(fit.enough_data);
  for (const BallRun& r : fit.runs) EXPECT_FALSE(r.kick_seen);
  const Truth truth;
  EXPECT_NEAR(fit.acc_slide.value, truth.acc_slide, 0.05 * std::abs(truth.acc_slide));
  EXPECT_NEAR(fit.acc_roll.value, truth.acc_roll, 0.08 * std::abs(truth.acc_roll));
  EXPECT_TRUE(Covers(fit.acc_roll, truth.acc_roll));
  EXPECT_FALSE(fit.k_switch.ok());
  EXPECT_FALSE(fit.inertia_factor.ok());
  EXPECT_FALSE(fit.rolling_friction.ok());
  EXPECT_TRUE(fit.mu.ok());
  bool said = false;
  for (const std::string& p : fit.problems) said = said || p.find("k_switch not estimated") != std::string::npos;
  EXPECT_TRUE(said);
}

// One kick rolls at most three runs (two walls), fewer than the four a fit needs, whatever the seed.
TEST(BallFit, TooFewRunsGiveNoFit) {
  const BallFit fit = FitBall(MakeLog(1, 0, 21).Input());
  EXPECT_FALSE(fit.enough_data);
  ASSERT_FALSE(fit.problems.empty());
  EXPECT_NE(fit.problems.front().find("need 4"), std::string::npos) << fit.problems.front();
  for (const Estimate* e : {&fit.acc_slide, &fit.acc_roll, &fit.k_switch, &fit.mu, &fit.rolling_friction,
                            &fit.inertia_factor, &fit.damping_z}) {
    EXPECT_FALSE(e->ok());
    EXPECT_TRUE(std::isfinite(e->value));
  }
  EXPECT_FALSE(FitBall(BallFitInput{}).enough_data);
}

TEST(BallFit, ReportShowsRunsEstimatesAndPlots) {
  const Log log = MakeLog(8, 3, 8, OneCamera());
  const BallFitInput input = log.Input();
  const BallFit fit = FitBall(input);
  ASSERT_TRUE(fit.enough_data);
  const ReportSection report = BallReport(fit, input);
  EXPECT_NE(report.markdown.find("### Ball"), std::string::npos);
  EXPECT_NE(report.markdown.find("acc_slide"), std::string::npos);
  EXPECT_NE(report.markdown.find("rolling_friction"), std::string::npos);
  EXPECT_NE(report.markdown.find("#### Runs"), std::string::npos);
  EXPECT_NE(report.markdown.find("used"), std::string::npos);
  EXPECT_EQ(report.markdown.find("\n# "), std::string::npos);
  EXPECT_EQ(report.markdown.find("\n## "), std::string::npos);
  ASSERT_GE(report.plots.size(), 2u);
  for (const validation::Plot& plot : report.plots) {
    EXPECT_EQ(plot.file.rfind("ball-", 0), 0u) << plot.file;
    EXPECT_NE(report.markdown.find(plot.file), std::string::npos);
    std::size_t values = 0;
    for (const validation::Series& s : plot.series) {
      values += s.x.size();
      EXPECT_EQ(s.x.size(), s.y.size());
    }
    EXPECT_GT(values, 20u) << plot.file;
  }
  const BallFit none = FitBall(MakeLog(1, 0, 21).Input());
  const ReportSection short_report = BallReport(none, input);
  EXPECT_NE(short_report.markdown.find("need 4"), std::string::npos);
  EXPECT_TRUE(short_report.plots.empty());
}

}  // namespace
}  // namespace ubersim::calibrate
