// SPDX-License-Identifier: Apache-2.0
// QuickStep with two iteration counts: one for the islands the ball belongs to, one for the rest;
// the bodies no joint touches stepped by the kernel.
#pragma once

#include <utility>
#include <vector>

#include <ode/ode.h>

#include "physics/contact_island.hpp"
#include "physics/linked_island.hpp"
#include "physics/lone_body.hpp"

namespace ubersim::kernel {

/// Flags, per body of `bodies` (newest first), each body a joint other than a contact links to a
/// body created before it: a robot's wheels and dribbler bar, which hang from its chassis, or a
/// URDF link below its parent. Following such joints from any of them ends at a body not
/// flagged, so an island search that starts only from those still reaches them all.
std::vector<char> FindLimbs(const std::vector<dBodyID>& bodies);

/// A body whose island needs at least `iterations` QuickStep iterations: a robot whose model
/// asks for more than the world's count for islands without the ball (its chassis).
struct IterationDemand {
  dBodyID body = nullptr;  ///< any body of the island
  int iterations = 1;      ///< at least this many
};

/// Steps an ODE world with QuickStep, giving the islands that hold the ball more solver iterations
/// than the others. QuickStep already solves each island (bodies linked by joints and contacts)
/// on its own; what needs many iterations is the 46 g ball pressed between a 2.5 kg robot's
/// dribbler, its front and the carpet (the mass ratio slows the solver's convergence), while a
/// robot driving on its own settles in a few. With equal counts and no limbs (Step) it is exactly
/// one QuickStep.
///
/// A body no joint touches (IsLoneBody: a one-body robot driving free, a ball in flight) is
/// stepped by LoneBodyStepper, a body touching only the static world (IsStaticContactIsland: a
/// wheel robot on its wheels' contacts, the ball on the carpet) by ContactIslandStepper, and an
/// island of free bodies linked only by contacts (the ball against a one-body robot, one-body
/// robots pushing) by LinkedIslandStepper, each bit for bit as QuickStep would; they sit
/// QuickStep out, and a pass left with nothing else calls no QuickStep at all.
class IslandStepper {
 public:
  /// QuickStep iterations for islands holding a ball, and for every other island (Step sets the
  /// world's count before each QuickStep).
  void SetIterations(int ball_islands, int other_islands);
  /// Whether the broadphase pairs geometries in the order they were told they moved (ODE's
  /// spaces do; the kernel's field and scene-graph broadphases sort by their own order). When
  /// it does not, lone bodies are stepped without first replaying QuickStep's order of telling.
  void SetMoveOrderMatters(bool matters) { move_order_matters_ = matters; }
  /// The log of the contacts with the static world the kernel's collision made (null: none):
  /// the bodies touching only those are stepped by ContactIslandStepper; the contacts of every
  /// other body it steps are made ODE joints first.
  void SetStaticContacts(StaticContactLog* log) { static_contacts_ = log; }

  /// How many islands of bodies linked by contacts the kernel has stepped (LinkedIslandStepper),
  /// over every step: what QuickStep was spared.
  std::size_t LinkedIslandsStepped() const { return linked_islands_stepped_; }

  /// One physics step of `world` (whose every body is in `bodies`) by `dt` seconds; `balls` are
  /// the balls' bodies. Bodies disabled before the step stay disabled. Lone bodies are stepped
  /// in the order of `bodies`: give them newest first, the order of ODE's own body list, for
  /// their geometries to be told they moved in the order QuickStep tells them (the broadphase
  /// lists moved geometries in that order).
  ///
  /// `limbs` (empty, or one flag per body of `bodies`: FindLimbs) marks the bodies QuickStep's
  /// island search must reach through their joints rather than start from. QuickStep solves an
  /// island's joints in the order its search meets them (at fewer than eight iterations it never
  /// shuffles them), and a search that starts from a robot's chassis meets every axle before any
  /// wheel's carpet contact: the contacts are solved last, after the axles have carried the
  /// chassis's weight to the wheels. Started from the newest wheel, as ODE's body list has it,
  /// that wheel's contact came first; at two iterations the wheel sank 10-13 mm into the carpet.
  ///
  /// `demands` raise the count of their bodies' islands: an island gets the most any of its
  /// bodies asks (a ball's island the ball's count, at least), each count one QuickStep pass,
  /// the highest first.
  void Step(dWorldID world, const std::vector<dBodyID>& bodies, const std::vector<dBodyID>& balls, double dt,
            const std::vector<char>& limbs = {}, const std::vector<IterationDemand>& demands = {});

 private:
  // Collects into ball_islands_ every body linked to a ball through enabled joints (contacts
  // included), as QuickStep's own island search does.
  void FindBallIslands(const std::vector<dBodyID>& balls);
  bool move_order_matters_ = true;
  bool InBallIslands(dBodyID b) const;
  // With demands: gives every body of `bodies` its pass (group_) and each pass its count
  // (pass_iterations_), the highest count first.
  void GroupByDemand(const std::vector<dBodyID>& bodies, const std::vector<dBodyID>& balls,
                     const std::vector<IterationDemand>& demands);
  // Steps the enabled bodies of pass `pass` (with one pass, all), the lone ones here and the
  // rest with one QuickStep of `iterations`; every other body sits the pass out.
  void Pass(dWorldID world, const std::vector<dBodyID>& bodies, int pass, int iterations, double dt);
  // Whether the index-th body of Step's list belongs to pass `pass`.
  bool InPass(std::size_t index, int pass) const { return !split_ || group_[index] == pass; }
  // Whether the index-th body of Step's list is a limb (see Step).
  bool IsLimb(std::size_t index) const { return limbs_ && (*limbs_)[index]; }
  // A pass of `iterations` >= ContactIslandStepper::kFirstShuffle with both static-contact
  // islands and QuickStep's: QuickStep called for each run of its islands between the kernel's,
  // in its island order, so that every island draws from ODE's generator where it would have.
  void InterleavedPass(dWorldID world, const std::vector<dBodyID>& bodies, int pass, int iterations, double dt);
  // Tells the geometries of every body of the pass that it moved, in the order QuickStep would
  // step them all (its island search), without moving any.
  void TouchInQuickStepOrder(const std::vector<dBodyID>& bodies, int pass);

  int ball_iterations_ = 20;
  int other_iterations_ = 20;
  bool split_ = false;                 // this step has more than one pass
  dVector3 gravity_ = {};              // the world's, read once a step
  LoneBodyStepper lone_stepper_;
  ContactIslandStepper contact_stepper_;
  LinkedIslandStepper linked_stepper_;     // its islands are this pass's
  std::size_t linked_islands_stepped_ = 0;
  StaticContactLog* static_contacts_ = nullptr;
  ContactSolverSettings settings_;     // the world's, read in a pass with static-contact islands
  struct OwnIsland {
    dBodyID body;                   // the island's first in Step's list (its only, but linked)
    const LoggedContact* contacts;  // a static-contact island's newest contact
    int linked = -1;                // else a linked island's (linked_stepper_'s); else a lone body
  };
  // Steps own island `o` (any kind), this pass's `iterations` SOR sweeps.
  void StepOwn(const OwnIsland& o, int iterations, double dt);
  // Whether `b` belongs to a linked island this pass gathered already.
  bool InLinkedIsland(dBodyID b) const;
  std::vector<dBodyID> ball_islands_;  // scratch, reused each step
  std::vector<int> group_;             // per body of Step's list: its pass
  std::vector<int> pass_iterations_;   // per pass: its QuickStep iterations
  std::vector<std::pair<dBodyID, int>> marked_;   // GroupByDemand's bodies reached, with their pass
  std::vector<IterationDemand> seeds_;  // GroupByDemand's balls and demands, highest count first
  std::vector<dBodyID> paused_;        // bodies disabled for one pass, to enable again
  std::vector<OwnIsland> own_;         // this pass's islands the kernel steps, in Step's order
  std::vector<dBodyID> walk_;          // TouchInQuickStepOrder's stack
  std::vector<dBodyID> reached_;       // and the bodies its walk has reached
  std::vector<dBodyID> held_;          // limbs disabled for QuickStep's search to reach them
  std::vector<dBodyID> segment_;       // InterleavedPass's bodies for its next QuickStep call
  const std::vector<char>* limbs_ = nullptr;  // Step's flags while it runs; none if not one per body
};

}  // namespace ubersim::kernel
