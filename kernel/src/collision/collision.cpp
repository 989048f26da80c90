// SPDX-License-Identifier: Apache-2.0
#include "collision/collision.hpp"

#include <algorithm>
#include <limits>
#include <cmath>
#include <stdexcept>

namespace ubersim::kernel {
namespace {

// Sorts `order` (indices) by `before` in place, by insertion: the orders the broadphases keep from
// step to step are nearly sorted already, and std::sort would start over.
template <typename Before>
void InsertionSort(std::vector<std::size_t>& order, const Before& before) {
  for (std::size_t i = 1; i < order.size(); ++i) {
    const std::size_t moving = order[i];
    std::size_t j = i;
    for (; j > 0 && before(moving, order[j - 1]); --j) order[j] = order[j - 1];
    order[j] = moving;
  }
}

bool IsAncestorOrSelf(const NodeImpl* maybe_ancestor, const NodeImpl* node) {
  for (const NodeImpl* n = node; n; n = n->parent()) {
    if (n == maybe_ancestor) return true;
  }
  return false;
}

double Mu2(const SurfaceMaterial& m) { return m.mu2 < 0 ? m.mu : m.mu2; }

double GeometricMean(double a, double b) {
  if (std::isinf(a) && std::isinf(b)) return a;
  if (std::isinf(a)) return b;  // an infinite-friction surface takes the other's value
  if (std::isinf(b)) return a;
  return std::sqrt(std::max(0.0, a) * std::max(0.0, b));
}

// Combines an optional (negative = unset) parameter, picking with `pick` when both are set.
template <typename Pick>
double CombineOptional(double a, double b, Pick pick) {
  if (a < 0) return b;
  if (b < 0) return a;
  return pick(a, b);
}

// How far a geometry's origin lies from its body's, m (0 for one without an offset).
double OffsetDistance(const GeomImpl& g) {
  const dReal* offset = dGeomGetOffsetPosition(g.id());
  return std::sqrt(offset[0] * offset[0] + offset[1] * offset[1] + offset[2] * offset[2]);
}

// How far a geometry on a body reaches from the body's origin, m (a sphere about it that holds
// the geometry however the body turns).
double ReachFromBody(const GeomImpl& g) {
  if (!g.body()) return 0.0;
  return OffsetDistance(g) + g.GetShape().BoundingRadius();
}

bool AabbsOverlap(dGeomID a, dGeomID b) {
  dReal x[6], y[6];
  dGeomGetAABB(a, x);
  dGeomGetAABB(b, y);
  return x[0] <= y[1] && y[0] <= x[1] && x[2] <= y[3] && y[2] <= x[3] && x[4] <= y[5] &&
         y[4] <= x[5];
}

// A plane reaches the narrow phase with every geometry (its box is infinite). A geometry whose
// box lies wholly on the plane's free side cannot touch it: skip dCollide, which for a trimesh
// chassis riding over the carpet would test every vertex each step. Exact: ODE makes contacts
// only where something penetrates the plane.
bool BoxAbovePlane(dGeomID plane, dGeomID other) {
  dVector4 p;
  dGeomPlaneGetParams(plane, p);
  dReal box[6];
  dGeomGetAABB(other, box);
  double lowest = -p[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double centre = 0.5 * (box[2 * axis] + box[2 * axis + 1]);
    const double half = 0.5 * (box[2 * axis + 1] - box[2 * axis]);
    lowest += p[axis] * centre - std::abs(p[axis]) * half;
  }
  return lowest > 0.0;
}

bool IsSphere(const GeomImpl& g) { return g.GetShape().kind == Shape::Kind::kSphere; }

bool SphereAndPlane(const GeomImpl& a, const GeomImpl& b) {
  return (IsSphere(a) && b.is_plane()) || (a.is_plane() && IsSphere(b));
}

bool AbovePlane(const GeomImpl& a, const GeomImpl& b) {
  if (a.is_plane()) return BoxAbovePlane(a.id(), b.id());
  if (b.is_plane()) return BoxAbovePlane(b.id(), a.id());
  return false;
}

struct SpaceCallbackData {
  const std::function<void(GeomImpl&, GeomImpl&)>* f;
};

void SpaceNearCallback(void* data, dGeomID o1, dGeomID o2) {
  if (dGeomIsSpace(o1) || dGeomIsSpace(o2)) {
    // A robot's space: a whole robot riding over the carpet ends here; else pair up its parts.
    if (dGeomGetClass(o1) == dPlaneClass && BoxAbovePlane(o1, o2)) return;
    if (dGeomGetClass(o2) == dPlaneClass && BoxAbovePlane(o2, o1)) return;
    dSpaceCollide2(o1, o2, data, &SpaceNearCallback);
    return;
  }
  auto* a = static_cast<GeomImpl*>(dGeomGetData(o1));
  auto* b = static_cast<GeomImpl*>(dGeomGetData(o2));
  if (!a || !b || !CollisionManager::MayCollide(*a, *b)) return;
  (*static_cast<SpaceCallbackData*>(data)->f)(*a, *b);
}

// Slip speed above which the ball's carpet friction acts against the slip only, m/s (below it the
// contact sticks, and the pyramid holds it without chatter).
constexpr double kSlipThreshold = 0.01;

Vec3 PointVelocity(const GeomImpl& g, const Vec3& p) {
  if (!g.body()) return Vec3::Zero();
  dVector3 v;
  dBodyGetPointVel(g.body()->id(), p.x(), p.y(), p.z(), v);
  return Vec3(v[0], v[1], v[2]);
}

// Tangential velocity of `a` relative to `b` where the ball touches the carpet (zero for other
// pairs: walls, goals and robots keep ODE's pyramid, whose behaviour their tests pin down).
Vec3 BallSlip(const GeomImpl& a, const GeomImpl& b, const Vec3& p, const Vec3& normal) {
  const auto on_plane = [](const GeomImpl& ball, const GeomImpl& other) {
    return ball.is_ball() && other.is_plane();
  };
  if (!on_plane(a, b) && !on_plane(b, a)) return Vec3::Zero();
  const Vec3 v = PointVelocity(a, p) - PointVelocity(b, p);
  return v - normal * normal.dot(v);
}

}  // namespace

int SpreadContacts(std::vector<dContactGeom>& contacts, int found, int keep) {
  if (found <= keep) return found;
  // ODE's colliders return the first points they find, often all along one edge (a convex
  // resting on a plane gets four neighbouring corners and tips over). Keep the deepest point,
  // then each time the candidate farthest from those kept: a spread the solver can stand on.
  std::vector<int> chosen;
  int deepest = 0;
  for (int i = 1; i < found; ++i) {
    if (contacts[static_cast<std::size_t>(i)].depth > contacts[static_cast<std::size_t>(deepest)].depth) deepest = i;
  }
  chosen.push_back(deepest);
  std::vector<double> gap(static_cast<std::size_t>(found), std::numeric_limits<double>::infinity());
  auto distance2 = [&](int i, int j) {
    const dReal* p = contacts[static_cast<std::size_t>(i)].pos;
    const dReal* q = contacts[static_cast<std::size_t>(j)].pos;
    return (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
  };
  while (static_cast<int>(chosen.size()) < keep) {
    int next = -1;
    for (int i = 0; i < found; ++i) {
      const std::size_t k = static_cast<std::size_t>(i);
      gap[k] = std::min(gap[k], distance2(i, chosen.back()));
      if (std::find(chosen.begin(), chosen.end(), i) == chosen.end() && (next < 0 || gap[k] > gap[static_cast<std::size_t>(next)])) next = i;
    }
    chosen.push_back(next);
  }
  std::sort(chosen.begin(), chosen.end());
  std::vector<dContactGeom> kept;
  for (int i : chosen) kept.push_back(contacts[static_cast<std::size_t>(i)]);
  std::copy(kept.begin(), kept.end(), contacts.begin());
  return keep;
}

// The ball and every wheel's carpet contact meet the carpet here: 89 pairs a Div A step. The
// formula and its floating-point operations are ODE's own (dCollideSpherePlane, and dCollide's
// reversal when the plane comes first).
int CollideSphereAndPlane(dGeomID first, dGeomID second, dContactGeom& c) {
  const bool sphere_first = dGeomGetClass(first) == dSphereClass;
  const dGeomID sphere = sphere_first ? first : second;
  dVector4 p;
  dGeomPlaneGetParams(sphere_first ? second : first, p);
  // The centre from the body's pose as ODE's computePosr finds it (the same operations), without
  // the rotation it would multiply out too: only the carpet asks for a wheel sphere's pose.
  dVector3 centre;
  const dBodyID body = dGeomGetBody(sphere);
  if (body && dGeomIsOffset(sphere)) {
    dMultiply0_331(centre, dBodyGetRotation(body), dGeomGetOffsetPosition(sphere));
    const dReal* origin = dBodyGetPosition(body);
    for (int i = 0; i < 3; ++i) centre[i] += origin[i];
  } else {
    const dReal* at = dGeomGetPosition(sphere);
    for (int i = 0; i < 3; ++i) centre[i] = at[i];
  }
  const dReal radius = dGeomSphereGetRadius(sphere);
  const dReal k = centre[0] * p[0] + centre[1] * p[1] + centre[2] * p[2];
  const dReal depth = p[3] - k + radius;
  if (!(depth >= 0)) return 0;
  const dReal sign = sphere_first ? 1.0 : -1.0;  // the normal points out of second into first
  for (int i = 0; i < 3; ++i) {
    c.pos[i] = centre[i] - p[i] * radius;
    c.normal[i] = sign * p[i];
  }
  c.depth = depth;
  c.g1 = first;
  c.g2 = second;
  c.side1 = -1;
  c.side2 = -1;
  return 1;
}

Broadphase ParseBroadphase(const std::string& name) {
  if (name == "scene_graph") return Broadphase::kSceneGraph;
  if (name == "hash") return Broadphase::kHash;
  if (name == "sap") return Broadphase::kSweepAndPrune;
  if (name == "field") return Broadphase::kField;
  throw std::invalid_argument("unknown broadphase '" + name + "' (scene_graph, hash, sap, field)");
}

const char* ToString(Broadphase b) {
  switch (b) {
    case Broadphase::kSceneGraph: return "scene_graph";
    case Broadphase::kHash: return "hash";
    case Broadphase::kSweepAndPrune: return "sap";
    case Broadphase::kField: return "field";
  }
  return "unknown";
}

// ---------------------------------------------------------------------------------------------
// MaterialTable

void MaterialTable::SetPair(const std::string& a, const std::string& b,
                            const SurfaceMaterial& surface) {
  SurfaceMaterial s = surface;
  s.name = a < b ? a + "|" + b : b + "|" + a;
  pairs_[std::minmax(a, b)] = s;
  ++version_;
}

SurfaceMaterial MaterialTable::Resolve(const SurfaceMaterial& a, const SurfaceMaterial& b) const {
  if (!pairs_.empty()) {
    const std::string_view x = a.name, y = b.name;
    const auto it = pairs_.find(x < y ? std::pair(x, y) : std::pair(y, x));
    if (it != pairs_.end()) return it->second;
  }
  SurfaceMaterial s;
  s.name = a.name < b.name ? a.name + "|" + b.name : b.name + "|" + a.name;
  s.mu = GeometricMean(a.mu, b.mu);
  s.mu2 = GeometricMean(Mu2(a), Mu2(b));
  s.bounce = std::max(a.bounce, b.bounce);
  s.bounce_velocity = std::max(a.bounce_velocity, b.bounce_velocity);
  s.soft_erp = CombineOptional(a.soft_erp, b.soft_erp, [](double x, double y) { return std::min(x, y); });
  s.soft_cfm = CombineOptional(a.soft_cfm, b.soft_cfm, [](double x, double y) { return std::max(x, y); });
  s.rolling_friction = std::max(a.rolling_friction, b.rolling_friction);
  s.slip = std::max(a.slip, b.slip);
  return s;
}

// ---------------------------------------------------------------------------------------------
// CollisionManager

CollisionManager::CollisionManager(SceneGraph& graph, Broadphase broadphase, int max_contacts)
    : graph_(graph),
      broadphase_(Broadphase::kSceneGraph),
      max_contacts_(std::clamp(max_contacts, 1, 64)),
      contacts_(dJointGroupCreate(0)),
      scratch_(static_cast<std::size_t>(kContactCandidates)) {
  graph_.SetGeomListener([this](GeomImpl& g) { File(g); }, [this](GeomImpl&) { field_grouped_ = false; });
  SetBroadphase(broadphase);
  static_contacts_.Bind(graph_.world(), contacts_.get());
}

CollisionManager::~CollisionManager() {
  // Geometries outlive us (the scene graph owns them): take them out of our spaces first.
  Unfile();
  graph_.SetGeomListener(nullptr, nullptr);
}

void CollisionManager::Refile() {
  // Destroyed geometries already left their ODE spaces (dGeomDestroy); the lists beside them
  // and the caches keyed by their addresses did not.
  SetBroadphase(broadphase_);
  balls_found_ = false;
  balls_.clear();
  sweep_targets_.clear();
  sweep_shells_.clear();
  sweep_shell_reach_.clear();
  sweep_target_reach_.clear();
  sweep_run_end_.clear();
  sweep_run_reach_.clear();
  hulls_found_ = false;
  hulls_.clear();
  hull_slack_.clear();
  hull_touching_.clear();
  surfaces_.clear();
  ++surfaces_epoch_;
  ball_touching_.clear();
}

void CollisionManager::Unfile() {
  graph_.Root().ForEachGeom([](GeomImpl& g) {
    if (dSpaceID s = dGeomGetSpace(g.id())) dSpaceRemove(s, g.id());
  });
  robot_spaces_.clear();  // each leaves space_ as it goes
  space_.reset();
}

void CollisionManager::SetBroadphase(Broadphase broadphase) {
  Unfile();
  broadphase_ = broadphase;
  field_grouped_ = false;
  if (broadphase == Broadphase::kHash) {
    space_.reset(dHashSpaceCreate(nullptr));
    // Cells from 2^-6 m (about a ball) to 2^4 m (a wall).
    dHashSpaceSetLevels(space_.get(), -3, 4);
  } else if (broadphase == Broadphase::kSweepAndPrune) {
    space_.reset(dSweepAndPruneSpaceCreate(nullptr, dSAP_AXES_XYZ));
  }
  planes_.clear();
  planes_only_.clear();
  if (space_) {
    dSpaceSetCleanup(space_.get(), 0);  // the scene graph owns the geometries
    // In creation order, the order they were filed in as they came: a world built anew from the
    // same robots in the same order (a snapshot's) pairs as this one does.
    std::vector<GeomImpl*> geoms;
    graph_.Root().ForEachGeom([&geoms](GeomImpl& g) { geoms.push_back(&g); });
    std::sort(geoms.begin(), geoms.end(), [](const GeomImpl* a, const GeomImpl* b) { return a->serial() < b->serial(); });
    for (GeomImpl* g : geoms) File(*g);
  }
}

void CollisionManager::File(GeomImpl& g) {
  field_grouped_ = false;
  if (!space_) return;
  if (g.is_plane()) planes_.push_back(&g);
  if (g.scope() == ContactScope::kPlanesOnly && !g.is_plane()) {
    planes_only_.push_back(&g);
    return;
  }
  if (g.robot() && !g.is_plane()) {
    OdeSpace& robot_space = robot_spaces_[g.robot()];
    if (!robot_space) {
      robot_space.reset(dSimpleSpaceCreate(space_.get()));
      dSpaceSetCleanup(robot_space.get(), 0);  // the scene graph owns the geometries
    }
    dSpaceAdd(robot_space.get(), g.id());
    return;
  }
  dSpaceAdd(space_.get(), g.id());
}

namespace {

// Whether `g`'s contact scope lets it touch `other`.
bool InScope(const GeomImpl& g, const GeomImpl& other) {
  switch (g.scope()) {
    case ContactScope::kAll: return true;
    case ContactScope::kPlanesOnly: return other.is_plane();
    case ContactScope::kNoPlanes: return !other.is_plane();
  }
  return true;
}

}  // namespace

bool CollisionManager::MayCollide(const GeomImpl& a, const GeomImpl& b) {
  return a.collides() && b.collides() && MayEverCollide(a, b);
}

bool CollisionManager::MayEverCollide(const GeomImpl& a, const GeomImpl& b) {
  if (&a == &b) return false;
  if (!InScope(a, b) || !InScope(b, a)) return false;
  if (!a.body() && !b.body()) return false;  // two static geometries never move apart
  if (a.body() == b.body()) return false;
  // Two robots meet through their hulls only. Wheels, dribbler and kicker sit inside or at the
  // hull; they touch another robot's parts only when the hulls overlap deeply (a teleport, a
  // pile-up), and then in arbitrary directions: in the soak such contacts lifted a robot onto
  // another and over the wall.
  if (a.robot() && b.robot() && a.robot() != b.robot() && !(MeetsOtherRobots(a) && MeetsOtherRobots(b))) return false;
  const NodeImpl* na = &a.owner();
  const NodeImpl* nb = &b.owner();
  return !IsAncestorOrSelf(na, nb) && !IsAncestorOrSelf(nb, na);
}

namespace {

// The hierarchical bounding-sphere traversal, as a template so the per-pair call inlines.
template <typename F>
struct SphereTree {
  F& f;
  std::size_t& tests;

  // All pairs inside one subtree: within each child, and between every two children. A node's
  // own geometries are never paired with its descendants (ancestor rule) nor with each other.
  void WithinSubtree(const NodeImpl& node) {
    const auto& children = node.children();
    for (const auto& c : children) WithinSubtree(*c);
    for (std::size_t i = 0; i < children.size(); ++i) {
      for (std::size_t j = i + 1; j < children.size(); ++j) NodeVsNode(*children[i], *children[j]);
    }
  }

  // Two disjoint subtrees: prune when their spheres miss, else open the larger one (so a robot
  // is tested against each opposing robot before any of its wheels is).
  void NodeVsNode(const NodeImpl& a, const NodeImpl& b) {
    ++tests;
    if (!a.Bounds().Overlaps(b.Bounds())) return;
    if (b.Bounds().radius > a.Bounds().radius) {
      Open(b, a);
    } else {
      Open(a, b);
    }
  }

  void Open(const NodeImpl& opened, const NodeImpl& other) {
    for (const auto& g : opened.geoms()) {
      if (g->collides()) GeomVsNode(*g, other);
    }
    for (const auto& c : opened.children()) NodeVsNode(*c, other);
  }

  void GeomVsNode(GeomImpl& g, const NodeImpl& node) {
    const BoundingSphere& gb = g.cached_bounds();
    ++tests;
    if (!gb.Overlaps(node.Bounds())) return;
    for (const auto& h : node.geoms()) {
      if (!h->collides()) continue;
      if (!g.body() && !h->body()) continue;
      if (g.body() == h->body()) continue;
      if (!InScope(g, *h) || !InScope(*h, g)) continue;
      ++tests;
      // Spheres prune the tree; a final box test drops long walls' many false positives.
      if (gb.Overlaps(h->cached_bounds()) && AabbsOverlap(g.id(), h->id())) f(g, *h);
    }
    for (const auto& c : node.children()) GeomVsNode(g, *c);
  }
};

}  // namespace

namespace {

// A geometry's box in its own frame: centre and half extents, m.
void LocalBox(const Shape& shape, Vec3& centre, Vec3& half) {
  centre = Vec3::Zero();
  switch (shape.kind) {
    case Shape::Kind::kSphere: half = Vec3::Constant(shape.radius); return;
    case Shape::Kind::kBox: half = 0.5 * shape.size; return;
    case Shape::Kind::kCylinder: half = Vec3(shape.radius, shape.radius, 0.5 * shape.length); return;
    case Shape::Kind::kCapsule: half = Vec3(shape.radius, shape.radius, 0.5 * shape.length + shape.radius); return;
    case Shape::Kind::kConvex:
    case Shape::Kind::kTriangleMesh: {
      Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
      for (const Vec3& v : shape.vertices) {
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
      }
      if (shape.vertices.empty()) lo = hi = Vec3::Zero();
      centre = 0.5 * (lo + hi);
      half = 0.5 * (hi - lo);
      return;
    }
    case Shape::Kind::kPlane: break;
  }
  half = Vec3::Constant(std::numeric_limits<double>::infinity());
}

// Whether the geometry lies wholly on `plane`'s free side: its box in its body's frame, turned
// with the body, reaches no lower along the normal than the plane. The same test as
// BoxAbovePlane's, on a box a little larger than ODE's: it needs no world pose of the geometry.
bool BodyBoxAbovePlane(const dReal* p, const dReal* r, const Vec3& centre, const Vec3& half, const Vec3& normal,
                       double offset) {
  double along = normal.x() * p[0] + normal.y() * p[1] + normal.z() * p[2];
  for (int k = 0; k < 3; ++k) {
    // Column k of the body's rotation (ODE's 3×4, row-major): the body's axis k in the world.
    const double axis = normal.x() * r[k] + normal.y() * r[4 + k] + normal.z() * r[8 + k];
    along += axis * centre[k] - std::abs(axis) * half[k];
  }
  return along > offset;
}

}  // namespace

CollisionManager::FieldGeom CollisionManager::BoxInBodyFrame(GeomImpl& g) {
  FieldGeom f{&g, dBodyGetPosition(g.body()->id()), dBodyGetRotation(g.body()->id()), Vec3::Zero(), Vec3::Zero()};
  Vec3 centre, half;
  LocalBox(g.GetShape(), centre, half);
  // The geometry's pose on its body (none: the body's own).
  const dReal* op = dGeomGetOffsetPosition(g.id());
  const dReal* orot = dGeomGetOffsetRotation(g.id());
  Eigen::Matrix3d rot;
  rot << orot[0], orot[1], orot[2], orot[4], orot[5], orot[6], orot[8], orot[9], orot[10];
  f.centre = Vec3(op[0], op[1], op[2]) + rot * centre;
  f.half = rot.cwiseAbs() * half;
  return f;
}

void CollisionManager::GroupForField() {
  field_groups_.clear();
  field_statics_.clear();
  field_planes_.clear();
  std::vector<GeomImpl*> geoms;
  graph_.Root().ForEachGeom([&geoms](GeomImpl& g) { geoms.push_back(&g); });
  // In creation order: a world built anew from the same robots in the same order groups alike.
  std::sort(geoms.begin(), geoms.end(), [](const GeomImpl* a, const GeomImpl* b) { return a->serial() < b->serial(); });
  std::map<const void*, std::size_t> group_of;  // robot node or loose body -> group
  for (GeomImpl* g : geoms) {
    if (g->is_plane()) {
      dVector4 p;
      dGeomPlaneGetParams(g->id(), p);
      field_planes_.push_back({g, Vec3(p[0], p[1], p[2]), p[3]});
      continue;
    }
    if (!g->body()) {
      StaticGeom s{g, {}};
      dGeomGetAABB(g->id(), s.box);
      field_statics_.push_back(s);
      continue;
    }
    const void* key = g->robot() ? static_cast<const void*>(g->robot()) : static_cast<const void*>(g->body());
    const auto [it, added] = group_of.emplace(key, field_groups_.size());
    if (added) field_groups_.emplace_back();
    FieldGroup& group = field_groups_[it->second];
    group.robot = g->robot();
    if (g->robot() && MeetsOtherRobots(*g)) group.hulls.push_back(group.geoms.size());
    group.geoms.push_back(BoxInBodyFrame(*g));
    // How far this geometry reaches from its body's origin; a little more, for the rounding.
    const dBodyID body = g->body()->id();
    const double reach = ReachFromBody(*g) + 1e-6;
    auto known = std::find_if(group.bodies.begin(), group.bodies.end(), [body](const auto& e) { return e.first == body; });
    if (known == group.bodies.end()) {
      group.bodies.emplace_back(body, reach);
    } else {
      known->second = std::max(known->second, reach);
    }
  }
  // Each group's geometries that may ever meet each plane (a wheel's tyre, scoped away from
  // planes, never does), plane by plane, each plane's in the group's order.
  for (FieldGroup& group : field_groups_) {
    for (std::size_t p = 0; p < field_planes_.size(); ++p) {
      FieldGeom cover{nullptr, group.geoms.front().position, group.geoms.front().rotation, Vec3::Zero(),
                      Vec3::Constant(-1.0)};
      Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
      bool all_covered = true;
      for (std::size_t i = 0; i < group.geoms.size(); ++i) {
        const FieldGeom& g = group.geoms[i];
        if (!MayEverCollide(*g.geom, *field_planes_[p].geom)) continue;
        const bool covered = !IsSphere(*g.geom) && g.position == cover.position;
        all_covered = all_covered && covered;
        group.on_planes.push_back({p, i, covered});
        if (covered) {
          lo = lo.cwiseMin(g.centre - g.half);
          hi = hi.cwiseMax(g.centre + g.half);
        }
      }
      if (lo.x() <= hi.x()) {
        cover.centre = 0.5 * (lo + hi);
        cover.half = 0.5 * (hi - lo);
      }
      group.plane_covers.push_back(cover);
      group.all_covered.push_back(all_covered);
    }
  }
  FindStaticsFreeRectangle();
  cover_above_.assign(field_planes_.size(), 0);
  field_order_.resize(field_groups_.size());
  for (std::size_t i = 0; i < field_order_.size(); ++i) field_order_[i] = i;
  field_grouped_ = true;
}

void CollisionManager::FindStaticsFreeRectangle() {
  // Grown from the middle of the fixed geometries (the field's centre: walls and goals stand
  // round it): each box that enters the rectangle is cut off along the side that leaves the
  // most area. Only ever smaller, so every box cut off earlier stays out.
  double* r = statics_free_;
  if (field_statics_.empty()) {
    r[0] = r[2] = -std::numeric_limits<double>::infinity();
    r[1] = r[3] = std::numeric_limits<double>::infinity();
    return;
  }
  double lo[2] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  double hi[2] = {-lo[0], -lo[1]};
  for (const StaticGeom& s : field_statics_) {
    for (int k = 0; k < 2; ++k) {
      lo[k] = std::min(lo[k], s.box[2 * k]);
      hi[k] = std::max(hi[k], s.box[2 * k + 1]);
    }
  }
  const double centre[2] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])};
  r[0] = lo[0];
  r[1] = hi[0];
  r[2] = lo[1];
  r[3] = hi[1];
  for (const StaticGeom& s : field_statics_) {
    const dReal* b = s.box;
    if (b[0] >= r[1] || r[0] >= b[1] || b[2] >= r[3] || r[2] >= b[3]) continue;  // outside already
    double best_area = -1.0;
    double best[4] = {0, -1, 0, -1};
    for (int k = 0; k < 2; ++k) {
      double cut[4] = {r[0], r[1], r[2], r[3]};
      if (b[2 * k] > centre[k]) {
        cut[2 * k + 1] = b[2 * k];  // the box lies beyond the centre: the high side moves in
      } else if (b[2 * k + 1] < centre[k]) {
        cut[2 * k] = b[2 * k + 1];
      } else {
        continue;  // the box spans the centre along this axis
      }
      const double area = (cut[1] - cut[0]) * (cut[3] - cut[2]);
      if (area > best_area) {
        best_area = area;
        std::copy(cut, cut + 4, best);
      }
    }
    std::copy(best, best + 4, r);  // none found: empty (low above high), nothing is inside
    if (best_area < 0) return;
  }
}

template <typename F>
void CollisionManager::ForEachFieldPair(F& f) {
  if (!field_grouped_) GroupForField();
  for (FieldGroup& group : field_groups_) {
    group.active = std::any_of(group.geoms.begin(), group.geoms.end(), [](const FieldGeom& g) { return g.geom->collides(); });
    if (!group.active) continue;
    for (int k = 0; k < 3; ++k) {
      group.lo[k] = std::numeric_limits<double>::infinity();
      group.hi[k] = -std::numeric_limits<double>::infinity();
    }
    for (const auto& [body, reach] : group.bodies) {
      const dReal* p = dBodyGetPosition(body);
      for (int k = 0; k < 3; ++k) {
        group.lo[k] = std::min(group.lo[k], p[k] - reach);
        group.hi[k] = std::max(group.hi[k], p[k] + reach);
      }
    }
  }
  // Sorted by the boxes' low x, ties by index: one order for one state, whatever the order was
  // the step before (a restored world pairs as the original). Nearly sorted already: insertion.
  InsertionSort(field_order_, [this](std::size_t a, std::size_t b) {
    const double xa = field_groups_[a].lo[0], xb = field_groups_[b].lo[0];
    return xa < xb || (xa == xb && a < b);
  });
  const auto pair_up = [&f](GeomImpl& a, GeomImpl& b) {
    if (MayCollide(a, b) && AabbsOverlap(a.id(), b.id())) f(a, b);
  };
  for (std::size_t i = 0; i < field_order_.size(); ++i) {
    FieldGroup& a = field_groups_[field_order_[i]];
    if (!a.active) continue;
    for (std::size_t j = i + 1; j < field_order_.size(); ++j) {
      FieldGroup& b = field_groups_[field_order_[j]];
      if (b.lo[0] > a.hi[0]) break;  // every later box starts farther along x
      if (!b.active || b.lo[1] > a.hi[1] || a.lo[1] > b.hi[1] || b.lo[2] > a.hi[2] || a.lo[2] > b.hi[2]) continue;
      if (a.robot && b.robot) {
        // Two robots (two groups, two robots) meet through their shells alone: the same pairs
        // in the same order as every part against every part, without the refusals.
        for (const std::size_t ia : a.hulls) {
          for (const std::size_t ib : b.hulls) pair_up(*a.geoms[ia].geom, *b.geoms[ib].geom);
        }
        continue;
      }
      for (const FieldGeom& ga : a.geoms) {
        for (const FieldGeom& gb : b.geoms) pair_up(*ga.geom, *gb.geom);
      }
    }
  }
  for (const std::size_t index : field_order_) {
    FieldGroup& group = field_groups_[index];
    if (!group.active) continue;
    const double* free = statics_free_;
    const bool among_statics = !(group.lo[0] > free[0] && group.hi[0] < free[1] && group.lo[1] > free[2] &&
                                 group.hi[1] < free[3]);
    for (StaticGeom& s : among_statics ? field_statics_ : no_statics_) {
      const dReal* box = s.box;
      if (box[0] > group.hi[0] || group.lo[0] > box[1] || box[2] > group.hi[1] || group.lo[1] > box[3] ||
          box[4] > group.hi[2] || group.lo[2] > box[5]) {
        continue;
      }
      for (const FieldGeom& g : group.geoms) pair_up(*g.geom, *s.geom);
    }
    // A plane's box is infinite: every geometry meets it in the narrow phase (which drops what
    // lies wholly on its free side).
    // A cover above its plane by more than rounding holds every box inside it above too.
    bool all_above = true;  // every geometry that may meet a plane is in a cover above it
    for (std::size_t p = 0; p < field_planes_.size(); ++p) {
      const FieldGeom& c = group.plane_covers[p];
      const FieldPlane& plane = field_planes_[p];
      cover_above_[p] = c.half.x() >= 0 &&
                        BodyBoxAbovePlane(c.position, c.rotation, c.centre, c.half, plane.normal, plane.offset + 1e-9);
      all_above = all_above && cover_above_[p] && group.all_covered[p];
    }
    if (all_above) continue;  // a one-body robot on the carpet, most steps
    // A sphere goes straight to the narrow phase, whose exact test is as cheap as the box's.
    for (const FieldGroup::OnPlane& on : group.on_planes) {
      const FieldPlane& plane = field_planes_[on.plane];
      const FieldGeom& b = group.geoms[on.geom];
      if (!b.geom->collides() || !plane.geom->collides()) continue;
      if (on.covered && cover_above_[on.plane]) continue;
      if (!IsSphere(*b.geom) && BodyBoxAbovePlane(b.position, b.rotation, b.centre, b.half, plane.normal, plane.offset)) {
        continue;
      }
      f(*b.geom, *plane.geom);
    }
  }
}

template <typename F>
void CollisionManager::ForEachPair(F& f) {
  if (broadphase_ == Broadphase::kField) {
    ForEachFieldPair(f);
    return;
  }
  if (broadphase_ == Broadphase::kSceneGraph) {
    graph_.UpdateBounds();
    SphereTree<F>{f, stats_.sphere_tests}.WithinSubtree(graph_.Root());
    return;
  }
  std::function<void(GeomImpl&, GeomImpl&)> call = [&f](GeomImpl& a, GeomImpl& b) { f(a, b); };
  SpaceCallbackData data{&call};
  dSpaceCollide(space_.get(), &data, &SpaceNearCallback);
  for (GeomImpl* g : planes_only_) {
    for (GeomImpl* plane : planes_) {
      if (MayCollide(*g, *plane)) f(*g, *plane);
    }
  }
}

void CollisionManager::ForEachCandidatePair(const std::function<void(GeomImpl&, GeomImpl&)>& f) {
  auto call = [&f](GeomImpl& a, GeomImpl& b) { f(a, b); };
  ForEachPair(call);
}

std::vector<std::pair<GeomImpl*, GeomImpl*>> CollisionManager::TouchingPairs() {
  std::vector<std::pair<GeomImpl*, GeomImpl*>> pairs;
  ForEachCandidatePair([&](GeomImpl& a, GeomImpl& b) {
    if (FindContacts(a, b) > 0) pairs.emplace_back(&a, &b);
  });
  return pairs;
}

void CollisionManager::Collide() {
  stats_ = CollisionStats{};
  ball_touching_.clear();
  hull_touching_.clear();
  robots_in_contact_.clear();
  if (++passes_ % kSurfaceCacheSweepPasses == 0) {
    if (std::erase_if(surfaces_, [this](const auto& entry) {
          return entry.second.last_pass + kSurfaceCacheSweepPasses < passes_;
        }) > 0) {
      ++surfaces_epoch_;
    }
  }
  auto narrow = [this](GeomImpl& a, GeomImpl& b) { Narrow(a, b); };
  ForEachPair(narrow);
  if (swept_ball_step_ > 0) SweepFastBalls();
  if (swept_robot_step_ > 0) SweepRobots();
}

void CollisionManager::SweepRobots() {
  if (!hulls_found_) {  // the robots on the field now; Refile starts over when they change
    graph_.Root().ForEachGeom([&](GeomImpl& g) {
      if (g.hull() && g.prism() && g.body()) {
        hulls_.push_back(&g);
        hull_slack_.push_back(OffsetDistance(g));
      }
    });
    hulls_found_ = true;
  }
  const double dt = swept_robot_step_;
  swept_.clear();
  for (std::size_t h = 0; h < hulls_.size(); ++h) {
    GeomImpl* g = hulls_[h];
    if (!g->collides()) continue;
    // The body's position, not the shell's: the shell's pose is computed only for pairs that
    // pass these bounds (each grown by how far the shell's centre may lie from the body's).
    const BodyImpl& body = *g->body();
    const dReal* p = body.position_array();
    const double slack = hull_slack_[h];
    const dReal* v = body.linear_array();
    const dReal* w = body.angular_array();
    const Vec3 velocity(v[0], v[1], v[2]);
    const double rim = std::abs(w[2]) * g->prism()->radius;
    swept_.push_back({g, p[0], p[1], velocity, rim, g->prism()->radius,
                      g->prism()->radius + (velocity.norm() + rim) * dt + slack, slack});
  }
  // The pairs within reach along x, found on the hulls sorted by x; then taken in the hulls'
  // own order, the order their contacts were always made in.
  double farthest = 0.0;
  for (const SweptHull& s : swept_) farthest = std::max(farthest, s.reach_bound);
  // The order the step before left is nearly sorted already (robots move millimetres a step):
  // insertion sort from it. Ties by index: one order for one state, as from scratch.
  if (swept_order_.size() != swept_.size()) {
    swept_order_.resize(swept_.size());
    for (std::size_t i = 0; i < swept_order_.size(); ++i) swept_order_[i] = i;
  }
  InsertionSort(swept_order_, [this](std::size_t a, std::size_t b) {
    return swept_[a].x < swept_[b].x || (swept_[a].x == swept_[b].x && a < b);
  });
  swept_pairs_.clear();
  for (std::size_t u = 0; u < swept_order_.size(); ++u) {
    const std::size_t i = swept_order_[u];
    for (std::size_t t = u + 1; t < swept_order_.size(); ++t) {
      const std::size_t k = swept_order_[t];
      if (swept_[k].x - swept_[i].x > swept_[i].reach_bound + farthest) break;  // so is every later one
      swept_pairs_.push_back((std::uint64_t{std::min(i, k)} << 32) | std::max(i, k));
    }
  }
  std::sort(swept_pairs_.begin(), swept_pairs_.end());
  for (const std::uint64_t pair : swept_pairs_) {
    const std::size_t i = pair >> 32, k = pair & 0xffffffffu;
    const SweptHull& sa = swept_[i];
    GeomImpl& a = *sa.geom;
    const SweptHull& sb = swept_[k];
    // Farther apart than both could reach at their own speeds: no closer test can pass.
    double dx = sa.x - sb.x, dy = sa.y - sb.y;
    const double bound = sa.reach_bound + sb.reach_bound;
    if (dx * dx + dy * dy > bound * bound) continue;
    GeomImpl& b = *sb.geom;
    if (a.robot() == b.robot()) continue;
    // Near by their bodies: the shells' own centres from here on (their poses computed now).
    const dReal* ca = dGeomGetPosition(a.id());
    const dReal* cb = dGeomGetPosition(b.id());
    dx = ca[0] - cb[0];
    dy = ca[1] - cb[1];
    const double exact = bound - sa.slack - sb.slack;
    if (dx * dx + dy * dy > exact * exact) continue;
    // The most the two can close in this step: their relative speed, and what turning adds at
    // the shells' rims (a flat front's corners sweep 1.35 m/s at 15 rad/s). Slower than a
    // millimetre a step, the ordinary contacts suffice.
    const double reach = ((sa.velocity - sb.velocity).norm() + sa.rim_speed + sb.rim_speed) * dt;
    if (reach < 0.001) continue;
    const double apart = std::hypot(dx, dy);
    if (apart > sa.radius + sb.radius + reach) continue;
    const bool touching = std::any_of(hull_touching_.begin(), hull_touching_.end(), [&](const auto& pair) {
      return (pair.first == &a && pair.second == &b) || (pair.first == &b && pair.second == &a);
    });
    if (touching) continue;  // its contacts are made already
    const Pose pa = a.GetPose(), pb = b.GetPose();
    // a's shell grown by the reach meets b's where the two would meet within the step.
    FlatFrontPrism grown = *a.prism();
    grown.radius += reach;
    grown.front_distance += reach;
    const int n = CollideUprightPrisms(grown, pa, *b.prism(), pb, kShellContacts, scratch_.data());
    if (n <= 0) continue;  // leaning (the mesh test's), or not within reach
    approach_.resize(static_cast<std::size_t>(n));
    for (int c = 0; c < n; ++c) {
      dContactGeom& cg = scratch_[static_cast<std::size_t>(c)];
      const double gap = std::max(0.0, reach - cg.depth);
      approach_[static_cast<std::size_t>(c)] = gap / dt;
      cg.depth = 0.0;
      cg.g1 = a.id();
      cg.g2 = b.id();
    }
    stats_.swept_contacts += static_cast<std::size_t>(n);
    robots_in_contact_.push_back(a.body()->id());
    robots_in_contact_.push_back(b.body()->id());
    AddContacts(a, b, n, approach_.data());
  }
}

namespace {

// Where a ball moving `reach` along `dir` from `from` first meets a shell, in steps of a quarter
// of its radius: the solid test's contact there (normal out of the shell toward the ball).
bool SweepBallAgainstShell(const FlatFrontPrism& shell, const Pose& pose, const Vec3& from, const Vec3& dir,
                           double reach, double radius, dContactGeom& hit) {
  const int samples = static_cast<int>(std::ceil(reach / (0.25 * radius)));
  for (int i = 1; i <= samples; ++i) {
    const Vec3 at = from + dir * (reach * i / samples);
    if (CollideFlatFrontPrismWithSphere(shell, pose, at, radius, &hit) > 0) return true;
  }
  return false;
}

}  // namespace

void CollisionManager::SweepFastBalls() {
  if (!balls_found_) {  // the scene is complete by the first step; a reset builds a new manager
    graph_.Root().ForEachGeom([&](GeomImpl& g) {
      if (g.is_ball() && g.body()) balls_.push_back(&g);
      if (g.prism() && g.body()) {
        sweep_shells_.push_back(&g);
        sweep_shell_reach_.push_back(ReachFromBody(g));
      } else if (!g.is_plane()) {
        sweep_targets_.push_back(&g);
        sweep_target_reach_.push_back(ReachFromBody(g));
      }
    });
    // Runs of targets on one body, each run's farthest reach (a run's first entry is read).
    sweep_run_end_.assign(sweep_targets_.size(), 0);
    sweep_run_reach_.assign(sweep_targets_.size(), 0.0);
    for (std::size_t k = sweep_targets_.size(); k-- > 0;) {
      const bool same = k + 1 < sweep_targets_.size() && sweep_targets_[k]->body() &&
                        sweep_targets_[k + 1]->body() == sweep_targets_[k]->body();
      sweep_run_end_[k] = same ? sweep_run_end_[k + 1] : k + 1;
      sweep_run_reach_[k] = same ? std::max(sweep_target_reach_[k], sweep_run_reach_[k + 1]) : sweep_target_reach_[k];
    }
    balls_found_ = true;
  }
  for (GeomImpl* ball : balls_) {
    if (!ball->collides()) continue;
    const Vec3 v = ball->body()->GetTwist().linear;
    const double radius = ball->GetShape().radius;
    const Vec3 from = ball->GetPose().position;
    // A robot's shell by the ball's speed relative to it: a robot driving at 1.4 m/s into a
    // resting ball moved 7 mm a step at 5 ms, and had the ball 11 mm inside its shell.
    for (std::size_t k = 0; k < sweep_shells_.size(); ++k) {
      GeomImpl& shell = *sweep_shells_[k];
      // Out of reach of the ball's path however the shell is turned: its pose is not needed.
      const BodyImpl& body = *shell.body();  // its ODE arrays, without a call each
      const dReal* at = body.position_array();
      const dReal* w = body.linear_array();
      const Vec3 relative = v - Vec3(w[0], w[1], w[2]);
      const double bound = relative.norm() * swept_ball_step_ + radius + sweep_shell_reach_[k];
      if ((from - Vec3(at[0], at[1], at[2])).squaredNorm() > bound * bound) continue;
      if (!MayCollide(*ball, shell)) continue;
      SweepBallAt(*ball, shell, from, relative, radius);
    }
    // Everything else by the ball's own speed. Slower than half a radius per step the ordinary
    // contacts keep the ball out of the field's static walls and goals (a step's travel in, then
    // pushed out); a robot's other parts are swept down to a tenth of a radius a step.
    const double reach = v.norm() * swept_ball_step_;
    if (reach <= 0.1 * radius) continue;
    const bool slow = reach <= 0.5 * radius;
    const dReal* at = nullptr;  // the position of the body of the run being walked
    for (std::size_t k = 0; k < sweep_targets_.size(); ++k) {
      GeomImpl& other = *sweep_targets_[k];
      if (other.body() && (k == 0 || sweep_targets_[k - 1]->body() != other.body())) {
        // A run's first target: its body's position, and the whole run passed when even its
        // farthest-reaching part is out of reach (then each part's own test fails too).
        at = other.body()->position_array();
        const double run_bound = reach + radius + sweep_run_reach_[k];
        if ((from - Vec3(at[0], at[1], at[2])).squaredNorm() > run_bound * run_bound) {
          k = sweep_run_end_[k] - 1;
          continue;
        }
      }
      if (&other == ball || (slow && !other.body())) continue;
      if (other.body()) {  // a robot's part: out of reach by its body's position, as the shells
        const double bound = reach + radius + sweep_target_reach_[k];
        if ((from - Vec3(at[0], at[1], at[2])).squaredNorm() > bound * bound) continue;
      }
      if (!MayCollide(*ball, other)) continue;
      SweepBallAt(*ball, other, from, v, radius);
    }
  }
}

void CollisionManager::SweepBallAt(GeomImpl& ball, GeomImpl& other, const Vec3& from, const Vec3& velocity,
                                   double radius) {
  const double speed = velocity.norm();
  const double reach = speed * swept_ball_step_;
  // Slower than a tenth of a radius a step (2 mm), the ordinary contacts suffice.
  if (reach <= 0.1 * radius) return;
  const Vec3 dir = velocity / speed;
  // The path's box, grown by the ball's radius: only geometries whose boxes it reaches are tested
  // (a shell's solid test takes the whole ball; a ray's can only hit what its own box reaches).
  const Vec3 to = from + dir * (reach + radius);
  const Vec3 lo = from.cwiseMin(to) - Vec3::Constant(radius), hi = from.cwiseMax(to) + Vec3::Constant(radius);
  dReal box[6];
  dGeomGetAABB(other.id(), box);
  if (box[1] < lo.x() || box[0] > hi.x() || box[3] < lo.y() || box[2] > hi.y() || box[5] < lo.z() ||
      box[4] > hi.z()) {
    return;
  }
  const bool touching = std::any_of(ball_touching_.begin(), ball_touching_.end(), [&](const auto& pair) {
    return (pair.first == &ball && pair.second == &other) || (pair.second == &ball && pair.first == &other);
  });
  if (touching) return;  // its contacts are made already
  dContactGeom hit;
  if (other.prism()) {
    // A shell: the whole ball along its path against the solid (a ray from its centre passes by
    // a corner the ball's side hits, and under an edge a leaning robot lifts).
    if (!SweepBallAgainstShell(*other.prism(), other.GetPose(), from, dir, reach, radius, hit)) return;
  } else {
    if (!ray_) ray_.reset(dCreateRay(nullptr, 1.0));
    dGeomRaySetLength(ray_.get(), reach + radius);
    dGeomRaySet(ray_.get(), from.x(), from.y(), from.z(), dir.x(), dir.y(), dir.z());
    dGeomRaySetFirstContact(ray_.get(), 0);
    dGeomRaySetClosestHit(ray_.get(), 1);
    if (dCollide(ray_.get(), other.id(), 1, &hit, sizeof(dContactGeom)) <= 0) return;
  }
  // The ball's surface reaches `other` within this step: a contact at the surface point, normal
  // out of `other` toward the ball, no depth (ODE stops the approach there).
  Vec3 normal = ToVec3(hit.normal);
  if (normal.dot(dir) > 0) normal = -normal;
  dContactGeom& cg = scratch_[0];
  cg = hit;
  cg.normal[0] = normal.x();
  cg.normal[1] = normal.y();
  cg.normal[2] = normal.z();
  cg.depth = 0.0;
  cg.g1 = ball.id();
  cg.g2 = other.id();
  ++stats_.swept_contacts;
  AddContacts(ball, other, 1);
}

void CollisionManager::ClearContacts() {
  dJointGroupEmpty(contacts_.get());
  static_contacts_.Clear();
}

int CollisionManager::FindContacts(GeomImpl& a, GeomImpl& b) {
  if (SphereAndPlane(a, b)) return CollideSphereAndPlane(a.id(), b.id(), scratch_[0]);
  if (a.prism() && b.prism()) {
    // Two shells always get every level of their contact (bottom and top of the shared height):
    // one contact at mid-height, above the centre of mass, pitched robots that crash into each
    // other (tipped them over at 5 ms steps); with both levels the contact holds them upright.
    const int n = CollideUprightPrisms(*a.prism(), a.GetPose(), *b.prism(), b.GetPose(),
                                       std::max(max_contacts_, kShellContacts), scratch_.data());
    for (int i = 0; i < n; ++i) {
      scratch_[static_cast<std::size_t>(i)].g1 = a.id();
      scratch_[static_cast<std::size_t>(i)].g2 = b.id();
    }
    if (n >= 0) return n;  // else not both upright: the general test
  }
  if ((a.prism() && IsSphere(b)) || (IsSphere(a) && b.prism())) {
    // A ball meets a shell as the solid the shell stands for, not its hollow mesh.
    const GeomImpl& shell = a.prism() ? a : b;
    const GeomImpl& sphere = a.prism() ? b : a;
    dContactGeom& c = scratch_[0];
    const int n = CollideFlatFrontPrismWithSphere(*shell.prism(), shell.GetPose(), sphere.GetPose().position,
                                                  sphere.GetShape().radius, &c);
    c.g1 = a.id();
    c.g2 = b.id();
    if (n > 0 && &shell == &a) {  // the normal must point out of b into a
      for (int k = 0; k < 3; ++k) c.normal[k] = -c.normal[k];
    }
    return n;
  }
  const bool a_box = a.GetShape().kind == Shape::Kind::kBox, b_box = b.GetShape().kind == Shape::Kind::kBox;
  if ((a.prism() && b_box) || (a_box && b.prism())) {
    GeomImpl& shell = a.prism() ? a : b;
    GeomImpl& box = a.prism() ? b : a;
    const int n = CollideUprightPrismWithBox(*shell.prism(), shell.GetPose(), box.GetShape().size, box.GetPose(),
                                             std::max(max_contacts_, kShellContacts), scratch_.data());
    for (int i = 0; i < n; ++i) {
      dContactGeom& c = scratch_[static_cast<std::size_t>(i)];
      c.g1 = a.id();
      c.g2 = b.id();
      if (&shell == &b) {  // the normal must point out of b into a
        for (int k = 0; k < 3; ++k) c.normal[k] = -c.normal[k];
      }
    }
    if (n >= 0) return n;
  }
  return SpreadContacts(scratch_, dCollide(a.id(), b.id(), kContactCandidates, scratch_.data(), sizeof(dContactGeom)),
                        max_contacts_);
}

void CollisionManager::Narrow(GeomImpl& a, GeomImpl& b) {
  // The sphere-plane test is exact and cheaper than the box test that would skip it.
  if (!SphereAndPlane(a, b) && AbovePlane(a, b)) return;
  ++stats_.narrow_tests;
  const int n = FindContacts(a, b);
  if (n <= 0) return;
  ++stats_.touching_pairs;
  if (a.is_ball() || b.is_ball()) ball_touching_.emplace_back(&a, &b);
  if (a.hull() && b.hull() && a.body() && b.body() && a.robot() != b.robot()) {
    hull_touching_.emplace_back(&a, &b);
    robots_in_contact_.push_back(a.body()->id());
    robots_in_contact_.push_back(b.body()->id());
  }
  AddContacts(a, b, n);
}

const SurfaceMaterial& CollisionManager::PairSurface(const GeomImpl& a, const GeomImpl& b) {
  // A step touches a few hundred pairs; starting afresh when the cache is full costs one
  // resolution per pair and keeps memory flat however long a run is.
  constexpr std::size_t kMaxCachedSurfaces = 4096;
  SurfaceMemo* memo = nullptr;
  if (a.serial() < kMaxMemoSerial) {
    if (surface_memo_.size() <= a.serial()) surface_memo_.resize(a.serial() + 1);
    memo = &surface_memo_[a.serial()];
  }
  bool fresh = false;
  CachedSurface* cached = nullptr;
  if (memo && memo->other_serial == b.serial() && memo->epoch == surfaces_epoch_) {
    cached = memo->cached;
  } else {
    if (surfaces_.size() >= kMaxCachedSurfaces && !surfaces_.contains({&a, &b})) {
      surfaces_.clear();
      ++surfaces_epoch_;
    }
    auto [it, added] = surfaces_.try_emplace({&a, &b});
    cached = &it->second;  // a node of the map: it stays put until erased
    fresh = added;
    if (memo) *memo = SurfaceMemo{b.serial(), cached, surfaces_epoch_};
  }
  CachedSurface& c = *cached;
  // The serials tell a geometry from one made later at a freed one's address.
  if (fresh || c.a_serial != a.serial() || c.b_serial != b.serial() || c.a_version != a.material_version() ||
      c.b_version != b.material_version() || c.table_version != materials_.version()) {
    c = CachedSurface{a.serial(), b.serial(), a.material_version(), b.material_version(), materials_.version(),
                      materials_.Resolve(a.Material(), b.Material())};
  }
  c.last_pass = passes_;
  return c.surface;
}

void CollisionManager::AddContacts(GeomImpl& a, GeomImpl& b, int n, const double* approach) {
  const SurfaceMaterial& pair_surface = PairSurface(a, b);
  // The geometry with directional friction (an omni wheel) decides the friction direction.
  const GeomImpl* directional = a.friction_axis() ? &a : (b.friction_axis() ? &b : nullptr);
  for (int i = 0; i < n; ++i) {
    const dContactGeom& cg = scratch_[static_cast<std::size_t>(i)];
    SurfaceMaterial& surface = contact_surface_;
    surface = pair_surface;
    bool accept = true;
    const Vec3 position = ToVec3(cg.pos);
    const Vec3 normal = ToVec3(cg.normal);  // points out of b (g2) into a (g1)
    // Each side's observers may set its own surface's velocity (a roller fixed to its body).
    Vec3 moving_a = Vec3::Zero(), moving_b = Vec3::Zero();
    surface.surface_velocity = Vec3::Zero();
    for (const auto& h : a.observers()) {
      h(Contact{&a, &b, b.is_ball(), position, normal, cg.depth}, surface, accept);
      moving_a = surface.surface_velocity;
    }
    surface.surface_velocity = Vec3::Zero();
    for (const auto& h : b.observers()) {
      h(Contact{&b, &a, a.is_ball(), position, -normal, cg.depth}, surface, accept);
      moving_b = surface.surface_velocity;
    }
    if (!accept) continue;
    // ODE's friction rows hold (v1 - v2)·t = motion at the contact, body 1 being a's unless a is
    // static: then ODE attaches b's body first and turns the normal round. Surfaces moving over
    // their bodies meet without slip when v1 - v2 = moving2 - moving1.
    const bool reversed = !a.body() && b.body();
    const Vec3 ode_normal = reversed ? Vec3(-normal) : normal;
    Vec3 motion = reversed ? Vec3(moving_a - moving_b) : Vec3(moving_b - moving_a);
    motion -= normal * normal.dot(motion);
    const bool surface_moves = motion.norm() > 1e-9;

    // Zeroed but for the geometry, which is copied: zeroing all of it first cost a contact more
    // than any line of its own.
    dContact c;
    c.surface = dSurfaceParameters{};
    c.geom = cg;
    c.fdir1[0] = c.fdir1[1] = c.fdir1[2] = c.fdir1[3] = 0;
    // A level of two shells still apart (CollideUprightPrisms writes its gap as a depth below
    // zero; SweepRobots' contacts come at depth 0 with their approach) is speculative, as a swept
    // contact: it holds once the gap has closed in the step.
    double gap_speed = approach ? approach[i] : -1.0;
    if (cg.depth < 0.0) {
      if (step_ <= 0) continue;  // no step to close it in
      c.geom.depth = 0.0;
      gap_speed = -cg.depth / step_;
    }
    int mode = dContactApprox1;
    c.surface.mu = surface.mu;
    if (directional) {
      // The body's orientation alone: its pose would copy the position too, once per wheel contact.
      const Quat q = directional->body() ? ToQuat(dBodyGetQuaternion(directional->body()->id())) : Quat::Identity();
      Vec3 dir = Rotate(q, *directional->friction_axis());
      dir -= normal * normal.dot(dir);  // project onto the contact plane
      if (dir.norm() > 1e-6) {
        dir.normalize();
        if (const double turn = directional->friction_axis_turn(); turn != 0.0) {
          // Rollers at an angle to the axle: turned about the normal pointing into the wheel.
          const Vec3 into = directional == &a ? normal : Vec3(-normal);
          dir = Eigen::AngleAxisd(turn, into) * dir;
        }
        mode |= dContactMu2 | dContactFDir1;
        c.fdir1[0] = dir.x();
        c.fdir1[1] = dir.y();
        c.fdir1[2] = dir.z();
        c.surface.mu2 = Mu2(surface);
        if (surface_moves) {
          mode |= dContactMotion1 | dContactMotion2;
          c.surface.motion1 = motion.dot(dir);
          c.surface.motion2 = motion.dot(ode_normal.cross(dir));  // ODE's second direction: n × t1
        }
      }
    } else if (surface_moves) {
      // Friction pulls toward the moving surface's speed: its direction first, both directions mu.
      const Vec3 dir = motion.normalized();
      mode |= dContactFDir1 | dContactMotion1;
      c.fdir1[0] = dir.x();
      c.fdir1[1] = dir.y();
      c.fdir1[2] = dir.z();
      c.surface.motion1 = motion.norm();
      if (surface.mu2 >= 0 && surface.mu2 != surface.mu) {
        mode |= dContactMu2;
        c.surface.mu2 = surface.mu2;
      }
    } else if (const Vec3 slip = BallSlip(a, b, position, normal); slip.norm() > kSlipThreshold) {
      // ODE's friction is a pyramid: each of two directions holds up to mu·N on its own, so a
      // ball skidding one way still sticks fully across it (a spinning ball held by a dribbler
      // could never be carried sideways). Coulomb's cone acts against the slip alone: point the
      // first direction along the slip, with no friction across it.
      mode |= dContactMu2 | dContactFDir1;
      const Vec3 dir = slip.normalized();
      c.fdir1[0] = dir.x();
      c.fdir1[1] = dir.y();
      c.fdir1[2] = dir.z();
      c.surface.mu2 = 0.0;
    } else if (surface.mu2 >= 0 && surface.mu2 != surface.mu) {
      mode |= dContactMu2;
      c.surface.mu2 = surface.mu2;
    }
    if (gap_speed >= 0.0) {
      // Speculative: the bodies may close the gap within the step, no more; no bounce before
      // they touch.
      mode |= dContactMotionN;
      c.surface.motionN = -gap_speed;
    } else if (surface.bounce > 0) {
      mode |= dContactBounce;
      c.surface.bounce = surface.bounce;
      c.surface.bounce_vel = surface.bounce_velocity;
    }
    if (surface.soft_erp >= 0) {
      mode |= dContactSoftERP;
      c.surface.soft_erp = surface.soft_erp;
    }
    // Two shells touching as robots do (a push, a crash: a few cm at most) are stiff; two put into
    // each other (a teleport) part at the world's gentler rate. Either way no faster than
    // kRobotPartingSpeed, with no bounce once that deep: at the fast profile's 5 ms, ERP 0.8 on a
    // teleport's last 3 cm pushed at 3 m/s in a step and tipped wheel robots over.
    if (a.hull() && b.hull() && step_ > 0) {
      double erp = cg.depth < kStiffRobotContactDepth && robot_contact_erp_ >= 0 ? robot_contact_erp_ : erp_;
      const double parting = kRobotPartingSpeed * step_ / std::max(cg.depth, 1e-9);
      if (parting < erp) {
        erp = parting;
        mode &= ~dContactBounce;
      }
      if (cg.depth >= kStiffRobotContactDepth) {
        // Put into each other, the shells' surfaces do not rub: no friction while they part.
        c.surface.mu = 0.0;
        c.surface.mu2 = 0.0;
      }
      mode |= dContactSoftERP;
      c.surface.soft_erp = erp;
    }
    if (surface.soft_cfm >= 0) {
      mode |= dContactSoftCFM;
      c.surface.soft_cfm = surface.soft_cfm;
    }
    if (surface.rolling_friction > 0) {
      mode |= dContactRolling;
      c.surface.rho = surface.rolling_friction;
      c.surface.rho2 = surface.rolling_friction;
      c.surface.rhoN = surface.rolling_friction;
    }
    if (surface.slip > 0) {
      mode |= dContactSlip1 | dContactSlip2;
      c.surface.slip1 = surface.slip;
      c.surface.slip2 = surface.slip;
    }
    c.surface.mode = mode;
    // A body touching only the static world keeps its contacts out of ODE: the kernel solves it
    // (IslandStepper), and makes them joints if QuickStep must.
    static_contacts_.Make(c, a.body() ? a.body()->id() : nullptr, b.body() ? b.body()->id() : nullptr);
    ++stats_.contacts;
  }
}

std::optional<Vec3> CollisionManager::FreeBallSpot(const BodyImpl& ball, const Vec3& wanted, double tolerance,
                                                   double search, const Eigen::Vector2d& bounds) {
  GeomImpl* sphere = nullptr;
  graph_.Root().ForEachGeom([&](GeomImpl& g) {
    if (g.body() == &ball && g.GetShape().kind == Shape::Kind::kSphere) sphere = &g;
  });
  if (!sphere) return wanted;
  const double radius = sphere->GetShape().radius;
  // Robots' shells and the field's static geometry, with bounds taken now (robots may have been
  // put down this instant). A robot's parts are left out: a ball put in the mouth presses on
  // the dribbler bar as a real one sprung onto it does, and stays there.
  struct Obstacle {
    GeomImpl* geom;
    BoundingSphere bounds;
    Vec3 centre;
  };
  std::vector<Obstacle> obstacles;
  graph_.Root().ForEachGeom([&](GeomImpl& g) {
    if (g.is_plane() || (g.body() && !g.prism()) || !MayCollide(*sphere, g)) return;
    obstacles.push_back({&g, g.WorldBounds(), g.GetPose().position});
  });
  OdeGeom probe(dCreateSphere(nullptr, radius));
  // The deepest overlap of the ball at `at`, m, and the way out of it (horizontal, unit; zero
  // when the way out is straight up or down).
  Eigen::Vector2d out = Eigen::Vector2d::Zero();
  const auto deepest = [&](const Vec3& at) {
    double depth = 0.0;
    const BoundingSphere here{at, radius};
    for (const Obstacle& o : obstacles) {
      if (!here.Overlaps(o.bounds)) continue;
      dContactGeom hit;
      int n = 0;
      if (o.geom->prism()) {
        // A shell as the solid it is to every other contact (ODE's mesh test misses a ball inside).
        n = CollideFlatFrontPrismWithSphere(*o.geom->prism(), o.geom->GetPose(), at, radius, &hit);
      } else {
        dGeomSetPosition(probe.get(), at.x(), at.y(), at.z());
        n = dCollide(probe.get(), o.geom->id(), 1, &hit, sizeof hit);
      }
      if (n <= 0 || hit.depth <= depth) continue;
      depth = hit.depth;
      Eigen::Vector2d away(hit.normal[0], hit.normal[1]);
      if (away.dot((at - o.centre).head<2>()) < 0) away = -away;  // from the obstacle toward the ball
      out = away.norm() > 1e-9 ? Eigen::Vector2d(away.normalized()) : Eigen::Vector2d::Zero();
    }
    return depth;
  };
  if (deepest(wanted) <= tolerance) return wanted;
  // Rings about the wanted spot, each tried from the way out of its deepest overlap first.
  const double first = out.isZero() ? 0.0 : std::atan2(out.y(), out.x());
  for (double ring = kFreeSpotStep; ring <= search + 1e-12; ring += kFreeSpotStep) {
    const int n = std::clamp(static_cast<int>(std::ceil(2 * M_PI * ring / kFreeSpotStep)), 8, 64);
    for (int k = 0; k < n; ++k) {
      const int turn = (k + 1) / 2 * (k % 2 == 1 ? 1 : -1);  // 0, +1, -1, +2, -2, ...
      const double a = first + 2 * M_PI * turn / n;
      const Vec3 at = wanted + ring * Vec3(std::cos(a), std::sin(a), 0.0);
      if (std::abs(at.x()) > bounds.x() || std::abs(at.y()) > bounds.y()) continue;
      if (deepest(at) <= tolerance) return at;
    }
  }
  return std::nullopt;
}

}  // namespace ubersim::kernel
