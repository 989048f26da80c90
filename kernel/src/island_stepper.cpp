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
  dWorldGetGravity(world, gravity_);
  split_ = ball_iterations_ != other_iterations_ && !balls.empty();
  if (!split_) {
    Pass(world, bodies, true, ball_iterations_, dt);
    return;
  }
  // First the ball's islands, then the rest. Islands are disconnected, so QuickStep's search
  // from the enabled bodies never reaches a paused one. QuickStep may enable a disabled body a
  // ball's island reached, as one QuickStep would have: it stays enabled for the second pass,
  // which it sits out.
  FindBallIslands(balls);
  in_ball_islands_.resize(bodies.size());
  for (std::size_t i = 0; i < bodies.size(); ++i) in_ball_islands_[i] = InBallIslands(bodies[i]);
  Pass(world, bodies, true, ball_iterations_, dt);
  Pass(world, bodies, false, other_iterations_, dt);
}

void IslandStepper::Pass(dWorldID world, const std::vector<dBodyID>& bodies, bool ball_pass, int iterations,
                         double dt) {
  paused_.clear();
  bool solve = false;  // some enabled body of this pass is linked by a joint: QuickStep's work
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    dBodyID b = bodies[i];
    if (!dBodyIsEnabled(b)) continue;
    if (split_ && static_cast<bool>(in_ball_islands_[i]) != ball_pass) {
      paused_.push_back(b);
    } else if (dBodyGetJoint(b, 0) == nullptr && IsLoneBody(b)) {  // the first test rejects most
      lone_stepper_.Step(b, gravity_, dt);
      paused_.push_back(b);  // stepped: QuickStep must not step it again
    } else {
      solve = true;
    }
  }
  if (!solve) return;
  for (dBodyID b : paused_) dBodyDisable(b);
  dWorldSetQuickStepNumIterations(world, iterations);
  dWorldQuickStep(world, dt);
  for (dBodyID b : paused_) dBodyEnable(b);
}

}  // namespace ubersim::kernel
