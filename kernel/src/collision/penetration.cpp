// SPDX-License-Identifier: Apache-2.0
#include "collision/penetration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ubersim::kernel {
namespace {

// Coarse directions: a Fibonacci sphere (about 9° apart) and a finer horizontal ring, where
// upright robots and walls meet. Built once; the refinement below does the rest.
const std::vector<Vec3>& CoarseDirections() {
  static const std::vector<Vec3> directions = [] {
    std::vector<Vec3> d;
    constexpr int kSphere = 512;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < kSphere; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / kSphere;
      const double r = std::sqrt(1.0 - z * z);
      d.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
    }
    constexpr int kRing = 144;
    for (int i = 0; i < kRing; ++i) {
      const double a = 2.0 * M_PI * i / kRing;
      d.emplace_back(std::cos(a), std::sin(a), 0.0);
    }
    return d;
  }();
  return directions;
}

double Overlap(const PlacedShape& a, const PlacedShape& b, const Vec3& n) {
  return a.Support(n) + b.Support(-n);
}

// Pattern search on the unit sphere from `n`: tries eight neighbours `step` away, moves to the
// best that is lower, else halves the step. Overlap is continuous in n but has kinks (polytope
// edges), which rules out gradients and is why neighbours are tried all round.
double Refine(const PlacedShape& a, const PlacedShape& b, Vec3 n, double f, double enough) {
  double step = 0.1;  // rad, about the coarse spacing
  for (int iteration = 0; iteration < 400 && step > 1e-6 && f > enough; ++iteration) {
    const Vec3 t1 = n.unitOrthogonal();
    const Vec3 t2 = n.cross(t1);
    Vec3 best_n = n;
    double best_f = f;
    for (int k = 0; k < 8; ++k) {
      const double angle = k * M_PI / 4.0;
      const Vec3 m = (n + step * (std::cos(angle) * t1 + std::sin(angle) * t2)).normalized();
      const double fm = Overlap(a, b, m);
      if (fm < best_f) {
        best_f = fm;
        best_n = m;
      }
    }
    if (best_f < f) {
      n = best_n;
      f = best_f;
    } else {
      step *= 0.5;
    }
  }
  return f;
}

}  // namespace

PlacedShape::PlacedShape(const Shape& shape, const Pose& pose)
    : kind_(shape.kind), centre_(pose.position), axes_(pose.orientation.normalized().toRotationMatrix()) {
  switch (shape.kind) {
    case Shape::Kind::kSphere: radius_ = shape.radius; break;
    case Shape::Kind::kBox: half_size_ = 0.5 * shape.size; break;
    case Shape::Kind::kCylinder:
    case Shape::Kind::kCapsule:
      radius_ = shape.radius;
      half_length_ = 0.5 * shape.length;
      break;
    case Shape::Kind::kConvex:
    case Shape::Kind::kTriangleMesh:
      vertices_.reserve(shape.vertices.size());
      for (const Vec3& v : shape.vertices) vertices_.push_back(centre_ + axes_ * v);
      break;
    case Shape::Kind::kPlane: throw std::invalid_argument("PlacedShape: a plane has no support point");
  }
  bounding_radius_ = shape.BoundingRadius();
}

double PlacedShape::Support(const Vec3& n) const {
  switch (kind_) {
    case Shape::Kind::kSphere: return n.dot(centre_) + radius_ * n.norm();
    case Shape::Kind::kBox: {
      const Vec3 local = axes_.transpose() * n;
      return n.dot(centre_) + local.cwiseAbs().dot(half_size_);
    }
    case Shape::Kind::kCylinder: {
      const double along = n.dot(axes_.col(2));
      const double across = std::sqrt(std::max(0.0, n.squaredNorm() - along * along));
      return n.dot(centre_) + half_length_ * std::abs(along) + radius_ * across;
    }
    case Shape::Kind::kCapsule:
      return n.dot(centre_) + half_length_ * std::abs(n.dot(axes_.col(2))) + radius_ * n.norm();
    case Shape::Kind::kConvex:
    case Shape::Kind::kTriangleMesh: {
      double best = -std::numeric_limits<double>::infinity();
      for (const Vec3& v : vertices_) best = std::max(best, n.dot(v));
      return best;
    }
    case Shape::Kind::kPlane: break;
  }
  return std::numeric_limits<double>::infinity();
}

double PenetrationDepth(const PlacedShape& a, const PlacedShape& b, double enough) {
  // Cheap directions first: from a's centre to b's (parts shapes that are apart, or barely
  // touching, in one evaluation) and both shapes' own axes (a wall's face, a robot's flat front).
  std::array<Vec3, 13> quick;
  std::size_t count = 0;
  const Vec3 between = b.centre() - a.centre();
  if (between.norm() > 1e-12) quick[count++] = between.normalized();
  for (const PlacedShape* s : {&a, &b}) {
    for (int i = 0; i < 3; ++i) {
      quick[count++] = s->axes().col(i);
      quick[count++] = -s->axes().col(i);
    }
  }
  // Then all round; the three lowest directions seen are refined (the overlap can have a local
  // minimum per face).
  std::array<std::pair<double, Vec3>, 3> seeds;
  seeds.fill({std::numeric_limits<double>::infinity(), Vec3::UnitX()});
  auto low_enough = [&](const Vec3& n) {
    const double f = Overlap(a, b, n);
    if (f < seeds.back().first) {
      seeds.back() = {f, n};
      std::sort(seeds.begin(), seeds.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    }
    return f <= enough;
  };
  for (std::size_t i = 0; i < count; ++i) {
    if (low_enough(quick[i])) return seeds.front().first;
  }
  for (const Vec3& n : CoarseDirections()) {
    if (low_enough(n)) return seeds.front().first;
  }
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [f, n] : seeds) {
    if (!std::isfinite(f)) continue;
    best = std::min(best, Refine(a, b, n, f, enough));
    if (best <= enough) return best;
  }
  return best;
}

}  // namespace ubersim::kernel
