// SPDX-License-Identifier: Apache-2.0
// `ubersim bench`'s parts: the bare-ODE copy of a world, the random play, one short run. No
// timing is asserted here (the machines are shared); the figures live in docs/performance.md.
#include <cmath>
#include <sstream>

#include <gtest/gtest.h>

#include "bare_ode_mirror.hpp"
#include "bench.hpp"
#include "ubersim/kernel/scene_graph.hpp"

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
  world->scene().Root().ForEachBody([&](BodyImpl& b) {
    if (b.Name() == "chassis") chassis.emplace_back(bodies, b.GetPose().position.z());
    ++bodies;
  });
  ASSERT_EQ(chassis.size(), 12u);
  int joints = 0;
  std::function<void(const NodeImpl&)> count = [&](const NodeImpl& n) {
    joints += static_cast<int>(n.joints().size());
    for (const auto& c : n.children()) count(*c);
  };
  count(world->scene().Root());
  BareOdeMirror mirror(*world, 3);
  EXPECT_EQ(mirror.bodies(), bodies);
  EXPECT_EQ(mirror.joints(), joints);
  EXPECT_GT(mirror.geoms(), bodies);  // wheels carry two each, plus the field

  // Driven at random for 2 s, every chassis stays at its height: it stands on its wheels (the
  // tyres' carpet spheres), not on the chassis or a tyre's rim.
  for (int i = 0; i < 2000; ++i) mirror.Step();
  for (const auto& [index, z] : chassis) {
    EXPECT_NEAR(mirror.BodyPosition(index).z(), z, 0.003) << "chassis body " << index;
  }
  // About one carpet contact per wheel (a wheel briefly lifted while robots collide).
  EXPECT_GT(mirror.last_contacts(), 12 * 4 * 3 / 4);
  EXPECT_LT(mirror.last_contacts(), 12 * 4 * 2) << "the tyres' cylinders must not touch the carpet";
}

TEST_F(BenchWorld, RandomPlayDrivesEveryRobotAndKeepsTheBallMoving) {
  auto world = Make("div-b");
  const WorldSnapshot start = world->Snapshot();
  RandomPlay play(*world, 7);
  for (int i = 0; i < 3000; ++i) {
    play.BeforeStep();
    world->Step();
  }
  const WorldSnapshot end = world->Snapshot();
  for (std::size_t i = 0; i < end.robots.size(); ++i) {
    const double moved = (end.robots[i].pose.position - start.robots[i].pose.position).norm();
    EXPECT_GT(moved, 0.3) << "robot " << i;
    EXPECT_TRUE(std::isfinite(moved));
  }
  EXPECT_GT((end.ball.pose.position - start.ball.pose.position).norm(), 0.5);
  EXPECT_EQ(text.str(), "") << "every command accepted";
}

TEST_F(BenchWorld, ARunReportsItsSplitAndTheBaseline) {
  BenchOptions o;
  o.worlds = {UBERSIM_SOURCE_DIR "/models/worlds/ssl-2003.yaml"};
  o.sim_seconds = 0.2;
  o.physics_step = 0.002;
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
  EXPECT_NE(md.find("| ssl-2003 | 10 |"), std::string::npos) << md;
}

}  // namespace
}  // namespace ubersim::kernel::bench
