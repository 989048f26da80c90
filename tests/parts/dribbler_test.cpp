// SPDX-License-Identifier: Apache-2.0
// The roller dribbler on the modern robot holds the ball by contact friction alone: through a 1 m
// drive and a 90° turn at 2 rad/s, not through a fast spin, not without the roller turning; it
// reports touching the ball, spins it backwards, and leaves the robot standing still.
#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>

#include <gtest/gtest.h>

#include "../common/edited_model_file.hpp"
#include "parts_world.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel {
namespace {

constexpr double kDribble = 150.0;  // rad/s, the model's maximum

// Largest distance of the ball's centre from its resting place in the mouth while running.
struct MouthTracker {
  PartsWorld& w;
  double worst = 0.0;
  int touching = 0, steps = 0;
  void operator()() {
    const Vec3 b = w.BallInRobotFrame();
    worst = std::max(worst, std::hypot(b.x() - (w.Front() + w.BallRadius()), b.y()));
    touching += w.Robot().dribbler_ball_contact;
    ++steps;
  }
};

// The shipped modern robot (its bar fixed to the chassis, only the surface turning:
// bar_model surface) and the same robot with the bar a body on a motorised hinge.
enum class BarModel { kSurface, kHinge };

std::string HingeBarRobot();

// Each bar model at each physics profile: holding the ball is what a team meets at either.
class RollerDribbler : public ::testing::TestWithParam<std::tuple<BarModel, std::string>> {
 protected:
  static std::string RobotFile() {
    return std::get<0>(GetParam()) == BarModel::kSurface ? std::string(kModernRobot) : HingeBarRobot();
  }
  static std::string Profile() { return std::get<1>(GetParam()); }
};

// The modern robot file with its bar on a hinge, written once per test process.
std::string HingeBarRobot() {
  static const std::string file =
      testing::EditedModelFile(kModernRobot, "bar_model: surface", "bar_model: hinge", "ubersim-hinge-bar-robot");
  return file;
}

INSTANTIATE_TEST_SUITE_P(BarModels, RollerDribbler,
                         ::testing::Combine(::testing::Values(BarModel::kSurface, BarModel::kHinge),
                                            ::testing::ValuesIn(PhysicsProfileNames())),
                         [](const auto& info) {
                           return std::string(std::get<0>(info.param) == BarModel::kSurface ? "SurfaceBar_"
                                                                                             : "HingeBar_") +
                                  std::get<1>(info.param);
                         });

// The dribbler tests outside that list, at each profile.
class RollerDribblerAtProfile : public ::testing::TestWithParam<std::string> {};

INSTANTIATE_TEST_SUITE_P(Profiles, RollerDribblerAtProfile, ::testing::ValuesIn(PhysicsProfileNames()),
                         [](const auto& info) { return info.param; });

double Distance(PartsWorld& w) {
  const Vec3 b = w.BallInRobotFrame();
  return std::hypot(b.x() - (w.Front() + w.BallRadius()), b.y());
}

TEST_P(RollerDribbler, TouchesBallReportsTheContact) {
  PartsWorld w(Profile(), RobotFile());
  w.Run(0.2, std::nullopt, std::nullopt, kDribble);
  EXPECT_FALSE(w.Robot().dribbler_ball_contact) << "the ball is 5 m away";
  w.PlaceBallInMouth();
  w.Run(0.01, std::nullopt, std::nullopt, kDribble);
  EXPECT_TRUE(w.Robot().dribbler_ball_contact);
  w.PlaceBall(0.3, 0.0);
  w.Run(0.01, std::nullopt, std::nullopt, kDribble);
  EXPECT_FALSE(w.Robot().dribbler_ball_contact) << "reset once the ball has gone";
}

TEST_P(RollerDribbler, ARobotTakenOffTheFieldReportsNoContact) {
  PartsWorld w(Profile(), RobotFile());
  w.PlaceBallInMouth();
  w.Run(0.01, std::nullopt, std::nullopt, kDribble);
  ASSERT_TRUE(w.Robot().dribbler_ball_contact);
  ASSERT_TRUE(w.Robot().kicker_ready);
  w.world->events().Post(PositionEvent{Target::Robot(PartsWorld::kRobot), std::nullopt, std::nullopt, std::nullopt,
                                       std::nullopt, false});
  w.Run(0.01, std::nullopt, std::nullopt, kDribble);
  EXPECT_FALSE(w.Robot().present);
  EXPECT_FALSE(w.Robot().dribbler_ball_contact);
  EXPECT_FALSE(w.Robot().kicker_ready);
}

TEST_P(RollerDribbler, SpinsTheBallBackAgainstTheRobot) {
  PartsWorld w(Profile(), RobotFile());
  w.Run(0.2);
  w.PlaceBallInMouth();
  w.Run(0.5, std::nullopt, std::nullopt, kDribble);
  // Backspin about the robot's left (y) axis: the ball's top turns toward the robot.
  const RobotState r = w.Robot();
  const double spin_y = (r.pose.orientation.conjugate() * w.BallTwist().angular).y();
  EXPECT_LT(spin_y, -20.0);
  EXPECT_LT(Distance(w), 0.002);
}

TEST_P(RollerDribbler, DribblingLeavesTheRobotStandingStill) {
  PartsWorld w(Profile(), RobotFile());
  w.Run(0.2);
  w.PlaceBallInMouth();
  const RobotState before = w.Robot();
  w.Run(2.0, std::nullopt, std::nullopt, kDribble);
  const RobotState after = w.Robot();
  EXPECT_LT((after.pose.position - before.pose.position).norm(), 0.002);
  EXPECT_LT(std::abs(after.pose.Yaw() - before.pose.Yaw()), 0.01);
  EXPECT_GT((after.pose.orientation * Vec3::UnitZ()).z(), std::cos(0.01)) << "tilted";
  EXPECT_LT(after.twist.linear.norm(), 0.01);
}

TEST_P(RollerDribbler, HoldsTheBallThroughADriveAndATurn) {
  PartsWorld w(Profile(), RobotFile());
  w.Run(0.2);
  w.PlaceBallInMouth();
  w.Run(0.3, std::nullopt, std::nullopt, kDribble);
  MouthTracker t{w};
  const double x0 = w.Robot().pose.position.x();
  // 1 m forward at 1 m/s: the drive speeds up at 3 m/s² and brakes at its own 6 m/s².
  w.Run(1.0 + 1.0 / 6.0 - 1.0 / 12.0, LocalVelocityCommand{1.0, 0, 0}, std::nullopt, kDribble, std::ref(t));
  w.Run(0.5, LocalVelocityCommand{0, 0, 0}, std::nullopt, kDribble, std::ref(t));
  const double travelled = w.Robot().pose.position.x() - x0;
  EXPECT_NEAR(travelled, 1.0, 0.05);
  // 90° to the left at 2 rad/s.
  const double yaw0 = w.Robot().pose.Yaw();
  w.Run(M_PI / 4, LocalVelocityCommand{0, 0, 2.0}, std::nullopt, kDribble, std::ref(t));
  w.Run(0.5, LocalVelocityCommand{0, 0, 0}, std::nullopt, kDribble, std::ref(t));
  EXPECT_NEAR(w.Robot().pose.Yaw() - yaw0, M_PI / 2, 0.1);
  EXPECT_LT(t.worst, 0.01) << "the ball left the mouth";
  EXPECT_GT(t.touching, 0.95 * t.steps);
  EXPECT_TRUE(w.Robot().dribbler_ball_contact);
  RecordProperty("hold_worst_m", std::to_string(t.worst));
}

TEST_P(RollerDribbler, WithoutTheRollerTheBallIsLostWhenBraking) {
  // The same drive with the dribbler off: the ball rolls on when the robot brakes. This is what
  // the hold test above would see if the roller did nothing.
  PartsWorld w(Profile(), RobotFile());
  w.Run(0.2);
  w.PlaceBallInMouth();
  w.Run(1.0 + 1.0 / 6.0 - 1.0 / 12.0, LocalVelocityCommand{1.0, 0, 0}, std::nullopt, 0.0);
  w.Run(0.5, LocalVelocityCommand{0, 0, 0}, std::nullopt, 0.0);
  EXPECT_GT(Distance(w), 0.1);
}

TEST_P(RollerDribbler, LosesTheBallOnAFastSpin) {
  for (double spin : {8.0, 10.0}) {
    PartsWorld w(Profile(), RobotFile());
    w.Run(0.2);
    w.PlaceBallInMouth();
    w.Run(0.3, std::nullopt, std::nullopt, kDribble);
    w.Run(1.0, LocalVelocityCommand{0, 0, spin}, std::nullopt, kDribble);
    EXPECT_NEAR(w.Robot().twist.angular.z(), spin, 0.3) << "the robot did not spin";
    EXPECT_GT(Distance(w), 0.05) << spin << " rad/s";
    EXPECT_FALSE(w.Robot().dribbler_ball_contact) << spin << " rad/s";
  }
}

TEST_P(RollerDribbler, HoldsWhileSpinningSlowly) {
  PartsWorld w(Profile(), RobotFile());
  w.Run(0.2);
  w.PlaceBallInMouth();
  w.Run(0.3, std::nullopt, std::nullopt, kDribble);
  MouthTracker t{w};
  w.Run(3.0, LocalVelocityCommand{0, 0, 2.0}, std::nullopt, kDribble, std::ref(t));  // about one turn
  EXPECT_LT(t.worst, 0.01);
}

TEST_P(RollerDribblerAtProfile, HingeBarSpeedIsClampedToTheMaximum) {
  PartsWorld w(GetParam(), HingeBarRobot());
  w.Run(0.2);
  w.Run(0.5, std::nullopt, std::nullopt, 1e4);
  const NodeImpl* node = WorldAttorney::Scene(*w.world).Find("blue/0/dribbler");
  ASSERT_NE(node, nullptr);
  const Joint* axle = node->FindJoint("axle");
  ASSERT_NE(axle, nullptr);
  EXPECT_NEAR(axle->Rate(), 150.0, 1.0);
}

TEST_P(RollerDribblerAtProfile, SurfaceBarSpeedIsClampedToo) {
  // The surface bar has no axle: a held ball spins as fast with 10⁴ rad/s commanded as with the
  // maximum, and slower at half of it.
  auto spin = [](double command) {
    PartsWorld w(GetParam());
    w.Run(0.2);
    w.PlaceBallInMouth();
    w.Run(0.5, std::nullopt, std::nullopt, command);
    return -(w.Robot().pose.orientation.conjugate() * w.BallTwist().angular).y();
  };
  const double at_max = spin(kDribble);
  EXPECT_GT(at_max, 20.0);
  EXPECT_NEAR(spin(1e4), at_max, 0.01 * at_max);
  EXPECT_LT(spin(0.5 * kDribble), 0.75 * at_max);
  const PartsWorld plain(GetParam());
  EXPECT_EQ(WorldAttorney::Scene(*plain.world).Find("blue/0/dribbler")->FindJoint("axle"), nullptr) << "no hinge";
}

TEST_P(RollerDribblerAtProfile, The2003RobotAndTheUrdfTwinHoldTheBallToo) {
  for (const char* file : {k2003Robot, kModernUrdfRobot}) {
    PartsWorld w(GetParam(), file);
    w.Run(0.2);
    w.PlaceBallInMouth();
    w.Run(0.3, std::nullopt, std::nullopt, kDribble);
    MouthTracker t{w};
    w.Run(1.0, LocalVelocityCommand{1.0, 0, 0}, std::nullopt, kDribble, std::ref(t));
    w.Run(0.5, LocalVelocityCommand{0, 0, 0}, std::nullopt, kDribble, std::ref(t));
    w.Run(M_PI / 4, LocalVelocityCommand{0, 0, 2.0}, std::nullopt, kDribble, std::ref(t));
    w.Run(0.3, LocalVelocityCommand{0, 0, 0}, std::nullopt, kDribble, std::ref(t));
    EXPECT_LT(t.worst, 0.01) << file;
  }
}

}  // namespace
}  // namespace ubersim::kernel
