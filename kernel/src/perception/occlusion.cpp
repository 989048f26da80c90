// SPDX-License-Identifier: Apache-2.0
#include "perception/occlusion.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace ubersim::kernel {

namespace {

// The silhouette's sample points: the centre and three rings of eight on the disk through the
// ball's centre that faces the camera (unit radius), so a visible fraction moves in steps of 1/25.
constexpr int kRings = 3, kPerRing = 8;
constexpr int kSamples = 1 + kRings * kPerRing;

std::array<Vec3, kSamples> SilhouetteSamples(const Vec3& ball, double radius, const Vec3& camera) {
  const Vec3 view = (camera - ball).normalized();
  // Two directions across the view, the first horizontal where it can be.
  Vec3 across = view.cross(Vec3::UnitZ());
  if (across.norm() < 1e-9) across = Vec3::UnitX();
  across.normalize();
  const Vec3 up = view.cross(across).normalized();
  std::array<Vec3, kSamples> out;
  out[0] = ball;
  int n = 1;
  for (int ring = 1; ring <= kRings; ++ring) {
    const double r = radius * ring / kRings;
    for (int k = 0; k < kPerRing; ++k) {
      const double a = 2.0 * M_PI * (k + 0.5 * (ring % 2)) / kPerRing;
      out[n++] = ball + r * (std::cos(a) * across + std::sin(a) * up);
    }
  }
  return out;
}

}  // namespace

bool SegmentHitsHull(const Vec3& from, const Vec3& to, const RobotHull& hull) {
  const Vec3 d = to - from;
  // The parameters t in [0, 1] where the segment is within the infinite cylinder: a quadratic.
  const double fx = from.x() - hull.cx, fy = from.y() - hull.cy;
  const double a = d.x() * d.x() + d.y() * d.y();
  const double b = 2.0 * (fx * d.x() + fy * d.y());
  const double c = fx * fx + fy * fy - hull.radius * hull.radius;
  double t0 = 0.0, t1 = 1.0;
  if (a < 1e-15) {
    if (c > 0) return false;  // a vertical segment outside the circle
  } else {
    const double disc = b * b - 4 * a * c;
    if (disc < 0) return false;
    const double root = std::sqrt(disc);
    t0 = std::max(t0, (-b - root) / (2 * a));
    t1 = std::min(t1, (-b + root) / (2 * a));
    if (t0 > t1) return false;
  }
  // Behind the flat front: the distance along the heading is linear in t.
  const double hx = std::cos(hull.heading), hy = std::sin(hull.heading);
  const double s0 = fx * hx + fy * hy, ds = d.x() * hx + d.y() * hy;
  if (std::abs(ds) < 1e-15) {
    if (s0 > hull.front) return false;
  } else {
    const double t_front = (hull.front - s0) / ds;
    if (ds > 0) {
      t1 = std::min(t1, t_front);
    } else {
      t0 = std::max(t0, t_front);
    }
    if (t0 > t1) return false;
  }
  // And within the height: z is linear in t.
  const double z0 = from.z() + t0 * d.z(), z1 = from.z() + t1 * d.z();
  return std::min(z0, z1) <= hull.height && std::max(z0, z1) >= 0.0;
}

BallVisibility VisibleBall(const Vec3& ball, double radius, const Vec3& camera, const std::vector<RobotState>& robots,
                           const std::vector<double>& front_distances) {
  // Only robots that can stand between: near the ball's ray in the plane.
  std::vector<RobotHull> near;
  const Vec3 ray = camera - ball;
  const double ray_length_xy = std::hypot(ray.x(), ray.y());
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const RobotState& r = robots[i];
    if (!r.present) continue;
    const double px = r.pose.position.x() - ball.x(), py = r.pose.position.y() - ball.y();
    double along = ray_length_xy > 1e-9 ? (px * ray.x() + py * ray.y()) / ray_length_xy : 0.0;
    along = std::clamp(along, 0.0, ray_length_xy);
    const double cross = std::sqrt(std::max(0.0, px * px + py * py - along * along));
    if (cross > r.radius + radius) continue;
    RobotHull hull;
    hull.cx = r.pose.position.x();
    hull.cy = r.pose.position.y();
    hull.radius = r.radius;
    hull.height = r.height;
    hull.heading = r.pose.Yaw();
    if (i < front_distances.size()) hull.front = front_distances[i];
    near.push_back(hull);
  }
  BallVisibility v;
  if (near.empty()) {
    v.centroid = ball;
    return v;
  }
  Vec3 sum = Vec3::Zero();
  int visible = 0;
  for (const Vec3& s : SilhouetteSamples(ball, radius, camera)) {
    const bool hidden =
        std::any_of(near.begin(), near.end(), [&](const RobotHull& h) { return SegmentHitsHull(s, camera, h); });
    if (!hidden) {
      sum += s;
      ++visible;
    }
  }
  v.fraction = static_cast<double>(visible) / kSamples;
  v.centroid = visible > 0 ? Vec3(sum / visible) : ball;
  return v;
}

}  // namespace ubersim::kernel
