// SPDX-License-Identifier: Apache-2.0
#include "physics/lone_body.hpp"

#include <cmath>
#include <cstring>

#include "physics/free_body_start.hpp"

namespace ubersim::kernel {

namespace {

// StepsAsQuickStepsAFreeBody but for being enabled.
bool AsksForNothingLeftToOde(dBodyID body) {
  return !dBodyIsKinematic(body) && !dBodyGetFiniteRotationMode(body) && dBodyGetLinearDamping(body) == 0 &&
         dBodyGetAngularDamping(body) == 0 && dBodyGetMaxAngularSpeed(body) == dInfinity;
}

}  // namespace

bool StepsAsQuickStepsAFreeBody(dBodyID body) { return dBodyIsEnabled(body) && AsksForNothingLeftToOde(body); }

bool IsLoneBody(dBodyID body) { return dBodyIsEnabled(body) && IsLoneEnabledBody(body); }

bool IsLoneEnabledBody(dBodyID body) {
  // dBodyGetJoint(body, 0) is one pointer read; dBodyGetNumJoints walks the whole list.
  return dBodyGetJoint(body, 0) == nullptr && AsksForNothingLeftToOde(body);
}

namespace {

// What dBodySetMass stores as the inverse of `inertia`: the Cholesky inverse, or the identity
// for an inertia that is not positive definite.
void InverseOf(const dMatrix3 inertia, dMatrix3 inverse) {
  if (dInvertPDMatrix(inertia, inverse, 3) == 0) dRSetIdentity(inverse);
}

}  // namespace

InverseInertiaCache::Entry& InverseInertiaCache::FindElsewhere(dBodyID body) {
  std::size_t at = 0;
  while (at < entries_.size() && entries_[at].body != body) ++at;
  if (at == entries_.size()) {
    if (entries_.size() >= 4096) {  // bodies come and go: bound it
      entries_.clear();
      at = 0;
    }
    // First sight: the arrays from the getters; and does ODE's own storage, right before the
    // position, hold this body's mass, inverse inertia and inverse mass? (A body ODE reuses the
    // memory of has the same layout.)
    Entry e{body, BodyStorage::Of(body), false, {}, {}, {}};
    dBodyGetMass(body, &e.mass);
    InverseOf(e.mass.I, e.inverse);
    const BodyMass stored = StoredAt(e.storage.position);
    const dReal expected_inverse_mass = dRecip(e.mass.mass);
    e.in_place = std::memcmp(stored.mass, &e.mass, sizeof(dMass)) == 0 &&
                 std::memcmp(stored.inverse_inertia, e.inverse, sizeof(dMatrix3)) == 0 &&
                 std::memcmp(&stored.inverse_mass, &expected_inverse_mass, sizeof(dReal)) == 0;
    std::memcpy(e.inertia, e.mass.I, sizeof e.inertia);
    entries_.push_back(e);
  }
  next_ = at + 1;
  return entries_[at];
}

BodyMass InverseInertiaCache::MassOf(Entry& e) {
  if (e.in_place) return StoredAt(e.storage.position);
  // Checked against the inertia it came from: a pure function of it.
  dBodyGetMass(e.body, &e.mass);
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

namespace {

// The quaternion's rate of change at angular velocity `w`, as ODE's dDQfromW computes it.
inline void QuaternionRate(const dReal* w, const dReal* q, dReal* dq) {
  dq[0] = dReal(0.5) * (-w[0] * q[1] - w[1] * q[2] - w[2] * q[3]);
  dq[1] = dReal(0.5) * (w[0] * q[0] + w[1] * q[3] - w[2] * q[2]);
  dq[2] = dReal(0.5) * (-w[0] * q[3] + w[1] * q[0] + w[2] * q[1]);
  dq[3] = dReal(0.5) * (w[0] * q[2] - w[1] * q[1] + w[2] * q[0]);
}

// `q` scaled to unit length as ODE's dNormalize4 does it (the identity for a zero quaternion).
inline void NormaliseQuaternion(dReal* q) {
  dReal l = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  if (l > 0) {
    l = dReal(1.0) / std::sqrt(l);
    for (int k = 0; k < 4; ++k) q[k] *= l;
  } else {
    q[0] = 1;
    q[1] = q[2] = q[3] = 0;
  }
}

// The rotation matrix (ODE's 3×4) of the unit quaternion `q`, as ODE's dRfromQ computes it.
inline void RotationOf(const dReal* quaternion, dReal* r) {
  // Read once: every store into r could otherwise be a store into the quaternion.
  const dReal q[4] = {quaternion[0], quaternion[1], quaternion[2], quaternion[3]};
  const dReal qq1 = 2 * q[1] * q[1];
  const dReal qq2 = 2 * q[2] * q[2];
  const dReal qq3 = 2 * q[3] * q[3];
  r[0] = 1 - qq2 - qq3;
  r[1] = 2 * (q[1] * q[2] - q[0] * q[3]);
  r[2] = 2 * (q[1] * q[3] + q[0] * q[2]);
  r[3] = 0;
  r[4] = 2 * (q[1] * q[2] + q[0] * q[3]);
  r[5] = 1 - qq1 - qq3;
  r[6] = 2 * (q[2] * q[3] - q[0] * q[1]);
  r[7] = 0;
  r[8] = 2 * (q[1] * q[3] - q[0] * q[2]);
  r[9] = 2 * (q[2] * q[3] + q[0] * q[1]);
  r[10] = 1 - qq1 - qq2;
  r[11] = 0;
}

// The end of every step of a free body: its pose moves with its new velocities `linear` and
// `angular` over `dt`, in the body's own arrays (`storage`: the getters' pointers, ODE's storage,
// not copies): what dBodySetPosition and dBodySetQuaternion would store, with dDQfromW,
// dNormalize4 and dRfromQ's arithmetic written out in their order; each geometry is told that the
// body moved, as the setters tell it (the calls were a third of a lone body's step); the
// velocities are stored and the accumulators cleared.
void MoveBody(dBodyID body, const BodyStorage& storage, const dReal* linear, const dReal* angular, dReal dt) {
  dReal* position = storage.position;
  dReal* q = storage.quaternion;
  const BodyArrays& arrays = storage.arrays;
  for (int k = 0; k < 3; ++k) position[k] += dt * linear[k];
  // The turn and the orientation in locals: ODE's arrays are written once, at the end.
  const dReal w[3] = {angular[0], angular[1], angular[2]};
  dReal turned[4] = {q[0], q[1], q[2], q[3]};
  dReal dq[4];
  QuaternionRate(w, turned, dq);
  for (int k = 0; k < 4; ++k) turned[k] += dt * dq[k];
  NormaliseQuaternion(turned);
  for (int k = 0; k < 4; ++k) q[k] = turned[k];
  RotationOf(turned, storage.rotation);
  for (dGeomID g = dBodyGetFirstGeom(body); g; g = dGeomGetBodyNext(g)) dGeomMoved(g);

  for (int k = 0; k < 3; ++k) {
    arrays.linear[k] = linear[k];
    arrays.angular[k] = angular[k];
    arrays.force[k] = arrays.torque[k] = 0;
  }
}

}  // namespace

void FinishBodyStep(dBodyID body, const BodyStorage& storage, dReal inverse_mass, const dReal* inverse_inertia,
                    const dReal* force, dReal* torque, dReal* linear, dReal* angular, dReal dt) {
  // Velocities.
  const dReal impulse_per_force = dt * inverse_mass;
  for (int k = 0; k < 3; ++k) {
    linear[k] += impulse_per_force * force[k];
    torque[k] *= dt;
  }
  dMultiplyAdd0_331(angular, inverse_inertia, torque);

  MoveBody(body, storage, linear, angular, dt);
}

bool LoneBodyStepper::StepLevel(dBodyID body, const dReal* gravity, dReal dt) {
  // Level: no tilt in the orientation nor in the rotation matrix built from it, no tilting turn
  // (exactly +0: the general step's sums of zeros keep a +0 as it is), no tilting torque, and a
  // torque about the vertical that turns the body (with none, the sum of zeros below could
  // change the sign of a zero turn rate).
  BodyStorage storage;
  const BodyMass m = inverse_inertia_.Of(body, storage);
  const dReal* q = storage.quaternion;
  const dReal* rotation = storage.rotation;
  const BodyArrays& arrays = storage.arrays;
  const dReal* w = arrays.angular;
  const dReal* t = arrays.torque;
  const auto positive_zero = [](dReal x) { return x == 0 && !std::signbit(x); };
  if (q[1] != 0 || q[2] != 0 || rotation[8] != 0 || rotation[9] != 0 || rotation[10] != 1 ||
      !positive_zero(w[0]) || !positive_zero(w[1]) || t[0] != 0 || t[1] != 0) {
    return false;
  }
  const dReal* inverse = m.inverse_inertia;
  const dReal turn = inverse[10] * (t[2] * dt);
  // The vertical a principal axis (the general step skips the zero gyroscopic torque only
  // then), and a torque about it that turns the body only about it.
  if (m.mass->I[2] != 0 || m.mass->I[6] != 0 || inverse[2] != 0 || inverse[6] != 0 || turn == 0 ||
      !std::isfinite(turn) || !(m.inverse_mass > 0)) {
    return false;
  }
  dReal force[3] = {arrays.force[0], arrays.force[1], arrays.force[2]};
  if (dBodyGetGravityMode(body)) {
    for (int k = 0; k < 3; ++k) {
      if (gravity[k] != 0) force[k] += m.mass->mass * gravity[k];
    }
  }
  const dReal impulse_per_force = dt * m.inverse_mass;
  dReal linear[3], angular[3];
  for (int k = 0; k < 3; ++k) linear[k] = arrays.linear[k] + impulse_per_force * force[k];
  // The general step's world-frame inverse inertia times the torque: its row for the turn about
  // the vertical is exactly inverse[10] times the torque about it (the other products are zeros
  // that leave a non-zero sum as it is), and the tilting rows add zeros to the +0 turn rates.
  angular[0] = w[0];
  angular[1] = w[1];
  angular[2] = w[2] + turn;
  MoveBody(body, storage, linear, angular, dt);
  ++level_steps_;
  return true;
}

void LoneBodyStepper::Step(dBodyID body, const dReal* gravity, dReal dt) {
  if (!StepLevel(body, gravity, dt)) StepAnyPose(body, gravity, dt);
}

void LoneBodyStepper::StepAnyPose(dBodyID body, const dReal* gravity, dReal dt) {
  FreeBodyStart b;
  StartFreeBodyStep(body, gravity, inverse_inertia_, b);
  // Turning only about a vertical principal axis (a one-body robot driving level: most steps of
  // most robots), the momentum lies along the turn and the gyroscopic torque is zero: its work
  // is skipped. QuickStep's implicit form computes it as zero but for the last bit of the turn
  // rate, so here the stepper agrees with QuickStep to rounding, not to the bit.
  const dReal* rotation = b.storage.rotation;
  const bool about_principal_vertical = b.angular[0] == 0 && b.angular[1] == 0 && rotation[8] == 0 &&
                                        rotation[9] == 0 && b.mass->I[2] == 0 && b.mass->I[6] == 0;
  if (dBodyGetGyroscopicMode(body) && b.inverse_mass > 0 && !about_principal_vertical) {
    AddImplicitGyroscopicTorque(*b.mass, rotation, b.angular, dt, b.torque);
  }
  FinishBodyStep(body, b.storage, b.inverse_mass, b.inverse_inertia, b.force, b.torque, b.linear, b.angular, dt);
}

}  // namespace ubersim::kernel
