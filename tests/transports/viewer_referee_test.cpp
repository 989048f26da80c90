// SPDX-License-Identifier: Apache-2.0
// The viewer's match display without sockets: a Referee message as the page's "referee" JSON
// (units converted, missing fields as null, text from the network made safe), and the relay that
// rate-limits them. The plugin receiving a real datagram is in viewer_test.cpp (ViewerMatch).
#include <chrono>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <rapidjson/document.h>
#include <rapidjson/error/en.h>

#include "../common/referee_messages.hpp"
#include "ssl_gc_game_event.pb.h"
#include "ssl_gc_referee_message.pb.h"
#include "viewer_referee.hpp"

namespace {

using ubersim::viewer::EncodeReferee;
using ubersim::viewer::RefereeRelay;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

rapidjson::Document Parse(const std::string& text) {
  rapidjson::Document d;
  // Strict: a browser drops a WebSocket whose text is not valid UTF-8.
  d.Parse<rapidjson::kParseValidateEncodingFlag>(text.c_str());
  EXPECT_FALSE(d.HasParseError()) << rapidjson::GetParseError_En(d.GetParseError()) << " in " << text;
  return d;
}

// Only what the message requires: a halted match before the first kick-off.
Referee Minimal() {
  Referee r = ubersim::testing::HaltedReferee(1'700'000'000'000'000);
  return r;
}

// Mid-match, a ball placement by blue after yellow kicked the ball over the touch line.
Referee Placement() {
  Referee r = Minimal();
  r.set_stage(Referee::NORMAL_FIRST_HALF);
  r.set_stage_time_left(287'500'000);  // µs
  r.set_command(Referee::BALL_PLACEMENT_BLUE);
  r.set_command_counter(7);
  r.set_next_command(Referee::DIRECT_FREE_BLUE);
  r.set_current_action_time_remaining(29'000'000);
  r.mutable_designated_position()->set_x(1500.0f);  // mm
  r.mutable_designated_position()->set_y(-250.0f);
  r.set_blue_team_on_positive_half(true);
  Referee::TeamInfo* y = r.mutable_yellow();
  y->set_name("ER-Force");
  y->set_score(2);
  y->set_yellow_cards(1);
  y->add_yellow_card_times(95'000'000);
  y->set_foul_counter(3);
  y->set_goalkeeper(1);
  y->set_ball_placement_failures(1);
  y->set_can_place_ball(true);
  y->set_max_allowed_bots(5);
  Referee::TeamInfo* b = r.mutable_blue();
  b->set_name("TIGERs Mannheim");
  b->set_score(1);
  b->set_red_cards(1);
  b->set_foul_counter(0);
  b->set_goalkeeper(4);
  GameEvent* e = r.add_game_events();
  e->set_type(GameEvent::BALL_LEFT_FIELD_TOUCH_LINE);
  e->mutable_ball_left_field_touch_line()->set_by_team(YELLOW);
  e->mutable_ball_left_field_touch_line()->set_by_bot(3);
  r.set_status_message("Ball placement by blue");
  r.set_source_identifier("ubersim-builtin-referee");
  r.set_match_type(FRIENDLY);
  return r;
}

std::vector<std::uint8_t> Bytes(const Referee& r) {
  const std::string s = r.SerializeAsString();
  return {s.begin(), s.end()};
}

TEST(ViewerReferee, AMessageBecomesTheRefereeJsonInSiUnits) {
  const rapidjson::Document d = Parse(EncodeReferee(Placement()));
  EXPECT_STREQ(d["type"].GetString(), "referee");
  EXPECT_STREQ(d["stage"].GetString(), "NORMAL_FIRST_HALF");
  EXPECT_DOUBLE_EQ(d["stage_time_left"].GetDouble(), 287.5);
  EXPECT_STREQ(d["command"].GetString(), "BALL_PLACEMENT_BLUE");
  EXPECT_EQ(d["command_counter"].GetUint(), 7u);
  EXPECT_STREQ(d["next_command"].GetString(), "DIRECT_FREE_BLUE");
  EXPECT_DOUBLE_EQ(d["action_time_left"].GetDouble(), 29.0);
  EXPECT_DOUBLE_EQ(d["designated_position"]["x"].GetDouble(), 1.5);
  EXPECT_DOUBLE_EQ(d["designated_position"]["y"].GetDouble(), -0.25);
  EXPECT_TRUE(d["blue_team_on_positive_half"].GetBool());

  const auto& y = d["yellow"];
  EXPECT_STREQ(y["name"].GetString(), "ER-Force");
  EXPECT_EQ(y["score"].GetUint(), 2u);
  EXPECT_EQ(y["yellow_cards"].GetUint(), 1u);
  ASSERT_EQ(y["yellow_card_times"].Size(), 1u);
  EXPECT_DOUBLE_EQ(y["yellow_card_times"][0].GetDouble(), 95.0);
  EXPECT_EQ(y["red_cards"].GetUint(), 0u);
  EXPECT_EQ(y["fouls"].GetUint(), 3u);
  EXPECT_EQ(y["goalkeeper"].GetUint(), 1u);
  EXPECT_EQ(y["timeouts"].GetUint(), 4u);
  EXPECT_DOUBLE_EQ(y["timeout_time"].GetDouble(), 300.0);
  EXPECT_EQ(y["ball_placement_failures"].GetUint(), 1u);
  EXPECT_TRUE(y["can_place_ball"].GetBool());
  EXPECT_EQ(y["max_allowed_bots"].GetUint(), 5u);
  const auto& b = d["blue"];
  EXPECT_STREQ(b["name"].GetString(), "TIGERs Mannheim");
  EXPECT_EQ(b["score"].GetUint(), 1u);
  EXPECT_EQ(b["red_cards"].GetUint(), 1u);
  EXPECT_EQ(b["fouls"].GetUint(), 0u) << "a zero that was sent is 0, not null";
  EXPECT_EQ(b["goalkeeper"].GetUint(), 4u);
  EXPECT_EQ(b["yellow_card_times"].Size(), 0u);

  const auto& e = d["game_event"];
  EXPECT_STREQ(e["type"].GetString(), "BALL_LEFT_FIELD_TOUCH_LINE");
  EXPECT_STREQ(e["by_team"].GetString(), "yellow");
  EXPECT_EQ(e["by_bot"].GetUint(), 3u);
  EXPECT_TRUE(e["current"].GetBool());
  EXPECT_EQ(d["game_events"].GetInt(), 1);
  EXPECT_STREQ(d["status_message"].GetString(), "Ball placement by blue");
  EXPECT_STREQ(d["source"].GetString(), "ubersim-builtin-referee");
  EXPECT_STREQ(d["match_type"].GetString(), "FRIENDLY");
  EXPECT_FALSE(d.HasMember("packet_timestamp")) << "changes every packet: an unchanged state must encode the same";
}

TEST(ViewerReferee, FieldsTheMessageLeavesOutAreNull) {
  const rapidjson::Document d = Parse(EncodeReferee(Minimal()));
  EXPECT_STREQ(d["stage"].GetString(), "NORMAL_FIRST_HALF_PRE");
  EXPECT_STREQ(d["command"].GetString(), "HALT");
  for (const char* key : {"stage_time_left", "next_command", "action_time_left", "designated_position",
                          "blue_team_on_positive_half", "game_event", "status_message", "source"}) {
    EXPECT_TRUE(d[key].IsNull()) << key;
  }
  EXPECT_STREQ(d["match_type"].GetString(), "UNKNOWN_MATCH") << "the proto's default";
  for (const char* team : {"yellow", "blue"}) {
    for (const char* key : {"fouls", "ball_placement_failures", "can_place_ball", "max_allowed_bots"}) {
      EXPECT_TRUE(d[team][key].IsNull()) << team << "." << key;
    }
  }
}

TEST(ViewerReferee, TimesCanRunOverAndBrokenPositionsAreNull) {
  Referee r = Minimal();
  r.set_stage_time_left(-12'250'000);  // the half ran 12.25 s over
  r.set_current_action_time_remaining(-500'000);
  r.mutable_designated_position()->set_x(std::numeric_limits<float>::quiet_NaN());
  r.mutable_designated_position()->set_y(0.0f);
  const rapidjson::Document d = Parse(EncodeReferee(r));
  EXPECT_DOUBLE_EQ(d["stage_time_left"].GetDouble(), -12.25);
  EXPECT_DOUBLE_EQ(d["action_time_left"].GetDouble(), -0.5);
  EXPECT_TRUE(d["designated_position"].IsNull()) << "JSON has no NaN";
}

TEST(ViewerReferee, GameEventsAreNamedWithTheirTeamWherePresentAndTheLastOneStays) {
  // No type set: the name comes from the payload; no by_team in this event's payload.
  Referee r = Minimal();
  GameEvent* first = r.add_game_events();
  first->mutable_goal()->set_by_team(BLUE);
  GameEvent* last = r.add_game_events();
  last->set_type(GameEvent::NO_PROGRESS_IN_GAME);
  last->mutable_no_progress_in_game()->set_time(10.0f);
  rapidjson::Document d = Parse(EncodeReferee(r));
  EXPECT_STREQ(d["game_event"]["type"].GetString(), "NO_PROGRESS_IN_GAME") << "the last of the list";
  EXPECT_TRUE(d["game_event"]["by_team"].IsNull());
  EXPECT_TRUE(d["game_event"]["by_bot"].IsNull());
  EXPECT_EQ(d["game_events"].GetInt(), 2);

  r.mutable_game_events()->DeleteSubrange(1, 1);
  d = Parse(EncodeReferee(r));
  EXPECT_STREQ(d["game_event"]["type"].GetString(), "GOAL") << "named after its payload";
  EXPECT_STREQ(d["game_event"]["by_team"].GetString(), "blue");

  // A message without events shows the earlier one, marked as not current.
  const GameEvent earlier = r.game_events(0);
  r.clear_game_events();
  d = Parse(EncodeReferee(r, &earlier));
  EXPECT_STREQ(d["game_event"]["type"].GetString(), "GOAL");
  EXPECT_FALSE(d["game_event"]["current"].GetBool());
  EXPECT_EQ(d["game_events"].GetInt(), 0);
}

TEST(ViewerReferee, TextFromTheNetworkIsAlwaysValidJsonAndUtf8) {
  Referee r = Minimal();
  r.mutable_yellow()->set_name(std::string("Bad\xff\xc0\xafName\"\n", 12));  // invalid bytes, a quote, a newline
  r.mutable_blue()->set_name("Über Team ✓");
  r.set_status_message(std::string("\xed\xa0\x80", 3));  // a UTF-16 surrogate, not allowed in UTF-8
  const rapidjson::Document d = Parse(EncodeReferee(r));
  EXPECT_STREQ(d["yellow"]["name"].GetString(), "Bad\xEF\xBF\xBD\xEF\xBF\xBD\xEF\xBF\xBDName\"\n");
  EXPECT_STREQ(d["blue"]["name"].GetString(), "Über Team ✓");
  EXPECT_STREQ(d["status_message"].GetString(), "\xEF\xBF\xBD\xEF\xBF\xBD\xEF\xBF\xBD");
}

// ---------------------------------------------------------------- relay

struct ViewerRefereeRelay : ::testing::Test {
  std::vector<std::string> sent;
  RefereeRelay relay{milliseconds(100), [this](std::shared_ptr<const std::string> json) { sent.push_back(*json); }};
  Clock::time_point t0 = Clock::now();
};

TEST_F(ViewerRefereeRelay, MalformedDatagramsAreRefusedAndChangeNothing) {
  const std::vector<std::vector<std::uint8_t>> bad = {
      {}, {0xff, 0xff, 0xff}, {'h', 'e', 'l', 'l', 'o'},
  };
  for (const auto& bytes : bad) EXPECT_FALSE(relay.OnDatagram(bytes, t0));
  // Well-formed protobuf without the required fields (what a partial writer or another message makes).
  Referee partial;
  partial.set_command(Referee::STOP);
  const std::string p = partial.SerializePartialAsString();
  EXPECT_FALSE(relay.OnDatagram({reinterpret_cast<const std::uint8_t*>(p.data()), p.size()}, t0));
  EXPECT_TRUE(sent.empty());
  EXPECT_EQ(relay.Latest(), nullptr);
  EXPECT_FALSE(relay.LastReceived().has_value());
  EXPECT_EQ(relay.Received(), 0u);
}

TEST_F(ViewerRefereeRelay, SendsChangesAtMostTenASecondAndTheNewestAlwaysLast) {
  Referee r = Placement();
  ASSERT_TRUE(relay.OnDatagram(Bytes(r), t0));
  ASSERT_EQ(sent.size(), 1u) << "the first goes out at once";
  EXPECT_EQ(*relay.Latest(), sent.back());

  // 40 a second, each with less stage time left: held back within 100 ms, the newest then.
  for (int i = 1; i <= 3; ++i) {
    r.set_stage_time_left(r.stage_time_left() - 25'000);
    ASSERT_TRUE(relay.OnDatagram(Bytes(r), t0 + milliseconds(25 * i)));
  }
  EXPECT_EQ(sent.size(), 1u);
  relay.Tick(t0 + milliseconds(90));
  EXPECT_EQ(sent.size(), 1u);
  relay.Tick(t0 + milliseconds(100));
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_DOUBLE_EQ(Parse(sent.back())["stage_time_left"].GetDouble(), 287.425);
  relay.Tick(t0 + milliseconds(300));
  EXPECT_EQ(sent.size(), 2u) << "nothing new";

  // The next datagram after the interval goes out without waiting for a tick.
  r.set_command(Referee::STOP);
  ASSERT_TRUE(relay.OnDatagram(Bytes(r), t0 + milliseconds(400)));
  ASSERT_EQ(sent.size(), 3u);
  EXPECT_STREQ(Parse(sent.back())["command"].GetString(), "STOP");
  EXPECT_EQ(relay.Received(), 5u);
  EXPECT_EQ(relay.LastReceived(), t0 + milliseconds(400));
}

TEST_F(ViewerRefereeRelay, AnUnchangedStateIsNotSentAgainAndTheLastEventStays) {
  Referee r = Placement();
  ASSERT_TRUE(relay.OnDatagram(Bytes(r), t0));
  // The game controller repeating the same state: only its packet time stamp moves.
  r.set_packet_timestamp(r.packet_timestamp() + 1'000'000);
  ASSERT_TRUE(relay.OnDatagram(Bytes(r), t0 + milliseconds(500)));
  EXPECT_EQ(sent.size(), 1u);

  // A running command clears the events; the page still shows the last one, as not current.
  r.set_command(Referee::NORMAL_START);
  r.clear_game_events();
  ASSERT_TRUE(relay.OnDatagram(Bytes(r), t0 + milliseconds(1000)));
  ASSERT_EQ(sent.size(), 2u);
  const rapidjson::Document d = Parse(sent.back());
  EXPECT_STREQ(d["game_event"]["type"].GetString(), "BALL_LEFT_FIELD_TOUCH_LINE");
  EXPECT_FALSE(d["game_event"]["current"].GetBool());
}

}  // namespace
