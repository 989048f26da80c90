// SPDX-License-Identifier: Apache-2.0
#include "physics/linked_island.hpp"

#include <algorithm>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "physics/contact_rows.hpp"

namespace ubersim::kernel {
namespace {

// f·j over six lanes, summed first to last as QuickStep spells it out. With SSE2 the products go
// two at a time: each is the scalar one, and the sum adds them in the same order: the same bits.
inline dReal Dot6(const dReal* f, const dReal* j) {
#if defined(__SSE2__)
  const __m128d p01 = _mm_mul_pd(_mm_loadu_pd(f), _mm_loadu_pd(j));
  const __m128d p23 = _mm_mul_pd(_mm_loadu_pd(f + 2), _mm_loadu_pd(j + 2));
  const __m128d p45 = _mm_mul_pd(_mm_loadu_pd(f + 4), _mm_loadu_pd(j + 4));
  dReal sum = _mm_cvtsd_f64(p01) + _mm_cvtsd_f64(_mm_unpackhi_pd(p01, p01));
  sum += _mm_cvtsd_f64(p23);
  sum += _mm_cvtsd_f64(_mm_unpackhi_pd(p23, p23));
  sum += _mm_cvtsd_f64(p45);
  return sum + _mm_cvtsd_f64(_mm_unpackhi_pd(p45, p45));
#else
  return f[0] * j[0] + f[1] * j[1] + f[2] * j[2] + f[3] * j[3] + f[4] * j[4] + f[5] * j[5];
#endif
}

// f += delta·imj over six lanes (lane by lane: the same bits two at a time).
inline void AddScaled6(dReal* f, dReal delta, const dReal* imj) {
#if defined(__SSE2__)
  const __m128d d = _mm_set1_pd(delta);
  _mm_storeu_pd(f, _mm_add_pd(_mm_loadu_pd(f), _mm_mul_pd(d, _mm_loadu_pd(imj))));
  _mm_storeu_pd(f + 2, _mm_add_pd(_mm_loadu_pd(f + 2), _mm_mul_pd(d, _mm_loadu_pd(imj + 2))));
  _mm_storeu_pd(f + 4, _mm_add_pd(_mm_loadu_pd(f + 4), _mm_mul_pd(d, _mm_loadu_pd(imj + 4))));
#else
  for (int k = 0; k < 6; ++k) f[k] += delta * imj[k];
#endif
}

}  // namespace

int LinkedIslandStepper::BodyIndex(dBodyID body, std::size_t first, std::size_t count) const {
  for (std::size_t i = 0; i < count; ++i) {
    if (bodies_[first + i] == body) return static_cast<int>(i);
  }
  return -1;  // not reached: every contact of an island links bodies of that island
}

int LinkedIslandStepper::Gather(dBodyID start, const StaticContactLog& log) {
  if (!StepsAsQuickStepsAFreeBody(start)) return -1;
  const std::size_t first_body = bodies_.size();
  const std::size_t first_joint = joints_.size();
  const auto leave_to_ode = [&] {
    bodies_.resize(first_body);
    joints_.resize(first_joint);
    return -1;
  };
  // QuickStep's island search (ODE's util.cpp): a stack; each body popped joins the island and
  // its joint list is walked in order, every joint not crossed yet joining the island and the
  // body across it, if not reached yet, going on the stack. The island's few bodies and joints
  // are scanned, not hashed.
  stack_.clear();
  crossed_.clear();
  stack_.push_back(start);
  const auto reached = [&](dBodyID b) {
    return std::find(bodies_.begin() + static_cast<std::ptrdiff_t>(first_body), bodies_.end(), b) != bodies_.end() ||
           std::find(stack_.begin(), stack_.end(), b) != stack_.end();
  };
  while (!stack_.empty()) {
    dBodyID b = stack_.back();
    stack_.pop_back();
    bodies_.push_back(b);
    for (int k = 0;; ++k) {
      dJointID j = dBodyGetJoint(b, k);
      if (!j) break;
      if (std::find(crossed_.begin(), crossed_.end(), j) != crossed_.end()) continue;
      const LoggedContact* c = log.Made(j);
      // A joint ODE skips (disabled) or reports on (feedback), or one the log did not make.
      if (!c || !dJointIsEnabled(j) || dJointGetFeedback(j)) return leave_to_ode();
      crossed_.push_back(j);
      joints_.push_back(c);
      dBodyID other = c->other == nullptr ? nullptr : (c->body == b ? c->other : c->body);
      if (other && !reached(other)) {
        if (!StepsAsQuickStepsAFreeBody(other)) return leave_to_ode();
        stack_.push_back(other);
      }
    }
  }
  islands_.push_back({first_body, bodies_.size() - first_body, first_joint, joints_.size() - first_joint});
  return static_cast<int>(islands_.size()) - 1;
}

// Everything below follows ODE 0.16's order of operations (quickstep.cpp) with ODE's own inline
// helpers, as ContactIslandStepper's: any other order changes the last bits.
void LinkedIslandStepper::Step(int island, const dReal* gravity, const ContactSolverSettings& settings,
                               int iterations, dReal dt) {
  const Island& is = islands_[Index(island)];
  const dBodyID* bodies = bodies_.data() + is.first_body;
  const std::size_t n = is.body_count;

  // Stage 0: gravity, the world-frame inverse inertia, the gyroscopic torque; body by body.
  if (starts_.size() < n) starts_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    StartConstrainedBodyStep(bodies[i], gravity, inverse_inertia_, dt, starts_[i]);
  }

  // Stage 2: the rows, joint by joint in the island's order.
  const dReal fps = dRecip(dt);
  row_count_ = 0;
  for (std::size_t k = 0; k < is.joint_count; ++k) {
    const LoggedContact& c = *joints_[is.first_joint + k];
    dSurfaceParameters s = c.contact.surface;  // getInfo1 clamps the friction coefficients in place
    const int m = ContactRowCount(s);
    const std::size_t first = row_count_;
    row_count_ += static_cast<std::size_t>(m);
    if (rows_.size() < row_count_) rows_.resize(2 * row_count_);  // grown, never shrunk
    const int b1 = BodyIndex(c.body, is.first_body, n);
    const int b2 = c.other ? BodyIndex(c.other, is.first_body, n) : -1;
    const FreeBodyStart& s1 = starts_[static_cast<std::size_t>(b1)];
    const ContactBody first_body{s1.storage.position, s1.linear, s1.angular};
    ContactBody second_body;
    if (b2 >= 0) {
      const FreeBodyStart& s2 = starts_[static_cast<std::size_t>(b2)];
      second_body = {s2.storage.position, s2.linear, s2.angular};
    }
    Row* row = &rows_[first];
    WriteContactRows(c.contact, s, c.reversed, m, row, first_body, b2 >= 0 ? &second_body : nullptr, settings, fps,
                     static_cast<int>(first));
    for (int i = 0; i < m; ++i) {
      row[i].b1 = b1;
      row[i].b2 = b2;
    }
  }

  // The right-hand side c/h - J·(v/h + M⁻¹·f): -(v/h + M⁻¹·f) per body first.
  rhs_tmp_.resize(6 * n);
  for (std::size_t i = 0; i < n; ++i) UnconstrainedVelocityTerm(starts_[i], fps, &rhs_tmp_[6 * i]);
  // Then, row by row (QuickStep does each stage for all rows, but no row depends on another):
  // J·rhs_tmp into the right-hand side, M⁻¹·Jᵀ, and the row scaled by its relaxed diagonal.
  const int m = static_cast<int>(row_count_);
  for (int i = 0; i < m; ++i) {
    Row& r = rows_[static_cast<std::size_t>(i)];
    const FreeBodyStart& s1 = starts_[static_cast<std::size_t>(r.b1)];
    const dReal* t1 = &rhs_tmp_[6 * static_cast<std::size_t>(r.b1)];
    dReal sum = 0;
    for (int k = 0; k < 6; ++k) sum += r.j[k] * t1[k];
    if (r.b2 >= 0) {
      const dReal* t2 = &rhs_tmp_[6 * static_cast<std::size_t>(r.b2)];
      for (int k = 0; k < 6; ++k) sum += r.j2[k] * t2[k];
    }
    r.rhs += sum;
    for (int k = 0; k < 3; ++k) r.imj[k] = s1.inverse_mass * r.j[k];
    dMultiply0_331(r.imj + 3, s1.inverse_inertia, r.j + 3);
    if (r.b2 >= 0) {
      const FreeBodyStart& s2 = starts_[static_cast<std::size_t>(r.b2)];
      for (int k = 0; k < 3; ++k) r.imj2[k] = s2.inverse_mass * r.j2[k];
      dMultiply0_331(r.imj2 + 3, s2.inverse_inertia, r.j2 + 3);
    }
    dReal diagonal = 0;
    for (int k = 0; k < 6; ++k) diagonal += r.imj[k] * r.j[k];
    if (r.b2 >= 0) {
      for (int k = 0; k < 6; ++k) diagonal += r.imj2[k] * r.j2[k];
    }
    const dReal ad = settings.sor_w / (diagonal + r.cfm);
    r.cfm = r.cfm * ad;
    r.rhs *= ad;
    for (dReal& v : r.j) v *= ad;
    if (r.b2 >= 0) {
      for (dReal& v : r.j2) v *= ad;
    }
    r.lambda = 0;
  }

  // Stage 4: unbounded rows first, then the SOR sweeps, shuffled as ContactIslandStepper's.
  UnboundedFirst(rows_, m, order_);
  fc_.assign(6 * n, 0);
  for (int i = 0; i < m; ++i) {  // each row's bodies' entries, found once for all sweeps
    Row& r = rows_[static_cast<std::size_t>(i)];
    r.f1 = &fc_[6 * static_cast<std::size_t>(r.b1)];
    r.f2 = r.b2 >= 0 ? &fc_[6 * static_cast<std::size_t>(r.b2)] : nullptr;
  }
  for (int iteration = 0; iteration < iterations; ++iteration) {
    ShuffleIfDue(iteration, order_);
    for (const int index : order_) {
      Row& r = rows_[static_cast<std::size_t>(index)];
      dReal delta = r.rhs - r.lambda * r.cfm;
      dReal* f1 = r.f1;
      delta -= Dot6(f1, r.j);
      dReal* f2 = r.f2;
      if (f2) delta -= Dot6(f2, r.j2);
      delta = ClampedUpdate(r, rows_.data(), delta);
      if (delta != 0) {
        AddScaled6(f1, delta, r.imj);
        if (f2) AddScaled6(f2, delta, r.imj2);
      }
    }
  }

  // Stage 4b: the constraint forces' velocity change; then each body's step as a free body's,
  // in the island's order (the order its geometries are told they moved).
  for (std::size_t i = 0; i < n; ++i) FinishConstrainedBodyStep(bodies[i], starts_[i], &fc_[6 * i], dt);
}

}  // namespace ubersim::kernel
