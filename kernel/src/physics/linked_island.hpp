// SPDX-License-Identifier: Apache-2.0
// QuickStep's step of an island of bodies linked only by contacts (the ball against a one-body
// robot, two one-body robots pushing), done by the kernel, bit for bit as ODE does it.
#pragma once

#include <cstddef>
#include <vector>

#include <ode/ode.h>

#include "physics/contact_island.hpp"
#include "physics/free_body_start.hpp"

namespace ubersim::kernel {

/// Steps islands whose every joint is a contact StaticContactLog made (Made) and whose every body
/// the kernel can step freely (StepsAsQuickStepsAFreeBody), the way ODE 0.16's QuickStep steps
/// them, floating-point operation for floating-point operation: its island search's body and
/// joint order, each contact's rows (both bodies' Jacobians), the right-hand side, the SOR-LCP
/// sweeps in QuickStep's row order (its shuffle every eighth sweep drawing from ODE's generator
/// as it does), then each body's step as LoneBodyStepper's, in the island's order. What it
/// saves is QuickStep's machinery around an island, not its sweeps: in bench's Div A play with
/// one-body robots, 12.4 K instructions a step where QuickStep spent 17.8 K (docs/performance.md).
/// tests/unit/physics/contact_island_test.cpp compares it with QuickStep.
///
/// A step gathers its islands first (Gather), then steps each (Step): the kernel's own islands
/// are stepped between QuickStep's, in QuickStep's island order.
class LinkedIslandStepper {
 public:
  /// Forgets the islands gathered: call before a pass gathers its own.
  void Clear() {
    bodies_.clear();
    joints_.clear();
    islands_.clear();
  }
  /// Gathers the island QuickStep's search would make from `start` (an enabled body with a joint)
  /// and returns its index, or -1 (gathering nothing) when the kernel cannot step it: a joint
  /// the log did not make, a joint with feedback, or a body not free (disabled, kinematic,
  /// damped...).
  int Gather(dBodyID start, const StaticContactLog& log);
  /// The bodies of island `island`, in QuickStep's order (its search's).
  const dBodyID* BodiesBegin(int island) const { return bodies_.data() + islands_[Index(island)].first_body; }
  const dBodyID* BodiesEnd(int island) const { return BodiesBegin(island) + islands_[Index(island)].body_count; }
  /// One step of island `island` by `dt` seconds under `gravity` (the world's, m/s²), with
  /// `iterations` SOR sweeps and the world's `settings`.
  void Step(int island, const dReal* gravity, const ContactSolverSettings& settings, int iterations, dReal dt);

 private:
  static std::size_t Index(int island) { return static_cast<std::size_t>(island); }
  // A constraint row as QuickStep lays it out: both bodies' Jacobians and their inverse-mass
  // images beside the row's terms, and the bodies (b2 -1: the static world).
  struct Row : RowTerms {
    dReal j[6];
    dReal j2[6];
    dReal imj[6];
    dReal imj2[6];
    int b1;
    int b2;
    dReal* f1;  // the sweeps' M⁻¹·Jᵀ·λ of body b1 (fc_'s), and of b2 (null: the static world)
    dReal* f2;
  };
  struct Island {
    std::size_t first_body;
    std::size_t body_count;
    std::size_t first_joint;
    std::size_t joint_count;
  };
  // The index of `body` among the island's (its first at `first`).
  int BodyIndex(dBodyID body, std::size_t first, std::size_t count) const;

  std::vector<dBodyID> bodies_;               // every island's, in order
  std::vector<const LoggedContact*> joints_;  // every island's, in order
  std::vector<Island> islands_;
  std::vector<dBodyID> stack_;                // Gather's search
  std::vector<dJointID> crossed_;             // and the joints it has crossed
  InverseInertiaCache inverse_inertia_;
  std::vector<FreeBodyStart> starts_;         // Step's bodies
  std::vector<dReal> rhs_tmp_;                // 6 per body
  std::vector<dReal> fc_;                     // 6 per body: M⁻¹·Jᵀ·λ
  std::vector<Row> rows_;                     // the first row_count_ are this step's
  std::size_t row_count_ = 0;
  std::vector<int> order_;
};

}  // namespace ubersim::kernel
