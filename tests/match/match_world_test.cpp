// SPDX-License-Identifier: Apache-2.0
// A match in a real world (the shipped Div B world, real ODE) through the built-in referee: the
// "teams" are scripts that shoot the ball (a kick as the ball's new velocity) when play runs; the
// referee's messages are taken as they would be recorded, decoded with the league's schema.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "refereed_world.hpp"

namespace ubersim::match {
namespace {

// Built before the world (a base of its own): the referee's messages as they would be recorded.
struct RecordedMessages {
  std::vector<Referee> messages;
};

// The built-in referee's messages, decoded with the league's schema.
struct MatchWorld : RecordedMessages, RefereedWorld {
  explicit MatchWorld(RefereeConfig config) : RecordedMessages(), RefereedWorld(Options(config, messages)) {}
  static MatchOptions Options(RefereeConfig config, std::vector<Referee>& into) {
    MatchOptions o;
    config.division = Division::kB;
    o.referee = config;
    o.unix_timestamps = false;
    o.recorder = [&into](std::int64_t t, WireMessage type, const std::string& bytes) {
      if (type != WireMessage::kReferee) return;
      Referee m;
      ASSERT_TRUE(m.ParseFromString(bytes)) << "at " << t;
      into.push_back(m);
    };
    return o;
  }
  const Referee& msg() const { return state(); }
};

TEST(BuiltinRefereeInAWorld, GoalTouchLineAndHalfTimeRunAsTheGameControllerWould) {
  RefereeConfig c;
  c.half_duration = 40.0;
  c.half_time_break = 2.0;
  MatchWorld m(c);
  ASSERT_TRUE(m.StepUntilCommand(Referee::NORMAL_START, 15)) << Referee::Command_Name(m.msg().command());
  EXPECT_EQ(m.msg().stage(), Referee::NORMAL_FIRST_HALF);

  // Blue (defending −x) shoots into the +x goal: a goal for blue, yellow kicks off.
  m.Shoot(Vec3(3.6, 0.25, 0.0215), Vec3(3.0, 0.0, 0.0));
  ASSERT_TRUE(m.StepUntil([&] { return m.msg().blue().score() == 1; }, 3.0));
  EXPECT_EQ(m.msg().command(), Referee::STOP);
  EXPECT_EQ(m.msg().next_command(), Referee::PREPARE_KICKOFF_YELLOW);
  ASSERT_TRUE(m.StepUntilCommand(Referee::PREPARE_KICKOFF_YELLOW, 10));
  // The referee put the ball on the centre spot.
  const Vec3 ball = m.world->GroundTruth().ball.pose.position;
  EXPECT_LT(std::hypot(ball.x(), ball.y()), 0.02);
  ASSERT_TRUE(m.StepUntilCommand(Referee::NORMAL_START, 15));

  // Yellow kicked off (it touched last): the ball over the +y touch line is blue's free kick.
  m.Shoot(Vec3(1.0, 2.95, 0.0215), Vec3(0.0, 0.5, 0.0));  // slow: it stays out, by the wall
  ASSERT_TRUE(m.StepUntilCommand(Referee::STOP, 3.0));
  EXPECT_EQ(m.msg().next_command(), Referee::DIRECT_FREE_BLUE);
  ASSERT_GE(m.msg().game_events_size(), 1);
  EXPECT_EQ(m.msg().game_events(0).type(), GameEvent::BALL_LEFT_FIELD_TOUCH_LINE);
  EXPECT_EQ(m.msg().game_events(0).ball_left_field_touch_line().by_team(), ::YELLOW);
  const float target_x = m.msg().designated_position().x(), target_y = m.msg().designated_position().y();
  EXPECT_NEAR(target_y, 2800.0f, 1.0f);  // 0.2 m inside the touch line
  // Blue is asked to place; its script does not, so the simulator does; then blue's free kick.
  ASSERT_TRUE(m.StepUntilCommand(Referee::BALL_PLACEMENT_BLUE, 5))
      << Referee::Command_Name(m.msg().command()) << " ball at " << m.world->GroundTruth().ball.pose.position.transpose();
  ASSERT_TRUE(m.StepUntilCommand(Referee::DIRECT_FREE_BLUE, 15));
  const Vec3 placed = m.world->GroundTruth().ball.pose.position;
  EXPECT_LT(std::hypot(placed.x() * 1000 - target_x, placed.y() * 1000 - target_y), 150.0);

  // Nobody plays on: no progress, force starts, until the half is over on time.
  ASSERT_TRUE(m.StepUntil([&] { return m.msg().stage() == Referee::NORMAL_HALF_TIME; }, 120));
  EXPECT_EQ(m.msg().command(), Referee::HALT);
  ASSERT_TRUE(m.StepUntil([&] { return m.msg().stage() == Referee::NORMAL_SECOND_HALF_PRE; }, 3));
  EXPECT_EQ(m.msg().next_command(), Referee::PREPARE_KICKOFF_BLUE);

  // Every message decoded (above); the counter rose by one per command, never skipped one.
  ASSERT_FALSE(m.messages.empty());
  unsigned counter = m.messages.front().command_counter();
  int commands = 0;
  for (const Referee& r : m.messages) {
    ASSERT_TRUE(r.command_counter() == counter || r.command_counter() == counter + 1)
        << counter << " then " << r.command_counter();
    commands += r.command_counter() != counter;
    counter = r.command_counter();
  }
  EXPECT_GE(commands, 12);
  EXPECT_EQ(m.messages.back().command_counter(), m.msg().command_counter());
}

}  // namespace
}  // namespace ubersim::match
