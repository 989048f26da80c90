// SPDX-License-Identifier: Apache-2.0
// The baseline opponent of ubersim's environments: a simple, deterministic team that a learner
// should learn to beat. The keeper keeps between the ball and its goal on the goal line, the
// robot nearest the ball takes it towards the other goal and shoots, the rest stand.
#pragma once

#include "ubersim/kernel/world.hpp"

namespace ubersim::python {

/// One team of one world played by the baseline.
class ScriptedTeam {
 public:
  /// Plays `team`, defending the goal at x = −attack_sign · length/2.
  ScriptedTeam(Team team, double attack_sign);
  /// Posts this team's commands for the next env step from the ground truth `now`.
  void Command(kernel::World& world, const WorldSnapshot& now) const;

 private:
  Team team_;
  double attack_sign_;
};

}  // namespace ubersim::python
