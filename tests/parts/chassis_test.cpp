// SPDX-License-Identifier: Apache-2.0
// The chassis is a cylinder cut flat at front_distance: a ball rolled at the front comes to the
// flat face (inside the full cylinder's outline) and no further; at the side the round shell
// keeps it a radius away.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "parts_world.hpp"

namespace ubersim::kernel {
namespace {

// Rolls the ball at the robot from (x, y) in the robot frame along `dir` and returns the closest
// the ball's centre came to the robot's centre line along `dir`'s axis.
double RollAt(PartsWorld& w, double x, double y, const Vec3& dir, double speed) {
  w.PlaceBall(x, y);
  const Vec3 v = dir * speed;
  w.world->events().Post(PositionEvent{Target::Ball(), std::nullopt, std::nullopt, v,
                                       Vec3::UnitZ().cross(v) / w.BallRadius(), std::nullopt});
  double closest = 1e9;
  w.Run(0.6, std::nullopt, std::nullopt, std::nullopt, [&] {
    const Vec3 b = w.BallInRobotFrame();
    closest = std::min(closest, std::abs(dir.x()) > 0.5 ? b.x() : std::abs(b.y()));
  });
  return closest;
}

TEST(FlatFront, TheBallReachesTheFlatFaceAndStopsThere) {
  PartsWorld w;
  w.Run(0.2);
  const double face = w.Front() + w.BallRadius();  // 0.0915 m: the ball against the face
  const double closest = RollAt(w, 0.3, 0.0, Vec3(-1, 0, 0), 1.0);
  EXPECT_LT(closest, w.robot_model->body.radius + w.BallRadius() - 0.01) << "still a full cylinder";
  EXPECT_GT(closest, face - 0.003) << "the ball went into the face";
}

TEST(FlatFront, TheSidesAreStillRound) {
  PartsWorld w;
  w.Run(0.2);
  const double closest = RollAt(w, 0.0, 0.3, Vec3(0, -1, 0), 1.0);
  EXPECT_NEAR(closest, w.robot_model->body.radius + w.BallRadius(), 0.003);
}

}  // namespace
}  // namespace ubersim::kernel
