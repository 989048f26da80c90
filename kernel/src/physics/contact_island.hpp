// SPDX-License-Identifier: Apache-2.0
// QuickStep's step of a body whose only constraints are contacts with the static world (a robot
// on its wheels' contacts with the carpet, the ball rolling on it), done by the kernel, bit for
// bit as ODE does it.
#pragma once

#include <cstdint>
#include <vector>

#include <ode/ode.h>

#include "physics/lone_body.hpp"

namespace ubersim::kernel {

/// A contact of one body with the static world as the kernel gave it to ODE. ODE keeps its own
/// copy inside the joint and gives none back; ContactIslandStepper writes the contact's
/// constraint rows from this one.
struct StaticContact {
  dContact contact{};     ///< as passed to dJointCreateContact
  bool reversed = false;  ///< the body was attached second: ODE turns the normal round
};

/// The static contacts of one step, each tied to its joint (the joint's user data holds its
/// place in the log) until Clear, which goes with emptying the contact joint group.
class StaticContactLog {
 public:
  /// Keeps `contact` for `joint`, a contact joint between one body and the static world.
  void Record(dJointID joint, const dContact& contact, bool reversed) {
    contacts_.push_back(StaticContact{contact, reversed});
    dJointSetData(joint, reinterpret_cast<void*>(static_cast<std::uintptr_t>(contacts_.size())));
  }
  /// Forgets every contact: call with the joints' destruction.
  void Clear() { contacts_.clear(); }
  /// The contact recorded for `joint`, or null (not a contact this log kept).
  const StaticContact* Of(dJointID joint) const {
    if (dJointGetType(joint) != dJointTypeContact) return nullptr;
    const auto place = reinterpret_cast<std::uintptr_t>(dJointGetData(joint));
    return place > 0 && place <= contacts_.size() ? &contacts_[place - 1] : nullptr;
  }

 private:
  std::vector<StaticContact> contacts_;
};

/// The world's settings a contact's rows and QuickStep's solver read, taken once a step.
struct ContactSolverSettings {
  dReal erp = 0.2;                       ///< dWorldGetERP
  dReal cfm = 1e-5;                      ///< dWorldGetCFM
  dReal surface_layer = 0;               ///< dWorldGetContactSurfaceLayer, m
  dReal max_correcting_velocity = 0;     ///< dWorldGetContactMaxCorrectingVel, m/s
  dReal sor_w = 1.3;                     ///< dWorldGetQuickStepW
  /// The settings of `world`.
  static ContactSolverSettings Of(dWorldID world);
};

/// Whether `body` is an island ContactIslandStepper steps as QuickStep would: a body the kernel
/// can step freely (StepsAsQuickStepsAFreeBody) with at least one joint, every joint an enabled
/// contact with the static world that `log` kept.
bool IsStaticContactIsland(dBodyID body, const StaticContactLog& log);

/// Steps static-contact islands (IsStaticContactIsland) the way ODE 0.16's QuickStep steps a
/// one-body island, floating-point operation for floating-point operation: the contact joints'
/// rows (contact.cpp's getInfo1 and getInfo2), the right-hand side, the SOR-LCP sweeps in
/// QuickStep's row order (its shuffle every eighth sweep drawing from ODE's generator as it
/// does), then the body's step as LoneBodyStepper's. What it saves is QuickStep's machinery
/// around an island, most of a wheel robot's step. tests/unit/physics/contact_island_test.cpp
/// compares it with QuickStep.
class ContactIslandStepper {
 public:
  /// QuickStep shuffles its rows before this sweep and every eighth after (0-based): a step of
  /// fewer sweeps draws nothing from ODE's generator.
  static constexpr int kFirstShuffle = 8;
  /// One step of `body` (IsStaticContactIsland with `log`) by `dt` seconds under `gravity` (the
  /// world's, m/s²), with `iterations` SOR sweeps and the world's `settings`.
  void Step(dBodyID body, const StaticContactLog& log, const dReal* gravity, const ContactSolverSettings& settings,
            int iterations, dReal dt);

 private:
  // One constraint row, as QuickStep lays it out: the Jacobian (linear, angular) and its
  // inverse-mass image, right-hand side, mixing, bounds, friction index, and its multiplier.
  struct Row {
    dReal j[6];
    dReal imj[6];
    dReal rhs;
    dReal cfm;
    dReal lo;
    dReal hi;
    dReal lambda;
    int findex;
  };
  // getInfo1 and getInfo2 of `c` for the body at `position` moving at `linear`/`angular`: its
  // rows appended after the row_count_ of rows_, indices global.
  void AddContactRows(const StaticContact& c, const dReal* position, const dReal* linear, const dReal* angular,
                      const ContactSolverSettings& settings, dReal fps);

  InverseInertiaCache inverse_inertia_;
  std::vector<Row> rows_;       // the first row_count_ are this step's
  std::size_t row_count_ = 0;
  std::vector<int> order_;
};

}  // namespace ubersim::kernel
