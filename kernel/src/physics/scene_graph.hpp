// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ubersim/component.hpp"
#include "ubersim/scene.hpp"
#include "physics/ode_handles.hpp"
#include "collision/upright_prism.hpp"

// The scene graph (SG): a tree of nodes that own ODE bodies, geometries and joints. Every module
// but the collision manager reads or changes the world through it.
namespace ubersim::kernel {

class NodeImpl;
class SceneGraph;

/// A rigid body owned by a node.
class BodyImpl final : public Body {
 public:
  /// `serial` orders bodies by creation (SceneGraph::NextBodySerial).
  BodyImpl(dWorldID world, const BodySpec& spec, std::uint64_t& non_finite_sums, std::uint64_t serial);
  const std::string& Name() const override { return name_; }
  Pose GetPose() const override;
  void SetPose(const Pose& pose) override;
  Twist GetTwist() const override;
  void SetTwist(const Twist& twist) override;
  Vec3 PointVelocity(const Vec3& world_point) const override;
  void AddForce(const Vec3& force) override;
  void AddForceAtPoint(const Vec3& force, const Vec3& world_point) override;
  void AddTorque(const Vec3& torque) override;
  void ApplyImpulse(const Vec3& impulse) override;
  double Mass() const override { return mass_; }
  void AddFixedMass(const MassSpec& part, const Pose& at) override;
  void Wake() override { dBodyEnable(body_.get()); }

  /// The ODE body.
  dBodyID id() const { return body_.get(); }
  /// ODE's own position, linear and angular velocity arrays for the body (what dBodyGetPosition,
  /// dBodyGetLinearVel and dBodyGetAngularVel return), fixed for its life.
  const dReal* position_array() const { return position_; }
  const dReal* linear_array() const { return linear_; }    ///< see position_array
  const dReal* angular_array() const { return angular_; }  ///< see position_array
  /// How many calls, on any body of its scene graph, have left a linear velocity, force or torque
  /// that is not finite (or may not be: see CountIfNonFinite). Adding to those is the only SDK
  /// write whose result can be non-finite with finite arguments (an overflowing sum); each such
  /// call checks its own sum. One counter for the graph, so a check reads one number.
  const std::uint64_t& non_finite_sums() const { return *non_finite_sums_; }
  /// Larger for a body created later. ODE lists a world's bodies newest first, and QuickStep
  /// steps them in that order (IslandStepper::Step).
  std::uint64_t serial() const { return serial_; }

 private:
  std::string name_;
  double mass_;
  OdeBody body_;
  // Counts `sum` (a velocity, force or torque of this body, 3 values) if it is not finite.
  void CountIfNonFinite(const dReal* sum);

  std::uint64_t* non_finite_sums_;  // the scene graph's
  std::uint64_t serial_;
  // ODE's own arrays for the body (what its getters return, fixed for its life): a pose or a
  // twist read is a copy, not two calls into ODE.
  const dReal* position_;
  const dReal* quaternion_;
  const dReal* linear_;
  const dReal* angular_;
  dReal* force_;   // the accumulated force and torque (added to in place, as ODE's adders do)
  dReal* torque_;
};

/// A geometry owned by a node, with its surface, optional directional friction and observers.
class GeomImpl final : public Geom {
 public:
  GeomImpl(NodeImpl& owner, const GeomSpec& spec, BodyImpl* body);
  const std::string& Name() const override { return name_; }
  Body* AttachedBody() const override { return body_; }
  SceneNode& Owner() const override;
  const Shape& GetShape() const override { return shape_; }
  const SurfaceMaterial& Material() const override { return material_; }
  void SetMaterial(const SurfaceMaterial& material) override {
    material_ = material;
    ++material_version_;
  }
  /// Counts SetMaterial calls (the collision manager's surface cache checks it).
  std::uint64_t material_version() const { return material_version_; }
  Pose GetPose() const override;
  void SetCollides(bool collides) override { collides_ = collides; }

  dGeomID id() const { return geom_.get(); }                   ///< the ODE geometry
  BodyImpl* body() const { return body_; }                     ///< attached body or null
  NodeImpl& owner() const { return owner_; }                   ///< owning node
  bool collides() const { return collides_; }                  ///< takes part in collisions
  ContactScope scope() const { return scope_; }                ///< what it may touch
  /// Orders geometries by creation (SceneGraph::NextGeomSerial).
  std::uint64_t serial() const { return serial_; }
  bool is_plane() const { return shape_.kind == Shape::Kind::kPlane; }  ///< an infinite plane
  /// Directional-friction axis in the body frame, if any.
  const std::optional<Vec3>& friction_axis() const { return friction_axis_; }
  /// The friction axis's turn about the contact normal, rad (GeomSpec::friction_axis_turn).
  double friction_axis_turn() const { return friction_axis_turn_; }
  /// World bounding sphere now (infinite for planes).
  BoundingSphere WorldBounds() const;
  /// The bounding sphere as of the last SceneGraph::UpdateBounds().
  const BoundingSphere& cached_bounds() const { return cached_bounds_; }
  /// Refreshes cached_bounds() (called by NodeImpl::UpdateBounds).
  void RefreshBounds() { cached_bounds_ = WorldBounds(); }
  /// Adds a contact observer.
  void AddObserver(ContactHandler handler) { observers_.push_back(std::move(handler)); }
  /// Removes every contact observer.
  void ClearObservers() { observers_.clear(); }
  /// Contact observers, in the order added.
  const std::vector<ContactHandler>& observers() const { return observers_; }
  /// Marks a robot shell (a triangle mesh) as this upright-standing prism, so two shells meet in
  /// CollideUprightPrisms rather than ODE's mesh-against-mesh test.
  void set_prism(const FlatFrontPrism& prism) { prism_ = prism; }
  /// The prism this shell is, if marked.
  const std::optional<FlatFrontPrism>& prism() const { return prism_; }
  /// The robot (its node, see NodeImpl::set_robot) this geometry belongs to, or null.
  const NodeImpl* robot() const { return robot_; }
  /// Marks the geometry as part of its robot's hull: two robots meet through their hulls only.
  void set_hull(bool hull) { hull_ = hull; }
  /// Part of its robot's hull.
  bool hull() const { return hull_; }
  /// Marks the geometry as the ball (contacts report other_is_ball).
  void set_is_ball(bool b) { is_ball_ = b; }
  bool is_ball() const { return is_ball_; }  ///< this is the ball

 private:
  dGeomID CreateConvex(const Shape& s);
  NodeImpl& owner_;
  std::string name_;
  Shape shape_;
  SurfaceMaterial material_;
  std::uint64_t material_version_ = 0;
  std::optional<Vec3> friction_axis_;
  double friction_axis_turn_ = 0.0;
  std::optional<FlatFrontPrism> prism_;
  const NodeImpl* robot_ = nullptr;
  bool hull_ = false;
  BodyImpl* body_;
  bool collides_;
  ContactScope scope_;
  std::uint64_t serial_ = 0;
  bool is_ball_ = false;
  double bounding_radius_;
  BoundingSphere cached_bounds_;
  std::vector<ContactHandler> observers_;
  std::vector<dReal> mesh_vertices_;     // trimesh vertices, or a convex's points (ODE keeps
  std::vector<dTriIndex> mesh_indices_;  // pointers to these, it does not copy them)
  std::vector<dReal> convex_planes_;
  std::vector<unsigned> convex_polygons_;
  OdeTriMeshData mesh_data_;
  OdeGeom geom_;
};

/// A joint owned by a node; hinge and slider motors use ODE's built-in joint motor.
class JointImpl final : public Joint {
 public:
  JointImpl(dWorldID world, const JointSpec& spec);
  const std::string& Name() const override { return name_; }
  JointKind Kind() const override { return kind_; }
  void SetMotor(double velocity, double max_effort) override;
  double Position() const override;
  double Rate() const override;
  Vec3 Axis() const override;
  Vec3 LastTorque() const override;

  dJointID id() const { return joint_.get(); }  ///< the ODE joint

 private:
  std::string name_;
  JointKind kind_;
  bool measure_torque_;
  dJointFeedback feedback_{};
  OdeJoint joint_;
};

/// A node of the tree. Owns its children, bodies, geometries and joints.
class NodeImpl final : public SceneNode {
 public:
  NodeImpl(SceneGraph& graph, NodeImpl* parent, std::string name);
  ~NodeImpl() override;

  const std::string& Name() const override { return name_; }
  std::string Path() const override;
  SceneNode* Parent() const override { return parent_; }
  SceneNode& AddChild(std::string_view name) override;
  SceneNode* FindChild(std::string_view name) const override;
  Body& AddBody(const BodySpec& spec) override;
  Geom& AddGeom(const GeomSpec& spec, Body* body) override;
  Joint& AddJoint(const JointSpec& spec) override;
  Body* FindBody(std::string_view name) const override;
  Geom* FindGeom(std::string_view name) const override;
  Joint* FindJoint(std::string_view name) const override;
  BoundingSphere Bounds() const override { return bounds_; }

  /// Child nodes in insertion order.
  const std::vector<std::unique_ptr<NodeImpl>>& children() const { return children_; }
  /// Own geometries in insertion order.
  const std::vector<std::unique_ptr<GeomImpl>>& geoms() const { return geoms_; }
  /// Own bodies in insertion order.
  const std::vector<std::unique_ptr<BodyImpl>>& bodies() const { return bodies_; }
  /// Own joints in insertion order.
  const std::vector<std::unique_ptr<JointImpl>>& joints() const { return joints_; }
  /// Typed child lookup.
  NodeImpl* FindChildNode(std::string_view name) const;
  /// Destroys `child` and its subtree (a robot leaving the world); nothing when it is not a
  /// child of this node. The collision manager must be told (CollisionManager::GeometriesRemoved).
  void RemoveChild(const NodeImpl& child);
  /// A new child before every other (the field, rebuilt while the world runs, keeps its place).
  NodeImpl& AddChildFirst(std::string_view name);
  /// Typed parent.
  NodeImpl* parent() const { return parent_; }
  /// Marks this node as one robot's root: geometries added to its subtree afterwards belong to it.
  void set_robot() { is_robot_ = true; }
  /// This node is a robot's root.
  bool is_robot() const { return is_robot_; }
  /// Graph this node belongs to.
  SceneGraph& graph() const { return graph_; }
  /// Recomputes this subtree's bounding spheres (children first); returns this node's.
  const BoundingSphere& UpdateBounds();
  /// Calls f on every body of the subtree, depth first, in insertion order.
  void ForEachBody(const std::function<void(BodyImpl&)>& f) const;
  /// Calls f on every geometry of the subtree, depth first, in insertion order.
  void ForEachGeom(const std::function<void(GeomImpl&)>& f) const;

 private:
  SceneGraph& graph_;
  NodeImpl* parent_;
  std::string name_;
  BoundingSphere bounds_;
  bool is_robot_ = false;
  // Declaration order = reverse destruction order: joints go first, then geoms, bodies, children.
  std::vector<std::unique_ptr<NodeImpl>> children_;
  std::vector<std::unique_ptr<BodyImpl>> bodies_;
  std::vector<std::unique_ptr<GeomImpl>> geoms_;
  std::vector<std::unique_ptr<JointImpl>> joints_;
};

/// The tree, rooted at an unnamed node, over one ODE world.
class SceneGraph {
 public:
  explicit SceneGraph(dWorldID world);
  ~SceneGraph();
  SceneGraph(const SceneGraph&) = delete;
  SceneGraph& operator=(const SceneGraph&) = delete;

  /// The root node (path "").
  NodeImpl& Root() { return *root_; }
  /// The root node (path "").
  const NodeImpl& Root() const { return *root_; }
  /// The node at a slash-separated path, or nullptr.
  NodeImpl* Find(std::string_view path) const;
  /// Recomputes every bounding sphere.
  void UpdateBounds() { root_->UpdateBounds(); }
  /// The ODE world the bodies live in.
  dWorldID world() const { return world_; }
  /// Called for each geometry as it is created (the collision manager files it).
  void SetGeomListener(std::function<void(GeomImpl&)> on_added,
                       std::function<void(GeomImpl&)> on_removed);
  /// Listener hooks (used by GeomImpl).
  void NotifyGeomAdded(GeomImpl& g) { if (on_geom_added_) on_geom_added_(g); }
  void NotifyGeomRemoved(GeomImpl& g) { if (on_geom_removed_) on_geom_removed_(g); }
  /// The counter every body of the graph counts its non-finite sums on (BodyImpl::non_finite_sums).
  std::uint64_t& non_finite_sums() { return non_finite_sums_; }
  /// A new body's serial (BodyImpl::serial): one more than the last.
  std::uint64_t NextBodySerial() { return ++bodies_created_; }
  /// Bodies created so far. A body lives as long as the graph: the same count, the same bodies.
  std::uint64_t bodies_created() const { return bodies_created_; }
  /// A new geometry's serial (GeomImpl::serial): one more than the last.
  std::uint64_t NextGeomSerial() { return ++geoms_created_; }

 private:
  dWorldID world_;
  std::uint64_t non_finite_sums_ = 0;
  std::uint64_t bodies_created_ = 0;
  std::uint64_t geoms_created_ = 0;
  std::function<void(GeomImpl&)> on_geom_added_;
  std::function<void(GeomImpl&)> on_geom_removed_;
  std::unique_ptr<NodeImpl> root_;
};

/// Converts between Eigen and ODE representations.
inline Vec3 ToVec3(const dReal* v) { return Vec3(v[0], v[1], v[2]); }
/// An ODE quaternion (w, x, y, z) as Eigen's.
inline Quat ToQuat(const dReal* q) { return Quat(q[0], q[1], q[2], q[3]); }

}  // namespace ubersim::kernel
