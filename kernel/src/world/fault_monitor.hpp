// SPDX-License-Identifier: Apache-2.0
// How a world watches its plugins: the fault record, the last good body states a fault is
// repaired from, and the checks for non-finite values (the public half is kernel/fault.hpp).
#pragma once

#include <cstdint>
#include <exception>
#include <string>
#include <vector>

#include "ubersim/log.hpp"
#include "ubersim/kernel/fault.hpp"
#include "physics/scene_graph.hpp"

namespace ubersim::kernel {

/// Collects a world's plugin faults. Reports each one once to the log, with the policy's
/// consequence, and tells the world when the policy asks it to stop.
class FaultMonitor {
 public:
  FaultMonitor(FaultPolicy policy, Log& log) : policy_(policy), log_(log) {}
  /// The step being run and its start time, stamped on faults reported from now on.
  void SetNow(std::int64_t step, std::int64_t sim_time_ns) {
    step_ = step;
    time_ns_ = sim_time_ns;
  }
  /// Records and logs a fault (the caller has already switched the plugin off).
  void Report(PluginFault fault);
  /// The world file's policy.
  FaultPolicy policy() const { return policy_; }
  /// True once a fault happened under the stop policy since the world was built, reset or
  /// restored (faults that came with a restored snapshot stop nothing: that world carries on).
  bool stop_requested() const { return policy_ == FaultPolicy::kStop && faults_.size() > restored_; }
  /// Every fault so far, oldest first (a restored snapshot's first).
  const std::vector<PluginFault>& faults() const { return faults_; }
  /// Replaces the record with a restored snapshot's, without logging.
  void Restore(std::vector<PluginFault> faults) {
    faults_ = std::move(faults);
    restored_ = faults_.size();
  }
  /// Forgets every fault (world reset).
  void Clear() {
    faults_.clear();
    restored_ = 0;
  }

 private:
  FaultPolicy policy_;
  Log& log_;
  std::int64_t step_ = 0;
  std::int64_t time_ns_ = 0;
  std::vector<PluginFault> faults_;
  std::size_t restored_ = 0;  // faults_[0, restored_) came with a restored snapshot
};

/// Body states the kernel last found finite: what a body made non-finite is put back to. Reads
/// ODE's storage through pointers taken once, so recording a world is a copy, not calls.
class LastGoodState {
 public:
  /// Tracks every body of `root`'s subtree from now on and records them (after a build, a
  /// reset or a restore; earlier records are dropped).
  void Track(const NodeImpl& root);
  /// Records every tracked body (pose and velocities) when all are finite; otherwise records
  /// nothing and returns false, keeping the previous record to repair from.
  bool CaptureIfFinite();
  /// Puts `body` back as last recorded, with no force or torque accumulated; false when it is
  /// not tracked (a body added since).
  bool Restore(BodyImpl& body) const;
  /// True when every tracked body's pose and velocities are finite now.
  bool AllFinite() const;

 private:
  struct Entry {
    BodyImpl* body;
    const dReal *position, *quaternion, *linear, *angular;  // ODE's storage for the body
  };
  void Put(std::size_t i) const;
  std::vector<Entry> entries_;
  std::vector<dReal> good_;     // 13 per entry: position, quaternion, linear and angular velocity
  std::vector<dReal> scratch_;  // the capture in progress, swapped in when finite
};

/// Watches bodies for what a plugin call can make non-finite through the SDK, which refuses
/// non-finite arguments: a linear velocity or an accumulated force or torque that overflows.
/// Only the calls that add to those can, and each counts a sum it left non-finite
/// (BodyImpl::non_finite_sums), so a check after a call reads one counter, and looks at the
/// values (nine additions per watched body, reading ODE's storage directly) only when it moved.
class BodyWatch {
 public:
  /// Watches `body` too (all watched bodies belong to one scene graph).
  void Add(const BodyImpl& body);
  /// True when every watched value is finite (without looking, when no body of the scene graph
  /// was left with a non-finite sum since a check that found them finite).
  bool AllFinite() { return !non_finite_sums_ || checked_ == *non_finite_sums_ || Recheck(); }

 private:
  bool Recheck();  // AllFinite's look at the values
  std::vector<const dReal*> vectors_;  // 3 values each
  const std::uint64_t* non_finite_sums_ = nullptr;  // the scene graph's counter
  // Its value when last found finite; kNeverChecked (a count it never reaches) before that.
  static constexpr std::uint64_t kNeverChecked = ~std::uint64_t{0};
  std::uint64_t checked_ = kNeverChecked;
};

/// The first non-finite value of a body (position, orientation, velocities, accumulated force
/// and torque), as "force (nan, 0, 0)"; empty when all are finite.
std::string NonFiniteIn(const BodyImpl& body);
/// The first non-finite body value or joint motor setting in `node`'s subtree, as
/// "blue/3/wheel0/wheel: linear velocity (inf, 0, 0)"; empty when all are finite.
std::string FindNonFinite(const NodeImpl& node);
/// Repairs every body of `node`'s subtree with a non-finite value: pose and velocities back to
/// `last_good`, force and torque cleared. Returns how many bodies it repaired.
int RepairNonFinite(const NodeImpl& node, const LastGoodState& last_good);

/// "std::out_of_range: vector::_M_range_check: …": the exception's type and text.
std::string ExceptionText(const std::exception& e);

/// Stops a joint's motor (target speed 0, its torque limit kept), as a robot's firmware stops
/// the motors its dead controller no longer commands. Joints without a motor are left alone.
void StopMotor(const JointImpl& joint);

}  // namespace ubersim::kernel
