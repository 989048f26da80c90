// SPDX-License-Identifier: Apache-2.0
// QuickStep with two iteration counts: one for the islands the ball belongs to, one for the rest.
#pragma once

#include <vector>

#include <ode/ode.h>

namespace ubersim::kernel {

/// Steps an ODE world with QuickStep, giving the islands that hold the ball more solver iterations
/// than the others. QuickStep already solves each island (bodies linked by joints and contacts)
/// on its own; what needs many iterations is the 46 g ball pressed between a 2.5 kg robot's
/// dribbler, its front and the carpet (the mass ratio slows the solver's convergence), while a
/// robot driving on its own settles in a few. With equal counts it is exactly one QuickStep.
class IslandStepper {
 public:
  /// QuickStep iterations for islands holding a ball, and for every other island (Step sets the
  /// world's count before each QuickStep).
  void SetIterations(int ball_islands, int other_islands);

  /// One physics step of `world` (whose every body is in `bodies`) by `dt` seconds; `balls` are
  /// the balls' bodies. Bodies disabled before the step stay disabled.
  void Step(dWorldID world, const std::vector<dBodyID>& bodies, const std::vector<dBodyID>& balls, double dt);

 private:
  // Collects into ball_islands_ every body linked to a ball through enabled joints (contacts
  // included), as QuickStep's own island search does.
  void FindBallIslands(const std::vector<dBodyID>& balls);
  bool InBallIslands(dBodyID b) const;

  int ball_iterations_ = 20;
  int other_iterations_ = 20;
  std::vector<dBodyID> ball_islands_;  // scratch, reused each step
  std::vector<dBodyID> paused_;        // bodies disabled for one pass, to enable again
};

}  // namespace ubersim::kernel
