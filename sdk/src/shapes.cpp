// SPDX-License-Identifier: Apache-2.0
#include <algorithm>
#include <limits>

#include "ubersim/error.hpp"
#include "ubersim/scene.hpp"

namespace ubersim {
inline namespace v1 {

Shape Shape::Prism(const std::vector<Vec3>& outline, double length) {
  if (outline.size() < 3) throw PluginError("Shape::Prism: an outline needs at least 3 corners");
  if (!(length > 0.0)) throw PluginError("Shape::Prism: length must be positive");
  Shape s;
  s.kind = Kind::kConvex;
  const unsigned n = static_cast<unsigned>(outline.size());
  for (const Vec3& p : outline) s.vertices.emplace_back(p.x(), p.y(), -0.5 * length);  // 0 … n-1
  for (const Vec3& p : outline) s.vertices.emplace_back(p.x(), p.y(), 0.5 * length);   // n … 2n-1
  s.indices.push_back(n);  // top, counter-clockwise from above
  for (unsigned i = 0; i < n; ++i) s.indices.push_back(n + i);
  s.indices.push_back(n);  // bottom, counter-clockwise from below
  for (unsigned i = n; i-- > 0;) s.indices.push_back(i);
  for (unsigned i = 0; i < n; ++i) {  // sides, counter-clockwise from outside
    const unsigned j = (i + 1) % n;
    s.indices.insert(s.indices.end(), {4u, i, j, n + j, n + i});
  }
  return s;
}

double Shape::BoundingRadius() const {
  switch (kind) {
    case Kind::kSphere: return radius;
    case Kind::kBox: return 0.5 * size.norm();
    case Kind::kCylinder: return std::hypot(radius, 0.5 * length);
    case Kind::kCapsule: return radius + 0.5 * length;
    case Kind::kPlane: return std::numeric_limits<double>::infinity();
    case Kind::kConvex:
    case Kind::kTriangleMesh: {
      double r = 0.0;
      for (const Vec3& v : vertices) r = std::max(r, v.norm());
      return r;
    }
  }
  return 0.0;
}

MassSpec MassSpec::Solid(const Shape& shape, double mass) {
  if (!(mass > 0.0)) throw PluginError("MassSpec::Solid: mass must be positive");
  MassSpec m;
  m.mass = mass;
  switch (shape.kind) {
    case Shape::Kind::kSphere: {
      const double i = 0.4 * mass * shape.radius * shape.radius;
      m.inertia_diagonal = Vec3(i, i, i);
      break;
    }
    case Shape::Kind::kBox: {
      const Vec3 s2 = shape.size.cwiseProduct(shape.size);
      m.inertia_diagonal = Vec3(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y()) * (mass / 12.0);
      break;
    }
    case Shape::Kind::kCylinder: {
      const double r2 = shape.radius * shape.radius, l2 = shape.length * shape.length;
      const double ixx = mass * (3.0 * r2 + l2) / 12.0;
      m.inertia_diagonal = Vec3(ixx, ixx, 0.5 * mass * r2);
      break;
    }
    case Shape::Kind::kCapsule: {
      // Approximation: a cylinder of the full length; good to a few percent for SSL parts.
      const double r2 = shape.radius * shape.radius;
      const double l = shape.length + 2.0 * shape.radius;
      const double ixx = mass * (3.0 * r2 + l * l) / 12.0;
      m.inertia_diagonal = Vec3(ixx, ixx, 0.5 * mass * r2);
      break;
    }
    default:
      throw PluginError("MassSpec::Solid: give the inertia explicitly for planes and meshes");
  }
  return m;
}

MassSpec MassSpec::HollowSphere(double radius, double mass) {
  if (!(mass > 0.0) || !(radius > 0.0)) throw PluginError("MassSpec::HollowSphere: need mass > 0, radius > 0");
  MassSpec m;
  m.mass = mass;
  const double i = (2.0 / 3.0) * mass * radius * radius;
  m.inertia_diagonal = Vec3(i, i, i);
  return m;
}

}  // namespace v1
}  // namespace ubersim
