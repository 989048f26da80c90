// SPDX-License-Identifier: Apache-2.0
#include "world/fault_monitor.hpp"

#include <cxxabi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <typeinfo>

namespace ubersim::kernel {
namespace {

bool Finite(const dReal* v, int n) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return false;
  }
  return true;
}

std::string Values(const dReal* v, int n) {
  std::string out = "(";
  for (int i = 0; i < n; ++i) {
    char text[32];
    std::snprintf(text, sizeof text, "%s%.6g", i ? ", " : "", static_cast<double>(v[i]));
    out += text;
  }
  return out + ")";
}

// The motor settings of a joint that has a motor: (velocity, max effort); false otherwise.
bool MotorOf(const JointImpl& joint, dReal& velocity, dReal& max_effort) {
  const dJointID j = joint.id();
  switch (joint.Kind()) {
    case JointKind::kHinge:
      velocity = dJointGetHingeParam(j, dParamVel);
      max_effort = dJointGetHingeParam(j, dParamFMax);
      return true;
    case JointKind::kSlider:
      velocity = dJointGetSliderParam(j, dParamVel);
      max_effort = dJointGetSliderParam(j, dParamFMax);
      return true;
    case JointKind::kUniversal:
      velocity = dJointGetUniversalParam(j, dParamVel);
      max_effort = dJointGetUniversalParam(j, dParamFMax);
      return true;
    default: return false;
  }
}

std::string FindIn(const NodeImpl& node, const std::string& prefix) {
  for (const auto& b : node.bodies()) {
    const std::string bad = NonFiniteIn(*b);
    if (!bad.empty()) return prefix + b->Name() + ": " + bad;
  }
  for (const auto& j : node.joints()) {
    dReal motor[2];
    if (MotorOf(*j, motor[0], motor[1]) && !Finite(motor, 2)) {
      return prefix + j->Name() + ": motor (velocity, max effort) " + Values(motor, 2);
    }
  }
  for (const auto& c : node.children()) {
    std::string bad = FindIn(*c, prefix + c->Name() + "/");
    if (!bad.empty()) return bad;
  }
  return {};
}

}  // namespace

FaultPolicy ParseFaultPolicy(const std::string& name) {
  if (name == "disable") return FaultPolicy::kDisable;
  if (name == "stop") return FaultPolicy::kStop;
  throw std::invalid_argument("unknown on_plugin_fault '" + name + "' (disable, stop)");
}

const char* ToString(FaultPolicy policy) { return policy == FaultPolicy::kStop ? "stop" : "disable"; }

std::string PluginFault::Describe() const {
  std::string who = robot ? "robot " + ToString(*robot) : "world";
  if (!plugin.empty()) {
    who = (robot ? who + " " : std::string()) + ToString(kind) + " '" + plugin + "'";
    if (!file.empty()) who += " (" + file + ")";
  }
  return who + ": " + (phase.empty() ? what : phase + " " + what);
}

void FaultMonitor::Report(PluginFault fault) {
  fault.step = step_;
  fault.sim_time_ns = time_ns_;
  std::string consequence;
  if (fault.plugin.empty()) {
    consequence = "put back to its last good state";
  } else {
    consequence = std::string("this ") + ToString(fault.kind) + " is switched off";
  }
  consequence += policy_ == FaultPolicy::kStop ? "; the world stops after this step (on_plugin_fault: stop)"
                                               : "; the world carries on without it (on_plugin_fault: disable)";
  log_.Error("plugin fault at step " + std::to_string(fault.step) + ": " + fault.Describe() + "; " + consequence);
  faults_.push_back(std::move(fault));
}

void LastGoodState::Track(const NodeImpl& root) {
  entries_.clear();
  root.ForEachBody([this](BodyImpl& b) {
    const dBodyID id = b.id();
    entries_.push_back(Entry{&b, dBodyGetPosition(id), dBodyGetQuaternion(id), dBodyGetLinearVel(id),
                             dBodyGetAngularVel(id)});
  });
  good_.assign(13 * entries_.size(), 0);
  scratch_.assign(13 * entries_.size(), 0);
  CaptureIfFinite();
}

bool LastGoodState::AllFinite() const {
  // NaN and infinity survive a sum: one test over everything (four sums the processor overlaps).
  dReal p = 0, q = 0, v = 0, w = 0;
  for (const Entry& e : entries_) {
    p += e.position[0] + e.position[1] + e.position[2];
    q += e.quaternion[0] + e.quaternion[1] + e.quaternion[2] + e.quaternion[3];
    v += e.linear[0] + e.linear[1] + e.linear[2];
    w += e.angular[0] + e.angular[1] + e.angular[2];
  }
  if (std::isfinite(p + q + v + w)) return true;
  // Finite values can still add up to infinity; only a real non-finite one counts.
  for (const Entry& e : entries_) {
    if (!Finite(e.position, 3) || !Finite(e.quaternion, 4) || !Finite(e.linear, 3) || !Finite(e.angular, 3)) {
      return false;
    }
  }
  return true;
}

bool LastGoodState::CaptureIfFinite() {
  // One pass: copy into the scratch record while summing, keep it only when sound.
  dReal sum = 0;
  dReal* out = scratch_.data();
  for (const Entry& e : entries_) {
    for (const dReal* from : {e.position, e.linear, e.angular}) {
      out[0] = from[0];
      out[1] = from[1];
      out[2] = from[2];
      sum += out[0] + out[1] + out[2];
      out += 3;
    }
    for (int i = 0; i < 4; ++i) out[i] = e.quaternion[i];
    sum += out[0] + out[1] + out[2] + out[3];
    out += 4;
  }
  if (!std::isfinite(sum)) {
    for (dReal x : scratch_) {
      if (!std::isfinite(x)) return false;
    }
  }
  good_.swap(scratch_);
  return true;
}

bool LastGoodState::Restore(BodyImpl& body) const {
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    if (entries_[i].body != &body) continue;
    Put(i);
    return true;
  }
  return false;
}

void LastGoodState::Put(std::size_t i) const {
  const dBodyID id = entries_[i].body->id();
  const dReal* s = good_.data() + 13 * i;  // position, linear, angular, quaternion
  dBodySetPosition(id, s[0], s[1], s[2]);
  dBodySetLinearVel(id, s[3], s[4], s[5]);
  dBodySetAngularVel(id, s[6], s[7], s[8]);
  dBodySetQuaternion(id, s + 9);
  dBodySetForce(id, 0, 0, 0);
  dBodySetTorque(id, 0, 0, 0);
}

void BodyWatch::Add(const BodyImpl& body) {
  const dBodyID id = body.id();
  // What the SDK's finite-only calls can still overflow: the linear velocity (ApplyImpulse) and
  // the accumulated force and torque (AddForce, AddForceAtPoint, AddTorque). Pose and angular
  // velocity are only ever set to finite values.
  for (const dReal* v : {dBodyGetLinearVel(id), dBodyGetForce(id), dBodyGetTorque(id)}) {
    vectors_.push_back(v);
  }
  non_finite_sums_ = &body.non_finite_sums();
  checked_ = kNeverChecked;
}

bool BodyWatch::Recheck() {
  const std::uint64_t sums = *non_finite_sums_;
  // Three sums, one per component: independent additions the processor overlaps.
  dReal x = 0, y = 0, z = 0;
  for (const dReal* v : vectors_) {
    x += v[0];
    y += v[1];
    z += v[2];
  }
  if (!std::isfinite(x + y + z)) {
    for (const dReal* v : vectors_) {
      if (!Finite(v, 3)) return false;
    }
  }  // else finite values whose sum overflowed
  checked_ = sums;
  return true;
}

std::string NonFiniteIn(const BodyImpl& body) {
  const dBodyID id = body.id();
  const struct {
    const char* name;
    const dReal* values;
    int n;
  } fields[] = {{"position", dBodyGetPosition(id), 3},    {"orientation", dBodyGetQuaternion(id), 4},
                {"linear velocity", dBodyGetLinearVel(id), 3}, {"angular velocity", dBodyGetAngularVel(id), 3},
                {"force", dBodyGetForce(id), 3},          {"torque", dBodyGetTorque(id), 3}};
  for (const auto& f : fields) {
    if (!Finite(f.values, f.n)) return std::string(f.name) + " " + Values(f.values, f.n);
  }
  return {};
}

std::string FindNonFinite(const NodeImpl& node) { return FindIn(node, node.Path().empty() ? "" : node.Path() + "/"); }

int RepairNonFinite(const NodeImpl& node, const LastGoodState& last_good) {
  int repaired = 0;
  node.ForEachBody([&](BodyImpl& b) {
    if (NonFiniteIn(b).empty()) return;
    if (!last_good.Restore(b)) {
      // Added after the last capture: nothing to go back to, so it stops where it was (at the
      // origin when even that is lost).
      const dBodyID id = b.id();
      if (!Finite(dBodyGetPosition(id), 3)) dBodySetPosition(id, 0, 0, 0);
      if (!Finite(dBodyGetQuaternion(id), 4)) {
        const dQuaternion identity = {1, 0, 0, 0};
        dBodySetQuaternion(id, identity);
      }
      dBodySetLinearVel(id, 0, 0, 0);
      dBodySetAngularVel(id, 0, 0, 0);
      dBodySetForce(id, 0, 0, 0);
      dBodySetTorque(id, 0, 0, 0);
    }
    ++repaired;
  });
  return repaired;
}

std::string ExceptionText(const std::exception& e) {
  const char* mangled = typeid(e).name();
  int status = -1;
  const std::unique_ptr<char, void (*)(void*)> name(abi::__cxa_demangle(mangled, nullptr, nullptr, &status), std::free);
  return std::string(status == 0 && name ? name.get() : mangled) + ": " + e.what();
}

void StopMotor(const JointImpl& joint) {
  dReal velocity, max_effort;
  if (!MotorOf(joint, velocity, max_effort)) return;
  if (!std::isfinite(max_effort) || max_effort < 0) max_effort = 0;
  const dJointID j = joint.id();
  switch (joint.Kind()) {
    case JointKind::kHinge:
      dJointSetHingeParam(j, dParamVel, 0);
      dJointSetHingeParam(j, dParamFMax, max_effort);
      break;
    case JointKind::kSlider:
      dJointSetSliderParam(j, dParamVel, 0);
      dJointSetSliderParam(j, dParamFMax, max_effort);
      break;
    case JointKind::kUniversal:
      dJointSetUniversalParam(j, dParamVel, 0);
      dJointSetUniversalParam(j, dParamFMax, max_effort);
      break;
    default: break;
  }
}

}  // namespace ubersim::kernel
