// SPDX-License-Identifier: Apache-2.0
// The chassis is a cylinder cut flat at front_distance: a ball rolled at the front comes to the
// flat face (inside the full cylinder's outline) and no further; at the side the round shell
// keeps it a radius away. And a robot left alone stands where it was put, level and at its
// height, as the dribbler's bar height and the kicker's reach assume. At both physics profiles.
#include <algorithm>
#include <cmath>
#include <string>

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

class FlatFront : public ::testing::TestWithParam<std::string> {};

INSTANTIATE_TEST_SUITE_P(Profiles, FlatFront, ::testing::ValuesIn(PhysicsProfileNames()),
                         [](const auto& info) { return info.param; });

TEST_P(FlatFront, TheBallReachesTheFlatFaceAndStopsThere) {
  PartsWorld w(GetParam());
  w.Run(0.2);
  const double face = w.Front() + w.BallRadius();  // 0.0915 m: the ball against the face
  const double closest = RollAt(w, 0.3, 0.0, Vec3(-1, 0, 0), 1.0);
  EXPECT_LT(closest, w.robot_model->body.radius + w.BallRadius() - 0.01) << "still a full cylinder";
  EXPECT_GT(closest, face - 0.003) << "the ball went into the face";
}

TEST_P(FlatFront, TheSidesAreStillRound) {
  PartsWorld w(GetParam());
  w.Run(0.2);
  const double closest = RollAt(w, 0.0, 0.3, Vec3(0, -1, 0), 1.0);
  EXPECT_NEAR(closest, w.robot_model->body.radius + w.BallRadius(), 0.003);
}

// A robot driving sideways into a ball at rest (about 1.5 m/s when it meets it): the ball stays
// out of the round side. With the fast-ball sweep by the ball's own speed (zero) no contact
// existed before the shell was in the ball: 3.2 mm deep at fast, measured.
TEST_P(FlatFront, ARobotDrivingIntoARestingBallDoesNotSinkIntoIt) {
  PartsWorld w(GetParam());
  w.Run(0.2);
  w.PlaceBall(0.0, 0.3);
  double closest = 1e9;
  w.Run(0.8, LocalVelocityCommand{0.0, 2.0, 0.0}, std::nullopt, std::nullopt,
        [&] { closest = std::min(closest, std::hypot(w.BallInRobotFrame().x(), w.BallInRobotFrame().y())); });
  EXPECT_GT(closest, w.robot_model->body.radius + w.BallRadius() - 0.003);
}

// Standing without commands for 2 s (its island has no ball: solver_iterations_without_ball).
// With wheel bodies the fast profile's 2 sweeps let it creep 13.4 mm, sink 6.8 mm and tip 1.5°
// nose down on its wheels' hinges (the dribbler's bar 7 mm low); contact wheels have no hinge to
// sag, and the robot's model asks 4 sweeps for its small island (it crept 0.55 mm/s at 2).
class StandingRobot : public ::testing::TestWithParam<std::string> {};

INSTANTIATE_TEST_SUITE_P(Profiles, StandingRobot, ::testing::ValuesIn(PhysicsProfileNames()),
                         [](const auto& info) { return info.param; });

TEST_P(StandingRobot, LeftAloneItStandsStillAndLevel) {
  PartsWorld w(GetParam());
  const Pose start = w.Robot().pose;
  w.Run(2.0);
  const Pose end = w.Robot().pose;
  EXPECT_LT((end.position - start.position).head<2>().norm(), 0.001) << "crept, m";
  EXPECT_LT(start.position.z() - end.position.z(), 0.001) << "sank, m";
  EXPECT_GT((end.orientation * Vec3::UnitZ()).z(), std::cos(0.5 * M_PI / 180)) << "tilted over 0.5°";
}

}  // namespace
}  // namespace ubersim::kernel
