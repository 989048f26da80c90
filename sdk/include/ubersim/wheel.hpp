// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cmath>
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

/// Spins a wheel body at `rate` (rad/s, about its axle as the hinge measures it) relative to the
/// chassis, keeping its centre's velocity: what a drive's Placed does to roll its wheels with the
/// robot's new motion. `axle` is the wheel's axle in the chassis frame (WheelSpec::axle).
inline void RollWheel(Body& wheel, const Body& chassis, const Vec3& axle, double rate) {
  const Twist c = chassis.GetTwist();
  Twist t = wheel.GetTwist();
  t.angular = c.angular + chassis.GetPose().orientation * axle.normalized() * rate;
  wheel.SetTwist(t);
}

}  // namespace v1
}  // namespace ubersim
