// SPDX-License-Identifier: Apache-2.0
// What the tests of the kernel's steppers share: a world for a twin stepped by QuickStep, and a
// comparison of two bodies' states bit for bit.
#pragma once

#include <array>
#include <cstring>
#include <string>

#include <ode/ode.h>

#include "physics/ode_handles.hpp"

namespace ubersim::test {

/// A world that never puts bodies to sleep, its gravity tilted by `gx` (m/s²): two components
/// for a stepper to add.
inline kernel::OdeWorld MakeTiltedWorld(double gx) {
  kernel::OdeWorld w(dWorldCreate());
  dWorldSetGravity(w.get(), gx, 0, -9.81);
  dWorldSetAutoDisableFlag(w.get(), 0);
  return w;
}

/// A new body in `world`: a 1 kg ball of 0.1 m radius, at rest at the origin.
inline dBodyID MakeBall(dWorldID world) {
  dBodyID b = dBodyCreate(world);
  dMass m;
  dMassSetSphereTotal(&m, 1.0, 0.1);
  dBodySetMass(b, &m);
  return b;
}

/// The first of the `n` values of a and b that differ in some bit, named; empty if none does.
inline std::string BitDifference(const char* what, const dReal* a, const dReal* b, int n) {
  for (int i = 0; i < n; ++i) {
    if (std::memcmp(&a[i], &b[i], sizeof(dReal)) != 0) {
      return std::string(what) + "[" + std::to_string(i) + "]: " + std::to_string(a[i]) + " vs " +
             std::to_string(b[i]);
    }
  }
  return "";
}

/// Every bit of the state QuickStep writes, or the first difference.
inline std::string StateDifference(dBodyID a, dBodyID b) {
  const std::array<std::string, 7> diffs = {
      BitDifference("position", dBodyGetPosition(a), dBodyGetPosition(b), 3),
      BitDifference("quaternion", dBodyGetQuaternion(a), dBodyGetQuaternion(b), 4),
      BitDifference("rotation", dBodyGetRotation(a), dBodyGetRotation(b), 11),
      BitDifference("linear velocity", dBodyGetLinearVel(a), dBodyGetLinearVel(b), 3),
      BitDifference("angular velocity", dBodyGetAngularVel(a), dBodyGetAngularVel(b), 3),
      BitDifference("force", dBodyGetForce(a), dBodyGetForce(b), 3),
      BitDifference("torque", dBodyGetTorque(a), dBodyGetTorque(b), 3),
  };
  for (const std::string& d : diffs) {
    if (!d.empty()) return d;
  }
  return "";
}

}  // namespace ubersim::test
