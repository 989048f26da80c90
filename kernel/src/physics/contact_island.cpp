// SPDX-License-Identifier: Apache-2.0
#include "physics/contact_island.hpp"

#include <utility>

#include "physics/free_body_start.hpp"

namespace ubersim::kernel {

ContactSolverSettings ContactSolverSettings::Of(dWorldID world) {
  ContactSolverSettings s;
  s.erp = dWorldGetERP(world);
  s.cfm = dWorldGetCFM(world);
  s.surface_layer = dWorldGetContactSurfaceLayer(world);
  s.max_correcting_velocity = dWorldGetContactMaxCorrectingVel(world);
  s.sor_w = dWorldGetQuickStepW(world);
  return s;
}

bool IsStaticContactIsland(dBodyID body, const StaticContactLog& log) {
  dJointID first = dBodyGetJoint(body, 0);
  if (!first || !StepsAsQuickStepsAFreeBody(body)) return false;
  for (int k = 0;; ++k) {
    dJointID j = k == 0 ? first : dBodyGetJoint(body, k);
    if (!j) return true;
    // The log keeps only contacts between a body and the static world.
    if (!dJointIsEnabled(j) || !log.Of(j)) return false;
  }
}

// Everything below follows ODE 0.16's order of operations (joints/contact.cpp, quickstep.cpp)
// with ODE's own inline helpers: any other order changes the last bits.
void ContactIslandStepper::AddContactRows(const StaticContact& sc, const dReal* position, const dReal* linear,
                                          const dReal* angular, const ContactSolverSettings& settings, dReal fps) {
  const dContact& c = sc.contact;
  dSurfaceParameters s = c.surface;  // getInfo1 clamps the friction coefficients in place
  const int mode = s.mode;

  // getInfo1: the row count, the friction coefficients made non-negative.
  int m = 1;
  if (mode & dContactAxisDep) {
    if (s.mu < 0) {
      s.mu = 0;
    } else if (s.mu > 0) {
      ++m;
    }
    if (s.mu2 < 0) {
      s.mu2 = 0;
    } else if (s.mu2 > 0) {
      ++m;
    }
    if (mode & dContactRolling) {
      for (dReal* rho : {&s.rho, &s.rho2, &s.rhoN}) {
        if (*rho < 0) {
          *rho = 0;
        } else {
          ++m;
        }
      }
    }
  } else {
    if (s.mu < 0) {
      s.mu = 0;
    } else if (s.mu > 0) {
      m += 2;
    }
    if (mode & dContactRolling) {
      if (s.rho < 0) {
        s.rho = 0;
      } else {
        m += 3;
      }
    }
  }

  // QuickStep's blank rows, then getInfo2 for a joint whose second body is the static world.
  const std::size_t first = rows_.size();
  Row blank{};
  blank.cfm = settings.cfm;
  blank.lo = -dInfinity;
  blank.hi = dInfinity;
  blank.findex = -1;
  rows_.resize(first + static_cast<std::size_t>(m), blank);
  Row* row = &rows_[first];

  const dReal erp = (mode & dContactSoftERP) ? s.soft_erp : settings.erp;
  const dReal k = fps * erp;
  dReal depth = c.geom.depth - settings.surface_layer;
  if (depth < 0) depth = 0;
  const dReal motion_n = (mode & dContactMotionN) ? s.motionN : REAL(0.0);
  const dReal pushout = k * depth + motion_n;
  const bool apply_bounce = (mode & dContactBounce) && s.bounce_vel >= 0;
  dReal outgoing = 0;
  const dReal max_vel = settings.max_correcting_velocity;
  dReal rhs = pushout > max_vel ? max_vel : pushout;

  dVector3 normal;
  if (sc.reversed) {
    dCopyNegatedVector3(normal, c.geom.normal);
  } else {
    dCopyVector3(normal, c.geom.normal);
  }
  dVector3 c1;
  dSubtractVectors3(c1, c.geom.pos, position);
  dCopyVector3(row[0].j, normal);
  dCalcVectorCross3(row[0].j + 3, c1, normal);
  if (apply_bounce) {
    outgoing += dCalcVectorDot3(row[0].j + 3, angular) + dCalcVectorDot3(normal, linear);
    const dReal negated_outgoing = motion_n - outgoing;
    if (negated_outgoing > s.bounce_vel) {
      const dReal bounced = s.bounce * negated_outgoing + motion_n;
      if (bounced > rhs) rhs = bounced;
    }
  }
  row[0].rhs = rhs;
  if (mode & dContactSoftCFM) row[0].cfm = s.soft_cfm;
  row[0].lo = 0;
  row[0].hi = dInfinity;

  if (m > 1) {
    dVector3 t1, t2;
    if (mode & dContactFDir1) {
      dCopyVector3(t1, c.fdir1);
      dCalcVectorCross3(t2, normal, t1);
    } else {
      dPlaneSpace(normal, t1, t2);
    }
    int r = 1;
    // A friction row along `t`: bounds ±coefficient, the surface's motion and slip if asked.
    const auto friction_row = [&](const dReal* t, dReal coefficient, int motion_flag, dReal motion, int slip_flag,
                                  dReal slip, int approx_flag) {
      dCopyVector3(row[r].j, t);
      dCalcVectorCross3(row[r].j + 3, c1, t);
      if (mode & motion_flag) row[r].rhs = motion;
      if (mode & slip_flag) row[r].cfm = slip;
      row[r].lo = -coefficient;
      row[r].hi = coefficient;
      if (mode & approx_flag) row[r].findex = 0;
      ++r;
    };
    const dReal mu = s.mu;
    if (mu > 0) friction_row(t1, mu, dContactMotion1, s.motion1, dContactSlip1, s.slip1, dContactApprox1_1);
    const dReal mu2 = (mode & dContactMu2) ? s.mu2 : mu;
    if (mu2 > 0) friction_row(t2, mu2, dContactMotion2, s.motion2, dContactSlip2, s.slip2, dContactApprox1_2);
    if (mode & dContactRolling) {
      const dReal* axes[3] = {t1, t2, normal};
      const int approx[3] = {dContactApprox1_1, dContactApprox1_2, dContactApprox1_N};
      const bool axis_dep = (mode & dContactAxisDep) != 0;
      const dReal rho[3] = {s.rho, axis_dep ? s.rho2 : s.rho, axis_dep ? s.rhoN : s.rho};
      for (int i = 0; i < 3; ++i) {
        if (rho[i] > 0) {
          dCopyVector3(row[r].j + 3, axes[i]);
          row[r].lo = -rho[i];
          row[r].hi = rho[i];
          if (mode & approx[i]) row[r].findex = 0;
          ++r;
        }
      }
    }
  }

  for (int i = 0; i < m; ++i) {
    if (row[i].findex != -1) row[i].findex += static_cast<int>(first);
    row[i].rhs *= fps;
    row[i].cfm *= fps;
  }
}

void ContactIslandStepper::Step(dBodyID body, const StaticContactLog& log, const dReal* gravity,
                                const ContactSolverSettings& settings, int iterations, dReal dt) {
  // Stage 0: gravity, the world-frame inverse inertia, the gyroscopic torque.
  FreeBodyStart b;
  StartFreeBodyStep(body, gravity, inverse_inertia_, b);
  if (dBodyGetGyroscopicMode(body) && b.inverse_mass > 0) {
    AddImplicitGyroscopicTorque(b.mass, b.rotation, b.angular, dt, b.torque);
  }
  const dReal inverse_mass = b.inverse_mass;
  const dReal* inverse_inertia = b.inverse_inertia;
  dReal* linear = b.linear;
  dReal* angular = b.angular;

  // Stage 2: the rows, joint by joint in the body's list (QuickStep's island order), and the
  // right-hand side c/h - J·(v/h + M⁻¹·f).
  const dReal fps = dRecip(dt);
  rows_.clear();
  const dReal* position = dBodyGetPosition(body);
  for (int k = 0;; ++k) {
    dJointID j = dBodyGetJoint(body, k);
    if (!j) break;
    AddContactRows(*log.Of(j), position, linear, angular, settings, fps);
  }
  dReal rhs_tmp[6];
  for (int k = 0; k < 3; ++k) rhs_tmp[k] = -(b.force[k] * inverse_mass + linear[k] * fps);
  dMultiply0_331(rhs_tmp + 3, inverse_inertia, b.torque);
  for (int k = 0; k < 3; ++k) rhs_tmp[3 + k] = -(angular[k] * fps) - rhs_tmp[3 + k];
  for (Row& r : rows_) {
    dReal sum = 0;
    for (int k = 0; k < 6; ++k) sum += r.j[k] * rhs_tmp[k];
    r.rhs += sum;
  }

  // Stage 4: M⁻¹·Jᵀ, each row scaled by its relaxed diagonal, unbounded rows first.
  const int m = static_cast<int>(rows_.size());
  order_.clear();
  for (Row& r : rows_) {
    for (int k = 0; k < 3; ++k) r.imj[k] = inverse_mass * r.j[k];
    dMultiply0_331(r.imj + 3, inverse_inertia, r.j + 3);
  }
  for (Row& r : rows_) {
    dReal sum = 0;
    for (int k = 0; k < 6; ++k) sum += r.imj[k] * r.j[k];
    const dReal ad = settings.sor_w / (sum + r.cfm);
    r.cfm = r.cfm * ad;
    r.rhs *= ad;
    for (dReal& v : r.j) v *= ad;
  }
  for (int i = 0; i < m; ++i) {
    if (rows_[static_cast<std::size_t>(i)].findex == -1) order_.push_back(i);
  }
  for (int i = 0; i < m; ++i) {
    if (rows_[static_cast<std::size_t>(i)].findex != -1) order_.push_back(i);
  }
  lambda_.assign(static_cast<std::size_t>(m), 0);
  dReal fc[6] = {0, 0, 0, 0, 0, 0};

  // The SOR sweeps. QuickStep shuffles the order before every eighth sweep after the first
  // eight, with ODE's generator.
  for (int iteration = 0; iteration < iterations; ++iteration) {
    if (iteration >= kFirstShuffle && iteration % kFirstShuffle == 0) {
      for (int index = 1; index < m; ++index) {
        const int swap = dRandInt(index + 1);
        std::swap(order_[static_cast<std::size_t>(index)], order_[static_cast<std::size_t>(swap)]);
      }
    }
    for (const int index : order_) {
      const Row& r = rows_[static_cast<std::size_t>(index)];
      dReal& lambda = lambda_[static_cast<std::size_t>(index)];
      const dReal old_lambda = lambda;
      dReal delta = r.rhs - old_lambda * r.cfm;
      delta -= fc[0] * r.j[0] + fc[1] * r.j[1] + fc[2] * r.j[2] + fc[3] * r.j[3] + fc[4] * r.j[4] + fc[5] * r.j[5];
      dReal hi, lo;
      if (r.findex != -1) {
        hi = dFabs(r.hi * lambda_[static_cast<std::size_t>(r.findex)]);
        lo = -hi;
      } else {
        hi = r.hi;
        lo = r.lo;
      }
      const dReal new_lambda = old_lambda + delta;
      if (new_lambda < lo) {
        delta = lo - old_lambda;
        lambda = lo;
      } else if (new_lambda > hi) {
        delta = hi - old_lambda;
        lambda = hi;
      } else {
        lambda = new_lambda;
      }
      if (delta != 0) {
        for (int k = 0; k < 6; ++k) fc[k] += delta * r.imj[k];
      }
    }
  }

  // Stage 4b: the constraint forces' velocity change; then the body's step as a free body's.
  for (int k = 0; k < 3; ++k) {
    linear[k] += dt * fc[k];
    angular[k] += dt * fc[3 + k];
  }
  FinishBodyStep(body, inverse_mass, inverse_inertia, b.force, b.torque, linear, angular, dt);
}

}  // namespace ubersim::kernel
