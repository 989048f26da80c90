// SPDX-License-Identifier: Apache-2.0
// `--referee gc`: the rule engine as the autoreferee of a game controller in CI mode, in lock
// step, against a stand-in written from the protocol's facts, in the shipped Div B world.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <thread>

#include <boost/asio.hpp>

#include "refereed_world.hpp"
#include "standin_game_controller.hpp"

namespace ubersim::match {
namespace {

bool HasEvent(const std::vector<CiInput>& inputs, GameEvent::Type type) {
  for (const CiInput& in : inputs) {
    for (const Input& i : in.api_inputs()) {
      if (i.has_change() && i.change().has_add_game_event_change() &&
          i.change().add_game_event_change().game_event().type() == type) {
        return true;
      }
    }
  }
  return false;
}

// Built before the world (a base of its own): the stand-in and what the session published.
struct GcParts {
  testing::StandinGameController gc;
  std::vector<std::string> published;
};

// The world refereed by the stand-in game controller.
struct GcMatch : GcParts, RefereedWorld {
  GcMatch() : GcParts(), RefereedWorld(Options(gc, published)) {}
  static MatchOptions Options(const testing::StandinGameController& gc, std::vector<std::string>& into) {
    MatchOptions o;
    RefereeConfig c;
    c.division = Division::kB;
    o.referee = c;
    o.game_controller = gc.Address();
    o.recorder = [&into](std::int64_t, WireMessage type, const std::string& bytes) {
      if (type == WireMessage::kReferee) into.push_back(bytes);
    };
    return o;
  }
};

TEST(GameControllerCi, TheEngineIsTheAutorefereeOfAGameControllerInLockStep) {
  GcMatch m;
  // Halted at the start: the engine asks for STOP after 1 s, the game controller prepares the
  // kick-off, the simulator puts the ball on the spot, play starts.
  ASSERT_TRUE(m.StepUntilCommand(Referee::NORMAL_START, 15)) << Referee::Command_Name(m.state().command());
  const auto early = m.gc.Inputs();
  ASSERT_GT(early.size(), 100u);
  // The first input carries the field (mm) and accepts the engine's events without a human.
  ASSERT_TRUE(early[0].has_geometry());
  EXPECT_EQ(early[0].geometry().field().field_length(), 9000);
  ASSERT_EQ(early[0].api_inputs_size(), 1);
  EXPECT_EQ(early[0].api_inputs(0).config_delta().game_event_behavior().at("BALL_LEFT_FIELD_TOUCH_LINE"),
            Config::BEHAVIOR_ACCEPT);
  // The game controller's clock is the simulation's: one input per 10 ms of simulated time.
  for (std::size_t i = 1; i < early.size(); ++i) {
    ASSERT_EQ(early[i].timestamp() - early[i - 1].timestamp(), 10'000'000) << i;
    EXPECT_EQ(early[i].tracker_packet().tracked_frame().robots_size(), 12);
  }
  bool asked_stop = false;
  for (const CiInput& in : early) {
    for (const Input& i : in.api_inputs()) asked_stop = asked_stop || i.change().has_new_command_change();
  }
  EXPECT_TRUE(asked_stop);

  // Over the touch line, yellow (who kicked off) last: the engine reports it; blue is to place and
  // does not, so the simulator does and the engine reports the placement; blue's free kick.
  m.Shoot(Vec3(1.0, 2.95, 0.0215), Vec3(0.0, 0.5, 0.0));
  ASSERT_TRUE(m.StepUntilCommand(Referee::BALL_PLACEMENT_BLUE, 6)) << Referee::Command_Name(m.state().command());
  EXPECT_TRUE(HasEvent(m.gc.Inputs(), GameEvent::BALL_LEFT_FIELD_TOUCH_LINE));
  ASSERT_TRUE(m.StepUntilCommand(Referee::DIRECT_FREE_BLUE, 10)) << Referee::Command_Name(m.state().command());
  EXPECT_TRUE(HasEvent(m.gc.Inputs(), GameEvent::PLACEMENT_SUCCEEDED));
  const Vec3 ball = m.world->GroundTruth().ball.pose.position;
  EXPECT_NEAR(ball.y(), 2.8, 0.15);

  // A shot into the +x goal: a possible goal halts; the engine accepts it as an operator would,
  // then asks for STOP; the ball goes to the centre for yellow's kick-off.
  m.Shoot(Vec3(3.6, 0.25, 0.0215), Vec3(3.0, 0.0, 0.0));
  ASSERT_TRUE(m.StepUntilCommand(Referee::HALT, 3));
  EXPECT_TRUE(HasEvent(m.gc.Inputs(), GameEvent::POSSIBLE_GOAL));
  ASSERT_TRUE(m.StepUntil([&] { return m.state().blue().score() == 1; }, 3));
  ASSERT_TRUE(m.StepUntilCommand(Referee::PREPARE_KICKOFF_YELLOW, 10)) << Referee::Command_Name(m.state().command());
  const Vec3 centre = m.world->GroundTruth().ball.pose.position;
  EXPECT_LT(std::hypot(centre.x(), centre.y()), 0.02);

  // Every message the game controller sent went out (and was recorded), unchanged.
  const auto outputs = m.gc.Outputs();
  ASSERT_EQ(m.published.size(), outputs.size());
  for (std::size_t i = 0; i < outputs.size(); ++i) ASSERT_EQ(m.published[i], outputs[i].SerializeAsString()) << i;
}

TEST(GameControllerCi, AGameControllerThatHangsUpIsAClearErrorNotAHang) {
  // Accepts, reads the first input, and closes without answering.
  boost::asio::io_context io;
  boost::asio::ip::tcp::acceptor acceptor(io, {boost::asio::ip::make_address("127.0.0.1"), 0});
  std::thread server([&] {
    boost::asio::ip::tcp::socket socket(io);
    acceptor.accept(socket);
    char byte[256];
    boost::system::error_code ignored;
    socket.read_some(boost::asio::buffer(byte), ignored);
  });
  testing::ShippedWorlds shipped;
  const kernel::WorldModel model = shipped.Load("div-b");
  kernel::World world(model, shipped.registry, shipped.log, false);
  MatchOptions o;
  o.referee = RefereeConfig{};
  o.game_controller = "127.0.0.1:" + std::to_string(acceptor.local_endpoint().port());
  o.network = false;
  MatchSession session(world, o, shipped.log);
  world.Step();
  try {
    session.AfterStep();
    FAIL() << "no error from a game controller that closed the connection";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("game controller " + o.game_controller + ": hung up (connection reset by peer)"),
              std::string::npos)
        << e.what();
  }
  server.join();
}

TEST(GameControllerCi, NoGameControllerIsAClearErrorNamingTheAddress) {
  testing::ShippedWorlds shipped;
  const kernel::WorldModel model = shipped.Load("div-b");
  kernel::World world(model, shipped.registry, shipped.log, false);
  MatchOptions o;
  o.referee = RefereeConfig{};
  o.game_controller = "127.0.0.1:1";
  o.network = false;
  try {
    MatchSession session(world, o, shipped.log);
    FAIL() << "connected to nothing";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("game controller 127.0.0.1:1: cannot connect"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ubersim::match
