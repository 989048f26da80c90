// SPDX-License-Identifier: Apache-2.0
// The robot fit: see robot_fit.hpp for the model and the method.
#include "robot_fit.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "track_smoothing.hpp"

namespace ubersim::calibrate {

const char* AxisName(MotionAxis axis) {
  switch (axis) {
    case MotionAxis::kForward: return "forward";
    case MotionAxis::kLeft: return "left";
    case MotionAxis::kAngular: return "angular";
  }
  return "?";
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool Linear(MotionAxis axis) { return axis != MotionAxis::kAngular; }

std::string Format(const char* format, double a) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, format, a);
  return buffer;
}

std::string Format(const char* format, double a, double b) {
  char buffer[128];
  std::snprintf(buffer, sizeof buffer, format, a, b);
  return buffer;
}

// ---------------------------------------------------------------------------------------------
// Statistics

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  const double upper = v[mid];
  if (v.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid)));
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double position = q * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(position);
  if (i + 1 >= v.size()) return v.back();
  return v[i] + (position - static_cast<double>(i)) * (v[i + 1] - v[i]);
}

// The median of per-segment values and a 95 % interval for it from their spread: from six values
// on the distribution-free order-statistic interval (the ranks a Binomial(n, ½) puts 2.5 % beyond
// on each side); from two to five a t-interval with the median's standard error (1.2533 s/√n);
// one value gives a zero-width interval.
Estimate Combine(std::vector<double> values) {
  Estimate e;
  const int n = static_cast<int>(values.size());
  if (n == 0) return e;
  std::sort(values.begin(), values.end());
  e.value = Median(values);
  e.samples = n;
  e.low = e.high = e.value;
  if (n == 1) return e;
  if (n < 6) {
    static constexpr std::array<double, 5> kT975 = {0, 12.706, 4.303, 3.182, 2.776};
    const double mean = std::accumulate(values.begin(), values.end(), 0.0) / n;
    double ss = 0;
    for (double v : values) ss += (v - mean) * (v - mean);
    const double se = 1.2533 * std::sqrt(ss / (n - 1)) / std::sqrt(static_cast<double>(n));
    e.low = e.value - kT975[static_cast<std::size_t>(n - 1)] * se;
    e.high = e.value + kT975[static_cast<std::size_t>(n - 1)] * se;
    return e;
  }
  double cumulative = 0;
  int j = 1;
  for (int k = 0; k < n; ++k) {
    cumulative += std::exp(std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0) -
                           n * std::log(2.0));
    if (2 * cumulative > 0.05) break;
    j = k + 1;
  }
  e.low = values[static_cast<std::size_t>(j - 1)];
  e.high = values[static_cast<std::size_t>(n - j)];
  return e;
}

// The limits without commands: the upper half of the slopes (a game's planner often asks less
// than the robot can), combined as above; under eight values all of them (a short ramp's slope is
// noisy, and the upper half of a few would be the noisiest).
Estimate CombineUpper(std::vector<double> values) {
  if (values.size() < 8) return Combine(std::move(values));
  std::sort(values.begin(), values.end());
  return Combine(std::vector<double>(values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end()));
}

// ---------------------------------------------------------------------------------------------
// The ramp model on one component
//
// The setpoint holds v0, ramps straight from `onset` for `duration`, then holds; the motion follows
// it through a first-order lag τ. Its position is p(t) = c_camera + v0·(t − t_ref) + slope·G(t),
// G(t) = Q(t − onset) − Q(t − onset − duration), Q the double integral of a unit ramp seen through
// the lag. Linear in the per-camera offsets, v0 and slope; onset and duration are searched.

// ∫₀ᵘ (the unit ramp through a first-order lag τ): u²/2 − τu + τ²(1 − e^(−u/τ)) for u > 0.
double LaggedRampIntegral(double u, double tau) {
  if (u <= 0) return 0;
  if (tau <= 0) return 0.5 * u * u;
  if (u > 36 * tau) return 0.5 * u * u - tau * u + tau * tau;  // e^(−36) is below a double's epsilon
  return 0.5 * u * u - tau * u - tau * tau * std::expm1(-u / tau);
}

// Detections of one component in a window: time, position along the axis (m) or heading (rad).
struct SeriesData {
  std::vector<double> t, y;
  std::vector<int> camera;  // 0..cameras−1
  int cameras = 0;
  double t_ref = 0;         // s, origin of the v0 term
};

struct RampSolution {
  double onset = 0, duration = 0;  // s
  double v0 = 0, slope = 0;        // level before (m/s, rad/s), signed slope (m/s², rad/s²)
  double sse = kInf;               // m² or rad²
  int n = 0;                       // points
  int k = 0;                       // linear parameters
  double End() const { return onset + duration; }
  double Level() const { return v0 + slope * duration; }
  double Rms() const { return n > 0 ? std::sqrt(sse / n) : 0; }
};

class RampFitter {
 public:
  RampFitter(const SeriesData& data, double tau, double onset_low, double onset_high, double max_duration)
      : data_(data), tau_(tau), onset_low_(onset_low), onset_high_(onset_high), max_duration_(max_duration),
        g_(data.t.size()) {
    // e^(−(t − onset)/τ) = e^(−(t − t0)/τ)·e^((onset − t0)/τ): the first factor once here, the
    // second once per evaluation, while both stay within a double's exponent range.
    if (tau_ > 0 && !data.t.empty() &&
        std::max(data.t.back() - data.t.front(), onset_high_ - data.t.front() + max_duration_) / tau_ < 650) {
      base_ = data.t.front();
      decay_.resize(data.t.size());
      for (std::size_t i = 0; i < data.t.size(); ++i) decay_[i] = std::exp(-(data.t[i] - base_) / tau_);
    }
  }

  // The least-squares misfit for one onset and duration, the linear part solved; fills `out`.
  double Misfit(double onset, double duration, RampSolution* out = nullptr) const {
    if (!(onset >= onset_low_ && onset <= onset_high_ && duration >= kMinDuration && duration <= max_duration_)) {
      return kInf;
    }
    using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxK, kMaxK>;
    using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxK, 1>;
    const int cams = data_.cameras;
    const int k = cams + 2;
    Matrix normal = Matrix::Zero(k, k);
    Vector rhs = Vector::Zero(k);
    const std::size_t n = data_.t.size();
    const double end = onset + duration;
    const bool fast = !decay_.empty();
    const double grow_onset = fast ? std::exp((onset - base_) / tau_) : 0, grow_end = fast ? std::exp((end - base_) / tau_) : 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double t = data_.t[i];
      const double g = fast ? Integral(t - onset, decay_[i] * grow_onset) - Integral(t - end, decay_[i] * grow_end)
                            : LaggedRampIntegral(t - onset, tau_) - LaggedRampIntegral(t - end, tau_);
      g_[i] = g;
      const double dt = t - data_.t_ref;
      const double y = data_.y[i];
      const int c = data_.camera[i];
      normal(c, c) += 1;
      normal(c, cams) += dt;
      normal(c, cams + 1) += g;
      normal(cams, cams) += dt * dt;
      normal(cams, cams + 1) += dt * g;
      normal(cams + 1, cams + 1) += g * g;
      rhs(c) += y;
      rhs(cams) += dt * y;
      rhs(cams + 1) += g * y;
    }
    for (int r = 0; r < k; ++r) {
      for (int c = r + 1; c < k; ++c) normal(c, r) = normal(r, c);
    }
    // A whisker of ridge keeps a ramp that starts after the data (G ≡ 0) solvable: slope 0.
    for (int r = 0; r < k; ++r) normal(r, r) += 1e-12 * (1 + normal(r, r));
    const Vector coef = normal.ldlt().solve(rhs);
    double sse = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double r = data_.y[i] - coef(data_.camera[i]) - coef(cams) * (data_.t[i] - data_.t_ref) -
                       coef(cams + 1) * g_[i];
      sse += r * r;
    }
    if (!std::isfinite(sse)) return kInf;
    if (out) {
      out->onset = onset;
      out->duration = duration;
      out->v0 = coef(cams);
      out->slope = coef(cams + 1);
      out->sse = sse;
      out->n = static_cast<int>(n);
      out->k = k;
    }
    return sse;
  }

  // Nelder–Mead on (onset, duration) from a guess, restarted once from where it stopped.
  RampSolution Fit(double onset, double duration) const {
    onset = std::clamp(onset, onset_low_, onset_high_);
    duration = std::clamp(duration, kMinDuration, max_duration_);
    Point best = Simplex({onset, duration}, 0.02);
    best = Simplex(best, 0.005);
    RampSolution s;
    if (!std::isfinite(Misfit(best[0], best[1], &s))) s.sse = kInf;
    return s;
  }

  static constexpr int kMaxK = 8;             // linear parameters at most: 6 cameras, v0, slope
  static constexpr double kMinDuration = 0.005;  // s

 private:
  using Point = std::array<double, 2>;  // onset, duration (s)

  // A standard Nelder–Mead simplex from `start` with sides of `step` s; stops when it is 20 µs
  // across. Out-of-bounds points score infinity, so it stays inside.
  Point Simplex(const Point& start, double step) const {
    std::array<Point, 3> x = {start, start, start};
    x[1][0] = start[0] + step <= onset_high_ ? start[0] + step : start[0] - step;
    x[2][1] = start[1] * 1.25 + step <= max_duration_ ? start[1] * 1.25 + step : start[1] * 0.75;
    std::array<double, 3> f{};
    for (std::size_t i = 0; i < 3; ++i) f[i] = Misfit(x[i][0], x[i][1]);
    for (int iteration = 0; iteration < 120; ++iteration) {
      std::array<std::size_t, 3> order = {0, 1, 2};
      std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return f[a] < f[b]; });
      const std::size_t best = order[0], middle = order[1], worst = order[2];
      const double size = std::max(std::abs(x[worst][0] - x[best][0]) + std::abs(x[middle][0] - x[best][0]),
                                   std::abs(x[worst][1] - x[best][1]) + std::abs(x[middle][1] - x[best][1]));
      if (size < 2e-5) break;
      const Point centre = {0.5 * (x[best][0] + x[middle][0]), 0.5 * (x[best][1] + x[middle][1])};
      const auto along = [&](double factor) {
        return Point{centre[0] + factor * (x[worst][0] - centre[0]), centre[1] + factor * (x[worst][1] - centre[1])};
      };
      const Point reflected = along(-1.0);
      const double fr = Misfit(reflected[0], reflected[1]);
      if (fr < f[best]) {
        const Point expanded = along(-2.0);
        const double fe = Misfit(expanded[0], expanded[1]);
        x[worst] = fe < fr ? expanded : reflected;
        f[worst] = std::min(fe, fr);
        continue;
      }
      if (fr < f[middle]) {
        x[worst] = reflected, f[worst] = fr;
        continue;
      }
      const Point contracted = fr < f[worst] ? along(-0.5) : along(0.5);
      const double fc = Misfit(contracted[0], contracted[1]);
      if (fc < std::min(fr, f[worst])) {
        x[worst] = contracted, f[worst] = fc;
        continue;
      }
      for (const std::size_t i : {middle, worst}) {  // shrink toward the best
        x[i] = {0.5 * (x[i][0] + x[best][0]), 0.5 * (x[i][1] + x[best][1])};
        f[i] = Misfit(x[i][0], x[i][1]);
      }
    }
    return x[static_cast<std::size_t>(std::min_element(f.begin(), f.end()) - f.begin())];
  }

  // LaggedRampIntegral(u, τ) given e^(−u/τ).
  double Integral(double u, double decay) const {
    if (u <= 0) return 0;
    return 0.5 * u * u - tau_ * u + tau_ * tau_ * (1 - decay);
  }

  const SeriesData& data_;
  double tau_, onset_low_, onset_high_, max_duration_;
  double base_ = 0;              // s, t0 of decay_
  std::vector<double> decay_;    // e^(−(t − t0)/τ), empty when out of range (or τ = 0)
  mutable std::vector<double> g_;
};

// ---------------------------------------------------------------------------------------------
// Steps and ramps

struct Candidate {
  SegmentRecord record;
  SeriesData data;
  double window_start = 0;          // s, where the detections fitted begin (record.t_end: end)
  double onset_low = 0, onset_high = 0, max_duration = 0;
  double guess_onset = 0, guess_duration = 0;
  double other_linear_command = 0;  // m/s, the other linear component's command after (top speed needs 0)
  RampSolution solution;
  bool open = true;                 // not rejected yet
};

void Reject(Candidate& c, std::string reason) {
  if (!c.open) return;
  c.open = false;
  c.record.used = false;
  c.record.reason = std::move(reason);
}

// Cuts [t0, t1] out of the track for one component: positions projected on the axis (fixed in the
// world: the heading's median; rejected when it turns more than max_turn) or the heading itself.
// Fills c.data, or rejects c with the reason.
void Extract(const SmoothedTrack& track, double t0, double t1, const RobotFitOptions& o, Candidate& c) {
  const auto& points = track.points();
  const std::size_t begin = track.LowerBound(t0);
  std::size_t end = begin;
  while (end < points.size() && points[end].t <= t1) ++end;
  std::vector<std::size_t> use;
  use.reserve(end - begin);
  std::vector<double> yaws;
  for (std::size_t i = begin; i < end; ++i) {
    if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y)) continue;
    if (std::isfinite(points[i].yaw)) yaws.push_back(points[i].yaw);
    if (c.record.axis == MotionAxis::kAngular && !std::isfinite(points[i].yaw)) continue;
    use.push_back(i);
  }
  if (use.size() < 15 || yaws.size() < 10) {
    Reject(c, Format("only %.0f detections in the window", static_cast<double>(use.size())));
    return;
  }
  double gap = std::max(points[use.front()].t - t0, t1 - points[use.back()].t);
  for (std::size_t k = 1; k < use.size(); ++k) gap = std::max(gap, points[use[k]].t - points[use[k - 1]].t);
  if (gap > o.max_track_gap) {
    Reject(c, Format("the track has a %.0f ms gap in the window", gap * 1e3));
    return;
  }
  const std::size_t fifth = std::max<std::size_t>(yaws.size() / 5, 3);
  const double yaw_first = Median(std::vector<double>(yaws.begin(), yaws.begin() + static_cast<std::ptrdiff_t>(fifth)));
  const double yaw_last = Median(std::vector<double>(yaws.end() - static_cast<std::ptrdiff_t>(fifth), yaws.end()));
  if (Linear(c.record.axis) && std::abs(yaw_last - yaw_first) > o.max_turn) {
    Reject(c, Format("the robot turned %.2f rad in the window: no fixed axis for a linear ramp", yaw_last - yaw_first));
    return;
  }
  const double heading = Median(yaws);
  double ux = std::cos(heading), uy = std::sin(heading);
  if (c.record.axis == MotionAxis::kLeft) std::tie(ux, uy) = std::pair(-uy, ux);
  // Cameras: each its own offset (their calibrations differ by millimetres); the six most frequent.
  std::map<int, int> counts;
  for (std::size_t i : use) ++counts[points[i].camera_id];
  std::vector<std::pair<int, int>> by_count;
  for (const auto& [id, count] : counts) by_count.emplace_back(count, id);
  std::sort(by_count.rbegin(), by_count.rend());
  std::map<int, int> index;
  for (const auto& [count, id] : by_count) {
    if (static_cast<int>(index.size()) >= RampFitter::kMaxK - 2 || count < 3) break;
    const int next = static_cast<int>(index.size());
    index[id] = next;
  }
  SeriesData& d = c.data;
  d.cameras = static_cast<int>(index.size());
  d.t_ref = c.record.t_change;
  const TrackPoint& first = points[use.front()];
  for (std::size_t i : use) {
    const auto it = index.find(points[i].camera_id);
    if (it == index.end()) continue;
    const TrackPoint& p = points[i];
    d.t.push_back(p.t);
    d.y.push_back(c.record.axis == MotionAxis::kAngular ? p.yaw - first.yaw
                                                         : (p.x - first.x) * ux + (p.y - first.y) * uy);
    d.camera.push_back(it->second);
  }
  c.record.points = static_cast<int>(d.t.size());
}

// The motion in the robot frame at one instant, from a local fit.
struct GridSample {
  double t = 0;
  double forward = 0, left = 0, angular = 0;          // m/s and rad/s
  double a_forward = 0, a_left = 0, a_angular = 0;    // their rates, m/s² and rad/s²
  double Component(std::size_t k) const { return k == 0 ? forward : k == 1 ? left : angular; }
};

// The robot-frame velocity and its rate of change at t (the local fit over ±half_window), or
// nullopt. The rate is the change of the robot-frame velocity, what the servo limits:
// R(−yaw)·a − ω × v.
std::optional<GridSample> MotionAt(const SmoothedTrack& track, double t, double half_window, int min_points = 5) {
  const auto m = track.At(t, half_window, min_points);
  if (!m || !std::isfinite(m->yaw)) return std::nullopt;
  const double c = std::cos(m->yaw), s = std::sin(m->yaw);
  GridSample g;
  g.t = t;
  g.forward = c * m->vx + s * m->vy;
  g.left = -s * m->vx + c * m->vy;
  g.angular = m->omega;
  g.a_forward = c * m->ax + s * m->ay + m->omega * g.left;
  g.a_left = -s * m->ax + c * m->ay - m->omega * g.forward;
  g.a_angular = m->alpha;
  return g;
}

// One ramp on one component is all the model holds, so the other components must hold steady
// from `from` to `to` (the servo ramps the linear velocity as a vector: a sideways motion still
// settling bends a forward ramp). Velocities from the wide local fits (detect_half_window),
// whose noise is several times below the tolerances.
void RequireOthersSteady(const SmoothedTrack& track, const RobotFitOptions& o, double from, double to, Candidate& c) {
  const double h = o.detect_half_window;
  const auto a = MotionAt(track, from, h), b = MotionAt(track, to, h);
  if (!a || !b) return;
  const std::array<double, 3> tolerance = {o.steady_linear, o.steady_linear, o.steady_angular};
  for (std::size_t k = 0; k < 3; ++k) {
    if (k == static_cast<std::size_t>(c.record.axis)) continue;
    const double change = b->Component(k) - a->Component(k);
    if (std::abs(change) <= tolerance[k] + 0.05 * std::abs(a->Component(k))) continue;
    return Reject(c, std::string("the ") + AxisName(static_cast<MotionAxis>(k)) + " velocity changed as well" +
                         Format(" (%+.2f)", change));
  }
}

// A step must start from steady motion (a step on top of a ramp not yet finished is no step):
// the local fit over the detect window just before the change shows no ramp-sized rate.
void RequireSteadyBefore(const SmoothedTrack& track, const RobotFitOptions& o, Candidate& c) {
  const auto m = MotionAt(track, c.record.t_change - o.detect_half_window, o.detect_half_window);
  if (!m) return;
  if (std::hypot(m->a_forward, m->a_left) > o.ramp_linear_accel) {
    return Reject(c, Format("not steady before the change (accelerating at %.1f m/s²)", std::hypot(m->a_forward, m->a_left)));
  }
  if (std::abs(m->a_angular) > o.ramp_angular_accel) {
    return Reject(c, Format("not steady before the change (turning faster at %.0f rad/s²)", std::abs(m->a_angular)));
  }
}

// Where to start the search: levels before and after from the smoothed velocity, the onset and
// duration from where it crosses 20 % and 80 % of the change.
void Guess(const SmoothedTrack& track, const RobotFitOptions& o, double reference, Candidate& c) {
  const double t0 = c.data.t.front(), t1 = c.data.t.back();
  std::vector<std::pair<double, double>> v;
  for (double t = t0 + o.smoothing_half_window; t <= t1 - o.smoothing_half_window; t += 0.01) {
    if (const auto m = MotionAt(track, t, o.smoothing_half_window)) {
      v.emplace_back(t, m->Component(static_cast<std::size_t>(c.record.axis)));
    }
  }
  c.guess_onset = std::clamp(reference + 0.05, c.onset_low, c.onset_high);
  c.guess_duration = std::min(0.2, c.max_duration);
  if (v.size() < 6) return;
  std::vector<double> before, after;
  const double tail = t1 - 0.25 * (t1 - reference);
  for (const auto& [t, value] : v) {
    if (t <= reference) before.push_back(value);
    if (t >= tail) after.push_back(value);
  }
  if (before.empty()) before.push_back(v.front().second);
  if (after.empty()) after.push_back(v.back().second);
  const double v0 = Median(before), level = Median(after), change = level - v0;
  if (std::abs(change) < 1e-6) return;
  double t20 = kInf, t80 = kInf;
  for (const auto& [t, value] : v) {
    if (t < reference) continue;
    const double f = (value - v0) / change;
    if (t20 == kInf && f >= 0.2) t20 = t;
    if (t20 != kInf && f >= 0.8) {
      t80 = t;
      break;
    }
  }
  if (t80 == kInf) return;
  const double duration = std::max((t80 - t20) / 0.6, 0.02);
  c.guess_onset = std::clamp(t20 - 0.2 * duration, c.onset_low, c.onset_high);
  c.guess_duration = std::clamp(duration, RampFitter::kMinDuration, c.max_duration);
}

// Fits c at lag tau from (onset, duration), then once more without the points beyond five robust
// standard deviations (a swapped or ghost detection).
RampSolution FitCandidate(Candidate& c, double tau, double onset, double duration) {
  RampSolution s = RampFitter(c.data, tau, c.onset_low, c.onset_high, c.max_duration).Fit(onset, duration);
  if (!std::isfinite(s.sse)) return s;
  // Residuals; each camera's offset is the mean of its points' (the linear solution's own).
  std::vector<double> residual(c.data.t.size());
  std::vector<double> sum(static_cast<std::size_t>(c.data.cameras), 0.0), count(sum.size(), 0.0);
  for (std::size_t i = 0; i < c.data.t.size(); ++i) {
    const double g = LaggedRampIntegral(c.data.t[i] - s.onset, tau) - LaggedRampIntegral(c.data.t[i] - s.End(), tau);
    residual[i] = c.data.y[i] - s.v0 * (c.data.t[i] - c.data.t_ref) - s.slope * g;
    sum[static_cast<std::size_t>(c.data.camera[i])] += residual[i];
    count[static_cast<std::size_t>(c.data.camera[i])] += 1;
  }
  for (std::size_t i = 0; i < residual.size(); ++i) {
    const auto cam = static_cast<std::size_t>(c.data.camera[i]);
    residual[i] -= sum[cam] / count[cam];
  }
  std::vector<double> magnitude(residual.size());
  for (std::size_t i = 0; i < residual.size(); ++i) magnitude[i] = std::abs(residual[i]);
  const double sigma = 1.4826 * Median(magnitude);
  if (sigma <= 0) return s;
  SeriesData kept;
  kept.cameras = c.data.cameras;
  kept.t_ref = c.data.t_ref;
  for (std::size_t i = 0; i < residual.size(); ++i) {
    if (magnitude[i] > 5 * sigma) continue;
    kept.t.push_back(c.data.t[i]);
    kept.y.push_back(c.data.y[i]);
    kept.camera.push_back(c.data.camera[i]);
  }
  if (kept.t.size() == c.data.t.size() || kept.t.size() < 15) return s;
  c.data = std::move(kept);
  c.record.points = static_cast<int>(c.data.t.size());
  const RampFitter fitter(c.data, tau, c.onset_low, c.onset_high, c.max_duration);
  return fitter.Fit(s.onset, s.duration);
}

// Reads a fitted ramp into the record and rejects what cannot serve: no response, a reversal, a
// ramp too short or unseen, no onset in reach.
void Interpret(Candidate& c, const RobotFitOptions& o, bool with_commands) {
  const RampSolution& s = c.solution;
  SegmentRecord& r = c.record;
  r.onset = s.onset;
  r.ramp_end = s.End();
  r.v_start = s.v0;
  r.v_end = s.Level();
  r.slope = s.duration > 0 ? std::abs(r.v_end - r.v_start) / s.duration : 0;
  r.rms = s.Rms();
  r.speeding_up = std::abs(r.v_end) > std::abs(r.v_start);
  r.plateau_reached = r.ramp_end <= r.t_end - o.min_plateau_time;
  r.speed_limited = false;
  if (!c.open) return;
  if (!std::isfinite(s.sse)) return Reject(c, "the fit failed");
  const bool linear = Linear(r.axis);
  const char* unit = linear ? "m/s" : "rad/s";
  const double change = r.v_end - r.v_start;
  const double min_step = linear ? o.min_linear_step : o.min_angular_step;
  if (with_commands) {
    const double asked = r.command_after - r.command_before;
    const double needed = std::max(0.5 * min_step, 0.2 * std::min(std::abs(asked), linear ? 2.0 : 6.0));
    if (std::abs(change) < needed || change * asked < 0) {
      return Reject(c, Format("the robot did not follow: its velocity changed %+.2f", change) + " " + unit +
                           Format(" for a command change of %+.2f", asked) + " " + unit);
    }
  } else if (std::abs(change) < min_step) {
    return Reject(c, Format("the velocity changed only %.2f", std::abs(change)) + " " + unit);
  }
  if (r.v_start * r.v_end < 0 && std::min(std::abs(r.v_start), std::abs(r.v_end)) > 0.1 * std::abs(change)) {
    return Reject(c, "reverses direction (brakes, then speeds up): not one ramp");
  }
  if (s.onset >= c.onset_high - 1e-4) return Reject(c, "no onset within reach of the change");
  if (s.duration < o.min_ramp_time) {
    return Reject(c, Format("the ramp lasts %.0f ms: too short for a slope", s.duration * 1e3));
  }
  if (std::min(r.ramp_end, r.t_end) - r.onset < o.min_ramp_time) {
    return Reject(c, "the ramp leaves the window before it can be measured");
  }
  if (with_commands && r.plateau_reached && r.speeding_up) {
    const double reached = std::abs(r.v_end);
    const bool other_ok = !linear || std::abs(c.other_linear_command) <= o.linear_tolerance;
    r.speed_limited = other_ok && std::abs(r.command_after) >= reached * (1 + o.speed_limit_margin);
  }
  r.used = true;
}

// Rejects the fits whose residual is far above the typical (median) one of their kind.
void RejectPoorFits(std::vector<Candidate>& candidates, const RobotFitOptions& o) {
  for (const bool linear : {true, false}) {
    std::vector<double> rms;
    for (const auto& c : candidates) {
      if (c.open && Linear(c.record.axis) == linear) rms.push_back(c.record.rms);
    }
    if (rms.size() < 3) continue;
    const double typical = Median(rms);
    for (auto& c : candidates) {
      if (!c.open || Linear(c.record.axis) != linear || c.record.rms <= o.fit_tolerance * typical) continue;
      const double scale = linear ? 1e3 : 1.0;
      Reject(c, Format(linear ? "poor fit: residual %.1f mm against a typical %.1f mm (motion not steady?)"
                              : "poor fit: residual %.3f rad against a typical %.3f rad (motion not steady?)",
                       c.record.rms * scale, typical * scale));
    }
  }
}

// Keeps at most max_segments open candidates: the largest command steps, or (ramps, no command)
// ones spread evenly over the log.
void Cap(std::vector<Candidate>& candidates, int max_segments, std::vector<std::string>& problems) {
  std::vector<std::size_t> open;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (candidates[i].open) open.push_back(i);
  }
  const std::size_t total = open.size(), keep = static_cast<std::size_t>(std::max(max_segments, 0));
  if (total <= keep) return;
  std::vector<char> kept(candidates.size(), 0);
  std::vector<double> size(candidates.size(), 0.0);
  bool any_size = false;
  for (std::size_t i : open) {
    const auto& r = candidates[i].record;
    size[i] = std::abs(r.command_after - r.command_before) / (Linear(r.axis) ? 1.0 : 3.0);
    any_size = any_size || size[i] > 0;
  }
  if (any_size) {
    std::stable_sort(open.begin(), open.end(), [&](std::size_t a, std::size_t b) { return size[a] > size[b]; });
    for (std::size_t k = 0; k < keep; ++k) kept[open[k]] = 1;
  } else {
    for (std::size_t k = 0; k < keep; ++k) kept[open[k * total / keep]] = 1;
  }
  for (std::size_t i : open) {
    if (!kept[i]) Reject(candidates[i], "not fitted: more than max_segments found");
  }
  problems.push_back(Format("%.0f steps or ramps found; only %.0f were fitted (max_segments)", static_cast<double>(total),
                            static_cast<double>(keep)));
}

// ---------------------------------------------------------------------------------------------
// With commands

struct CommandRun {
  double t0 = 0, t1 = 0;           // first sample, and when the next run starts (or the last sample)
  std::array<double, 3> value{};   // forward, left, angular
  bool after_gap = false;          // the commands stopped before it
};

std::vector<CommandRun> Runs(const std::vector<CommandSample>& commands, const RobotFitOptions& o) {
  std::vector<CommandRun> runs;
  const std::array<double, 3> tolerance = {o.linear_tolerance, o.linear_tolerance, o.angular_tolerance};
  double last_t = -kInf;
  for (const CommandSample& s : commands) {
    const std::array<double, 3> value = {s.forward, s.left, s.angular};
    if (!std::isfinite(s.t) || !std::isfinite(s.forward) || !std::isfinite(s.left) || !std::isfinite(s.angular)) continue;
    const bool gap = s.t - last_t > o.max_command_gap;
    bool changed = runs.empty() || gap;
    for (std::size_t k = 0; k < 3 && !changed; ++k) changed = std::abs(value[k] - runs.back().value[k]) > tolerance[k];
    if (changed) {
      if (!runs.empty()) runs.back().t1 = gap ? last_t : s.t;
      runs.push_back({s.t, s.t, value, gap});
    }
    last_t = s.t;
  }
  if (!runs.empty()) runs.back().t1 = last_t;
  return runs;
}

// The steps the commands hold (cut out of the track later, by Extract).
std::vector<Candidate> StepCandidates(const std::vector<CommandSample>& commands, const RobotFitOptions& o) {
  const std::vector<CommandRun> runs = Runs(commands, o);
  const std::array<double, 3> tolerance = {o.linear_tolerance, o.linear_tolerance, o.angular_tolerance};
  std::vector<Candidate> out;
  for (std::size_t i = 1; i < runs.size(); ++i) {
    const CommandRun& run = runs[i];
    const CommandRun& prior = runs[i - 1];
    if (run.after_gap || run.t1 - run.t0 < o.min_hold) continue;  // no step
    std::array<double, 3> change{};
    int changed = 0;
    std::size_t axis = 0;
    double largest = -1;
    for (std::size_t k = 0; k < 3; ++k) {
      change[k] = run.value[k] - prior.value[k];
      if (std::abs(change[k]) <= tolerance[k]) continue;
      ++changed;
      const double size = std::abs(change[k]) / (k == 2 ? 3.0 : 1.0);  // 1 m/s ~ 3 rad/s
      if (size > largest) largest = size, axis = k;
    }
    Candidate c;
    SegmentRecord& r = c.record;
    r.axis = static_cast<MotionAxis>(axis);
    r.t_change = run.t0;
    r.t_end = std::min(run.t1, run.t0 + o.max_window);
    r.command_before = prior.value[axis];
    r.command_after = run.value[axis];
    c.other_linear_command = axis == 0 ? run.value[1] : run.value[0];
    c.onset_low = run.t0 - 0.05;
    c.onset_high = std::min(run.t0 + o.max_latency, r.t_end - o.min_ramp_time);
    c.max_duration = r.t_end - c.onset_low;
    if (changed > 1) {
      Reject(c, "changes more than one component at once");
    } else if (prior.t1 - prior.t0 < o.min_prior_hold) {
      Reject(c, Format("the command before held only %.2f s", prior.t1 - prior.t0));
    } else if (std::abs(change[axis]) < (axis == 2 ? o.min_angular_step : o.min_linear_step)) {
      Reject(c, Format(axis == 2 ? "a step of %.2f rad/s is below the smallest fitted" : "a step of %.2f m/s is below the smallest fitted",
                       std::abs(change[axis])));
    } else if (axis != 2 && (std::abs(run.value[2]) > o.angular_tolerance || std::abs(prior.value[2]) > o.angular_tolerance)) {
      Reject(c, "turning during a linear step (the robot's frame turns)");
    }
    c.window_start = run.t0 - o.pre_window;
    out.push_back(std::move(c));
  }
  return out;
}

// The lag τ: the summed misfit of the strongest steps, each normalised by its own noise, profiled
// over τ on a grid; the minimum by a parabola, the interval where it rises by 3.84 (χ², 1 dof).
Estimate ProfileWheelLag(std::vector<Candidate>& candidates, const RobotFitOptions& o, double nominal,
                         std::vector<std::string>& problems) {
  std::vector<std::size_t> strong;
  std::vector<double> strength(candidates.size(), 0.0);
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const Candidate& c = candidates[i];
    if (!c.open || c.solution.Rms() <= 0) continue;
    strong.push_back(i);
    strength[i] = c.record.slope * std::sqrt(static_cast<double>(c.solution.n)) / c.solution.Rms();
  }
  std::stable_sort(strong.begin(), strong.end(), [&](std::size_t a, std::size_t b) { return strength[a] > strength[b]; });
  if (strong.size() > static_cast<std::size_t>(o.max_lag_segments)) strong.resize(static_cast<std::size_t>(o.max_lag_segments));
  Estimate e;
  e.value = e.low = e.high = nominal;
  if (strong.size() < 3) {
    problems.push_back(Format("wheel lag not estimated (%.0f usable steps, 3 needed): latency assumes 15 ms",
                              static_cast<double>(strong.size())));
    return e;
  }
  const double step = 0.005;
  const int count = static_cast<int>(std::floor(o.max_wheel_lag / step + 1e-9)) + 1;
  std::vector<double> taus(static_cast<std::size_t>(count)), chi(taus.size(), 0.0);
  for (int j = 0; j < count; ++j) taus[static_cast<std::size_t>(j)] = j * step;
  for (std::size_t i : strong) {
    Candidate& c = candidates[i];
    std::vector<double> sse(taus.size());
    double onset = c.solution.onset + nominal, duration = c.solution.duration;
    for (std::size_t j = 0; j < taus.size(); ++j) {
      const RampFitter fitter(c.data, taus[j], c.onset_low, c.onset_high, c.max_duration);
      const RampSolution s = fitter.Fit(onset - taus[j], duration);
      sse[j] = s.sse;
      if (std::isfinite(s.sse)) onset = s.onset + taus[j], duration = s.duration;
    }
    const double best = *std::min_element(sse.begin(), sse.end());
    const double variance = best / std::max(1, c.solution.n - c.solution.k - 2);
    if (!(variance > 0) || !std::isfinite(variance)) continue;
    for (std::size_t j = 0; j < taus.size(); ++j) chi[j] += std::isfinite(sse[j]) ? sse[j] / variance : 1e12;
  }
  // The corners' rounding grows as τ², so the misfit is near-parabolic in τ², not in τ: the
  // minimum and the interval are read on that scale.
  const auto jmin = static_cast<std::size_t>(std::min_element(chi.begin(), chi.end()) - chi.begin());
  std::vector<double> squares(taus.size());
  for (std::size_t j = 0; j < taus.size(); ++j) squares[j] = taus[j] * taus[j];
  double square = squares[jmin];
  if (taus.size() >= 3) {
    const std::size_t j = std::clamp<std::size_t>(jmin, 1, taus.size() - 2);
    const double x0 = squares[j - 1], x1 = squares[j], x2 = squares[j + 1];
    const double y0 = chi[j - 1], y1 = chi[j], y2 = chi[j + 1];
    const double d01 = (y1 - y0) / (x1 - x0), d12 = (y2 - y1) / (x2 - x1), curvature = (d12 - d01) / (x2 - x0);
    if (curvature > 0) {
      const double vertex = 0.5 * (x0 + x1) - d01 / (2 * curvature);
      const double lo = jmin == 0 ? 0.0 : squares[jmin - 1], hi = jmin + 1 < taus.size() ? squares[jmin + 1] : squares[jmin];
      square = std::clamp(vertex, lo, hi);
    }
  }
  const double tau = std::sqrt(std::max(square, 0.0));
  const double chi_min = chi[jmin];
  double low = 0, high = taus.back();
  for (std::size_t j = jmin; j-- > 0;) {
    if (chi[j] - chi_min > 3.84) {
      const double f = (3.84 - (chi[j + 1] - chi_min)) / (chi[j] - chi[j + 1]);
      low = std::sqrt(squares[j + 1] - f * (squares[j + 1] - squares[j]));
      break;
    }
  }
  for (std::size_t j = jmin + 1; j < taus.size(); ++j) {
    if (chi[j] - chi_min > 3.84) {
      const double f = (3.84 - (chi[j - 1] - chi_min)) / (chi[j] - chi[j - 1]);
      high = std::sqrt(squares[j - 1] + f * (squares[j] - squares[j - 1]));
      break;
    }
  }
  e.value = tau;
  e.low = std::min(low, tau);
  e.high = std::max(high, tau);
  e.samples = static_cast<int>(strong.size());
  if (jmin + 1 == taus.size()) {
    problems.push_back(Format("the wheel lag came out at the %.0f ms searched at most: latency may be too small",
                              o.max_wheel_lag * 1e3));
  }
  return e;
}

// ---------------------------------------------------------------------------------------------
// Without commands

// The robot-frame velocity and its rate on a grid (gaps left out).
std::vector<GridSample> VelocityGrid(const SmoothedTrack& track, const RobotFitOptions& o) {
  std::vector<GridSample> grid;
  const auto& points = track.points();
  if (points.empty()) return grid;
  for (double t = points.front().t; t <= points.back().t; t += o.grid_step) {
    if (const auto g = MotionAt(track, t, o.detect_half_window, 8)) grid.push_back(*g);
  }
  return grid;
}

struct Run {
  std::size_t begin = 0, end = 0;  // grid indices [begin, end)
};

// Runs of consecutive grid samples where `keep(previous-in-run-first, sample)` holds.
template <typename Keep>
std::vector<Run> FindRuns(const std::vector<GridSample>& grid, double step, double min_duration, Keep keep) {
  std::vector<Run> runs;
  std::size_t i = 0;
  while (i < grid.size()) {
    if (!keep(grid[i], grid[i])) {
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j < grid.size() && grid[j].t - grid[j - 1].t < 1.5 * step && keep(grid[i], grid[j])) ++j;
    if (grid[j - 1].t - grid[i].t >= min_duration) runs.push_back({i, j});
    i = j;
  }
  return runs;
}

// The ramps the velocity grid shows (cut out of the track later, by Extract).
std::vector<Candidate> RampCandidates(const std::vector<GridSample>& grid, const RobotFitOptions& o) {
  std::vector<Candidate> out;
  const double lin = o.ramp_linear_accel, ang = o.ramp_angular_accel;
  const std::vector<Run> linear = FindRuns(grid, o.grid_step, o.min_ramp_duration, [lin](const GridSample& first, const GridSample& g) {
    const double norm = std::hypot(g.a_forward, g.a_left);
    if (norm < lin) return false;
    const double first_norm = std::hypot(first.a_forward, first.a_left);
    return (g.a_forward * first.a_forward + g.a_left * first.a_left) >= std::cos(0.785) * norm * first_norm;
  });
  const std::vector<Run> angular = FindRuns(grid, o.grid_step, o.min_ramp_duration, [ang](const GridSample& first, const GridSample& g) {
    return std::abs(g.a_angular) >= ang && g.a_angular * first.a_angular > 0;
  });
  for (const bool is_linear : {true, false}) {
    const std::vector<Run>& runs = is_linear ? linear : angular;
    for (std::size_t k = 0; k < runs.size(); ++k) {
      const Run& run = runs[k];
      const double start = grid[run.begin].t, stop = grid[run.end - 1].t;
      double window_start = start - 0.25, window_end = stop + 0.35;
      if (k > 0) window_start = std::max(window_start, grid[runs[k - 1].end - 1].t);
      if (k + 1 < runs.size()) window_end = std::min(window_end, grid[runs[k + 1].begin].t);
      Candidate c;
      SegmentRecord& r = c.record;
      r.t_change = window_start;
      r.t_end = window_end;
      c.onset_low = window_start;
      c.onset_high = stop;
      c.max_duration = window_end - window_start;
      if (is_linear) {
        double sf = 0, sl = 0;
        for (std::size_t i = run.begin; i < run.end; ++i) sf += grid[i].a_forward, sl += grid[i].a_left;
        const double angle = std::atan2(std::abs(sl), std::abs(sf));
        if (angle <= 0.35) {
          r.axis = MotionAxis::kForward;
        } else if (angle >= 1.22) {
          r.axis = MotionAxis::kLeft;
        } else {
          r.axis = std::abs(sf) >= std::abs(sl) ? MotionAxis::kForward : MotionAxis::kLeft;
          Reject(c, Format("a diagonal ramp (%.0f° off the heading): neither along nor across", angle * 57.2958));
        }
      } else {
        r.axis = MotionAxis::kAngular;
      }
      c.window_start = window_start;
      out.push_back(std::move(c));
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) { return a.record.t_change < b.record.t_change; });
  return out;
}

struct Plateau {
  double t0 = 0, t1 = 0;  // s
  double level = 0;       // m/s or rad/s, unsigned
};

// Sustained steady motion: the grid's runs with |rate| under half the ramp threshold and the speed
// above the plateau minimum, at least plateau_duration long, with their median levels.
std::vector<Plateau> Plateaus(const std::vector<GridSample>& grid, const RobotFitOptions& o, bool linear) {
  const double lin = 0.5 * o.ramp_linear_accel, ang = 0.5 * o.ramp_angular_accel;
  const std::vector<Run> runs = FindRuns(grid, o.grid_step, o.plateau_duration, [&](const GridSample& first, const GridSample& g) {
    if (linear) {
      const double speed = std::hypot(g.forward, g.left);
      return speed >= o.min_plateau_speed && std::hypot(g.a_forward, g.a_left) < lin &&
             std::abs(speed - std::hypot(first.forward, first.left)) < 0.05 * speed + 0.02;
    }
    return std::abs(g.angular) >= o.min_plateau_angular && std::abs(g.a_angular) < ang && g.angular * first.angular > 0 &&
           std::abs(g.angular - first.angular) < 0.05 * std::abs(g.angular) + 0.05;
  });
  std::vector<Plateau> out;
  for (const Run& run : runs) {
    std::vector<double> v;
    for (std::size_t i = run.begin; i < run.end; ++i) {
      v.push_back(linear ? std::hypot(grid[i].forward, grid[i].left) : std::abs(grid[i].angular));
    }
    out.push_back({grid[run.begin].t, grid[run.end - 1].t, Median(v)});
  }
  return out;
}

// The top speed without commands: the levels the used speed-up ramps reached, and the steady
// plateaus the grid shows apart from those (a plateau too short for the grid still ends a fitted
// ramp); of them the fastest cluster (from 97 % of the 90th-percentile level up).
Estimate TopWithoutCommands(const std::vector<Plateau>& plateaus, const std::vector<SegmentRecord>& ramps, bool linear) {
  std::vector<double> levels;
  std::vector<std::pair<double, double>> covered;  // the ramps' windows, by start
  for (const SegmentRecord& r : ramps) {
    if (!r.used || Linear(r.axis) != linear || !r.speeding_up || !r.plateau_reached) continue;
    levels.push_back(std::abs(r.v_end));
    covered.emplace_back(r.t_change, r.t_end);
  }
  std::sort(covered.begin(), covered.end());
  std::vector<double> latest_end(covered.size());  // the latest end among the windows up to each
  for (std::size_t i = 0; i < covered.size(); ++i) {
    latest_end[i] = std::max(covered[i].second, i > 0 ? latest_end[i - 1] : -kInf);
  }
  for (const Plateau& p : plateaus) {
    // A window overlaps the plateau when it starts before the plateau ends and ends after it starts.
    const auto starts_before = static_cast<std::size_t>(
        std::lower_bound(covered.begin(), covered.end(), std::pair(p.t1, -kInf)) - covered.begin());
    if (starts_before == 0 || latest_end[starts_before - 1] <= p.t0) levels.push_back(p.level);
  }
  if (levels.empty()) return {};
  const double reference = Quantile(levels, 0.9);
  std::vector<double> top;
  for (double level : levels) {
    if (level >= 0.97 * reference) top.push_back(level);
  }
  Estimate e = Combine(top);
  e.low = std::max(e.low, 0.0);
  return e;
}

// ---------------------------------------------------------------------------------------------
// Estimates from the used records

void Estimates(RobotFit& fit, const RobotFitOptions& o) {
  std::vector<double> accel[3], brake[3], top[2], latency, latency_linear;
  for (const SegmentRecord& r : fit.segments) {
    if (!r.used) continue;
    const auto a = static_cast<std::size_t>(r.axis);
    (r.speeding_up ? accel : brake)[a].push_back(r.slope);
    if (r.speed_limited) top[Linear(r.axis) ? 0 : 1].push_back(std::abs(r.v_end));
    if (fit.from_commands) (Linear(r.axis) ? latency_linear : latency).push_back(r.onset - r.t_change);
  }
  const char* kind = fit.from_commands ? " steps" : " ramps";
  auto make = [&](std::vector<double> v, const char* what, const char* why) {
    const std::size_t n = v.size();
    Estimate e = fit.from_commands ? Combine(std::move(v)) : CombineUpper(std::move(v));
    e.low = std::max(e.low, 0.0);  // speeds and rates are not negative (latency goes its own way)
    if (static_cast<int>(n) < o.min_samples) {
      e = {};
      fit.problems.push_back(Format("%.0f ", static_cast<double>(n)) + why + kind +
                             Format(" (%.0f needed): ", o.min_samples) + what + " not estimated");
    }
    return e;
  };
  fit.accel_along = make(accel[0], "acceleration along the heading", "forward/backward speed-up");
  fit.brake_along = make(brake[0], "braking along the heading", "forward/backward slow-down");
  fit.accel_across = make(accel[1], "acceleration across the heading", "sideways speed-up");
  fit.brake_across = make(brake[1], "braking across the heading", "sideways slow-down");
  fit.angular_accel = make(accel[2], "angular acceleration", "turning speed-up");
  fit.angular_brake = make(brake[2], "angular braking", "turning slow-down");
  if (fit.from_commands) {
    fit.top_speed = make(top[0], "top speed", "speed-limited linear");
    fit.angular_top_speed = make(top[1], "angular top speed", "speed-limited turning");
    // Positions pin an onset down several times better than headings do: the linear steps alone
    // when there are enough of them.
    if (latency_linear.size() < 6) latency.insert(latency.end(), latency_linear.begin(), latency_linear.end());
    fit.latency = Combine(latency_linear.size() >= 6 ? latency_linear : latency);
    if (fit.latency.samples < o.min_samples) {
      fit.latency = {};
      fit.problems.push_back(Format("%.0f usable steps", static_cast<double>(latency.size() + latency_linear.size())) +
                             Format(" (%.0f needed): latency not estimated", o.min_samples));
    }
    if (fit.latency.ok()) {
      // Latency and lag move together; their sum per step is what the steps pin down.
      std::vector<double> linear, all;
      for (double v : latency_linear) linear.push_back(v + fit.wheel_lag.value);
      for (double v : latency) all.push_back(v + fit.wheel_lag.value);
      fit.response_delay = Combine(latency_linear.size() >= 6 ? linear : all);
    }
    if (fit.latency.ok() && fit.wheel_lag.ok()) {  // the onset moves back as the lag grows
      fit.latency.low -= fit.wheel_lag.high - fit.wheel_lag.value;
      fit.latency.high += fit.wheel_lag.value - fit.wheel_lag.low;
    }
  }
}

bool AnythingEstimated(const RobotFit& f) {
  for (const Estimate* e : {&f.top_speed, &f.accel_along, &f.brake_along, &f.accel_across, &f.brake_across,
                            &f.angular_top_speed, &f.angular_accel, &f.angular_brake}) {
    if (e->ok()) return true;
  }
  return false;
}

// Drops the detections that jump off their neighbours (a ghost, another robot's blob, a flipped
// heading): one whose position is more than 15 mm, or heading more than 0.1 rad, off the line
// between the detections before and after it, and further off than either of those is from
// theirs (the ghost's neighbours look off by half as much). The local fits are least squares and
// would smear such a point over their whole window. Returns how many went.
std::size_t DropJumps(std::vector<TrackPoint>& track) {
  const std::size_t n = track.size();
  if (n < 3) return 0;
  std::vector<double> off(n, 0.0);  // in units of the thresholds
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const TrackPoint &a = track[i - 1], &p = track[i], &b = track[i + 1];
    const double span = b.t - a.t;
    const double f = span > 1e-6 ? (p.t - a.t) / span : 0.5;
    const double dx = p.x - (a.x + f * (b.x - a.x)), dy = p.y - (a.y + f * (b.y - a.y));
    double score = std::hypot(dx, dy) / 0.015;
    if (std::isfinite(p.yaw) && std::isfinite(a.yaw) && std::isfinite(b.yaw)) {
      const double dyaw = AngleDifference(p.yaw, a.yaw + f * AngleDifference(b.yaw, a.yaw));
      score = std::max(score, std::abs(dyaw) / 0.1);
    }
    off[i] = score;
  }
  std::size_t kept = 0, dropped = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool jump = off[i] > 1 && (i == 0 || off[i] >= off[i - 1]) && (i + 1 == n || off[i] >= off[i + 1]);
    if (jump) {
      ++dropped;
    } else {
      track[kept++] = track[i];
    }
  }
  track.resize(kept);
  return dropped;
}

}  // namespace

RobotFit FitRobot(const RobotFitInput& input, const RobotFitOptions& options) {
  RobotFit fit;
  fit.robot = input.robot;
  const RobotFitOptions& o = options;
  std::vector<TrackPoint> clean;
  clean.reserve(input.track.size());
  int with_yaw = 0;
  for (const TrackPoint& p : input.track) {
    if (!std::isfinite(p.t) || !std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    with_yaw += std::isfinite(p.yaw) ? 1 : 0;
    clean.push_back(p);
  }
  std::stable_sort(clean.begin(), clean.end(), [](const TrackPoint& a, const TrackPoint& b) { return a.t < b.t; });
  if (const std::size_t dropped = DropJumps(clean); dropped * 200 > clean.size()) {  // over 0.5 %
    fit.problems.push_back(Format("%.0f detections jumped off the track and were dropped", static_cast<double>(dropped)) +
                           Format(" (%.1f %%): check the log for swapped or ghost robots", 100.0 * dropped / (clean.size() + dropped)));
  }
  const double duration = clean.size() >= 2 ? clean.back().t - clean.front().t : 0;
  if (clean.size() < 50 || duration < o.min_track_duration) {
    fit.problems.push_back(Format("only %.1f s of track", duration) + Format(" (%.0f detections)", static_cast<double>(clean.size())) +
                           Format(": at least %.1f s needed, nothing estimated", o.min_track_duration));
    return fit;
  }
  if (with_yaw < static_cast<int>(clean.size()) / 2) {
    fit.problems.push_back("the track has no orientation for most detections: nothing in the robot frame can be fitted");
    return fit;
  }
  const SmoothedTrack track(std::move(clean));

  std::vector<Candidate> candidates;
  std::vector<Plateau> linear_plateaus, angular_plateaus;  // without commands
  bool with_commands = !input.commands.empty();
  double tau = o.wheel_lag >= 0 ? o.wheel_lag : 0.015;
  if (with_commands) {
    candidates = StepCandidates(input.commands, o);
    for (Candidate& c : candidates) {
      if (c.open) Extract(track, c.window_start, c.record.t_end, o, c);
      if (c.open) RequireSteadyBefore(track, o, c);
      if (c.open) RequireOthersSteady(track, o, c.record.t_change - o.detect_half_window, c.record.t_end - o.detect_half_window, c);
    }
    Cap(candidates, o.max_segments, fit.problems);
    for (Candidate& c : candidates) {
      if (c.open) {
        Guess(track, o, c.record.t_change, c);
      } else {
        c.data = {};
      }
    }
    if (o.wheel_lag < 0) {
      // The lag from the largest steps (twice as many as the profile takes, fitted at a nominal
      // lag first so that the ones that cannot serve drop out), then every step at that lag.
      std::vector<std::size_t> order;
      for (std::size_t i = 0; i < candidates.size(); ++i) {
        if (candidates[i].open) order.push_back(i);
      }
      auto size = [&](std::size_t i) {
        const SegmentRecord& r = candidates[i].record;
        return std::abs(r.command_after - r.command_before) / (Linear(r.axis) ? 1.0 : 3.0);
      };
      std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return size(a) > size(b); });
      order.resize(std::min(order.size(), static_cast<std::size_t>(2 * std::max(o.max_lag_segments, 0))));
      std::vector<Candidate> probe;
      for (std::size_t i : order) {
        Candidate c = candidates[i];
        c.solution = FitCandidate(c, tau, c.guess_onset, c.guess_duration);
        Interpret(c, o, true);
        probe.push_back(std::move(c));
      }
      RejectPoorFits(probe, o);
      fit.wheel_lag = ProfileWheelLag(probe, o, tau, fit.problems);
      for (std::size_t k = 0; k < order.size(); ++k) {  // start the final fits where the probe ended
        Candidate& c = candidates[order[k]];
        if (probe[k].open) {
          c.guess_onset = std::clamp(probe[k].solution.onset - (fit.wheel_lag.value - tau), c.onset_low, c.onset_high);
          c.guess_duration = std::clamp(probe[k].solution.duration, RampFitter::kMinDuration, c.max_duration);
        }
      }
      tau = fit.wheel_lag.value;
    } else {
      fit.wheel_lag = {tau, tau, tau, 0};
    }
    for (Candidate& c : candidates) {
      if (!c.open) continue;
      c.solution = FitCandidate(c, tau, c.guess_onset, c.guess_duration);
      Interpret(c, o, true);
    }
    if (std::none_of(candidates.begin(), candidates.end(), [](const Candidate& c) { return c.open; })) {
      fit.problems.push_back(candidates.empty()
                                 ? "the commands hold no step (a change held for min_hold): fitted from the motion alone"
                                 : "no command step could be fitted: fitted from the motion alone");
      with_commands = false;
      fit.wheel_lag = {};
      fit.segments.reserve(candidates.size());
      for (Candidate& c : candidates) fit.segments.push_back(std::move(c.record));
      candidates.clear();
    }
  }
  if (!with_commands) {
    const std::vector<GridSample> grid = VelocityGrid(track, o);
    candidates = RampCandidates(grid, o);
    for (Candidate& c : candidates) {
      if (c.open) Extract(track, c.window_start, c.record.t_end, o, c);
    }
    Cap(candidates, o.max_segments, fit.problems);
    const double ramp_tau = o.wheel_lag >= 0 ? o.wheel_lag : 0.0;  // the slope does not depend on it
    for (Candidate& c : candidates) {
      if (!c.open) {
        c.data = {};
        continue;
      }
      Guess(track, o, c.record.t_change, c);
      c.solution = FitCandidate(c, ramp_tau, c.guess_onset, c.guess_duration);
      Interpret(c, o, false);
      // The ramp's own span is known only now: the other components steady across it.
      const double h = o.detect_half_window;
      if (c.open) RequireOthersSteady(track, o, c.record.onset - h, c.record.ramp_end + h, c);
    }
    linear_plateaus = Plateaus(grid, o, true);
    angular_plateaus = Plateaus(grid, o, false);
    fit.problems.push_back(input.commands.empty()
                               ? "the log has no commands: latency and wheel lag not estimated; limits are the upper half of the ramps seen"
                               : "latency and wheel lag not estimated (no usable command step); limits are the upper half of the ramps seen");
  }
  fit.from_commands = with_commands;
  RejectPoorFits(candidates, o);
  for (Candidate& c : candidates) {
    c.record.used = c.open && c.record.used;
    fit.segments.push_back(std::move(c.record));
  }
  std::stable_sort(fit.segments.begin(), fit.segments.end(),
                   [](const SegmentRecord& a, const SegmentRecord& b) { return a.t_change < b.t_change; });
  if (!with_commands) {
    fit.top_speed = TopWithoutCommands(linear_plateaus, fit.segments, true);
    fit.angular_top_speed = TopWithoutCommands(angular_plateaus, fit.segments, false);
    if (!fit.top_speed.ok()) fit.problems.push_back("no sustained linear plateau: top speed not estimated");
    if (!fit.angular_top_speed.ok()) fit.problems.push_back("no sustained turning plateau: angular top speed not estimated");
  }
  Estimates(fit, o);
  fit.enough_data = AnythingEstimated(fit);
  if (!fit.enough_data) {
    const bool moved = std::any_of(fit.segments.begin(), fit.segments.end(), [](const SegmentRecord& r) { return r.used; });
    fit.problems.insert(fit.problems.begin(), moved ? "too few usable steps: nothing estimated"
                                                    : "the robot showed no usable step or ramp (standing still?): nothing estimated");
  }
  return fit;
}

// ---------------------------------------------------------------------------------------------
// Report

namespace {

// A rejection reason with its numbers blanked ("the ramp lasts # ms: ..."), to count alike ones.
std::string ReasonKind(const std::string& reason) {
  std::string out;
  for (std::size_t i = 0; i < reason.size();) {
    std::size_t j = i;
    bool digit = false;
    while (j < reason.size() && (std::isdigit(static_cast<unsigned char>(reason[j])) || reason[j] == '.' ||
                                 ((reason[j] == '+' || reason[j] == '-') && j == i))) {
      digit = digit || std::isdigit(static_cast<unsigned char>(reason[j]));
      ++j;
    }
    if (digit) {
      out += '#';
      i = j;
    } else {
      out += reason[i++];
    }
  }
  return out;
}

std::string Slug(const RobotKey& robot) {
  std::string name = RobotName(robot);
  std::replace(name.begin(), name.end(), ' ', '-');
  return name;
}

// The fitted model driven by the commands: latency, speed clamp, ramps at the fitted limits (an
// ellipse between along and across for a diagonal change), then the lag. Starts at `start`.
struct Response {
  std::vector<double> t;
  std::vector<std::array<double, 3>> v;
};

Response SimulateResponse(const RobotFit& fit, const std::vector<CommandSample>& commands, double t0, double t1,
                          std::array<double, 3> start) {
  auto pick = [](const Estimate& a, const Estimate& b) { return a.ok() ? a.value : (b.ok() ? b.value : kInf); };
  const double accel_x = pick(fit.accel_along, fit.accel_across), accel_y = pick(fit.accel_across, fit.accel_along);
  const double brake_x = pick(fit.brake_along, fit.brake_across), brake_y = pick(fit.brake_across, fit.brake_along);
  const double top = fit.top_speed.ok() ? fit.top_speed.value : kInf;
  const double top_angular = fit.angular_top_speed.ok() ? fit.angular_top_speed.value : kInf;
  const double latency = fit.latency.ok() ? fit.latency.value : 0;
  const double tau = fit.wheel_lag.value > 0 ? fit.wheel_lag.value : 0;
  const double dt = 0.001;
  const double blend = tau > 0 ? -std::expm1(-dt / tau) : 1.0;
  Response out;
  std::array<double, 3> setpoint = start, v = start;
  auto it = std::upper_bound(commands.begin(), commands.end(), t0 - latency,
                             [](double t, const CommandSample& c) { return t < c.t; });
  std::array<double, 3> target = setpoint;
  if (it != commands.begin()) {
    const auto& c = *std::prev(it);
    target = {c.forward, c.left, c.angular};
  }
  int step = 0;
  for (double t = t0; t <= t1; t += dt, ++step) {
    while (it != commands.end() && it->t + latency <= t) {
      target = {it->forward, it->left, it->angular};
      ++it;
    }
    std::array<double, 3> goal = target;
    const double speed = std::hypot(goal[0], goal[1]);
    if (speed > top) goal[0] *= top / speed, goal[1] *= top / speed;
    goal[2] = std::clamp(goal[2], -top_angular, top_angular);
    const double dx = goal[0] - setpoint[0], dy = goal[1] - setpoint[1], length = std::hypot(dx, dy);
    if (length > 0) {
      const bool slowing = std::hypot(goal[0], goal[1]) < std::hypot(setpoint[0], setpoint[1]) ||
                           goal[0] * setpoint[0] + goal[1] * setpoint[1] < 0;
      const double ax = slowing ? brake_x : accel_x, ay = slowing ? brake_y : accel_y;
      const double limit = 1 / std::hypot(dx / length / ax, dy / length / ay);
      if (length <= limit * dt) {
        setpoint[0] = goal[0], setpoint[1] = goal[1];
      } else {
        setpoint[0] += dx / length * limit * dt, setpoint[1] += dy / length * limit * dt;
      }
    }
    const bool slowing = std::abs(goal[2]) < std::abs(setpoint[2]) || goal[2] * setpoint[2] < 0;
    const double angular_limit = (slowing ? (fit.angular_brake.ok() ? fit.angular_brake.value : kInf)
                                          : (fit.angular_accel.ok() ? fit.angular_accel.value : kInf)) * dt;
    setpoint[2] += std::clamp(goal[2] - setpoint[2], -angular_limit, angular_limit);
    for (std::size_t k = 0; k < 3; ++k) v[k] += (setpoint[k] - v[k]) * blend;
    if (step % 5 == 0) {
      out.t.push_back(t);
      out.v.push_back(v);
    }
  }
  return out;
}

std::string EstimateRow(const char* name, const Estimate& e, double scale, const char* format, const char* unit,
                        const char* samples) {
  if (!e.ok()) return std::string("| ") + name + " | — | — | not estimated |\n";
  return std::string("| ") + name + " | " + Format(format, e.value * scale) + " " + unit + " | " +
         Format(format, e.low * scale) + " – " + Format(format, e.high * scale) + " " + unit + " | " +
         Format("%.0f ", e.samples) + samples + " |\n";
}

}  // namespace

ReportSection RobotReport(const RobotFit& fit, const RobotFitInput& input) {
  ReportSection out;
  const std::string name = RobotName(fit.robot);
  const std::string slug = "robot-" + Slug(fit.robot);
  std::string& md = out.markdown;
  md += "### " + name + "\n\n";
  const double span = input.track.size() >= 2 ? input.track.back().t - input.track.front().t : 0;
  md += Format("%.0f detections over %.1f s", static_cast<double>(input.track.size()), span) +
        Format(", %.0f command samples. ", static_cast<double>(input.commands.size()));
  if (fit.from_commands) {
    md += "Fitted from the command steps: each step's ramp (level, onset, slope, level) is fitted to the "
          "detections' positions with the wheels' lag; latency is onset − command, the limits are the "
          "medians over the steps, intervals 95 % from their spread.\n\n";
  } else {
    md += "Fitted without commands (best effort): ramps are found where the robot-frame acceleration stays "
          "high, their slopes fitted to the positions; the limits are the upper half of those slopes and "
          "the top speed the fastest sustained plateaus, so a robot never driven to its limits reads low. "
          "No latency.\n\n";
  }
  if (!fit.enough_data) md += "**Not enough data: nothing estimated.**\n\n";
  if (!fit.problems.empty()) {
    for (const std::string& p : fit.problems) md += "- " + p + "\n";
    md += "\n";
  }
  const char* unit_steps = fit.from_commands ? "steps" : "ramps";
  md += "| quantity | estimate | 95 % interval | from |\n|---|---|---|---|\n";
  md += EstimateRow("top speed", fit.top_speed, 1, "%.3f", "m/s", fit.from_commands ? "steps" : "plateaus");
  md += EstimateRow("acceleration along", fit.accel_along, 1, "%.2f", "m/s²", unit_steps);
  md += EstimateRow("braking along", fit.brake_along, 1, "%.2f", "m/s²", unit_steps);
  md += EstimateRow("acceleration across", fit.accel_across, 1, "%.2f", "m/s²", unit_steps);
  md += EstimateRow("braking across", fit.brake_across, 1, "%.2f", "m/s²", unit_steps);
  md += EstimateRow("angular top speed", fit.angular_top_speed, 1, "%.2f", "rad/s", fit.from_commands ? "steps" : "plateaus");
  md += EstimateRow("angular acceleration", fit.angular_accel, 1, "%.1f", "rad/s²", unit_steps);
  md += EstimateRow("angular braking", fit.angular_brake, 1, "%.1f", "rad/s²", unit_steps);
  md += EstimateRow("latency", fit.latency, 1e3, "%.1f", "ms", "steps");
  md += EstimateRow("wheel lag", fit.wheel_lag, 1e3, "%.1f", "ms", "steps (profile)");
  if (fit.response_delay.ok()) {
    md += EstimateRow("latency + wheel lag", fit.response_delay, 1e3, "%.1f", "ms", "steps");
  }
  md += "\n";

  // Plots: per component, the largest used speed-up step with what follows it.
  const SmoothedTrack track(input.track);
  for (const MotionAxis axis : {MotionAxis::kForward, MotionAxis::kLeft, MotionAxis::kAngular}) {
    const SegmentRecord* best = nullptr;
    for (const SegmentRecord& r : fit.segments) {
      if (r.used && r.axis == axis && r.speeding_up &&
          (!best || std::abs(r.v_end - r.v_start) > std::abs(best->v_end - best->v_start))) {
        best = &r;
      }
    }
    if (!best) continue;
    const double t0 = best->t_change - 0.2;
    double t1 = best->t_end + 0.3;
    if (fit.from_commands) {
      for (const SegmentRecord& r : fit.segments) {
        if (std::abs(r.t_change - best->t_end) < 0.05) t1 = std::max(t1, std::min(r.t_end, best->t_end + 2.0));
      }
    }
    t1 = std::min(t1, t0 + 4.0);
    validation::Plot plot;
    plot.file = slug + "-" + AxisName(axis) + ".svg";
    plot.title = name + ": " + AxisName(axis) + (fit.from_commands ? " step" : " ramp") + Format(" at %.2f s", best->t_change);
    plot.x_label = fit.from_commands ? "time since the command, s" : "time since the window's start, s";
    plot.y_label = Linear(axis) ? "velocity in the robot frame, m/s" : "angular velocity, rad/s";
    const std::array<const char*, 3> names = {"forward", "left", "angular"};
    std::array<validation::Series, 3> measured;
    std::array<double, 3> start{};
    bool have_start = false;
    for (std::size_t k = 0; k < 3; ++k) {
      measured[k].label = std::string(names[k]) + " measured";
      measured[k].points = true;
    }
    for (double t = t0; t <= t1; t += 0.01) {
      const auto m = track.At(t, 0.05);
      if (!m || !std::isfinite(m->yaw)) continue;
      const double c = std::cos(m->yaw), s = std::sin(m->yaw);
      const std::array<double, 3> v = {c * m->vx + s * m->vy, -s * m->vx + c * m->vy, m->omega};
      if (!have_start) start = v, have_start = true;
      for (std::size_t k = 0; k < 3; ++k) {
        measured[k].x.push_back(t - best->t_change);
        measured[k].y.push_back(v[k]);
      }
    }
    const std::vector<std::size_t> shown = Linear(axis) ? std::vector<std::size_t>{0, 1} : std::vector<std::size_t>{2};
    for (std::size_t k : shown) plot.series.push_back(measured[k]);
    if (fit.from_commands) {
      const Response response = SimulateResponse(fit, input.commands, t0, t1, start);
      for (std::size_t k : shown) {
        validation::Series model;
        model.label = std::string(names[k]) + " model";
        for (std::size_t i = 0; i < response.t.size(); ++i) {
          model.x.push_back(response.t[i] - best->t_change);
          model.y.push_back(response.v[i][k]);
        }
        plot.series.push_back(std::move(model));
      }
      validation::Series command;
      command.label = std::string(names[static_cast<std::size_t>(axis)]) + " command";
      command.dashed = true;
      for (const CommandSample& c : input.commands) {
        if (c.t < t0 || c.t > t1) continue;
        command.x.push_back(c.t - best->t_change);
        command.y.push_back(axis == MotionAxis::kForward ? c.forward : axis == MotionAxis::kLeft ? c.left : c.angular);
      }
      plot.series.push_back(std::move(command));
    } else {
      validation::Series ramp;
      ramp.label = std::string(AxisName(axis)) + " fitted ramp";
      for (double t : {t0, best->onset, best->ramp_end, t1}) {
        ramp.x.push_back(t - best->t_change);
        ramp.y.push_back(t <= best->onset ? best->v_start : best->v_end);
      }
      plot.series.push_back(std::move(ramp));
    }
    md += "![" + plot.title + "](" + plot.file + ")\n\n";
    out.plots.push_back(std::move(plot));
  }

  // Segments: counts by reason, then a table of the first ones.
  std::map<std::string, int> reasons;
  int used = 0;
  for (const SegmentRecord& r : fit.segments) {
    if (r.used) {
      ++used;
    } else {
      ++reasons[ReasonKind(r.reason)];
    }
  }
  md += std::string("#### ") + (fit.from_commands ? "Steps" : "Ramps") + Format(": %.0f used", used) +
        Format(", %.0f rejected\n\n", static_cast<double>(fit.segments.size() - static_cast<std::size_t>(used)));
  if (!reasons.empty()) {
    std::vector<std::pair<int, std::string>> sorted;
    for (const auto& [reason, count] : reasons) sorted.emplace_back(count, reason);
    std::sort(sorted.rbegin(), sorted.rend());
    for (const auto& [count, reason] : sorted) md += Format("- %.0f: ", count) + reason + "\n";
    md += "\n";
  }
  if (!fit.segments.empty()) {
    md += "| t, s | component | command | kind | onset − t, ms | slope | level | rms | used |\n"
          "|---|---|---|---|---|---|---|---|---|\n";
    constexpr std::size_t kRows = 60;
    std::size_t rows = 0;
    for (const SegmentRecord& r : fit.segments) {
      if (rows++ == kRows) break;
      const bool linear = Linear(r.axis);
      const bool fitted = r.used || r.rms > 0;
      md += Format("| %.2f | ", r.t_change) + AxisName(r.axis) + " | " +
            (fit.from_commands ? Format("%+.2f → %+.2f", r.command_before, r.command_after) : std::string("—")) + " | " +
            (fitted ? (r.speeding_up ? "speed-up" : "slow-down") : "—") + std::string(r.speed_limited ? " (top)" : "") + " | " +
            (fitted ? Format("%.1f", (r.onset - r.t_change) * 1e3) : "—") + " | " +
            (fitted ? Format(linear ? "%.2f m/s²" : "%.1f rad/s²", r.slope) : "—") + " | " +
            (fitted ? Format(linear ? "%+.3f m/s" : "%+.2f rad/s", r.v_end) : "—") + " | " +
            (fitted ? Format(linear ? "%.1f mm" : "%.3f rad", linear ? r.rms * 1e3 : r.rms) : "—") + " | " +
            (r.used ? "yes" : "no: " + r.reason) + " |\n";
    }
    if (fit.segments.size() > kRows) md += Format("\n(%.0f more not listed)\n", static_cast<double>(fit.segments.size() - kRows));
    md += "\n";
  }
  return out;
}

}  // namespace ubersim::calibrate
