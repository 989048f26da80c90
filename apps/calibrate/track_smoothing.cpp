// SPDX-License-Identifier: Apache-2.0
#include "track_smoothing.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Dense>

namespace ubersim::calibrate {

double AngleDifference(double a, double b) {
  double d = std::remainder(a - b, 2 * std::numbers::pi);
  if (d <= -std::numbers::pi) d += 2 * std::numbers::pi;
  return d;
}

SmoothedTrack::SmoothedTrack(std::vector<TrackPoint> track) : points_(std::move(track)) {
  for (std::size_t i = 1; i < points_.size(); ++i) {
    if (!std::isfinite(points_[i].yaw) || !std::isfinite(points_[i - 1].yaw)) continue;
    points_[i].yaw = points_[i - 1].yaw + AngleDifference(points_[i].yaw, points_[i - 1].yaw);
  }
}

std::size_t SmoothedTrack::LowerBound(double t) const {
  return static_cast<std::size_t>(
      std::lower_bound(points_.begin(), points_.end(), t, [](const TrackPoint& p, double v) { return p.t < v; }) -
      points_.begin());
}

std::optional<LocalMotion> SmoothedTrack::At(double t, double half_window, int min_points) const {
  const std::size_t begin = LowerBound(t - half_window);
  std::size_t end = begin;
  int before = 0, after = 0;
  while (end < points_.size() && points_[end].t <= t + half_window) {
    (points_[end].t < t ? before : after) += 1;
    ++end;
  }
  const int n = static_cast<int>(end - begin);
  if (n < std::max(min_points, 3) || before == 0 || after == 0) return std::nullopt;
  // Least squares in τ = t_i − t: p(τ) = c0 + c1·τ + c2·τ², the same design for x, y and yaw.
  Eigen::MatrixXd a(n, 3);
  Eigen::MatrixXd b(n, 3);
  for (int i = 0; i < n; ++i) {
    const TrackPoint& p = points_[begin + i];
    const double tau = p.t - t;
    a.row(i) << 1.0, tau, tau * tau;
    b.row(i) << p.x, p.y, std::isfinite(p.yaw) ? p.yaw : 0.0;
  }
  const Eigen::MatrixXd c = a.colPivHouseholderQr().solve(b);
  LocalMotion m;
  m.x = c(0, 0);
  m.y = c(0, 1);
  m.yaw = c(0, 2);
  m.vx = c(1, 0);
  m.vy = c(1, 1);
  m.omega = c(1, 2);
  m.ax = 2 * c(2, 0);
  m.ay = 2 * c(2, 1);
  m.alpha = 2 * c(2, 2);
  m.points = n;
  return m;
}

}  // namespace ubersim::calibrate
