// SPDX-License-Identifier: Apache-2.0
// The start of QuickStep's step of one body (its stage 0), shared by the kernel's steppers.
#pragma once

#include <ode/ode.h>

#include "physics/lone_body.hpp"

namespace ubersim::kernel {

/// A body's state as QuickStep's stage 0 leaves it: gravity in the force, the world-frame inverse
/// inertia, the velocities read.
struct FreeBodyStart {
  const dMass* mass = nullptr;      ///< the body's mass parameters (InverseInertiaCache::Of)
  dVector3 force{};                 ///< the accumulated force, gravity added, N
  dVector3 torque{};                ///< the accumulated torque, N·m
  dVector3 linear{};                ///< linear velocity, m/s
  dVector3 angular{};               ///< angular velocity, rad/s
  dMatrix3 inverse_inertia{};       ///< world frame
  dReal inverse_mass = 0;           ///< 1/kg, as dBodySetMass stored it
  BodyStorage storage;              ///< the body's own arrays
};

/// Reads `body` under `gravity` (the world's, m/s²) as QuickStep's stage 0 does, operation for
/// operation; the gyroscopic torque is left to the caller.
inline void StartFreeBodyStep(dBodyID body, const dReal* gravity, InverseInertiaCache& cache, FreeBodyStart& s) {
  const BodyMass m = cache.Of(body, s.storage);  // the arrays too: no getter calls
  s.mass = m.mass;
  const BodyArrays& arrays = s.storage.arrays;
  for (int k = 0; k < 3; ++k) {
    s.force[k] = arrays.force[k];
    s.torque[k] = arrays.torque[k];
    s.linear[k] = arrays.linear[k];
    s.angular[k] = arrays.angular[k];
  }
  if (dBodyGetGravityMode(body)) {
    // Only the non-zero components: adding m·0 would turn a -0 force into +0.
    for (int k = 0; k < 3; ++k) {
      if (gravity[k] != 0) s.force[k] += s.mass->mass * gravity[k];
    }
  }
  dMatrix3 tmp = {};
  dMultiply2_333(tmp, m.inverse_inertia, s.storage.rotation);
  dMultiply0_333(s.inverse_inertia, s.storage.rotation, tmp);
  s.inverse_mass = m.inverse_mass;
}

/// QuickStep's whole stage 0 for a body its solver will constrain: StartFreeBodyStep and, if the
/// body asks for it, the implicit gyroscopic torque over `dt`.
inline void StartConstrainedBodyStep(dBodyID body, const dReal* gravity, InverseInertiaCache& cache, dReal dt,
                                     FreeBodyStart& s) {
  StartFreeBodyStep(body, gravity, cache, s);
  if (dBodyGetGyroscopicMode(body) && s.inverse_mass > 0) {
    AddImplicitGyroscopicTorque(*s.mass, s.storage.rotation, s.angular, dt, s.torque);
  }
}

/// QuickStep's rhs_tmp of body `s`: -(v/h + M⁻¹·f), linear then angular, `fps` = 1/h.
inline void UnconstrainedVelocityTerm(const FreeBodyStart& s, dReal fps, dReal* out) {
  for (int k = 0; k < 3; ++k) out[k] = -(s.force[k] * s.inverse_mass + s.linear[k] * fps);
  dMultiply0_331(out + 3, s.inverse_inertia, s.torque);
  for (int k = 0; k < 3; ++k) out[3 + k] = -(s.angular[k] * fps) - out[3 + k];
}

/// QuickStep's stage 4b and the rest of the step for body `s`: the constraint forces' velocity
/// change (`velocity_change`, M⁻¹·Jᵀ·λ, linear then angular) over `dt`, then FinishBodyStep.
inline void FinishConstrainedBodyStep(dBodyID body, FreeBodyStart& s, const dReal* velocity_change, dReal dt) {
  for (int k = 0; k < 3; ++k) {
    s.linear[k] += dt * velocity_change[k];
    s.angular[k] += dt * velocity_change[3 + k];
  }
  FinishBodyStep(body, s.storage, s.inverse_mass, s.inverse_inertia, s.force, s.torque, s.linear, s.angular, dt);
}

}  // namespace ubersim::kernel
