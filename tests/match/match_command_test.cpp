// SPDX-License-Identifier: Apache-2.0
// `ubersim match` as a user runs it: two team programs (tests/match/scripted_team.py) started with
// their colour and ports, watched, stopped; the result as JSON; a team that crashes or stops
// answering ends the match with a clear result and exit code 8, never a hang. Loopback only.
#include <gtest/gtest.h>

#include <rapidjson/document.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "../common/run_ubersim.hpp"

namespace {

namespace fs = std::filesystem;
using ubersim::testing::CliResult;
using ubersim::testing::RunUbersim;

// Ports of one test (42xxx from `base`: ctest runs the tests of this file in parallel), every
// transport on loopback.
std::string Ports(int base) {
  const auto p = [&](int offset) { return std::to_string(base + offset); };
  return " --local-only --no-viewer --control-port " + p(0) + " --blue-port " + p(1) + " --yellow-port " + p(2) +
         " --grsim-port " + p(11) + " --vision-port " + p(20) + " --referee-port " + p(3) + " --tracker-port " + p(10);
}

struct MatchRun {
  CliResult cli;
  rapidjson::Document result;
  std::string yellow_output, blue_output;
};

std::string Slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

MatchRun Match(const std::string& name, int ports, const std::string& yellow, const std::string& blue,
               const std::string& more) {
  const fs::path dir = fs::temp_directory_path() / ("ubersim-match-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string team = "/usr/bin/python3 " UBERSIM_SOURCE_DIR "/tests/match/scripted_team.py ";
  MatchRun r;
  // `timeout` is the test's guard against a hang, far beyond what the match needs.
  r.cli = RunUbersim("match div-b --yellow '" + team + yellow + "' --blue '" + team + blue + "' --result " +
                         (dir / "result.json").string() + " --team-output " + dir.string() + Ports(ports) + " " + more,
                     "UBERSIM_PROTO_DIR=" UBERSIM_BINARY_DIR "/python timeout -s KILL 120");
  r.result.Parse(Slurp(dir / "result.json").c_str());
  r.yellow_output = Slurp(dir / "yellow.log");
  r.blue_output = Slurp(dir / "blue.log");
  fs::remove_all(dir);
  return r;
}

TEST(MatchCommand, TwoTeamsPlayToTheEndOfTheDurationAndTheResultSaysSo) {
  const MatchRun m = Match("play", 42300, "play", "play", "--duration 6 --speed 3");
  ASSERT_EQ(m.cli.exit_code, 0) << m.cli.output;
  ASSERT_TRUE(m.result.IsObject()) << m.cli.output;
  EXPECT_STREQ(m.result["outcome"].GetString(), "completed");
  EXPECT_STREQ(m.result["reason"].GetString(), "the duration was reached");
  EXPECT_NEAR(m.result["sim_time"].GetDouble(), 6.0, 0.01);
  EXPECT_STREQ(m.result["referee"].GetString(), "builtin");
  EXPECT_STREQ(m.result["stage"].GetString(), "NORMAL_FIRST_HALF");  // kicked off after 5 s
  for (const char* color : {"yellow", "blue"}) {
    const auto& team = m.result[color];
    EXPECT_GT(team["commands_received"].GetInt64(), 100) << color;
    EXPECT_EQ(team["score"].GetUint(), 0u);
    EXPECT_TRUE(team["ended"].IsNull());  // stopped by the match, not ended by itself
  }
  // Each program was told its colour and its own ports.
  EXPECT_NE(m.yellow_output.find("team yellow control 42302 vision 42320 referee 42303"), std::string::npos) << m.yellow_output;
  EXPECT_NE(m.blue_output.find("team blue control 42301 vision 42320 referee 42303"), std::string::npos) << m.blue_output;
}

TEST(MatchCommand, ATeamThatCrashesEndsTheMatchWithItsExitCode) {
  const MatchRun m = Match("crash", 42330, "play", "crash 1", "--speed 2");
  EXPECT_EQ(m.cli.exit_code, 8) << m.cli.output;
  ASSERT_TRUE(m.result.IsObject()) << m.cli.output;
  EXPECT_STREQ(m.result["outcome"].GetString(), "team failed");
  EXPECT_NE(std::string(m.result["reason"].GetString()).find("blue team's program ended (exit code 3)"), std::string::npos)
      << m.result["reason"].GetString();
  EXPECT_STREQ(m.result["blue"]["ended"].GetString(), "exit code 3");
  EXPECT_TRUE(m.result["yellow"]["ended"].IsNull());
  EXPECT_LT(m.result["sim_time"].GetDouble(), 30.0);
}

TEST(MatchCommand, ATeamThatStopsSendingEndsTheMatchAfterTheTimeout) {
  const MatchRun m = Match("silent", 42360, "silent", "play", "--speed 2 --team-timeout 2");
  EXPECT_EQ(m.cli.exit_code, 8) << m.cli.output;
  ASSERT_TRUE(m.result.IsObject()) << m.cli.output;
  EXPECT_NE(std::string(m.result["reason"].GetString()).find("yellow team sent no robot command for 2"), std::string::npos)
      << m.result["reason"].GetString();
  EXPECT_NEAR(m.result["sim_time"].GetDouble(), 2.0, 0.2);
  EXPECT_EQ(m.result["yellow"]["commands_received"].GetInt64(), 0);
}

TEST(MatchCommand, SynchronousAdvancesOneCameraFrameForEachRoundOfBothTeamsCommands) {
  const MatchRun m = Match("sync", 42390, "play", "play", "--sync --duration 3");
  ASSERT_EQ(m.cli.exit_code, 0) << m.cli.output;
  ASSERT_TRUE(m.result.IsObject()) << m.cli.output;
  EXPECT_STREQ(m.result["outcome"].GetString(), "completed");
  // At least one command from each team per frame period (60 Hz) of the 3 s.
  for (const char* color : {"yellow", "blue"}) EXPECT_GE(m.result[color]["commands_received"].GetInt64(), 179) << color;
}

TEST(MatchCommand, SynchronousWithATeamThatDoesNotAnswerEndsAfterTheTimeout) {
  const MatchRun m = Match("sync-silent", 42420, "play", "silent", "--sync --team-timeout 1");
  EXPECT_EQ(m.cli.exit_code, 8) << m.cli.output;
  ASSERT_TRUE(m.result.IsObject()) << m.cli.output;
  EXPECT_NE(std::string(m.result["reason"].GetString()).find("blue team did not answer within 1"), std::string::npos)
      << m.result["reason"].GetString();
  EXPECT_LT(m.result["sim_time"].GetDouble(), 0.05);  // the world waited: nothing was simulated past the first frame
}

// The shipped Div B world with a `match:` block, in the temp directory (model paths made absolute).
std::string WorldWithMatchBlock(const std::string& name, const std::string& block) {
  std::string yaml = Slurp(UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml");
  const std::string models = UBERSIM_SOURCE_DIR "/models/";
  for (std::size_t at = yaml.find("../"); at != std::string::npos; at = yaml.find("../", at)) {
    yaml.replace(at, 3, models);
    at += models.size();
  }
  const fs::path file = fs::temp_directory_path() / (name + "-" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(file) << yaml << "\n" << block << "\n";
  return file.string();
}

TEST(MatchCommand, TheWorldsMatchBlockSetsTheMatchAndItEndsAfterTheSecondHalf) {
  const std::string world = WorldWithMatchBlock(
      "match-block", "match:\n  half_duration: 2\n  half_time_break: 1\n  yellow: {name: Alpha}\n  blue: {name: Beta, keeper: 1}");
  const fs::path dir = fs::temp_directory_path() / ("ubersim-match-block-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string team = "/usr/bin/python3 " UBERSIM_SOURCE_DIR "/tests/match/scripted_team.py play";
  const CliResult r = RunUbersim("match " + world + " --yellow '" + team + "' --blue '" + team + "' --speed 4 --result " +
                                     (dir / "result.json").string() + " --team-output " + dir.string() + Ports(42450),
                                 "UBERSIM_PROTO_DIR=" UBERSIM_BINARY_DIR "/python timeout -s KILL 120");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  rapidjson::Document result;
  result.Parse(Slurp(dir / "result.json").c_str());
  ASSERT_TRUE(result.IsObject()) << r.output;
  EXPECT_STREQ(result["reason"].GetString(), "the match is over");
  EXPECT_STREQ(result["stage"].GetString(), "POST_GAME");
  EXPECT_STREQ(result["yellow"]["name"].GetString(), "Alpha");
  EXPECT_STREQ(result["blue"]["name"].GetString(), "Beta");
  // Two halves of 2 s of play, a 1 s break, and the stoppages before each kick-off.
  EXPECT_GT(result["sim_time"].GetDouble(), 9.0);
  EXPECT_LT(result["sim_time"].GetDouble(), 30.0);
  fs::remove_all(dir);
  fs::remove(world);
}

TEST(MatchCommand, AMistypedMatchBlockIsALocatedModelError) {
  const std::string world = WorldWithMatchBlock("match-typo", "match:\n  referee: builtn");
  const CliResult r = RunUbersim("validate " + world);
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find(world), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("referee"), std::string::npos) << r.output;
  fs::remove(world);
}

TEST(MatchCommand, TheRefereePortMovesTheViewersToo) {
  // The viewer shows the match the referee publishes, wherever that is.
  const CliResult r = RunUbersim(
      "run div-b --local-only --no-transport ssl_simulation --no-transport grsim --vision-port 42920 --viewer-port 42980"
      " --referee builtin --referee-port 42903 --tracker-port 42910 --fast --duration 0.5 -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("transport viewer: shows the match from the referee on 224.5.23.1:42903"), std::string::npos)
      << r.output;
}

TEST(MatchCommand, BadUsageNamesWhatIsMissing) {
  const CliResult no_teams = RunUbersim("match div-b --blue true" + Ports(42480));
  EXPECT_EQ(no_teams.exit_code, 2);
  EXPECT_NE(no_teams.output.find("give both teams' programs"), std::string::npos) << no_teams.output;
  const CliResult none = RunUbersim("match div-b --yellow true --blue true --referee none" + Ports(42480));
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.output.find("a match needs a referee"), std::string::npos) << none.output;
  const CliResult level = RunUbersim("match div-b --yellow true --blue true --log-level loud" + Ports(42480));
  EXPECT_EQ(level.exit_code, 2);
  EXPECT_NE(level.output.find("unknown --log-level 'loud'"), std::string::npos) << level.output;
}

}  // namespace
