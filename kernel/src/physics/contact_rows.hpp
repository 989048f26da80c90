// SPDX-License-Identifier: Apache-2.0
// A contact joint's constraint rows as ODE 0.16 writes them (joints/contact.cpp's getInfo1 and
// getInfo2, then QuickStep's scaling by the step's rate), shared by the kernel's steppers.
#pragma once

#include <utility>
#include <vector>

#include <ode/ode.h>

#include "physics/contact_island.hpp"

namespace ubersim::kernel {

/// One body of a contact as getInfo2 reads it: where its centre of mass is and how it moves.
struct ContactBody {
  const dReal* position = nullptr;  ///< m, world frame
  const dReal* linear = nullptr;    ///< m/s
  const dReal* angular = nullptr;   ///< rad/s
};

/// getInfo1: the number of rows of a contact with `s` (its surface), whose friction and rolling
/// coefficients it makes non-negative in place, as ODE does.
inline int ContactRowCount(dSurfaceParameters& s) {
  const int mode = s.mode;
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
  return m;
}

/// QuickStep's blank rows, getInfo2 and the scaling by `fps` for contact `c` with surface `s`
/// (ContactRowCount's, `m` rows) between `first` and `second` (null: the static world), into
/// `row[0..m)`; `reversed`: attached with the static world first (ODE turns the normal round).
/// Friction indices are made global by `first_index`, the first row's. A Row has j (the first
/// body's Jacobian, linear then angular), rhs, cfm, lo, hi and findex; with a second body, j2.
template <typename Row>
void WriteContactRows(const dContact& c, const dSurfaceParameters& s, bool reversed, int m, Row* row,
                      const ContactBody& first, const ContactBody* second, const ContactSolverSettings& settings,
                      dReal fps, int first_index) {
  constexpr bool kTwoBodies = requires(Row r) { r.j2; };
  const int mode = s.mode;
  for (int i = 0; i < m; ++i) {
    for (dReal& v : row[i].j) v = 0;
    if constexpr (kTwoBodies) {
      for (dReal& v : row[i].j2) v = 0;
    }
    row[i].rhs = 0;
    row[i].cfm = settings.cfm;
    row[i].lo = -dInfinity;
    row[i].hi = dInfinity;
    row[i].findex = -1;
  }

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
  if (reversed) {
    dCopyNegatedVector3(normal, c.geom.normal);
  } else {
    dCopyVector3(normal, c.geom.normal);
  }
  // ODE writes the second body's rows first, and starts the outgoing speed from it.
  dVector3 c2 = {0, 0, 0};
  if constexpr (kTwoBodies) {
    if (second) {
      dSubtractVectors3(c2, c.geom.pos, second->position);
      dCopyNegatedVector3(row[0].j2, normal);
      dCalcVectorCross3(row[0].j2 + 3, normal, c2);
      if (apply_bounce) {
        outgoing = dCalcVectorDot3(row[0].j2 + 3, second->angular) - dCalcVectorDot3(normal, second->linear);
      }
    }
  }
  dVector3 c1;
  dSubtractVectors3(c1, c.geom.pos, first.position);
  dCopyVector3(row[0].j, normal);
  dCalcVectorCross3(row[0].j + 3, c1, normal);
  if (apply_bounce) {
    outgoing += dCalcVectorDot3(row[0].j + 3, first.angular) + dCalcVectorDot3(normal, first.linear);
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
      if constexpr (kTwoBodies) {
        if (second) {
          dCopyNegatedVector3(row[r].j2, t);
          dCalcVectorCross3(row[r].j2 + 3, t, c2);
        }
      }
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
          if constexpr (kTwoBodies) {
            if (second) dCopyNegatedVector3(row[r].j2 + 3, axes[i]);
          }
          row[r].lo = -rho[i];
          row[r].hi = rho[i];
          if (mode & approx[i]) row[r].findex = 0;
          ++r;
        }
      }
    }
  }

  for (int i = 0; i < m; ++i) {
    if (row[i].findex != -1) row[i].findex += first_index;
    row[i].rhs *= fps;
    row[i].cfm *= fps;
  }
}

/// QuickStep's row order before its sweeps: the `m` rows without a friction index first, then
/// the others, each in index order.
template <typename Row>
void UnboundedFirst(const std::vector<Row>& rows, int m, std::vector<int>& order) {
  order.clear();
  for (int i = 0; i < m; ++i) {
    if (rows[static_cast<std::size_t>(i)].findex == -1) order.push_back(i);
  }
  for (int i = 0; i < m; ++i) {
    if (rows[static_cast<std::size_t>(i)].findex != -1) order.push_back(i);
  }
}

/// QuickStep's shuffle of the row order before sweep `iteration` (0-based): before the ninth and
/// every eighth after, with ODE's generator; a step of fewer sweeps draws nothing.
inline void ShuffleIfDue(int iteration, std::vector<int>& order) {
  constexpr int kEvery = ContactIslandStepper::kFirstShuffle;
  if (iteration < kEvery || iteration % kEvery != 0) return;
  for (int index = 1; index < static_cast<int>(order.size()); ++index) {
    const int swap = dRandInt(index + 1);
    std::swap(order[static_cast<std::size_t>(index)], order[static_cast<std::size_t>(swap)]);
  }
}

/// A sweep's update of row `r`'s multiplier by `delta`, clamped to its bounds (a friction row's
/// by its normal row's multiplier, found in `rows`); returns the change made.
template <typename Row>
dReal ClampedUpdate(Row& r, const Row* rows, dReal delta) {
  const dReal old_lambda = r.lambda;
  dReal hi, lo;
  if (r.findex != -1) {
    hi = dFabs(r.hi * rows[r.findex].lambda);
    lo = -hi;
  } else {
    hi = r.hi;
    lo = r.lo;
  }
  const dReal new_lambda = old_lambda + delta;
  if (new_lambda < lo) {
    r.lambda = lo;
    return lo - old_lambda;
  }
  if (new_lambda > hi) {
    r.lambda = hi;
    return hi - old_lambda;
  }
  r.lambda = new_lambda;
  return delta;
}

}  // namespace ubersim::kernel
