// SPDX-License-Identifier: Apache-2.0
#include "physics/lone_body.hpp"

#include <cstring>

#include "physics/free_body_start.hpp"

namespace ubersim::kernel {

bool StepsAsQuickStepsAFreeBody(dBodyID body) {
  return dBodyIsEnabled(body) && !dBodyIsKinematic(body) && !dBodyGetFiniteRotationMode(body) &&
         dBodyGetLinearDamping(body) == 0 && dBodyGetAngularDamping(body) == 0 &&
         dBodyGetMaxAngularSpeed(body) == dInfinity;
}

bool IsLoneBody(dBodyID body) {
  // dBodyGetJoint(body, 0) is one pointer read; dBodyGetNumJoints walks the whole list.
  return dBodyGetJoint(body, 0) == nullptr && StepsAsQuickStepsAFreeBody(body);
}

namespace {

// What dBodySetMass stores as the inverse of `inertia`: the Cholesky inverse, or the identity
// for an inertia that is not positive definite.
void InverseOf(const dMatrix3 inertia, dMatrix3 inverse) {
  if (dInvertPDMatrix(inertia, inverse, 3) == 0) dRSetIdentity(inverse);
}

// Where ODE keeps `body`'s mass, inverse inertia and inverse mass if its dxBody is laid out as
// mass, invI, invMass, then the position (InverseInertiaCache checks that it is).
BodyMass StoredIn(dBodyID body) {
  const dReal* inverse_mass = dBodyGetPosition(body) - 1;
  const dReal* inverse = inverse_mass - 12;
  return {reinterpret_cast<const dMass*>(inverse - sizeof(dMass) / sizeof(dReal)), inverse, *inverse_mass};
}

}  // namespace

BodyMass InverseInertiaCache::Of(dBodyID body) {
  std::size_t at = next_ < entries_.size() && entries_[next_].body == body ? next_ : entries_.size();
  if (at == entries_.size()) {
    at = 0;
    while (at < entries_.size() && entries_[at].body != body) ++at;
    if (at == entries_.size()) {
      if (entries_.size() >= 4096) {  // bodies come and go: bound it
        entries_.clear();
        at = 0;
      }
      // First sight: does ODE's own storage, right before the position, hold this body's mass,
      // inverse inertia and inverse mass? (A body ODE reuses the memory of has the same layout.)
      Entry e{body, false, {}, {}, {}};
      dBodyGetMass(body, &e.mass);
      InverseOf(e.mass.I, e.inverse);
      const BodyMass stored = StoredIn(body);
      const dReal expected_inverse_mass = dRecip(e.mass.mass);
      e.in_place = std::memcmp(stored.mass, &e.mass, sizeof(dMass)) == 0 &&
                   std::memcmp(stored.inverse_inertia, e.inverse, sizeof(dMatrix3)) == 0 &&
                   std::memcmp(&stored.inverse_mass, &expected_inverse_mass, sizeof(dReal)) == 0;
      std::memcpy(e.inertia, e.mass.I, sizeof e.inertia);
      entries_.push_back(e);
    }
  }
  next_ = at + 1;
  Entry& e = entries_[at];
  if (e.in_place) return StoredIn(body);
  // Checked against the inertia it came from: a pure function of it.
  dBodyGetMass(body, &e.mass);
  if (std::memcmp(e.inertia, e.mass.I, sizeof e.inertia) != 0) {
    std::memcpy(e.inertia, e.mass.I, sizeof e.inertia);
    InverseOf(e.mass.I, e.inverse);
  }
  return {&e.mass, e.inverse, dRecip(e.mass.mass)};
}

// The order of every operation below is QuickStep's (quickstep.cpp, stages 0 and 6, and
// dxStepBody in util.cpp), with ODE's own inline helpers: any other order changes the last bits.
void AddImplicitGyroscopicTorque(const dMass& mass, const dReal* rotation, const dReal* angular, dReal dt,
                                 dReal* torque) {
  dMatrix3 tmp = {};
  dMatrix3 inertia = {};
  dMultiply2_333(tmp, mass.I, rotation);
  dMultiply0_333(inertia, rotation, tmp);
  dVector3 momentum;
  dMultiply0_331(momentum, inertia, angular);
  dMatrix3 tilde = {};
  dSetCrossMatrixMinus(tilde, momentum, 4);
  for (int i = 0; i < 12; ++i) tilde[i] = tilde[i] * dt + inertia[i];
  dScaleVector3(momentum, dRecip(dt));
  dMatrix3 tilde_inverse = {};
  if (dInvertMatrix3(tilde_inverse, tilde) != 0) {
    dMultiply0_333(tilde, inertia, tilde_inverse);
    tilde[0] -= 1;
    tilde[5] -= 1;
    tilde[10] -= 1;
    dVector3 gyroscopic;
    dMultiply0_331(gyroscopic, tilde, momentum);
    dAddVectors3(torque, torque, gyroscopic);
  }
}

void FinishBodyStep(dBodyID body, const BodyArrays& arrays, dReal inverse_mass, const dReal* inverse_inertia,
                    const dReal* force, dReal* torque, dReal* linear, dReal* angular, dReal dt) {
  // Velocities.
  const dReal impulse_per_force = dt * inverse_mass;
  for (int k = 0; k < 3; ++k) {
    linear[k] += impulse_per_force * force[k];
    torque[k] *= dt;
  }
  dMultiplyAdd0_331(angular, inverse_inertia, torque);

  // Pose: dBodySetQuaternion normalises and converts to the rotation matrix as dxStepBody does,
  // and tells the body's geometries that it moved. The position goes straight into the body's
  // own array (dBodyGetPosition's pointer is ODE's storage, not a copy): dBodySetPosition would
  // tell every geometry a second time, a third of a wheel robot's integration.
  auto* position = const_cast<dReal*>(dBodyGetPosition(body));
  for (int k = 0; k < 3; ++k) position[k] += dt * linear[k];
  dQuaternion q;
  std::memcpy(q, dBodyGetQuaternion(body), sizeof q);
  dReal dq[4];
  dDQfromW(dq, angular, q);
  for (int k = 0; k < 4; ++k) q[k] += dt * dq[k];

  for (int k = 0; k < 3; ++k) {
    arrays.linear[k] = linear[k];
    arrays.angular[k] = angular[k];
  }
  dBodySetQuaternion(body, q);
  for (int k = 0; k < 3; ++k) arrays.force[k] = arrays.torque[k] = 0;
}

void LoneBodyStepper::Step(dBodyID body, const dReal* gravity, dReal dt) {
  FreeBodyStart b;
  StartFreeBodyStep(body, gravity, inverse_inertia_, b);
  // Turning only about a vertical principal axis (a one-body robot driving level: most steps of
  // most robots), the momentum lies along the turn and the gyroscopic torque is zero: its work
  // is skipped. QuickStep's implicit form computes it as zero but for the last bit of the turn
  // rate, so here the stepper agrees with QuickStep to rounding, not to the bit.
  const dReal* rotation = b.rotation;
  const bool about_principal_vertical = b.angular[0] == 0 && b.angular[1] == 0 && rotation[8] == 0 &&
                                        rotation[9] == 0 && b.mass->I[2] == 0 && b.mass->I[6] == 0;
  if (dBodyGetGyroscopicMode(body) && b.inverse_mass > 0 && !about_principal_vertical) {
    AddImplicitGyroscopicTorque(*b.mass, rotation, b.angular, dt, b.torque);
  }
  FinishBodyStep(body, b.arrays, b.inverse_mass, b.inverse_inertia, b.force, b.torque, b.linear, b.angular, dt);
}

}  // namespace ubersim::kernel
