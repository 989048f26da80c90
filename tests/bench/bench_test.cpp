// SPDX-License-Identifier: Apache-2.0
// `ubersim bench`'s parts: the bare-ODE copy of a world, the random play, one short run. No
// timing is asserted here (the machines are shared); the figures live in docs/performance.md.
#include <cmath>
#include <map>
#include <sstream>

#include <gtest/gtest.h>

#include "bare_ode_mirror.hpp"
#include "bench.hpp"
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

  std::unique_ptr<World> Make(const char* name) {
    WorldModel model = loader.LoadWorld(std::string(UBERSIM_SOURCE_DIR "/models/worlds/") + name + ".yaml");
    model.transports.clear();
    return std::make_unique<World>(model, registry, log, false);
  }
};

TEST_F(BenchWorld, TheBaselineCopiesEveryBodyAndJointAndItsRobotsStandOnTheirWheels) {
  auto world = Make("div-b");
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
  for (int i = 0; i < 2000; ++i) {
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
      // A step behind the kernel's at most: put where the kernel's was, then stepped once.
      EXPECT_LT((lockstep.BodyPosition(index) - kernel).norm(), 3.0 * 0.001 + 1e-9) << "robot body " << index;
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
  for (int i = 0; i < 3000; ++i) {
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
  EXPECT_NE(md.find("| ssl-2003 | precise | 10 |"), std::string::npos) << md;
}

}  // namespace
}  // namespace ubersim::kernel::bench
