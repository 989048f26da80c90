// SPDX-License-Identifier: Apache-2.0
// `ubersim calibrate` as a user runs it. A drill recorded in tests/calibrate/data/world.yaml — a
// ball, robots, cameras and radio far from the shipped defaults, with noise, drop-outs, false balls
// and latency on — is fitted over the shipped Div B world, whose values all differ from the test
// world's, and the files it writes must hold the test world's numbers (within the tolerances
// below): a value the fit did not write would keep Div B's and fail. A log with too little data
// says so (exit 9); a damaged one names the record and its byte offset (exit 1).
#include <gtest/gtest.h>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "run_ubersim.hpp"

namespace {

namespace fs = std::filesystem;
using ubersim::testing::RunUbersim;

const std::string kWorld = UBERSIM_SOURCE_DIR "/tests/calibrate/data/world.yaml";

fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("ubersim_calibrate_cli_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string Slurp(const fs::path& file) {
  std::ifstream f(file);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

YAML::Node Material(const YAML::Node& world, const std::string& a, const std::string& b) {
  for (const auto& m : world["materials"]) {
    const auto x = m["between"][0].as<std::string>(), y = m["between"][1].as<std::string>();
    if ((x == a && y == b) || (x == b && y == a)) return m;
  }
  return {};
}

TEST(CalibrateCli, ADrillFitsBackTheWorldItWasRecordedIn) {
  const fs::path dir = TempDir("drill");
  const fs::path log = dir / "drill.log.gz";
  const auto drill = RunUbersim("calibrate --drill " + log.string() + " --world " + kWorld + " --robots 5 --duration 240");
  ASSERT_EQ(drill.exit_code, 0) << drill.output;
  EXPECT_NE(drill.output.find("recorded"), std::string::npos) << drill.output;

  const fs::path out = dir / "fit";
  const auto fit =
      RunUbersim("calibrate " + log.string() + " --out " + out.string() + " --geometry-models --check --dump-tracks");
  ASSERT_EQ(fit.exit_code, 0) << fit.output;
  const YAML::Node world = YAML::LoadFile((out / "world.yaml").string());

  // Ball: μ 0.25 (Div B 0.35); a rolling deceleration of 0.548 m/s², which Div B's golf ball
  // (inertia factor 0.4, kept: it is the ball's) gets from ρ = 0.548·1.4·0.0215/9.81 = 0.00168 m.
  const YAML::Node carpet = Material(world, "ball", "carpet");
  ASSERT_TRUE(carpet) << Slurp(out / "world.yaml");
  EXPECT_NEAR(carpet["mu"].as<double>(), 0.25, 0.0125) << fit.output;
  EXPECT_NEAR(carpet["rolling_friction"].as<double>(), 0.001681, 0.000085);
  const YAML::Node ball = YAML::LoadFile((out / "ball.yaml").string());
  EXPECT_DOUBLE_EQ(ball["inertia_factor"].as<double>(), 0.4);
  EXPECT_NEAR(ball["surface"]["rolling_friction"].as<double>(), 0.001681, 0.000085);
  // The geometry announces the league's form: −μ·g, −ρ·g/((1 + k)·r), and the switch the kicks
  // showed: spin-free 1/(1 + k) = 2/3, less for the back-spin a robot's dribbler bar gives a ball
  // it kicks (the unit tests check the switch against a known truth).
  bool announced = false;
  for (const auto& t : world["transports"]) {
    if (t["plugin"].as<std::string>() != "ssl_vision") continue;
    const YAML::Node m = t["ball_model"]["straight_two_phase"];
    EXPECT_NEAR(m["acc_slide"].as<double>(), -2.4525, 0.12);
    EXPECT_NEAR(m["acc_roll"].as<double>(), -0.548, 0.03);
    EXPECT_GT(m["k_switch"].as<double>(), 0.45);
    EXPECT_LT(m["k_switch"].as<double>(), 2.0 / 3.0 + 0.02);
    announced = true;
  }
  EXPECT_TRUE(announced) << Slurp(out / "world.yaml");

  // Robots (blue 0..4): 2.2 m/s, 4.5 / 5.5 m/s², 7 rad/s, 30 / 40 rad/s²; command latency 40 ms
  // of radio plus up to a 5 ms step.
  for (int id = 0; id < 5; ++id) {
    const fs::path file = out / ("robot-blue-" + std::to_string(id) + ".yaml");
    ASSERT_TRUE(fs::exists(file)) << fit.output;
    const YAML::Node limits = YAML::LoadFile(file.string())["drive"]["limits"];
    SCOPED_TRACE("blue " + std::to_string(id));
    EXPECT_NEAR(limits["max_speed"].as<double>(), 2.2, 0.066);
    EXPECT_NEAR(limits["max_accel"].as<double>(), 4.5, 0.45);
    EXPECT_NEAR(limits["max_brake"].as<double>(), 5.5, 0.55);
    EXPECT_NEAR(limits["max_angular_speed"].as<double>(), 7.0, 0.35);
    EXPECT_NEAR(limits["max_angular_accel"].as<double>(), 30.0, 4.5);
    EXPECT_NEAR(limits["max_angular_brake"].as<double>(), 40.0, 6.0);
  }
  EXPECT_NEAR(world["radio"]["latency"].as<double>(), 0.0425, 0.0075);

  // Cameras: 50 Hz, 50 ms to the recorder, σ 2.5 mm / 0.02 rad / 3 mm, drop-outs
  // 8 % and 10 %, 1 ms capture jitter, false balls at dribblers 0.5/s.
  const YAML::Node p = world["perception"];
  EXPECT_NEAR(p["frame_rate"].as<double>(), 50.0, 0.25);
  EXPECT_NEAR(p["latency"].as<double>(), 0.05, 0.002);
  EXPECT_FALSE(p["processing_time"]) << "true stamps: t_sent − t_capture is the latency";
  EXPECT_NEAR(p["noise"]["robot_position"].as<double>(), 0.0025, 0.00025);
  EXPECT_NEAR(p["noise"]["robot_orientation"].as<double>(), 0.02, 0.002);
  EXPECT_NEAR(p["noise"]["ball_position"].as<double>(), 0.003, 0.00045);
  EXPECT_NEAR(p["drop"]["robot"].as<double>(), 0.08, 0.015);
  EXPECT_NEAR(p["drop"]["ball"].as<double>(), 0.10, 0.02);
  EXPECT_NEAR(p["capture_jitter"].as<double>(), 0.001, 0.0003);
  EXPECT_NEAR(p["dribbler_false_balls"].as<double>(), 0.5, 0.15);
  // Two cameras 5 m up over the halves (Div B: one 6 m up over the centre), each over its own half.
  ASSERT_EQ(p["cameras"].size(), 2u) << Slurp(out / "world.yaml");
  EXPECT_FALSE(p["camera_count"]);
  for (const auto& c : p["cameras"]) {
    const double x = c["position"][0].as<double>();
    EXPECT_NEAR(std::abs(x), 2.4, 1e-3);  // over the halves of the carpet (9.6 m with its margins)
    EXPECT_NEAR(c["position"][2].as<double>(), 5.0, 1e-3);
    EXPECT_NEAR(x < 0 ? c["area"][2].as<double>() : c["area"][0].as<double>(), 0.0, 0.021);
  }

  // The fitted world loads, and the report shows the fits and the check.
  const auto validate = RunUbersim("validate " + (out / "world.yaml").string());
  EXPECT_EQ(validate.exit_code, 0) << validate.output;
  const std::string report = Slurp(out / "report.md");
  for (const char* part : {"## The log", "## Summary", "## Ball", "## Robots", "## Cameras",
                           "## Check: the fitted world against the log", "Over "}) {
    EXPECT_NE(report.find(part), std::string::npos) << part;
  }
  // --dump-tracks: what the fits saw, as CSV with a header row.
  for (const char* csv : {"ball.csv", "cameras.csv", "robot-blue-0.csv", "commands-blue-0.csv"}) {
    const std::string text = Slurp(out / "tracks" / csv);
    EXPECT_GT(std::count(text.begin(), text.end(), '\n'), 2) << csv;
  }
  EXPECT_EQ(Slurp(out / "tracks" / "commands-blue-0.csv").rfind("t,forward,left,angular,", 0), 0u);
  int svgs = 0;
  for (const auto& e : fs::directory_iterator(out)) svgs += e.path().extension() == ".svg" ? 1 : 0;
  EXPECT_GE(svgs, 5);
}

TEST(CalibrateCli, ALogWithTooLittleDataSaysSoInsteadOfFitting) {
  const fs::path dir = TempDir("short");
  const fs::path log = dir / "short.log";
  ASSERT_EQ(RunUbersim("calibrate --drill " + log.string() + " --world " + kWorld + " --robots 2 --duration 2").exit_code, 0);
  const auto fit = RunUbersim("calibrate " + log.string() + " --out " + (dir / "fit").string());
  EXPECT_EQ(fit.exit_code, 9) << fit.output;
  EXPECT_NE(fit.output.find("too little data"), std::string::npos) << fit.output;
  EXPECT_NE(fit.output.find("not fitted: ball:"), std::string::npos) << fit.output;
  EXPECT_FALSE(fs::exists(dir / "fit" / "world.yaml"));
  const std::string report = Slurp(dir / "fit" / "report.md");
  EXPECT_NE(report.find("Not fitted, and why"), std::string::npos) << report;
}

TEST(CalibrateCli, ADamagedLogNamesTheRecordAndItsByteOffset) {
  const fs::path dir = TempDir("damaged");
  const fs::path log = dir / "cut.log";
  ASSERT_EQ(RunUbersim("calibrate --drill " + log.string() + " --world " + kWorld + " --robots 2 --duration 3").exit_code, 0);
  fs::resize_file(log, fs::file_size(log) - 7);
  const auto fit = RunUbersim("calibrate " + log.string() + " --out " + (dir / "fit").string());
  EXPECT_EQ(fit.exit_code, 1) << fit.output;
  EXPECT_NE(fit.output.find("ubersim calibrate: " + log.string() + ": record "), std::string::npos) << fit.output;
  EXPECT_NE(fit.output.find(" at byte "), std::string::npos) << fit.output;
  EXPECT_NE(fit.output.find("truncated"), std::string::npos) << fit.output;

  const auto missing = RunUbersim("calibrate " + (dir / "none.log").string());
  EXPECT_EQ(missing.exit_code, 1) << missing.output;
  EXPECT_NE(missing.output.find("none.log"), std::string::npos) << missing.output;
  EXPECT_EQ(RunUbersim("calibrate").exit_code, 2);
  EXPECT_EQ(RunUbersim("calibrate " + log.string() + " --min-runs 0").exit_code, 2);
  EXPECT_EQ(RunUbersim("calibrate " + log.string() + " --drill " + (dir / "d.log").string()).exit_code, 2);
}

}  // namespace
