// SPDX-License-Identifier: Apache-2.0
#pragma once

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
  /// Directional friction: `tyre.mu` acts along the axle and `tyre.mu2` across it (an omni
  /// wheel's free rollers); unset: the same grip every way.
  bool rollers_along_axle = false;
  double holding_torque = 0.5;         ///< N·m the motor holds the wheel still with until commanded
  /// kg·m² the motor's rotor and gears add about the axle (rotor inertia × gear ratio²).
  double rotor_inertia = 0.0;
};

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
  if (spec.rollers_along_axle) tyre.friction_axis = Vec3::UnitZ();  // the cylinder's axis is the axle
  node.AddGeom(tyre, &wheel);
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

}  // namespace v1
}  // namespace ubersim
