// SPDX-License-Identifier: Apache-2.0
// The ball fit. How it works, step by step (each step is a function below):
//
// 1. Marks on the track. Each detection is marked near a robot (within `reach`) or stray (far off
//    a quadratic through its neighbours) and gets a local speed. Breaks in the motion, a turn
//    (wall bounce, a touch nobody saw) or a rise in speed (a kick), are found by comparing the
//    velocity fitted over 0.1 s before each detection with the one over 0.1 s after, against a
//    threshold that grows with the noise of those velocities.
// 2. Candidate runs: stretches with no robot near, no break, no gap over max_gap and a speed of at
//    least min_speed. Each gets a straight line (principal axis); the fit uses the positions along
//    it, s(t). Runs too short, or not straight, are rejected.
// 3. Kick dating. When a run begins as the ball leaves a robot, or after a kick, the kick instant is
//    where the ball's motion before (at rest or carried: a line in time) meets the run's start
//    extrapolated back; when the ball was hidden at the robot, where that extrapolation reaches the
//    robot (kick_contact). A dated kick gives the kick speed V, so the switch at k_switch·V
//    constrains k_switch. Other runs (after a bounce or a gap) start in an unknown state of spin:
//    they get their own slide time and constrain only the decelerations.
// 4. Ground fit: one least-squares problem on positions, with 3 globals (acc_slide, acc_roll,
//    k_switch) and 2–3 parameters per run, solved by Levenberg–Marquardt on the arrow-shaped
//    normal equations: each run's block is eliminated (Schur complement), so a step costs O(runs).
//    Detections off by more than outlier_sigmas·σ are dropped, runs fitting far worse than the
//    typical run are rejected, and the fit repeats. Intervals: σ²(JᵀJ)⁻¹ of the globals (the inverse
//    Schur complement), widened to a grouped jackknife over runs when that is larger, so that what
//    differs between runs beyond the model (carpet, spin) shows in the interval.
// 5. Chips: where a kick is not followed by a run the ground law explains, a ballistic-hop model
//    seen through the camera (the carpet point on the ray through the ball) is fitted. If it fits
//    at noise level with a first hop higher than chip_min_apex, it is a chip and its flight leaves
//    the ground data. The dampings are then fitted over all chips at once (globals), each chip's
//    launch being its own block.
#include "ball_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Dense>

namespace ubersim::calibrate {
namespace {

using Eigen::MatrixXd;
using Eigen::Vector2d;
using Eigen::Vector3d;
using Eigen::VectorXd;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
constexpr double kZ95 = 1.959964;         // two-sided 95 % quantile of the normal distribution
constexpr double kLocalHalfWidth = 0.06;  // s, half-width of the local fits (stray test, speed)
constexpr double kBreakWindow = 0.1;      // s, velocity windows either side of a candidate break
constexpr double kBreakTrim = 0.03;       // s, detections this close to a break are left out
constexpr double kStrayFloor = 0.02;      // m, a stray is at least this far off its neighbours…
constexpr double kStraySigmas = 6;        // …and this many σ
constexpr double kKickLookBack = 0.5;     // s, detections before a run searched for its kick
constexpr double kMaxKickAge = 0.3;       // s, a kick older than this at the run's start is not used
constexpr double kChipFirstWindow = 1.6;  // s, detections a chip trial first looks at
constexpr double kChipRollOut = 0.4;      // s, rolling after the last landing a chip fit keeps
constexpr double kChipGroundMargin = 0.15;  // s, after the last landing before a ground run may start
constexpr double kChipGridGiveUp = 0.1;     // m, rms of the best launch on the grid above which no chip
constexpr double kChipGoodEnough = 0.005;   // m, rms of a launch fit that needs no other start

// Default globals: the league's (ssl-vision) models, where the fit starts and what unestimated
// parameters are held at.
constexpr double kDefaultSlide = -3.0, kDefaultRoll = -0.4, kDefaultSwitch = 0.7;
constexpr double kDefaultDampingZ = 0.7, kDefaultDampingFirst = 0.6, kDefaultDampingOther = 0.95;

template <typename... Args>
std::string Format(const char* format, Args... args) {
  char buf[512];
  std::snprintf(buf, sizeof buf, format, args...);
  return buf;
}

double Median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// σ of zero-centred normal residuals from their median absolute value.
double RobustSigma(std::vector<double> v) {
  for (double& x : v) x = std::abs(x);
  return 1.4826 * Median(std::move(v));
}

// Two-sided 95 % quantile of Student's t with `dof` degrees of freedom.
double StudentT95(int dof) {
  static constexpr double kTable[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228};
  if (dof < 1) return kInf;
  if (dof <= 10) return kTable[dof - 1];
  return kZ95 + 2.4 / dof;  // within 1 % above 10
}

Vector2d At(const TrackPoint& p) { return {p.x, p.y}; }

double Cross(const Vector2d& a, const Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// ------------------------------------------------------------------------- local fits on the track

// x(t) and y(t) as polynomials c0 + c1·τ + c2·τ² in τ = t − t0, fitted over some detections.
struct LocalPoly {
  Vector3d cx = Vector3d::Zero(), cy = Vector3d::Zero();
  int n = 0;
  double spread = 0;     // Σ(τ − τ̄)², s²: a slope's variance is σ²/spread
  double leverage = 0;   // c0's variance over σ²
  bool ok = false;
  Vector2d Position(double tau) const {
    return {cx[0] + tau * (cx[1] + tau * cx[2]), cy[0] + tau * (cy[1] + tau * cy[2])};
  }
  Vector2d Velocity(double tau) const { return {cx[1] + 2 * tau * cx[2], cy[1] + 2 * tau * cy[2]}; }
};

// Fits degree 1 or 2 over track[begin, end), leaving out `except` and detections marked in `skip`.
LocalPoly FitLocal(const std::vector<TrackPoint>& track, const std::vector<char>& skip, std::size_t begin,
                   std::size_t end, double t0, int degree, std::size_t except = kNone) {
  const int m = degree + 1;
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Vector3d bx = Vector3d::Zero(), by = Vector3d::Zero();
  LocalPoly fit;
  double st = 0, stt = 0;
  for (std::size_t i = begin; i < end; ++i) {
    if (i == except || skip[i]) continue;
    const double tau = track[i].t - t0;
    const Vector3d phi(1.0, tau, tau * tau);
    a += phi * phi.transpose();
    bx += track[i].x * phi;
    by += track[i].y * phi;
    st += tau;
    stt += tau * tau;
    ++fit.n;
  }
  if (fit.n < m + 2) return fit;
  fit.spread = stt - st * st / fit.n;
  if (fit.spread <= 1e-9) return fit;
  const Eigen::MatrixXd am = a.topLeftCorner(m, m);
  const auto solver = am.ldlt();
  fit.cx.head(m) = solver.solve(bx.head(m));
  fit.cy.head(m) = solver.solve(by.head(m));
  fit.leverage = solver.solve(VectorXd::Unit(m, 0))[0];
  fit.ok = fit.cx.allFinite() && fit.cy.allFinite();
  return fit;
}

std::size_t FirstAtOrAfter(const std::vector<TrackPoint>& track, double t) {
  return static_cast<std::size_t>(
      std::lower_bound(track.begin(), track.end(), t, [](const TrackPoint& p, double v) { return p.t < v; }) -
      track.begin());
}

std::size_t FirstAfter(const std::vector<TrackPoint>& track, double t) {
  return static_cast<std::size_t>(
      std::upper_bound(track.begin(), track.end(), t, [](double v, const TrackPoint& p) { return v < p.t; }) -
      track.begin());
}

// ------------------------------------------------------------------------------ marks on the track

// What the track says about each detection before any run is cut out of it.
struct TrackMarks {
  std::vector<char> near;                // a robot within reach
  std::vector<char> stray;               // far off the motion of its neighbours
  std::vector<double> speed;             // m/s, local speed (NaN: too few neighbours)
  std::vector<int> brk;                  // the break it is next to (index into break_kind), or −1
  std::vector<std::string> break_kind;   // "turn" or "kick"
  double noise = 0.003;                  // m, σ of one coordinate
};

std::vector<char> MarkNear(const std::vector<TrackPoint>& track, const BallFitInput& input, double reach) {
  std::vector<char> near(track.size(), 0);
  if (!input.robot_distance) return near;
  for (std::size_t i = 0; i < track.size(); ++i) {
    near[i] = input.robot_distance(track[i].t, track[i].x, track[i].y) < reach;
  }
  return near;
}

// Each detection's offset from a quadratic through its neighbours within ±kLocalHalfWidth (twice
// that where detections are sparse; itself left out), scaled to the detection noise (the fit's own
// error taken out); NaN where there are too few neighbours.
std::vector<Vector2d> NeighbourResiduals(const std::vector<TrackPoint>& track, const std::vector<char>& skip) {
  std::vector<Vector2d> e(track.size(), Vector2d(kNaN, kNaN));
  std::size_t lo = 0, hi = 0;
  for (std::size_t i = 0; i < track.size(); ++i) {
    while (track[lo].t < track[i].t - kLocalHalfWidth) ++lo;
    while (hi < track.size() && track[hi].t <= track[i].t + kLocalHalfWidth) ++hi;
    LocalPoly fit = FitLocal(track, skip, lo, hi, track[i].t, 2, i);
    if (!fit.ok || fit.n < 6) {
      fit = FitLocal(track, skip, FirstAtOrAfter(track, track[i].t - 2 * kLocalHalfWidth),
                     FirstAfter(track, track[i].t + 2 * kLocalHalfWidth), track[i].t, 2, i);
    }
    if (fit.ok && fit.n >= 6) e[i] = (At(track[i]) - fit.Position(0)) / std::sqrt(1 + fit.leverage);
  }
  return e;
}

double NoiseOf(const std::vector<Vector2d>& e, const std::vector<char>& skip) {
  std::vector<double> c;
  c.reserve(2 * e.size());
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (skip[i] || !e[i].allFinite()) continue;
    c.push_back(e[i].x());
    c.push_back(e[i].y());
  }
  return c.size() < 20 ? 0.003 : std::max(1e-4, RobustSigma(std::move(c)));
}

// NeighbourResiduals with each camera's detections on their own: where cameras overlap they see an
// airborne ball in different places (each along its own ray), and neither is a stray.
std::vector<Vector2d> PerCameraResiduals(const std::vector<TrackPoint>& track, const std::vector<char>& skip) {
  std::map<int, std::vector<std::size_t>> by_camera;
  for (std::size_t i = 0; i < track.size(); ++i) by_camera[track[i].camera_id].push_back(i);
  std::vector<Vector2d> e(track.size(), Vector2d(kNaN, kNaN));
  for (const auto& [camera, idx] : by_camera) {
    std::vector<TrackPoint> own;
    std::vector<char> own_skip;
    for (std::size_t i : idx) {
      own.push_back(track[i]);
      own_skip.push_back(skip[i]);
    }
    const std::vector<Vector2d> own_e = NeighbourResiduals(own, own_skip);
    for (std::size_t k = 0; k < idx.size(); ++k) e[idx[k]] = own_e[k];
  }
  return e;
}

// Strays in two passes: the second with the first's strays out of the neighbours' fits, so that a
// good detection next to a stray is not condemned with it. Sets marks.stray and marks.noise.
void MarkStrays(const std::vector<TrackPoint>& track, TrackMarks& marks) {
  std::vector<char> none(track.size(), 0);
  std::vector<Vector2d> e = PerCameraResiduals(track, none);
  marks.noise = NoiseOf(e, none);
  const double limit = std::max(kStrayFloor, kStraySigmas * marks.noise);
  std::vector<char> first(track.size(), 0);
  for (std::size_t i = 0; i < track.size(); ++i) first[i] = e[i].allFinite() && e[i].norm() > limit;
  e = PerCameraResiduals(track, first);
  marks.stray.assign(track.size(), 0);
  for (std::size_t i = 0; i < track.size(); ++i) {
    marks.stray[i] = e[i].allFinite() ? e[i].norm() > limit : first[i];
  }
  marks.noise = NoiseOf(e, marks.stray);
}

void MarkSpeeds(const std::vector<TrackPoint>& track, TrackMarks& marks) {
  marks.speed.assign(track.size(), kNaN);
  std::size_t lo = 0, hi = 0;
  for (std::size_t i = 0; i < track.size(); ++i) {
    while (track[lo].t < track[i].t - kLocalHalfWidth) ++lo;
    while (hi < track.size() && track[hi].t <= track[i].t + kLocalHalfWidth) ++hi;
    const LocalPoly fit = FitLocal(track, marks.stray, lo, hi, track[i].t, 1);
    if (fit.ok) marks.speed[i] = fit.Velocity(0).norm();
  }
}

// How strongly the motion breaks at detection i: > 1 is a break. Compares the velocity over
// kBreakWindow before with the one over kBreakWindow after, each against its own noise.
std::pair<double, bool> BreakScore(const std::vector<TrackPoint>& track, const TrackMarks& marks,
                                   const BallFitOptions& options, std::size_t i) {
  const double t = track[i].t;
  const std::size_t b0 = FirstAtOrAfter(track, t - kBreakWindow), mid = FirstAtOrAfter(track, t);
  const std::size_t a1 = FirstAfter(track, t + kBreakWindow);
  const LocalPoly before = FitLocal(track, marks.stray, b0, mid, t, 1);
  const LocalPoly after = FitLocal(track, marks.stray, mid, a1, t, 1);
  if (!before.ok || !after.ok) return {0.0, false};
  const Vector2d vb = before.Velocity(0), va = after.Velocity(0);
  const double sb = marks.noise / std::sqrt(before.spread), sa = marks.noise / std::sqrt(after.spread);
  const double jump = (va.norm() - vb.norm()) / std::max(options.speed_jump, 4 * std::hypot(sb, sa));
  double turn = 0;
  if (vb.norm() >= options.min_speed && va.norm() >= options.min_speed) {
    const double angle = std::atan2(std::abs(Cross(vb, va)), vb.dot(va));
    turn = angle / std::max(options.turn_angle, 4 * std::hypot(sb / vb.norm(), sa / va.norm()));
  }
  return {std::max(jump, turn), jump >= turn};
}

// Breaks: the strongest detection of each cluster whose score exceeds 1; detections within
// kBreakTrim of it are marked, since a bounce or kick happens somewhere between frames.
void MarkBreaks(const std::vector<TrackPoint>& track, const BallFitOptions& options, TrackMarks& marks) {
  marks.brk.assign(track.size(), -1);
  std::size_t best = kNone;
  double best_score = 0, last_t = -kInf;
  bool best_kick = false;
  auto close_cluster = [&]() {
    if (best == kNone) return;
    const int id = static_cast<int>(marks.break_kind.size());
    marks.break_kind.push_back(best_kick ? "kick" : "turn");
    const double tb = track[best].t;
    const std::size_t end = FirstAfter(track, tb + kBreakTrim);
    for (std::size_t j = FirstAtOrAfter(track, tb - kBreakTrim); j < end; ++j) marks.brk[j] = id;
    best = kNone;
    best_score = 0;
  };
  for (std::size_t i = 0; i < track.size(); ++i) {
    if (marks.stray[i]) continue;
    const auto [score, kick] = BreakScore(track, marks, options, i);
    if (score <= 1) continue;
    if (track[i].t - last_t > 0.5 * kBreakWindow) close_cluster();
    last_t = track[i].t;
    if (score > best_score) {
      best = i;
      best_score = score;
      best_kick = kick;
    }
  }
  close_cluster();
}

TrackMarks MarkTrack(const std::vector<TrackPoint>& track, const BallFitInput& input, const BallFitOptions& options) {
  TrackMarks marks;
  marks.near = MarkNear(track, input, options.reach);
  MarkStrays(track, marks);
  MarkSpeeds(track, marks);
  MarkBreaks(track, options, marks);
  return marks;
}

// ------------------------------------------------------------------------------- candidate runs

bool Free(const TrackMarks& marks, const BallFitOptions& options, std::size_t i) {
  return !marks.stray[i] && !marks.near[i] && marks.brk[i] < 0 && marks.speed[i] >= options.min_speed;
}

std::size_t PreviousGood(const TrackMarks& marks, std::size_t i) {
  while (i > 0) {
    if (!marks.stray[--i]) return i;
  }
  return kNone;
}

std::size_t NextGood(const TrackMarks& marks, std::size_t i) {
  while (++i < marks.stray.size()) {
    if (!marks.stray[i]) return i;
  }
  return kNone;
}

// Why a run stops at the edge detection `edge`: `j` is the good detection beyond it (kNone: none).
std::string Cause(const std::vector<TrackPoint>& track, const TrackMarks& marks, const BallFitOptions& options,
                  std::size_t edge, std::size_t j) {
  if (j == kNone) return "track";
  if (std::abs(track[j].t - track[edge].t) > options.max_gap) return "gap";
  if (marks.near[j]) return "robot";
  if (marks.brk[j] >= 0) return marks.break_kind[static_cast<std::size_t>(marks.brk[j])];
  return "slow";
}

// The detections in [first, last) that are not strays.
std::vector<std::size_t> GoodIndices(const TrackMarks& marks, std::size_t first, std::size_t last) {
  std::vector<std::size_t> idx;
  for (std::size_t i = first; i < last; ++i) {
    if (!marks.stray[i]) idx.push_back(i);
  }
  return idx;
}

// Maximal stretches of free detections (strays inside are skipped, not breaking the stretch); the
// odd one or two detections of a slow ball's speed flickering about min_speed are not runs.
std::vector<BallRun> Stretches(const std::vector<TrackPoint>& track, const TrackMarks& marks,
                               const BallFitOptions& options) {
  std::vector<BallRun> runs;
  std::size_t i = 0;
  while (i < track.size()) {
    if (!Free(marks, options, i)) {
      ++i;
      continue;
    }
    std::size_t last = i;
    for (std::size_t j = NextGood(marks, i); j != kNone; j = NextGood(marks, j)) {
      if (track[j].t - track[last].t > options.max_gap || !Free(marks, options, j)) break;
      last = j;
    }
    BallRun run;
    run.first = i;
    run.last = last + 1;
    run.begins = Cause(track, marks, options, i, PreviousGood(marks, i));
    run.ends = Cause(track, marks, options, last, NextGood(marks, last));
    if (GoodIndices(marks, run.first, run.last).size() >= 3) runs.push_back(std::move(run));
    i = last + 1;
  }
  return runs;
}

// The straight line a run's detections lie on: origin where s = 0 (the first detection's foot).
struct Line {
  Vector2d origin = Vector2d::Zero();
  Vector2d dir = Vector2d::UnitX();
  double Along(const Vector2d& p) const { return (p - origin).dot(dir); }
  double Across(const Vector2d& p) const { return Cross(dir, p - origin); }
};

Line LineOf(const BallRun& run) {
  Line line;
  line.origin = {run.x0, run.y0};
  line.dir = {std::cos(run.heading), std::sin(run.heading)};
  return line;
}

// Principal axis of the detections, pointing the way the ball went.
Line FitLine(const std::vector<TrackPoint>& track, const std::vector<std::size_t>& idx) {
  Vector2d mean = Vector2d::Zero();
  for (std::size_t i : idx) mean += At(track[i]);
  mean /= static_cast<double>(idx.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (std::size_t i : idx) cov += (At(track[i]) - mean) * (At(track[i]) - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  Line line;
  line.dir = eig.eigenvectors().col(1);
  if ((At(track[idx.back()]) - At(track[idx.front()])).dot(line.dir) < 0) line.dir = -line.dir;
  line.origin = mean + line.dir * (At(track[idx.front()]) - mean).dot(line.dir);
  return line;
}

// RMS distance of the detections from a smooth curve across the line (a quadratic in s absorbs
// a gentle curve of the real ball, not a chip's swing or a touch).
double CrossTrackRms(const std::vector<TrackPoint>& track, const std::vector<std::size_t>& idx, const Line& line) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Vector3d b = Vector3d::Zero();
  for (std::size_t i : idx) {
    const double s = line.Along(At(track[i]));
    const Vector3d phi(1.0, s, s * s);
    a += phi * phi.transpose();
    b += line.Across(At(track[i])) * phi;
  }
  const Vector3d c = a.ldlt().solve(b);
  double ss = 0;
  for (std::size_t i : idx) {
    const double s = line.Along(At(track[i]));
    const double d = line.Across(At(track[i])) - (c[0] + s * (c[1] + s * c[2]));
    ss += d * d;
  }
  return std::sqrt(ss / static_cast<double>(idx.size()));
}

// Geometry and the checks that need no fit: long enough, straight enough.
void Describe(const std::vector<TrackPoint>& track, const TrackMarks& marks, const BallFitOptions& options,
              BallRun& run) {
  const std::vector<std::size_t> idx = GoodIndices(marks, run.first, run.last);
  run.t_begin = track[idx.front()].t;
  run.t_end = track[idx.back()].t;
  run.points = static_cast<int>(idx.size());
  run.start_speed = marks.speed[idx.front()];
  run.t_ref = run.t_begin;
  run.reason.clear();
  const double duration = run.t_end - run.t_begin;
  if (duration < options.min_duration || run.points < options.min_points) {
    run.reason = Format("too short: %.2f s, %d detections (need %.2f s and %d)", duration, run.points,
                        options.min_duration, options.min_points);
    return;
  }
  const Line line = FitLine(track, idx);
  run.x0 = line.origin.x();
  run.y0 = line.origin.y();
  run.heading = std::atan2(line.dir.y(), line.dir.x());
  const double across = CrossTrackRms(track, idx, line);
  if (across > 3 * marks.noise + 0.002) {
    run.reason = Format("not straight: %.1f mm off a smooth path (noise %.1f mm)", 1e3 * across, 1e3 * marks.noise);
  }
}

// ------------------------------------------------------------------------------------ kick dating

// A run's first 0.25 s as a quadratic in τ = t − t_begin: what is extrapolated back to the kick.
LocalPoly EarlyMotion(const std::vector<TrackPoint>& track, const TrackMarks& marks, const BallRun& run) {
  const std::size_t end = std::min(run.last, FirstAfter(track, run.t_begin + 0.25));
  return FitLocal(track, marks.stray, run.first, end, run.t_begin, 2);
}

// Root of f in [lo, hi] by bisection; NaN without a sign change.
template <typename F>
double Bisect(F f, double lo, double hi) {
  double flo = f(lo);
  if (flo * f(hi) > 0) return kNaN;
  for (int k = 0; k < 50; ++k) {
    const double mid = 0.5 * (lo + hi), fm = f(mid);
    if ((fm <= 0) == (flo <= 0)) {
      lo = mid;
      flo = fm;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

// Good detections in the look-back before a run, oldest first, stopping at a gap.
std::vector<std::size_t> DetectionsBefore(const std::vector<TrackPoint>& track, const TrackMarks& marks,
                                          const BallFitOptions& options, const BallRun& run) {
  std::vector<std::size_t> pre;
  double later = run.t_begin;
  for (std::size_t j = PreviousGood(marks, run.first); j != kNone; j = PreviousGood(marks, j)) {
    if (track[j].t < run.t_begin - kKickLookBack || later - track[j].t > options.max_gap) break;
    pre.push_back(j);
    later = track[j].t;
  }
  std::reverse(pre.begin(), pre.end());
  return pre;
}

// Where and when a run's kick happened, as the detections before it (or the robot) tell: at t the
// ball was at s along the run's line (σ sigma), moving at v before the kick.
struct KickPoint {
  double t = kNaN, s = kNaN, v = 0, sigma = kInf;
};

// The kick from detections before the run: split them where a line in time (the ball at rest or
// carried) before and the run's start extrapolated back after fit them best, then date the kick
// where the two motions meet. t is NaN when the detections do not show a kick.
KickPoint KickFromDetections(const std::vector<TrackPoint>& track, const TrackMarks& marks,
                             const BallFitOptions& options, const BallRun& run, const Line& line,
                             const LocalPoly& early) {
  const std::vector<std::size_t> pre = DetectionsBefore(track, marks, options, run);
  double best_cost = kInf;
  std::size_t best = 0;
  LocalPoly best_before;
  for (std::size_t m = 3; m <= pre.size(); ++m) {
    double cost = 0;
    for (std::size_t j = m; j < pre.size(); ++j) {
      cost += (At(track[pre[j]]) - early.Position(track[pre[j]].t - run.t_begin)).squaredNorm();
    }
    const LocalPoly before = FitLocal(track, marks.stray, pre.front(), pre[m - 1] + 1, track[pre[m - 1]].t, 1);
    if (!before.ok) continue;
    for (std::size_t j = 0; j < m; ++j) {
      cost += (At(track[pre[j]]) - before.Position(track[pre[j]].t - track[pre[m - 1]].t)).squaredNorm();
    }
    if (cost < best_cost) {
      best_cost = cost;
      best = m;
      best_before = before;
    }
  }
  if (best == 0) return {};
  const double t_last_rest = track[pre[best - 1]].t;
  const double t_first_moving = best < pre.size() ? track[pre[best]].t : run.t_begin;
  auto gap = [&](double t) {
    return line.Along(early.Position(t - run.t_begin)) - line.Along(best_before.Position(t - t_last_rest));
  };
  const double tk = Bisect(gap, t_last_rest, t_first_moving);
  if (!std::isfinite(tk)) return {};
  // A kick: the ball is faster after it (a wall or a robot's body only slows it), and it was on the
  // run's line when it happened.
  const double v_kick = line.dir.dot(early.Velocity(tk - run.t_begin));
  const double v_before = line.dir.dot(best_before.Velocity(0));
  const double speed_before = best_before.Velocity(0).norm();
  const double off_line = std::abs(line.Across(best_before.Position(tk - t_last_rest)));
  if (v_kick - speed_before < std::max(0.5, 0.2 * v_kick) || off_line > 0.03 + 3 * marks.noise) return {};
  // The place is as good as the mean of the detections before, plus a millimetre for how the ball
  // sits at the robot.
  const double sigma = std::hypot(marks.noise / std::sqrt(best_before.n), 0.001);
  return {tk, line.Along(best_before.Position(tk - t_last_rest)), v_before, sigma};
}

// The kick of a ball the cameras lost at the robot: where the run's start, extrapolated back, comes
// within kick_contact of the robot (known to a centimetre: robots' fronts differ). t is NaN when it
// does not within kMaxKickAge.
KickPoint KickAtRobot(const BallFitInput& input, const BallFitOptions& options, const BallRun& run,
                      const LocalPoly& early, const Line& line) {
  if (!input.robot_distance) return {};
  auto clearance = [&](double t) {
    const Vector2d p = early.Position(t - run.t_begin);
    return input.robot_distance(t, p.x(), p.y()) - options.kick_contact;
  };
  if (!(clearance(run.t_begin) > 0)) return {};
  for (double t = run.t_begin - 0.005; t >= run.t_begin - kMaxKickAge; t -= 0.005) {
    if (early.Velocity(t - run.t_begin).dot(early.Velocity(0)) <= 0) return {};  // past the parabola's vertex
    if (clearance(t) > 0) continue;
    const double tk = Bisect(clearance, t, t + 0.005);
    return {tk, line.Along(early.Position(tk - run.t_begin)), 0.0, 0.01};
  }
  return {};
}

// Dates the kick a run begins with (robot, kick or slow start) and sets its reference state. The
// fit refines the kick's time later, held to the place found here.
KickPoint DateKick(const std::vector<TrackPoint>& track, const TrackMarks& marks, const BallFitInput& input,
                   const BallFitOptions& options, BallRun& run) {
  if (run.begins != "robot" && run.begins != "kick" && run.begins != "slow") return {};
  const LocalPoly early = EarlyMotion(track, marks, run);
  if (!early.ok || early.n < 6) return {};
  const Line line = LineOf(run);
  KickPoint kick = KickFromDetections(track, marks, options, run, line, early);
  std::string how = "kick seen";
  if (!std::isfinite(kick.t) && run.begins == "robot") {
    kick = KickAtRobot(input, options, run, early, line);
    how = "kick dated at the robot";
  }
  const double tk = kick.t;
  if (!std::isfinite(tk) || run.t_begin - tk > kMaxKickAge || tk > run.t_begin) return {};
  const double v = line.dir.dot(early.Velocity(tk - run.t_begin));
  if (v <= options.min_speed) return {};
  run.kick_seen = true;
  run.t_ref = tk;
  run.v_ref = v;
  run.s_ref = kick.s;
  run.begins += " (" + how + ")";
  return kick;
}

// The candidate runs, checked, with their kicks (kicks[k] belongs to runs[k]).
std::vector<BallRun> CandidateRuns(const std::vector<TrackPoint>& track, const TrackMarks& marks,
                                   const BallFitInput& input, const BallFitOptions& options,
                                   std::vector<KickPoint>& kicks) {
  std::vector<BallRun> runs = Stretches(track, marks, options);
  kicks.assign(runs.size(), KickPoint{});
  for (std::size_t k = 0; k < runs.size(); ++k) {
    Describe(track, marks, options, runs[k]);
    if (runs[k].reason.empty()) kicks[k] = DateKick(track, marks, input, options, runs[k]);
  }
  return runs;
}

// --------------------------------------------------------------------------- block least squares

// A least-squares problem whose residuals fall into blocks (runs, chips): a block's residuals depend
// on a few globals shared by all blocks and on the block's own parameters only.
class BlockProblem {
 public:
  virtual ~BlockProblem() = default;
  virtual int Blocks() const = 0;
  /// The block's residuals (model − data, weighted) and, when asked, their derivatives.
  virtual void Evaluate(int block, const VectorXd& globals, const VectorXd& local, VectorXd& r, MatrixXd* d_globals,
                        MatrixXd* d_local) const = 0;
  /// Keeps the globals in their physical range after a step.
  virtual void Bound(VectorXd& /*globals*/) const {}
  /// Keeps a block's parameters in their physical range after a step.
  virtual void BoundLocal(int /*block*/, const VectorXd& /*globals*/, VectorXd& /*local*/) const {}
};

// The unknowns: globals and each block's own parameters.
struct Params {
  VectorXd globals;
  std::vector<VectorXd> locals;
};

// Which blocks take part and which globals are fitted (the others are held).
struct Selection {
  std::vector<char> blocks;
  std::vector<char> globals;
};

double Cost(const BlockProblem& problem, const Params& x, const Selection& sel) {
  double cost = 0;
  VectorXd r;
  for (int b = 0; b < problem.Blocks(); ++b) {
    if (!sel.blocks[static_cast<std::size_t>(b)]) continue;
    problem.Evaluate(b, x.globals, x.locals[static_cast<std::size_t>(b)], r, nullptr, nullptr);
    cost += r.squaredNorm();
  }
  return cost;
}

// The linearised normal equations, blocks kept apart: [U W; Wᵀ V] [δg; δl] = −[gu; gv].
struct NormalEquations {
  MatrixXd u;
  VectorXd gu;
  std::vector<MatrixXd> v, w;
  std::vector<VectorXd> gv;
  Eigen::Index residuals = 0;
};

NormalEquations Linearize(const BlockProblem& problem, const Params& x, const Selection& sel) {
  const int g = static_cast<int>(x.globals.size());
  NormalEquations ne;
  ne.u = MatrixXd::Zero(g, g);
  ne.gu = VectorXd::Zero(g);
  const auto blocks = static_cast<std::size_t>(problem.Blocks());
  ne.v.resize(blocks);
  ne.w.resize(blocks);
  ne.gv.resize(blocks);
  VectorXd r;
  MatrixXd jg, jl;
  for (std::size_t b = 0; b < blocks; ++b) {
    if (!sel.blocks[b]) continue;
    problem.Evaluate(static_cast<int>(b), x.globals, x.locals[b], r, &jg, &jl);
    for (int j = 0; j < g; ++j) {
      if (!sel.globals[static_cast<std::size_t>(j)]) jg.col(j).setZero();
    }
    // Thin matrices: coefficient-wise products beat the blocked kernel here.
    ne.u.noalias() += jg.transpose().lazyProduct(jg);
    ne.gu.noalias() += jg.transpose() * r;
    ne.v[b].noalias() = jl.transpose().lazyProduct(jl);
    ne.w[b].noalias() = jg.transpose().lazyProduct(jl);
    ne.gv[b].noalias() = jl.transpose() * r;
    ne.residuals += r.size();
  }
  return ne;
}

// A step of the damped equations, each block eliminated (Schur complement); `reduced` is the
// globals' matrix after elimination, whose inverse (at λ = 0) is their covariance over σ².
struct Step {
  VectorXd globals;
  std::vector<VectorXd> locals;
  MatrixXd reduced;
};

Step SolveStep(const NormalEquations& ne, double lambda, const Selection& sel) {
  Step step;
  MatrixXd s = ne.u;
  s.diagonal() += lambda * ne.u.diagonal();
  VectorXd rhs = -ne.gu;
  std::vector<Eigen::LDLT<MatrixXd>> solvers(ne.v.size());
  for (std::size_t b = 0; b < ne.v.size(); ++b) {
    if (!sel.blocks[b]) continue;
    MatrixXd vb = ne.v[b];
    // A tiny ridge keeps a parameter the data do not see (a run that never slides) solvable.
    vb.diagonal() += lambda * ne.v[b].diagonal() +
                     VectorXd::Constant(vb.rows(), 1e-12 * (1 + ne.v[b].diagonal().maxCoeff()));
    solvers[b].compute(vb);
    const MatrixXd x = solvers[b].solve(ne.w[b].transpose());
    s.noalias() -= ne.w[b] * x;
    rhs.noalias() += x.transpose() * ne.gv[b];
  }
  step.reduced = s;
  for (std::size_t j = 0; j < sel.globals.size(); ++j) {
    if (sel.globals[j]) continue;
    s.row(static_cast<Eigen::Index>(j)).setZero();
    s.col(static_cast<Eigen::Index>(j)).setZero();
    s(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j)) = 1;
    rhs[static_cast<Eigen::Index>(j)] = 0;
  }
  s.diagonal().array() += 1e-14 * (1 + s.diagonal().array().abs());
  step.globals = s.ldlt().solve(rhs);
  step.locals.resize(ne.v.size());
  for (std::size_t b = 0; b < ne.v.size(); ++b) {
    if (sel.blocks[b]) step.locals[b] = solvers[b].solve(-ne.gv[b] - ne.w[b].transpose() * step.globals);
  }
  return step;
}

Params Apply(const BlockProblem& problem, const Params& x, const Step& step, const Selection& sel) {
  Params y = x;
  if (step.globals.allFinite()) y.globals += step.globals;
  problem.Bound(y.globals);
  for (std::size_t b = 0; b < y.locals.size(); ++b) {
    if (!sel.blocks[b] || !step.locals[b].allFinite()) continue;
    y.locals[b] += step.locals[b];
    problem.BoundLocal(static_cast<int>(b), y.globals, y.locals[b]);
  }
  return y;
}

// Converged when a step gains less than this share of the cost per residual (σ²): Δχ² < 0.001, far
// below what moves an estimate by a noticeable part of its uncertainty.
bool Converged(double gain, double cost, Eigen::Index residuals) {
  return gain <= 1e-3 * cost / static_cast<double>(std::max<Eigen::Index>(1, residuals)) + 1e-24;
}

double BlockCost(const BlockProblem& problem, std::size_t b, const VectorXd& globals, const VectorXd& local) {
  static thread_local VectorXd r;
  problem.Evaluate(static_cast<int>(b), globals, local, r, nullptr, nullptr);
  return r.squaredNorm();
}

// The cost of a trial step, each block keeping its old parameters where the step made it worse:
// a block at a kink of its model (a run switching to rolling) must not hold back all the others,
// as one shared damping would make it.
double TrialCost(const BlockProblem& problem, const Params& x, const std::vector<double>& costs, Params& trial,
                 std::vector<double>& trial_costs, const Selection& sel) {
  double total = 0;
  for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
    if (!sel.blocks[b]) continue;
    trial_costs[b] = BlockCost(problem, b, trial.globals, trial.locals[b]);
    if (trial_costs[b] > costs[b]) {
      const double kept = BlockCost(problem, b, trial.globals, x.locals[b]);
      if (kept < trial_costs[b]) {
        trial_costs[b] = kept;
        trial.locals[b] = x.locals[b];
      }
    }
    total += trial_costs[b];
  }
  return total;
}

// Levenberg–Marquardt on a block problem; returns the final cost.
double Minimise(const BlockProblem& problem, Params& x, const Selection& sel, int max_iterations) {
  std::vector<double> costs(sel.blocks.size(), 0.0), trial_costs = costs;
  double cost = 0;
  for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
    if (sel.blocks[b]) cost += costs[b] = BlockCost(problem, b, x.globals, x.locals[b]);
  }
  double lambda = 1e-3;
  for (int it = 0; it < max_iterations; ++it) {
    const NormalEquations ne = Linearize(problem, x, sel);
    bool better = false;
    double gain = 0, moved = kInf;
    while (!better && lambda < 1e12) {
      const Step step = SolveStep(ne, lambda, sel);
      Params trial = Apply(problem, x, step, sel);
      const double c = TrialCost(problem, x, costs, trial, trial_costs, sel);
      if (c < cost) {
        better = true;
        gain = cost - c;
        moved = step.globals.dot(step.reduced * step.globals);
        x = std::move(trial);
        costs.swap(trial_costs);
        cost = c;
        lambda = std::max(lambda / 3, 1e-12);
      } else {
        lambda *= 4;
      }
    }
    // Done when the cost no longer falls, or the globals no longer move (by 0.1 % of their standard
    // error): what is left is a run's own parameters creeping along a kink of its law.
    const double sigma2 = cost / static_cast<double>(std::max<Eigen::Index>(1, ne.residuals));
    const bool still = it >= 2 && x.globals.size() > 0 && moved < 1e-6 * sigma2;
    if (!better || Converged(gain, cost, ne.residuals) || still) return cost;
  }
  return cost;
}

// Levenberg–Marquardt on one block's own parameters, the globals held; returns the block's cost.
double MinimiseBlock(const BlockProblem& problem, int block, const VectorXd& globals, VectorXd& local,
                     int max_iterations) {
  VectorXd r, rt;
  MatrixXd jg, jl;
  problem.Evaluate(block, globals, local, r, nullptr, nullptr);
  double cost = r.squaredNorm(), lambda = 1e-3;
  for (int it = 0; it < max_iterations; ++it) {
    problem.Evaluate(block, globals, local, r, &jg, &jl);
    const MatrixXd v = jl.transpose().lazyProduct(jl);
    const VectorXd gv = jl.transpose() * r;
    bool better = false;
    double gain = 0;
    while (!better && lambda < 1e12) {
      MatrixXd damped = v;
      damped.diagonal() += lambda * v.diagonal() + VectorXd::Constant(v.rows(), 1e-12 * (1 + v.diagonal().maxCoeff()));
      VectorXd trial = local - damped.ldlt().solve(gv);
      problem.BoundLocal(block, globals, trial);
      problem.Evaluate(block, globals, trial, rt, nullptr, nullptr);
      if (trial.allFinite() && rt.squaredNorm() < cost) {
        better = true;
        gain = cost - rt.squaredNorm();
        cost = rt.squaredNorm();
        local = std::move(trial);
        lambda = std::max(lambda / 3, 1e-12);
      } else {
        lambda *= 4;
      }
    }
    if (!better || Converged(gain, cost, r.size())) break;
  }
  return cost;
}

// The globals' information matrix JᵀJ with the blocks eliminated, at x.
MatrixXd Information(const BlockProblem& problem, const Params& x, const Selection& sel) {
  return SolveStep(Linearize(problem, x, sel), 0.0, sel).reduced;
}

// --------------------------------------------------------------------------------- the ground law

// Ground law globals: acc_slide, acc_roll (m/s², negative), k_switch.
struct GroundLaw {
  double slide = kDefaultSlide, roll = kDefaultRoll, k = kDefaultSwitch;
};

// Position along the line τ after the reference instant, and its derivatives, for a ball that
// slides (deceleration −a_s) for `slide` s from speed u, then rolls (−a_r) until it stops.
struct LawPoint {
  double s = 0, v = 0, d_p0 = 1, d_u = 0, d_slide = 0, d_as = 0, d_ar = 0;  // v = ds/dτ
};

LawPoint TwoPhase(double tau, double p0, double u, double slide, double as, double ar) {
  LawPoint o;
  if (tau <= slide) {
    o.s = p0 + u * tau + 0.5 * as * tau * tau;
    o.v = u + as * tau;
    o.d_u = tau;
    o.d_as = 0.5 * tau * tau;
    return o;
  }
  const double vs = std::max(0.0, u + as * slide);  // speed when it starts to roll
  const double ss = p0 + u * slide + 0.5 * as * slide * slide;
  const double stop = vs / -ar;
  const double tr = tau - slide;
  if (tr < stop) {
    o.s = ss + vs * tr + 0.5 * ar * tr * tr;
    o.v = vs + ar * tr;
    o.d_u = tau;
    o.d_as = 0.5 * slide * slide + slide * tr;
    o.d_ar = 0.5 * tr * tr;
    o.d_slide = (as - ar) * tr;
    return o;
  }
  o.s = ss - 0.5 * vs * vs / ar;
  o.d_u = slide - vs / ar;
  o.d_as = 0.5 * slide * slide - vs * slide / ar;
  o.d_ar = 0.5 * vs * vs / (ar * ar);
  o.d_slide = vs * (1 - as / ar);
  return o;
}

double TwoPhaseSpeed(double tau, double u, double slide, double as, double ar) {
  if (tau <= slide) return std::max(0.0, u + as * tau);
  return std::max(0.0, u + as * slide + ar * (tau - slide));
}

// A ground run's detections in its line's frame. Its own parameters: after a dated kick (s_k, V,
// δt): at the kick, t_ref + δt, the ball was at s_k with speed V; δt moves the kick's time, while
// an extra residual holds s_k to where the kick was seen. Otherwise (s0, u0, q): at t_ref = t_begin
// the ball was at s0 with speed u0, and slid for q more seconds.
struct GroundData {
  std::vector<double> tau;  // s after t_ref
  std::vector<double> s;    // m along the line
  std::vector<double> w;    // 1, or 0 for an outlier
  bool kick = false;
  double kick_s = 0, kick_v = 0;  // m, m/s: the kick's place at t_ref, and how it moves with δt
  double kick_weight = 0;         // detection σ over the place's σ: the extra residual's weight
};

// A run's slide duration and its derivatives: a dated kick slides until k_switch·V; another run
// has its own slide time q (held in [0, the time to stop]).
struct SlideTime {
  double t = 0, d_u = 0, d_as = 0, d_k = 0, d_q = 0;
};

SlideTime SlideOf(const GroundData& d, const VectorXd& g, const VectorXd& l) {
  const double as = g[0], k = g[2], u = l[1];
  if (d.kick) return {u * (1 - k) / -as, (1 - k) / -as, u * (1 - k) / (as * as), u / as, 0};
  const double cap = u / -as;
  if (l[2] > cap) return {cap, 1 / -as, u / (as * as), 0, 0};
  return {std::max(0.0, l[2]), 0, 0, 0, 1};
}

class GroundProblem : public BlockProblem {
 public:
  explicit GroundProblem(std::vector<GroundData> runs) : runs_(std::move(runs)) {}
  int Blocks() const override { return static_cast<int>(runs_.size()); }
  const GroundData& Run(std::size_t b) const { return runs_[b]; }
  GroundData& Run(std::size_t b) { return runs_[b]; }

  void Evaluate(int block, const VectorXd& g, const VectorXd& l, VectorXd& r, MatrixXd* jg,
                MatrixXd* jl) const override {
    const GroundData& d = runs_[static_cast<std::size_t>(block)];
    const auto n = static_cast<Eigen::Index>(d.tau.size());
    r.resize(n + d.kick);
    if (jg) jg->setZero(n + d.kick, 3);
    if (jl) jl->setZero(n + d.kick, 3);
    const SlideTime sl = SlideOf(d, g, l);
    const double shift = d.kick ? l[2] : 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const LawPoint p = TwoPhase(d.tau[k] - shift, l[0], l[1], sl.t, g[0], g[1]);
      const double w = d.w[k];
      r[i] = w * (p.s - d.s[k]);
      if (!jg) continue;
      (*jg)(i, 0) = w * (p.d_as + p.d_slide * sl.d_as);
      (*jg)(i, 1) = w * p.d_ar;
      (*jg)(i, 2) = w * p.d_slide * sl.d_k;
      (*jl)(i, 0) = w * p.d_p0;
      (*jl)(i, 1) = w * (p.d_u + p.d_slide * sl.d_u);
      (*jl)(i, 2) = d.kick ? -w * p.v : w * p.d_slide * sl.d_q;
    }
    if (!d.kick) return;
    r[n] = d.kick_weight * (l[0] - d.kick_s - d.kick_v * l[2]);
    if (!jl) return;
    (*jl)(n, 0) = d.kick_weight;
    (*jl)(n, 2) = -d.kick_weight * d.kick_v;
  }
  void Bound(VectorXd& g) const override {
    g[0] = std::clamp(g[0], -60.0, -0.02);
    g[1] = std::clamp(g[1], -5.0, -0.002);
    g[2] = std::clamp(g[2], 0.2, 0.98);
  }
  void BoundLocal(int block, const VectorXd& g, VectorXd& l) const override {
    const GroundData& d = runs_[static_cast<std::size_t>(block)];
    l[1] = std::max(l[1], 0.01);
    // A kick stays before the run's first detection; a slide ends before the ball would stop.
    l[2] = d.kick ? std::clamp(l[2], -kMaxKickAge, d.tau.front()) : std::clamp(l[2], 0.0, l[1] / -g[0]);
  }

 private:
  std::vector<GroundData> runs_;
};

constexpr const char* kLawMisfit = "does not follow the two-phase law";

// A run the ground fit takes: on the carpet, and passed the checks (or failed only the fit before).
bool GroundCandidate(const BallRun& run) {
  return !run.airborne && (run.reason.empty() || run.reason.rfind(kLawMisfit, 0) == 0);
}

GroundData MakeGroundData(const std::vector<TrackPoint>& track, const TrackMarks& marks, const BallRun& run,
                          const KickPoint& kick) {
  GroundData d;
  d.kick = run.kick_seen && std::isfinite(kick.t);
  if (d.kick) {
    d.kick_s = kick.s + kick.v * (run.t_ref - kick.t);
    d.kick_v = kick.v;
    d.kick_weight = marks.noise / kick.sigma;
  }
  const Line line = LineOf(run);
  for (std::size_t i : GoodIndices(marks, run.first, run.last)) {
    d.tau.push_back(track[i].t - run.t_ref);
    d.s.push_back(line.Along(At(track[i])));
    d.w.push_back(1.0);
  }
  return d;
}

// Sum of squares of a run that slides for `slide` s, with (s0, u0) by linear least squares: the
// position is s0 + u0·τ + B(τ), B what the decelerations add (the stop is past the run's end, which
// ends above min_speed).
std::pair<double, Vector2d> BestStartFor(const GroundData& d, double slide, const GroundLaw& law) {
  Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
  Vector2d b = Vector2d::Zero();
  double yy = 0;
  for (std::size_t i = 0; i < d.tau.size(); ++i) {
    const double tau = d.tau[i], rolled = std::max(0.0, tau - slide), slid = tau - rolled;
    const double added = 0.5 * law.slide * slid * slid + law.slide * slid * rolled + 0.5 * law.roll * rolled * rolled;
    const double y = d.s[i] - added;
    const Vector2d phi(1.0, tau);
    a += d.w[i] * phi * phi.transpose();
    b += d.w[i] * y * phi;
    yy += d.w[i] * y * y;
  }
  const Vector2d c = a.ldlt().solve(b);
  return {yy - c.dot(b), c};
}

// A run with its own slide time: the slide time on a grid, each with its best start (the law's
// kink makes a local search from one guess unreliable).
VectorXd InitialMidLocals(const GroundData& d, const GroundLaw& law) {
  const double duration = d.tau.empty() ? 0 : d.tau.back();
  double best = kInf;
  VectorXd l = VectorXd::Zero(3);
  for (double slide = 0; slide <= std::min(duration, 2.0) + 1e-9; slide += 0.04) {
    const auto [ss, c] = BestStartFor(d, slide, law);
    if (ss < best && c[1] > 0 && c[1] + law.slide * slide >= 0) {
      best = ss;
      l << c[0], c[1], slide;
    }
  }
  return l;
}

VectorXd InitialLocals(const GroundData& d, const BallRun& run, const GroundLaw& law) {
  if (d.kick) return Vector3d(run.s_ref, run.v_ref, 0.0);
  return InitialMidLocals(d, law);
}

// ----------------------------------------------------------------------------------- ground fit

// The ground fit: the problem, its solution, and what each run contributed.
struct GroundResult {
  std::vector<std::size_t> run_of;  // block → index into the runs
  std::optional<GroundProblem> problem;
  Params x;
  Selection sel;
  double sigma = 0;       // m, residual σ of the used detections
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // of the globals, formal
  Eigen::Matrix3d jackknife = Eigen::Matrix3d::Zero();   // of the globals, grouped jackknife
  int jackknife_groups = 0;
  std::array<int, 3> informers{};  // runs that inform acc_slide, acc_roll, k_switch
};

GroundLaw LawOf(const VectorXd& g) { return {g[0], g[1], g[2]}; }

// Per-block rms over kept detections and the fraction dropped as outliers.
std::pair<double, double> BlockRms(const GroundProblem& problem, const Params& x, std::size_t b) {
  VectorXd r;
  problem.Evaluate(static_cast<int>(b), x.globals, x.locals[b], r, nullptr, nullptr);
  const GroundData& d = problem.Run(b);
  double kept = 0;
  for (double w : d.w) kept += w;
  if (kept < 1) return {kInf, 1.0};
  const auto n = static_cast<Eigen::Index>(d.w.size());  // the kick's place residual left out
  return {std::sqrt(r.head(n).squaredNorm() / kept), 1.0 - kept / static_cast<double>(n)};
}

// Fits a rejected run's own parameters with the globals held, so that it can be judged again.
void RefitLocals(const GroundProblem& problem, Params& x, std::size_t b) {
  MinimiseBlock(problem, static_cast<int>(b), x.globals, x.locals[b], 30);
}

// Drops detections further than outlier_sigmas·σ off the law (and takes back ones that no
// longer are); σ from the used runs' residuals, robustly. A rejected run is first refitted with all
// its detections, so that a run once off the law can come back.
double UpdateOutliers(GroundProblem& problem, Params& x, const Selection& sel, double sigmas) {
  std::vector<double> all;
  std::vector<VectorXd> residuals(static_cast<std::size_t>(problem.Blocks()));
  for (std::size_t b = 0; b < residuals.size(); ++b) {
    GroundData& d = problem.Run(b);
    std::fill(d.w.begin(), d.w.end(), 1.0);
    if (!sel.blocks[b]) RefitLocals(problem, x, b);
    problem.Evaluate(static_cast<int>(b), x.globals, x.locals[b], residuals[b], nullptr, nullptr);
    if (sel.blocks[b]) all.insert(all.end(), residuals[b].data(), residuals[b].data() + d.w.size());
  }
  const double sigma = std::max(1e-5, RobustSigma(std::move(all)));
  for (std::size_t b = 0; b < residuals.size(); ++b) {
    GroundData& d = problem.Run(b);
    for (std::size_t i = 0; i < d.w.size(); ++i) {
      d.w[i] = std::abs(residuals[b][static_cast<Eigen::Index>(i)]) <= sigmas * sigma;
    }
  }
  return sigma;
}

// Runs fitting much worse than the typical used run, or with many detections off the law, are out.
bool JudgeRuns(const GroundProblem& problem, Params& x, Selection& sel, const BallFitOptions& options,
               std::vector<std::string>& why) {
  std::vector<double> rms(sel.blocks.size(), kInf), dropped(sel.blocks.size(), 1.0), used;
  for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
    if (!sel.blocks[b]) RefitLocals(problem, x, b);
    std::tie(rms[b], dropped[b]) = BlockRms(problem, x, b);
    if (sel.blocks[b]) used.push_back(rms[b]);
  }
  const double typical = Median(used);
  const double limit = std::max(options.run_rms_factor * typical, typical + 0.001);
  bool changed = false;
  for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
    const bool keep = rms[b] <= limit && dropped[b] <= 0.05;
    if (keep != static_cast<bool>(sel.blocks[b])) changed = true;
    sel.blocks[b] = keep;
    why[b] = keep ? std::string()
             : dropped[b] > 0.05
                 ? Format("%s: %.0f %% of its detections off it", kLawMisfit, 100 * dropped[b])
                 : Format("%s: rms %.1f mm (typical %.1f mm)", kLawMisfit, 1e3 * rms[b], 1e3 * typical);
  }
  return changed;
}

// Each used run's own parameters to their best with the globals held: cheap, and it spares the
// joint steps from runs creeping along their own narrow valleys (slide time against speed).
void RefitAllLocals(const GroundProblem& problem, Params& x, const Selection& sel) {
  for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
    if (sel.blocks[b]) RefitLocals(problem, x, b);
  }
}

// A run whose slide time is its own may have settled on the wrong side of the law's kink: put it
// where the grid says, when that is better.
void RegridSlides(const GroundProblem& problem, Params& x, const Selection& sel) {
  for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
    const GroundData& d = problem.Run(b);
    if (!sel.blocks[b] || d.kick) continue;
    VectorXd r;
    problem.Evaluate(static_cast<int>(b), x.globals, x.locals[b], r, nullptr, nullptr);
    const VectorXd l = InitialMidLocals(d, LawOf(x.globals));
    VectorXd rg;
    problem.Evaluate(static_cast<int>(b), x.globals, l, rg, nullptr, nullptr);
    if (rg.squaredNorm() < r.squaredNorm()) x.locals[b] = l;
  }
}

// How many used runs inform each global: enough detections in the slide phase (acc_slide), in a
// rolling phase of at least 0.2 s (acc_roll), and both after a dated kick (k_switch).
std::array<int, 3> Informers(const GroundProblem& problem, const Params& x, const Selection& sel) {
  std::array<int, 3> count{};
  for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
    if (!sel.blocks[b]) continue;
    const GroundData& d = problem.Run(b);
    const double slide = SlideOf(d, x.globals, x.locals[b]).t;
    int sliding = 0, rolling = 0;
    double roll_from = kInf, roll_to = -kInf;
    for (std::size_t i = 0; i < d.tau.size(); ++i) {
      if (d.w[i] == 0) continue;
      if (d.tau[i] < slide) {
        ++sliding;
      } else {
        ++rolling;
        roll_from = std::min(roll_from, d.tau[i]);
        roll_to = std::max(roll_to, d.tau[i]);
      }
    }
    const bool slides = sliding >= 5, rolls = rolling >= 5 && roll_to - roll_from >= 0.2;
    count[0] += slides;
    count[1] += rolls;
    count[2] += d.kick && slides && rolling >= 5;
  }
  return count;
}

// σ of the used detections' residuals, with the parameters fitted taken out of their number.
double ResidualSigma(const GroundProblem& problem, const Params& x, const Selection& sel) {
  double ss = 0, kept = 0, params = 3;
  for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
    if (!sel.blocks[b]) continue;
    VectorXd r;
    problem.Evaluate(static_cast<int>(b), x.globals, x.locals[b], r, nullptr, nullptr);
    ss += r.squaredNorm();
    for (double w : problem.Run(b).w) kept += w;
    kept += problem.Run(b).kick;  // the kick's place
    params += static_cast<double>(x.locals[b].size());
  }
  return kept > params ? std::sqrt(ss / (kept - params)) : kNaN;
}

// Grouped jackknife over the used runs: the globals refitted with each tenth of the runs left out.
void Jackknife(GroundResult& fit) {
  std::vector<std::size_t> used;
  for (std::size_t b = 0; b < fit.sel.blocks.size(); ++b) {
    if (fit.sel.blocks[b]) used.push_back(b);
  }
  // Dated kicks first, so that each group leaves out its share of them.
  std::stable_sort(used.begin(), used.end(),
                   [&](std::size_t a, std::size_t b) { return fit.problem->Run(a).kick > fit.problem->Run(b).kick; });
  const int groups = static_cast<int>(std::min<std::size_t>(10, used.size()));
  if (groups < 4) return;
  std::vector<Vector3d> estimates;
  for (int g = 0; g < groups; ++g) {
    Selection sel = fit.sel;
    for (std::size_t k = static_cast<std::size_t>(g); k < used.size(); k += static_cast<std::size_t>(groups)) {
      sel.blocks[used[k]] = 0;
    }
    const std::array<int, 3> informers = Informers(*fit.problem, fit.x, sel);
    bool ok = true;
    for (std::size_t j = 0; j < 3; ++j) ok = ok && (!fit.sel.globals[j] || informers[j] > 0);
    if (!ok) continue;
    Params x = fit.x;
    Minimise(*fit.problem, x, sel, 30);
    estimates.push_back(x.globals.head<3>());
  }
  const auto n = static_cast<double>(estimates.size());
  if (estimates.size() < 4) return;
  Vector3d mean = Vector3d::Zero();
  for (const Vector3d& e : estimates) mean += e / n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Vector3d& e : estimates) cov += (e - mean) * (e - mean).transpose();
  fit.jackknife = cov * (n - 1) / n;
  fit.jackknife_groups = static_cast<int>(estimates.size());
}

// The globals' covariance σ²(JᵀJ)⁻¹, the runs' own parameters eliminated; held globals get none.
void Covariance(GroundResult& fit) {
  const MatrixXd info = Information(*fit.problem, fit.x, fit.sel);
  Eigen::Matrix3d free_info = Eigen::Matrix3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (fit.sel.globals[static_cast<std::size_t>(i)] && fit.sel.globals[static_cast<std::size_t>(j)]) {
        free_info(i, j) = info(i, j);
      }
    }
  }
  fit.covariance = fit.sigma * fit.sigma * free_info.inverse();
  for (int j = 0; j < 3; ++j) {
    if (!fit.sel.globals[static_cast<std::size_t>(j)]) {
      fit.covariance.row(j).setZero();
      fit.covariance.col(j).setZero();
    }
  }
}

// Brings the globals near from where they start: on a sample of at most 200 runs first, then on
// all. Between passes the runs with their own slide time are put back on the grid (from far-off
// globals they may sit on the wrong side of the law's kink). Passes are capped: with runs off the
// law still in, the joint steps are short, and judging the runs soon does more for the speed.
void Settle(const GroundProblem& problem, Params& x, const Selection& all, int passes) {
  Selection sample = all;
  const std::size_t stride = std::max<std::size_t>(1, all.blocks.size() / 200);
  for (std::size_t b = 0; b < sample.blocks.size(); ++b) sample.blocks[b] = all.blocks[b] && b % stride == 0;
  for (int pass = 0; pass < passes; ++pass) {
    const Selection& sel = pass + 1 < passes ? sample : all;
    RefitAllLocals(problem, x, sel);
    Minimise(problem, x, sel, 20);
    RegridSlides(problem, x, all);
  }
}

// The ground fit over the runs that passed the checks: robust rounds (outliers dropped, runs off
// the law rejected, refit), then globals no run informs held, then (when `final`) intervals.
// `start` is where the globals start (the defaults, or the first fit's after chips are taken out).
GroundResult FitGround(const std::vector<TrackPoint>& track, const TrackMarks& marks, const BallFitOptions& options,
                       std::vector<BallRun>& runs, const std::vector<KickPoint>& kicks, const GroundLaw& start,
                       bool final) {
  GroundResult fit;
  std::vector<GroundData> data;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    if (!GroundCandidate(runs[k])) continue;
    fit.run_of.push_back(k);
    data.push_back(MakeGroundData(track, marks, runs[k], k < kicks.size() ? kicks[k] : KickPoint{}));
  }
  if (data.empty()) return fit;
  fit.problem.emplace(std::move(data));
  GroundProblem& problem = *fit.problem;
  const std::size_t blocks = fit.run_of.size();
  fit.x.globals = Vector3d(start.slide, start.roll, start.k);
  for (std::size_t b = 0; b < blocks; ++b) {
    fit.x.locals.push_back(InitialLocals(problem.Run(b), runs[fit.run_of[b]], start));
  }
  fit.sel.blocks.assign(blocks, 1);
  fit.sel.globals.assign(3, 1);
  Settle(problem, fit.x, fit.sel, final ? 1 : 3);
  std::vector<std::string> why(blocks);
  for (int round = 0; round < 6; ++round) {
    RefitAllLocals(problem, fit.x, fit.sel);
    Minimise(problem, fit.x, fit.sel, 30);
    UpdateOutliers(problem, fit.x, fit.sel, options.outlier_sigmas);
    if (round < 2) RegridSlides(problem, fit.x, fit.sel);
    RefitAllLocals(problem, fit.x, fit.sel);
    Minimise(problem, fit.x, fit.sel, 30);
    if (!JudgeRuns(problem, fit.x, fit.sel, options, why) && round >= 1) break;
  }
  // Globals no used run informs are held at the league's defaults and reported as not estimated.
  fit.informers = Informers(problem, fit.x, fit.sel);
  const Vector3d defaults(kDefaultSlide, kDefaultRoll, kDefaultSwitch);
  for (std::size_t j = 0; j < 3; ++j) {
    if (fit.informers[j] > 0) continue;
    fit.sel.globals[j] = 0;
    fit.x.globals[static_cast<Eigen::Index>(j)] = defaults[static_cast<Eigen::Index>(j)];
  }
  Minimise(problem, fit.x, fit.sel, 100);
  fit.sigma = ResidualSigma(problem, fit.x, fit.sel);
  if (std::isfinite(fit.sigma) && final) {
    Covariance(fit);
    Jackknife(fit);
  }
  // Back into the runs: used or why not, the fitted state, the rms.
  for (std::size_t b = 0; b < blocks; ++b) {
    BallRun& run = runs[fit.run_of[b]];
    const GroundData& d = problem.Run(b);
    const VectorXd& l = fit.x.locals[b];
    run.used = fit.sel.blocks[b];
    run.reason = why[b];
    run.rms = BlockRms(problem, fit.x, b).first;
    run.points = static_cast<int>(std::count(d.w.begin(), d.w.end(), 1.0));
    run.kick_seen = d.kick;
    if (d.kick) run.t_ref += l[2];
    run.s_ref = l[0];
    run.v_ref = l[1];
    run.slide_time = SlideOf(d, fit.x.globals, l).t;
    run.start_speed = TwoPhaseSpeed(run.t_begin - run.t_ref, l[1], run.slide_time, fit.x.globals[0], fit.x.globals[1]);
  }
  return fit;
}

// ------------------------------------------------------------------------------------------ chips

// A chip's own unknowns, in the order of its parameter vector.
enum ChipParam { kLaunchTime, kLaunchX, kLaunchY, kVx, kVy, kVz, kChipParams };

// The detections a chip is fitted to: time, carpet point, the camera that saw it, weight.
struct ChipData {
  std::vector<double> t;
  std::vector<Vector2d> p;
  std::vector<Vector3d> camera;
  std::vector<double> w;
  std::vector<std::size_t> index;  // into the track
  int hops = -1;                   // flights before it rolls; −1: by the hop-height rule
};

// Flights before a chipped ball rolls: hops go on while one would rise at least min_hop_height.
int HopsUntilRolling(double vz, double damping_z, double min_hop_height, double g) {
  const double vz_min = std::sqrt(2 * g * min_hop_height);
  int hops = 1;
  for (double v = vz * damping_z; v >= vz_min && hops < 15; v *= damping_z) ++hops;
  return hops;
}

// The fixed-loss chip model: the ball's carpet position and height above rest at t. Each landing
// multiplies the vertical speed by damping_z and the horizontal by damping_xy (first or other);
// after the last, the ball slides and rolls by the ground law.
Vector3d ChipAt(double t, const VectorXd& c, const VectorXd& loss, int hops, const GroundLaw& law, double g) {
  double tau = t - c[kLaunchTime];
  Vector2d p(c[kLaunchX], c[kLaunchY]);
  if (tau <= 0) return {p.x(), p.y(), 0.0};
  Vector2d vh(c[kVx], c[kVy]);
  double vz = c[kVz];
  for (int i = 0; i < hops; ++i) {
    const double flight = 2 * vz / g;
    if (tau < flight) {
      const Vector2d q = p + vh * tau;
      return {q.x(), q.y(), vz * tau - 0.5 * g * tau * tau};
    }
    p += vh * flight;
    tau -= flight;
    vz *= loss[0];
    vh *= i == 0 ? loss[1] : loss[2];
  }
  const double v = vh.norm();
  if (v < 1e-9) return {p.x(), p.y(), 0.0};
  const double s = TwoPhase(tau, 0, v, v * (1 - law.k) / -law.slide, law.slide, law.roll).s;
  const Vector2d q = p + vh / v * s;
  return {q.x(), q.y(), 0.0};
}

// The flight counts a chip may have: the hop-height rule's, and its neighbour when the last flight
// (or the first one not flown) is within 10 % of the rule's threshold speed; a hop of about
// min_hop_height barely shows, so there the detections decide.
std::vector<int> HopChoices(double vz, double damping_z, double min_hop_height, double g) {
  const double vz_min = std::sqrt(2 * g * min_hop_height);
  const int rule = HopsUntilRolling(vz, damping_z, min_hop_height, g);
  const double last = vz * std::pow(damping_z, rule - 1);
  std::vector<int> choices{rule};
  if (rule > 1 && last < 1.1 * vz_min) choices.push_back(rule - 1);
  if (last * damping_z > 0.9 * vz_min && rule < 15) choices.push_back(rule + 1);
  return choices;
}

// Time of a chip's last landing (after which it is on the carpet).
double LastLanding(const VectorXd& c, const VectorXd& loss, int hops, double g) {
  double t = c[kLaunchTime], vz = c[kVz];
  for (int i = 0; i < hops; ++i, vz *= loss[0]) t += 2 * vz / g;
  return t;
}

// Where a camera reports a ball at height h above rest: the carpet point on its ray through the
// ball (as the simulator's vision does; the height is capped at 0.9 of the camera's).
Vector2d Reported(const Vector3d& camera, const Vector3d& ball) {
  const double h = std::clamp(ball.z(), 0.0, 0.9 * camera.z());
  const double scale = camera.z() / (camera.z() - h);
  return camera.head<2>() + (ball.head<2>() - camera.head<2>()) * scale;
}

class ChipProblem : public BlockProblem {
 public:
  ChipProblem(std::vector<ChipData> chips, GroundLaw law, const BallFitOptions& options)
      : chips_(std::move(chips)), law_(law), g_(options.gravity), min_hop_(options.min_hop_height) {}
  int Blocks() const override { return static_cast<int>(chips_.size()); }
  ChipData& Chip(std::size_t b) { return chips_[b]; }
  const ChipData& Chip(std::size_t b) const { return chips_[b]; }
  int Hops(const ChipData& d, const VectorXd& c, const VectorXd& loss) const {
    return d.hops > 0 ? d.hops : HopsUntilRolling(c[kVz], loss[0], min_hop_, g_);
  }
  const GroundLaw& law() const { return law_; }
  double gravity() const { return g_; }
  std::vector<int> Choices(const VectorXd& c, const VectorXd& loss) const {
    return HopChoices(c[kVz], loss[0], min_hop_, g_);
  }

  void Evaluate(int block, const VectorXd& g, const VectorXd& l, VectorXd& r, MatrixXd* jg,
                MatrixXd* jl) const override {
    const ChipData& d = chips_[static_cast<std::size_t>(block)];
    Residuals(d, g, l, r);
    if (!jg) return;
    // Forward differences: the model is a chain of flights with kinks at the landings, which no
    // formula differentiates more usefully, and chips are few.
    const auto n = r.size();
    jg->resize(n, g.size());
    jl->resize(n, l.size());
    VectorXd rp;
    for (Eigen::Index j = 0; j < g.size(); ++j) {
      VectorXd gp = g;
      gp[j] += kStep;
      Residuals(d, gp, l, rp);
      jg->col(j) = (rp - r) / kStep;
    }
    for (Eigen::Index j = 0; j < l.size(); ++j) {
      VectorXd lp = l;
      lp[j] += kStep;
      Residuals(d, g, lp, rp);
      jl->col(j) = (rp - r) / kStep;
    }
  }
  void Bound(VectorXd& loss) const override {
    loss[0] = std::clamp(loss[0], 0.02, 0.95);
    loss[1] = std::clamp(loss[1], 0.05, 1.3);
    loss[2] = std::clamp(loss[2], 0.05, 1.3);
  }
  void BoundLocal(int block, const VectorXd&, VectorXd& c) const override {
    c[kVz] = std::clamp(c[kVz], 0.1, 15.0);
    c[kLaunchTime] = std::min(c[kLaunchTime], chips_[static_cast<std::size_t>(block)].t.front());
  }

 private:
  void Residuals(const ChipData& d, const VectorXd& loss, const VectorXd& c, VectorXd& r) const {
    const int hops = Hops(d, c, loss);
    r.resize(static_cast<Eigen::Index>(2 * d.t.size()));
    for (std::size_t i = 0; i < d.t.size(); ++i) {
      const Vector2d e = d.w[i] * (Reported(d.camera[i], ChipAt(d.t[i], c, loss, hops, law_, g_)) - d.p[i]);
      r.segment<2>(static_cast<Eigen::Index>(2 * i)) = e;
    }
  }

  static constexpr double kStep = 1e-7;  // s, m, m/s, 1: small against every parameter's scale
  std::vector<ChipData> chips_;
  GroundLaw law_;
  double g_, min_hop_;
};

// Where the ball was launched: it leaves a robot's reach, or a kick break, and moves on at some speed.
std::vector<std::size_t> Launches(const std::vector<TrackPoint>& track, const TrackMarks& marks,
                                  const BallFitOptions& options) {
  std::vector<std::size_t> launches;
  for (std::size_t i = 0; i < track.size(); ++i) {
    if (marks.stray[i] || marks.near[i]) continue;
    const std::size_t j = PreviousGood(marks, i);
    if (j == kNone || track[i].t - track[j].t > options.max_gap) continue;
    // Left a robot (breaks right after do not matter: a chip seen by two cameras zig-zags), or
    // the first detection clear of a kick.
    const bool left_robot = marks.near[j];
    const bool kicked = marks.brk[i] < 0 && marks.brk[j] >= 0 &&
                        marks.break_kind[static_cast<std::size_t>(marks.brk[j])] == "kick";
    if (!left_robot && !kicked) continue;
    const std::size_t later = FirstAfter(track, track[i].t + 0.3);
    if (later == 0 || later - 1 <= i) continue;
    if ((At(track[later - 1]) - At(track[i])).norm() >= 0.3) launches.push_back(i);
  }
  return launches;
}

// True when a used ground run that the law explains well starts right at the launch and goes on
// for a while. A chip's first flight can pass for a short run (its swing away from the camera and
// back looks like a slide); such a run ends at the landing's kink, soon after the launch.
bool Explained(const std::vector<BallRun>& runs, double t_launch, double typical_rms) {
  for (const BallRun& run : runs) {
    if (!run.used || run.airborne || run.t_begin < t_launch - 1e-9 || run.t_begin > t_launch + 0.1) continue;
    const bool broken_soon = (run.ends == "turn" || run.ends == "kick") && run.t_end < t_launch + 1.5;
    if (run.rms <= 1.5 * typical_rms && !broken_soon) return true;
  }
  return false;
}

// The good detections from a launch on, until a robot, a gap, or `until`.
std::vector<std::size_t> ChipWindow(const std::vector<TrackPoint>& track, const TrackMarks& marks,
                                    const BallFitOptions& options, std::size_t launch, double until) {
  std::vector<std::size_t> idx{launch};
  for (std::size_t j = NextGood(marks, launch); j != kNone && track[j].t <= until; j = NextGood(marks, j)) {
    if (marks.near[j] || track[j].t - track[idx.back()].t > options.max_gap) break;
    idx.push_back(j);
  }
  return idx;
}

ChipData MakeChipData(const std::vector<TrackPoint>& track, const BallFitInput& input,
                      const std::vector<std::size_t>& idx) {
  ChipData d;
  for (std::size_t i : idx) {
    d.t.push_back(track[i].t);
    d.p.push_back(At(track[i]));
    d.camera.push_back(input.cameras.at(track[i].camera_id));
    d.w.push_back(1.0);
    d.index.push_back(i);
  }
  return d;
}

// Where and when a chip may have left: the ball's resting place before the launch, and the times
// it may have left it (one when the cameras saw it go, several when the robot hid it).
struct LaunchGuess {
  Vector2d from = Vector2d::Zero();
  std::vector<double> t0;
};

LaunchGuess GuessLaunch(const std::vector<TrackPoint>& track, const TrackMarks& marks, const BallFitOptions& options,
                        std::size_t launch) {
  BallRun probe;
  probe.first = launch;
  probe.t_begin = track[launch].t;
  const std::vector<std::size_t> pre = DetectionsBefore(track, marks, options, probe);
  std::vector<double> xs, ys;
  for (std::size_t k = 0; k < pre.size() / 2; ++k) {
    xs.push_back(track[pre[k]].x);
    ys.push_back(track[pre[k]].y);
  }
  LaunchGuess guess;
  if (xs.size() >= 2) {
    guess.from = Vector2d(Median(xs), Median(ys));
    // It left after the last detection still at rest.
    std::size_t k = 0;
    while (k + 1 < pre.size() && (At(track[pre[k + 1]]) - guess.from).norm() <= 3 * marks.noise + 0.005) ++k;
    if (k + 1 < pre.size() || (At(track[launch]) - guess.from).norm() > 3 * marks.noise + 0.005) {
      guess.t0 = {track[pre[k]].t + 0.005};
      return guess;
    }
  }
  guess.from = At(track[launch]);
  guess.t0 = {probe.t_begin - 0.03, probe.t_begin - 0.1, probe.t_begin - 0.2};
  return guess;
}

// One chip, fitted alone with its own dampings.
struct ChipTrial {
  ChipProblem problem;
  Params x;
  double rms = kInf;      // m, per coordinate, kept detections
  double dropped = 1;     // fraction of detections dropped as outliers
};

const Selection& OneChip() {
  static const Selection kOne{{1}, {1, 1, 1}};
  return kOne;
}

// Fits a chip alone. The landings make the cost rough, so launch speeds are searched on a grid
// first (cost only, dampings at typical values), and the best few followed by Levenberg–Marquardt.
std::optional<ChipTrial> FitOneChip(ChipData data, const LaunchGuess& guess, const GroundLaw& law,
                                    const BallFitOptions& options) {
  const Vector2d to = data.p.back();
  if ((to - guess.from).norm() < 0.1) return std::nullopt;
  const Vector2d dir = (to - guess.from).normalized();
  const double t_first = data.t.front();
  std::vector<ChipData> one{std::move(data)};
  ChipTrial trial{ChipProblem(std::move(one), law, options), {}, kInf, 1};
  auto start_at = [&](double t0, double vh, double vz) {
    Params x;
    x.globals = Vector3d(0.6, 0.75, 0.9);
    // Launched from the resting place; or, hidden, from back along the way it went.
    const Vector2d from = guess.t0.size() == 1 ? guess.from : Vector2d(guess.from - dir * vh * (t_first - t0));
    VectorXd c(kChipParams);
    c << t0, from.x(), from.y(), vh * dir.x(), vh * dir.y(), vz;
    x.locals = {c};
    return std::make_pair(Cost(trial.problem, x, OneChip()), std::move(x));
  };
  // Coarse grid of launch speeds, then a finer one about its three best.
  std::vector<std::pair<double, Params>> coarse, starts;
  for (double t0 : guess.t0) {
    for (double vh = 1.0; vh <= 6.5; vh += 0.5) {
      for (double vz = 1.0; vz <= 6.0; vz += 0.5) coarse.push_back(start_at(t0, vh, vz));
    }
  }
  std::sort(coarse.begin(), coarse.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t k = 0; k < std::min<std::size_t>(3, coarse.size()); ++k) {
    const VectorXd& c = coarse[k].second.locals[0];
    const double t0 = c[kLaunchTime], vh = std::hypot(c[kVx], c[kVy]), vz = c[kVz];
    for (double dh = -0.375; dh <= 0.376; dh += 0.125) {
      for (double dz = -0.375; dz <= 0.376; dz += 0.125) starts.push_back(start_at(t0, vh + dh, vz + dz));
    }
  }
  std::sort(starts.begin(), starts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  // Nothing in the grid comes within a decimetre: no chip (a bounce off a wall, a touch).
  const auto residuals = static_cast<double>(2 * trial.problem.Chip(0).t.size());
  auto rms = [&](double cost) { return std::sqrt(cost / residuals); };
  if (starts.empty() || rms(starts.front().first) > kChipGridGiveUp) return std::nullopt;
  double best = kInf;
  for (std::size_t k = 0; k < std::min<std::size_t>(3, starts.size()) && rms(best) > kChipGoodEnough; ++k) {
    const double cost = Minimise(trial.problem, starts[k].second, OneChip(), 60);
    if (cost < best) {
      best = cost;
      trial.x = starts[k].second;
    }
  }
  return trial;
}

// Sets chip b's number of flights to the best of its choices (its launch refitted for each; with
// `globals_free`, a lone chip's dampings too); true when it changed.
bool ChooseHops(ChipProblem& problem, Params& x, std::size_t b, bool globals_free) {
  ChipData& d = problem.Chip(b);
  const std::vector<int> choices = problem.Choices(x.locals[b], x.globals);
  if (choices.size() == 1) {
    const bool changed = d.hops != choices.front();
    d.hops = choices.front();
    return changed;
  }
  const int before = d.hops;
  double best = kInf;
  Params best_x = x;
  int best_hops = choices.front();
  for (int hops : choices) {
    d.hops = hops;
    Params y = x;
    const double cost = globals_free ? Minimise(problem, y, OneChip(), 40)
                                     : MinimiseBlock(problem, static_cast<int>(b), y.globals, y.locals[b], 40);
    if (cost < best) {
      best = cost;
      best_x = std::move(y);
      best_hops = hops;
    }
  }
  d.hops = best_hops;
  x = std::move(best_x);
  return best_hops != before;
}

// Fixes a lone chip's number of flights (the rule's steps make the cost jump, which
// Levenberg–Marquardt does not cross well), refitting until the choice settles.
void SettleHops(ChipTrial& trial) {
  trial.problem.Chip(0).hops = -1;
  for (int round = 0; round < 4; ++round) {
    if (!ChooseHops(trial.problem, trial.x, 0, true)) return;
  }
}

// Weights (1 kept, 0 outlier) of a chip's detections against the fit, and the rms of the kept.
double ChipOutliers(const ChipProblem& problem, const Params& x, std::size_t b, double noise, double sigmas,
                    std::vector<double>& w) {
  VectorXd r;
  problem.Evaluate(static_cast<int>(b), x.globals, x.locals[b], r, nullptr, nullptr);
  const double sigma = std::max(noise, RobustSigma(std::vector<double>(r.data(), r.data() + r.size())));
  for (std::size_t i = 0; i < w.size(); ++i) {
    w[i] = r.segment<2>(static_cast<Eigen::Index>(2 * i)).cwiseAbs().maxCoeff() <= sigmas * sigma;
  }
  return sigma;
}

double ChipRms(const ChipProblem& problem, const Params& x, std::size_t b) {
  VectorXd r;
  problem.Evaluate(static_cast<int>(b), x.globals, x.locals[b], r, nullptr, nullptr);
  const std::vector<double>& w = problem.Chip(b).w;
  const double kept = std::accumulate(w.begin(), w.end(), 0.0);
  return kept > 0 ? std::sqrt(r.squaredNorm() / (2 * kept)) : kInf;
}

// Drops detections off the chip's fit by more than outlier_sigmas·σ, refits, and measures it.
void CleanChip(ChipTrial& trial, double noise, double sigmas) {
  ChipData& d = trial.problem.Chip(0);
  // Twice: detections judged against a fit that was still moving get a second hearing.
  for (int pass = 0; pass < 2; ++pass) {
    std::fill(d.w.begin(), d.w.end(), 1.0);
    ChipOutliers(trial.problem, trial.x, 0, noise, sigmas, d.w);
    Minimise(trial.problem, trial.x, OneChip(), 40);
  }
  trial.rms = ChipRms(trial.problem, trial.x, 0);
  trial.dropped = 1 - std::accumulate(d.w.begin(), d.w.end(), 0.0) / static_cast<double>(d.w.size());
}

// The run a chip shows as: its detections, launch and flights.
void SetChipRun(const std::vector<TrackPoint>& track, const ChipData& d, const VectorXd& c,
                const BallFitOptions& options, BallRun& run) {
  run.airborne = true;
  run.first = d.index.front();
  run.last = d.index.back() + 1;
  run.t_begin = track[run.first].t;
  run.t_end = track[run.last - 1].t;
  run.points = static_cast<int>(std::accumulate(d.w.begin(), d.w.end(), 0.0));
  run.t_ref = c[kLaunchTime];
  run.x0 = c[kLaunchX];
  run.y0 = c[kLaunchY];
  run.launch_vx = c[kVx];
  run.launch_vy = c[kVy];
  run.launch_vz = c[kVz];
  run.heading = std::atan2(c[kVy], c[kVx]);
  run.start_speed = std::hypot(c[kVx], c[kVy]);
  run.hops = d.hops;
  run.apex = c[kVz] * c[kVz] / (2 * options.gravity);
}

// How far from the ball's carpet point the cameras see it at most: what a flight shows.
double Swing(const ChipProblem& problem, const Params& x) {
  const ChipData& d = problem.Chip(0);
  const int hops = problem.Hops(d, x.locals[0], x.globals);
  double swing = 0;
  for (std::size_t i = 0; i < d.t.size(); ++i) {
    const Vector3d b = ChipAt(d.t[i], x.locals[0], x.globals, hops, problem.law(), problem.gravity());
    swing = std::max(swing, (Reported(d.camera[i], b) - b.head<2>()).norm());
  }
  return swing;
}

// A chip found in the track: its run, detections, and its own fit to start the joint one from.
struct FoundChip {
  BallRun run;
  ChipData data;
  VectorXd launch;
  Vector3d loss = Vector3d::Zero();
  double landed = 0;  // s, its last landing
};

// A run for a launch whose detections name a camera with no known position.
BallRun UnfittableChip(const std::vector<TrackPoint>& track, const std::vector<std::size_t>& idx, int camera) {
  BallRun run;
  run.airborne = true;
  run.first = idx.front();
  run.last = idx.back() + 1;
  run.t_begin = track[run.first].t;
  run.t_end = track[run.last - 1].t;
  run.points = static_cast<int>(idx.size());
  run.reason = Format("possible chip not fitted: no position for camera %d", camera);
  return run;
}

// The hop model fitted to the detections after a launch: first over kChipFirstWindow, then over
// its flights and a short roll-out (later on, walls and robots are the ground fit's business).
std::optional<ChipTrial> FitChipAfter(const std::vector<TrackPoint>& track, const TrackMarks& marks,
                                      const BallFitInput& input, const BallFitOptions& options,
                                      std::size_t launch, std::vector<std::size_t> idx, const GroundLaw& law,
                                      double noise) {
  std::optional<ChipTrial> trial =
      FitOneChip(MakeChipData(track, input, idx), GuessLaunch(track, marks, options, launch), law, options);
  if (!trial) return std::nullopt;
  CleanChip(*trial, noise, options.outlier_sigmas);  // a stray must not steer what follows
  const ChipData& first = trial->problem.Chip(0);
  const int hops = trial->problem.Hops(first, trial->x.locals[0], trial->x.globals);
  const double landed = LastLanding(trial->x.locals[0], trial->x.globals, hops, options.gravity);
  idx = ChipWindow(track, marks, options, launch, std::max(landed, track[launch].t + 0.3) + kChipRollOut);
  if (idx.size() != first.t.size()) {
    trial->problem.Chip(0) = MakeChipData(track, input, idx);
    CleanChip(*trial, noise, options.outlier_sigmas);
  }
  SettleHops(*trial);
  CleanChip(*trial, noise, options.outlier_sigmas);
  return trial;
}

// Tries the chip model on the detections after a launch. nullopt: nothing airborne there;
// otherwise a chip, used when the hop model fits (or rejected, saying why).
std::optional<FoundChip> TryChip(const std::vector<TrackPoint>& track, const TrackMarks& marks,
                                 const BallFitInput& input, const BallFitOptions& options, std::size_t launch,
                                 const GroundLaw& law, double noise) {
  const std::vector<std::size_t> idx =
      ChipWindow(track, marks, options, launch, track[launch].t + kChipFirstWindow);
  if (static_cast<int>(idx.size()) < options.min_points) return std::nullopt;
  FoundChip chip;
  for (std::size_t i : idx) {
    if (input.cameras.count(track[i].camera_id)) continue;
    chip.run = UnfittableChip(track, idx, track[i].camera_id);
    chip.run.begins = marks.near[PreviousGood(marks, launch)] ? "robot" : "kick";
    return chip;
  }
  const std::optional<ChipTrial> trial = FitChipAfter(track, marks, input, options, launch, idx, law, noise);
  if (!trial) return std::nullopt;
  chip.data = trial->problem.Chip(0);
  chip.launch = trial->x.locals[0];
  chip.loss = trial->x.globals;
  chip.landed = LastLanding(chip.launch, chip.loss, chip.data.hops, options.gravity);
  SetChipRun(track, chip.data, chip.launch, options, chip.run);
  // Airborne only if the flight shows: its apex, and how far the cameras see it off the carpet. A
  // fit that bounces on and on (damping_z near 1) is a ball on the carpet the hops imitate, and one
  // far off the detections is no near miss worth reporting.
  const double limit = std::max(1.5 * noise, noise + 0.002);
  if (chip.run.apex < options.chip_min_apex || Swing(trial->problem, trial->x) < std::max(6 * noise, 0.015) ||
      chip.loss[0] > 0.9 || chip.data.hops >= 12 || trial->rms > 5 * limit) {
    return std::nullopt;
  }
  chip.run.begins = marks.near[PreviousGood(marks, launch)] ? "robot" : "kick";
  chip.run.ends = "rolling";
  chip.run.rms = trial->rms;
  const double first_landing = chip.launch[kLaunchTime] + 2 * chip.launch[kVz] / options.gravity;
  if (trial->rms > limit || trial->dropped > 0.05) {
    chip.run.reason = Format("airborne, but the hop model does not fit: rms %.1f mm (noise %.1f mm), %.0f %% of "
                             "the detections off it", 1e3 * trial->rms, 1e3 * noise, 100 * trial->dropped);
  } else if (first_landing > chip.run.t_end) {
    chip.run.reason = "airborne, but its first landing is not seen";
  }
  return chip;
}

// Ground runs under a chip's flight are no ground runs: cut to what follows its last landing, or
// rejected.
void TakeOutFlight(const std::vector<TrackPoint>& track, const TrackMarks& marks, const BallFitOptions& options,
                   const FoundChip& chip, std::vector<BallRun>& runs) {
  const double ground_from = chip.landed + kChipGroundMargin;
  for (BallRun& run : runs) {
    if (run.airborne || run.t_end < chip.run.t_begin || run.t_begin >= ground_from) continue;
    const std::size_t first = FirstAtOrAfter(track, ground_from);
    if (first < run.last && track[run.last - 1].t - ground_from >= options.min_duration) {
      run.first = first;
      run.begins = "chip landing";
      run.kick_seen = false;
      Describe(track, marks, options, run);
    } else {
      run.used = false;
      run.reason = Format("airborne: part of the chip launched at t = %.2f s", chip.run.t_ref);
    }
  }
}

// The chips: launches the ground law does not explain, tried with the hop model. Ground runs under
// a chip's flight are taken out; every tried chip is added to the runs.
std::vector<FoundChip> FindChips(const std::vector<TrackPoint>& track, const TrackMarks& marks,
                                 const BallFitInput& input, const BallFitOptions& options, const GroundLaw& law,
                                 double noise, std::vector<BallRun>& runs) {
  std::vector<double> rms;
  for (const BallRun& run : runs) {
    if (run.used) rms.push_back(run.rms);
  }
  const double typical = rms.empty() ? noise : Median(rms);
  std::vector<FoundChip> chips;
  std::vector<BallRun> tried_runs;
  double busy_until = -kInf;
  for (std::size_t launch : Launches(track, marks, options)) {
    if (track[launch].t < busy_until || Explained(runs, track[launch].t, typical)) continue;
    std::optional<FoundChip> chip = TryChip(track, marks, input, options, launch, law, noise);
    if (!chip) continue;
    busy_until = chip->run.t_end;  // one trial per flight, even when a later launch point is in it
    if (chip->run.reason.empty()) {
      TakeOutFlight(track, marks, options, *chip, runs);
      chips.push_back(*chip);
    } else {
      tried_runs.push_back(chip->run);
    }
  }
  runs.insert(runs.end(), tried_runs.begin(), tried_runs.end());
  return chips;
}

// Landings a chip's detections show (flights that ended before its last detection).
int LandingsSeen(const FoundChip& chip, const VectorXd& c, const VectorXd& loss, double g) {
  int seen = 0;
  double t = c[kLaunchTime], vz = c[kVz];
  for (int i = 0; i < chip.data.hops; ++i, vz *= loss[0]) {
    t += 2 * vz / g;
    if (t < chip.data.t.back() - 0.05) ++seen;
  }
  return seen;
}

// ---------------------------------------------------------------------------------- estimates

Estimate MakeEstimate(double value, double half_width, int samples) {
  if (!std::isfinite(value) || !std::isfinite(half_width) || samples <= 0) return {};
  return {value, value - half_width, value + half_width, samples};
}

// Half-width of a 95 % interval: the formal one, or the jackknife's when that is wider.
double HalfWidth(double formal_variance, double jackknife_variance, int groups) {
  double half = kZ95 * std::sqrt(std::max(0.0, formal_variance));
  if (groups >= 4) half = std::max(half, StudentT95(groups - 1) * std::sqrt(std::max(0.0, jackknife_variance)));
  return half;
}

// An estimate of a function of the globals, by the delta method with gradient `grad`.
Estimate Derived(double value, const Vector3d& grad, const GroundResult& ground, int samples) {
  const double formal = grad.dot(ground.covariance * grad);
  const double jack = grad.dot(ground.jackknife * grad);
  return MakeEstimate(value, HalfWidth(formal, jack, ground.jackknife_groups), samples);
}

// The league's two-phase estimates and the ÜberSim contact parameters that produce them:
// acc_slide = −μ·g, k_switch = 1/(1+k), acc_roll = −ρ·g/((1+k)·r) = −ρ·g·k_switch/r.
void GroundEstimates(const GroundResult& ground, const BallFitInput& input, const BallFitOptions& options,
                     BallFit& fit) {
  const Vector3d g = ground.x.globals;
  const std::array<int, 3>& n = ground.informers;
  Estimate* out[] = {&fit.acc_slide, &fit.acc_roll, &fit.k_switch};
  for (std::size_t j = 0; j < 3; ++j) {
    const auto k = static_cast<Eigen::Index>(j);
    *out[j] = Derived(g[k], Vector3d::Unit(k), ground, ground.sel.globals[j] ? n[j] : 0);
  }
  const double grav = options.gravity, r = input.ball_radius;
  fit.mu = Derived(-g[0] / grav, Vector3d(-1 / grav, 0, 0), ground, fit.acc_slide.samples);
  fit.inertia_factor = Derived(1 / g[2] - 1, Vector3d(0, 0, -1 / (g[2] * g[2])), ground, fit.k_switch.samples);
  const double rho = -g[1] * r / (grav * g[2]);
  fit.rolling_friction = Derived(rho, Vector3d(0, -r / (grav * g[2]), g[1] * r / (grav * g[2] * g[2])), ground,
                                 std::min(fit.acc_roll.samples, fit.k_switch.samples));
  const char* what[] = {"acc_slide not estimated (nor mu)", "acc_roll not estimated (nor rolling_friction)",
                        "k_switch not estimated (nor inertia_factor, rolling_friction)"};
  const char* needs[] = {"sliding for 5 detections", "rolling for 0.2 s",
                         "starting at a dated kick and sliding into rolling"};
  for (std::size_t j = 0; j < 3; ++j) {
    if (!ground.sel.globals[j]) fit.problems.push_back(Format("no used run was seen %s: %s", needs[j], what[j]));
  }
}

// Solves the joint chip problem, each chip's number of flights following the hop-height rule at
// the joint dampings (or the data, where the rule is borderline).
void SolveChips(ChipProblem& problem, Params& x, const Selection& sel) {
  for (int round = 0; round < 4; ++round) {
    // Each launch to its best first (each with its own damping), then all together.
    for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
      if (sel.blocks[b]) MinimiseBlock(problem, static_cast<int>(b), x.globals, x.locals[b], 30);
    }
    Minimise(problem, x, sel, 50);
    bool changed = false;
    for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
      if (sel.blocks[b]) changed = ChooseHops(problem, x, b, false) || changed;
    }
    if (!changed) return;
  }
}

// Which dampings the used chips show: a first landing seen (xy first hop), a second (z, other hops).
std::array<int, 3> ChipInformers(const std::vector<FoundChip>& chips, const Params& x, const Selection& sel,
                                 double g) {
  std::array<int, 3> informers{};
  for (std::size_t b = 0; b < chips.size(); ++b) {
    if (!sel.blocks[b]) continue;
    const int seen = LandingsSeen(chips[b], x.locals[b], x.globals, g);
    informers[0] += seen >= 2;
    informers[1] += seen >= 1;
    informers[2] += seen >= 2;
  }
  return informers;
}

// Covariance σ²(JᵀJ)⁻¹ of the dampings, σ² from the used chips' residuals.
Eigen::Matrix3d ChipCovariance(const ChipProblem& problem, const Params& x, const Selection& sel) {
  double ss = 0, kept = 0, params = 3;
  for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
    if (!sel.blocks[b]) continue;
    VectorXd r;
    problem.Evaluate(static_cast<int>(b), x.globals, x.locals[b], r, nullptr, nullptr);
    ss += r.squaredNorm();
    for (double w : problem.Chip(b).w) kept += 2 * w;
    params += static_cast<double>(kChipParams);
  }
  const double sigma2 = kept > params ? ss / (kept - params) : kNaN;
  MatrixXd info = Information(problem, x, sel);
  for (std::size_t j = 0; j < 3; ++j) {
    if (sel.globals[j]) continue;
    info.row(static_cast<Eigen::Index>(j)).setZero();
    info.col(static_cast<Eigen::Index>(j)).setZero();
    info(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j)) = 1;
  }
  Eigen::Matrix3d cov = sigma2 * info.inverse();
  for (std::size_t j = 0; j < 3; ++j) {
    if (sel.globals[j]) continue;
    cov.row(static_cast<Eigen::Index>(j)).setZero();
    cov.col(static_cast<Eigen::Index>(j)).setZero();
  }
  return cov;
}

// Delete-one jackknife over the used chips (from four on): what differs from chip to chip beyond
// the detection noise (spin, the carpet, the ground law the flights end in) shows here.
Eigen::Matrix3d ChipJackknife(ChipProblem& problem, const Params& x, const Selection& sel, int& replicates) {
  std::vector<Vector3d> estimates;
  for (std::size_t b = 0; b < sel.blocks.size(); ++b) {
    if (!sel.blocks[b]) continue;
    Selection without = sel;
    without.blocks[b] = 0;
    Params y = x;
    Minimise(problem, y, without, 15);
    estimates.push_back(y.globals.head<3>());
  }
  replicates = static_cast<int>(estimates.size());
  if (replicates < 4) return Eigen::Matrix3d::Zero();
  const auto n = static_cast<double>(replicates);
  Vector3d mean = Vector3d::Zero();
  for (const Vector3d& e : estimates) mean += e / n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Vector3d& e : estimates) cov += (e - mean) * (e - mean).transpose();
  return cov * (n - 1) / n;
}

// Chips that fit the shared dampings much worse than their own are left out (the worst first,
// one at a time, as one odd chip can drag the shared values and make the others look bad).
bool JudgeChips(const ChipProblem& problem, const Params& x, Selection& sel, std::vector<FoundChip>& chips) {
  std::size_t worst = kNone;
  double worst_ratio = 1;
  for (std::size_t b = 0; b < chips.size(); ++b) {
    if (!sel.blocks[b]) continue;
    const double own = chips[b].run.rms, shared = ChipRms(problem, x, b);
    const double ratio = shared / std::max(2 * own, own + 0.002);
    if (ratio > worst_ratio) {
      worst = b;
      worst_ratio = ratio;
    }
  }
  if (worst == kNone) return false;
  sel.blocks[worst] = 0;
  chips[worst].run.reason = Format("does not fit the dampings the other chips share: rms %.1f mm (%.1f mm alone)",
                                   1e3 * ChipRms(problem, x, worst), 1e3 * chips[worst].run.rms);
  return true;
}

// The dampings over all chips at once (globals), each chip's launch its own block; intervals from
// the covariance, widened to the chips' jackknife when that is larger.
void FitChipsJointly(const std::vector<TrackPoint>& track, std::vector<FoundChip>& chips, const GroundLaw& law,
                     const BallFitOptions& options, BallFit& fit) {
  if (chips.empty()) return;
  std::vector<ChipData> data;
  Params x;
  std::vector<double> dz, d1, d2;
  for (const FoundChip& chip : chips) {
    data.push_back(chip.data);
    x.locals.push_back(chip.launch);
    dz.push_back(chip.loss[0]);
    d1.push_back(chip.loss[1]);
    d2.push_back(chip.loss[2]);
  }
  x.globals = Vector3d(Median(dz), Median(d1), Median(d2));
  ChipProblem problem(std::move(data), law, options);
  Selection sel{std::vector<char>(chips.size(), 1), {1, 1, 1}};
  for (std::size_t round = 0; round < chips.size(); ++round) {
    SolveChips(problem, x, sel);
    if (!JudgeChips(problem, x, sel, chips)) break;
  }
  // Dampings no used chip shows are held at the league's defaults and not estimated.
  const std::array<int, 3> informers = ChipInformers(chips, x, sel, options.gravity);
  const Vector3d defaults(kDefaultDampingZ, kDefaultDampingFirst, kDefaultDampingOther);
  for (std::size_t j = 0; j < 3; ++j) {
    if (informers[j] > 0) continue;
    sel.globals[j] = 0;
    x.globals[static_cast<Eigen::Index>(j)] = defaults[static_cast<Eigen::Index>(j)];
  }
  SolveChips(problem, x, sel);
  const Eigen::Matrix3d cov = ChipCovariance(problem, x, sel);
  int replicates = 0;
  const Eigen::Matrix3d jack = ChipJackknife(problem, x, sel, replicates);
  Estimate* out[] = {&fit.damping_z, &fit.damping_xy_first_hop, &fit.damping_xy_other_hops};
  for (std::size_t j = 0; j < 3; ++j) {
    const auto k = static_cast<Eigen::Index>(j);
    *out[j] = MakeEstimate(x.globals[k], HalfWidth(cov(k, k), jack(k, k), replicates),
                           sel.globals[j] ? informers[j] : 0);
  }
  for (std::size_t b = 0; b < chips.size(); ++b) {
    chips[b].data = problem.Chip(b);
    chips[b].launch = x.locals[b];
    SetChipRun(track, problem.Chip(b), x.locals[b], options, chips[b].run);
    chips[b].run.rms = ChipRms(problem, x, b);
    chips[b].run.used = sel.blocks[b];
  }
}

// ------------------------------------------------------------------------------------ the whole fit

// The ball track in time order, non-finite detections dropped (the order BallRun indices refer to).
std::vector<TrackPoint> TimeOrdered(const std::vector<TrackPoint>& ball) {
  std::vector<TrackPoint> track;
  track.reserve(ball.size());
  for (const TrackPoint& p : ball) {
    if (std::isfinite(p.t) && std::isfinite(p.x) && std::isfinite(p.y)) track.push_back(p);
  }
  auto earlier = [](const TrackPoint& a, const TrackPoint& b) { return a.t < b.t; };
  if (!std::is_sorted(track.begin(), track.end(), earlier)) std::stable_sort(track.begin(), track.end(), earlier);
  return track;
}

int CountUsable(const std::vector<BallRun>& runs) {
  return static_cast<int>(
      std::count_if(runs.begin(), runs.end(), [](const BallRun& r) { return !r.airborne && r.reason.empty(); }));
}

int CountUsed(const std::vector<BallRun>& runs) {
  return static_cast<int>(
      std::count_if(runs.begin(), runs.end(), [](const BallRun& r) { return !r.airborne && r.used; }));
}

double UsedRms(const std::vector<BallRun>& runs) {
  double ss = 0, n = 0;
  for (const BallRun& r : runs) {
    if (r.airborne || !r.used) continue;
    ss += r.rms * r.rms * r.points;
    n += r.points;
  }
  return n > 0 ? std::sqrt(ss / n) : 0;
}

bool TooFewUsed(const std::vector<BallRun>& runs, const BallFitOptions& options, BallFit& fit) {
  const int used = CountUsed(runs);
  if (used >= options.min_runs) return false;
  fit.problems.push_back(Format("only %d runs follow the two-phase law (need %d)", used, options.min_runs));
  return true;
}

}  // namespace

BallFit FitBall(const BallFitInput& input, const BallFitOptions& options) {
  BallFit fit;
  const std::vector<TrackPoint> track = TimeOrdered(input.ball);
  if (static_cast<int>(track.size()) < std::max(options.min_points, 20)) {
    fit.problems.push_back(Format("the ball track has only %zu detections", track.size()));
    return fit;
  }
  const TrackMarks marks = MarkTrack(track, input, options);
  fit.noise = marks.noise;
  std::vector<KickPoint> kicks;
  fit.runs = CandidateRuns(track, marks, input, options, kicks);
  auto by_time = [](const BallRun& a, const BallRun& b) { return a.t_begin < b.t_begin; };
  const int usable = CountUsable(fit.runs);
  if (usable < std::max(options.min_runs, 1)) {
    fit.problems.push_back(Format("only %d free runs longer than %.2f s (need %d)", usable, options.min_duration,
                                  options.min_runs));
    return fit;
  }
  GroundResult ground = FitGround(track, marks, options, fit.runs, kicks, GroundLaw{}, false);
  if (TooFewUsed(fit.runs, options, fit)) return fit;
  const double noise = std::isfinite(ground.sigma) ? ground.sigma : marks.noise;
  std::vector<FoundChip> chips = FindChips(track, marks, input, options, LawOf(ground.x.globals), noise, fit.runs);
  // Again without the flights, now with intervals.
  ground = FitGround(track, marks, options, fit.runs, kicks, LawOf(ground.x.globals), true);
  if (TooFewUsed(fit.runs, options, fit)) {
    for (FoundChip& chip : chips) {
      chip.run.used = false;
      chip.run.reason = "not fitted: too few ground runs for the roll after the hops";
      fit.runs.push_back(chip.run);
    }
    std::stable_sort(fit.runs.begin(), fit.runs.end(), by_time);
    return fit;
  }
  fit.enough_data = true;
  fit.rms_residual = UsedRms(fit.runs);
  GroundEstimates(ground, input, options, fit);
  FitChipsJointly(track, chips, LawOf(ground.x.globals), options, fit);
  for (FoundChip& chip : chips) fit.runs.push_back(chip.run);
  std::stable_sort(fit.runs.begin(), fit.runs.end(), by_time);
  return fit;
}

// ----------------------------------------------------------------------------------------- report

namespace {

std::string Number(double v, int digits) {
  if (!std::isfinite(v)) return "–";
  return Format("%.*f", digits, v);
}

// "| name | value | [low, high] | samples | note |"
std::string EstimateRow(const std::string& name, const Estimate& e, const std::string& unit, int digits,
                        const std::string& note) {
  if (!e.ok()) return "| " + name + " | not estimated | | 0 | " + note + " |\n";
  return "| " + name + " | " + Number(e.value, digits) + (unit.empty() ? "" : " " + unit) + " | [" +
         Number(e.low, digits) + ", " + Number(e.high, digits) + "] | " + std::to_string(e.samples) + " | " + note +
         " |\n";
}

// Up to `count` runs of `pool` spread evenly over their speeds.
std::vector<const BallRun*> SpreadOverSpeed(std::vector<const BallRun*> pool, std::size_t count) {
  std::sort(pool.begin(), pool.end(), [](const BallRun* a, const BallRun* b) { return a->v_ref < b->v_ref; });
  if (pool.size() <= count) return pool;
  std::vector<const BallRun*> out;
  for (std::size_t k = 0; k < count; ++k) {
    out.push_back(pool[k * (pool.size() - 1) / std::max<std::size_t>(1, count - 1)]);
  }
  return out;
}

// The runs the report draws: up to three after dated kicks and one more, over the speeds seen.
std::vector<const BallRun*> SampleRuns(const BallFit& fit) {
  std::vector<const BallRun*> kicked, other;
  for (const BallRun& r : fit.runs) {
    if (r.used && !r.airborne) (r.kick_seen ? kicked : other).push_back(&r);
  }
  std::vector<const BallRun*> sample = SpreadOverSpeed(kicked, 3);
  for (const BallRun* r : SpreadOverSpeed(other, 4 - sample.size())) sample.push_back(r);
  return sample;
}

double ModelAlong(const BallRun& run, const BallFit& fit, double t) {
  return TwoPhase(t - run.t_ref, run.s_ref, run.v_ref, run.slide_time, fit.acc_slide.value, fit.acc_roll.value).s;
}

// A run's detections near its fitted law (strays left out), as (t, s) along its line.
std::vector<std::pair<double, double>> RunDetections(const std::vector<TrackPoint>& track, const BallRun& run,
                                                     const BallFit& fit) {
  const Line line = LineOf(run);
  const double limit = std::max(0.02, 6 * std::max(fit.noise, fit.rms_residual));
  std::vector<std::pair<double, double>> out;
  for (std::size_t i = run.first; i < run.last && i < track.size(); ++i) {
    const double s = line.Along(At(track[i]));
    if (std::abs(s - ModelAlong(run, fit, track[i].t)) <= limit) out.emplace_back(track[i].t, s);
  }
  return out;
}

// Measured speed along the run (local line fits over ±0.05 s, one every 0.04 s) and the law's.
void SpeedSeries(const std::vector<TrackPoint>& track, const BallRun& run, const BallFit& fit,
                 validation::Series& data, validation::Series& law) {
  const auto det = RunDetections(track, run, fit);
  double next = -kInf;
  for (std::size_t i = 0; i < det.size(); ++i) {
    if (det[i].first < next) continue;
    double st = 0, ss = 0, stt = 0, sts = 0, n = 0;
    for (const auto& [t, s] : det) {
      if (std::abs(t - det[i].first) > 0.05) continue;
      const double tau = t - det[i].first;
      st += tau, ss += s, stt += tau * tau, sts += tau * s, n += 1;
    }
    const double spread = stt - st * st / n;
    if (n < 5 || spread <= 0) continue;
    data.x.push_back(det[i].first - run.t_ref);
    data.y.push_back((sts - st * ss / n) / spread);
    next = det[i].first + 0.04;
  }
  for (double t = std::max(run.t_ref, run.t_begin - 0.1); t <= run.t_end; t += 0.01) {
    law.x.push_back(t - run.t_ref);
    law.y.push_back(TwoPhaseSpeed(t - run.t_ref, run.v_ref, run.slide_time, fit.acc_slide.value, fit.acc_roll.value));
  }
}

// One run's speed along its line: from the detections, and by the fitted law.
validation::Plot SpeedPlot(const std::vector<TrackPoint>& track, const BallFit& fit, const BallRun& run, int number) {
  validation::Plot plot;
  plot.file = Format("ball-run-%d.svg", number);
  plot.title = run.kick_seen ? Format("Run at t = %.1f s: kicked at %.2f m/s, slides %.2f s, then rolls", run.t_begin,
                                      run.v_ref, run.slide_time)
                             : Format("Run at t = %.1f s (%s): slides %.2f s more, then rolls", run.t_begin,
                                      run.begins.c_str(), run.slide_time);
  plot.x_label = run.kick_seen ? "time since the kick, s" : "time since the run's first detection, s";
  plot.y_label = "speed along the run, m/s";
  validation::Series data{"detections (0.1 s line fits)", {}, {}}, law{"fitted two-phase law", {}, {}};
  data.points = true;
  SpeedSeries(track, run, fit, data, law);
  plot.series = {data, law};
  return plot;
}

validation::Plot ResidualPlot(const std::vector<TrackPoint>& track, const BallFit& fit) {
  validation::Plot plot;
  plot.file = "ball-residuals.svg";
  plot.title = "Residuals of the used runs along their lines";
  plot.x_label = "time since the kick (or the run's start), s";
  plot.y_label = "detection − fit, mm";
  validation::Series kicked{"dated kick", {}, {}}, other{"other start", {}, {}};
  kicked.points = other.points = true;
  std::size_t total = 0;
  for (const BallRun& r : fit.runs) total += r.used && !r.airborne ? static_cast<std::size_t>(r.points) : 0;
  const std::size_t stride = std::max<std::size_t>(1, total / 4000);
  std::size_t k = 0;
  for (const BallRun& r : fit.runs) {
    if (!r.used || r.airborne) continue;
    for (const auto& [t, s] : RunDetections(track, r, fit)) {
      if (k++ % stride) continue;
      validation::Series& out = r.kick_seen ? kicked : other;
      out.x.push_back(t - r.t_ref);
      out.y.push_back(1e3 * (s - ModelAlong(r, fit, t)));
    }
  }
  plot.series = {kicked, other};
  return plot;
}

// A chip's detections on the carpet, where the fit says the cameras saw it, and the ball beneath.
validation::Plot ChipPlot(const std::vector<TrackPoint>& track, const BallFitInput& input, const BallFit& fit,
                          const BallRun& chip, int number) {
  validation::Plot plot;
  plot.file = Format("ball-chip-%d.svg", number);
  plot.title = Format("Chip at t = %.2f s: detections and the fitted hops", chip.t_ref);
  plot.x_label = "x, m";
  plot.y_label = "y, m";
  plot.equal_axes = true;
  validation::Series seen{"detections", {}, {}}, model{"fit, as the cameras see it", {}, {}},
      ground{"ball below (fit)", {}, {}, true};
  seen.points = true;
  VectorXd c(kChipParams), loss(3);
  c << chip.t_ref, chip.x0, chip.y0, chip.launch_vx, chip.launch_vy, chip.launch_vz;
  loss << fit.damping_z.value, fit.damping_xy_first_hop.value, fit.damping_xy_other_hops.value;
  const GroundLaw law{fit.acc_slide.value, fit.acc_roll.value, fit.k_switch.value};
  const double g = 9.81;
  for (std::size_t i = chip.first; i < chip.last && i < track.size(); ++i) {
    seen.x.push_back(track[i].x);
    seen.y.push_back(track[i].y);
    const auto cam = input.cameras.find(track[i].camera_id);
    if (cam == input.cameras.end()) continue;
    const Vector3d b = ChipAt(track[i].t, c, loss, chip.hops, law, g);
    const Vector2d p = Reported(cam->second, b);
    model.x.push_back(p.x());
    model.y.push_back(p.y());
    ground.x.push_back(b.x());
    ground.y.push_back(b.y());
  }
  plot.series = {seen, model, ground};
  return plot;
}

// Rejection reasons counted by their wording up to the colon.
std::map<std::string, int> Outcomes(const BallFit& fit) {
  std::map<std::string, int> count;
  for (const BallRun& r : fit.runs) {
    const std::string kind = r.airborne ? "chip" : "ground run";
    count[r.used ? "used (" + kind + ")" : kind + ": " + r.reason.substr(0, r.reason.find(':'))] += 1;
  }
  return count;
}

std::string RunRow(const BallRun& r) {
  const std::string kind = r.airborne ? Format("chip, %d hops, apex %.2f m", r.hops, r.apex)
                                      : (r.kick_seen ? "rolling, dated kick" : "rolling");
  return Format("| %.2f | %.2f | %d | %.2f | %s | %s → %s | %s | %s |\n", r.t_begin, r.t_end - r.t_begin, r.points,
                r.start_speed, kind.c_str(), r.begins.c_str(), r.ends.c_str(),
                r.rms > 0 && std::isfinite(r.rms) ? Number(1e3 * r.rms, 1).c_str() : "–",
                r.used ? "used" : r.reason.c_str());
}

std::string RunsTable(const BallFit& fit) {
  std::ostringstream md;
  md << "#### Runs\n\n| Outcome | Runs |\n|---|---|\n";
  for (const auto& [what, n] : Outcomes(fit)) md << "| " << what << " | " << n << " |\n";
  md << "\n| t (s) | duration (s) | detections | start speed (m/s) | kind | begins → ends | rms (mm) | outcome |\n"
        "|---|---|---|---|---|---|---|---|\n";
  int used = 0, rejected = 0, skipped = 0;
  for (const BallRun& r : fit.runs) {
    int& shown = r.used ? used : rejected;
    if (shown >= 30) {
      ++skipped;
      continue;
    }
    ++shown;
    md << RunRow(r);
  }
  if (skipped > 0) md << "\n" << skipped << " more runs not listed (30 used and 30 rejected are).\n";
  return md.str();
}

std::string GroundSection(const BallFit& fit) {
  std::ostringstream md;
  md << "#### Two-phase model (league `straight_two_phase`)\n\n"
        "| Parameter | Value | 95 % interval | Runs | |\n|---|---|---|---|---|\n"
     << EstimateRow("acc_slide", fit.acc_slide, "m/s²", 3, "sliding deceleration")
     << EstimateRow("acc_roll", fit.acc_roll, "m/s²", 4, "rolling deceleration")
     << EstimateRow("k_switch", fit.k_switch, "", 4, "rolls from k_switch × kick speed")
     << "\n#### ÜberSim ball parameters (models/balls)\n\n"
        "| Parameter | Value | 95 % interval | Runs | From |\n|---|---|---|---|---|\n"
     << EstimateRow("surface.mu", fit.mu, "", 4, "acc_slide = −μ·g")
     << EstimateRow("surface.rolling_friction", fit.rolling_friction, "m", 6, "acc_roll = −ρ·g/((1+k)·r)")
     << EstimateRow("inertia_factor", fit.inertia_factor, "", 3, "k_switch = 1/(1+k), I = k·m·r²") << "\n";
  if (fit.mu.ok() && fit.rolling_friction.ok() && fit.inertia_factor.ok()) {
    md << "```yaml\ninertia_factor: " << Number(fit.inertia_factor.value, 3) << "\nsurface:\n  mu: "
       << Number(fit.mu.value, 4) << "\n  rolling_friction: " << Number(fit.rolling_friction.value, 6) << "\n```\n\n";
  }
  return md.str();
}

std::string ChipSection(const BallFit& fit) {
  std::ostringstream md;
  md << "#### Chips (league `chip_fixed_loss`)\n\n";
  if (!fit.damping_z.ok() && !fit.damping_xy_first_hop.ok() && !fit.damping_xy_other_hops.ok()) {
    md << "No chip was found and fitted, so the dampings are not estimated.\n\n";
    return md.str();
  }
  md << "| Parameter | Value | 95 % interval | Chips | |\n|---|---|---|---|---|\n"
     << EstimateRow("damping_z", fit.damping_z, "", 3, "vertical speed kept at a landing")
     << EstimateRow("damping_xy_first_hop", fit.damping_xy_first_hop, "", 3, "horizontal speed kept, first landing")
     << EstimateRow("damping_xy_other_hops", fit.damping_xy_other_hops, "", 3, "horizontal speed kept, later landings")
     << "\n";
  return md.str();
}

// The opening lines: what the log gave, and what went wrong.
std::string Summary(const BallFit& fit, const BallFitInput& input) {
  auto count = [&](auto pred) { return static_cast<int>(std::count_if(fit.runs.begin(), fit.runs.end(), pred)); };
  const int used = CountUsed(fit.runs);
  const int kicks = count([](const BallRun& r) { return r.used && !r.airborne && r.kick_seen; });
  const int chips = count([](const BallRun& r) { return r.used && r.airborne; });
  std::ostringstream md;
  md << "### Ball\n\n";
  if (!input.source.empty()) md << "Log: `" << input.source << "`. ";
  md << Format("%zu candidate runs; %d ground runs used (%d start at a dated kick), %d chips. ", fit.runs.size(), used,
               kicks, chips)
     << Format("Detection noise σ ≈ %.1f mm; rms of the used runs under the fit %.1f mm.\n\n", 1e3 * fit.noise,
               1e3 * fit.rms_residual);
  if (!fit.problems.empty()) {
    md << "**Problems:**\n\n";
    for (const std::string& p : fit.problems) md << "- " << p << "\n";
    md << "\n";
  }
  return md.str();
}

// The figures: a few runs' speeds under the law, all residuals, up to two chips.
std::vector<validation::Plot> Plots(const std::vector<TrackPoint>& track, const BallFitInput& input,
                                   const BallFit& fit) {
  std::vector<validation::Plot> plots;
  int number = 0;
  for (const BallRun* run : SampleRuns(fit)) plots.push_back(SpeedPlot(track, fit, *run, ++number));
  plots.push_back(ResidualPlot(track, fit));
  number = 0;
  for (const BallRun& r : fit.runs) {
    if (r.used && r.airborne && number < 2) plots.push_back(ChipPlot(track, input, fit, r, ++number));
  }
  return plots;
}

}  // namespace

ReportSection BallReport(const BallFit& fit, const BallFitInput& input) {
  ReportSection section;
  std::ostringstream md;
  md << Summary(fit, input);
  if (fit.enough_data) {
    md << GroundSection(fit) << ChipSection(fit) << "#### The fit over the data\n\n";
    section.plots = Plots(TimeOrdered(input.ball), input, fit);
    for (const validation::Plot& p : section.plots) md << "![" << p.title << "](" << p.file << ")\n\n";
  } else {
    md << "Not enough data for a ball fit: no estimates.\n\n";
  }
  if (!fit.runs.empty()) md << RunsTable(fit);
  section.markdown = md.str();
  return section;
}

}  // namespace ubersim::calibrate
