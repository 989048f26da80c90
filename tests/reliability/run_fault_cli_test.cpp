// SPDX-License-Identifier: Apache-2.0
// `ubersim run` and faults, as a user runs it (a separate process): a plugin fault under "stop"
// ends the run with exit code 7, a crash report naming the plugin and a snapshot beside it that
// --restore resumes; "disable" carries on; --snapshot-out and --restore continue a run bit for
// bit; a snapshot of another world is refused; a crash (SIGSEGV) leaves a report and the last
// periodic snapshot.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "../common/run_ubersim.hpp"
#include "ubersim/kernel/snapshot.hpp"

namespace ubersim::kernel {
namespace {

namespace fs = std::filesystem;

using Result = ubersim::testing::CliResult;
using ubersim::testing::RunUbersim;

const std::string kModels = UBERSIM_SOURCE_DIR "/models";

class RunFault : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("ubersim_run_fault_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "crash");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A Div B world with one robot whose drive misbehaves as `fault` says at step `at_step`, and a
  // shipped robot beside it; no transports.
  fs::path FaultyWorld(const std::string& fault, const std::string& policy, int at_step = 300) {
    std::ofstream(dir_ / "faulty.yaml") << "kind: robot\nname: faulty\n"
                                           "body: {mass: 2.0, radius: 0.09, height: 0.15}\n"
                                           "drive: {plugin: faulty_drive, fault: "
                                        << fault << ", at_step: " << at_step << "}\n";
    const fs::path world = dir_ / "world.yaml";
    std::ofstream(world) << "kind: world\nname: faulty-world\nfield: " << kModels << "/fields/div-b.yaml\nball: "
                         << kModels << "/balls/golf.yaml\n"
                         << "plugin_paths: [" << UBERSIM_RELIABILITY_FAKE_DIR << "]\n"
                         << "on_plugin_fault: " << policy << "\n"
                         << "robots:\n  - {team: blue, id: 0, model: faulty.yaml, x: -1, y: 1}\n"
                         << "  - {team: yellow, id: 0, model: " << kModels
                         << "/robots/ssl-omni-2026.yaml, x: 1, y: -1, yaw: 3.14159}\n";
    return world;
  }

  // The crash report and snapshot `ubersim run` left in the crash folder.
  std::pair<fs::path, fs::path> CrashFiles() const {
    fs::path report, snapshot;
    for (const auto& e : fs::directory_iterator(dir_ / "crash")) {
      if (e.path().extension() == ".txt") report = e.path();
      if (e.path().extension() == ".snapshot") snapshot = e.path();
    }
    return {report, snapshot};
  }

  static std::string Read(const fs::path& file) {
    std::ifstream in(file);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

  std::string Run(const fs::path& world, const std::string& more) const {
    return "run " + world.string() + " --fast --quiet --crash-dir " + (dir_ / "crash").string() + " " + more;
  }

  fs::path dir_;
};

TEST_F(RunFault, AFaultUnderStopExitsSevenWithAReportAndASnapshotThatResumes) {
  const fs::path world = FaultyWorld("prestep_throws", "stop");
  const Result r = RunUbersim(Run(world, "--duration 2"));
  ASSERT_EQ(r.exit_code, 7) << r.output;
  const auto [report, snapshot] = CrashFiles();
  ASSERT_FALSE(report.empty()) << r.output;
  ASSERT_FALSE(snapshot.empty()) << r.output;
  EXPECT_NE(r.output.find("crash report " + report.string()), std::string::npos) << r.output;
  const std::string text = Read(report);
  const std::string plugin_file = fs::canonical(UBERSIM_RELIABILITY_FAKE_DIR "/libubersim_faulty_drive.so").string();
  EXPECT_NE(text.find("step 300 (sim time 0.300 s): robot blue 0 drive 'faulty_drive' (" + plugin_file +
                      "): PreStep threw std::runtime_error: motor controller exploded"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("stopped: after step 300"), std::string::npos) << text;
  EXPECT_NE(text.find("resume:  ubersim run " + world.string() + " --restore " + snapshot.string()), std::string::npos)
      << text;
  const SavedState saved = ReadSnapshotFile(snapshot);
  EXPECT_EQ(saved.step, 301);
  ASSERT_EQ(saved.faults.size(), 1u);
  EXPECT_TRUE(saved.robots[0].parts[0].failed);

  // Resumed: the drive stays off, the world steps on to the end.
  const Result resumed = RunUbersim(Run(world, "--duration 0.5 --restore " + snapshot.string()));
  EXPECT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("restored " + snapshot.string() + ": step 301"), std::string::npos) << resumed.output;
}

TEST_F(RunFault, AFaultUnderDisableIsLoggedAndTheRunCarriesOn) {
  const Result nan = RunUbersim(Run(FaultyWorld("nan_force", "disable"), "--duration 0.5"));
  EXPECT_TRUE(CrashFiles().first.empty());
  EXPECT_EQ(nan.exit_code, 0) << nan.output;
  EXPECT_NE(nan.output.find("plugin fault at step 300: robot blue 0 drive 'faulty_drive'"), std::string::npos)
      << nan.output;
  EXPECT_NE(nan.output.find("left a non-finite value: blue/0/chassis: force (inf"), std::string::npos) << nan.output;
  EXPECT_NE(nan.output.find("the world carries on without it (on_plugin_fault: disable)"), std::string::npos);
  EXPECT_NE(nan.output.find("stopped at sim time 0.5 s after 500 steps"), std::string::npos) << nan.output;
}

// A Configure that throws is a load error, not a fault: exit 4 naming the model file, the plugin
// and the reason, and no crash report (there is no running world to resume).
TEST_F(RunFault, AConfigureThatThrowsIsALoadErrorWithoutACrashReport) {
  const Result r = RunUbersim(Run(FaultyWorld("configure_throws", "stop"), "--duration 1 --local-only"));
  ASSERT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("plugin error: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find((dir_ / "faulty.yaml").string() + "): drive plugin 'faulty_drive'"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("failed to configure: std::out_of_range: wheel index 4 of 4"), std::string::npos) << r.output;
  EXPECT_EQ(CrashFiles().first, fs::path()) << "a crash report was written";
  // ubersim validate builds the world too, and refuses it the same way.
  const Result v = RunUbersim("validate " + (dir_ / "world.yaml").string());
  EXPECT_EQ(v.exit_code, 4) << v.output;
  EXPECT_NE(v.output.find("failed to configure: std::out_of_range: wheel index 4 of 4"), std::string::npos) << v.output;
}

// One exception-to-exit-code map for every command (apps/cli/exit_codes.cpp, docs/cli.md): a
// plugin refusing its parameters is a plugin error, 4, under run, bench and soak alike.
TEST_F(RunFault, APluginRefusingItsParametersExitsFourUnderEveryCommand) {
  const fs::path world = FaultyWorld("configure_refuses", "stop");
  const std::string commands[] = {Run(world, "--duration 0.1 --local-only"),
                                  "bench " + world.string() + " --duration 0.05 --no-baseline",
                                  "soak " + world.string() + " --duration 1 --quiet"};
  for (const std::string& command : commands) {
    const Result r = RunUbersim(command);
    EXPECT_EQ(r.exit_code, 4) << command << "\n" << r.output;
    EXPECT_NE(r.output.find("plugin error: "), std::string::npos) << command << "\n" << r.output;
    EXPECT_NE(r.output.find("gain must be positive (a parameter refused)"), std::string::npos) << command << "\n" << r.output;
  }
}

TEST_F(RunFault, SnapshotOutThenRestoreContinuesBitForBit) {
  const fs::path world = FaultyWorld("none", "stop");
  const fs::path straight = dir_ / "straight.snapshot", half = dir_ / "half.snapshot", resumed = dir_ / "resumed.snapshot";
  ASSERT_EQ(RunUbersim(Run(world, "--duration 1 --snapshot-out " + straight.string())).exit_code, 0);
  const Result first = RunUbersim(Run(world, "--duration 0.4 --snapshot-out " + half.string()));
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("snapshot of step 400 written to " + half.string()), std::string::npos) << first.output;
  const Result second =
      RunUbersim(Run(world, "--duration 0.6 --restore " + half.string() + " --snapshot-out " + resumed.string()));
  ASSERT_EQ(second.exit_code, 0) << second.output;
  const SavedState a = ReadSnapshotFile(straight), b = ReadSnapshotFile(resumed);
  EXPECT_EQ(a.step, 1000);
  EXPECT_EQ(b.step, 1000);
  ASSERT_EQ(a.bodies.size(), b.bodies.size());
  for (std::size_t i = 0; i < a.bodies.size(); ++i) {
    EXPECT_EQ(a.bodies[i].position, b.bodies[i].position) << a.bodies[i].path;
    EXPECT_EQ(a.bodies[i].quaternion, b.bodies[i].quaternion) << a.bodies[i].path;
    EXPECT_EQ(a.bodies[i].linear_velocity, b.bodies[i].linear_velocity) << a.bodies[i].path;
    EXPECT_EQ(a.bodies[i].angular_velocity, b.bodies[i].angular_velocity) << a.bodies[i].path;
  }
  EXPECT_EQ(a.perception.rng, b.perception.rng);
}

TEST_F(RunFault, ASnapshotOfAnotherWorldIsRefused) {
  const fs::path other = dir_ / "other.yaml", other_snapshot = dir_ / "other.snapshot";
  std::ofstream(other) << "kind: world\nname: other-world\nfield: " << kModels << "/fields/div-b.yaml\nball: " << kModels
                       << "/balls/golf.yaml\n";
  ASSERT_EQ(RunUbersim(Run(other, "--duration 0.1 --snapshot-out " + other_snapshot.string())).exit_code, 0);
  const Result r = RunUbersim(Run(FaultyWorld("none", "stop"), "--duration 0.1 --restore " + other_snapshot.string()));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("ubersim run: snapshot: the snapshot is of world 'other-world' (" + other.string() +
                          "), not of world 'faulty-world'"),
            std::string::npos)
      << r.output;

  std::ofstream(dir_ / "cut.snapshot", std::ios::binary) << Read(other_snapshot).substr(0, 100);
  const Result cut = RunUbersim(Run(FaultyWorld("none", "stop"), "--restore " + (dir_ / "cut.snapshot").string()));
  EXPECT_EQ(cut.exit_code, 1) << cut.output;
  EXPECT_NE(cut.output.find((dir_ / "cut.snapshot").string() + ": truncated or damaged"), std::string::npos)
      << cut.output;
}

TEST_F(RunFault, ACrashLeavesAReportAndTheLastPeriodicSnapshot) {
  const fs::path world = FaultyWorld("segfault", "stop", 450);
  const Result r = RunUbersim(Run(world, "--duration 2 --crash-snapshot-interval 0.1"));
  EXPECT_EQ(r.signal, SIGSEGV) << r.exit_code << "\n" << r.output;
  const auto [report, snapshot] = CrashFiles();
  ASSERT_FALSE(report.empty()) << r.output;
  const std::string text = Read(report);
  EXPECT_NE(text.find("fatal signal: SIGSEGV (invalid memory access)"), std::string::npos) << text;
  EXPECT_NE(text.find("(the last one taken, of step 400, sim time 0.400 s)"), std::string::npos) << text;
  const SavedState saved = ReadSnapshotFile(snapshot);
  EXPECT_EQ(saved.step, 400);
  EXPECT_EQ(saved.world_name, "faulty-world");
}

}  // namespace
}  // namespace ubersim::kernel
