// SPDX-License-Identifier: Apache-2.0
// The held ball ("perfect dribbling", the league's simulate_dribbling false): once a turning
// dribbler touches the ball, a point constraint at its centre holds it to the robot until a kick, the dribbler
// stopping, a teleport or the robot leaving the field lets it go.
#pragma once

#include <optional>

#include <ode/ode.h>

#include "physics/ode_handles.hpp"
#include "ubersim/events.hpp"

namespace ubersim::kernel {

/// The joint that holds the ball to one robot, or none.
class HeldBall {
 public:
  /// The robot holding the ball.
  const std::optional<RobotId>& holder() const { return holder_; }
  /// Holds `ball` to `chassis` where they are now (lets go of any other robot first).
  void Attach(dWorldID world, const RobotId& robot, dBodyID chassis, dBodyID ball);
  /// Lets go (nothing when nobody holds it).
  void Release();

 private:
  std::optional<RobotId> holder_;
  OdeJoint joint_;
};

}  // namespace ubersim::kernel
