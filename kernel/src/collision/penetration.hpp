// SPDX-License-Identifier: Apache-2.0
// How far a convex shape reaches in a direction, and how deep two convex shapes overlap. Pure
// geometry on the SDK's Shape, independent of ODE's colliders, so the state checks
// (state_check.hpp) can judge a contact without trusting the code that made it.
#pragma once

#include <vector>

#include "ubersim/math.hpp"
#include "ubersim/scene.hpp"

namespace ubersim::kernel {

/// A shape at a world pose, answering support queries: how far it reaches along a direction.
/// Meshes and convex hulls count as the convex hull of their vertices (exact for the robots'
/// flat-front shells, which are convex). Planes are not supported (throws std::invalid_argument).
class PlacedShape {
 public:
  PlacedShape(const Shape& shape, const Pose& pose);

  /// max over the shape's points p of n·p, m (n need not be unit length: scales with it).
  double Support(const Vec3& n) const;
  /// Height of the shape's lowest point, m.
  double Lowest() const { return -Support(-Vec3::UnitZ()); }
  /// The pose's origin, world, m.
  const Vec3& centre() const { return centre_; }
  /// Radius of a sphere about centre() that holds the shape, m.
  double bounding_radius() const { return bounding_radius_; }
  /// The shape's own axes in the world (columns x, y, z).
  const Eigen::Matrix3d& axes() const { return axes_; }

 private:
  Shape::Kind kind_;
  Vec3 centre_;
  Eigen::Matrix3d axes_;
  double radius_ = 0, half_length_ = 0;
  Vec3 half_size_ = Vec3::Zero();
  std::vector<Vec3> vertices_;  // world frame (meshes, convex hulls)
  double bounding_radius_ = 0;
};

/// How deep `a` and `b` overlap: the shortest distance one must move to part them, m. Negative when
/// they are apart (minus their distance, approximately). Found by minimising the overlap along a
/// direction, h_a(n) + h_b(-n), over all directions. Any direction with an overlap at or below
/// `enough` ends the search early: the value returned is then only an upper bound, which is all
/// a check against a limit of `enough` needs.
double PenetrationDepth(const PlacedShape& a, const PlacedShape& b, double enough);

}  // namespace ubersim::kernel
