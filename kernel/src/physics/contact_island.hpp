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

/// A contact the log made or keeps: one body's with the static world, or two bodies' with each
/// other. ContactIslandStepper and LinkedIslandStepper write the contact's constraint rows from it.
struct LoggedContact {
  /// A contact not yet placed: its bodies, side and predecessor are set next.
  explicit LoggedContact(const dContact& c) : contact(c) {}
  dContact contact;        ///< as given to dJointCreateContact
  dBodyID body = nullptr;  ///< the joint's first body (ODE's: the one touching the static world)
  dBodyID other = nullptr; ///< its second body; null: the static world
  bool reversed = false;   ///< the body is the contact's second: ODE turns the normal round
  int previous = -1;       ///< a static contact: the body's made before this one (-1: none)
};

/// Makes a step's contact joints, and keeps a body's contacts with the static world out of ODE
/// while that body touches nothing else (the kernel steps such a body: ContactIslandStepper).
/// While it keeps them, every joint it makes carries its contact (Made), so that an island of
/// bodies linked only by the log's contacts can be stepped by the kernel (LinkedIslandStepper).
/// Every joint is made in the order its contact came, so a body QuickStep does step finds its
/// joints as it would have: a body's kept contacts become joints (Join) before any other joint
/// is made for it this step.
class StaticContactLog {
 public:
  /// Where joints are made: `world`, its contact joint group.
  void Bind(dWorldID world, dJointGroupID group) {
    world_ = world;
    group_ = group;
  }
  /// Whether a body's contacts with the static world are kept out of ODE until Join (off: every
  /// contact is an ODE joint at once, for a caller stepping with QuickStep alone). The caller
  /// that keeps them steps their bodies with IslandStepper, which joins what QuickStep steps.
  void KeepStaticContacts(bool keep) { keep_ = keep; }
  /// A contact between bodies `a` and `b` (either null: the static world, not both), attached
  /// in that order.
  void Make(const dContact& contact, dBodyID a, dBodyID b);
  /// Makes `body`'s kept contacts ODE joints, in the order they came; its later contacts are
  /// made joints at once.
  void Join(dBodyID body);
  /// The newest of `body`'s kept contacts (earlier ones through `previous`), or null: none, or
  /// made joints.
  const LoggedContact* Kept(dBodyID body) const;
  /// The contact `previous` names.
  const LoggedContact& At(int index) const { return contacts_[static_cast<std::size_t>(index)]; }
  /// The contact ODE joint `joint` was made from, or null: not a joint the log made while keeping.
  const LoggedContact* Made(dJointID joint) const;
  /// Forgets every contact: call with emptying the contact joint group.
  void Clear() {
    contacts_.clear();
    bodies_.clear();
    last_ = 0;
    listed_ = 0;
  }

 private:
  struct BodyContacts {
    dBodyID body;
    int newest;   // its newest contact with the static world, -1: none
    bool joined;  // its contacts are ODE joints
  };
  BodyContacts& Of(dBodyID body);
  // Makes contacts_[index] an ODE joint that knows it (Made).
  void MakeJoint(std::size_t index);

  dWorldID world_ = nullptr;
  dJointGroupID group_ = nullptr;
  bool keep_ = false;
  std::vector<LoggedContact> contacts_;
  std::vector<BodyContacts> bodies_;  // the bodies with contacts this step
  std::size_t last_ = 0;              // the last one asked for: a body's contacts come together
  // One bit per listed body (ListedBit): most bodies asked about have no contacts, and a bit
  // that is not set says so without the scan.
  std::uint64_t listed_ = 0;
  static std::uint64_t ListedBit(dBodyID body) {
    return std::uint64_t{1} << ((reinterpret_cast<std::uintptr_t>(body) >> 4) & 63);
  }
};

/// What a constraint row of the kernel's steppers holds beside its Jacobians: QuickStep's
/// right-hand side, constraint force mixing, bounds, friction index and multiplier.
struct RowTerms {
  dReal rhs;     ///< right-hand side (scaled by the relaxed diagonal before the sweeps)
  dReal cfm;     ///< constraint force mixing (likewise)
  dReal lo;      ///< lower bound of the multiplier
  dReal hi;      ///< upper bound (a friction row: its coefficient)
  dReal lambda;  ///< the multiplier the sweeps solve for
  int findex;    ///< a friction row's normal row, global index; -1: none
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
/// can step freely (StepsAsQuickStepsAFreeBody) with contacts `log` kept and no ODE joint.
bool IsStaticContactIsland(dBodyID body, const StaticContactLog& log);
/// The same with `kept`, the log's Kept(body), looked up already.
bool IsStaticContactIsland(dBodyID body, const LoggedContact* kept);

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
  /// The same with `newest`, the log's Kept(body), looked up already.
  void Step(dBodyID body, const LoggedContact& newest, const StaticContactLog& log, const dReal* gravity,
            const ContactSolverSettings& settings, int iterations, dReal dt);

 private:
  // One constraint row, as QuickStep lays it out: the Jacobian (linear, angular) and its
  // inverse-mass image beside the row's terms.
  struct Row : RowTerms {
    dReal j[6];
    dReal imj[6];
  };
  // getInfo1 and getInfo2 of `c` for the body at `position` moving at `linear`/`angular`: its
  // rows appended after the row_count_ of rows_, indices global.
  void AddContactRows(const LoggedContact& c, const dReal* position, const dReal* linear, const dReal* angular,
                      const ContactSolverSettings& settings, dReal fps);

  InverseInertiaCache inverse_inertia_;
  std::vector<Row> rows_;       // the first row_count_ are this step's
  std::size_t row_count_ = 0;
  std::vector<int> order_;
};

}  // namespace ubersim::kernel
