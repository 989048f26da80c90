// SPDX-License-Identifier: Apache-2.0
// World stepping: determinism, events, clock control, and the field and ball as physical bodies.
#include <cmath>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "../../common/test_world.hpp"
#include "ubersim/kernel/field.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/world.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel {
namespace {

struct Fixture {
  std::ostringstream log_text;
  StreamLog log{log_text, LogLevel::kDebug};
  PluginRegistry registry{{}};
};

std::uint64_t RunAndHash(const WorldModel& model, int steps) {
  Fixture f;
  World world(model, f.registry, f.log, false);
  world.events().Post(PositionEvent{Target::Ball(), Vec3(0.3, -0.2, 0.3), std::nullopt,
                                    Vec3(2.5, 1.5, 0.5), Vec3(0, 0, 20), std::nullopt});
  for (int i = 0; i < steps; ++i) world.Step();
  return world.StateHash();
}

TEST(World, SameWorldSteppedTwiceIsBitIdentical) {
  const WorldModel model = testing::BallWorld();
  const std::uint64_t a = RunAndHash(model, 3000);
  const std::uint64_t b = RunAndHash(model, 3000);
  EXPECT_EQ(a, b);
  // And the hash sees the state: a different run gives a different hash.
  EXPECT_NE(a, RunAndHash(model, 2999));
}

TEST(World, DeterministicWhileAnotherWorldStepsInBetween) {
  const WorldModel model = testing::BallWorld();
  Fixture f;
  World one(model, f.registry, f.log, false);
  World two(model, f.registry, f.log, false);
  const PositionEvent kick{Target::Ball(), Vec3(0, 0, 0.05), std::nullopt, Vec3(3, -1, 1),
                           std::nullopt, std::nullopt};
  one.events().Post(kick);
  two.events().Post(kick);
  for (int i = 0; i < 2000; ++i) {
    one.Step();
    two.Step();
    two.Step();  // interleaved and unequal: each world keeps its own ODE random sequence
  }
  for (int i = 0; i < 2000; ++i) one.Step();
  EXPECT_EQ(one.StateHash(), two.StateHash());
}

// The ball's reported positions (noise on) of the first `steps` steps.
std::vector<double> SeenBall(World& world, int steps) {
  std::vector<double> seen;
  world.SetVisionObserver([&seen](const VisionFrame& f) {
    for (const DetectedBall& b : f.balls) seen.push_back(b.x);
  });
  for (int i = 0; i < steps; ++i) world.Step();
  return seen;
}

WorldModel NoisyBallWorld(std::uint64_t seed) {
  WorldModel model = testing::BallWorld(Vec3(0.5, 0.2, 0));
  model.seed = seed;
  model.perception.ball_position_sigma = 0.01;
  model.perception.ball_drop = 0.2;
  CameraModel camera;
  camera.x_min = -5, camera.x_max = 5, camera.y_min = -4, camera.y_max = 4;
  model.perception.cameras.push_back(camera);
  return model;
}

TEST(World, ResetWithASeedIsTheWorldBuiltWithThatSeed) {
  Fixture f;
  World fresh(NoisyBallWorld(7), f.registry, f.log, false);
  const std::vector<double> expected = SeenBall(fresh, 500);
  World reseeded(NoisyBallWorld(1), f.registry, f.log, false);
  const std::vector<double> first = SeenBall(reseeded, 500);
  ASSERT_GT(expected.size(), 10u);
  EXPECT_NE(first, expected);  // another seed: other noise, other drop-outs
  reseeded.Reset(7);
  EXPECT_EQ(SeenBall(reseeded, 500), expected);
  EXPECT_EQ(reseeded.StateHash(), fresh.StateHash());
  EXPECT_EQ(reseeded.model().seed, 7u);
}

TEST(World, DroppedBallComesToRestOnTheCarpet) {
  Fixture f;
  World world(testing::BallWorld(Vec3(1.0, 0.5, 0.5)), f.registry, f.log, false);
  double max_bounce_height = 0;
  bool left_ground = false;
  for (int i = 0; i < 5000; ++i) {
    world.Step();
    const double z = WorldAttorney::Ball(world).GetPose().position.z();
    if (i > 400 && z > 0.0215 + 0.005) left_ground = true;
    if (i > 400) max_bounce_height = std::max(max_bounce_height, z);
  }
  const Pose p = WorldAttorney::Ball(world).GetPose();
  const Twist t = WorldAttorney::Ball(world).GetTwist();
  EXPECT_NEAR(p.position.z(), 0.0215, 0.001);  // resting on the carpet, not in it
  EXPECT_LT(t.linear.norm(), 0.01);
  EXPECT_NEAR(p.position.x(), 1.0, 0.01);
  EXPECT_NEAR(p.position.y(), 0.5, 0.01);
  EXPECT_TRUE(left_ground) << "a ball dropped from 0.5 m should bounce (restitution 0.56)";
  EXPECT_LT(max_bounce_height, 0.5 * 0.56 * 0.56 + 0.0215 + 0.02);
}

TEST(World, BallRolledIntoAWallComesBack) {
  Fixture f;
  World world(testing::BallWorld(Vec3(4.0, 1.0, 0)), f.registry, f.log, false);
  // Rolling (not sliding) toward the +x wall at x = 4.8.
  const double v = 2.0, r = 0.0215;
  world.events().Post(PositionEvent{Target::Ball(), std::nullopt, std::nullopt, Vec3(v, 0, 0),
                                    Vec3(0, v / r, 0), std::nullopt});
  double max_x = 0;
  for (int i = 0; i < 1500; ++i) {
    world.Step();
    max_x = std::max(max_x, WorldAttorney::Ball(world).GetPose().position.x());
  }
  const Twist t = WorldAttorney::Ball(world).GetTwist();
  EXPECT_LT(t.linear.x(), -0.2) << "the ball must bounce back off the wall";
  EXPECT_LE(max_x, 4.8 - r + 0.002) << "the ball must not enter the wall";
  EXPECT_GT(max_x, 4.8 - r - 0.01) << "the ball must reach the wall";
}

TEST(World, RandomBouncedBallStaysOnTheFieldForTenSimulatedMinutes) {
  Fixture f;
  const WorldModel model = testing::BallWorld();
  World world(model, f.registry, f.log, false);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), speed(0.5, 6.5), up(0.0, 1.0);
  const int steps = 600 * 1000;  // 10 min at 1 ms
  double min_z = 1.0;
  int outside = 0;
  for (int i = 0; i < steps; ++i) {
    if (i % 1500 == 0) {  // a random kick every 1.5 s, at up to the rules' 6.5 m/s
      const double a = angle(rng), s = speed(rng);
      world.events().Post(PositionEvent{Target::Ball(), std::nullopt, std::nullopt,
                                        Vec3(s * std::cos(a), s * std::sin(a), up(rng)),
                                        std::nullopt, std::nullopt});
    }
    world.Step();
    const Vec3 p = WorldAttorney::Ball(world).GetPose().position;
    ASSERT_TRUE(p.allFinite()) << "step " << i;
    min_z = std::min(min_z, p.z());
    if (!InsideWalls(*model.field, p, 0.0)) ++outside;
  }
  EXPECT_EQ(outside, 0);
  EXPECT_GT(min_z, 0.0215 - 0.003) << "the ball sank into the carpet";
  EXPECT_NEAR(world.clock().seconds(), 600.0, 1e-9);
}

TEST(World, QueryAndTeleportEvents) {
  Fixture f;
  World world(testing::BallWorld(), f.registry, f.log, false);
  world.events().Post(PositionEvent{Target::Ball(), Vec3(-2, 1.5, 0), std::nullopt, std::nullopt,
                                    std::nullopt, std::nullopt});
  ObjectState answer;
  int replies = 0;
  world.events().Post(QueryEvent{Target::Ball(), [&](const ObjectState& s) {
                                   answer = s;
                                   ++replies;
                                 }});
  world.ProcessEvents();
  EXPECT_EQ(replies, 1);
  EXPECT_TRUE(answer.found);
  EXPECT_NEAR(answer.pose.position.x(), -2.0, 1e-12);
  EXPECT_NEAR(answer.pose.position.y(), 1.5, 1e-12);
  EXPECT_NEAR(answer.pose.position.z(), 0.0215, 1e-12);  // lifted onto the carpet

  world.events().Post(QueryEvent{Target::Robot({Team::kBlue, 3}), [&](const ObjectState& s) {
                                   answer = s;
                                   ++replies;
                                 }});
  world.ProcessEvents();
  EXPECT_EQ(replies, 2);
  EXPECT_FALSE(answer.found);
}

TEST(World, BadEventsAreRejectedAndChangeNothing) {
  Fixture f;
  World world(testing::BallWorld(Vec3(1, 1, 0)), f.registry, f.log, false);
  for (int i = 0; i < 10; ++i) world.Step();
  const std::uint64_t before = world.StateHash();
  world.events().Post(PositionEvent{Target::Ball(), Vec3(NAN, 0, 0), std::nullopt, std::nullopt,
                                    std::nullopt, std::nullopt});
  world.events().Post(PositionEvent{Target::Ball(), std::nullopt, std::nullopt,
                                    Vec3(INFINITY, 0, 0), std::nullopt, std::nullopt});
  world.events().Post(CommandEvent{{Team::kYellow, 9}, LocalVelocityCommand{1, 0, 0}, {}, {}});
  world.events().Post(ClockEvent{ClockEvent::Action::kSetSpeed, -3.0, 1});
  world.ProcessEvents();
  EXPECT_EQ(world.StateHash(), before);
  EXPECT_EQ(world.event_counters().rejected, 4);
  EXPECT_EQ(world.event_counters().applied, 0);
  EXPECT_DOUBLE_EQ(world.clock_control().speed_factor, 1.0);
  EXPECT_EQ(f.log.count(LogLevel::kWarning), 4);
}

TEST(World, ClockEventsPauseStepAndReset) {
  Fixture f;
  World world(testing::BallWorld(Vec3(0, 0, 0.3)), f.registry, f.log, false);
  const std::uint64_t initial = world.StateHash();
  world.events().Post(ClockEvent{ClockEvent::Action::kPause, 1.0, 1});
  world.events().Post(ClockEvent{ClockEvent::Action::kStep, 1.0, 5});
  world.events().Post(ClockEvent{ClockEvent::Action::kSetSpeed, 4.0, 1});
  world.ProcessEvents();
  EXPECT_TRUE(world.clock_control().paused);
  EXPECT_EQ(world.clock_control().pending_steps, 5);
  EXPECT_DOUBLE_EQ(world.clock_control().speed_factor, 4.0);
  for (int i = 0; i < 100; ++i) world.Step();
  EXPECT_NE(world.StateHash(), initial);
  world.events().Post(ClockEvent{ClockEvent::Action::kReset, 1.0, 1});
  world.ProcessEvents();
  EXPECT_EQ(world.clock().steps(), 0);
  EXPECT_EQ(world.StateHash(), initial);
}

TEST(Pacer, RealTimePacingWaitsAndFastModeDoesNot) {
  Pacer pacer;
  EXPECT_EQ(pacer.WaitBefore(0, 1.0), Pacer::Clock::duration::zero());  // anchors
  // 50 ms of sim time at speed 1 is due about 50 ms after the anchor.
  const auto wait = pacer.WaitBefore(50'000'000, 1.0);
  EXPECT_GT(wait, std::chrono::milliseconds(30));
  EXPECT_LE(wait, std::chrono::milliseconds(50));
  // At speed 2 the same sim time is due in half: re-anchored on the change, so zero now.
  EXPECT_EQ(pacer.WaitBefore(50'000'000, 2.0), Pacer::Clock::duration::zero());
  const auto half = pacer.WaitBefore(90'000'000, 2.0);
  EXPECT_GT(half, std::chrono::milliseconds(10));
  EXPECT_LE(half, std::chrono::milliseconds(20));
  EXPECT_EQ(pacer.WaitBefore(1'000'000'000, 0.0), Pacer::Clock::duration::zero());
}

TEST(SimClock, IntegerTimeHasNoDrift) {
  SimClock c(0.001);
  for (int i = 0; i < 3'600'000; ++i) c.Advance();
  EXPECT_EQ(c.time_ns(), 3'600'000'000'000LL);
  EXPECT_EQ(c.steps(), 3'600'000);
}

}  // namespace
}  // namespace ubersim::kernel
