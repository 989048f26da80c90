// SPDX-License-Identifier: Apache-2.0
// The held ball (`dribbling: held`, the league's simulate_dribbling false): once the turning
// dribbler touches the ball it stays in the mouth through what a roller loses it in (a fast
// spin, a hard brake); a kick, the dribbler stopping or a teleport lets it go; a snapshot keeps it.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "../common/edited_model_file.hpp"
#include "parts_world.hpp"
#include "ubersim/kernel/snapshot.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel {
namespace {

constexpr double kDribble = 150.0;  // rad/s

class HeldBall : public ::testing::TestWithParam<std::string> {};

INSTANTIATE_TEST_SUITE_P(Profiles, HeldBall, ::testing::ValuesIn(PhysicsProfileNames()),
                         [](const auto& info) { return info.param; });

double FromMouth(PartsWorld& w) {
  const Vec3 b = w.BallInRobotFrame();
  return std::hypot(b.x() - (w.Front() + w.BallRadius()), b.y());
}

TEST_P(HeldBall, TheBallStaysThroughAFastSpinThatARollerLosesItIn) {
  for (const bool held : {false, true}) {
    PartsWorld w(GetParam(), kModernRobot, held);
    w.Run(0.2);
    w.PlaceBallInMouth();
    w.Run(0.3, std::nullopt, std::nullopt, kDribble);
    w.Run(1.0, LocalVelocityCommand{0, 0, 10.0}, std::nullopt, kDribble);
    EXPECT_NEAR(w.Robot().twist.angular.z(), 10.0, 0.5) << "the robot did not spin";
    if (held) {
      EXPECT_LT(FromMouth(w), 0.01) << "held, the ball stays in the mouth";
    } else {
      EXPECT_GT(FromMouth(w), 0.05) << "by friction alone a 10 rad/s spin loses it (the roller's own test)";
    }
  }
}

TEST_P(HeldBall, ARobotFileMayHoldTheBallInAPhysicalWorld) {
  static const std::string held_robot =
      testing::EditedModelFile(kModernRobot, "kind: robot", "kind: robot\ndribbling: held", "ubersim-held-robot");
  PartsWorld w(GetParam(), held_robot, false);
  w.Run(0.2);
  w.PlaceBallInMouth();
  w.Run(0.3, std::nullopt, std::nullopt, kDribble);
  w.Run(1.0, LocalVelocityCommand{0, 0, 10.0}, std::nullopt, kDribble);
  EXPECT_LT(FromMouth(w), 0.01);
}

TEST_P(HeldBall, AKickLetsGoAndTheBallLeavesAtTheKickSpeed) {
  PartsWorld w(GetParam(), kModernRobot, true);
  w.Run(0.2);
  w.PlaceBallInMouth();
  w.Run(0.5, std::nullopt, std::nullopt, kDribble);
  w.Run(0.02, std::nullopt, KickCommand{4.0, 0.0}, kDribble);
  w.Run(0.1, std::nullopt, std::nullopt, kDribble);
  EXPECT_NEAR(w.BallTwist().linear.norm(), 4.0, 0.6);
  EXPECT_GT(FromMouth(w), 0.2);
}

TEST_P(HeldBall, StoppingTheDribblerLetsGo) {
  PartsWorld w(GetParam(), kModernRobot, true);
  w.Run(0.2);
  w.PlaceBallInMouth();
  w.Run(0.3, std::nullopt, std::nullopt, kDribble);
  // Driving forward and braking hard with the roller off: the ball rolls on.
  w.Run(1.0, LocalVelocityCommand{1.0, 0, 0}, std::nullopt, 0.0);
  w.Run(0.5, LocalVelocityCommand{0, 0, 0}, std::nullopt, 0.0);
  EXPECT_GT(FromMouth(w), 0.1);
}

// The hold is re-made at the ball's centre when restored: the ball goes on as before to within
// micrometres (the original joint's anchor had drifted by that much), not bit for bit.
TEST_P(HeldBall, ASnapshotKeepsTheHold) {
  PartsWorld w(GetParam(), kModernRobot, true);
  w.Run(0.2);
  w.PlaceBallInMouth();
  w.Run(0.3, std::nullopt, std::nullopt, kDribble);
  const SavedState saved = w.world->Save();
  ASSERT_TRUE(saved.ball_held_by.has_value());
  w.Run(0.5, LocalVelocityCommand{0, 0, 10.0}, std::nullopt, kDribble);
  const double after = FromMouth(w);
  w.world->Restore(saved);
  w.Run(0.5, LocalVelocityCommand{0, 0, 10.0}, std::nullopt, kDribble);
  EXPECT_LT(FromMouth(w), 0.01);
  EXPECT_NEAR(FromMouth(w), after, 2e-3);
  EXPECT_TRUE(w.world->Save().ball_held_by.has_value());
}

}  // namespace
}  // namespace ubersim::kernel
