// SPDX-License-Identifier: Apache-2.0
#include "world/held_ball.hpp"

namespace ubersim::kernel {

void HeldBall::Attach(dWorldID world, const RobotId& robot, dBodyID chassis, dBodyID ball) {
  Release();
  // A point constraint at the ball's centre, as ER-Force's perfect dribbling: the ball stays where
  // it touched the dribbler and still turns (the roller spins it).
  joint_.reset(dJointCreateBall(world, nullptr));
  dJointAttach(joint_.get(), chassis, ball);
  const dReal* centre = dBodyGetPosition(ball);
  dJointSetBallAnchor(joint_.get(), centre[0], centre[1], centre[2]);
  holder_ = robot;
}

void HeldBall::Release() {
  joint_.reset();
  holder_.reset();
}

}  // namespace ubersim::kernel
