// SPDX-License-Identifier: Apache-2.0
// QuickStep's step of a body no joint touches, done by the kernel, bit for bit as ODE does it.
#pragma once

#include <unordered_map>

#include <ode/ode.h>

namespace ubersim::kernel {

/// Whether QuickStep would step `body` on its own, as a one-body island without constraints, and
/// LoneBodyStepper reproduces that step exactly: enabled, no joint attached (contacts included),
/// dynamic, and none of the options LoneBodyStepper leaves to ODE (finite rotation, damping, a
/// cap on the angular speed). The kernel sets no moved-callback on its bodies, which ODE cannot
/// be asked about.
bool IsLoneBody(dBodyID body);

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

 private:
  // The body-frame inverse inertia ODE derived in dBodySetMass, with the inertia it came from.
  struct InverseInertia {
    dMatrix3 inertia;
    dMatrix3 inverse;
  };
  const dReal* BodyInverseInertia(dBodyID body, const dMass& mass);

  std::unordered_map<dBodyID, InverseInertia> inverse_inertia_;
};

}  // namespace ubersim::kernel
