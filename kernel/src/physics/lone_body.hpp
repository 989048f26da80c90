// SPDX-License-Identifier: Apache-2.0
// QuickStep's step of a body no joint touches, done by the kernel, bit for bit as ODE does it.
#pragma once

#include <vector>

#include <ode/ode.h>

namespace ubersim::kernel {

/// Whether QuickStep would step `body` on its own, as a one-body island without constraints, and
/// LoneBodyStepper reproduces that step exactly: enabled, no joint attached (contacts included),
/// dynamic, and none of the options LoneBodyStepper leaves to ODE (finite rotation, damping, a
/// cap on the angular speed). The kernel sets no moved-callback on its bodies, which ODE cannot
/// be asked about.
bool IsLoneBody(dBodyID body);

/// Whether `body` is enabled, dynamic and asks for none of the options the kernel's steppers
/// leave to ODE (finite rotation, damping, a cap on the angular speed); its joints aside.
bool StepsAsQuickStepsAFreeBody(dBodyID body);

/// A body's mass as QuickStep reads it: the mass parameters, the body-frame inverse inertia and
/// the inverse mass dBodySetMass stored.
struct BodyMass {
  const dMass* mass = nullptr;              ///< mass, centre, inertia (body frame)
  const dReal* inverse_inertia = nullptr;   ///< the inverse of mass->I, a 3×4 ODE matrix
  dReal inverse_mass = 0;                   ///< 1/kg
};

/// BodyMass per body. ODE keeps all three in the body, right before its position (every ODE
/// since 0.11 lays out dxBody as mass, invI, invMass, posr): read there, after checking once per
/// body that what lies there is what dBodyGetMass and dBodySetMass's inverse give, bit for bit.
/// Where it is not (another layout), the inverse is computed and cached as dBodySetMass does.
class InverseInertiaCache {
 public:
  /// `body`'s mass, inverse inertia and inverse mass, as dBodySetMass stored them.
  BodyMass Of(dBodyID body);
  /// Of(body) for a body whose position array (dBodyGetPosition's) is `position`.
  BodyMass Of(dBodyID body, const dReal* position) {
    // The step before's order, in ODE's storage: most lookups end here.
    if (next_ < entries_.size() && entries_[next_].body == body && entries_[next_].in_place) {
      ++next_;
      return StoredAt(position);
    }
    return Of(body);
  }

 private:
  /// Where ODE keeps the mass, inverse inertia and inverse mass of the body whose position array
  /// is `position`, if its dxBody is laid out as mass, invI, invMass, then the position.
  static BodyMass StoredAt(const dReal* position) {
    const dReal* inverse_mass = position - 1;
    const dReal* inverse = inverse_mass - 12;
    return {reinterpret_cast<const dMass*>(inverse - sizeof(dMass) / sizeof(dReal)), inverse, *inverse_mass};
  }

  struct Entry {
    dBodyID body;
    bool in_place;      // ODE's own storage checked: read there
    dMass mass;         // else: a copy, and the inverse of its inertia
    dMatrix3 inertia;
    dMatrix3 inverse;
  };
  // A step asks for the same bodies in the same order as the step before: the entry after the
  // last one found is looked at first.
  std::vector<Entry> entries_;
  std::size_t next_ = 0;
};

/// QuickStep's implicit gyroscopic torque (Lacoursière 2006) of a body of `mass` turned by
/// `rotation` and turning at `angular`, added to `torque`, floating-point operation for operation.
void AddImplicitGyroscopicTorque(const dMass& mass, const dReal* rotation, const dReal* angular, dReal dt,
                                 dReal* torque);

/// A body's velocity and accumulator arrays in ODE's own storage (the pointers dBodyGetLinearVel,
/// dBodyGetAngularVel, dBodyGetForce and dBodyGetTorque return): written in place, as the
/// setters would, without a call each.
struct BodyArrays {
  dReal* linear = nullptr;   ///< linear velocity, m/s
  dReal* angular = nullptr;  ///< angular velocity, rad/s
  dReal* force = nullptr;    ///< accumulated force, N
  dReal* torque = nullptr;   ///< accumulated torque, N·m
  /// `body`'s.
  static BodyArrays Of(dBodyID body) {
    return {const_cast<dReal*>(dBodyGetLinearVel(body)), const_cast<dReal*>(dBodyGetAngularVel(body)),
            const_cast<dReal*>(dBodyGetForce(body)), const_cast<dReal*>(dBodyGetTorque(body))};
  }
};

/// The end of QuickStep's step of one body: `linear` and `angular` (its velocities so far) take
/// `force` and `torque` over `dt` (torque through `inverse_inertia`, world frame), become the
/// body's velocities (written to `arrays`, the body's), the pose follows, the geometries are
/// told it moved, and the accumulators are cleared. `torque` is scaled by dt in place, as
/// QuickStep does.
void FinishBodyStep(dBodyID body, const BodyArrays& arrays, dReal inverse_mass, const dReal* inverse_inertia,
                    const dReal* force, dReal* torque, dReal* linear, dReal* angular, dReal dt);

/// Steps lone bodies (IsLoneBody) the way ODE 0.16's QuickStep steps a one-body island without
/// constraints, floating-point operation for floating-point operation: gravity, the implicit
/// gyroscopic torque, the velocity update, the position and quaternion update, the geometries
/// told that the body moved, the force and torque accumulators cleared. What it saves is ODE's
/// machinery around each island (its island search, memory arenas and job scheduling): a third
/// of a step of 22 one-body robots. tests/unit/physics/lone_body_test.cpp compares it with QuickStep.
class LoneBodyStepper {
 public:
  /// One step of `body` by `dt` seconds under `gravity` (the world's, m/s²).
  void Step(dBodyID body, const dReal* gravity, dReal dt);
  /// Step's work for a body in any pose; Step takes a shorter way to the same bits for a body
  /// standing level and turning about a vertical principal axis (a one-body robot driving).
  void StepAnyPose(dBodyID body, const dReal* gravity, dReal dt);
  /// How many of Step's steps took the level body's way.
  std::size_t LevelSteps() const { return level_steps_; }

 private:
  // The level body's step (see StepAnyPose); false, and nothing done, for any other.
  bool StepLevel(dBodyID body, const dReal* gravity, dReal dt);

  InverseInertiaCache inverse_inertia_;
  std::size_t level_steps_ = 0;
};

}  // namespace ubersim::kernel
