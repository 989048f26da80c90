// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cmath>

#include <Eigen/Geometry>

namespace ubersim {
inline namespace v1 {

/// A 3-vector in metres, m/s, newtons… (SI, frame stated where used).
using Vec3 = Eigen::Vector3d;
/// A unit quaternion (w, x, y, z) for orientations.
using Quat = Eigen::Quaterniond;

/// `q * v` (v turned by the unit quaternion q) by Eigen's own formula, operation for operation
/// (the same bits), always inlined: at -O2 Eigen's is a call, and so was this one (through the
/// PLT, into whichever plugin's copy the loader bound first), which a step's hot loops (every
/// wheel, every wheel contact) notice.
[[gnu::always_inline]] inline Vec3 Rotate(const Quat& q, const Vec3& v) {
  const Vec3 axis = q.vec();
  Vec3 uv = axis.cross(v);
  uv += uv;
  return v + q.w() * uv + axis.cross(uv);
}

/// Position (m) and orientation of a frame, in the world frame unless stated.
struct Pose {
  Vec3 position = Vec3::Zero();            ///< origin of the frame, m
  Quat orientation = Quat::Identity();     ///< rotation from the frame to its parent

  /// Maps a point given in this frame into the parent frame.
  Vec3 Transform(const Vec3& p) const { return position + orientation * p; }
  /// Composes this pose with a pose given relative to it.
  Pose Compose(const Pose& child) const {
    return Pose{Transform(child.position), (orientation * child.orientation).normalized()};
  }
  /// Heading about the world z axis, rad in (-pi, pi].
  double Yaw() const {
    const Vec3 x = orientation * Vec3::UnitX();
    return std::atan2(x.y(), x.x());
  }
  /// A pose at position p turned by yaw rad about z.
  static Pose FromYaw(const Vec3& p, double yaw) {
    return Pose{p, Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ()))};
  }
};

/// Linear (m/s) and angular (rad/s) velocity, world frame.
struct Twist {
  Vec3 linear = Vec3::Zero();   ///< velocity of the body origin, m/s
  Vec3 angular = Vec3::Zero();  ///< angular velocity, rad/s
};

/// A sphere that bounds geometry: centre (m, world) and radius (m).
struct BoundingSphere {
  Vec3 center = Vec3::Zero();  ///< centre, world frame, m
  double radius = -1.0;        ///< radius, m; negative means empty

  /// True when the sphere bounds nothing.
  bool Empty() const { return radius < 0.0; }
  /// True when the two spheres overlap (touching counts).
  bool Overlaps(const BoundingSphere& o) const {
    if (Empty() || o.Empty()) return false;
    const double r = radius + o.radius;
    return (center - o.center).squaredNorm() <= r * r;
  }
  /// Grows this sphere to bound another one as well.
  void Merge(const BoundingSphere& o) {
    if (o.Empty()) return;
    if (Empty()) { *this = o; return; }
    const Vec3 d = o.center - center;
    const double dist = d.norm();
    if (dist + o.radius <= radius) return;        // o inside this
    if (dist + radius <= o.radius) { *this = o; return; }  // this inside o
    const double new_radius = 0.5 * (dist + radius + o.radius);
    center += d * ((new_radius - radius) / dist);
    radius = new_radius;
  }
};

}  // namespace v1
}  // namespace ubersim
