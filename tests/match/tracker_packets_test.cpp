// SPDX-License-Identifier: Apache-2.0
// Tracked frames from the truth: units and fields as the league's readers expect, and the optional
// vision noise with the perception block's σ, reproducible from the seed.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "tracker_packets.hpp"

namespace ubersim::match {
namespace {

WorldSnapshot Truth() {
  WorldSnapshot s;
  s.sim_time_ns = 2'500'000'000;
  s.ball.pose.position = Vec3(1.0, -2.0, 0.0215);
  s.ball.twist.linear = Vec3(3.0, 0.5, 0.0);
  RobotState r;
  r.id = {Team::kBlue, 3};
  r.pose.position = Vec3(-1.5, 0.25, 0.0);
  r.pose.orientation = Quat(Eigen::AngleAxisd(0.75, Vec3::UnitZ()));
  r.twist.linear = Vec3(0.4, -0.2, 0.0);
  r.twist.angular = Vec3(0, 0, 1.5);
  s.robots.push_back(r);
  RobotState off = r;
  off.id = {Team::kYellow, 1};
  off.present = false;
  s.robots.push_back(off);
  return s;
}

TEST(TrackedPacket, CarriesTheTruthInMetresAndUnixSeconds) {
  const TrackerWrapperPacket p = TrackedPacket(Truth(), 7, 1'700'000'000'000'000'000LL, {"u-1", "UberSim"});
  EXPECT_EQ(p.uuid(), "u-1");
  EXPECT_EQ(p.source_name(), "UberSim");
  const TrackedFrame& f = p.tracked_frame();
  EXPECT_EQ(f.frame_number(), 7u);
  EXPECT_DOUBLE_EQ(f.timestamp(), 1'700'000'002.5);
  ASSERT_EQ(f.balls_size(), 1);
  EXPECT_FLOAT_EQ(f.balls(0).pos().x(), 1.0f);
  EXPECT_FLOAT_EQ(f.balls(0).pos().y(), -2.0f);
  EXPECT_NEAR(f.balls(0).pos().z(), 0.0f, 1e-6);  // height above the carpet: a rolling ball is at 0
  EXPECT_FLOAT_EQ(f.balls(0).vel().x(), 3.0f);
  ASSERT_EQ(f.robots_size(), 1);  // the robot off the field is not tracked
  EXPECT_EQ(f.robots(0).robot_id().id(), 3u);
  EXPECT_EQ(f.robots(0).robot_id().team(), ::BLUE);
  EXPECT_NEAR(f.robots(0).orientation(), 0.75f, 1e-6);
  EXPECT_FLOAT_EQ(f.robots(0).vel().x(), 0.4f);
  EXPECT_FLOAT_EQ(f.robots(0).vel_angular(), 1.5f);
}

TEST(TrackedPacket, NoiseHasThePerceptionSigmaAndRepeatsFromTheSeed) {
  std::mt19937_64 rng(42), again(42);
  const TrackerNoise noise{0.004, 0.002, 0.01, &rng};
  TrackerNoise same = noise;
  same.rng = &again;
  const WorldSnapshot truth = Truth();
  double bx2 = 0, rx2 = 0, yaw2 = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const TrackedFrame f = TrackedPacket(truth, i, 0, {"u", "s"}, &noise).tracked_frame();
    const TrackedFrame g = TrackedPacket(truth, i, 0, {"u", "s"}, &same).tracked_frame();
    ASSERT_EQ(f.SerializeAsString(), g.SerializeAsString());
    bx2 += std::pow(f.balls(0).pos().x() - 1.0, 2);
    rx2 += std::pow(f.robots(0).pos().x() + 1.5, 2);
    yaw2 += std::pow(f.robots(0).orientation() - 0.75, 2);
    EXPECT_FLOAT_EQ(f.balls(0).vel().x(), 3.0f);  // velocities stay true
  }
  // σ within 5 % (4000 samples: the estimate's own spread is about 1.1 %).
  EXPECT_NEAR(std::sqrt(bx2 / n), 0.004, 0.0002);
  EXPECT_NEAR(std::sqrt(rx2 / n), 0.002, 0.0001);
  EXPECT_NEAR(std::sqrt(yaw2 / n), 0.01, 0.0005);
}

TEST(TrackedPacket, TheSourceUuidIsFixedPerSeedAndShapedAsVersion4) {
  EXPECT_EQ(UuidFromSeed(1), UuidFromSeed(1));
  EXPECT_NE(UuidFromSeed(1), UuidFromSeed(2));
  EXPECT_TRUE(std::regex_match(UuidFromSeed(1), std::regex("[0-9a-f]{8}-[0-9a-f]{4}-4[0-9a-f]{3}-[89ab][0-9a-f]{3}-[0-9a-f]{12}")))
      << UuidFromSeed(1);
}

}  // namespace
}  // namespace ubersim::match
