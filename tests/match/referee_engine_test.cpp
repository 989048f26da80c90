// SPDX-License-Identifier: Apache-2.0
// The built-in referee on scripted fields: each test moves the ball and robots as a match would
// and checks the commands, events, placements and counters the game controller would publish.
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <functional>

#include "field_rules.hpp"
#include "referee_engine.hpp"

namespace ubersim::match {
namespace {

constexpr std::int64_t kMs = 1'000'000;

FieldGeometry DivA() {
  FieldGeometry f;
  f.name = "div-a";
  f.field_length = 12.0;
  f.field_width = 9.0;
  f.goal_width = 1.8;
  f.goal_depth = 0.18;
  f.goal_height = 0.16;
  f.boundary_width = 0.3;
  f.penalty_area_depth = 1.8;
  f.penalty_area_width = 3.6;
  f.center_circle_radius = 0.5;
  f.goal_center_to_penalty_mark = 8.0;
  return f;
}

// A scripted field: the ball and a few robots, stepped 10 ms at a time through the referee.
struct Match {
  explicit Match(RefereeConfig config = {}) : referee(config, DivA()) {
    view.robots = {Robot(Team::kBlue, 0, -5.5, 0), Robot(Team::kBlue, 1, -2, 1), Robot(Team::kYellow, 0, 5.5, 0),
                   Robot(Team::kYellow, 1, 2, -1)};
  }
  static RobotView Robot(Team t, int id, double x, double y) {
    RobotView r;
    r.id = {t, id};
    r.pos = {x, y};
    return r;
  }
  // Runs `seconds`, applying ball placements the referee asks for; `each` may move things.
  void Run(double seconds, const std::function<void()>& each = {}) {
    const auto steps = static_cast<int>(std::lround(seconds * 100));
    for (int i = 0; i < steps; ++i) {
      view.t_ns += 10 * kMs;
      if (each) each();
      for (const FieldRequest& r : referee.Update(view)) {
        requests.push_back(r);
        if (r.kind == FieldRequest::Kind::kPlaceBall) {
          view.ball = r.position;
          view.ball_vel = {0, 0};
        }
        if (r.kind == FieldRequest::Kind::kTakeOff || r.kind == FieldRequest::Kind::kPutOn) {
          for (auto& robot : view.robots) {
            if (robot.id == r.robot) robot.present = r.kind == FieldRequest::Kind::kPutOn;
          }
        }
      }
      for (const Referee& m : referee.TakeCommandMessages()) commands.push_back(m);
    }
  }
  // Runs until the command is `c` (at most `limit` s); false if it never came.
  bool RunUntil(Referee::Command c, double limit = 30) {
    for (int i = 0; i < limit * 100; ++i) {
      if (referee.message().command() == c) return true;
      Run(0.01);
    }
    return referee.message().command() == c;
  }
  // Starts the first half: HALT → STOP → PREPARE_KICKOFF → NORMAL_START.
  void KickOff() {
    ASSERT_TRUE(RunUntil(Referee::NORMAL_START)) << Referee::Command_Name(referee.message().command());
  }
  const Referee& msg() const { return referee.message(); }

  RefereeEngine referee;
  FieldView view;
  std::vector<FieldRequest> requests;
  std::vector<Referee> commands;
};

std::vector<Referee::Command> CommandsOf(const std::vector<Referee>& messages) {
  std::vector<Referee::Command> out;
  for (const auto& m : messages) out.push_back(m.command());
  return out;
}

TEST(BuiltinReferee, StartsHaltedAndKicksOffTheFirstHalfForTheFirstTeam) {
  Match m;
  EXPECT_EQ(m.msg().stage(), Referee::NORMAL_FIRST_HALF_PRE);
  EXPECT_EQ(m.msg().command(), Referee::HALT);
  EXPECT_EQ(m.msg().next_command(), Referee::PREPARE_KICKOFF_YELLOW);
  m.KickOff();
  EXPECT_EQ(CommandsOf(m.commands),
            (std::vector<Referee::Command>{Referee::STOP, Referee::PREPARE_KICKOFF_YELLOW, Referee::NORMAL_START}));
  EXPECT_EQ(m.msg().stage(), Referee::NORMAL_FIRST_HALF);
  EXPECT_FALSE(m.msg().has_designated_position());
  EXPECT_FALSE(m.msg().has_next_command());
  // The preparation during the kick-off carried the centre and NORMAL_START next.
  EXPECT_EQ(m.commands[1].next_command(), Referee::NORMAL_START);
  EXPECT_FLOAT_EQ(m.commands[1].designated_position().x(), 0.0f);
  // One counter step per command, starting from 0.
  for (std::size_t i = 0; i < m.commands.size(); ++i) EXPECT_EQ(m.commands[i].command_counter(), i + 1);
}

TEST(BuiltinReferee, AGoalScoresAndTheTeamThatConcededKicksOff) {
  Match m;
  m.KickOff();
  // Blue defends −x (blue_team_on_positive_half false): the ball into the +x goal is blue's goal.
  m.view.robots[1].pos = {5.8, 0.0};  // a blue robot touches the ball on its way in
  m.view.ball = {5.9, 0.0};
  m.Run(0.05);
  m.view.ball = {6.1, 0.1};
  m.commands.clear();
  m.Run(0.02);
  EXPECT_EQ(m.msg().blue().score(), 1u);
  EXPECT_EQ(m.msg().yellow().score(), 0u);
  ASSERT_GE(m.commands.size(), 2u);
  EXPECT_EQ(m.commands[0].command(), Referee::GOAL_BLUE);
  EXPECT_EQ(m.commands[1].command(), Referee::STOP);
  EXPECT_EQ(m.commands[1].command_counter(), m.commands[0].command_counter() + 1);
  EXPECT_EQ(m.msg().next_command(), Referee::PREPARE_KICKOFF_YELLOW);
  ASSERT_EQ(m.msg().game_events_size(), 1);
  EXPECT_EQ(m.msg().game_events(0).type(), GameEvent::GOAL);
  EXPECT_EQ(m.msg().game_events(0).goal().by_team(), ::BLUE);
  // The referee puts the ball on the centre spot, and yellow kicks off.
  m.view.robots[1].pos = {-2, 1};
  m.requests.clear();
  ASSERT_TRUE(m.RunUntil(Referee::PREPARE_KICKOFF_YELLOW));
  ASSERT_FALSE(m.requests.empty());
  EXPECT_EQ(m.requests[0].kind, FieldRequest::Kind::kPlaceBall);
  EXPECT_NEAR(std::hypot(m.view.ball.x, m.view.ball.y), 0.0, 1e-9);
  ASSERT_TRUE(m.RunUntil(Referee::NORMAL_START));
}

TEST(BuiltinReferee, OverTheTouchLineThePlacingTeamPlacesAndTakesTheFreeKick) {
  Match m;
  m.KickOff();
  // Yellow 1 touches the ball last; it leaves over the +y touch line at x = 3.
  m.view.robots[3].pos = {3.0, 4.3};
  m.view.ball = {3.0, 4.42};
  m.Run(0.05);
  m.view.robots[3].pos = {3.0, 3.5};
  m.view.ball = {3.0, 4.6};
  m.Run(0.02);
  ASSERT_EQ(m.msg().command(), Referee::STOP);
  EXPECT_EQ(m.msg().next_command(), Referee::DIRECT_FREE_BLUE);
  ASSERT_EQ(m.msg().game_events_size(), 1);
  EXPECT_EQ(m.msg().game_events(0).type(), GameEvent::BALL_LEFT_FIELD_TOUCH_LINE);
  EXPECT_EQ(m.msg().game_events(0).ball_left_field_touch_line().by_team(), ::YELLOW);
  // 0.2 m in from the touch line where it crossed (mm on the wire).
  EXPECT_FLOAT_EQ(m.msg().designated_position().x(), 3000.0f);
  EXPECT_FLOAT_EQ(m.msg().designated_position().y(), 4300.0f);
  ASSERT_TRUE(m.RunUntil(Referee::BALL_PLACEMENT_BLUE, 5));
  // Blue carries the ball there, 0.1 m short, and backs off.
  const P2 target{3.0, 4.3};
  m.Run(1.0, [&] {
    m.view.ball.x += (target.x - m.view.ball.x) * 0.2;
    m.view.ball.y += (target.y - 0.1 - m.view.ball.y) * 0.2;
  });
  EXPECT_EQ(m.msg().command(), Referee::STOP);
  EXPECT_EQ(m.referee.history().back().type(), GameEvent::PLACEMENT_SUCCEEDED);
  EXPECT_EQ(m.referee.history().back().placement_succeeded().by_team(), ::BLUE);
  ASSERT_TRUE(m.RunUntil(Referee::DIRECT_FREE_BLUE, 5));
  EXPECT_FALSE(m.msg().has_designated_position());
  // No request to place: the team did it.
  for (const auto& r : m.requests) EXPECT_NE(r.kind, FieldRequest::Kind::kPlaceBall);
}

TEST(BuiltinReferee, ATeamThatDoesNotPlaceHasTheBallPlacedForIt) {
  Match m;
  m.KickOff();
  m.view.robots[1].pos = {-3.0, -4.3};  // blue touches last, over the −y line
  m.view.ball = {-3.0, -4.42};
  m.Run(0.05);
  m.view.robots[1].pos = {-3.0, -3.0};
  m.view.ball = {-3.0, -4.6};
  m.Run(0.02);
  ASSERT_TRUE(m.RunUntil(Referee::BALL_PLACEMENT_YELLOW, 5));
  ASSERT_TRUE(m.RunUntil(Referee::DIRECT_FREE_YELLOW, 10));
  ASSERT_EQ(m.requests.size(), 1u);
  EXPECT_EQ(m.requests[0].kind, FieldRequest::Kind::kPlaceBall);
  EXPECT_NEAR(m.requests[0].position.x, -3.0, 1e-9);
  EXPECT_NEAR(m.requests[0].position.y, -4.3, 1e-9);
  EXPECT_EQ(m.msg().yellow().ball_placement_failures(), 0u);
}

TEST(BuiltinReferee, AHalfEndsOnTimeAndTheOtherTeamKicksOffTheSecond) {
  RefereeConfig c;
  c.half_duration = 3.0;
  c.half_time_break = 1.0;
  Match m(c);
  m.KickOff();
  double y = 0;
  // Keep the ball moving so that there is progress; stage time counts only while running.
  auto play = [&] { m.view.ball = {0.5, y += 0.002}; };
  m.Run(2.9, play);
  EXPECT_EQ(m.msg().stage(), Referee::NORMAL_FIRST_HALF);
  m.Run(0.2, play);
  EXPECT_EQ(m.msg().stage(), Referee::NORMAL_HALF_TIME);
  EXPECT_EQ(m.msg().command(), Referee::HALT);
  m.Run(1.1);
  EXPECT_EQ(m.msg().stage(), Referee::NORMAL_SECOND_HALF_PRE);
  EXPECT_EQ(m.msg().next_command(), Referee::PREPARE_KICKOFF_BLUE);
  ASSERT_TRUE(m.RunUntil(Referee::NORMAL_START));
  EXPECT_EQ(m.msg().stage(), Referee::NORMAL_SECOND_HALF);
  y = 0;
  m.Run(3.2, play);
  EXPECT_EQ(m.msg().stage(), Referee::POST_GAME);
  EXPECT_TRUE(m.referee.finished());
}

TEST(BuiltinReferee, NoProgressForFiveSecondsIsAForceStart) {
  Match m;
  m.KickOff();
  m.view.ball = {1.0, 1.0};  // kicked: in play
  m.Run(4.9);
  EXPECT_EQ(m.msg().command(), Referee::NORMAL_START);
  m.Run(0.2);
  ASSERT_EQ(m.msg().command(), Referee::STOP);
  EXPECT_EQ(m.msg().next_command(), Referee::FORCE_START);
  EXPECT_EQ(m.referee.history().back().type(), GameEvent::NO_PROGRESS_IN_GAME);
  ASSERT_TRUE(m.RunUntil(Referee::FORCE_START, 5));
}

TEST(BuiltinReferee, AGoalAfterTheBallFlewTooHighIsAGoalKick) {
  Match m;
  m.KickOff();
  m.view.robots[1].pos = {4.0, 0.0};
  m.view.ball = {4.1, 0.0};
  m.Run(0.05);  // blue touches
  m.view.robots[1].pos = {0.0, 0.0};
  m.view.ball_z = 0.4;  // a chip higher than 0.15 m
  m.view.ball = {5.0, 0.0};
  m.Run(0.02);
  m.view.ball_z = 0.02;
  m.view.ball = {6.1, 0.0};
  m.Run(0.02);
  EXPECT_EQ(m.msg().blue().score(), 0u);
  EXPECT_EQ(m.referee.history().back().type(), GameEvent::INVALID_GOAL);
  // A goal kick for yellow, who defends +x: 1 m from the goal line, 0.2 m from the touch line.
  EXPECT_EQ(m.msg().next_command(), Referee::DIRECT_FREE_YELLOW);
  EXPECT_FLOAT_EQ(m.msg().designated_position().x(), 5000.0f);
  EXPECT_FLOAT_EQ(m.msg().designated_position().y(), 4300.0f);
}

// A stoppage (no progress: STOP, then FORCE_START) in which blue 1 drives at 2 m/s past the 2 s
// grace, while yellow 1 stands 0.3 m from the ball so that play does not resume before.
void StoppageWithSpeeding(Match& m) {
  m.view.ball = {m.view.ball.x + 0.2, 0.5};  // in play, then stalled (5 s Div A, 10 s Div B)
  ASSERT_TRUE(m.RunUntil(Referee::STOP, 11));
  m.view.robots[3].pos = {m.view.ball.x + 0.3, m.view.ball.y};
  m.Run(2.1);
  m.view.robots[1].vel = {2.0, 0.0};
  m.Run(0.1);
  m.view.robots[1].vel = {0.0, 0.0};
  m.view.robots[3].pos = {2, -1};
  ASSERT_TRUE(m.RunUntil(Referee::FORCE_START, 20));
}

TEST(BuiltinReferee, ThreeFoulsAreAYellowCard) {
  Match m;
  m.KickOff();
  for (int i = 0; i < 3; ++i) {
    StoppageWithSpeeding(m);
    EXPECT_EQ(m.msg().blue().foul_counter(), static_cast<unsigned>(i + 1));
  }
  EXPECT_EQ(m.msg().blue().yellow_cards(), 1u);
  EXPECT_EQ(m.msg().blue().max_allowed_bots(), 10u);
  ASSERT_EQ(m.msg().blue().yellow_card_times_size(), 1);
  EXPECT_EQ(m.msg().yellow().foul_counter(), 0u);
  const auto fast = std::count_if(m.referee.history().begin(), m.referee.history().end(),
                                  [](const GameEvent& e) { return e.type() == GameEvent::BOT_TOO_FAST_IN_STOP; });
  EXPECT_EQ(fast, 3);
  EXPECT_EQ(m.referee.history().back().type(), GameEvent::MULTIPLE_FOULS);
  // Blue has 2 robots, under its new limit of 10: nobody has to go.
  for (const auto& r : m.requests) EXPECT_NE(r.kind, FieldRequest::Kind::kTakeOff);
}

TEST(BuiltinReferee, ACardTakesTheHighestNonKeeperOffAFullTeamAndBringsItBack) {
  RefereeConfig c;
  c.division = Division::kB;  // six robots
  c.yellow_card_time = 1.0;
  c.fouls_per_card = 1;
  Match m(c);
  for (int id = 2; id < 6; ++id) m.view.robots.push_back(Match::Robot(Team::kBlue, id, -3.0, -2.5 + id * 0.5));
  m.KickOff();
  StoppageWithSpeeding(m);
  ASSERT_EQ(m.msg().blue().yellow_cards(), 1u);
  EXPECT_EQ(m.msg().blue().max_allowed_bots(), 5u);
  const auto off = std::find_if(m.requests.begin(), m.requests.end(),
                                [](const FieldRequest& r) { return r.kind == FieldRequest::Kind::kTakeOff; });
  ASSERT_NE(off, m.requests.end());
  EXPECT_EQ(off->robot, (RobotId{Team::kBlue, 5}));
  // The card runs in playing time only; after it the robot comes back.
  m.Run(1.5, [&] { m.view.ball.x += 0.002; });
  const auto on = std::find_if(m.requests.begin(), m.requests.end(),
                               [](const FieldRequest& r) { return r.kind == FieldRequest::Kind::kPutOn; });
  ASSERT_NE(on, m.requests.end());
  EXPECT_EQ(on->robot, (RobotId{Team::kBlue, 5}));
  EXPECT_EQ(m.msg().blue().max_allowed_bots(), 6u);
  EXPECT_EQ(m.msg().blue().yellow_card_times_size(), 0);
}

TEST(BuiltinReferee, TooManyRobotsStopsPlayForAForceStartOncePerTenSeconds) {
  RefereeConfig c;
  c.division = Division::kB;  // six allowed
  Match m(c);
  for (int id = 2; id < 7; ++id) m.view.robots.push_back(Match::Robot(Team::kYellow, id, 3.0, -2.5 + id * 0.5));
  m.KickOff();  // seven yellow robots: over the limit as soon as play runs
  EXPECT_EQ(m.msg().command(), Referee::NORMAL_START);
  m.Run(0.02);
  ASSERT_EQ(m.msg().command(), Referee::STOP);
  EXPECT_EQ(m.msg().next_command(), Referee::FORCE_START);
  ASSERT_EQ(m.msg().game_events_size(), 1);
  const auto& e = m.msg().game_events(0);
  EXPECT_EQ(e.type(), GameEvent::TOO_MANY_ROBOTS);
  EXPECT_EQ(e.too_many_robots().by_team(), ::YELLOW);
  EXPECT_EQ(e.too_many_robots().num_robots_allowed(), 6);
  EXPECT_EQ(e.too_many_robots().num_robots_on_field(), 7);
  ASSERT_TRUE(m.RunUntil(Referee::FORCE_START, 10));
  m.Run(1.0);  // not raised again within 10 s
  EXPECT_EQ(m.msg().command(), Referee::FORCE_START);
  m.view.robots.back().present = false;  // the team took one off
  m.view.ball = {0.5, 0.5};
  m.Run(10.0, [&] { m.view.ball.x += 0.001; });
  const auto too_many = std::count_if(m.referee.history().begin(), m.referee.history().end(),
                                      [](const GameEvent& g) { return g.type() == GameEvent::TOO_MANY_ROBOTS; });
  EXPECT_EQ(too_many, 1);
}

TEST(FieldRulesTest, PlacementPointsFollowTheGameController) {
  const FieldRules rules(DivA());
  // Touch line: 0.2 m in, and at least 0.2 m from the goal lines.
  const P2 t = rules.PlacementAfter({Exit::kTouchLine, {5.95, -4.5}, 0}, false);
  EXPECT_NEAR(t.x, 5.8, 1e-9);
  EXPECT_NEAR(t.y, -4.3, 1e-9);
  // Goal kick and corner at the −x goal line, ball out on the +y side.
  const P2 g = rules.PlacementAfter({Exit::kGoalLine, {-6.0, 2.0}, -1}, false);
  EXPECT_NEAR(g.x, -5.0, 1e-9);
  EXPECT_NEAR(g.y, 4.3, 1e-9);
  const P2 c = rules.PlacementAfter({Exit::kGoalLine, {-6.0, 2.0}, -1}, true);
  EXPECT_NEAR(c.x, -5.8, 1e-9);
  EXPECT_NEAR(c.y, 4.3, 1e-9);
  // A point near the defense area is pushed out along the nearer axis.
  const P2 d = rules.ValidFreeKickPoint({4.0, 0.5});
  EXPECT_NEAR(d.x, 3.2, 1e-9);  // 6 − 1.8 − 1
  EXPECT_NEAR(d.y, 0.5, 1e-9);
  // Leaving: entirely over the line only.
  EXPECT_FALSE(rules.Left({0, 4.5 + 0.02}, 0.0215, 0.02));
  EXPECT_TRUE(rules.Left({0, 4.5 + 0.022}, 0.0215, 0.02));
  const auto goal = rules.Left({6.05, 0.3}, 0.0215, 0.02);
  ASSERT_TRUE(goal);
  EXPECT_EQ(goal->kind, Exit::kGoal);
  EXPECT_EQ(goal->goal_side, 1);
  const auto wide = rules.Left({6.05, 1.2}, 0.0215, 0.02);
  ASSERT_TRUE(wide);
  EXPECT_EQ(wide->kind, Exit::kGoalLine);
}

}  // namespace
}  // namespace ubersim::match
