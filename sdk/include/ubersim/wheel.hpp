// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "ubersim/component.hpp"
#include "ubersim/scene.hpp"

namespace ubersim {
inline namespace v1 {

/// A driven wheel: where it sits on the robot, its size and its tyre.
struct WheelSpec {
  std::string node_name;               ///< child node of the robot's node, e.g. "wheel0"
  Vec3 centre = Vec3::Zero();          ///< wheel centre in the chassis frame, m
  Vec3 axle = Vec3::UnitY();           ///< axle direction, chassis frame; a positive motor rate turns the wheel counter-clockwise about it
  double radius = 0.03;                ///< m
  double width = 0.01;                 ///< along the axle, m
  double mass = 0.05;                  ///< kg
  SurfaceMaterial tyre;                ///< the tyre's surface (on the carpet and everything else)
  /// Directional friction: `tyre.mu` acts along the rollers' free direction and `tyre.mu2`
  /// across it, the grip; unset: the same grip every way.
  bool rollers_along_axle = false;
  /// With rollers: the angle of the free direction from the axle, rad, counter-clockwise seen
  /// from above the carpet (0: an omni wheel, free along the axle; ±π/4: a mecanum wheel, whose
  /// rollers sit at 45° to the axle).
  double roller_turn = 0.0;
  double holding_torque = 0.5;         ///< N·m the motor holds the wheel still with until commanded
  /// kg·m² the motor's rotor and gears add about the axle (rotor inertia × gear ratio²).
  double rotor_inertia = 0.0;
  /// The chassis' shell keeps everything but the carpet off the wheel (ShellShieldsWheel): it
  /// gets no tyre geometry, only its carpet contact (a third of a wheel robot's geometries).
  bool tyre_shielded = false;
};

/// Whether the chassis' shell — `body.radius` round, cut flat at `body.front_distance`, from
/// `body.ground_clearance` up — covers a wheel of `spec` from the ball, the walls and other
/// robots. True when the wheel's axle is horizontal, its disc lies inside the shell's outline by
/// at least `margin` (m: more than a ball resting against the shell sinks into it, the world's
/// 0.5 mm contact layer), and the shell comes down lower than a resting ball's centre, so that a
/// ball touching the shell never reaches under it (other robots touch only the shell). A shot
/// sinks deeper for a step or two (6 mm at 6.5 m/s) before the shell pushes it out: a wheel
/// inside the shell is no surface a real ball meets, so a tyre there only added contacts.
inline bool ShellShieldsWheel(const RobotBodyInfo& body, double ball_radius, const WheelSpec& spec,
                              double margin = 0.001) {
  if (body.ground_clearance >= ball_radius) return false;
  const Vec3 axle = spec.axle.normalized();
  if (std::abs(axle.z()) > 1e-9) return false;
  const Vec3 along = Vec3::UnitZ().cross(axle);  // the disc's horizontal extent
  for (double s : {-1.0, 1.0}) {
    for (double t : {-1.0, 1.0}) {
      const Vec3 corner = spec.centre + along * (s * spec.radius) + axle * (t * 0.5 * spec.width);
      if (std::hypot(corner.x(), corner.y()) > body.radius - margin) return false;
      if (corner.x() > body.front_distance - margin) return false;
    }
  }
  return true;
}

/// Builds a wheel body on a motorised hinge to the chassis and returns the hinge (drive it with
/// SetMotor). The carpet touches the wheel at one point under its centre — a sphere of the
/// wheel's radius — as a real wheel does at its rim or roller; a flat-ended cylinder on a plane
/// would touch at both rims and the inner rim would set the track. Everything else (the ball,
/// walls, other robots) touches the cylinder. Contact scopes keep the two apart before any
/// contact is computed.
inline Joint& AddDrivenWheel(RobotContext& ctx, const WheelSpec& spec) {
  Body& chassis = ctx.Chassis();
  const Pose chassis_pose = chassis.GetPose();
  const Quat axle_in_chassis = Quat::FromTwoVectors(Vec3::UnitZ(), spec.axle.normalized());
  SceneNode& node = ctx.Node().AddChild(spec.node_name);
  BodySpec body;
  body.name = "wheel";
  body.mass = MassSpec::Solid(Shape::Cylinder(spec.radius, spec.width), spec.mass);
  // The motor spins with the wheel through its gears: its rotor adds inertia about the axle (the
  // cylinder's z) but no mass the carpet carries apart from the chassis's.
  body.mass.inertia_diagonal.z() += spec.rotor_inertia;
  body.pose = chassis_pose.Compose(Pose{spec.centre, axle_in_chassis});
  body.twist = chassis.GetTwist();
  Body& wheel = node.AddBody(body);

  GeomSpec tyre;
  tyre.name = "tyre";
  tyre.shape = Shape::Cylinder(spec.radius, spec.width);
  tyre.material = spec.tyre;
  tyre.scope = ContactScope::kNoPlanes;
  if (spec.rollers_along_axle) {
    tyre.friction_axis = Vec3::UnitZ();  // the cylinder's axis is the axle
    tyre.friction_axis_turn = spec.roller_turn;
  }
  if (!spec.tyre_shielded) node.AddGeom(tyre, &wheel);
  GeomSpec contact = tyre;
  contact.name = "carpet_contact";
  contact.shape = Shape::Sphere(spec.radius);
  contact.scope = ContactScope::kPlanesOnly;
  node.AddGeom(contact, &wheel);

  JointSpec hinge;
  hinge.name = "axle";
  hinge.kind = JointKind::kHinge;
  hinge.parent = &chassis;
  hinge.child = &wheel;
  hinge.anchor = body.pose.position;
  hinge.axis = body.pose.orientation * Vec3::UnitZ();
  Joint& joint = node.AddJoint(hinge);
  joint.SetMotor(0.0, spec.holding_torque);  // a powered-off robot still holds its wheels
  return joint;
}

/// A driven wheel without a body of its own (AddContactWheel): its carpet contact sits on the
/// chassis, and the wheel's turning is a surface velocity of that contact, so the carpet pushes
/// the chassis directly and a robot's step solves four contacts on one body instead of four light
/// bodies on hinges between the chassis and the carpet. Its spin (wheel and rotor inertia about
/// the axle) is stepped here: the motor reaches its rate within its torque and pushes the chassis
/// back by what it spends on the rotor.
class ContactWheel {
 public:
  /// How far a tyre gives under its static load, m: a rigid support of four would leave the load
  /// to the solver (a robot rocked onto two diagonal wheels and slipped on the other two); a
  /// tyre's spring spreads it as on a real robot, and turns and braking shift it.
  static constexpr double kTyreSink = 0.00005;

  /// Use AddContactWheel. `gravity` (m/s²) turns the static load into the mass the tyre carries.
  ContactWheel(Body& chassis, const WheelSpec& spec, double static_load, double gravity)
      : chassis_(&chassis),
        axle_(spec.axle.normalized()),
        rolling_(spec.axle.normalized().cross(Vec3::UnitZ())),
        contact_point_(spec.centre - Vec3::UnitZ() * spec.radius),
        grip_share_(std::abs(std::cos(spec.roller_turn))),
        free_share_(std::abs(std::sin(spec.roller_turn))),
        radius_(spec.radius),
        spin_inertia_(0.5 * spec.mass * spec.radius * spec.radius + spec.rotor_inertia),
        static_load_(static_load),
        // A tyre giving kTyreSink under its static load, critically damped for its share of the robot.
        stiffness_(static_load / kTyreSink),
        damping_(gravity > 0.0 ? 2.0 * std::sqrt(stiffness_ * static_load / gravity) : 0.0),
        max_torque_(spec.holding_torque) {}
  ContactWheel(const ContactWheel&) = delete;
  ContactWheel& operator=(const ContactWheel&) = delete;

  /// Drives the wheel toward `rate` (rad/s about its axle, relative to the chassis) with at most
  /// `max_torque` (N·m), as Joint::SetMotor does a hinge.
  void SetMotor(double rate, double max_torque) {
    target_ = rate;
    max_torque_ = max_torque;
  }
  /// The wheel's rate about its axle relative to the chassis, rad/s.
  double Rate() const { return rate_; }
  /// Sets the rate at once: a robot put down moving (Drive::Placed).
  void Roll(double rate) {
    rate_ = rate;
    target_ = rate;
    Aim(chassis_->GetPose().orientation);
  }
  /// The motor's step of `dt` s toward its rate; call once a step in PreStep, after SetMotor.
  /// Within its torque the motor holds the rate it is asked for, the carpet's pull on the rim
  /// included. Saturated, the wheel spins up by what is left of the motor's torque after the
  /// carpet's pull on a slipping rim (kinetic friction at the static load, along the rolling
  /// direction). The chassis takes the reaction of the wheel's change of spin.
  void Step(double dt) { Step(dt, chassis_->GetPose()); }
  /// Step(dt) with the chassis' pose as the step starts (`chassis_pose`): a drive stepping all
  /// its wheels reads the pose once.
  void Step(double dt, const Pose& chassis_pose) {
    dt_ = dt;
    const Pose& pose = chassis_pose;
    const double wanted = spin_inertia_ * (target_ - rate_) / dt;
    double torque = std::clamp(wanted, -max_torque_, max_torque_);
    if (torque != wanted && touched_) {
      const double ground = chassis_->PointVelocity(pose.position + Rotate(pose.orientation, contact_point_))
                                .dot(Rotate(pose.orientation, rolling_));
      const double slip = rate_ * radius_ - ground;  // the rim over the carpet
      const double pull = static_load_ * radius_ * (grip_mu_ * grip_share_ + free_mu_ * free_share_);
      if (std::abs(slip) > 1e-3) torque -= std::copysign(pull, slip);
      // The pull slows a slipping rim toward the carpet's speed, never past the rate asked for.
      if ((wanted > 0 && torque > wanted) || (wanted < 0 && torque < wanted)) torque = wanted;
    }
    touched_ = false;
    rate_ += torque * dt / spin_inertia_;
    if (torque != 0.0) chassis_->AddTorque(Rotate(pose.orientation, axle_) * -torque);
    Aim(pose.orientation);
  }
  /// The contact observer's part: the tyre's surface moves at the rim's speed (the contact takes
  /// the part along the rollers' free direction as their drag, the rest as the grip), and
  /// grips no harder than the motor can hold (its torque over the radius, against the wheel's
  /// static load). The torque the rotor takes is not counted against that hold: a wheel spinning
  /// up against the carpet would spin up more slowly, which only its encoder would show.
  void Touch(SurfaceMaterial& surface) {
    surface.surface_velocity = surface_velocity_;
    touched_ = true;
    free_mu_ = surface.mu;
    if (static_load_ > 0.0) {
      // ODE's contact as the tyre's spring and damper over the step: ERP = hk/(hk+d), CFM = 1/(hk+d).
      const double hk = dt_ * stiffness_;
      surface.soft_erp = hk / (hk + damping_);
      surface.soft_cfm = 1.0 / (hk + damping_);
      const double motor_mu = max_torque_ / (radius_ * static_load_);
      if (motor_mu < (surface.mu2 < 0 ? surface.mu : surface.mu2)) surface.mu2 = motor_mu;
    }
    grip_mu_ = surface.mu2 < 0 ? surface.mu : surface.mu2;
  }

 private:
  // The rim's velocity over the chassis, world frame, with the chassis turned by `orientation`.
  void Aim(const Quat& orientation) { surface_velocity_ = Rotate(orientation, rolling_) * (-rate_ * radius_); }

  Body* chassis_;
  Vec3 axle_;             // chassis frame
  Vec3 rolling_;          // chassis frame: where a positive rate rolls the wheel (axle × up)
  Vec3 contact_point_;    // chassis frame: under the wheel's centre
  double grip_share_;     // |cos| of the rollers' angle: how much of a slip along the rolling
  double free_share_;     // direction the grip and the rollers' drag take (|sin|)
  double radius_;
  double spin_inertia_;   // kg·m² about the axle: the wheel's own and the rotor's
  double static_load_;    // N the wheel carries standing
  double stiffness_;      // N/m: the tyre's
  double damping_;        // N·s/m
  double dt_ = 0.001;     // s, the step being run
  bool touched_ = false;  // the carpet touched the wheel in the last step
  double grip_mu_ = 0.0;  // the last contact's friction across the rollers ...
  double free_mu_ = 0.0;  // ... and along them
  double target_ = 0.0;
  double rate_ = 0.0;
  double max_torque_;
  Vec3 surface_velocity_ = Vec3::Zero();
};

/// Builds a wheel without a body (ContactWheel): its mass joins the chassis at its place
/// (Body::AddFixedMass), a sphere of its radius on the chassis touches the carpet under its centre
/// with the tyre's directional friction, and the tyre's cylinder, unless shielded, meets everything
/// else. `static_load` (N) is what the wheel carries standing (the robot's weight over its wheels),
/// against which a motor weaker than the tyre's grip limits the grip. Keep the result alive as
/// long as the robot: its contact observer refers to it.
inline std::unique_ptr<ContactWheel> AddContactWheel(RobotContext& ctx, const WheelSpec& spec, double static_load) {
  Body& chassis = ctx.Chassis();
  const Quat axle_in_chassis = Quat::FromTwoVectors(Vec3::UnitZ(), spec.axle.normalized());
  chassis.AddFixedMass(MassSpec::Solid(Shape::Cylinder(spec.radius, spec.width), spec.mass),
                       Pose{spec.centre, axle_in_chassis});
  auto wheel = std::make_unique<ContactWheel>(chassis, spec, static_load, ctx.Gravity().norm());
  SceneNode& node = ctx.Node().AddChild(spec.node_name);
  GeomSpec contact;
  contact.name = "carpet_contact";
  contact.shape = Shape::Sphere(spec.radius);
  contact.offset = Pose{spec.centre, Quat::Identity()};
  contact.material = spec.tyre;
  contact.scope = ContactScope::kPlanesOnly;
  // Friction along the axle (the rollers' free direction, turned by their angle) and across it
  // (the grip), in the chassis frame; a plain tyre grips the same both ways, but its axes still
  // turn with the wheel, so the solver's friction pyramid does not depend on the heading.
  contact.friction_axis = spec.axle.normalized();
  if (spec.rollers_along_axle) {
    contact.friction_axis_turn = spec.roller_turn;
  } else {
    contact.material.mu2 = contact.material.mu;
  }
  Geom& sphere = node.AddGeom(contact, &chassis);
  ContactWheel* self = wheel.get();
  ctx.ObserveContacts(sphere, [self](const Contact&, SurfaceMaterial& surface, bool&) { self->Touch(surface); });
  if (!spec.tyre_shielded) {
    GeomSpec tyre = contact;
    tyre.name = "tyre";
    tyre.shape = Shape::Cylinder(spec.radius, spec.width);
    tyre.offset = Pose{spec.centre, axle_in_chassis};
    tyre.scope = ContactScope::kNoPlanes;
    node.AddGeom(tyre, &chassis);  // a tyre touching a ball or a wall does not turn: no observer
  }
  return wheel;
}

/// Spins a wheel body at `rate` (rad/s, about its axle as the hinge measures it) relative to the
/// chassis, keeping its centre's velocity: what a drive's Placed does to roll its wheels with the
/// robot's new motion. `axle` is the wheel's axle in the chassis frame (WheelSpec::axle).
inline void RollWheel(Body& wheel, const Body& chassis, const Vec3& axle, double rate) {
  const Twist c = chassis.GetTwist();
  Twist t = wheel.GetTwist();
  t.angular = c.angular + chassis.GetPose().orientation * axle.normalized() * rate;
  wheel.SetTwist(t);
}

/// A drive's wheel as its model asks: a body on a motorised hinge (AddDrivenWheel) or a motorised
/// contact on the chassis (AddContactWheel), behind one interface.
class DrivenWheel {
 public:
  /// Builds the wheel: a body on a hinge when `as_body`, else a contact wheel carrying
  /// `static_load` (N) standing.
  DrivenWheel(RobotContext& ctx, const WheelSpec& spec, bool as_body, double static_load)
      : chassis_(&ctx.Chassis()), axle_(spec.axle) {
    if (as_body) {
      hinge_ = &AddDrivenWheel(ctx, spec);
      body_ = ctx.Node().FindChild(spec.node_name)->FindBody("wheel");
    } else {
      contact_ = AddContactWheel(ctx, spec, static_load);
    }
  }
  /// Drives the wheel toward `rate` (rad/s, relative to the chassis) with at most `max_torque` N·m.
  void SetMotor(double rate, double max_torque) {
    if (contact_) {
      contact_->SetMotor(rate, max_torque);
    } else {
      hinge_->SetMotor(rate, max_torque);
    }
  }
  /// The wheel's rate about its axle relative to the chassis, rad/s.
  double Rate() const { return contact_ ? contact_->Rate() : hinge_->Rate(); }
  /// Steps a contact wheel's motor (a body's is ODE's): call once a step in PreStep, after SetMotor.
  void Step(double dt) {
    if (contact_) contact_->Step(dt);
  }
  /// Step(dt) with the chassis' pose as the step starts, read once for all of a robot's wheels.
  void Step(double dt, const Pose& chassis_pose) {
    if (contact_) contact_->Step(dt, chassis_pose);
  }
  /// Spins the wheel at `rate` at once, rolling with the chassis: a robot put down moving.
  void Roll(double rate) {
    if (contact_) {
      contact_->Roll(rate);
    } else {
      RollWheel(*body_, *chassis_, axle_, rate);
    }
  }
  /// The wheel's body, or nullptr for a contact wheel.
  Body* WheelBody() const { return body_; }

 private:
  Body* chassis_;
  Vec3 axle_;
  Joint* hinge_ = nullptr;
  Body* body_ = nullptr;
  std::unique_ptr<ContactWheel> contact_;
};

}  // namespace v1
}  // namespace ubersim
