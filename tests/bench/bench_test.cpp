// SPDX-License-Identifier: Apache-2.0
// `ubersim bench`'s parts: the bare-ODE copy of a world, the random play, one short run. No
// timing is asserted here (the machines are shared); the figures live in docs/performance.md.
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include <gtest/gtest.h>

#include "../common/sanitizer.hpp"
#include "bare_ode_mirror.hpp"
#include "bench.hpp"
#include "instructions.hpp"
#include "physics/scene_graph.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel::bench {
namespace {

struct BenchWorld : ::testing::Test {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kWarning};
  PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  ModelLoader loader{ModelLoader::DefaultSchemaDir(),
                     [this](PluginKind k, const std::string& id) { return registry.Find(k, id).schema_json; }};

  // A shipped world at its own profile, or the one named.
  std::unique_ptr<World> Make(const char* name, const std::string& profile = "") {
    WorldModel model = loader.LoadWorld(std::string(UBERSIM_SOURCE_DIR "/models/worlds/") + name + ".yaml");
    if (!profile.empty()) {
      PhysicsOverrides o;
      o.profile = profile;
      o.ApplyTo(model.physics);
    }
    model.transports.clear();
    return std::make_unique<World>(model, registry, log, false);
  }
};

// At precise: at fast's 5 ms the bare copy's wheel robots sag 7 mm within 2 s (measured), which
// the kernel's do not (the copy lacks the kernel's own contact handling, e.g. the shells'
// speculative contacts); there it is a baseline of cost, not of motion.
TEST_F(BenchWorld, TheBaselineCopiesEveryBodyAndJointAndItsRobotsStandOnTheirWheels) {
  auto world = Make("div-b", "precise");
  int bodies = 0;
  std::vector<std::pair<int, double>> chassis;  // body index, start height
  std::map<int, Eigen::Vector2d> start_xy;
  WorldAttorney::Scene(*world).Root().ForEachBody([&](BodyImpl& b) {
    if (b.Name() == "chassis") {
      chassis.emplace_back(bodies, b.GetPose().position.z());
      start_xy[bodies] = b.GetPose().position.head<2>();
    }
    ++bodies;
  });
  ASSERT_EQ(chassis.size(), 12u);
  int joints = 0;
  std::function<void(const NodeImpl&)> count = [&](const NodeImpl& n) {
    joints += static_cast<int>(n.joints().size());
    for (const auto& c : n.children()) count(*c);
  };
  count(WorldAttorney::Scene(*world).Root());
  BareOdeMirror mirror(*world, 3);
  EXPECT_EQ(mirror.bodies(), bodies);
  EXPECT_EQ(mirror.joints(), joints);
  EXPECT_GT(mirror.geoms(), bodies);  // shells and dribbler bars on the chassis, plus the field

  // Driven by the kernel's motor commands for 2 s, every chassis stays at its height: it stands
  // on its wheels (the tyres' carpet spheres), not on the chassis or a tyre's rim; and each robot
  // goes where its twin in the kernel goes.
  RandomPlay play(*world, 5);
  const int two_seconds = static_cast<int>(std::lround(2.0 / world->model().physics.step));
  for (int i = 0; i < two_seconds; ++i) {
    const bool ball_moved = play.BeforeStep();
    world->Step();
    mirror.Record(ball_moved);
    mirror.StepRecorded();
  }
  double moved = 0, apart = 0;
  for (const auto& [index, z] : chassis) {
    EXPECT_NEAR(mirror.BodyPosition(index).z(), z, 0.003) << "chassis body " << index;
    int k = 0;
    Vec3 kernel_position = Vec3::Zero();
    // A copy: a lambda may capture a structured binding only from C++20 on, which clang 14 lacks.
    const auto body = index;
    WorldAttorney::Scene(*world).Root().ForEachBody([&](BodyImpl& b) {
      if (k++ == body) kernel_position = b.GetPose().position;
    });
    apart += (mirror.BodyPosition(index) - kernel_position).head<2>().norm() / 12.0;
    moved += (kernel_position.head<2>() - start_xy.at(index)).norm() / 12.0;
  }
  EXPECT_GT(moved, 0.5) << "the robots drove";
  EXPECT_LT(apart, 0.25 * moved) << "the copy drove the same way";
  // About one carpet contact per wheel (a wheel briefly lifted while robots collide).
  EXPECT_GT(mirror.last_contacts(), 12 * 4 * 3 / 4);
  EXPECT_LT(mirror.last_contacts(), 12 * 4 * 2) << "the tyres' cylinders must not touch the carpet";
}

TEST_F(BenchWorld, TheBaselineStepsTheSameInStretchesAsInLockstepAndItsOneBodyRobotsFollowTheKernels) {
  // One-body robots: their drive holds them up with forces the copy lacks, so the copy puts
  // them where the kernel's are each step, and steps its ball and contacts around them.
  WorldModel model = LoadTrialWorld(loader, UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml", {},
                                    std::string(UBERSIM_SOURCE_DIR "/models/robots/ssl-omni-2026-force.yaml"));
  model.transports.clear();
  World world(model, registry, log, false);
  BareOdeMirror lockstep(world, 3), stretches(world, 3);
  RandomPlay play(world, 5);
  const int steps = 700;
  for (int i = 0; i < steps; ++i) {
    const bool ball_moved = play.BeforeStep();
    world.Step();
    lockstep.Record(ball_moved);  // a stretch of one step
    lockstep.StepRecorded();
    stretches.Record(ball_moved);
    if (stretches.recorded() == 250) stretches.StepRecorded();
  }
  EXPECT_EQ(stretches.recorded(), 200u);
  stretches.StepRecorded();
  EXPECT_EQ(stretches.recorded(), 0u);
  int index = 0, robots = 0;
  WorldAttorney::Scene(world).Root().ForEachBody([&](BodyImpl& b) {
    const Vec3 kernel = b.GetPose().position;
    EXPECT_EQ(stretches.BodyPosition(index), lockstep.BodyPosition(index)) << b.Name() << " " << index;
    if (b.Name() == "chassis") {
      ++robots;
      // A step behind the kernel's at most: put where the kernel's was, then stepped once (at
      // most 3 m/s for one step).
      EXPECT_LT((lockstep.BodyPosition(index) - kernel).norm(), 3.0 * model.physics.step + 1e-9)
          << "robot body " << index;
    }
    ++index;
  });
  EXPECT_EQ(robots, 12);
  EXPECT_GT(lockstep.last_contacts(), 0);
}

TEST_F(BenchWorld, RandomPlayDrivesEveryRobotAndKeepsTheBallMoving) {
  auto world = Make("div-b");
  const WorldSnapshot start = world->GroundTruth();
  RandomPlay play(*world, 7);
  for (int i = 0; i < std::lround(3.0 / world->model().physics.step); ++i) {  // 3 s
    play.BeforeStep();
    world->Step();
  }
  const WorldSnapshot end = world->GroundTruth();
  for (std::size_t i = 0; i < end.robots.size(); ++i) {
    const double moved = (end.robots[i].pose.position - start.robots[i].pose.position).norm();
    EXPECT_GT(moved, 0.3) << "robot " << i;
    EXPECT_TRUE(std::isfinite(moved));
  }
  EXPECT_GT((end.ball.pose.position - start.ball.pose.position).norm(), 0.5);
  EXPECT_EQ(text.str(), "") << "every command accepted";
}

// A ball that left the field is put back clear of every robot: inside a robot's hollow shell it
// could never get out (the soak once found one there).
TEST_F(BenchWorld, RandomPlayPutsABallThatLeftTheFieldClearOfTheRobots) {
  auto world = Make("div-b");
  const double ball_radius = world->model().ball->radius;
  PositionEvent out;
  out.target = Target::Ball();
  out.position = Vec3(20.0, 0.0, 0.0);
  int placed = 0;
  for (std::uint64_t seed = 0; seed < 1000; ++seed) {
    world->events().Post(out);
    world->ProcessEvents();
    RandomPlay play(*world, seed);
    if (!play.BeforeStep()) continue;
    world->ProcessEvents();
    ++placed;
    const WorldSnapshot s = world->GroundTruth();
    ASSERT_LT(std::abs(s.ball.pose.position.x()), 10.0) << "seed " << seed << ": not put back";
    for (const RobotState& r : s.robots) {
      EXPECT_GE((r.pose.position - s.ball.pose.position).head<2>().norm(), r.radius + ball_radius)
          << "seed " << seed << ": ball put inside robot " << r.id.id;
    }
  }
  EXPECT_EQ(placed, 1000);
}

TEST_F(BenchWorld, ARunReportsItsSplitAndTheBaseline) {
  BenchOptions o;
  o.worlds = {UBERSIM_SOURCE_DIR "/models/worlds/ssl-2003.yaml"};
  o.sim_seconds = 0.2;
  o.physics.step = 0.002;
  int calls = 0;
  const auto results = RunBench(o, registry, loader, log, [&](const std::string&, double) { ++calls; });
  ASSERT_EQ(results.size(), 1u);
  const BenchResult& r = results[0];
  EXPECT_EQ(r.world, "ssl-2003");
  EXPECT_EQ(r.robots, 10);
  EXPECT_DOUBLE_EQ(r.physics_step, 0.002);
  EXPECT_NEAR(r.sim_seconds, 0.2, 1e-9);
  EXPECT_GT(r.real_time_factor, 0);
  const TimeSplit& s = r.split;
  EXPECT_NEAR(s.collision + s.physics + s.plugins + s.perception + s.transports + s.events + s.other, 1.0, 1e-9);
  EXPECT_GT(s.physics, 0);
  EXPECT_TRUE(r.baseline);
  EXPECT_GT(r.baseline_real_time_factor, 0);
  EXPECT_GT(r.rss_peak_mb, 1.0);
  EXPECT_GT(calls, 10);
  const std::string table = FormatTable(results);
  EXPECT_NE(table.find("ssl-2003"), std::string::npos) << table;
  const std::string md = FormatMarkdown(results, "test machine", "ubersim bench");
  EXPECT_NE(md.find("| ssl-2003 | " + loader.LoadWorld(o.worlds[0]).physics.profile + " | 10 |"), std::string::npos)
      << md;
}

// Scaling with the robots: N robots on the field, half each team, none inside another.
TEST_F(BenchWorld, PlaceRobotsPutsHalfEachTeamOnTheFieldApartAndOutOfTheCentreCircle) {
  const WorldModel shipped = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/div-a.yaml");
  const FieldGeometry& f = shipped.field->geometry;
  for (int count : {1, 2, 6, 12, 22, 31, 32}) {
    WorldModel model = shipped;
    PlaceRobots(model, count);
    ASSERT_EQ(model.robots.size(), static_cast<std::size_t>(count));
    int blue = 0;
    for (std::size_t i = 0; i < model.robots.size(); ++i) {
      const RobotPlacement& a = model.robots[i];
      ASSERT_TRUE(a.model);
      const bool is_blue = a.id.team == Team::kBlue;
      blue += is_blue ? 1 : 0;
      EXPECT_EQ(is_blue, a.x < 0) << "a team in its own half";
      EXPECT_LT(std::abs(a.x), 0.5 * f.field_length);
      EXPECT_LT(std::abs(a.y), 0.5 * f.field_width);
      EXPECT_GT(std::hypot(a.x, a.y), f.center_circle_radius + a.model->body.radius);
      for (std::size_t k = i + 1; k < model.robots.size(); ++k) {
        const RobotPlacement& b = model.robots[k];
        EXPECT_FALSE(a.id == b.id) << count << " robots: " << ToString(a.id) << " twice";
        EXPECT_GT(std::hypot(a.x - b.x, a.y - b.y), a.model->body.radius + b.model->body.radius + 0.05)
            << count << " robots: " << ToString(a.id) << " and " << ToString(b.id);
      }
    }
    EXPECT_EQ(blue, (count + 1) / 2) << count << " robots";
  }
  WorldModel model = shipped;
  EXPECT_THROW(PlaceRobots(model, 33), std::invalid_argument);
  EXPECT_THROW(PlaceRobots(model, 0), std::invalid_argument);
}

// The step's work against the robots: more robots, more contacts and narrow-phase tests, with
// the robot model given (no timing asserted).
TEST_F(BenchWorld, ARunPerRobotCountCountsTheContactsOfEachDrive) {
  for (const char* robot : {"ssl-omni-2026.yaml", "ssl-omni-2026-force.yaml"}) {
    BenchOptions o;
    o.worlds = {UBERSIM_SOURCE_DIR "/models/worlds/div-a.yaml"};
    o.sim_seconds = 1.0;
    o.baseline = false;
    o.physics.profile = "fast";
    o.robot_model = std::string(UBERSIM_SOURCE_DIR "/models/robots/") + robot;
    o.robot_counts = {2, 6};
    const auto results = RunBench(o, registry, loader, log, nullptr);
    ASSERT_EQ(results.size(), 2u);
    const BenchResult& two = results[0];
    const BenchResult& six = results[1];
    EXPECT_EQ(two.robots, 2);
    EXPECT_EQ(six.robots, 6);
    EXPECT_EQ(two.profile, "fast");
    EXPECT_EQ(two.drive, std::string(robot) == "ssl-omni-2026.yaml" ? "omni" : "omni_force");
    EXPECT_FALSE(two.instructions.has_value());
    if (two.drive == "omni") {
      // Wheel bodies stand on the carpet, each through its wheels' contacts.
      EXPECT_GE(two.contacts_per_step, 2 * 2.0) << robot;
      EXPECT_GT(six.contacts_per_step, 2.0 * two.contacts_per_step) << robot;
      EXPECT_GT(six.narrow_tests_per_step, two.narrow_tests_per_step) << robot;
    } else {
      // A one-body robot's drive holds it up with forces: the ball on the carpet, and robots
      // meeting now and then, are the contacts.
      EXPECT_GE(two.contacts_per_step, 0.5) << robot;
      EXPECT_LT(six.contacts_per_step, 6.0) << robot;
      // Their parts ride over the carpet: the broadphase drops them by their boxes, and only
      // the ball and robots meeting reach the narrow phase (one robot's parts, tested, are 4).
      EXPECT_LT(six.narrow_tests_per_step, 4.0) << robot;
    }
    EXPECT_GE(six.contacts_per_step, six.touching_pairs_per_step) << robot;
    EXPECT_GE(six.narrow_tests_per_step, six.touching_pairs_per_step) << robot;
    const TimeSplit& s = six.split;
    EXPECT_NEAR(s.collision + s.physics + s.plugins + s.perception + s.transports + s.events + s.other, 1.0, 1e-9);
    const std::string table = FormatWorkTable(results);
    EXPECT_NE(table.find(two.drive), std::string::npos) << table;
    const std::string csv = FormatCsv(results);
    EXPECT_EQ(csv.rfind("world,profile,drive,robots,", 0), 0u) << csv;
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3) << csv;
    EXPECT_NE(csv.find("div-a,fast," + two.drive + ",6,0.005,"), std::string::npos) << csv;
    EXPECT_NE(FormatWorkMarkdown(results).find("| div-a | fast | " + two.drive + " | 6 |"), std::string::npos);
  }
}

TEST(CallgrindOutput, TheTotalIsTheSummaryLineElseTheTotalsLine) {
  std::istringstream both(
      "version: 1\ncreator: callgrind-3.19.0\ncmd: ubersim bench\nevents: Ir\nsummary: 1234567\n"
      "fn=(1) main\n0 12\ntotals: 1234567\n");
  EXPECT_EQ(CallgrindTotal(both), std::optional<std::uint64_t>(1234567));
  std::istringstream totals_only("events: Ir Dr\nfn=(1) main\n0 3 4\ntotals: 987 55\n");
  EXPECT_EQ(CallgrindTotal(totals_only), std::optional<std::uint64_t>(987));
  std::istringstream summary_first("summary: 42\ntotals: 41\n");
  EXPECT_EQ(CallgrindTotal(summary_first), std::optional<std::uint64_t>(42));
  std::istringstream neither("events: Ir\nfn=(1) main\n0 12\n");
  EXPECT_EQ(CallgrindTotal(neither), std::nullopt);
  std::istringstream garbled("summary: lots\n");
  EXPECT_EQ(CallgrindTotal(garbled), std::nullopt);
}

TEST(CallgrindOutput, TheRunsGetTheBenchsOwnSettings) {
  BenchOptions o;
  o.seed = 7;
  o.physics.profile = "fast";
  o.physics.step = 0.004;
  o.physics.solver_iterations_without_ball = 3;
  o.robot_model = "models/robots/ssl-omni-2026-force.yaml";
  const auto a = CallgrindArguments(o, "div-a.yaml", 12);
  auto has = [&a](const std::string& key, const std::string& value) {
    const auto at = std::find(a.begin(), a.end(), key);
    return at != a.end() && at + 1 != a.end() && *(at + 1) == value;
  };
  ASSERT_GE(a.size(), 2u);
  EXPECT_EQ(a[0], "bench");
  EXPECT_EQ(a[1], std::filesystem::absolute("div-a.yaml").string());
  EXPECT_NE(std::find(a.begin(), a.end(), "--no-baseline"), a.end());
  EXPECT_TRUE(has("--seed", "7"));
  EXPECT_TRUE(has("--robot-count", "12"));
  EXPECT_TRUE(has("--profile", "fast"));
  EXPECT_TRUE(has("--physics-step", "0.0040000000000000001"));
  EXPECT_TRUE(has("--solver-iterations-without-ball", "3"));
  EXPECT_TRUE(has("--robot", std::filesystem::absolute(*o.robot_model).string()));
  EXPECT_EQ(std::find(a.begin(), a.end(), "--duration"), a.end()) << "MeasureInstructions adds it";
  EXPECT_EQ(std::find(a.begin(), a.end(), "--max-contacts"), a.end()) << "not given, not passed";
}

// The real thing, on a tiny run: this test's own build of `ubersim` twice under callgrind.
// Valgrind cannot run a binary built with AddressSanitizer (the suite's sanitizer pass).
using testing::kAddressSanitizer;

TEST_F(BenchWorld, InstructionsAreCountedUnderCallgrindWhenValgrindIsInstalled) {
  if (kAddressSanitizer) GTEST_SKIP() << "valgrind cannot run an AddressSanitizer build";
  const auto valgrind = FindValgrind();
  if (!valgrind) GTEST_SKIP() << "valgrind is not installed";
  BenchOptions o;
  o.worlds = {UBERSIM_SOURCE_DIR "/models/worlds/ssl-2003.yaml"};
  o.sim_seconds = 0.2;
  o.baseline = false;
  o.robot_counts = {2};
  BenchOptions::Instructions counting;
  counting.valgrind = *valgrind;
  counting.program = UBERSIM_BINARY_DIR "/bin/ubersim";
  counting.short_seconds = 0.2;
  counting.long_seconds = 0.4;
  o.instructions = counting;
  const auto results = RunBench(o, registry, loader, log, nullptr);
  ASSERT_EQ(results.size(), 1u);
  ASSERT_TRUE(results[0].instructions.has_value());
  const InstructionFigures& f = *results[0].instructions;
  const double dt = loader.LoadWorld(o.worlds[0]).physics.step;  // the shipped world's profile's
  const int steps = static_cast<int>(std::lround(0.2 / dt));
  EXPECT_EQ(f.short_steps, steps);
  EXPECT_EQ(f.long_steps, 2 * steps);
  EXPECT_GT(f.short_total, 1'000'000u) << "start-up and 0.2 s of steps";
  EXPECT_GT(f.long_total, f.short_total) << "0.2 s of steps more";
  EXPECT_GT(f.per_sim_second, 0);
  EXPECT_NEAR(f.per_step * steps, static_cast<double>(f.long_total - f.short_total), 1.0);
  EXPECT_NEAR(f.per_sim_second, f.per_step / dt, 1e-6 * f.per_sim_second);
  EXPECT_NE(FormatWorkTable(results).find("callgrind counted"), std::string::npos);

  // A run that fails says so, with the end of its output.
  CallgrindRun failing;
  failing.valgrind = *valgrind;
  failing.program = UBERSIM_BINARY_DIR "/bin/ubersim";
  failing.arguments = {"bench", "no-such-world", "--no-baseline"};
  failing.short_seconds = 0.1;
  failing.long_seconds = 0.2;
  try {
    MeasureInstructions(failing);
    ADD_FAILURE() << "no error";
  } catch (const CallgrindError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("the callgrind run failed (exit code "), std::string::npos) << what;
    EXPECT_NE(what.find("no-such-world"), std::string::npos) << what;
    EXPECT_NE(what.find("  | "), std::string::npos) << "the tail of its output: " << what;
  }
}

}  // namespace
}  // namespace ubersim::kernel::bench
