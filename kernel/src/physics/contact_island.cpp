// SPDX-License-Identifier: Apache-2.0
#include "physics/contact_island.hpp"

#include <cstdint>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "physics/contact_rows.hpp"
#include "physics/free_body_start.hpp"

namespace ubersim::kernel {
namespace {

// M⁻¹·Jᵀ·λ of one body as the sweeps build it (QuickStep's `fc`), held in registers. With SSE2
// the six lanes go two at a time: each lane's products and sums are the scalar ones, and the
// dot product still adds its six terms in QuickStep's order, so the bits are the same.
class ConstraintVelocity {
 public:
#if defined(__SSE2__)
  // fc·j, summed first to last.
  dReal Dot(const dReal* j) const {
    const __m128d p01 = _mm_mul_pd(v01_, _mm_loadu_pd(j));
    const __m128d p23 = _mm_mul_pd(v23_, _mm_loadu_pd(j + 2));
    const __m128d p45 = _mm_mul_pd(v45_, _mm_loadu_pd(j + 4));
    dReal sum = _mm_cvtsd_f64(p01) + _mm_cvtsd_f64(_mm_unpackhi_pd(p01, p01));
    sum += _mm_cvtsd_f64(p23);
    sum += _mm_cvtsd_f64(_mm_unpackhi_pd(p23, p23));
    sum += _mm_cvtsd_f64(p45);
    return sum + _mm_cvtsd_f64(_mm_unpackhi_pd(p45, p45));
  }
  // fc += delta·imj.
  void Add(dReal delta, const dReal* imj) {
    const __m128d d = _mm_set1_pd(delta);
    v01_ = _mm_add_pd(v01_, _mm_mul_pd(d, _mm_loadu_pd(imj)));
    v23_ = _mm_add_pd(v23_, _mm_mul_pd(d, _mm_loadu_pd(imj + 2)));
    v45_ = _mm_add_pd(v45_, _mm_mul_pd(d, _mm_loadu_pd(imj + 4)));
  }
  void Store(dReal* out) const {
    _mm_storeu_pd(out, v01_);
    _mm_storeu_pd(out + 2, v23_);
    _mm_storeu_pd(out + 4, v45_);
  }

 private:
  __m128d v01_ = _mm_setzero_pd(), v23_ = _mm_setzero_pd(), v45_ = _mm_setzero_pd();
#else
  dReal Dot(const dReal* j) const {
    return v_[0] * j[0] + v_[1] * j[1] + v_[2] * j[2] + v_[3] * j[3] + v_[4] * j[4] + v_[5] * j[5];
  }
  void Add(dReal delta, const dReal* imj) {
    for (int k = 0; k < 6; ++k) v_[k] += delta * imj[k];
  }
  void Store(dReal* out) const {
    for (int k = 0; k < 6; ++k) out[k] = v_[k];
  }

 private:
  dReal v_[6] = {0, 0, 0, 0, 0, 0};
#endif
};

}  // namespace

ContactSolverSettings ContactSolverSettings::Of(dWorldID world) {
  ContactSolverSettings s;
  s.erp = dWorldGetERP(world);
  s.cfm = dWorldGetCFM(world);
  s.surface_layer = dWorldGetContactSurfaceLayer(world);
  s.max_correcting_velocity = dWorldGetContactMaxCorrectingVel(world);
  s.sor_w = dWorldGetQuickStepW(world);
  return s;
}

StaticContactLog::BodyContacts& StaticContactLog::Of(dBodyID body) {
  if (last_ < bodies_.size() && bodies_[last_].body == body) return bodies_[last_];
  for (last_ = 0; last_ < bodies_.size(); ++last_) {
    if (bodies_[last_].body == body) return bodies_[last_];
  }
  bodies_.push_back({body, -1, false});
  listed_ |= ListedBit(body);
  return bodies_.back();
}

void StaticContactLog::MakeJoint(std::size_t index) {
  const LoggedContact& c = contacts_[index];
  dJointID joint = dJointCreateContact(world_, group_, &c.contact);
  // The contact's place in the log, plus one: a joint's data is null until set.
  dJointSetData(joint, reinterpret_cast<void*>(static_cast<std::uintptr_t>(index + 1)));
  if (c.other) {
    dJointAttach(joint, c.body, c.other);
  } else {
    dJointAttach(joint, c.reversed ? nullptr : c.body, c.reversed ? c.body : nullptr);
  }
}

void StaticContactLog::Make(const dContact& contact, dBodyID a, dBodyID b) {
  if (!keep_) {
    dJointAttach(dJointCreateContact(world_, group_, &contact), a, b);
    return;
  }
  if (a && b) {
    Join(a);
    Join(b);
    LoggedContact& linked = contacts_.emplace_back(contact);
    linked.body = a;
    linked.other = b;
    MakeJoint(contacts_.size() - 1);
    return;
  }
  dBodyID body = a ? a : b;
  BodyContacts& owner = Of(body);
  // Built in place: a contact is 300 bytes, and a temporary would copy it twice.
  LoggedContact& kept = contacts_.emplace_back(contact);
  kept.body = body;
  kept.reversed = a == nullptr;
  kept.previous = owner.newest;
  owner.newest = static_cast<int>(contacts_.size()) - 1;
  if (owner.joined) MakeJoint(contacts_.size() - 1);
}

void StaticContactLog::Join(dBodyID body) {
  BodyContacts& owner = Of(body);
  if (owner.joined) return;
  owner.joined = true;
  // Oldest first: the log holds every body's contacts in the order they came.
  for (int i = 0; i <= owner.newest; ++i) {
    const LoggedContact& c = contacts_[static_cast<std::size_t>(i)];
    if (c.body == body && !c.other) MakeJoint(static_cast<std::size_t>(i));
  }
}

const LoggedContact* StaticContactLog::Made(dJointID joint) const {
  const auto tag = reinterpret_cast<std::uintptr_t>(dJointGetData(joint));
  if (tag == 0 || tag > contacts_.size() || dJointGetType(joint) != dJointTypeContact) return nullptr;
  return &contacts_[tag - 1];
}

const LoggedContact* StaticContactLog::Kept(dBodyID body) const {
  if (!(listed_ & ListedBit(body))) return nullptr;  // no contact of its own this step
  for (const BodyContacts& b : bodies_) {
    if (b.body == body) return b.joined || b.newest < 0 ? nullptr : &contacts_[static_cast<std::size_t>(b.newest)];
  }
  return nullptr;
}

bool IsStaticContactIsland(dBodyID body, const StaticContactLog& log) {
  return IsStaticContactIsland(body, log.Kept(body));
}

bool IsStaticContactIsland(dBodyID body, const LoggedContact* kept) {
  return kept && dBodyGetJoint(body, 0) == nullptr && StepsAsQuickStepsAFreeBody(body);
}

// Everything below follows ODE 0.16's order of operations (joints/contact.cpp, quickstep.cpp)
// with ODE's own inline helpers: any other order changes the last bits.
void ContactIslandStepper::AddContactRows(const LoggedContact& sc, const dReal* position, const dReal* linear,
                                          const dReal* angular, const ContactSolverSettings& settings, dReal fps) {
  dSurfaceParameters s = sc.contact.surface;  // getInfo1 clamps the friction coefficients in place
  const int m = ContactRowCount(s);
  const std::size_t first = row_count_;
  row_count_ += static_cast<std::size_t>(m);
  if (rows_.size() < row_count_) rows_.resize(2 * row_count_);  // grown, never shrunk: no per-step fill
  WriteContactRows(sc.contact, s, sc.reversed, m, &rows_[first], ContactBody{position, linear, angular}, nullptr,
                   settings, fps, static_cast<int>(first));
}

void ContactIslandStepper::Step(dBodyID body, const StaticContactLog& log, const dReal* gravity,
                                const ContactSolverSettings& settings, int iterations, dReal dt) {
  Step(body, *log.Kept(body), log, gravity, settings, iterations, dt);
}

void ContactIslandStepper::Step(dBodyID body, const LoggedContact& newest, const StaticContactLog& log,
                                const dReal* gravity, const ContactSolverSettings& settings, int iterations, dReal dt) {
  // Stage 0: gravity, the world-frame inverse inertia, the gyroscopic torque.
  FreeBodyStart b;
  StartConstrainedBodyStep(body, gravity, inverse_inertia_, dt, b);
  const dReal inverse_mass = b.inverse_mass;
  const dReal* inverse_inertia = b.inverse_inertia;
  dReal* linear = b.linear;
  dReal* angular = b.angular;

  // Stage 2: the rows, joint by joint in the body's list (QuickStep's island order), and the
  // right-hand side c/h - J·(v/h + M⁻¹·f).
  const dReal fps = dRecip(dt);
  row_count_ = 0;
  const dReal* position = b.storage.position;
  // Newest first: the order of the body's joint list, had they been ODE joints.
  for (const LoggedContact* c = &newest; c; c = c->previous >= 0 ? &log.At(c->previous) : nullptr) {
    AddContactRows(*c, position, linear, angular, settings, fps);
  }
  dReal rhs_tmp[6];
  UnconstrainedVelocityTerm(b, fps, rhs_tmp);

  // Then, row by row (QuickStep does each stage for all rows, but no row depends on another):
  // J·rhs_tmp into the right-hand side, M⁻¹·Jᵀ, and the row scaled by its relaxed diagonal.
  const int m = static_cast<int>(row_count_);
  for (int i = 0; i < m; ++i) {
    Row& r = rows_[static_cast<std::size_t>(i)];
    dReal sum = 0;
    for (int k = 0; k < 6; ++k) sum += r.j[k] * rhs_tmp[k];
    r.rhs += sum;
    for (int k = 0; k < 3; ++k) r.imj[k] = inverse_mass * r.j[k];
    dMultiply0_331(r.imj + 3, inverse_inertia, r.j + 3);
    dReal diagonal = 0;
    for (int k = 0; k < 6; ++k) diagonal += r.imj[k] * r.j[k];
    const dReal ad = settings.sor_w / (diagonal + r.cfm);
    r.cfm = r.cfm * ad;
    r.rhs *= ad;
    for (dReal& v : r.j) v *= ad;
    r.lambda = 0;
  }
  // Stage 4: unbounded rows first, then the SOR sweeps. QuickStep shuffles the order before
  // every eighth sweep after the first eight, with ODE's generator.
  UnboundedFirst(rows_, m, order_);
  ConstraintVelocity fc;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    ShuffleIfDue(iteration, order_);
    for (const int index : order_) {
      Row& r = rows_[static_cast<std::size_t>(index)];
      const dReal delta = ClampedUpdate(r, rows_.data(), r.rhs - r.lambda * r.cfm - fc.Dot(r.j));
      if (delta != 0) fc.Add(delta, r.imj);
    }
  }
  dReal velocity_change[6];
  fc.Store(velocity_change);

  // Stage 4b: the constraint forces' velocity change; then the body's step as a free body's.
  FinishConstrainedBodyStep(body, b, velocity_change, dt);
}

}  // namespace ubersim::kernel
