// SPDX-License-Identifier: Apache-2.0
// What a referee sees of the field at one moment: the ball and every robot, SI, field frame.
// Built from the simulated truth (or, later, from tracked vision), so the rule engine never
// touches the world itself.
#pragma once

#include <cstdint>
#include <vector>

#include <ubersim/events.hpp>
#include <ubersim/world_state.hpp>

namespace ubersim::match {

/// A point or vector on the field, m (or m/s).
struct P2 {
  double x = 0, y = 0;  ///< field frame
};

/// One robot as the referee sees it.
struct RobotView {
  RobotId id;              ///< team and id
  bool present = true;     ///< on the field
  P2 pos;                  ///< centre, m
  P2 vel;                  ///< m/s
  double radius = 0.09;    ///< m
};

/// The field at one moment.
struct FieldView {
  std::int64_t t_ns = 0;      ///< simulated time
  P2 ball;                    ///< ball centre over the carpet, m
  double ball_z = 0;          ///< height of the ball's centre, m
  P2 ball_vel;                ///< m/s
  double ball_vz = 0;         ///< m/s
  double ball_radius = 0.0215;  ///< m
  std::vector<RobotView> robots;  ///< every robot in the world (present or not)
};

/// The referee's view of the simulated truth.
FieldView ViewOf(const WorldSnapshot& truth);

}  // namespace ubersim::match
