// SPDX-License-Identifier: Apache-2.0
// The camera fit. Per camera:
//  * timing: t_capture against frame_number, a robust line per chunk of frames (jitter: the pooled
//    residual σ with the lines' degrees of freedom, so a slow clock drift does not count), a line
//    per unbroken run of the counter (the period, hence the frame rate); latency and processing
//    stamp as medians of the frames' stamps;
//  * noise: every detection against a local quadratic through the same camera's neighbouring
//    detections of that object (the motion model of track_smoothing.hpp, solved in closed form
//    because it runs millions of times); the centre's residual divided by √(1 − leverage) has the
//    detection's own variance, so σ needs no further correction. A fit whose centre or RSS is too
//    large for the noise (kicks, collisions, wrong identities) is not smooth motion, and neither
//    is any fit sharing a detection with it (a kink at a window's edge bends a fit without failing
//    it). σ grows with the distance d from the nadir as σ₀(1 + g·d): a weighted line through σ
//    per distance bin. Intervals by a jackknife over time blocks (neighbouring fits share
//    detections). Above max_noise_fits per camera and kind every k-th detection is judged;
//  * drop-outs: between two sightings of an object by this camera a few frames apart, each frame
//    sees it or misses it; each run's first and last sightings are left out (they are sightings
//    by construction), and only frames with the object well inside the convex hull of where the
//    camera detected things count;
//  * false balls: ball detections neither the ball's track nor near it, split into those at a
//    robot's dribbler corner (per robot in view and second) and the rest, less detections chained
//    in place for a second or more (another ball lying there).
// Across cameras: the phase between their frames, and how far each sees past the border it shares
// with a neighbour (the bisector of their nadirs): the edge of the step in "a saw the robot in
// this frame" against where the robot was (from b's sightings), with a block bootstrap interval.
#include "camera_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <sstream>
#include <unordered_map>

#include <Eigen/Dense>

#include "track_smoothing.hpp"

namespace ubersim::calibrate {
namespace {

constexpr double kZ95 = 1.959963984540054;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------------
// Small statistics.

double Median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  double m = v[mid];
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid)));
  return m;
}

/// σ from the median absolute value (data centred on zero).
double MadSigma(const std::vector<double>& v) {
  std::vector<double> a(v.size());
  std::transform(v.begin(), v.end(), a.begin(), [](double x) { return std::abs(x); });
  return 1.482602218505602 * Median(std::move(a));
}

/// The median with its order-statistics 95 % interval.
Estimate MedianEstimate(std::vector<double> v) {
  Estimate e;
  if (v.empty()) return e;
  std::sort(v.begin(), v.end());
  const double n = static_cast<double>(v.size());
  e.value = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  const double half = kZ95 * std::sqrt(n) / 2;
  const auto lo = static_cast<std::ptrdiff_t>(std::floor(n / 2 - half));
  const auto hi = static_cast<std::ptrdiff_t>(std::ceil(n / 2 + half));
  e.low = v[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(lo, 0, static_cast<std::ptrdiff_t>(n) - 1))];
  e.high = v[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(hi, 0, static_cast<std::ptrdiff_t>(n) - 1))];
  e.samples = static_cast<int>(v.size());
  return e;
}

/// A fraction k/n with Wilson's 95 % interval.
Estimate Proportion(std::int64_t k, std::int64_t n) {
  Estimate e;
  if (n <= 0) return e;
  const double p = static_cast<double>(k) / static_cast<double>(n), nn = static_cast<double>(n);
  const double z2 = kZ95 * kZ95;
  const double centre = (p + z2 / (2 * nn)) / (1 + z2 / nn);
  const double half = kZ95 * std::sqrt(p * (1 - p) / nn + z2 / (4 * nn * nn)) / (1 + z2 / nn);
  e.value = p;
  e.low = std::max(0.0, centre - half);
  e.high = std::min(1.0, centre + half);
  e.samples = static_cast<int>(std::min<std::int64_t>(n, std::numeric_limits<int>::max()));
  return e;
}

/// k events over `exposure` (s, or robot·s): the rate with a 95 % Poisson interval
/// (Wilson–Hilferty's approximation to the exact one).
Estimate PoissonRate(std::int64_t k, double exposure) {
  Estimate e;
  if (!(exposure > 0)) return e;
  const double kk = static_cast<double>(k);
  const auto cube = [](double x) { return x * x * x; };
  const double low = k == 0 ? 0.0 : kk * cube(1 - 1 / (9 * kk) - kZ95 / (3 * std::sqrt(kk)));
  const double k1 = kk + 1;
  const double high = k1 * cube(1 - 1 / (9 * k1) + kZ95 / (3 * std::sqrt(k1)));
  e.value = kk / exposure;
  e.low = std::max(0.0, low) / exposure;
  e.high = high / exposure;
  e.samples = static_cast<int>(std::max<std::int64_t>(k, 1));
  return e;
}

/// The χ² quantile with `dof` degrees of freedom at the normal quantile z (Wilson–Hilferty).
double ChiSquareQuantile(double dof, double z) {
  const double c = 2 / (9 * dof);
  const double x = 1 - c + z * std::sqrt(c);
  return dof * std::max(0.0, x * x * x);
}

/// Student's t two-sided 95 % quantile with `dof` degrees of freedom (Cornish–Fisher expansion).
double T95(int dof) {
  const double z = kZ95, v = std::max(dof, 1);
  return z + (z * z * z + z) / (4 * v) + (5 * std::pow(z, 5) + 16 * z * z * z + 3 * z) / (96 * v * v);
}

/// Weighted median of (value, weight): each value stands at the middle of its weight's share of
/// the cumulative weight, and the median is interpolated at one half (two cameras of equal
/// frames give their mean, three the middle one).
double WeightedMedian(std::vector<std::pair<double, double>> v) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  double total = 0;
  for (const auto& [x, w] : v) total += w;
  if (!(total > 0)) return v[v.size() / 2].first;
  double before = 0, prev_at = 0, prev_x = v.front().first;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const double at = (before + 0.5 * v[i].second) / total;
    if (at >= 0.5) {
      if (i == 0 || at == prev_at) return v[i].first;
      return prev_x + (v[i].first - prev_x) * (0.5 - prev_at) / (at - prev_at);
    }
    before += v[i].second;
    prev_at = at;
    prev_x = v[i].first;
  }
  return v.back().first;
}

// ---------------------------------------------------------------------------------------------
// Per camera data.

/// One object's detections by one camera, with the index of each one's frame in that camera.
struct SubTrack {
  std::vector<TrackPoint> points;
  std::vector<int> frame;  // index into Cam::frames, −1 when not found
};

/// Where a camera sees: the convex hull of the cells where it detected things (a few detections
/// each, so a stray one does not widen it), and whether a point lies `margin` inside it.
struct Area {
  std::vector<Eigen::Vector2d> hull;     // counter-clockwise
  std::vector<Eigen::Vector3d> edges;    // unit inward normal (x, y) and offset: n·p − c ≥ 0 inside
  double margin = 0;
  bool Inside(double x, double y) const {
    if (edges.empty() || !std::isfinite(x) || !std::isfinite(y)) return false;
    for (const Eigen::Vector3d& e : edges) {
      if (e.x() * x + e.y() * y - e.z() < margin) return false;
    }
    return true;
  }
};

struct Cam {
  int id = 0;
  std::vector<const CameraFrame*> frames;
  std::vector<double> t;  // t_capture of each frame
  double period = 0;      // s
  std::optional<Eigen::Vector2d> nadir;
  std::map<RobotKey, SubTrack> robots;
  SubTrack ball;
  Area area;
  CameraStats stats;

  int FrameIndex(double time) const {
    if (t.empty()) return -1;
    const auto it = std::lower_bound(t.begin(), t.end(), time - 1e-7);
    const double tol = std::max(1e-6, 0.01 * period);
    if (it != t.end() && std::abs(*it - time) <= tol) return static_cast<int>(it - t.begin());
    if (it != t.begin() && std::abs(*(it - 1) - time) <= tol) return static_cast<int>(it - t.begin()) - 1;
    return -1;
  }
  double Distance(double x, double y) const { return nadir ? std::hypot(x - nadir->x(), y - nadir->y()) : 0.0; }
};

std::string CameraName(int id) { return "camera " + std::to_string(id); }

/// A number with `digits` decimals, for messages.
std::string Fixed(double v, int digits) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

// ---------------------------------------------------------------------------------------------
// Timing.

void FitTiming(Cam& cam, const CameraFitOptions& options, std::vector<std::string>& problems) {
  CameraStats& s = cam.stats;
  const std::size_t n = cam.frames.size();
  if (n < 3) {
    problems.push_back(CameraName(cam.id) + ": fewer than 3 frames, no frame rate, jitter or latency.");
    return;
  }
  // Latency and the processing stamp.
  std::vector<double> latency, processing;
  latency.reserve(n);
  processing.reserve(n);
  for (const CameraFrame* f : cam.frames) {
    latency.push_back(f->t_received - f->t_capture);
    processing.push_back(f->t_sent - f->t_capture);
  }
  s.latency = MedianEstimate(std::move(latency));
  s.processing_time = MedianEstimate(std::move(processing));
  if (!(s.latency.value >= 0 && s.latency.value < 2)) {
    problems.push_back(CameraName(cam.id) + ": t_received − t_capture is " + Fixed(s.latency.value, 3) +
                       " s: the recorder's clock is not the vision's, no latency.");
    s.latency = {};
  }
  if (!(s.processing_time.value >= 0 && s.processing_time.value < 2)) {
    problems.push_back(CameraName(cam.id) + ": t_sent − t_capture is " + Fixed(s.processing_time.value, 3) +
                       " s: the frames carry no usable send stamp, no processing time.");
    s.processing_time = {};
  }

  // The nominal period: the median spacing per counted frame.
  std::vector<double> spacing;
  spacing.reserve(n);
  for (std::size_t i = 1; i < n; ++i) {
    const std::int64_t dn = cam.frames[i]->frame_number - cam.frames[i - 1]->frame_number;
    const double dt = cam.t[i] - cam.t[i - 1];
    if (dn >= 1 && dt > 0) spacing.push_back(dt / static_cast<double>(dn));
  }
  const double t0 = Median(spacing);
  if (!(t0 > 0)) {
    problems.push_back(CameraName(cam.id) + ": frame numbers do not advance with capture time, no frame rate.");
    return;
  }
  cam.period = t0;
  // Unbroken runs of the counter (a restarted ssl-vision starts again).
  std::vector<std::pair<std::size_t, std::size_t>> segments;
  std::size_t begin = 0;
  for (std::size_t i = 1; i <= n; ++i) {
    bool cut = i == n;
    if (!cut) {
      const std::int64_t dn = cam.frames[i]->frame_number - cam.frames[i - 1]->frame_number;
      const double dt = cam.t[i] - cam.t[i - 1];
      cut = dn <= 0 || std::abs(dt - static_cast<double>(dn) * t0) > 0.5 * t0 + 1e-3 * static_cast<double>(dn) * t0;
      if (!cut) {
        s.dropped_frames += static_cast<int>(dn - 1);
      } else if (dn == 1 && dt > 1.5 * t0 && dt < 1.0) {
        s.dropped_frames += static_cast<int>(std::lround(dt / t0)) - 1;  // lost without the counter knowing
      }
    }
    if (cut) {
      segments.emplace_back(begin, i);
      begin = i;
    }
  }
  // Jitter: robust local lines over chunks; the period: one line per segment over the inliers.
  double rss = 0, dof = 0;
  double w_sum = 0, wb_sum = 0;
  std::int64_t used = 0;
  std::vector<std::uint8_t> inlier(n, 0);
  std::vector<double> residual(n, kNaN);
  const int chunk = std::max(options.jitter_chunk_frames, 8);
  for (const auto& [sb, se] : segments) {
    const std::size_t len = se - sb;
    if (len < 4) continue;
    const std::int64_t n0 = cam.frames[sb]->frame_number;
    const auto number = [&](std::size_t i) { return static_cast<double>(cam.frames[i]->frame_number - n0); };
    const std::size_t chunks = std::max<std::size_t>(1, len / static_cast<std::size_t>(chunk));
    for (std::size_t c = 0; c < chunks; ++c) {
      const std::size_t cb = sb + c * len / chunks, ce = sb + (c + 1) * len / chunks;
      if (ce - cb < 4) continue;
      // Start from the nominal period, then least squares over the inliers, twice; in the
      // chunk's own origin (frame number and time of its first frame) to keep the sums small.
      const double x0 = number(cb), y0 = cam.t[cb];
      const auto xr = [&](std::size_t i) { return number(i) - x0; };
      const auto yr = [&](std::size_t i) { return cam.t[i] - y0; };
      std::vector<double> r;
      r.reserve(ce - cb);
      for (std::size_t i = cb; i < ce; ++i) r.push_back(yr(i) - t0 * xr(i));
      double a = Median(r), b = t0;
      double sigma = 0;
      for (int pass = 0; pass < 2; ++pass) {
        for (std::size_t i = cb; i < ce; ++i) r[i - cb] = yr(i) - a - b * xr(i);
        sigma = std::max(MadSigma(r), 1e-7);
        double sn = 0, st = 0, snn = 0, snt = 0, m = 0;
        for (std::size_t i = cb; i < ce; ++i) {
          if (std::abs(r[i - cb]) > 5 * sigma) continue;
          const double x = xr(i), y = yr(i);
          sn += x, st += y, snn += x * x, snt += x * y, m += 1;
        }
        if (m < 4) break;
        const double den = m * snn - sn * sn;
        if (!(den > 0)) break;
        b = (m * snt - sn * st) / den;
        a = (st - b * sn) / m;
      }
      double chunk_rss = 0, chunk_m = 0;
      for (std::size_t i = cb; i < ce; ++i) {
        const double e = yr(i) - a - b * xr(i);
        if (std::abs(e) > 5 * sigma) continue;
        chunk_rss += e * e;
        chunk_m += 1;
        inlier[i] = 1;
        residual[i] = e;
      }
      if (chunk_m > 2) {
        rss += chunk_rss;
        dof += chunk_m - 2;
      }
    }
    // The segment's period: least squares over its inliers, centred.
    double m = 0, mx = 0, my = 0;
    for (std::size_t i = sb; i < se; ++i) {
      if (!inlier[i]) continue;
      m += 1, mx += number(i), my += cam.t[i];
    }
    if (m < 4) continue;
    mx /= m, my /= m;
    double sxx = 0, sxy = 0;
    for (std::size_t i = sb; i < se; ++i) {
      if (!inlier[i]) continue;
      sxx += (number(i) - mx) * (number(i) - mx);
      sxy += (number(i) - mx) * (cam.t[i] - my);
    }
    if (!(sxx > 0)) continue;
    const double b = sxy / sxx;
    double srr = 0;
    for (std::size_t i = sb; i < se; ++i) {
      if (!inlier[i]) continue;
      const double e = cam.t[i] - my - b * (number(i) - mx);
      srr += e * e;
    }
    const double se2 = std::max(srr / (m - 2) / sxx, 1e-30);
    w_sum += 1 / se2;
    wb_sum += b / se2;
    used += static_cast<std::int64_t>(m);
  }
  if (w_sum > 0) {
    const double period = wb_sum / w_sum, se = std::sqrt(1 / w_sum);
    cam.period = period;
    s.frame_rate.value = 1 / period;
    s.frame_rate.low = 1 / (period + kZ95 * se);
    s.frame_rate.high = 1 / std::max(period - kZ95 * se, 1e-12);
    s.frame_rate.samples = static_cast<int>(used);
  } else {
    problems.push_back(CameraName(cam.id) + ": no run of 4 or more frames with a steady counter, no frame rate.");
  }
  if (dof >= 10) {
    const double sigma = std::sqrt(rss / dof);
    s.capture_jitter.value = sigma;
    s.capture_jitter.low = sigma * std::sqrt(dof / ChiSquareQuantile(dof, kZ95));
    s.capture_jitter.high = sigma * std::sqrt(dof / ChiSquareQuantile(dof, -kZ95));
    s.capture_jitter.samples = static_cast<int>(dof);
  } else {
    problems.push_back(CameraName(cam.id) + ": too few steady frames for the capture jitter.");
  }
  // The plot: up to 3000 residuals over time.
  const std::size_t step = std::max<std::size_t>(1, n / 3000);
  for (std::size_t i = 0; i < n; i += step) {
    if (!std::isfinite(residual[i])) continue;
    s.curves.jitter_t.push_back(cam.t[i]);
    s.curves.jitter_ms.push_back(residual[i] * 1e3);
  }
}

// ---------------------------------------------------------------------------------------------
// Noise.

/// One detection judged against the local quadratic through its neighbours.
struct LocalResidual {
  double t = 0, d = 0;           // time, distance from the nadir
  double zx = 0, zy = 0;         // centre residual / √(1 − h), m
  double zyaw = kNaN;            // rad (NaN: no heading in the window)
  double rss_pos = 0;            // the window's residual sum of squares, x and y
  double rss_yaw = kNaN;
  int dof = 0;                   // per axis: points − 3
  int track = 0, lo = 0, hi = 0; // which track, and the window's first and last point in it
};

void LocalFits(const std::vector<TrackPoint>& pts, int track, const Cam& cam, std::size_t stride,
               const CameraFitOptions& o, std::vector<LocalResidual>& out) {
  const int n = static_cast<int>(pts.size());
  const double hw = o.noise_half_window;
  const int k = std::max(o.noise_neighbours, 2);
  for (int i = 0; i < n; i += static_cast<int>(stride)) {
    const TrackPoint& c = pts[static_cast<std::size_t>(i)];
    int lo = i, hi = i;
    while (lo > 0 && i - (lo - 1) <= k && c.t - pts[static_cast<std::size_t>(lo - 1)].t <= hw) --lo;
    while (hi + 1 < n && (hi + 1) - i <= k && pts[static_cast<std::size_t>(hi + 1)].t - c.t <= hw) ++hi;
    const int m = hi - lo + 1;
    if (i - lo < 2 || hi - i < 2 || m < std::max(o.noise_min_points, 4)) continue;
    Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d b = Eigen::Matrix3d::Zero();  // columns x, y, yaw
    Eigen::Vector3d yy = Eigen::Vector3d::Zero();
    bool yaw_ok = std::isfinite(c.yaw);
    for (int j = lo; j <= hi; ++j) {
      const TrackPoint& p = pts[static_cast<std::size_t>(j)];
      const double u = (p.t - c.t) / hw;
      const Eigen::Vector3d phi(1.0, u, u * u);
      s.noalias() += phi * phi.transpose();
      const double dyaw = p.yaw - c.yaw;
      if (!std::isfinite(dyaw)) yaw_ok = false;
      const Eigen::Vector3d v(p.x - c.x, p.y - c.y, std::isfinite(dyaw) ? dyaw : 0.0);
      b.noalias() += phi * v.transpose();
      yy += v.cwiseProduct(v);
    }
    const double det = s.determinant();
    if (!(std::abs(det) > 1e-12)) continue;
    const Eigen::Matrix3d inv = s.inverse();
    const Eigen::Matrix3d coef = inv * b;
    const double h = inv(0, 0);
    if (!(h < 1)) continue;
    const double scale = 1 / std::sqrt(1 - h);
    LocalResidual r;
    r.t = c.t;
    r.d = cam.Distance(c.x, c.y);
    r.zx = -coef(0, 0) * scale;
    r.zy = -coef(0, 1) * scale;
    r.dof = m - 3;
    r.track = track;
    r.lo = lo;
    r.hi = hi;
    r.rss_pos = std::max(0.0, yy(0) - coef.col(0).dot(b.col(0))) + std::max(0.0, yy(1) - coef.col(1).dot(b.col(1)));
    if (yaw_ok) {
      r.zyaw = -coef(0, 2) * scale;
      r.rss_yaw = std::max(0.0, yy(2) - coef.col(2).dot(b.col(2)));
    }
    out.push_back(r);
  }
}

/// Accepted squared residuals (per axis) by time block and distance bin.
struct NoiseSums {
  int blocks = 1, bins = 1;
  std::vector<double> v, n, d;  // [block * bins + bin]: Σ z², count, Σ distance
  std::int64_t samples = 0;
  std::vector<double> z;        // accepted residuals (for the histogram), m or rad
  std::vector<double> zd;       // their distances
  void Init(int b, int k) {
    blocks = b, bins = k;
    v.assign(static_cast<std::size_t>(b * k), 0.0);
    n.assign(v.size(), 0.0);
    d.assign(v.size(), 0.0);
  }
};

struct NoiseScale {
  double t_first = 0, t_last = 1;
  double bin = 0.1;
};

/// Accepts the residuals of smooth motion and sums them into `pos` (and `yaw` when given). A fit
/// fails when its centre is more than outlier_sigmas σ off or its RSS exceeds the χ² quantile there,
/// σ estimated robustly per coarse distance band; a fit sharing any detection with a failed one is
/// left out too (a kink at a window's edge bends the fit without failing it).
void AcceptResiduals(const std::vector<LocalResidual>& all, const NoiseScale& scale, const CameraFitOptions& o,
                     NoiseSums& pos, NoiseSums* yaw) {
  if (all.empty()) return;
  constexpr double kBand = 0.5;  // m
  const auto band_sigmas = [&](bool of_yaw) {
    std::map<int, std::vector<double>> bands;
    std::vector<double> every;
    for (const LocalResidual& r : all) {
      const int band = static_cast<int>(r.d / kBand);
      if (of_yaw) {
        if (!std::isfinite(r.zyaw)) continue;
        bands[band].push_back(r.zyaw);
        every.push_back(r.zyaw);
      } else {
        bands[band].push_back(r.zx);
        bands[band].push_back(r.zy);
        every.push_back(r.zx);
        every.push_back(r.zy);
      }
    }
    std::map<int, double> sigma;
    const double global = every.empty() ? kNaN : MadSigma(every);
    for (const auto& [band, values] : bands) sigma[band] = values.size() >= 100 ? MadSigma(values) : global;
    return sigma;
  };
  std::map<int, double> sigma_pos = band_sigmas(false), sigma_yaw;
  if (yaw) sigma_yaw = band_sigmas(true);
  const double k = o.outlier_sigmas;
  const auto fails = [&](const LocalResidual& r) {
    const int band = static_cast<int>(r.d / kBand);
    const double sp = sigma_pos[band];
    if (!(sp > 0)) return true;
    if (std::abs(r.zx) > k * sp || std::abs(r.zy) > k * sp) return true;
    if (r.rss_pos > sp * sp * ChiSquareQuantile(2.0 * r.dof, k)) return true;
    if (yaw && std::isfinite(r.zyaw)) {
      const double sy = sigma_yaw[band];
      if (!(sy > 0)) return true;
      if (std::abs(r.zyaw) > k * sy || r.rss_yaw > sy * sy * ChiSquareQuantile(r.dof, k)) return true;
    }
    return false;
  };
  const auto add = [&](NoiseSums& sums, double v, int axes, const LocalResidual& r) {
    const double span = scale.t_last - scale.t_first;
    const int block = std::clamp(static_cast<int>(sums.blocks * (r.t - scale.t_first) / (span > 0 ? span : 1)), 0,
                                 sums.blocks - 1);
    const int bin = std::clamp(static_cast<int>(r.d / scale.bin), 0, sums.bins - 1);
    const std::size_t at = static_cast<std::size_t>(block * sums.bins + bin);
    sums.v[at] += v;
    sums.n[at] += axes;
    sums.d[at] += r.d * axes;
    sums.samples += 1;
  };
  // Track by track (LocalFits emits each track's fits together, in order).
  std::vector<std::uint8_t> tainted;
  for (std::size_t first = 0; first < all.size();) {
    std::size_t last = first;
    int points = 0;
    while (last < all.size() && all[last].track == all[first].track) points = std::max(points, all[last++].hi + 1);
    tainted.assign(static_cast<std::size_t>(points), 0);
    for (std::size_t i = first; i < last; ++i) {
      if (fails(all[i])) std::fill(tainted.begin() + all[i].lo, tainted.begin() + all[i].hi + 1, 1);
    }
    for (std::size_t i = first; i < last; ++i) {
      const LocalResidual& r = all[i];
      if (std::any_of(tainted.begin() + r.lo, tainted.begin() + r.hi + 1, [](std::uint8_t t) { return t != 0; })) continue;
      add(pos, r.zx * r.zx + r.zy * r.zy, 2, r);
      pos.z.push_back(r.zx);
      pos.z.push_back(r.zy);
      pos.zd.push_back(r.d);
      pos.zd.push_back(r.d);
      if (yaw && std::isfinite(r.zyaw)) {
        add(*yaw, r.zyaw * r.zyaw, 1, r);
        yaw->z.push_back(r.zyaw);
        yaw->zd.push_back(r.d);
      }
    }
    first = last;
  }
}

/// Per-bin totals with one time block left out (−1: none).
struct Bins {
  std::vector<double> v, n, d;
};
Bins Totals(const NoiseSums& s, int leave_out) {
  Bins b;
  b.v.assign(static_cast<std::size_t>(s.bins), 0.0);
  b.n = b.v;
  b.d = b.v;
  for (int blk = 0; blk < s.blocks; ++blk) {
    if (blk == leave_out) continue;
    for (int k = 0; k < s.bins; ++k) {
      const std::size_t at = static_cast<std::size_t>(blk * s.bins + k);
      b.v[static_cast<std::size_t>(k)] += s.v[at];
      b.n[static_cast<std::size_t>(k)] += s.n[at];
      b.d[static_cast<std::size_t>(k)] += s.d[at];
    }
  }
  return b;
}

constexpr double kMinBinCount = 60;  // residuals (axes) for a bin to enter the growth line

/// g of σ(d) = σ₀(1 + g·d) from per-bin σ: weighted least squares of σ on d; nullopt when the bins
/// do not span enough distance.
std::optional<double> GrowthOf(const Bins& b, const CameraFitOptions& o) {
  double sw = 0, swx = 0, swy = 0, swxx = 0, swxy = 0, dmin = 1e9, dmax = -1e9;
  int used = 0;
  for (std::size_t k = 0; k < b.v.size(); ++k) {
    if (b.n[k] < kMinBinCount || !(b.v[k] > 0)) continue;
    const double sigma = std::sqrt(b.v[k] / b.n[k]), d = b.d[k] / b.n[k];
    const double w = b.n[k] / (sigma * sigma);  // var σ̂ ∝ σ²/n
    sw += w, swx += w * d, swy += w * sigma, swxx += w * d * d, swxy += w * d * sigma;
    dmin = std::min(dmin, d), dmax = std::max(dmax, d);
    ++used;
  }
  if (used < 3 || dmax - dmin < o.min_distance_span) return std::nullopt;
  const double den = sw * swxx - swx * swx;
  if (!(den > 0)) return std::nullopt;
  const double slope = (sw * swxy - swx * swy) / den;
  const double intercept = (swy - slope * swx) / sw;
  if (!(intercept > 0)) return std::nullopt;
  return slope / intercept;
}

/// σ₀ = √(mean z² / (1 + g·d)²) over the bins.
double SigmaAtNadir(const Bins& b, double g) {
  double v = 0, n = 0;
  for (std::size_t k = 0; k < b.v.size(); ++k) {
    if (!(b.n[k] > 0)) continue;
    const double d = b.d[k] / b.n[k];
    const double f = std::max(1 + g * d, 1e-3);
    v += b.v[k] / (f * f);
    n += b.n[k];
  }
  return n > 0 ? std::sqrt(v / n) : kNaN;
}

/// Jackknife interval over time blocks of a statistic of the sums; falls back to the χ² interval
/// of a plain σ when there are too few blocks with data.
template <typename Statistic>
Estimate Jackknife(const NoiseSums& s, Statistic stat, bool is_sigma) {
  Estimate e;
  const std::optional<double> full = stat(-1);
  if (!full || !std::isfinite(*full)) return e;
  e.value = *full;
  e.samples = static_cast<int>(s.samples);
  std::vector<double> reps;
  for (int blk = 0; blk < s.blocks; ++blk) {
    double nb = 0;
    for (int k = 0; k < s.bins; ++k) nb += s.n[static_cast<std::size_t>(blk * s.bins + k)];
    if (nb <= 0) continue;
    const std::optional<double> r = stat(blk);
    if (r && std::isfinite(*r)) reps.push_back(*r);
  }
  if (reps.size() >= 5) {
    const double b = static_cast<double>(reps.size());
    const double mean = std::accumulate(reps.begin(), reps.end(), 0.0) / b;
    double var = 0;
    for (double r : reps) var += (r - mean) * (r - mean);
    var *= (b - 1) / b;
    const double half = T95(static_cast<int>(reps.size()) - 1) * std::sqrt(var);
    e.low = e.value - half;
    e.high = e.value + half;
  } else if (is_sigma) {
    double n = 0;
    for (double x : s.n) n += x;
    e.low = e.value * std::sqrt(n / ChiSquareQuantile(n, kZ95));
    e.high = e.value * std::sqrt(n / ChiSquareQuantile(n, -kZ95));
  } else {
    e.samples = 0;
  }
  if (is_sigma) e.low = std::max(e.low, 0.0);
  return e;
}

void FitNoise(Cam& cam, const CameraFitOptions& o, const NoiseScale& scale, std::vector<std::string>& problems) {
  CameraStats& s = cam.stats;
  // Robots: position and heading from the same fits.
  std::size_t robot_points = 0;
  for (const auto& [key, st] : cam.robots) robot_points += st.points.size();
  const std::size_t stride_r = std::max<std::size_t>(1, (robot_points + o.max_noise_fits - 1) / std::max<std::size_t>(o.max_noise_fits, 1));
  std::vector<LocalResidual> robot_res;
  robot_res.reserve(robot_points / stride_r + 16);
  int track = 0;
  for (const auto& [key, st] : cam.robots) {
    // Headings unwrapped along this camera's own sightings.
    const SmoothedTrack unwrapped(st.points);
    LocalFits(unwrapped.points(), track++, cam, stride_r, o, robot_res);
  }
  std::vector<LocalResidual> ball_res;
  const std::size_t stride_b =
      std::max<std::size_t>(1, (cam.ball.points.size() + o.max_noise_fits - 1) / std::max<std::size_t>(o.max_noise_fits, 1));
  LocalFits(cam.ball.points, 0, cam, stride_b, o, ball_res);

  const int bins = cam.nadir ? static_cast<int>(std::ceil(30.0 / scale.bin)) : 1;
  const int blocks = std::max(o.jackknife_blocks, 1);
  NoiseSums pos, ori, ball;
  pos.Init(blocks, bins);
  ori.Init(blocks, bins);
  ball.Init(blocks, bins);
  AcceptResiduals(robot_res, scale, o, pos, &ori);
  AcceptResiduals(ball_res, scale, o, ball, nullptr);

  // Growth from the robots' positions (the most data), applied to every σ of this camera.
  const auto growth = [&](int leave_out) { return GrowthOf(Totals(pos, leave_out), o); };
  const bool enough_pos = pos.samples >= o.min_noise_samples;
  std::optional<double> g_full;
  if (enough_pos && cam.nadir) g_full = growth(-1);
  if (g_full) {
    s.noise_growth_per_metre = Jackknife(pos, growth, false);
  } else if (!cam.nadir) {
    problems.push_back(CameraName(cam.id) + ": the log's geometry gives no camera position, no noise growth with distance.");
  } else if (enough_pos) {
    problems.push_back(CameraName(cam.id) + ": the robots' detections do not span " +
                       Fixed(o.min_distance_span, 1) + " m of distance from the nadir, no noise growth.");
  }
  const auto g_of = [&](int leave_out) -> double {
    if (!g_full) return 0.0;
    const std::optional<double> g = growth(leave_out);
    return g ? *g : *g_full;
  };
  const auto sigma_of = [&](const NoiseSums& sums) {
    return [&sums, &g_of](int leave_out) -> std::optional<double> {
      return SigmaAtNadir(Totals(sums, leave_out), g_of(leave_out));
    };
  };
  const auto estimate = [&](const NoiseSums& sums, const char* what, Estimate& out) {
    if (sums.samples < o.min_noise_samples) {
      problems.push_back(CameraName(cam.id) + ": " + std::to_string(sums.samples) + " " + what +
                         " residuals of smooth motion, fewer than " + std::to_string(o.min_noise_samples) + ": no estimate.");
      return;
    }
    out = Jackknife(sums, sigma_of(sums), true);
  };
  estimate(pos, "robot position", s.robot_position_noise);
  estimate(ori, "robot heading", s.robot_orientation_noise);
  estimate(ball, "ball position", s.ball_position_noise);

  // Curves: the residual histogram at the nadir's scale, σ per distance bin.
  if (s.robot_position_noise.ok()) {
    const double g = s.noise_growth_per_metre.ok() ? s.noise_growth_per_metre.value : 0.0;
    const double sigma = s.robot_position_noise.value;
    constexpr int kBins = 41;
    const double lo = -4 * sigma, width = 8 * sigma / kBins;
    std::vector<double> counts(kBins, 0.0);
    for (std::size_t i = 0; i < pos.z.size(); ++i) {
      const double z = pos.z[i] / std::max(1 + g * pos.zd[i], 1e-3);
      const int b = static_cast<int>(std::floor((z - lo) / width));
      if (b >= 0 && b < kBins) counts[static_cast<std::size_t>(b)] += 1;
    }
    const double total = static_cast<double>(pos.z.size());
    for (int b = 0; b < kBins; ++b) {
      const double x = lo + (b + 0.5) * width;
      s.curves.residual_mm.push_back(x * 1e3);
      s.curves.residual_density.push_back(counts[static_cast<std::size_t>(b)] / (total * width * 1e3));
      s.curves.residual_gaussian.push_back(std::exp(-0.5 * x * x / (sigma * sigma)) /
                                           (std::sqrt(2 * std::numbers::pi) * sigma * 1e3));
    }
    if (cam.nadir) {
      // Plot bins of 0.25 m (the fit's are finer).
      const Bins all = Totals(pos, -1);
      const int merge = std::max(1, static_cast<int>(std::lround(0.25 / scale.bin)));
      for (std::size_t k0 = 0; k0 < all.v.size(); k0 += static_cast<std::size_t>(merge)) {
        double v = 0, n = 0, d = 0;
        for (std::size_t k = k0; k < std::min(all.v.size(), k0 + static_cast<std::size_t>(merge)); ++k) {
          v += all.v[k], n += all.n[k], d += all.d[k];
        }
        if (n < kMinBinCount) continue;
        s.curves.distance.push_back(d / n);
        s.curves.sigma_mm.push_back(std::sqrt(v / n) * 1e3);
        if (s.noise_growth_per_metre.ok()) s.curves.sigma_fit_mm.push_back(sigma * (1 + g * d / n) * 1e3);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Where each camera detected things.

struct Grid {
  double x0 = 0, y0 = 0, cell = 0.1;
  int nx = 0, ny = 0;
};

Grid MakeGrid(const std::vector<Cam>& cams, double cell) {
  double xmin = 1e9, xmax = -1e9, ymin = 1e9, ymax = -1e9;
  const auto add = [&](double x, double y) {
    if (!std::isfinite(x) || !std::isfinite(y) || std::abs(x) > 30 || std::abs(y) > 30) return;
    xmin = std::min(xmin, x), xmax = std::max(xmax, x), ymin = std::min(ymin, y), ymax = std::max(ymax, y);
  };
  for (const Cam& c : cams) {
    for (const CameraFrame* f : c.frames) {
      for (const RobotDetection& r : f->robots) add(r.x, r.y);
    }
    for (const TrackPoint& p : c.ball.points) add(p.x, p.y);
  }
  Grid g;
  g.cell = cell;
  if (xmin > xmax) return g;
  g.x0 = xmin - cell;
  g.y0 = ymin - cell;
  g.nx = static_cast<int>(std::ceil((xmax - xmin) / cell)) + 3;
  g.ny = static_cast<int>(std::ceil((ymax - ymin) / cell)) + 3;
  return g;
}

/// Andrew's monotone chain: the convex hull of `p`, counter-clockwise.
std::vector<Eigen::Vector2d> ConvexHull(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() != b.x() ? a.x() < b.x() : a.y() < b.y();
  });
  p.erase(std::unique(p.begin(), p.end()), p.end());
  if (p.size() < 3) return {};
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

void BuildArea(Cam& cam, const Grid& grid, double margin) {
  Area& a = cam.area;
  a.margin = margin;
  if (grid.nx <= 0 || grid.ny <= 0) return;
  std::vector<std::uint16_t> count(static_cast<std::size_t>(grid.nx) * static_cast<std::size_t>(grid.ny), 0);
  const auto mark = [&](double x, double y) {
    if (!std::isfinite(x) || !std::isfinite(y)) return;
    const int i = static_cast<int>(std::floor((x - grid.x0) / grid.cell));
    const int j = static_cast<int>(std::floor((y - grid.y0) / grid.cell));
    if (i < 0 || j < 0 || i >= grid.nx || j >= grid.ny) return;
    std::uint16_t& c = count[static_cast<std::size_t>(j) * grid.nx + i];
    if (c < 1000) ++c;
  };
  for (const CameraFrame* f : cam.frames) {
    for (const RobotDetection& r : f->robots) mark(r.x, r.y);
  }
  for (const TrackPoint& p : cam.ball.points) mark(p.x, p.y);
  std::vector<Eigen::Vector2d> centres;
  for (int j = 0; j < grid.ny; ++j) {
    for (int i = 0; i < grid.nx; ++i) {
      if (count[static_cast<std::size_t>(j) * grid.nx + i] >= 3) {
        centres.emplace_back(grid.x0 + (i + 0.5) * grid.cell, grid.y0 + (j + 0.5) * grid.cell);
      }
    }
  }
  a.hull = ConvexHull(std::move(centres));
  for (std::size_t i = 0; i < a.hull.size(); ++i) {
    const Eigen::Vector2d& p = a.hull[i];
    const Eigen::Vector2d& q = a.hull[(i + 1) % a.hull.size()];
    const Eigen::Vector2d d = (q - p).normalized();
    const Eigen::Vector2d inward(-d.y(), d.x());  // left of a counter-clockwise edge
    a.edges.emplace_back(inward.x(), inward.y(), inward.dot(p));
  }
}

// ---------------------------------------------------------------------------------------------
// Drop-outs.

struct DropCount {
  std::int64_t trials = 0, misses = 0;
};

void CountDrops(const SubTrack& st, const Cam& cam, int max_gap, DropCount& out) {
  int run_first = -1, prev = -1;
  std::size_t prev_point = 0;
  for (std::size_t k = 0; k < st.points.size(); ++k) {
    const int j = st.frame[k];
    if (j < 0 || j == prev) continue;
    if (prev < 0 || j < prev || j - prev > max_gap) {
      run_first = j;  // a new run; its first sighting is not a trial
      prev = j;
      prev_point = k;
      continue;
    }
    // prev is inside the run (not its first): a trial that saw the object.
    const TrackPoint& a = st.points[prev_point];
    const TrackPoint& b = st.points[k];
    if (prev != run_first && cam.area.Inside(a.x, a.y)) ++out.trials;
    // The frames between: misses, where the object was (interpolated) inside the area.
    for (int f = prev + 1; f < j; ++f) {
      const double tf = cam.t[static_cast<std::size_t>(f)];
      const double w = b.t > a.t ? (tf - a.t) / (b.t - a.t) : 0.5;
      if (cam.area.Inside(a.x + w * (b.x - a.x), a.y + w * (b.y - a.y))) {
        ++out.trials;
        ++out.misses;
      }
    }
    prev = j;
    prev_point = k;
  }
}

void FitDrops(Cam& cam, const CameraFitOptions& o, std::vector<std::string>& problems) {
  DropCount robots, ball;
  for (const auto& [key, st] : cam.robots) CountDrops(st, cam, o.drop_max_gap_frames, robots);
  CountDrops(cam.ball, cam, o.drop_max_gap_frames, ball);
  const auto set = [&](const DropCount& c, const char* what, Estimate& out) {
    if (c.trials < o.min_drop_trials) {
      problems.push_back(CameraName(cam.id) + ": " + std::to_string(c.trials) + " frames where the " + what +
                         " should have been seen, fewer than " + std::to_string(o.min_drop_trials) + ": no drop rate.");
      return;
    }
    out = Proportion(c.misses, c.trials);
  };
  set(robots, "robots", cam.stats.robot_drop);
  set(ball, "ball", cam.stats.ball_drop);
}

// ---------------------------------------------------------------------------------------------
// False balls.

struct Pose {
  double x = 0, y = 0, yaw = kNaN;
};

/// Where a track was at t: interpolated between its points within max_dt either side.
std::optional<Pose> PoseAt(const std::vector<TrackPoint>& tr, double t, double max_dt) {
  if (tr.empty()) return std::nullopt;
  const auto it = std::lower_bound(tr.begin(), tr.end(), t, [](const TrackPoint& p, double v) { return p.t < v; });
  const TrackPoint* next = it != tr.end() && it->t - t <= max_dt ? &*it : nullptr;
  const TrackPoint* prev = it != tr.begin() && t - (it - 1)->t <= max_dt ? &*(it - 1) : nullptr;
  if (!next && !prev) return std::nullopt;
  if (!next || !prev || next->t <= prev->t) {
    const TrackPoint* p = next ? next : prev;
    return Pose{p->x, p->y, p->yaw};
  }
  const double w = (t - prev->t) / (next->t - prev->t);
  Pose pose{prev->x + w * (next->x - prev->x), prev->y + w * (next->y - prev->y), kNaN};
  if (std::isfinite(prev->yaw) && std::isfinite(next->yaw)) pose.yaw = prev->yaw + w * AngleDifference(next->yaw, prev->yaw);
  return pose;
}

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int Find(int a) {
    while (parent[static_cast<std::size_t>(a)] != a) {
      parent[static_cast<std::size_t>(a)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(a)])];
      a = parent[static_cast<std::size_t>(a)];
    }
    return a;
  }
  void Join(int a, int b) { parent[static_cast<std::size_t>(Find(a))] = Find(b); }
};

void FitFalseBalls(Cam& cam, const CameraFitInput& in, const CameraFitOptions& o, std::vector<std::string>& problems) {
  CameraStats& s = cam.stats;
  if (!(cam.period > 0)) return;
  const double seconds = static_cast<double>(cam.frames.size()) * cam.period;
  if (seconds < o.min_duration) {
    problems.push_back(CameraName(cam.id) + ": its frames cover " + Fixed(seconds, 1) +
                       " s, too little for false-ball rates.");
    return;
  }
  // This camera's ball sightings by frame.
  std::unordered_map<int, std::vector<std::size_t>> ball_at;
  for (std::size_t k = 0; k < cam.ball.points.size(); ++k) {
    if (cam.ball.frame[k] >= 0) ball_at[cam.ball.frame[k]].push_back(k);
  }
  const double side = std::sqrt(std::max(0.0, o.robot_radius * o.robot_radius - in.robot_front * in.robot_front));
  struct Candidate {
    double t, x, y;
  };
  std::vector<Candidate> rest;
  std::int64_t dribbler = 0;
  std::int64_t robot_sightings = 0;
  for (std::size_t fi = 0; fi < cam.frames.size(); ++fi) {
    const CameraFrame& f = *cam.frames[fi];
    robot_sightings += static_cast<std::int64_t>(f.robots.size());
    if (f.balls.empty()) continue;
    const auto found = ball_at.find(static_cast<int>(fi));
    for (const BallDetection& d : f.balls) {
      bool is_ball = false;
      if (found != ball_at.end()) {
        for (std::size_t k : found->second) {
          const TrackPoint& p = cam.ball.points[k];
          if (std::abs(p.x - d.x) < 1e-6 && std::abs(p.y - d.y) < 1e-6) is_ball = true;
        }
      }
      if (!is_ball) {
        const std::optional<Pose> b = PoseAt(in.ball, cam.t[fi], 0.05);
        is_ball = b && std::hypot(b->x - d.x, b->y - d.y) <= o.ball_match_radius;
      }
      if (is_ball) continue;
      // At a dribbler corner of some robot?
      bool at_dribbler = false;
      for (const auto& [key, track] : in.robots) {
        const std::optional<Pose> r = PoseAt(track, cam.t[fi], 0.1);
        if (!r) continue;
        const double dx = d.x - r->x, dy = d.y - r->y;
        const double dist = std::hypot(dx, dy);
        if (dist > o.robot_radius + o.dribbler_radius + 0.02) continue;
        if (!std::isfinite(r->yaw)) continue;
        const double c = std::cos(r->yaw), sn = std::sin(r->yaw);
        const double u = c * dx + sn * dy, v = -sn * dx + c * dy;
        const double corner = std::min(std::hypot(u - in.robot_front, v - side), std::hypot(u - in.robot_front, v + side));
        if (corner <= o.dribbler_radius) {
          at_dribbler = true;
          break;
        }
      }
      if (at_dribbler) {
        ++dribbler;
      } else {
        rest.push_back({cam.t[fi], d.x, d.y});
      }
    }
  }
  // Another ball: detections chained cell to neighbouring cell within second_ball_link s over
  // second_ball_seconds or more.
  UnionFind sets(rest.size());
  std::unordered_map<std::int64_t, std::pair<int, double>> last;  // cell → (detection, time)
  const auto key = [](std::int64_t i, std::int64_t j) { return (i << 32) ^ (j & 0xffffffff); };
  for (std::size_t k = 0; k < rest.size(); ++k) {
    const std::int64_t ci = static_cast<std::int64_t>(std::floor(rest[k].x / o.second_ball_cell));
    const std::int64_t cj = static_cast<std::int64_t>(std::floor(rest[k].y / o.second_ball_cell));
    for (std::int64_t di = -1; di <= 1; ++di) {
      for (std::int64_t dj = -1; dj <= 1; ++dj) {
        const auto it = last.find(key(ci + di, cj + dj));
        if (it != last.end() && rest[k].t - it->second.second <= o.second_ball_link) {
          sets.Join(static_cast<int>(k), it->second.first);
        }
      }
    }
    last[key(ci, cj)] = {static_cast<int>(k), rest[k].t};
  }
  std::unordered_map<int, std::pair<double, double>> span;  // root → (first, last) time
  std::unordered_map<int, int> size;
  for (std::size_t k = 0; k < rest.size(); ++k) {
    const int root = sets.Find(static_cast<int>(k));
    auto [it, inserted] = span.try_emplace(root, rest[k].t, rest[k].t);
    if (!inserted) {
      it->second.first = std::min(it->second.first, rest[k].t);
      it->second.second = std::max(it->second.second, rest[k].t);
    }
    ++size[root];
  }
  std::int64_t false_balls = 0;
  for (std::size_t k = 0; k < rest.size(); ++k) {
    const int root = sets.Find(static_cast<int>(k));
    const auto& [first, lastt] = span[root];
    if (lastt - first >= o.second_ball_seconds && size[root] >= 5) {
      ++s.second_ball_detections;
    } else {
      ++false_balls;
    }
  }
  s.false_balls_per_second = PoissonRate(false_balls, seconds);
  // Per robot in view: the robots' sightings, with the ones dropped added back.
  const double seen = s.robot_drop.ok() && s.robot_drop.value < 0.9 ? 1 - s.robot_drop.value : 1.0;
  const double robot_seconds = static_cast<double>(robot_sightings) / seen * cam.period;
  if (robot_sightings > 0) s.dribbler_false_balls = PoissonRate(dribbler, robot_seconds);
}

// ---------------------------------------------------------------------------------------------
// Across cameras.

/// One frame of camera a with a robot past the border: how far past, and whether a saw it.
struct EdgeItem {
  double s = 0;      // m past the border
  bool seen = false;
  int block = 0;     // time block (for the bootstrap)
  bool operator<(const EdgeItem& o) const { return s < o.s; }
};

/// The change point of a step in P(seen) along s (items sorted by s): maximum likelihood of two
/// Bernoulli segments, over splits i in [from, to) with each item weighted by its block's weight.
/// Returns the split index (0: none) and fills `score` when given.
std::size_t BestSplit(const std::vector<EdgeItem>& items, const std::vector<double>& block_weight, std::size_t from,
                      std::size_t to, std::vector<double>* score) {
  const std::size_t n = items.size();
  double k_all = 0, n_all = 0;
  for (const EdgeItem& it : items) {
    const double w = block_weight[static_cast<std::size_t>(it.block)];
    n_all += w;
    k_all += it.seen ? w : 0;
  }
  const auto ll = [](double k, double m) {
    if (m <= 0) return 0.0;
    const double p = k / m;
    double r = 0;
    if (k > 0) r += k * std::log(p);
    if (m - k > 0) r += (m - k) * std::log(1 - p);
    return r;
  };
  double k1 = 0, n1 = 0;
  for (std::size_t i = 0; i < from; ++i) {
    const double w = block_weight[static_cast<std::size_t>(items[i].block)];
    n1 += w;
    k1 += items[i].seen ? w : 0;
  }
  double best = -std::numeric_limits<double>::infinity();
  std::size_t best_i = 0;
  for (std::size_t i = std::max<std::size_t>(from, 1); i < std::min(to, n); ++i) {
    const double w = block_weight[static_cast<std::size_t>(items[i - 1].block)];
    if (i > from || from == 0) {
      n1 += w;
      k1 += items[i - 1].seen ? w : 0;
    }
    if (items[i].s == items[i - 1].s || n1 <= 0 || n_all - n1 <= 0) continue;
    const double k2 = k_all - k1, n2 = n_all - n1;
    if (k1 / n1 <= k2 / n2) continue;
    const double v = ll(k1, n1) + ll(k2, n2);
    if (score) (*score)[i] = v;
    if (v > best) best = v, best_i = i;
  }
  return best_i;
}

/// The step's edge with a 95 % interval. The likelihood's split is pushed outwards (beyond it a
/// sighting is nearly impossible, so the split takes in the blurred ones), so it only places the
/// edge's zone, ±5 cm. With q the level inside, the edge is where the zone's items, counted from
/// its inner end, reach its sightings / q: unbiased for a blur symmetric about the edge. The
/// interval is a bootstrap over time blocks (neighbouring frames see the same robots).
std::optional<Estimate> StepEdge(std::vector<EdgeItem> items, int blocks) {
  const std::size_t n = items.size();
  if (n < 40) return std::nullopt;
  std::sort(items.begin(), items.end());
  std::vector<double> ones(static_cast<std::size_t>(blocks), 1.0);
  const std::size_t split = BestSplit(items, ones, 0, n, nullptr);
  if (split == 0) return std::nullopt;
  double k1 = 0;
  for (std::size_t i = 0; i < split; ++i) k1 += items[i].seen ? 1 : 0;
  double k2 = 0;
  for (std::size_t i = split; i < n; ++i) k2 += items[i].seen ? 1 : 0;
  const double n1 = static_cast<double>(split), n2 = static_cast<double>(n - split);
  if (k1 < 20 || n2 < 10 || k1 / n1 < 0.3 || k2 / n2 > 0.5 * k1 / n1) return std::nullopt;
  const double rough = 0.5 * (items[split - 1].s + items[split].s);
  constexpr double kReach = 0.05, kInside = 0.3;  // m
  const auto index = [&](double s) {
    return static_cast<std::size_t>(std::lower_bound(items.begin(), items.end(), EdgeItem{s}) - items.begin());
  };
  const std::size_t inner = index(rough - kInside), zone = index(rough - kReach), outer = index(rough + kReach);
  if (zone - inner < 20 || outer - zone < 10) return std::nullopt;
  const auto edge = [&](const std::vector<double>& w) -> std::optional<double> {
    double seen = 0, all = 0;
    for (std::size_t i = inner; i < zone; ++i) {
      const double wi = w[static_cast<std::size_t>(items[i].block)];
      all += wi;
      seen += items[i].seen ? wi : 0;
    }
    if (!(all > 0) || !(seen > 0)) return std::nullopt;
    const double q = seen / all;
    double zone_seen = 0;
    for (std::size_t i = zone; i < outer; ++i) zone_seen += items[i].seen ? w[static_cast<std::size_t>(items[i].block)] : 0;
    const double target = zone_seen / q;
    double acc = 0;
    for (std::size_t i = zone; i < outer; ++i) {
      const double wi = w[static_cast<std::size_t>(items[i].block)];
      if (acc + wi >= target && wi > 0) {
        const double lo = i == zone ? rough - kReach : items[i - 1].s;
        return lo + (items[i].s - lo) * (target - acc) / wi;
      }
      acc += wi;
    }
    return rough + kReach;
  };
  const std::optional<double> value = edge(ones);
  if (!value) return std::nullopt;
  Estimate e;
  e.value = *value;
  e.low = e.high = e.value;
  std::uint64_t state = 0x9e3779b97f4a7c15ULL;  // a fixed stream: the same log gives the same interval
  const auto next = [&state]() {
    state ^= state << 13, state ^= state >> 7, state ^= state << 17;
    return state;
  };
  std::vector<double> edges;
  std::vector<double> weight(static_cast<std::size_t>(blocks));
  for (int r = 0; r < 200; ++r) {
    std::fill(weight.begin(), weight.end(), 0.0);
    for (int b = 0; b < blocks; ++b) weight[next() % static_cast<std::uint64_t>(blocks)] += 1;
    if (const auto x = edge(weight)) edges.push_back(*x);
  }
  if (edges.size() >= 50) {
    std::sort(edges.begin(), edges.end());
    const auto at = [&](double q) { return edges[static_cast<std::size_t>(std::lround(q * static_cast<double>(edges.size() - 1)))]; };
    e.low = std::min(e.value, at(0.025));
    e.high = std::max(e.value, at(0.975));
  }
  e.samples = static_cast<int>(n);
  return e;
}

void FitAcross(std::vector<Cam>& cams, const NoiseScale& scale, int blocks, CameraFit& fit) {
  if (cams.size() < 2) return;
  // Phases: from a sample of each camera's frames to the nearest frame of every other camera.
  std::vector<double> gaps;
  double max_jitter = 0, min_period = 1e9;
  for (const Cam& c : cams) {
    if (c.stats.capture_jitter.ok()) max_jitter = std::max(max_jitter, c.stats.capture_jitter.value);
    if (c.period > 0) min_period = std::min(min_period, c.period);
  }
  for (const Cam& a : cams) {
    for (const Cam& b : cams) {
      if (&a == &b || a.t.size() < 10 || b.t.size() < 10) continue;
      const std::size_t step = std::max<std::size_t>(1, a.t.size() / 2000);
      for (std::size_t i = 0; i < a.t.size(); i += step) {
        const auto it = std::lower_bound(b.t.begin(), b.t.end(), a.t[i]);
        double g = 1e9;
        if (it != b.t.end()) g = std::min(g, *it - a.t[i]);
        if (it != b.t.begin()) g = std::min(g, a.t[i] - *(it - 1));
        if (g < 1e8) gaps.push_back(g);
      }
    }
  }
  if (!gaps.empty() && min_period < 1e8) {
    fit.phase_difference = Median(gaps);
    fit.unsynchronised = fit.phase_difference > std::max(4 * max_jitter, 0.1 * min_period);
  }

  // Overlap: for each neighbouring pair (a, b) and each way, the step in "a sees the robot too"
  // against how far b's sighting lies past the border (the bisector of their nadirs).
  std::vector<Eigen::Vector2d> centre(cams.size());
  for (std::size_t i = 0; i < cams.size(); ++i) {
    if (cams[i].nadir) {
      centre[i] = *cams[i].nadir;
      continue;
    }
    std::vector<double> xs, ys;
    for (const auto& [key, st] : cams[i].robots) {
      for (const TrackPoint& p : st.points) xs.push_back(p.x), ys.push_back(p.y);
    }
    centre[i] = xs.empty() ? Eigen::Vector2d(kNaN, kNaN) : Eigen::Vector2d(Median(xs), Median(ys));
  }
  std::vector<Estimate> edges;
  for (std::size_t ia = 0; ia < cams.size(); ++ia) {
    for (std::size_t ib = 0; ib < cams.size(); ++ib) {
      if (ia == ib || !centre[ia].allFinite() || !centre[ib].allFinite()) continue;
      const Eigen::Vector2d mid = 0.5 * (centre[ia] + centre[ib]);
      const double half = 0.5 * (centre[ib] - centre[ia]).norm();
      if (half < 0.1) continue;
      bool neighbours = true;  // no other camera as near the midpoint (a Voronoi edge, not a corner)
      for (std::size_t ic = 0; ic < cams.size(); ++ic) {
        if (ic != ia && ic != ib && centre[ic].allFinite() && (centre[ic] - mid).norm() < half + 0.01) neighbours = false;
      }
      if (!neighbours) continue;
      const Eigen::Vector2d u = (centre[ib] - centre[ia]) / (2 * half);
      const Cam& a = cams[ia];
      const Cam& b = cams[ib];
      if (!(a.period > 0)) continue;
      // For each frame of a: where each robot b followed was then (between b's sightings, at
      // most 2.5 frames apart), and whether a saw it in that frame.
      std::vector<EdgeItem> items;
      const double span = std::max(scale.t_last - scale.t_first, 1e-9);
      for (const auto& [key, st] : b.robots) {
        std::vector<int> hits;
        if (const auto other = a.robots.find(key); other != a.robots.end()) {
          for (int f : other->second.frame) {
            if (f >= 0) hits.push_back(f);
          }
        }
        for (std::size_t k = 0; k + 1 < st.points.size(); ++k) {
          const TrackPoint& p = st.points[k];
          const TrackPoint& q = st.points[k + 1];
          if (!(q.t > p.t) || q.t - p.t > 2.5 * b.period) continue;
          for (auto it = std::lower_bound(a.t.begin(), a.t.end(), p.t); it != a.t.end() && *it < q.t; ++it) {
            const double w = (*it - p.t) / (q.t - p.t);
            const Eigen::Vector2d at(p.x + w * (q.x - p.x), p.y + w * (q.y - p.y));
            const double s = (at - mid).dot(u);
            if (s < 0 || s > half) continue;
            const int frame = static_cast<int>(it - a.t.begin());
            const int block = std::clamp(static_cast<int>(blocks * (*it - scale.t_first) / span), 0, blocks - 1);
            items.push_back({s, std::binary_search(hits.begin(), hits.end(), frame), block});
          }
        }
      }
      if (const auto e = StepEdge(std::move(items), blocks)) edges.push_back(*e);
    }
  }
  if (edges.empty()) {
    fit.problems.push_back("no two neighbouring cameras saw the same robots across their border: no overlap.");
    return;
  }
  for (const Estimate& e : edges) {
    fit.overlap.value += e.value / static_cast<double>(edges.size());
    fit.overlap.low += e.low / static_cast<double>(edges.size());
    fit.overlap.high += e.high / static_cast<double>(edges.size());
    fit.overlap.samples += e.samples;
  }
}

void Sanitise(Estimate& e) {
  if (!std::isfinite(e.value) || !std::isfinite(e.low) || !std::isfinite(e.high)) e = {};
}

}  // namespace

CameraFit FitCameras(const CameraFitInput& input, const CameraFitOptions& options) {
  CameraFit fit;
  if (!input.frames || input.frames->empty()) {
    fit.problems.push_back("the log has no camera frames.");
    return fit;
  }
  const std::vector<CameraFrame>& frames = *input.frames;
  // Cameras and their frames, ordered by capture time.
  std::map<int, std::size_t> index;
  std::vector<Cam> cams;
  for (const CameraFrame& f : frames) {
    auto [it, inserted] = index.try_emplace(f.camera_id, cams.size());
    if (inserted) {
      cams.emplace_back();
      cams.back().id = f.camera_id;
    }
    cams[it->second].frames.push_back(&f);
  }
  std::sort(cams.begin(), cams.end(), [](const Cam& a, const Cam& b) { return a.id < b.id; });
  index.clear();
  for (std::size_t i = 0; i < cams.size(); ++i) index[cams[i].id] = i;
  double t_first = std::numeric_limits<double>::infinity(), t_last = -t_first;
  for (Cam& c : cams) {
    std::stable_sort(c.frames.begin(), c.frames.end(),
                     [](const CameraFrame* a, const CameraFrame* b) { return a->t_capture < b->t_capture; });
    c.t.reserve(c.frames.size());
    for (const CameraFrame* f : c.frames) c.t.push_back(f->t_capture);
    c.stats.camera_id = c.id;
    c.stats.frames = static_cast<int>(c.frames.size());
    c.stats.duration = c.t.back() - c.t.front();
    t_first = std::min(t_first, c.t.front());
    t_last = std::max(t_last, c.t.back());
    if (const auto p = input.cameras.find(c.id); p != input.cameras.end() && p->second.allFinite()) {
      c.nadir = Eigen::Vector2d(p->second.x(), p->second.y());
    }
  }
  for (Cam& c : cams) FitTiming(c, options, fit.problems);
  // The tracks split by camera, each point tied to its frame.
  const auto add = [&](SubTrack& st, const Cam& c, const TrackPoint& p) {
    st.points.push_back(p);
    st.frame.push_back(c.FrameIndex(p.t));
  };
  for (const TrackPoint& p : input.ball) {
    if (const auto it = index.find(p.camera_id); it != index.end()) add(cams[it->second].ball, cams[it->second], p);
  }
  for (const auto& [key, track] : input.robots) {
    for (const TrackPoint& p : track) {
      if (const auto it = index.find(p.camera_id); it != index.end()) add(cams[it->second].robots[key], cams[it->second], p);
    }
  }
  const Grid grid = MakeGrid(cams, options.area_cell);
  NoiseScale scale;
  scale.t_first = t_first;
  scale.t_last = t_last;
  scale.bin = options.distance_bin;
  for (Cam& c : cams) {
    BuildArea(c, grid, options.area_margin);
    FitNoise(c, options, scale, fit.problems);
    FitDrops(c, options, fit.problems);
    FitFalseBalls(c, input, options, fit.problems);
  }
  FitAcross(cams, scale, std::max(options.jackknife_blocks, 2), fit);

  const double duration = t_last - t_first;
  bool some_camera = false;
  for (Cam& c : cams) {
    CameraStats& s = c.stats;
    for (Estimate* e : {&s.frame_rate, &s.capture_jitter, &s.latency, &s.processing_time, &s.robot_position_noise,
                        &s.robot_orientation_noise, &s.ball_position_noise, &s.robot_drop, &s.ball_drop,
                        &s.false_balls_per_second, &s.dribbler_false_balls, &s.noise_growth_per_metre}) {
      Sanitise(*e);
    }
    if (s.frame_rate.ok() && s.latency.ok() && s.robot_position_noise.ok() && s.robot_drop.ok()) some_camera = true;
    fit.cameras.push_back(std::move(s));
  }
  Sanitise(fit.overlap);
  if (!std::isfinite(fit.phase_difference)) fit.phase_difference = 0;
  if (!(duration >= options.min_duration)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "the log spans %.1f s of frames, less than the %.0f s the camera fit needs.", duration,
                  options.min_duration);
    fit.problems.emplace_back(buf);
  } else if (!some_camera) {
    fit.problems.push_back("no camera gave frame rate, latency, robot noise and robot drop-outs together.");
  }
  fit.enough_data = duration >= options.min_duration && some_camera;
  return fit;
}

PerceptionValues PerceptionFromFit(const CameraFit& fit) {
  PerceptionValues out;
  out.unsynchronised_cameras = fit.unsynchronised;
  const auto key = [&](const char* name, Estimate CameraStats::*member) {
    std::vector<std::pair<double, double>> values;
    for (const CameraStats& c : fit.cameras) {
      const Estimate& e = c.*member;
      if (e.ok() && std::isfinite(e.value)) values.emplace_back(e.value, std::max(c.frames, 1));
    }
    if (!values.empty()) out.keys[name] = WeightedMedian(std::move(values));
  };
  key("frame_rate", &CameraStats::frame_rate);
  key("latency", &CameraStats::latency);
  key("processing_time", &CameraStats::processing_time);
  key("noise.robot_position", &CameraStats::robot_position_noise);
  key("noise.robot_orientation", &CameraStats::robot_orientation_noise);
  key("noise.ball_position", &CameraStats::ball_position_noise);
  key("noise.growth_per_metre", &CameraStats::noise_growth_per_metre);
  key("drop.robot", &CameraStats::robot_drop);
  key("drop.ball", &CameraStats::ball_drop);
  key("capture_jitter", &CameraStats::capture_jitter);
  key("dribbler_false_balls", &CameraStats::dribbler_false_balls);
  // The model's keys have ranges; a value just outside from noise is clipped to them.
  if (auto it = out.keys.find("noise.growth_per_metre"); it != out.keys.end()) it->second = std::clamp(it->second, 0.0, 10.0);
  for (const char* k : {"drop.robot", "drop.ball"}) {
    if (auto it = out.keys.find(k); it != out.keys.end()) it->second = std::clamp(it->second, 0.0, 1.0);
  }
  // The σ are at the nadir when a growth was fitted, else over every distance: then the growth
  // that goes with them is 0 (a base world's growth would inflate them).
  if (!out.keys.count("noise.growth_per_metre") &&
      (out.keys.count("noise.robot_position") || out.keys.count("noise.ball_position"))) {
    out.keys["noise.growth_per_metre"] = 0.0;
  }
  if (fit.overlap.ok()) out.keys["camera_overlap"] = std::max(0.0, fit.overlap.value);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Report.

namespace {

std::string Format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

/// A table row: value and interval scaled to the shown unit.
std::string Row(const std::string& what, const Estimate& e, double scale, const char* fmt, const std::string& unit,
                const std::string& from, const std::string& key) {
  std::string r = "| " + what + " | ";
  if (!e.ok()) return r + "not estimated | | | " + key + " |\n";
  r += Format(fmt, e.value * scale) + " " + unit + " | " + Format(fmt, e.low * scale) + " – " +
       Format(fmt, e.high * scale) + " | " + std::to_string(e.samples) + " " + from + " | " + key + " |\n";
  return r;
}

}  // namespace

ReportSection CameraReport(const CameraFit& fit) {
  ReportSection out;
  std::ostringstream md;
  md << "Each camera's frames and detections, measured as `perception:` defines them (docs/model-files.md). "
        "Noise is each detection against a local quadratic through the same camera's neighbouring detections "
        "(corrected for the fit's leverage); with a camera position it is σ at the nadir, growing by the "
        "fitted fraction per metre. Intervals are 95 %.\n\n";
  for (const CameraStats& c : fit.cameras) {
    md << "### Camera " << c.camera_id << "\n\n";
    md << c.frames << " frames over " << Format("%.1f", c.duration) << " s";
    if (c.dropped_frames) md << "; " << c.dropped_frames << " frames lost (skipped by the camera's counter, or a frame's time without it)";
    md << ". " << c.second_ball_detections << " ball detections were another ball (in place for a second or more).\n\n";
    md << "| quantity | value | 95 % interval | from | `perception:` key |\n|---|---|---|---|---|\n";
    md << Row("frame rate", c.frame_rate, 1, "%.4f", "Hz", "frames", "`frame_rate`");
    md << Row("capture jitter", c.capture_jitter, 1e3, "%.3f", "ms", "degrees of freedom", "`capture_jitter`");
    md << Row("latency (t_received − t_capture)", c.latency, 1e3, "%.2f", "ms", "frames", "`latency`");
    md << Row("processing (t_sent − t_capture)", c.processing_time, 1e3, "%.2f", "ms", "frames", "`processing_time`");
    md << Row("robot position σ", c.robot_position_noise, 1e3, "%.3f", "mm", "detections", "`noise.robot_position`");
    md << Row("robot heading σ", c.robot_orientation_noise, 1, "%.4f", "rad", "detections", "`noise.robot_orientation`");
    md << Row("ball position σ", c.ball_position_noise, 1e3, "%.3f", "mm", "detections", "`noise.ball_position`");
    md << Row("σ growth with distance", c.noise_growth_per_metre, 1, "%.4f", "1/m", "detections",
              "`noise.growth_per_metre`");
    md << Row("robot drop-out", c.robot_drop, 100, "%.2f", "%", "frames", "`drop.robot`");
    md << Row("ball drop-out", c.ball_drop, 100, "%.2f", "%", "frames", "`drop.ball`");
    md << Row("false balls at dribblers", c.dribbler_false_balls, 1, "%.4f", "1/s per robot", "detections",
              "`dribbler_false_balls`");
    md << Row("other false balls", c.false_balls_per_second, 1, "%.4f", "1/s", "detections", "(report only)");
    md << "\n";
    const std::string id = std::to_string(c.camera_id);
    if (!c.curves.residual_mm.empty()) {
      validation::Plot p;
      p.file = "camera-" + id + "-residuals.svg";
      p.title = "Camera " + id + ": robot position residuals";
      p.x_label = "residual at the nadir's scale, mm";
      p.y_label = "density, 1/mm";
      validation::Series measured{"measured", c.curves.residual_mm, c.curves.residual_density};
      measured.points = true;
      validation::Series gauss{"Gaussian, fitted σ", c.curves.residual_mm, c.curves.residual_gaussian};
      gauss.dashed = true;
      p.series = {measured, gauss};
      out.plots.push_back(p);
      md << "![Robot position residuals of camera " << id << "](" << p.file << ")\n\n";
    }
    if (!c.curves.jitter_t.empty()) {
      validation::Plot p;
      p.file = "camera-" + id + "-jitter.svg";
      p.title = "Camera " + id + ": capture time against its regular schedule";
      p.x_label = "t_capture, s";
      p.y_label = "t_capture − schedule, ms";
      validation::Series r{"frames", c.curves.jitter_t, c.curves.jitter_ms};
      r.points = true;
      p.series = {r};
      out.plots.push_back(p);
      md << "![Capture jitter of camera " << id << "](" << p.file << ")\n\n";
    }
    if (!c.curves.distance.empty()) {
      validation::Plot p;
      p.file = "camera-" + id + "-noise-distance.svg";
      p.title = "Camera " + id + ": robot position σ against distance from the nadir";
      p.x_label = "distance from the nadir, m";
      p.y_label = "σ, mm";
      validation::Series m{"measured", c.curves.distance, c.curves.sigma_mm};
      m.points = true;
      p.series = {m};
      if (c.curves.sigma_fit_mm.size() == c.curves.distance.size()) {
        validation::Series f{"σ₀(1 + g·d)", c.curves.distance, c.curves.sigma_fit_mm};
        f.dashed = true;
        p.series.push_back(f);
      }
      out.plots.push_back(p);
      md << "![Noise against distance, camera " << id << "](" << p.file << ")\n\n";
    }
  }
  md << "### The cameras together\n\n";
  md << "| quantity | value |\n|---|---|\n";
  md << "| cameras | " << fit.cameras.size() << " |\n";
  md << "| capture phases | " << (fit.unsynchronised ? "unsynchronised" : "synchronised") << " (median "
     << Format("%.2f", fit.phase_difference * 1e3) << " ms from a frame to the nearest of another camera) |\n";
  if (fit.overlap.ok()) {
    md << "| overlap past the shared border | " << Format("%.3f", fit.overlap.value) << " m ["
       << Format("%.3f", fit.overlap.low) << ", " << Format("%.3f", fit.overlap.high) << "] (`camera_overlap`) |\n";
  } else {
    md << "| overlap past the shared border | not estimated |\n";
  }
  md << "| enough data | " << (fit.enough_data ? "yes" : "no") << " |\n\n";
  if (!fit.problems.empty()) {
    md << "#### Not estimated\n\n";
    for (const std::string& p : fit.problems) md << "- " << p << "\n";
    md << "\n";
  }
  out.markdown = md.str();
  return out;
}

}  // namespace ubersim::calibrate
