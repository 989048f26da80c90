// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <memory>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ubersim/export.hpp"
#include "ubersim/math.hpp"

namespace ubersim {
inline namespace v1 {

class Body;
class SceneNode;

/// Collision shape of a geometry, in the geometry's own frame (cylinders and capsules along z).
struct Shape {
  /// Which primitive.
  enum class Kind { kSphere, kBox, kCylinder, kCapsule, kPlane, kConvex, kTriangleMesh };
  Kind kind = Kind::kSphere;       ///< primitive
  double radius = 0.0;             ///< sphere/cylinder/capsule radius, m
  double length = 0.0;             ///< cylinder/capsule length along z, m
  Vec3 size = Vec3::Zero();        ///< box edge lengths, m
  Vec3 plane_normal = Vec3::UnitZ();  ///< plane normal (world), for kPlane
  double plane_offset = 0.0;          ///< plane: normal·p = offset, m
  std::vector<Vec3> vertices;         ///< kConvex / kTriangleMesh vertices, m
  /// kTriangleMesh: 3 vertex indices per triangle. kConvex: the faces, each as its vertex count
  /// followed by its vertex indices, counter-clockwise seen from outside.
  std::vector<unsigned> indices;

  /// A sphere of radius r.
  static Shape Sphere(double r) { Shape s; s.kind = Kind::kSphere; s.radius = r; return s; }
  /// A box with edge lengths sx, sy, sz.
  static Shape Box(double sx, double sy, double sz) {
    Shape s; s.kind = Kind::kBox; s.size = Vec3(sx, sy, sz); return s;
  }
  /// A cylinder of radius r and length l along its z axis.
  static Shape Cylinder(double r, double l) {
    Shape s; s.kind = Kind::kCylinder; s.radius = r; s.length = l; return s;
  }
  /// A capsule of radius r and cylinder length l along its z axis.
  static Shape Capsule(double r, double l) {
    Shape s; s.kind = Kind::kCapsule; s.radius = r; s.length = l; return s;
  }
  /// The static half-space below normal·p = offset.
  static Shape Plane(const Vec3& normal, double offset) {
    Shape s; s.kind = Kind::kPlane; s.plane_normal = normal.normalized(); s.plane_offset = offset;
    return s;
  }
  /// A convex prism: `outline` (x, y of each corner, counter-clockwise seen from +z, convex)
  /// extruded from z = -length/2 to +length/2.
  UBERSIM_SDK_API static Shape Prism(const std::vector<Vec3>& outline, double length);
  /// Radius of the smallest sphere about the shape's origin that holds it, m (infinite for planes).
  UBERSIM_SDK_API double BoundingRadius() const;
};

/// Contact properties of one surface. A contact between two surfaces uses the material-pair
/// table of the world when it has the pair, else combines the two (see docs/model-files.md).
struct SurfaceMaterial {
  std::string name = "default";   ///< name used in the world's material-pair table
  double mu = 0.5;                ///< Coulomb friction (first direction when anisotropic)
  double mu2 = -1.0;              ///< friction along the second direction; < 0: same as mu
  double bounce = 0.0;            ///< restitution 0..1
  double bounce_velocity = 0.1;   ///< minimum incoming speed for a bounce, m/s
  double soft_erp = -1.0;         ///< contact ERP; < 0: world default
  double soft_cfm = -1.0;         ///< contact CFM; < 0: world default
  double rolling_friction = 0.0;  ///< rolling resistance coefficient (dContactRolling rho), m
  double slip = 0.0;              ///< force-dependent slip (both directions), s/kg
  /// Velocity of the observing geometry's surface over its own body at the contact point (a
  /// spinning roller fixed to its body, a conveyor), world frame, m/s. Set by a contact
  /// observer; the contact then drags the other side along it, up to the friction limit.
  Vec3 surface_velocity = Vec3::Zero();
};

/// Which geometries a geometry makes contacts with. Decided before any contact point is
/// computed, so it costs nothing, unlike dropping contacts in a contact observer afterwards.
enum class ContactScope : std::uint8_t {
  kAll,         ///< everything
  kPlanesOnly,  ///< only planes (the carpet): a wheel's ground contact, a support
  kNoPlanes,    ///< everything but planes: a tyre whose ground contact is a geometry of its own
};

/// What a geometry adds to the scene: shape, pose relative to its body (or the node, when
/// static), surface, and optional directional friction.
struct GeomSpec {
  std::string name;                    ///< unique within its node
  Shape shape;                         ///< collision shape
  Pose offset;                         ///< pose relative to the body (or world, when static)
  SurfaceMaterial material;            ///< surface properties
  /// When set, `material.mu` acts along this axis (body frame) projected onto the contact plane
  /// and `material.mu2` across it: an omni wheel's rollers (mu along the axle) in one line.
  std::optional<Vec3> friction_axis;
  bool collides = true;                ///< false: a sensor-like geometry that never makes contacts
  ContactScope scope = ContactScope::kAll;  ///< what it may touch
  /// With `friction_axis`: the axis, once projected onto the contact plane, is turned by this
  /// angle (rad, counter-clockwise about the contact normal pointing into this geometry) before
  /// `material.mu` acts along it. A wheel's rollers at an angle to its axle: the axle turns with
  /// the wheel's body, the free direction stays fixed to the chassis (mecanum: ±45°).
  double friction_axis_turn = 0.0;
};

/// Mass properties of a body.
struct MassSpec {
  double mass = 1.0;                   ///< kg
  Vec3 center_of_mass = Vec3::Zero();  ///< body frame, m
  /// Inertia tensor about the centre of mass, body frame, kg·m²; diagonal (Ixx, Iyy, Izz).
  Vec3 inertia_diagonal = Vec3::Ones() * 1e-3;
  Vec3 inertia_off_diagonal = Vec3::Zero();  ///< (Ixy, Ixz, Iyz), kg·m²

  /// Uniform solid of the given shape (sphere, box, cylinder, capsule).
  UBERSIM_SDK_API static MassSpec Solid(const Shape& shape, double mass);
  /// Thin spherical shell of radius r (a hollow ball).
  UBERSIM_SDK_API static MassSpec HollowSphere(double radius, double mass);
};

/// What a rigid body is when created.
struct BodySpec {
  std::string name;          ///< unique within its node
  MassSpec mass;             ///< mass properties
  Pose pose;                 ///< initial pose, world frame
  Twist twist;               ///< initial velocity, world frame
  bool gravity = true;       ///< false: gravity does not act on it
};

/// A rigid body in the scene (kernel-owned; the reference stays valid while its node lives).
class UBERSIM_SDK_API Body {
 public:
  virtual ~Body();
  /// Name given at creation.
  virtual const std::string& Name() const = 0;
  /// Pose of the body frame, world.
  virtual Pose GetPose() const = 0;
  /// Moves the body (teleport); velocities are kept.
  virtual void SetPose(const Pose& pose) = 0;
  /// Velocity of the body origin and angular velocity, world.
  virtual Twist GetTwist() const = 0;
  /// Sets linear and angular velocity, world.
  virtual void SetTwist(const Twist& twist) = 0;
  /// Velocity of a point given in world coordinates, m/s.
  virtual Vec3 PointVelocity(const Vec3& world_point) const = 0;
  /// Adds a force (N, world) at the centre of mass for the next step.
  virtual void AddForce(const Vec3& force) = 0;
  /// Adds a force (N, world) at a world point for the next step.
  virtual void AddForceAtPoint(const Vec3& force, const Vec3& world_point) = 0;
  /// Adds a torque (N·m, world) for the next step.
  virtual void AddTorque(const Vec3& torque) = 0;
  /// Changes velocity at once by impulse/mass (N·s, world), through the centre of mass.
  virtual void ApplyImpulse(const Vec3& impulse) = 0;
  /// Total mass, kg.
  virtual double Mass() const = 0;
  /// Adds a part fixed to the body — `part` about its own centre, its frame at `at` in the body
  /// frame — to the body's mass and inertia (parallel axes about the body origin). The origin
  /// stays the centre of mass: the part's first moment is left out, so add parts that balance
  /// about it (a robot's wheels) or that are light against the body.
  virtual void AddFixedMass(const MassSpec& part, const Pose& at) = 0;
  /// Wakes the body if ODE put it to sleep.
  virtual void Wake() = 0;
};

/// A geometry in the scene.
class UBERSIM_SDK_API Geom {
 public:
  virtual ~Geom();
  /// Name given at creation.
  virtual const std::string& Name() const = 0;
  /// The body it moves with, or nullptr for static geometry.
  virtual Body* AttachedBody() const = 0;
  /// The scene node that owns it.
  virtual SceneNode& Owner() const = 0;
  /// Its shape.
  virtual const Shape& GetShape() const = 0;
  /// Its surface.
  virtual const SurfaceMaterial& Material() const = 0;
  /// Replaces its surface.
  virtual void SetMaterial(const SurfaceMaterial& material) = 0;
  /// World pose of the geometry.
  virtual Pose GetPose() const = 0;
  /// Turns contact generation for this geometry on or off.
  virtual void SetCollides(bool collides) = 0;
};

/// Kinds of joint a plugin can create.
enum class JointKind { kHinge, kFixed, kSlider, kBall, kUniversal };

/// What a joint connects and how.
struct JointSpec {
  std::string name;              ///< unique within its node
  JointKind kind = JointKind::kHinge;
  Body* parent = nullptr;        ///< first body; nullptr means the world
  Body* child = nullptr;         ///< second body (required)
  Vec3 anchor = Vec3::Zero();    ///< anchor point, world frame, m
  Vec3 axis = Vec3::UnitZ();     ///< hinge/slider axis, world frame
  Vec3 axis2 = Vec3::UnitY();    ///< universal joint second axis, world frame
  double lower_limit = -1e30;    ///< hinge rad / slider m; below -1e29 means none
  double upper_limit = 1e30;     ///< hinge rad / slider m; above 1e29 means none
  /// Record the joint's torque (force) every step for Joint::LastTorque. Off unless asked: the
  /// solver then does extra work for this joint each step.
  bool measure_torque = false;
};

/// A joint in the scene, with an optional velocity motor along its first axis.
class UBERSIM_SDK_API Joint {
 public:
  virtual ~Joint();
  /// Name given at creation.
  virtual const std::string& Name() const = 0;
  /// Its kind.
  virtual JointKind Kind() const = 0;
  /// Drives the first axis toward `velocity` (rad/s or m/s) with at most `max_effort` (N·m or N).
  virtual void SetMotor(double velocity, double max_effort) = 0;
  /// Hinge angle (rad) or slider position (m) of the first axis.
  virtual double Position() const = 0;
  /// Rate of the first axis, rad/s or m/s.
  virtual double Rate() const = 0;
  /// First axis, world frame.
  virtual Vec3 Axis() const = 0;
  /// Torque (or force) the joint applied to its child in the last step, world frame. Throws
  /// PluginError unless the joint was created with JointSpec::measure_torque.
  virtual Vec3 LastTorque() const = 0;
};

/// A node of the scene graph: owns bodies, geometries and joints, and child nodes. Its bounding
/// sphere holds its geometries and all its children's; nodes never collide with their own
/// ancestors or descendants.
class UBERSIM_SDK_API SceneNode {
 public:
  virtual ~SceneNode();
  /// Name, unique among its siblings.
  virtual const std::string& Name() const = 0;
  /// Slash-separated path from the root, e.g. "blue/3/dribbler".
  virtual std::string Path() const = 0;
  /// Parent node, nullptr for the root.
  virtual SceneNode* Parent() const = 0;
  /// Adds a child node; throws PluginError when the name is taken.
  virtual SceneNode& AddChild(std::string_view name) = 0;
  /// Finds a direct child by name.
  virtual SceneNode* FindChild(std::string_view name) const = 0;
  /// Adds a rigid body to this node.
  virtual Body& AddBody(const BodySpec& spec) = 0;
  /// Adds a geometry fixed to `body`, or a static one when body is nullptr.
  virtual Geom& AddGeom(const GeomSpec& spec, Body* body) = 0;
  /// Adds a joint between two bodies (parent may be nullptr: the world).
  virtual Joint& AddJoint(const JointSpec& spec) = 0;
  /// Finds a body of this node by name.
  virtual Body* FindBody(std::string_view name) const = 0;
  /// Finds a geometry of this node by name.
  virtual Geom* FindGeom(std::string_view name) const = 0;
  /// Finds a joint of this node by name.
  virtual Joint* FindJoint(std::string_view name) const = 0;
  /// Sphere around this node's geometries and all its children's (world, current).
  virtual BoundingSphere Bounds() const = 0;
};

}  // namespace v1
}  // namespace ubersim
