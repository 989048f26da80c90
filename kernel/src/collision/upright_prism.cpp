// SPDX-License-Identifier: Apache-2.0
#include "collision/upright_prism.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

namespace ubersim::kernel {
namespace {

using V2 = Eigen::Vector2d;

// A shell's cross-section at one height: the disc of `radius` about `centre`, cut by the face
// at `front` along the unit `forward`, whose ends (the corners) lie `half_width` to either side.
struct Outline {
  V2 centre;
  V2 forward;
  V2 left;
  double radius;
  double front;
  double half_width;  // 0: no face

  bool has_face() const { return half_width > 0.0; }
  V2 Corner(int k) const { return centre + forward * front + left * (k == 0 ? half_width : -half_width); }
  // The point of the outline farthest along unit u: on the arc unless the face cuts it off there,
  // then the corner farther along u (the arc's remaining part peaks at its ends).
  V2 Support(const V2& u) const {
    if (!has_face() || u.dot(forward) * radius <= front) return centre + u * radius;
    return Corner(u.dot(left) >= 0.0 ? 0 : 1);
  }
};

// A shell standing nearly upright: its cross-section at height z is its outline moved along
// the leaning axis (and stretched by 1/cos(tilt) along it: neglected, kUprightTilt).
struct Standing {
  Outline outline;  // at the height of the geometry's origin
  double origin_z;
  V2 lean;          // horizontal shift of the axis per metre of height
  double z_low, z_high;

  Outline At(double z) const {
    Outline o = outline;
    o.centre += lean * (z - origin_z);
    return o;
  }
};

bool MakeStanding(const FlatFrontPrism& p, const Pose& pose, Standing& s) {
  const Vec3 up = pose.orientation * Vec3::UnitZ();
  if (up.z() < std::cos(kUprightTilt)) return false;
  const Vec3 x = pose.orientation * Vec3::UnitX();
  const V2 forward(x.x(), x.y());
  if (forward.norm() < 1e-9) return false;
  Outline& o = s.outline;
  o.centre = V2(pose.position.x(), pose.position.y());
  o.forward = forward.normalized();
  o.left = V2(-o.forward.y(), o.forward.x());
  o.radius = p.radius;
  o.front = std::min(p.front_distance, p.radius);
  o.half_width = std::sqrt(std::max(0.0, p.radius * p.radius - o.front * o.front));
  s.origin_z = pose.position.z();
  s.lean = V2(up.x(), up.y()) / up.z();
  s.z_low = pose.position.z() - p.half_height * up.z();   // the caps' centres
  s.z_high = pose.position.z() + p.half_height * up.z();
  return true;
}

// Whether two cross-sections of one shell lie at the same place, to the bit: TouchAt is a
// function of its outlines alone, so a level whose outlines are bit for bit the other's touches
// as it does (two shells both standing straight, as one-body robots always do: half the work).
bool SameCentre(const Outline& x, const Outline& y) {
  return std::memcmp(x.centre.data(), y.centre.data(), 2 * sizeof(double)) == 0;
}

// How far A and B overlap along unit n (A's farthest point along n minus B's nearest): the
// shells are apart when any direction gives a negative overlap (separating axis).
double Overlap(const Outline& a, const Outline& b, const V2& n) {
  return n.dot(a.Support(n)) - n.dot(b.Support(-n));
}

// Two cross-sections at one height: the depth, the direction n from a to b, and where they
// touch (one spot, or both ends of the stretch two flat faces share). False when apart.
struct Touch {
  double depth = 0.0;
  V2 n = V2::UnitX();
  std::array<V2, 2> spots;
  int spot_count = 0;
};

// Unit directions to try as separating axes (at most 24; the longest list, shell against box, has 20).
struct Directions {
  std::array<V2, 24> unit;
  std::size_t count = 0;
  void Add(const V2& v) {
    const double length = v.norm();
    if (length > 1e-12) unit[count++] = v / length;
  }
};

// The least overlap of a and b over the directions, and the direction giving it, into t.
// False when one of them separates them.
template <typename Other>
bool LeastOverlap(const Outline& a, const Other& b, const Directions& d, Touch& t) {
  t.depth = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < d.count; ++i) {
    const double overlap = Overlap(a, b, d.unit[i]);
    if (overlap <= 0.0) return false;  // a separating axis: the least can only be lower
    if (overlap < t.depth) {
      t.depth = overlap;
      t.n = d.unit[i];
    }
  }
  return t.depth > 0.0;
}

// A box standing upright, seen from above: a rectangle.
struct Rect {
  V2 centre;
  std::array<V2, 2> axis;  // its edges' directions (unit, perpendicular)
  std::array<double, 2> half;

  V2 Corner(int k) const {
    return centre + axis[0] * ((k & 1) ? -half[0] : half[0]) + axis[1] * ((k & 2) ? -half[1] : half[1]);
  }
  V2 Support(const V2& u) const {
    return centre + axis[0] * (u.dot(axis[0]) >= 0.0 ? half[0] : -half[0]) +
           axis[1] * (u.dot(axis[1]) >= 0.0 ? half[1] : -half[1]);
  }
};

double Overlap(const Outline& a, const Rect& b, const V2& n) { return n.dot(a.Support(n)) - n.dot(b.Support(-n)); }

// Where a shape lies deepest along unit u, across u (coordinate along `side`): one point, or
// the stretch [lo, hi] of a flat edge square to u.
struct Reach {
  double lo, hi;
};

Reach DeepestAcross(const Outline& o, const V2& u, const V2& side, double parallel) {
  if (o.has_face() && u.dot(o.forward) > parallel) {
    const double c0 = side.dot(o.Corner(0)), c1 = side.dot(o.Corner(1));
    return {std::min(c0, c1), std::max(c0, c1)};
  }
  const double s = side.dot(o.Support(u));
  return {s, s};
}

Reach DeepestAcross(const Rect& r, const V2& u, const V2& side, double parallel) {
  for (std::size_t i = 0; i < 2; ++i) {
    if (std::abs(u.dot(r.axis[i])) > parallel) {
      const V2 mid = r.centre + r.axis[i] * (u.dot(r.axis[i]) > 0.0 ? r.half[i] : -r.half[i]);
      const V2& along = r.axis[1 - i];
      const double c0 = side.dot(mid + along * r.half[1 - i]), c1 = side.dot(mid - along * r.half[1 - i]);
      return {std::min(c0, c1), std::max(c0, c1)};
    }
  }
  const double s = side.dot(r.Support(u));
  return {s, s};
}

// Where A and B, overlapping t.depth along t.n, touch: midway between their deepest points along
// n, and across n where the deepest point is. Where one side is flat there (a face square to n),
// its deepest point is anywhere along the face: across from the other's one deepest point, so
// the normal passes through a disc's centre (a face's corner there instead pushed a round back
// off its centre line, the push spun it up, and the spin let the solver leave two robots sinking
// 3.5 mm a step into each other); where both are flat, along the stretch they share (both ends).
template <typename A, typename B>
void PlaceSpots(const A& a, const B& b, Touch& t) {
  const V2& n = t.n;
  const V2 side(-n.y(), n.x());
  const double kParallel = std::cos(0.01);
  const double across = 0.5 * (n.dot(a.Support(n)) + n.dot(b.Support(-n)));
  const Reach ra = DeepestAcross(a, n, side, kParallel), rb = DeepestAcross(b, -n, side, kParallel);
  const bool a_flat = ra.hi > ra.lo, b_flat = rb.hi > rb.lo;
  t.spot_count = 1;
  if (a_flat && b_flat) {
    const double lo = std::max(ra.lo, rb.lo), hi = std::min(ra.hi, rb.hi);
    if (hi - lo > 1e-6) {
      t.spots = {n * across + side * lo, n * across + side * hi};
      t.spot_count = 2;
    } else {
      t.spots = {n * across + side * (0.5 * (lo + hi)), V2::Zero()};
    }
  } else if (a_flat) {
    t.spots = {n * across + side * rb.lo, V2::Zero()};
  } else if (b_flat) {
    t.spots = {n * across + side * ra.lo, V2::Zero()};
  } else {
    t.spots = {n * across + side * (0.5 * (ra.lo + rb.lo)), V2::Zero()};
  }
}

bool TouchAt(const Outline& a, const Outline& b, Touch& t) {
  // The overlap along a direction is, piece by piece, a constant plus a sinusoid of the angle
  // (each outline's support is an arc point or a fixed corner). Its least value, the depth, lies
  // where a piece is stationary (centre to centre, corner to centre, corner to corner) or where
  // pieces meet (a face's normal, a corner's radial direction): try them all.
  Directions d;
  auto add = [&](const V2& v) { d.Add(v); };
  add(b.centre - a.centre);
  // Apart along the line of centres (most pairs a broadphase passes on): no need for the rest.
  if (d.count > 0 && Overlap(a, b, d.unit[0]) <= 0.0) return false;
  if (a.has_face()) {
    add(a.forward);
    for (int k = 0; k < 2; ++k) {
      add(b.centre - a.Corner(k));
      add(a.Corner(k) - a.centre);
    }
  }
  if (b.has_face()) {
    add(-b.forward);
    for (int k = 0; k < 2; ++k) {
      add(b.Corner(k) - a.centre);
      add(b.centre - b.Corner(k));
    }
  }
  if (a.has_face() && b.has_face()) {
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 2; ++j) add(b.Corner(j) - a.Corner(i));
    }
  }
  if (d.count == 0) add(V2::UnitX());  // concentric discs: any direction
  if (!LeastOverlap(a, b, d, t)) return false;
  PlaceSpots(a, b, t);
  return true;
}

void Write(const Touch& t, const V2& spot, double z, dContactGeom& c) {
  c.pos[0] = spot.x();
  c.pos[1] = spot.y();
  c.pos[2] = z;
  c.normal[0] = -t.n.x();  // out of b into a
  c.normal[1] = -t.n.y();
  c.normal[2] = 0.0;
  c.depth = t.depth;
  c.side1 = c.side2 = -1;
  c.g1 = c.g2 = nullptr;
}

// A shell's cross-section against a box's: the same separating-axis search as two shells'. The
// overlap is piecewise the arc's or a corner's sinusoid against a box corner; its least value
// lies where the rectangle's supporting corner changes (its edges' normals), where the outline's
// does (its face normal, its corners' radial directions), or where a piece is stationary (the
// outline's centre or a corner toward a box corner).
bool TouchAt(const Outline& a, const Rect& b, Touch& t) {
  Directions d;
  auto add = [&](const V2& v) { d.Add(v); };
  for (std::size_t i = 0; i < 2; ++i) {
    add(b.axis[i]);
    add(-b.axis[i]);
  }
  add(b.centre - a.centre);
  for (int k = 0; k < 4; ++k) add(b.Corner(k) - a.centre);
  if (a.has_face()) {
    add(a.forward);
    for (int i = 0; i < 2; ++i) {
      add(a.Corner(i) - a.centre);
      for (int k = 0; k < 4; ++k) add(b.Corner(k) - a.Corner(i));
    }
  }
  if (!LeastOverlap(a, b, d, t)) return false;
  PlaceSpots(a, b, t);
  return true;
}

// The touches at the bottom and the top of the height two shapes share.
struct Levels {
  std::array<Touch, 2> touches;
  std::array<double, 2> heights;
};

// Writes a level's contacts: every spot when max_contacts allows, else the deeper level's (its
// middle, at the middle of the shared height when both levels touch alike, for one).
int WriteLevels(const Levels& levels, int max_contacts, dContactGeom* out) {
  const auto& touches = levels.touches;
  const auto& heights = levels.heights;
  if (touches[0].spot_count == 0 && touches[1].spot_count == 0) return 0;
  const int wanted = touches[0].spot_count + touches[1].spot_count;
  if (wanted <= max_contacts) {
    int written = 0;
    for (std::size_t h = 0; h < 2; ++h) {
      for (int s = 0; s < touches[h].spot_count; ++s) {
        Write(touches[h], touches[h].spots[static_cast<std::size_t>(s)], heights[h], out[written++]);
      }
    }
    return written;
  }
  const std::size_t deeper =
      touches[1].spot_count > 0 && (touches[0].spot_count == 0 || touches[1].depth > touches[0].depth) ? 1 : 0;
  const Touch& t = touches[deeper];
  const bool alike = touches[0].spot_count > 0 && touches[1].spot_count > 0 &&
                     std::abs(touches[0].depth - touches[1].depth) < 1e-6;
  const double z = alike ? 0.5 * (heights[0] + heights[1]) : heights[deeper];
  if (t.spot_count <= max_contacts) {
    for (int s = 0; s < t.spot_count; ++s) Write(t, t.spots[static_cast<std::size_t>(s)], z, out[s]);
    return t.spot_count;
  }
  Write(t, 0.5 * (t.spots[0] + t.spots[1]), z, out[0]);
  return 1;
}

// Two shells put nearly onto each other (a teleport) have cross-sections that almost coincide,
// and a lean of a degree or two shifts the top one's least-overlap direction round: the bottom
// level pushed one way, the top level the other, a couple that rolled both robots over in a
// step. When the levels' directions disagree by more than 30°, both push along the deeper one's,
// each with its own overlap along it.
void SharedNormal(const Standing& a, const Standing& b, Levels& levels) {
  auto& t = levels.touches;
  if (t[0].spot_count == 0 || t[1].spot_count == 0 || t[0].n.dot(t[1].n) >= std::cos(M_PI / 6)) return;
  const std::size_t deeper = t[1].depth > t[0].depth ? 1 : 0, other = 1 - deeper;
  const V2 n = t[deeper].n;
  const double depth = Overlap(a.At(levels.heights[other]), b.At(levels.heights[other]), n);
  if (depth <= 0.0) {
    t[other].spot_count = 0;
    return;
  }
  t[other].n = n;
  t[other].depth = depth;
}

// How far apart a shared height's other level may be and still be written (as a gap) beside the
// touching one, m: two degrees of lean over a shell's height, with room to spare.
constexpr double kLevelMargin = 0.01;

// One level touching and the other apart by less than kLevelMargin (two robots arriving at a touch
// in the same step, a shell leaning a degree): the other level is written too, along the touching
// one's direction, its gap as a depth below zero for the caller to make speculative (it holds once
// the gap closes within the step). With the touching level alone, a 4.5 m/s crash pushed only at
// the shells' bottoms, 3.5 cm below the centres of mass, and pitched both robots onto their sides.
template <typename AtHeight>
void NearLevel(const Standing& a, const AtHeight& b_at, Levels& levels) {
  auto& t = levels.touches;
  if ((t[0].spot_count > 0) == (t[1].spot_count > 0)) return;
  const std::size_t touching = t[0].spot_count > 0 ? 0 : 1, other = 1 - touching;
  const double z = levels.heights[other], z_touching = levels.heights[touching];
  const Outline a_there = a.At(z);
  const auto b_there = b_at(z);
  const double depth = Overlap(a_there, b_there, t[touching].n);
  if (depth <= -kLevelMargin) return;
  t[other] = t[touching];
  t[other].depth = std::min(depth, 0.0);
  // The spots move with the shells' lean between the levels.
  const V2 shift = 0.5 * (a_there.centre - a.At(z_touching).centre) + 0.5 * (b_there.centre - b_at(z_touching).centre);
  for (V2& spot : t[other].spots) spot += shift;
}

}  // namespace

// A closed triangle mesh, not a convex prism: ODE's convex-plane test returns the first
// max_contacts vertices below the plane, all on one side of a 33-corner outline, so a chassis
// resting on the carpet (no ground clearance, or knocked over) tips over. Triangle meshes
// collide well with every shape the field, ball and robots use (the URDF twin's shell is the
// same mesh).
Shape FlatFrontPrismMesh(const FlatFrontPrism& prism) {
  constexpr int kArcSegments = 32;
  const double radius = prism.radius;
  const double cut = std::acos(std::clamp(prism.front_distance / radius, -1.0, 1.0));
  const double h = prism.half_height;
  Shape s;
  s.kind = Shape::Kind::kTriangleMesh;
  // Ring i: bottom vertex 2i, top vertex 2i + 1, counter-clockwise seen from above, from the
  // left end of the flat face (y > 0) round the back to its right end.
  for (int i = 0; i <= kArcSegments; ++i) {
    const double a = cut + (2.0 * M_PI - 2.0 * cut) * i / kArcSegments;
    s.vertices.emplace_back(radius * std::cos(a), radius * std::sin(a), -h);
    s.vertices.emplace_back(radius * std::cos(a), radius * std::sin(a), h);
  }
  const unsigned ring = static_cast<unsigned>(s.vertices.size()) / 2;
  const unsigned bottom_centre = 2 * ring, top_centre = 2 * ring + 1;
  s.vertices.emplace_back(0.0, 0.0, -h);
  s.vertices.emplace_back(0.0, 0.0, h);
  // Sides (the arc's segments, then the flat face closing the ring), outward and counter-clockwise.
  for (unsigned i = 0; i < ring; ++i) {
    const unsigned j = (i + 1) % ring;
    s.indices.insert(s.indices.end(), {2 * i, 2 * j, 2 * j + 1, 2 * i, 2 * j + 1, 2 * i + 1});
    s.indices.insert(s.indices.end(), {top_centre, 2 * i + 1, 2 * j + 1});  // top cap, up
    s.indices.insert(s.indices.end(), {bottom_centre, 2 * j, 2 * i});      // bottom cap, down
  }
  return s;
}

int CollideUprightPrisms(const FlatFrontPrism& pa_shape, const Pose& pa, const FlatFrontPrism& pb_shape,
                         const Pose& pb, int max_contacts, dContactGeom* out) {
  Standing a, b;
  if (!MakeStanding(pa_shape, pa, a) || !MakeStanding(pb_shape, pb, b)) return -1;
  const double z_low = std::max(a.z_low, b.z_low), z_high = std::min(a.z_high, b.z_high);
  if (z_high < z_low || max_contacts < 1) return 0;
  // The cross-sections at the bottom and the top of the shared height (they differ when a shell
  // leans): each touching one gives its contacts there.
  Levels levels;
  levels.heights = {z_low, z_high};
  const Outline a_low = a.At(z_low), b_low = b.At(z_low);
  if (!TouchAt(a_low, b_low, levels.touches[0])) levels.touches[0].spot_count = 0;
  const Outline a_high = a.At(z_high), b_high = b.At(z_high);
  if (SameCentre(a_high, a_low) && SameCentre(b_high, b_low)) {
    levels.touches[1] = levels.touches[0];  // standing straight: the same cross-sections, the same touch
  } else if (!TouchAt(a_high, b_high, levels.touches[1])) {
    levels.touches[1].spot_count = 0;
  }
  SharedNormal(a, b, levels);
  NearLevel(a, [&b](double z) { return b.At(z); }, levels);
  return WriteLevels(levels, max_contacts, out);
}

int CollideUprightPrismWithBox(const FlatFrontPrism& prism_shape, const Pose& prism_pose, const Vec3& box_size,
                               const Pose& box_pose, int max_contacts, dContactGeom* out) {
  Standing a;
  if (!MakeStanding(prism_shape, prism_pose, a)) return -1;
  const Vec3 box_z = box_pose.orientation * Vec3::UnitZ();
  if (std::abs(box_z.z()) < 1.0 - 1e-9) return -1;  // a tilted box: not a rectangle at each height
  Rect b;
  b.centre = V2(box_pose.position.x(), box_pose.position.y());
  const Vec3 box_x = box_pose.orientation * Vec3::UnitX();
  b.axis[0] = V2(box_x.x(), box_x.y()).normalized();
  b.axis[1] = V2(-b.axis[0].y(), b.axis[0].x());
  b.half = {0.5 * box_size.x(), 0.5 * box_size.y()};
  const double z_low = std::max(a.z_low, box_pose.position.z() - 0.5 * box_size.z());
  const double z_high = std::min(a.z_high, box_pose.position.z() + 0.5 * box_size.z());
  if (z_high < z_low || max_contacts < 1) return 0;
  Levels levels;
  levels.heights = {z_low, z_high};
  double deepest = 0.0;
  for (std::size_t h = 0; h < 2; ++h) {
    Touch& t = levels.touches[h];
    if (TouchAt(a.At(levels.heights[h]), b, t)) {
      deepest = std::max(deepest, t.depth);
    } else {
      t.spot_count = 0;
    }
  }
  // A shell standing mostly above (or below) the box and overlapping it less in height than
  // across: it is landing on the box's top, the way out is vertical, and the general test finds
  // it. A shell beside a box (its middle within the box's height) is pushed out sideways, however
  // deep: robots do not climb walls.
  const double box_low = box_pose.position.z() - 0.5 * box_size.z(), box_high = box_low + box_size.z();
  const bool beside = a.origin_z >= box_low && a.origin_z <= box_high;
  if (!beside && deepest > 0.0 && z_high - z_low < deepest) return -1;
  NearLevel(a, [&b](double) { return b; }, levels);
  return WriteLevels(levels, max_contacts, out);
}

int CollideFlatFrontPrismWithSphere(const FlatFrontPrism& prism, const Pose& prism_pose, const Vec3& centre,
                                    double radius, dContactGeom* out) {
  const Vec3 p = prism_pose.orientation.conjugate() * (centre - prism_pose.position);
  const double r = prism.radius, f = std::min(prism.front_distance, prism.radius), h = prism.half_height;
  const double half_face = std::sqrt(std::max(0.0, r * r - f * f));  // the flat face's half width
  const double planar = std::hypot(p.x(), p.y());
  const bool inside_outline = planar <= r && p.x() <= f;
  Vec3 surface, normal;  // local: the nearest point of the shell, the way out toward the centre
  double depth = 0;
  if (inside_outline && std::abs(p.z()) <= h) {
    // The centre inside the solid: out through the nearer of the round wall and the flat face.
    const double to_wall = r - planar, to_face = f - p.x();
    if (to_face < to_wall) {
      normal = Vec3::UnitX();
      surface = Vec3(f, p.y(), p.z());
      depth = radius + to_face;
    } else {
      const Vec3 radial = planar > 1e-12 ? Vec3(p.x() / planar, p.y() / planar, 0.0) : Vec3(-1.0, 0.0, 0.0);
      normal = radial;
      surface = Vec3(r * radial.x(), r * radial.y(), p.z());
      depth = radius + to_wall;
    }
  } else {
    // Outside: the nearest point of the outline (at the centre's own height, clamped to the
    // shell's), then the distance to it.
    double qx = p.x(), qy = p.y();
    if (!inside_outline) {
      if (p.x() >= f && std::abs(p.y()) <= half_face) {
        qx = f;  // in front of the flat face
      } else {
        qx = r * p.x() / planar;  // toward the round wall ...
        qy = r * p.y() / planar;
        if (qx > f) {             // ... unless that part is cut away: the face's corner
          qx = f;
          qy = std::copysign(half_face, p.y());
        }
      }
    }
    surface = Vec3(qx, qy, std::clamp(p.z(), -h, h));
    const Vec3 gap = p - surface;
    const double distance = gap.norm();
    if (distance >= radius) return 0;
    if (distance < 1e-12) {
      // The centre on the surface (within rounding): half the sphere is in. Out along the
      // surface's own normal there: the top or bottom, the flat face, or the round wall.
      if (std::abs(p.z()) >= h) {
        normal = Vec3(0.0, 0.0, p.z() > 0 ? 1.0 : -1.0);
      } else if (qx >= f) {
        normal = Vec3::UnitX();
      } else {
        normal = Vec3(qx / r, qy / r, 0.0);
      }
      depth = radius;
    } else {
      normal = gap / distance;
      depth = radius - distance;
    }
  }
  const Vec3 world_normal = prism_pose.orientation * normal;
  const Vec3 world_surface = prism_pose.position + prism_pose.orientation * surface;
  dContactGeom& c = *out;
  for (int k = 0; k < 3; ++k) {
    c.pos[k] = world_surface[k];
    c.normal[k] = world_normal[k];
  }
  c.depth = depth;
  c.side1 = c.side2 = -1;
  return 1;
}

}  // namespace ubersim::kernel
