// SPDX-License-Identifier: Apache-2.0
// The world the transport fuzz targets decode against: six robots a team (ids 0..5) on a
// Division B carpet, blue 0 with the ball at its dribbler.
#pragma once

#include <ubersim/world_state.hpp>

namespace ubersim::fuzz {

constexpr int kRobotsPerTeam = 6;
constexpr double kHalfCarpetLength = 5.0;  // m (Division B: 9 m field, 0.5 m boundary)
constexpr double kHalfCarpetWidth = 3.5;   // m (6 m field)

/// A snapshot of that world after its first step.
inline WorldSnapshot Snapshot() {
  WorldSnapshot s;
  s.step = 1;
  s.sim_time_ns = 1'000'000;
  s.ball.pose.position = Vec3(0.1, 0.0, s.ball.radius);
  for (Team team : {Team::kBlue, Team::kYellow}) {
    for (int id = 0; id < kRobotsPerTeam; ++id) {
      RobotState r;
      r.id = RobotId{team, id};
      r.pose.position = Vec3(team == Team::kBlue ? -1.0 : 1.0, 0.5 * id - 1.25, 0.0);
      r.kicker_ready = true;
      r.dribbler_ball_contact = team == Team::kBlue && id == 0;
      if (id % 2 == 0) r.drive = DriveFeedback{{1.0, -2.0, 3.0, -4.0}, Twist{}};  // feedback travels too
      s.robots.push_back(r);
    }
  }
  return s;
}

}  // namespace ubersim::fuzz
