// SPDX-License-Identifier: Apache-2.0
// How much of the ball a camera sees past the robots (the league's enable_invisible_ball): points
// of the ball's silhouette ray-cast to the camera against the robots' hulls.
#pragma once

#include <vector>

#include "ubersim/math.hpp"
#include "ubersim/world_state.hpp"

namespace ubersim::kernel {

/// What a camera sees of the ball.
struct BallVisibility {
  double fraction = 1.0;          ///< of the silhouette's sample points, 0..1
  Vec3 centroid = Vec3::Zero();   ///< of the visible points (the ball's centre when all are)
};

/// The ball of `radius` at `ball` seen from `camera` past `robots`: upright cylinders of their
/// radius and height on the carpet, cut flat at their front (front_distances[i] from the centre,
/// in `robots`' order; none when empty). Robots off the field hide nothing.
BallVisibility VisibleBall(const Vec3& ball, double radius, const Vec3& camera, const std::vector<RobotState>& robots,
                           const std::vector<double>& front_distances);

/// A robot's hull as the cameras' rays meet it.
struct RobotHull {
  double cx = 0, cy = 0;          ///< centre on the carpet, m
  double radius = 0.09, height = 0.15;  ///< m
  double heading = 0;             ///< rad
  double front = 1e9;             ///< centre to the flat front, m (large: a full cylinder)
};

/// True when the segment from `from` to `to` passes through `hull`.
bool SegmentHitsHull(const Vec3& from, const Vec3& to, const RobotHull& hull);

}  // namespace ubersim::kernel
