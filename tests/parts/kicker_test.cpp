// SPDX-License-Identifier: Apache-2.0
// The solenoid kicker on the modern robot: flat kicks clamped to the rules' 6.5 m/s, chips at the
// hardware angle, no kick unless the ball lies in front of the flat face, recharge and arming
// times, recoil, a kick out of the dribbler, and the URDF twin kicking like the YAML one.
#include <cmath>

#include <gtest/gtest.h>

#include "parts_world.hpp"

namespace ubersim::kernel {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Sends `kick` at 100 Hz for up to `seconds` and returns the simulated time (s) at the end of the
// step in which the ball's speed jumped above 1 m/s (the kick), or -1; stops right after it.
double KickAndWait(PartsWorld& w, const KickCommand& kick, double seconds, std::optional<double> dribble = {}) {
  const double dt = w.world->clock().step_seconds();
  for (long i = 0; i < std::lround(seconds / dt); ++i) {
    if (i % 10 == 0) w.Send(std::nullopt, kick, dribble);
    w.world->Step();
    if (w.BallTwist().linear.norm() > 1.0) return w.world->clock().time_ns() * 1e-9;
  }
  return -1;
}

// The ball's velocity a few steps after the kick: after leaving the robot, before the carpet has
// slowed it noticeably (3 ms of sliding friction take 0.01 m/s off).
Vec3 LaunchVelocity(PartsWorld& w, const KickCommand& kick, std::optional<double> dribble = {}) {
  Vec3 v = Vec3::Zero();
  long after = -1;
  w.Run(0.2, std::nullopt, kick, dribble, [&] {
    if (after < 0 && w.BallTwist().linear.norm() > 1.0) after = 0;
    if (after >= 0 && after++ == 3) v = w.BallTwist().linear;
  });
  return v;
}

TEST(SolenoidKicker, FlatKickIsClampedToTheRulesLimit) {
  PartsWorld w;
  w.Run(0.2);  // settle on the wheels
  w.PlaceBallInMouth();
  const Vec3 v = LaunchVelocity(w, KickCommand{10.0, 0.0});
  EXPECT_NEAR(v.norm(), 6.5, 0.1);
  EXPECT_NEAR(v.y(), 0.0, 0.05);  // along the heading (+x)
  EXPECT_NEAR(v.z(), 0.0, 0.1);
  RecordProperty("flat_kick_speed", std::to_string(v.norm()));
}

TEST(SolenoidKicker, FlatKickBelowTheLimitLeavesAtTheCommandedSpeed) {
  PartsWorld w;
  w.Run(0.2);
  w.PlaceBallInMouth();
  const Vec3 v = LaunchVelocity(w, KickCommand{3.0, 0.0});
  EXPECT_NEAR(v.norm(), 3.0, 0.1);
}

TEST(SolenoidKicker, ChipLeavesAtTheHardwareAngle) {
  PartsWorld w;
  w.Run(0.2);
  w.PlaceBallInMouth();
  // The command's angle only selects a chip; the chipper's angle is the configured 45°.
  const Vec3 v = LaunchVelocity(w, KickCommand{3.0, 20 * kDeg});
  const double angle = std::atan2(v.z(), std::hypot(v.x(), v.y())) / kDeg;
  EXPECT_NEAR(angle, 45.0, 1.0);
  EXPECT_NEAR(v.norm(), 3.0, 0.1);
  EXPECT_GT(v.x(), 0.0);
  RecordProperty("chip_angle_deg", std::to_string(angle));
}

TEST(SolenoidKicker, ChipIsClampedToItsOwnLimit) {
  PartsWorld w;
  w.Run(0.2);
  w.PlaceBallInMouth();
  const Vec3 v = LaunchVelocity(w, KickCommand{10.0, 45 * kDeg});
  EXPECT_NEAR(v.norm(), 5.5, 0.1);
}

TEST(SolenoidKicker, NoKickWhenTheBallIsNotInFrontOfTheFace) {
  struct Where { const char* name; double x, y; };
  PartsWorld probe;
  const double front = probe.Front(), r = probe.BallRadius();
  for (const Where& p : {Where{"behind", -0.12, 0.0}, Where{"beside", 0.0, 0.13},
                         Where{"off_the_face_edge", front + r, 0.045}, Where{"too_far_ahead", front + r + 0.03, 0.0}}) {
    PartsWorld w;
    w.Run(0.2);
    w.PlaceBall(p.x, p.y);
    EXPECT_LT(KickAndWait(w, KickCommand{5.0, 0.0}, 0.2), 0) << p.name;
    EXPECT_TRUE(w.Robot().kicker_ready) << p.name << ": a kicker that did not fire stays charged";
  }
}

TEST(SolenoidKicker, RechargeBlocksASecondKickAndReadyReportsIt) {
  PartsWorld w;
  w.Run(0.2);
  EXPECT_TRUE(w.Robot().kicker_ready);
  w.PlaceBallInMouth();
  const double first = KickAndWait(w, KickCommand{4.0, 0.0}, 0.05);
  ASSERT_GE(first, 0);
  EXPECT_FALSE(w.Robot().kicker_ready);
  // Ball straight back into the mouth; the AI keeps asking for a kick.
  w.PlaceBallInMouth();
  w.Run(0.3, std::nullopt, KickCommand{4.0, 0.0}, std::nullopt);
  EXPECT_LT(w.BallTwist().linear.norm(), 0.5) << "kicked again while recharging";
  EXPECT_FALSE(w.Robot().kicker_ready);
  const double second = KickAndWait(w, KickCommand{4.0, 0.0}, 1.0);
  ASSERT_GE(second, 0) << "it never fired again";
  EXPECT_NEAR(second - first, 0.5, 0.011) << "fires as soon as recharged (0.5 s), within a radio frame";
  EXPECT_FALSE(w.Robot().kicker_ready);
  RecordProperty("recharge_s", std::to_string(second - first));
}

TEST(SolenoidKicker, ArmingLastsArmTimeAndSpeedZeroDisarms) {
  {  // armed while the ball is away; the ball arrives 50 ms later: it fires
    PartsWorld w;
    w.Run(0.2);
    w.Send(std::nullopt, KickCommand{4.0, 0.0}, std::nullopt);
    w.Run(0.05);
    w.PlaceBallInMouth();
    long fired = -1, step = 0;
    w.Run(0.02, std::nullopt, std::nullopt, std::nullopt, [&] {
      ++step;
      if (fired < 0 && w.BallTwist().linear.norm() > 1.0) fired = step;
    });
    EXPECT_GE(fired, 0) << "still armed 50 ms after the command";
  }
  {  // the ball arrives 150 ms after the only command: arming (0.1 s) has lapsed
    PartsWorld w;
    w.Run(0.2);
    w.Send(std::nullopt, KickCommand{4.0, 0.0}, std::nullopt);
    w.Run(0.15);
    w.PlaceBallInMouth();
    w.Run(0.1);
    EXPECT_LT(w.BallTwist().linear.norm(), 0.5) << "fired 150 ms after a single command";
    EXPECT_TRUE(w.Robot().kicker_ready);
  }
  {  // speed 0 disarms at once
    PartsWorld w;
    w.Run(0.2);
    w.Send(std::nullopt, KickCommand{4.0, 0.0}, std::nullopt);
    w.Run(0.01);
    w.Send(std::nullopt, KickCommand{0.0, 0.0}, std::nullopt);
    w.Run(0.01);
    w.PlaceBallInMouth();
    w.Run(0.1);
    EXPECT_LT(w.BallTwist().linear.norm(), 0.5) << "fired after a disarm";
  }
}

TEST(SolenoidKicker, RecoilPushesTheRobotBack) {
  PartsWorld w;
  w.Run(0.2);
  w.PlaceBallInMouth();
  const double robot_mass = 2.3 + 4 * 0.05 + 0.02;  // chassis, wheels, dribbler bar
  // Fire, then look at the robot right after the step that fired.
  double vx = 0;
  long after = -1;
  w.Run(0.05, std::nullopt, KickCommand{6.5, 0.0}, std::nullopt, [&] {
    if (after < 0 && w.BallTwist().linear.norm() > 1.0) {
      after = 0;
      vx = w.Robot().twist.linear.x();
    }
  });
  // Momentum: 0.046 kg × 6.5 m/s over about 2.5 kg, less what one step of wheel friction takes.
  EXPECT_LT(vx, -0.5 * 0.046 * 6.5 / robot_mass);
  EXPECT_GT(vx, -1.2 * 0.046 * 6.5 / robot_mass);
  RecordProperty("recoil_speed", std::to_string(vx));
}

TEST(SolenoidKicker, KickWhileDribblingLeavesAtTheClampedSpeed) {
  PartsWorld w;
  w.Run(0.2);
  w.PlaceBallInMouth();
  w.Run(0.5, std::nullopt, std::nullopt, 150.0);  // the dribbler holds and spins the ball
  ASSERT_TRUE(w.Robot().dribbler_ball_contact);
  const Vec3 v = LaunchVelocity(w, KickCommand{10.0, 0.0}, 150.0);
  EXPECT_NEAR(v.norm(), 6.5, 0.1);
  EXPECT_NEAR(v.y(), 0.0, 0.05);
  // And a chip out of the dribbler keeps its angle.
  PartsWorld c;
  c.Run(0.2);
  c.PlaceBallInMouth();
  c.Run(0.5, std::nullopt, std::nullopt, 150.0);
  const Vec3 u = LaunchVelocity(c, KickCommand{3.0, 1.0}, 150.0);
  EXPECT_NEAR(std::atan2(u.z(), std::hypot(u.x(), u.y())) / kDeg, 45.0, 1.0);
  EXPECT_NEAR(u.norm(), 3.0, 0.1);
}

TEST(SolenoidKicker, KickAddsTheRobotsVelocity) {
  PartsWorld w;
  w.Run(0.2);
  w.PlaceBallInMouth();
  // Dribble forward at 1 m/s, then kick at 3 m/s: the ball leaves at about 4 m/s.
  w.Run(1.0, LocalVelocityCommand{1.0, 0, 0}, std::nullopt, 150.0);
  const double robot_speed = w.Robot().twist.linear.x();
  ASSERT_NEAR(robot_speed, 1.0, 0.05);
  const Vec3 v = LaunchVelocity(w, KickCommand{3.0, 0.0}, 150.0);
  EXPECT_NEAR(v.x(), robot_speed + 3.0, 0.15);
}

TEST(SolenoidKicker, UrdfTwinKicksLikeTheYamlTwin) {
  for (const KickCommand& k : {KickCommand{10.0, 0.0}, KickCommand{4.0, 0.0}, KickCommand{3.0, 1.0}}) {
    PartsWorld yaml(kModernRobot), urdf(kModernUrdfRobot);
    yaml.Run(0.2);
    urdf.Run(0.2);
    yaml.PlaceBallInMouth();
    urdf.PlaceBallInMouth();
    const Vec3 vy = LaunchVelocity(yaml, k), vu = LaunchVelocity(urdf, k);
    EXPECT_GT(vu.norm(), 1.0) << "the URDF twin did not kick";
    EXPECT_NEAR(vu.norm(), vy.norm(), 0.1) << "speed " << k.speed << " angle " << k.angle;
    EXPECT_NEAR(vu.z(), vy.z(), 0.1);
  }
}

TEST(SolenoidKicker, The2003RobotKicksAtItsOwnLimit) {
  PartsWorld w(k2003Robot);
  w.Run(0.2);
  w.PlaceBallInMouth();
  EXPECT_NEAR(LaunchVelocity(w, KickCommand{10.0, 0.0}).norm(), 5.0, 0.1);
}

}  // namespace
}  // namespace ubersim::kernel
