// SPDX-License-Identifier: Apache-2.0
#include "physics/scene_graph.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ubersim/error.hpp"

namespace ubersim::kernel {
namespace {

constexpr double kNoLimit = 1e29;

void SetOdeRotation(dBodyID body, const Quat& q) {
  const dQuaternion odeq = {q.w(), q.x(), q.y(), q.z()};
  dBodySetQuaternion(body, odeq);
}

bool AllFinite(const Vec3& v) { return v.allFinite(); }

void RequireFinite(const Vec3& v, const char* what) {
  if (!AllFinite(v)) throw PluginError(std::string(what) + " is not finite");
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// BodyImpl

BodyImpl::BodyImpl(dWorldID world, const BodySpec& spec, std::uint64_t& non_finite_sums, std::uint64_t serial)
    : name_(spec.name),
      mass_(spec.mass.mass),
      body_(dBodyCreate(world)),
      non_finite_sums_(&non_finite_sums),
      serial_(serial),
      position_(dBodyGetPosition(body_.get())),
      quaternion_(dBodyGetQuaternion(body_.get())),
      linear_(dBodyGetLinearVel(body_.get())),
      angular_(dBodyGetAngularVel(body_.get())),
      force_(const_cast<dReal*>(dBodyGetForce(body_.get()))),
      torque_(const_cast<dReal*>(dBodyGetTorque(body_.get()))) {
  const MassSpec& m = spec.mass;
  if (!(m.mass > 0.0) || !std::isfinite(m.mass)) {
    throw PluginError("body '" + spec.name + "': mass must be positive and finite");
  }
  if (m.center_of_mass.norm() > 1e-12) {
    // ODE keeps the centre of mass at the body origin; offsets belong in the geometry poses.
    throw PluginError("body '" + spec.name +
                      "': center_of_mass must be zero; place the body origin at the centre of "
                      "mass and offset its geometries instead");
  }
  dMass mass;
  dMassSetParameters(&mass, m.mass, 0, 0, 0, m.inertia_diagonal.x(), m.inertia_diagonal.y(),
                     m.inertia_diagonal.z(), m.inertia_off_diagonal.x(),
                     m.inertia_off_diagonal.y(), m.inertia_off_diagonal.z());
  if (!dMassCheck(&mass)) {
    throw PluginError("body '" + spec.name + "': inertia tensor is not physically valid");
  }
  dBodySetMass(body_.get(), &mass);
  dBodySetGravityMode(body_.get(), spec.gravity ? 1 : 0);
  SetPose(spec.pose);
  SetTwist(spec.twist);
  dBodySetData(body_.get(), this);
}

void BodyImpl::AddFixedMass(const MassSpec& part, const Pose& at) {
  if (!(part.mass > 0.0) || !std::isfinite(part.mass) || !part.inertia_diagonal.allFinite() ||
      !part.inertia_off_diagonal.allFinite() || !at.position.allFinite()) {
    throw PluginError("body '" + name_ + "': a fixed part's mass must be positive and finite");
  }
  const Eigen::Matrix3d own = (Eigen::Matrix3d() << part.inertia_diagonal.x(), part.inertia_off_diagonal.x(),
                               part.inertia_off_diagonal.y(), part.inertia_off_diagonal.x(), part.inertia_diagonal.y(),
                               part.inertia_off_diagonal.z(), part.inertia_off_diagonal.y(),
                               part.inertia_off_diagonal.z(), part.inertia_diagonal.z())
                                  .finished();
  const Eigen::Matrix3d r = at.orientation.normalized().toRotationMatrix();
  const Vec3& p = at.position;
  // The part's inertia turned into the body frame, then moved to the body origin (parallel axes).
  const Eigen::Matrix3d added =
      r * own * r.transpose() + part.mass * (p.squaredNorm() * Eigen::Matrix3d::Identity() - p * p.transpose());
  dMass m;
  dBodyGetMass(body_.get(), &m);
  const auto at_origin = [&m, &added](int row, int col) { return m.I[row * 4 + col] + added(row, col); };
  const double total = m.mass + part.mass;
  dMassSetParameters(&m, total, 0, 0, 0, at_origin(0, 0), at_origin(1, 1), at_origin(2, 2), at_origin(0, 1),
                     at_origin(0, 2), at_origin(1, 2));
  if (!dMassCheck(&m)) throw PluginError("body '" + name_ + "': adding a fixed part left no valid inertia tensor");
  dBodySetMass(body_.get(), &m);
  mass_ = total;
}

Pose BodyImpl::GetPose() const {
  return Pose{ToVec3(position_), ToQuat(quaternion_)};
}

void BodyImpl::SetPose(const Pose& pose) {
  RequireFinite(pose.position, "body position");
  dBodySetPosition(body_.get(), pose.position.x(), pose.position.y(), pose.position.z());
  SetOdeRotation(body_.get(), pose.orientation.normalized());
  dBodyEnable(body_.get());
}

Twist BodyImpl::GetTwist() const {
  return Twist{ToVec3(linear_), ToVec3(angular_)};
}

void BodyImpl::SetTwist(const Twist& t) {
  RequireFinite(t.linear, "body velocity");
  RequireFinite(t.angular, "body angular velocity");
  dBodySetLinearVel(body_.get(), t.linear.x(), t.linear.y(), t.linear.z());
  dBodySetAngularVel(body_.get(), t.angular.x(), t.angular.y(), t.angular.z());
  dBodyEnable(body_.get());
}

Vec3 BodyImpl::PointVelocity(const Vec3& p) const {
  dVector3 v;
  dBodyGetPointVel(body_.get(), p.x(), p.y(), p.z(), v);
  return ToVec3(v);
}

void BodyImpl::CountIfNonFinite(const dReal* sum) {
  // A sum of finite values that is not finite itself: one of them overflowed, or the value was
  // not finite before the call. Summing first is one test for the three (a false alarm, finite
  // values whose sum overflows, costs BodyWatch a look and no more).
  if (!std::isfinite(sum[0] + sum[1] + sum[2])) ++*non_finite_sums_;
}

void BodyImpl::AddForce(const Vec3& f) {
  RequireFinite(f, "force");
  // dBodyAddForce's whole work (facc += f, nothing else), without the call into ODE.
  for (int k = 0; k < 3; ++k) force_[k] += f[k];
  CountIfNonFinite(force_);
}

void BodyImpl::AddForceAtPoint(const Vec3& f, const Vec3& p) {
  RequireFinite(f, "force");
  RequireFinite(p, "force point");
  dBodyAddForceAtPos(body_.get(), f.x(), f.y(), f.z(), p.x(), p.y(), p.z());
  CountIfNonFinite(force_);
  CountIfNonFinite(torque_);
}

void BodyImpl::AddTorque(const Vec3& t) {
  RequireFinite(t, "torque");
  // dBodyAddTorque's whole work (tacc += t, nothing else), without the call into ODE.
  for (int k = 0; k < 3; ++k) torque_[k] += t[k];
  CountIfNonFinite(torque_);
}

void BodyImpl::ApplyImpulse(const Vec3& impulse) {
  RequireFinite(impulse, "impulse");
  const Vec3 v = ToVec3(dBodyGetLinearVel(body_.get())) + impulse / mass_;
  dBodySetLinearVel(body_.get(), v.x(), v.y(), v.z());
  dBodyEnable(body_.get());
  CountIfNonFinite(linear_);
}

// ---------------------------------------------------------------------------------------------
// GeomImpl

// A convex polyhedron for ODE: its points, one plane per face (outward normal, offset), and the
// faces. Checks what ODE would silently get wrong: bad indices, degenerate or non-convex faces.
dGeomID GeomImpl::CreateConvex(const Shape& s) {
  const auto fail = [this](const std::string& why) {
    return PluginError("geometry '" + name_ + "': convex shape " + why);
  };
  if (s.vertices.size() < 4) throw fail("needs at least 4 vertices");
  for (const Vec3& v : s.vertices) mesh_vertices_.insert(mesh_vertices_.end(), {v.x(), v.y(), v.z()});
  std::size_t at = 0;
  while (at < s.indices.size()) {
    const unsigned count = s.indices[at];
    if (count < 3 || at + 1 + count > s.indices.size()) {
      throw fail("has a face that is not 'count, then count vertex indices' (at index " + std::to_string(at) + ")");
    }
    std::vector<Vec3> face;
    for (unsigned k = 1; k <= count; ++k) {
      const unsigned i = s.indices[at + k];
      if (i >= s.vertices.size()) throw fail("face index " + std::to_string(i) + " is out of range");
      face.push_back(s.vertices[i]);
    }
    const Vec3 normal = (face[1] - face[0]).cross(face[2] - face[0]);
    if (normal.norm() < 1e-12) throw fail("has a degenerate face (at index " + std::to_string(at) + ")");
    const Vec3 n = normal.normalized();
    const double offset = n.dot(face[0]);
    for (const Vec3& v : s.vertices) {
      if (n.dot(v) - offset > 1e-9) {
        throw fail("is not convex, or a face is not counter-clockwise seen from outside (at index " +
                   std::to_string(at) + ")");
      }
    }
    convex_planes_.insert(convex_planes_.end(), {n.x(), n.y(), n.z(), offset});
    convex_polygons_.insert(convex_polygons_.end(), s.indices.begin() + static_cast<long>(at),
                            s.indices.begin() + static_cast<long>(at + 1 + count));
    at += 1 + count;
  }
  if (convex_planes_.size() < 4 * 4) throw fail("needs at least 4 faces");
  return dCreateConvex(nullptr, convex_planes_.data(), static_cast<unsigned>(convex_planes_.size() / 4),
                       mesh_vertices_.data(), static_cast<unsigned>(s.vertices.size()), convex_polygons_.data());
}

GeomImpl::GeomImpl(NodeImpl& owner, const GeomSpec& spec, BodyImpl* body)
    : owner_(owner),
      name_(spec.name),
      shape_(spec.shape),
      material_(spec.material),
      friction_axis_(spec.friction_axis),
      friction_axis_turn_(spec.friction_axis_turn),
      body_(body),
      collides_(spec.collides),
      scope_(spec.scope),
      bounding_radius_(spec.shape.BoundingRadius()) {
  serial_ = owner.graph().NextGeomSerial();
  for (const NodeImpl* n = &owner; n && !robot_; n = n->parent()) {
    if (n->is_robot()) robot_ = n;
  }
  const Shape& s = shape_;
  auto positive = [&](double v, const char* what) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw PluginError("geometry '" + name_ + "': " + what + " must be positive and finite");
    }
  };
  dGeomID g = nullptr;
  switch (s.kind) {
    case Shape::Kind::kSphere:
      positive(s.radius, "radius");
      g = dCreateSphere(nullptr, s.radius);
      break;
    case Shape::Kind::kBox:
      positive(s.size.x(), "size.x");
      positive(s.size.y(), "size.y");
      positive(s.size.z(), "size.z");
      g = dCreateBox(nullptr, s.size.x(), s.size.y(), s.size.z());
      break;
    case Shape::Kind::kCylinder:
      positive(s.radius, "radius");
      positive(s.length, "length");
      g = dCreateCylinder(nullptr, s.radius, s.length);
      break;
    case Shape::Kind::kCapsule:
      positive(s.radius, "radius");
      positive(s.length, "length");
      g = dCreateCapsule(nullptr, s.radius, s.length);
      break;
    case Shape::Kind::kPlane:
      if (body) throw PluginError("geometry '" + name_ + "': a plane cannot move with a body");
      g = dCreatePlane(nullptr, s.plane_normal.x(), s.plane_normal.y(), s.plane_normal.z(),
                       s.plane_offset);
      break;
    case Shape::Kind::kTriangleMesh: {
      if (s.vertices.empty() || s.indices.size() < 3 || s.indices.size() % 3 != 0) {
        throw PluginError("geometry '" + name_ + "': a triangle mesh needs vertices and 3·n indices");
      }
      for (unsigned i : s.indices) {
        if (i >= s.vertices.size()) {
          throw PluginError("geometry '" + name_ + "': mesh index out of range");
        }
      }
      for (const Vec3& v : s.vertices) {
        mesh_vertices_.insert(mesh_vertices_.end(), {v.x(), v.y(), v.z()});
      }
      mesh_indices_.assign(s.indices.begin(), s.indices.end());
      mesh_data_.reset(dGeomTriMeshDataCreate());
      dGeomTriMeshDataBuildDouble(mesh_data_.get(), mesh_vertices_.data(), 3 * sizeof(dReal),
                                  static_cast<int>(s.vertices.size()), mesh_indices_.data(),
                                  static_cast<int>(mesh_indices_.size()), 3 * sizeof(dTriIndex));
      g = dCreateTriMesh(nullptr, mesh_data_.get(), nullptr, nullptr, nullptr);
      break;
    }
    case Shape::Kind::kConvex:
      g = CreateConvex(s);
      break;
  }
  geom_.reset(g);
  dGeomSetData(g, this);
  if (body) {
    dGeomSetBody(g, body->id());
    const Pose& o = spec.offset;
    // A geometry without an offset uses its body's pose as it is; one with an offset, even an
    // identity one, has ODE compose the two whenever the body moves (a wheel's carpet contact
    // and its bounding box, every step).
    if (o.position != Vec3::Zero() || o.orientation.coeffs() != Quat::Identity().coeffs()) {
      dGeomSetOffsetPosition(g, o.position.x(), o.position.y(), o.position.z());
      const dQuaternion q = {o.orientation.w(), o.orientation.x(), o.orientation.y(),
                             o.orientation.z()};
      dGeomSetOffsetQuaternion(g, q);
    }
  } else if (s.kind != Shape::Kind::kPlane) {
    const Pose& o = spec.offset;
    dGeomSetPosition(g, o.position.x(), o.position.y(), o.position.z());
    const dQuaternion q = {o.orientation.w(), o.orientation.x(), o.orientation.y(),
                           o.orientation.z()};
    dGeomSetQuaternion(g, q);
  }
}

SceneNode& GeomImpl::Owner() const { return owner_; }

Pose GeomImpl::GetPose() const {
  if (shape_.kind == Shape::Kind::kPlane) return Pose{};
  dQuaternion q;
  dGeomGetQuaternion(geom_.get(), q);
  return Pose{ToVec3(dGeomGetPosition(geom_.get())), ToQuat(q)};
}

BoundingSphere GeomImpl::WorldBounds() const {
  if (shape_.kind == Shape::Kind::kPlane) {
    return BoundingSphere{Vec3::Zero(), std::numeric_limits<double>::infinity()};
  }
  return BoundingSphere{ToVec3(dGeomGetPosition(geom_.get())), bounding_radius_};
}

// ---------------------------------------------------------------------------------------------
// JointImpl

JointImpl::JointImpl(dWorldID world, const JointSpec& spec)
    : name_(spec.name), kind_(spec.kind), measure_torque_(spec.measure_torque) {
  auto* child = dynamic_cast<BodyImpl*>(spec.child);
  auto* parent = spec.parent ? dynamic_cast<BodyImpl*>(spec.parent) : nullptr;
  if (!child) throw PluginError("joint '" + name_ + "': child body is required");
  if (spec.parent && !parent) throw PluginError("joint '" + name_ + "': parent is not a scene body");
  if (!spec.anchor.allFinite() || !spec.axis.allFinite() || spec.axis.norm() < 1e-9) {
    throw PluginError("joint '" + name_ + "': anchor and axis must be finite, axis non-zero");
  }
  const Vec3 a = spec.anchor;
  const Vec3 ax = spec.axis.normalized();
  dJointID j = nullptr;
  switch (kind_) {
    case JointKind::kHinge:
      j = dJointCreateHinge(world, nullptr);
      dJointAttach(j, child->id(), parent ? parent->id() : nullptr);
      dJointSetHingeAnchor(j, a.x(), a.y(), a.z());
      dJointSetHingeAxis(j, ax.x(), ax.y(), ax.z());
      if (spec.lower_limit > -kNoLimit) dJointSetHingeParam(j, dParamLoStop, spec.lower_limit);
      if (spec.upper_limit < kNoLimit) dJointSetHingeParam(j, dParamHiStop, spec.upper_limit);
      break;
    case JointKind::kSlider:
      j = dJointCreateSlider(world, nullptr);
      dJointAttach(j, child->id(), parent ? parent->id() : nullptr);
      dJointSetSliderAxis(j, ax.x(), ax.y(), ax.z());
      if (spec.lower_limit > -kNoLimit) dJointSetSliderParam(j, dParamLoStop, spec.lower_limit);
      if (spec.upper_limit < kNoLimit) dJointSetSliderParam(j, dParamHiStop, spec.upper_limit);
      break;
    case JointKind::kFixed:
      j = dJointCreateFixed(world, nullptr);
      dJointAttach(j, child->id(), parent ? parent->id() : nullptr);
      dJointSetFixed(j);
      break;
    case JointKind::kBall:
      j = dJointCreateBall(world, nullptr);
      dJointAttach(j, child->id(), parent ? parent->id() : nullptr);
      dJointSetBallAnchor(j, a.x(), a.y(), a.z());
      break;
    case JointKind::kUniversal: {
      const Vec3 ax2 = spec.axis2.normalized();
      j = dJointCreateUniversal(world, nullptr);
      dJointAttach(j, child->id(), parent ? parent->id() : nullptr);
      dJointSetUniversalAnchor(j, a.x(), a.y(), a.z());
      dJointSetUniversalAxis1(j, ax.x(), ax.y(), ax.z());
      dJointSetUniversalAxis2(j, ax2.x(), ax2.y(), ax2.z());
      break;
    }
  }
  joint_.reset(j);
  // Feedback makes QuickStep compute the joint's force and torque every step: 6.5 % of a Div A
  // step with 88 wheel hinges, for a number no shipped part reads.
  if (measure_torque_) dJointSetFeedback(j, &feedback_);
}

void JointImpl::SetMotor(double velocity, double max_effort) {
  if (!std::isfinite(velocity) || !std::isfinite(max_effort) || max_effort < 0) {
    throw PluginError("joint '" + name_ + "': motor velocity/effort must be finite, effort >= 0");
  }
  dJointID j = joint_.get();
  switch (kind_) {
    case JointKind::kHinge:
      dJointSetHingeParam(j, dParamVel, velocity);
      dJointSetHingeParam(j, dParamFMax, max_effort);
      break;
    case JointKind::kSlider:
      dJointSetSliderParam(j, dParamVel, velocity);
      dJointSetSliderParam(j, dParamFMax, max_effort);
      break;
    case JointKind::kUniversal:
      dJointSetUniversalParam(j, dParamVel, velocity);
      dJointSetUniversalParam(j, dParamFMax, max_effort);
      break;
    default:
      throw PluginError("joint '" + name_ + "': this joint kind has no motor");
  }
  dBodyID b = dJointGetBody(j, 0);
  if (b) dBodyEnable(b);
}

double JointImpl::Position() const {
  switch (kind_) {
    case JointKind::kHinge: return dJointGetHingeAngle(joint_.get());
    case JointKind::kSlider: return dJointGetSliderPosition(joint_.get());
    case JointKind::kUniversal: return dJointGetUniversalAngle1(joint_.get());
    default: return 0.0;
  }
}

double JointImpl::Rate() const {
  switch (kind_) {
    case JointKind::kHinge: return dJointGetHingeAngleRate(joint_.get());
    case JointKind::kSlider: return dJointGetSliderPositionRate(joint_.get());
    case JointKind::kUniversal: return dJointGetUniversalAngle1Rate(joint_.get());
    default: return 0.0;
  }
}

Vec3 JointImpl::Axis() const {
  dVector3 a = {0, 0, 1, 0};
  switch (kind_) {
    case JointKind::kHinge: dJointGetHingeAxis(joint_.get(), a); break;
    case JointKind::kSlider: dJointGetSliderAxis(joint_.get(), a); break;
    case JointKind::kUniversal: dJointGetUniversalAxis1(joint_.get(), a); break;
    default: break;
  }
  return ToVec3(a);
}

Vec3 JointImpl::LastTorque() const {
  if (!measure_torque_) {
    throw PluginError("joint '" + name_ + "': LastTorque needs the joint created with JointSpec::measure_torque");
  }
  // Body 0 of the joint is the child (see the constructor's dJointAttach order).
  return ToVec3(kind_ == JointKind::kSlider ? feedback_.f1 : feedback_.t1);
}

// ---------------------------------------------------------------------------------------------
// NodeImpl

NodeImpl::NodeImpl(SceneGraph& graph, NodeImpl* parent, std::string name)
    : graph_(graph), parent_(parent), name_(std::move(name)) {}

NodeImpl::~NodeImpl() = default;

std::string NodeImpl::Path() const {
  if (!parent_) return "";
  const std::string up = parent_->Path();
  return up.empty() ? name_ : up + "/" + name_;
}

SceneNode& NodeImpl::AddChild(std::string_view name) {
  if (name.empty() || name.find('/') != std::string_view::npos) {
    throw PluginError("scene node name '" + std::string(name) + "' must be non-empty without '/'");
  }
  if (FindChildNode(name)) {
    throw PluginError("scene node '" + Path() + "' already has a child '" + std::string(name) + "'");
  }
  children_.push_back(std::make_unique<NodeImpl>(graph_, this, std::string(name)));
  return *children_.back();
}

void NodeImpl::RemoveChild(const NodeImpl& child) {
  std::erase_if(children_, [&child](const std::unique_ptr<NodeImpl>& c) { return c.get() == &child; });
}

NodeImpl& NodeImpl::AddChildFirst(std::string_view name) {
  AddChild(name);  // its checks
  std::rotate(children_.begin(), children_.end() - 1, children_.end());
  return *children_.front();
}

NodeImpl* NodeImpl::FindChildNode(std::string_view name) const {
  for (const auto& c : children_) {
    if (c->name_ == name) return c.get();
  }
  return nullptr;
}

SceneNode* NodeImpl::FindChild(std::string_view name) const { return FindChildNode(name); }

Body& NodeImpl::AddBody(const BodySpec& spec) {
  if (FindBody(spec.name)) {
    throw PluginError("scene node '" + Path() + "' already has a body '" + spec.name + "'");
  }
  bodies_.push_back(std::make_unique<BodyImpl>(graph_.world(), spec, graph_.non_finite_sums(), graph_.NextBodySerial()));
  return *bodies_.back();
}

Geom& NodeImpl::AddGeom(const GeomSpec& spec, Body* body) {
  if (FindGeom(spec.name)) {
    throw PluginError("scene node '" + Path() + "' already has a geometry '" + spec.name + "'");
  }
  BodyImpl* b = nullptr;
  if (body) {
    b = dynamic_cast<BodyImpl*>(body);
    if (!b) throw PluginError("geometry '" + spec.name + "': body is not a scene body");
  }
  geoms_.push_back(std::make_unique<GeomImpl>(*this, spec, b));
  graph_.NotifyGeomAdded(*geoms_.back());
  return *geoms_.back();
}

Joint& NodeImpl::AddJoint(const JointSpec& spec) {
  if (FindJoint(spec.name)) {
    throw PluginError("scene node '" + Path() + "' already has a joint '" + spec.name + "'");
  }
  joints_.push_back(std::make_unique<JointImpl>(graph_.world(), spec));
  return *joints_.back();
}

Body* NodeImpl::FindBody(std::string_view name) const {
  for (const auto& b : bodies_) {
    if (b->Name() == name) return b.get();
  }
  return nullptr;
}

Geom* NodeImpl::FindGeom(std::string_view name) const {
  for (const auto& g : geoms_) {
    if (g->Name() == name) return g.get();
  }
  return nullptr;
}

Joint* NodeImpl::FindJoint(std::string_view name) const {
  for (const auto& j : joints_) {
    if (j->Name() == name) return j.get();
  }
  return nullptr;
}

const BoundingSphere& NodeImpl::UpdateBounds() {
  BoundingSphere b;
  for (const auto& g : geoms_) {
    g->RefreshBounds();
    if (g->collides()) b.Merge(g->cached_bounds());
  }
  for (const auto& c : children_) b.Merge(c->UpdateBounds());
  bounds_ = b;
  return bounds_;
}

void NodeImpl::ForEachBody(const std::function<void(BodyImpl&)>& f) const {
  for (const auto& b : bodies_) f(*b);
  for (const auto& c : children_) c->ForEachBody(f);
}

void NodeImpl::ForEachGeom(const std::function<void(GeomImpl&)>& f) const {
  for (const auto& g : geoms_) f(*g);
  for (const auto& c : children_) c->ForEachGeom(f);
}

// ---------------------------------------------------------------------------------------------
// SceneGraph

SceneGraph::SceneGraph(dWorldID world)
    : world_(world), root_(std::make_unique<NodeImpl>(*this, nullptr, "")) {}

SceneGraph::~SceneGraph() = default;

NodeImpl* SceneGraph::Find(std::string_view path) const {
  NodeImpl* node = root_.get();
  while (node && !path.empty()) {
    const auto slash = path.find('/');
    node = node->FindChildNode(path.substr(0, slash));
    path = slash == std::string_view::npos ? std::string_view{} : path.substr(slash + 1);
  }
  return node;
}

void SceneGraph::SetGeomListener(std::function<void(GeomImpl&)> on_added,
                                 std::function<void(GeomImpl&)> on_removed) {
  on_geom_added_ = std::move(on_added);
  on_geom_removed_ = std::move(on_removed);
}

}  // namespace ubersim::kernel
