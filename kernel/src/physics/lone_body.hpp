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
/// IsLoneBody for a body known to be enabled (one call into ODE fewer).
bool IsLoneEnabledBody(dBodyID body);

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

/// All of a body's arrays in ODE's storage: its pose's (dBodyGetPosition's, dBodyGetQuaternion's,
/// dBodyGetRotation's) and BodyArrays. They lie inside the body, so they are the same for its
/// whole life, and for any body ODE later puts at the same address.
struct BodyStorage {
  dReal* position = nullptr;    ///< m
  dReal* quaternion = nullptr;  ///< w, x, y, z
  dReal* rotation = nullptr;    ///< ODE's 3×4
  BodyArrays arrays;            ///< velocities and accumulators
  /// `body`'s, from its getters.
  static BodyStorage Of(dBodyID body) {
    return {const_cast<dReal*>(dBodyGetPosition(body)), const_cast<dReal*>(dBodyGetQuaternion(body)),
            const_cast<dReal*>(dBodyGetRotation(body)), BodyArrays::Of(body)};
  }
};

/// BodyMass per body. ODE keeps all three in the body, right before its position (every ODE
/// since 0.11 lays out dxBody as mass, invI, invMass, posr): read there, after checking once per
/// body that what lies there is what dBodyGetMass and dBodySetMass's inverse give, bit for bit.
/// Where it is not (another layout), the inverse is computed and cached as dBodySetMass does.
/// Each entry keeps the body's BodyStorage too, asked for once: a step's getter calls were a
/// tenth of a level one-body robot's step.
class InverseInertiaCache {
 public:
  /// `body`'s mass, inverse inertia and inverse mass, as dBodySetMass stored them.
  BodyMass Of(dBodyID body) { return MassOf(Find(body)); }
  /// The same, and `body`'s arrays into `storage`, with one lookup.
  BodyMass Of(dBodyID body, BodyStorage& storage) {
    Entry& e = Find(body);
    storage = e.storage;
    return MassOf(e);
  }

 private:
  struct Entry {
    dBodyID body;
    BodyStorage storage;  // the body's arrays
    bool in_place;        // ODE's own storage checked: read there
    dMass mass;           // else: a copy, and the inverse of its inertia
    dMatrix3 inertia;
    dMatrix3 inverse;
  };
  // The entry of `body`, made at first sight.
  Entry& Find(dBodyID body) {
    // The step before's order: most lookups end at the first look.
    if (next_ < entries_.size() && entries_[next_].body == body) return entries_[next_++];
    return FindElsewhere(body);
  }
  Entry& FindElsewhere(dBodyID body);
  BodyMass MassOf(Entry& e);

  /// Where ODE keeps the mass, inverse inertia and inverse mass of the body whose position array
  /// is `position`, if its dxBody is laid out as mass, invI, invMass, then the position.
  static BodyMass StoredAt(const dReal* position) {
    const dReal* inverse_mass = position - 1;
    const dReal* inverse = inverse_mass - 12;
    return {reinterpret_cast<const dMass*>(inverse - sizeof(dMass) / sizeof(dReal)), inverse, *inverse_mass};
  }

  // A step asks for the same bodies in the same order as the step before: the entry after the
  // last one found is looked at first.
  std::vector<Entry> entries_;
  std::size_t next_ = 0;
};

/// QuickStep's implicit gyroscopic torque (Lacoursière 2006) of a body of `mass` turned by
/// `rotation` and turning at `angular`, added to `torque`, floating-point operation for operation.
void AddImplicitGyroscopicTorque(const dMass& mass, const dReal* rotation, const dReal* angular, dReal dt,
                                 dReal* torque);

/// The end of QuickStep's step of one body: `linear` and `angular` (its velocities so far) take
/// `force` and `torque` over `dt` (torque through `inverse_inertia`, world frame), become the
/// body's velocities (written to `storage`, the body's), the pose follows, the geometries are
/// told it moved, and the accumulators are cleared. `torque` is scaled by dt in place, as
/// QuickStep does.
void FinishBodyStep(dBodyID body, const BodyStorage& storage, dReal inverse_mass, const dReal* inverse_inertia,
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
