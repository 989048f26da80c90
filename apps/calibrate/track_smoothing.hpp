// SPDX-License-Identifier: Apache-2.0
// The motion under a track's noise: a local quadratic fit of position (and unwrapped heading)
// against time in a window about an instant, the way a tracker's smoother sees it. Used for
// velocities and accelerations (robot fit) and for the residuals that are a camera's noise.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "samples.hpp"

namespace ubersim::calibrate {

/// The local fit at one instant: position, velocity and acceleration, world frame, SI.
struct LocalMotion {
  double x = 0, y = 0, yaw = 0;     ///< m, rad (yaw unwrapped along the track)
  double vx = 0, vy = 0, omega = 0; ///< m/s, rad/s
  double ax = 0, ay = 0, alpha = 0; ///< m/s², rad/s²
  int points = 0;                   ///< detections the fit used
};

/// A time-ordered track with its headings unwrapped, ready for local fits.
class SmoothedTrack {
 public:
  /// `track` must be ordered by time (equal times allowed: two cameras' frames of one instant).
  explicit SmoothedTrack(std::vector<TrackPoint> track);

  /// The quadratic fit over the points within ±half_window s of `t` (at least `min_points`, and
  /// some on each side of t); nullopt when there are not enough.
  std::optional<LocalMotion> At(double t, double half_window, int min_points = 5) const;

  const std::vector<TrackPoint>& points() const { return points_; }  ///< the track, yaw unwrapped
  bool empty() const { return points_.empty(); }                     ///< no points

  /// Index of the first point at or after t.
  std::size_t LowerBound(double t) const;

 private:
  std::vector<TrackPoint> points_;
};

/// The angle a − b wrapped into (−π, π], rad.
double AngleDifference(double a, double b);

}  // namespace ubersim::calibrate
