// SPDX-License-Identifier: Apache-2.0
#include "ubersim/kernel/island_stepper.hpp"

#include <algorithm>

namespace ubersim::kernel {

void IslandStepper::SetIterations(int ball_islands, int other_islands) {
  ball_iterations_ = std::max(1, ball_islands);
  other_iterations_ = std::max(1, other_islands);
}

bool IslandStepper::InBallIslands(dBodyID b) const {
  // A ball's island is a handful of bodies (the ball, a robot or two): a scan beats a hash set.
  return std::find(ball_islands_.begin(), ball_islands_.end(), b) != ball_islands_.end();
}

void IslandStepper::FindBallIslands(const std::vector<dBodyID>& balls) {
  ball_islands_.clear();
  for (dBodyID ball : balls) {
    if (!InBallIslands(ball)) ball_islands_.push_back(ball);
  }
  // Breadth first over the growing list: the same links QuickStep's island search follows.
  for (std::size_t next = 0; next < ball_islands_.size(); ++next) {
    dBodyID b = ball_islands_[next];
    const int joints = dBodyGetNumJoints(b);
    for (int i = 0; i < joints; ++i) {
      dJointID j = dBodyGetJoint(b, i);
      if (!dJointIsEnabled(j)) continue;
      for (int side = 0; side < 2; ++side) {
        dBodyID other = dJointGetBody(j, side);
        if (other && !InBallIslands(other)) ball_islands_.push_back(other);
      }
    }
  }
}

void IslandStepper::Step(dWorldID world, const std::vector<dBodyID>& bodies, const std::vector<dBodyID>& balls,
                         double dt) {
  if (ball_iterations_ == other_iterations_ || balls.empty()) {
    dWorldSetQuickStepNumIterations(world, ball_iterations_);
    dWorldQuickStep(world, dt);
    return;
  }
  FindBallIslands(balls);
  // First the ball's islands: every other body sits this pass out. Islands are disconnected, so
  // QuickStep's search from the enabled bodies never reaches a paused one.
  paused_.clear();
  for (dBodyID b : bodies) {
    if (dBodyIsEnabled(b) && !InBallIslands(b)) {
      dBodyDisable(b);
      paused_.push_back(b);
    }
  }
  dWorldSetQuickStepNumIterations(world, ball_iterations_);
  dWorldQuickStep(world, dt);
  for (dBodyID b : paused_) dBodyEnable(b);

  // Then the rest, the ball's islands (stepped now) sitting out. QuickStep may have enabled a
  // disabled body a ball's island reached, as one QuickStep would have: it stays enabled.
  paused_.clear();
  for (dBodyID b : ball_islands_) {
    if (dBodyIsEnabled(b)) {
      dBodyDisable(b);
      paused_.push_back(b);
    }
  }
  dWorldSetQuickStepNumIterations(world, other_iterations_);
  dWorldQuickStep(world, dt);
  for (dBodyID b : paused_) dBodyEnable(b);
}

}  // namespace ubersim::kernel
