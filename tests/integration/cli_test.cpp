// SPDX-License-Identifier: Apache-2.0
// The `ubersim` command as a user runs it: a separate process, its output and exit code.

#include <cctype>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "../common/run_ubersim.hpp"

namespace {

namespace fs = std::filesystem;

using Result = ubersim::testing::CliResult;
using ubersim::testing::RunUbersim;

fs::path TempDir() {
  const fs::path dir = fs::temp_directory_path() /
                       ("ubersim_cli_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

const std::string kModels = UBERSIM_SOURCE_DIR "/models";
const std::string kFakePlugins = UBERSIM_BINARY_DIR "/tests/unit/registry/fakes";

TEST(Cli, HelpAndUsageErrors) {
  const Result help = RunUbersim("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("run [WORLD]"), std::string::npos);
  const Result none = RunUbersim("");
  EXPECT_EQ(none.exit_code, 2);
  const Result unknown = RunUbersim("fly");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.output.find("unknown command 'fly'"), std::string::npos);
  for (const char* cmd : {"run", "validate", "plugins"}) {
    const Result r = RunUbersim(std::string(cmd) + " --help");
    EXPECT_EQ(r.exit_code, 0) << cmd;
    EXPECT_NE(r.output.find("usage: ubersim " + std::string(cmd)), std::string::npos) << cmd;
  }
  const Result bad_option = RunUbersim("run --no-such-option");
  EXPECT_EQ(bad_option.exit_code, 2);
}

TEST(Cli, ValidateAcceptsEveryShippedModelFile) {
  for (const auto& entry : fs::recursive_directory_iterator(kModels)) {
    if (entry.path().extension() != ".yaml") continue;
    const Result r = RunUbersim("validate " + entry.path().string());
    EXPECT_EQ(r.exit_code, 0) << entry.path() << "\n" << r.output;
    EXPECT_NE(r.output.find("ok: "), std::string::npos) << r.output;
  }
}

TEST(Cli, ValidateReportsFileLineColumnAndKey) {
  const fs::path dir = TempDir();
  const fs::path ball = dir / "typo-ball.yaml";
  std::ofstream(ball) << "kind: ball\nname: golf\nradius: 0.0215\nmasss: 0.046\n";
  const Result r = RunUbersim("validate " + ball.string());
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find(ball.string() + ":4:1"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("masss"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

// cli.md's exit codes: a model file naming a plugin that is not there is a plugin error, 4, at the
// plugin key's line, under validate and run alike; a typo in a key is an invalid model, 3.
TEST(Cli, ExitCodesAreTheOnesCliMdGives) {
  const fs::path dir = TempDir() / "codes";
  fs::create_directories(dir);
  std::ofstream(dir / "robot.yaml") << "kind: robot\nname: r\nbody: {mass: 2.3, radius: 0.09, height: 0.146}\n"
                                       "drive: {plugin: warp_drive}\n";
  const fs::path world = dir / "world.yaml";
  std::ofstream(world) << "kind: world\nname: w\nfield: " << kModels << "/fields/div-b.yaml\nball: " << kModels
                       << "/balls/golf.yaml\nrobots:\n  - {team: blue, id: 0, model: robot.yaml, x: 0, y: 0}\n";
  for (const std::string& command : {"validate " + (dir / "robot.yaml").string(),
                                    "run " + world.string() + " --fast --duration 0.1 --local-only"}) {
    const Result r = RunUbersim(command);
    EXPECT_EQ(r.exit_code, 4) << command << "\n" << r.output;
    EXPECT_NE(r.output.find((dir / "robot.yaml").string() + ":4:"), std::string::npos) << command << "\n" << r.output;
    EXPECT_NE(r.output.find("unknown plugin 'warp_drive'"), std::string::npos) << command << "\n" << r.output;
  }
  std::ofstream(dir / "robot.yaml") << "kind: robot\nname: r\nbody: {mass: 2.3, radius: 0.09, heigth: 0.146}\n";
  EXPECT_EQ(RunUbersim("validate " + (dir / "robot.yaml").string()).exit_code, 3);
  EXPECT_EQ(RunUbersim("run --no-such-flag").exit_code, 2);
  fs::remove_all(dir);
}

// A team checks its own robot: validate-physics --robot runs the drive, kicker and dribbler
// scenarios on any robot file against its own limits, into the folder it is given.
TEST(Cli, ValidatePhysicsChecksATeamsOwnRobot) {
  const fs::path dir = TempDir() / "own-robot";
  fs::remove_all(dir);
  const fs::path robot = dir / "our-bot.yaml";
  fs::create_directories(dir);
  std::string text;
  {
    std::ifstream in(kModels + "/robots/ssl-omni-2026.yaml");
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  // A slower robot than the shipped one: its own limits scale the commands and the bands.
  const std::string from = "    max_speed: 3.0";
  ASSERT_NE(text.find(from), std::string::npos);
  text.replace(text.find(from), from.size(), "    max_speed: 2.1");
  std::ofstream(robot) << text;
  EXPECT_EQ(RunUbersim("validate-physics --robot " + robot.string()).exit_code, 2) << "--out is needed";
  const Result r = RunUbersim("validate-physics --robot " + robot.string() + " --out " + (dir / "report").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (const char* id : {"our_bot_steady_velocity", "our_bot_acceleration", "our_bot_kicker_speeds", "our_bot_dribbler_hold"}) {
    EXPECT_NE(r.output.find(std::string("ok   ") + id), std::string::npos) << id << "\n" << r.output;
  }
  std::ifstream report(dir / "report" / "README.md");
  const std::string md((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
  EXPECT_NE(md.find("1.4 m/s commanded from rest"), std::string::npos) << "two thirds of its 2.1 m/s";
  EXPECT_TRUE(fs::exists(dir / "report" / "our-bot-acceleration.svg"));
  fs::remove_all(dir);
}

// `validate` and `run` agree on a robot file: a URDF that `run` would refuse (a link without a
// mass) makes `validate` refuse the robot file, and the world naming it, at the URDF's line.
TEST(Cli, ValidateAndRunRefuseTheSameBrokenUrdf) {
  const fs::path dir = TempDir() / "urdf";
  fs::create_directories(dir);
  std::ofstream(dir / "bad.urdf") << "<robot name=\"bad\">\n  <link name=\"base_link\"/>\n</robot>\n";
  std::string robot_text;
  {
    std::ifstream in(kModels + "/robots/ssl-omni-2026-urdf.yaml");
    robot_text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string from = "urdf: urdf/ssl-omni-2026.urdf";
  ASSERT_NE(robot_text.find(from), std::string::npos);
  robot_text.replace(robot_text.find(from), from.size(), "urdf: bad.urdf");
  std::ofstream(dir / "robot.yaml") << robot_text;
  const fs::path world = dir / "world.yaml";
  std::ofstream(world) << "kind: world\nname: w\nfield: " << kModels << "/fields/div-b.yaml\nball: " << kModels
                       << "/balls/golf.yaml\nrobots:\n  - {team: blue, id: 0, model: robot.yaml, x: 0, y: 0}\n";
  const std::string where = (dir / "bad.urdf").string() + ":2:";
  for (const std::string& command : {"validate " + (dir / "robot.yaml").string(), "validate " + world.string(),
                                    "run " + world.string() + " --fast --duration 0.1 --local-only"}) {
    const Result r = RunUbersim(command);
    EXPECT_EQ(r.exit_code, 3) << command << "\n" << r.output;
    EXPECT_NE(r.output.find(where), std::string::npos) << command << "\n" << r.output;
    EXPECT_NE(r.output.find("positive mass"), std::string::npos) << command << "\n" << r.output;
  }
  fs::remove_all(dir);
}

// Every run of a shipped world here is --local-only: outside a network namespace of its own a
// test never sends on the machine's interfaces (the shipped worlds send on the default route's).
TEST(Cli, RunsTheDefaultWorldFastForAFixedDuration) {
  const Result r = RunUbersim("run --fast --duration 2 --quiet --local-only");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("world 'div-b'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("stopped at sim time 2"), std::string::npos) << r.output;
}

TEST(Cli, RunPrintsTheViewersAddressAndNoViewerLeavesItOut) {
  const Result with = RunUbersim("run --fast --duration 0.5 --quiet --local-only");
  EXPECT_EQ(with.exit_code, 0) << with.output;
  EXPECT_NE(with.output.find("http://127.0.0.1:8080/ (open it in a browser)"), std::string::npos) << with.output;

  const Result without = RunUbersim("run --fast --duration 0.5 --quiet --no-viewer --local-only");
  EXPECT_EQ(without.exit_code, 0) << without.output;
  EXPECT_EQ(without.output.find("http://"), std::string::npos) << without.output;
  EXPECT_NE(without.output.find("transport viewer not started (--no-viewer)"), std::string::npos) << without.output;

  const Result grsim_off = RunUbersim("run --fast --duration 0.5 --quiet --no-transport grsim --local-only");
  EXPECT_EQ(grsim_off.exit_code, 0) << grsim_off.output;
  EXPECT_EQ(grsim_off.output.find("udp 127.0.0.1:20011"), std::string::npos) << grsim_off.output;
  EXPECT_NE(grsim_off.output.find("http://127.0.0.1:8080/"), std::string::npos) << grsim_off.output;

  const Result typo = RunUbersim("run --fast --duration 0.5 --quiet --no-transport grsm --local-only");
  EXPECT_EQ(typo.exit_code, 2) << typo.output;
  EXPECT_NE(typo.output.find("--no-transport grsm: the world has no such transport"), std::string::npos)
      << typo.output;
}

TEST(Cli, BenchPrintsEachWorldWithItsBaselineAndRefusesBadOptions) {
  const Result r = RunUbersim("bench ssl-2003 --duration 0.05 --physics-step 0.002 --markdown " +
                              (TempDir() / "bench.md").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("ssl-2003   fast         10    2.00"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("machine: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bench.md"), std::string::npos) << r.output;
  const Result bad = RunUbersim("bench --physics-step 0.5");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  const Result split = RunUbersim(
      "bench ssl-2003 --duration 0.05 --no-baseline --solver-iterations 10 --solver-iterations-without-ball 6");
  EXPECT_EQ(split.exit_code, 0) << split.output;
  EXPECT_NE(split.output.find(" 10/6 "), std::string::npos) << "the iterations column names both" << split.output;
  const Result zero = RunUbersim("bench --solver-iterations-without-ball 0");
  EXPECT_EQ(zero.exit_code, 2) << zero.output;
  EXPECT_NE(zero.output.find("--solver-iterations-without-ball >= 1"), std::string::npos) << zero.output;
  const Result missing = RunUbersim("bench no-such-world --duration 0.05");
  EXPECT_EQ(missing.exit_code, 3) << missing.output;
  EXPECT_NE(missing.output.find("no-such-world"), std::string::npos) << missing.output;
}

TEST(Cli, OneFlagChoosesThePhysicsProfileAndRunAndBenchSayWhichIsInForce) {
  // The shipped worlds run fast; precise is one flag away.
  const Result precise = RunUbersim("run --fast --duration 0.1 --quiet --no-viewer --local-only --profile precise");
  EXPECT_EQ(precise.exit_code, 0) << precise.output;
  EXPECT_NE(precise.output.find("physics profile precise: step 1 ms, 20 solver iterations, 4 contacts per pair\n"),
            std::string::npos) << precise.output;
  const Result fast = RunUbersim("run --fast --duration 0.1 --quiet --no-viewer --local-only");
  EXPECT_EQ(fast.exit_code, 0) << fast.output;
  EXPECT_NE(fast.output.find("physics profile fast: step 5 ms, 10 solver iterations (2 without the ball), 1 contact per pair"),
            std::string::npos) << fast.output;
  // A flag beside the profile still sets its key.
  const Result tuned = RunUbersim("run --fast --duration 0.1 --quiet --no-viewer --local-only --profile fast --solver-iterations 12");
  EXPECT_NE(tuned.output.find("physics profile fast: step 5 ms, 12 solver iterations"), std::string::npos) << tuned.output;

  const Result bench = RunUbersim("bench ssl-2003 --duration 0.05 --no-baseline --profile fast");
  EXPECT_EQ(bench.exit_code, 0) << bench.output;
  EXPECT_NE(bench.output.find("ssl-2003   fast         10    5.00  10/2"), std::string::npos) << bench.output;

  // Every command that takes physics flags takes --profile, and refuses a name that is none.
  for (const char* command : {"run", "bench", "batch", "soak", "validate-physics"}) {
    const Result bad = RunUbersim(std::string(command) + " --profile quick");
    EXPECT_EQ(bad.exit_code, 2) << command << ": " << bad.output;
    EXPECT_NE(bad.output.find("no physics profile 'quick' (there are: precise, fast)"), std::string::npos)
        << command << ": " << bad.output;
  }
}

TEST(Cli, ValidatePhysicsTriesOtherSettingsOnlyIntoAnotherFolder) {
  const Result refused = RunUbersim("validate-physics --physics-step 0.002 --only ball_roll_2");
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("give --out DIR"), std::string::npos) << refused.output;
  const fs::path dir = TempDir() / "tried";
  const Result r = RunUbersim("validate-physics --physics-step 0.002 --solver-iterations 10 --only ball_roll_2 --out " +
                              dir.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::ifstream report(dir / "README.md");
  const std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("--physics-step 0.002"), std::string::npos) << "the report names the settings it ran";
}

TEST(Cli, BatchRunsSeededWorldsOnWorkersAndChecksTheirHashesAgree) {
  const Result r = RunUbersim("batch ssl-2003 --count 2 --workers 2 --duration 0.2 --physics-step 0.002 --scaling");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 worlds on 2 worker processes"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("speed-up"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("not deterministic"), std::string::npos) << r.output;
  const Result bad = RunUbersim("batch --workers 0");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
}

TEST(Cli, RunPrintsAStatusLineWithSimTimeAndRealTimeFactor) {
  const Result r = RunUbersim("run " + kModels + "/worlds/ssl-2003.yaml --speed 4 --duration 3 --local-only");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("real-time factor"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("sim "), std::string::npos) << r.output;
}

TEST(Cli, RunRefusesABrokenWorldWithWhereAndWhy) {
  const fs::path dir = TempDir();
  const fs::path world = dir / "broken.yaml";
  std::ofstream(world) << "kind: world\nname: broken\nfield: no-such-field.yaml\nball: "
                       << kModels << "/balls/golf.yaml\n";
  const Result r = RunUbersim("run " + world.string() + " --fast --duration 1");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find(world.string() + ":3:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no-such-field.yaml"), std::string::npos) << r.output;
  const Result missing = RunUbersim("run " + (dir / "absent.yaml").string());
  EXPECT_EQ(missing.exit_code, 3) << missing.output;
  EXPECT_NE(missing.output.find("absent.yaml"), std::string::npos) << missing.output;
  fs::remove_all(dir);
}

// A world whose robot names a plugin that throws when constructed: exit code 4, the library file
// and the plugin's own message; `ubersim plugins` lists the good fakes and every refused file.
TEST(Cli, RunRefusesABrokenPluginNamingTheFileAndTheReason) {
  const fs::path dir = TempDir();
  std::ofstream(dir / "robot.yaml") << "kind: robot\nname: fragile\n"
                                       "body: {mass: 2.0, radius: 0.09, height: 0.15}\n"
                                       "drive: {plugin: fake_throwing}\n";
  std::ofstream(dir / "world.yaml") << "kind: world\nname: fragile\nfield: " << kModels
                                    << "/fields/div-b.yaml\nball: " << kModels << "/balls/golf.yaml\n"
                                    << "plugin_paths: [" << kFakePlugins << "]\n"
                                    << "robots:\n  - {team: blue, id: 0, model: robot.yaml, x: 0, y: 1}\n";
  const Result r = RunUbersim("run " + (dir / "world.yaml").string() + " --fast --duration 1");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("libubersim_fake_throwing.so"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("constructor threw: no motor controller on /dev/ttyACM0"), std::string::npos)
      << r.output;

  const Result list = RunUbersim("plugins --plugin-path " + kFakePlugins);
  EXPECT_NE(list.output.find("fake_good"), std::string::npos) << list.output;
  EXPECT_NE(list.output.find("libubersim_fake_plain.so: not an ÜberSim plugin"), std::string::npos)
      << list.output;
  fs::remove_all(dir);
}

// The physics validation as a user runs it: a scenario's verdict line, the report and its plot.
TEST(Cli, ValidatePhysicsWritesTheReportAndItsPlots) {
  const fs::path dir = TempDir() / "report";
  const Result r = RunUbersim("validate-physics --only chip_flight --out " + dir.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("ok   chip_flight"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir / "README.md"));
  EXPECT_TRUE(fs::exists(dir / "chip-flight.svg"));
  const Result bad = RunUbersim("validate-physics --only warp_drive --out " + dir.string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("no validation scenario 'warp_drive' (there are: ball_roll_2"), std::string::npos)
      << bad.output;
  const Result list = RunUbersim("validate-physics --list");
  EXPECT_NE(list.output.find("no_tunnelling"), std::string::npos) << list.output;
  fs::remove_all(dir.parent_path());
}

TEST(Cli, PluginsListsTheSearchPath) {
  const fs::path dir = TempDir();
  const Result r = RunUbersim("plugins --plugin-path " + dir.string());
  EXPECT_NE(r.output.find("search path:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(fs::canonical(dir).string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("PLUGIN"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

TEST(Cli, SoakLogsEveryTeleportOnlyWhenAsked) {
  // The verdict is not the point here (the sanitizer build's memory grows): what is printed is.
  const Result logged = RunUbersim("soak ssl-2003 --duration 2 --seed 1 --quiet --log-teleports");
  // The first teleport comes from the teleports' own random stream, before the physics matters.
  EXPECT_NE(logged.output.find("t = 0.125 s: teleport (robot into wall): robot blue 0 to (1.324, -0.480, 0.000) m"),
            std::string::npos)
      << logged.output;
  // As many teleport lines (put-backs aside) as the summary counts teleports.
  std::size_t lines = 0;
  for (std::size_t at = logged.output.find("teleport ("); at != std::string::npos;
       at = logged.output.find("teleport (", at + 1)) {
    if (logged.output.compare(at, 20, "teleport (put back):") != 0) ++lines;
  }
  const std::size_t summary = logged.output.find("\nteleports:");
  ASSERT_NE(summary, std::string::npos) << logged.output;
  std::istringstream counts(logged.output.substr(summary + 12, logged.output.find('\n', summary + 1) - summary - 12));
  std::size_t counted = 0;
  for (std::string word; counts >> word;) {
    if (std::isdigit(static_cast<unsigned char>(word[0]))) counted += std::stoul(word);
  }
  EXPECT_GT(counted, 0u) << logged.output;
  EXPECT_EQ(lines, counted) << logged.output;
  const Result quiet = RunUbersim("soak ssl-2003 --duration 2 --seed 1 --quiet");
  EXPECT_NE(quiet.output.find("\nteleports:"), std::string::npos) << quiet.output;
  EXPECT_EQ(quiet.output.find("teleport ("), std::string::npos) << quiet.output;
}

}  // namespace
