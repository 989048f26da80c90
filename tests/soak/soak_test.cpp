// SPDX-License-Identifier: Apache-2.0
// `ubersim soak`'s parts on Div A: the random teleports put things where they say, a run is
// deterministic for a seed, and a run reports what the state checks find (with the time, the
// object and the values). The long run itself is `soak_div_a_short` (CMakeLists.txt).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include "soak.hpp"
#include "teleports.hpp"
#include "ubersim/kernel/field.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"
#include "ubersim/kernel/state_check.hpp"

namespace ubersim::kernel::soak {
namespace {

struct DivA : ::testing::Test {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kWarning};
  PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  ModelLoader loader{ModelLoader::DefaultSchemaDir(),
                     [this](PluginKind k, const std::string& id) { return registry.Find(k, id).schema_json; }};

  // The shipped Div A world, at its own profile or the one named.
  std::unique_ptr<World> Make(const std::string& profile = "") {
    WorldModel model = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/div-a.yaml");
    if (!profile.empty()) {
      PhysicsOverrides o;
      o.profile = profile;
      o.ApplyTo(model.physics);
    }
    model.transports.clear();
    return std::make_unique<World>(model, registry, log, false);
  }
};

// How deep the most overlapping pair involving `who` is right now, m (negative: apart).
double DeepestOverlap(const World& world, const std::string& who) {
  StateCheckOptions o;
  o.finite = o.speed = o.carpet = o.walls = false;
  o.limits.robot_penetration = o.limits.ball_penetration = 0.0;
  double deepest = -1.0;
  for (const StateViolation& v : CheckState(world, o)) {
    if (v.object.name == who || (v.other && v.other->name == who)) deepest = std::max(deepest, v.value);
  }
  return deepest;
}

std::string Name(const PositionEvent& e) {
  return e.target.is_ball ? "ball" : std::string("robot ") + ToString(e.target.robot.team) + " " + std::to_string(e.target.robot.id);
}

TEST_F(DivA, EachTeleportPutsItsObjectWhereItSaysAndNeverWhereContactsCannotPartThem) {
  auto world = Make();
  RandomTeleports teleports(*world, 5, 0.5);
  const FieldModel& field = *world->model().field;
  for (int k = 0; k < kTeleportKinds; ++k) {
    const auto kind = static_cast<TeleportKind>(k);
    int overlapping = 0, made = 0, moved_out = 0;
    for (int i = 0; i < 20; ++i) {
      std::optional<PositionEvent> posted;
      teleports.SetObserver([&](const char*, const PositionEvent& e) { posted = e; });
      teleports.Teleport(kind);
      world->ProcessEvents();
      if (!posted) continue;
      ++made;
      const std::string who = Name(*posted);
      EXPECT_EQ(teleports.LastMoved(posted->target), world->clock().time_ns());
      ASSERT_TRUE(posted->position && posted->velocity);
      EXPECT_TRUE(InsideWalls(field, *posted->position, 0.0)) << ToString(kind) << ": " << who;
      const double speed = posted->velocity->norm();
      EXPECT_LE(speed, posted->target.is_ball ? 6.5 + 1e-9 : 3.0 + 1e-9) << ToString(kind);
      // Never the ball's centre inside a robot: a hull is hollow to the collision code.
      for (const RobotState& r : world->GroundTruth().robots) {
        EXPECT_GT((r.pose.position - world->GroundTruth().ball.pose.position).head<2>().norm(), 0.07 - 1e-9)
            << ToString(kind) << ": the ball inside robot " << r.id.id;
      }
      const double overlap = DeepestOverlap(*world, who);
      if (overlap > 0.0) ++overlapping;
      if (posted->target.is_ball) {
        // The world puts a ball that would overlap a shell or a wall at the nearest free spot.
        EXPECT_LT(overlap, 0.001 + 1e-9) << ToString(kind);
        const Vec3 landed = world->GroundTruth().ball.pose.position;
        EXPECT_LT((landed - *posted->position).norm(), 0.3) << ToString(kind);
        if ((landed - *posted->position).norm() > 0.002) ++moved_out;
      }
      // Apart again for the next one.
      teleports.Replace(posted->target);
      world->ProcessEvents();
    }
    EXPECT_GE(made, 15) << ToString(kind);
    EXPECT_EQ(teleports.counts()[k], made) << ToString(kind);
    if (kind == TeleportKind::kRobotAnywhere || kind == TeleportKind::kBallShot) continue;  // free spots
    if (kind == TeleportKind::kBallOntoRobot || kind == TeleportKind::kBallIntoWall) {
      // Put to overlap: the world moves most out (those in by more than a millimetre).
      EXPECT_GE(moved_out, made / 2) << ToString(kind) << " should be put where it overlaps";
      continue;
    }
    // Onto a robot, the flat fronts may just miss each other; into walls robots always overlap.
    const int expected = kind == TeleportKind::kRobotOntoRobot ? made / 2 : made;
    EXPECT_GE(overlapping, expected) << ToString(kind) << " should overlap what it is put onto or into";
  }
}

// Robots put a few millimetres into the +x goal's back wall from behind, as the soak's teleports
// put them before robots were thrown over the end wall (seed 1, at 649 s, 655 s and 784 s), and
// driving on: each is pushed back out and stays on the carpet. Shell against upright wall box is
// exact now (CollideUprightPrismWithBox); normals the wrong way round throw them over the wall.
// Alone, these placements do not reproduce the throw with ODE's mesh test either: that needed
// the soak's crowd (another robot put onto the same spot); the full hour is the evidence.
TEST_F(DivA, ARobotPutIntoAGoalsBackWallFromBehindIsPushedBackOut) {
  struct Case {
    Vec3 position;
    double yaw;
    Vec3 velocity;
  };
  // As the soak's teleports put them (position, yaw, velocity).
  const Case cases[] = {{Vec3(6.285, -0.498, 0.0), -0.120, Vec3(-2.50, 0.0, 0.0)},
                        {Vec3(6.281, -0.502, 0.0), -0.550, Vec3(0.77, 2.90, 0.0)},
                        {Vec3(6.286, -0.319, 0.0), 1.646, Vec3(2.72, -1.26, 0.0)},
                        {Vec3(6.287, 0.077, 0.0), -1.716, Vec3(-0.51, 0.0, 0.0)}};
  auto world = Make();
  const RobotId id{Team::kYellow, 3};
  StateCheckOptions walls_only;
  walls_only.finite = walls_only.speed = walls_only.carpet = walls_only.overlap = false;
  int index = 0;
  for (const Case& c : cases) {
    PositionEvent e;
    e.target = Target::Robot(id);
    e.position = c.position;
    e.yaw = c.yaw;
    e.velocity = c.velocity;
    e.angular_velocity = Vec3::Zero();
    world->events().Post(e);
    double highest = 0.0;
    for (int step = 0; step < 1000; ++step) {
      if (step % 50 == 0) {  // driving on as it was put there (the drive's watchdog wants 10 Hz)
        CommandEvent drive;
        drive.robot = id;
        drive.move = GlobalVelocityCommand{c.velocity.x(), c.velocity.y(), 0.0};
        world->events().Post(drive);
      }
      world->Step();
      for (const RobotState& r : world->GroundTruth().robots) {
        if (r.id.team == id.team && r.id.id == id.id) highest = std::max(highest, r.pose.position.z());
      }
    }
    EXPECT_TRUE(CheckState(*world, walls_only).empty()) << "case " << index;
    EXPECT_LT(highest, 0.1) << "case " << index << ": lifted off the carpet";
    ++index;
  }
}

// The soak's finding at 1378 s (seed 1): a robot put onto another, their hulls overlapping
// deeply, climbed onto it and flew over the side wall. Their wheels and dribblers, inside the
// hulls, met each other in arbitrary directions and tipped it; tipped, the hulls met in ODE's
// mesh test, whose normals pointed up. Robots meet through their hulls only now: put onto one
// another, they part sideways and stay on the carpet.
// Both profiles: at fast a wheel-body robot's hinges sag 1.5-2° at rest (two solver sweeps), and
// a robot pushed out sideways leans up to 5.8° (measured; under 5.7° at precise).
TEST_F(DivA, RobotsPutOntoOneAnotherPartSidewaysAndStayOnTheCarpet) {
  for (const std::string profile : {"precise", "fast"}) {
    SCOPED_TRACE(profile);
    auto world = Make(profile);
    const int steps = static_cast<int>(std::lround(0.6 / world->model().physics.step));
    const double tilt_limit = profile == "precise" ? 0.1 : 0.12;
    const RobotId mover{Team::kYellow, 1}, resting{Team::kBlue, 6};
    const Vec3 at(2.0, -2.0, 0.0);
    auto state = [&](const RobotId& id) {
      for (const RobotState& r : world->GroundTruth().robots) {
        if (r.id == id) return r;
      }
      return RobotState{};
    };
    int index = 0;
    for (double offset : {0.0, 0.03, 0.06, 0.09, 0.12, 0.15}) {
      for (double heading : {0.3, 2.0, 4.0}) {
        PositionEvent rest;
        rest.target = Target::Robot(resting);
        rest.position = at;
        rest.yaw = 1.0;
        rest.velocity = rest.angular_velocity = Vec3::Zero();
        world->events().Post(rest);
        PositionEvent onto;
        onto.target = Target::Robot(mover);
        onto.position = at + offset * Vec3(std::cos(heading), std::sin(heading), 0.0);
        onto.yaw = heading;
        onto.velocity = -3.0 * Vec3(std::cos(heading + 0.4), std::sin(heading + 0.4), 0.0);
        onto.angular_velocity = Vec3::Zero();
        world->events().Post(onto);
        double highest = 0.0, most_tilt = 0.0;
        for (int step = 0; step < steps; ++step) {
          world->Step();
          for (const RobotId& id : {mover, resting}) {
            const RobotState r = state(id);
            highest = std::max(highest, r.pose.position.z());
            most_tilt = std::max(most_tilt, std::acos(std::min(1.0, (r.pose.orientation * Vec3::UnitZ()).z())));
          }
        }
        // Resting, a chassis' centre stands 50 mm up; a robot on another's top would be 150 mm up.
        EXPECT_LT(highest, 0.06) << "case " << index << ": offset " << offset << ", heading " << heading;
        EXPECT_LT(most_tilt, tilt_limit) << "case " << index << ": offset " << offset << ", heading " << heading;
        EXPECT_GT((state(mover).pose.position - state(resting).pose.position).head<2>().norm(), 0.16)
            << "case " << index << ": still inside one another";
        ++index;
      }
    }
  }
}

TEST_F(DivA, TheSameSeedGivesTheSameRunAnotherSeedAnother) {
  SoakOptions o;
  o.sim_seconds = 2.0;
  o.teleport_interval = 0.2;
  auto run = [&](std::uint64_t seed) {
    auto world = Make();
    o.seed = seed;
    return RunSoak(*world, o, nullptr, nullptr);
  };
  const SoakReport a = run(3), b = run(3), c = run(4);
  EXPECT_EQ(a.state_hash, b.state_hash);
  EXPECT_EQ(a.teleports, b.teleports);
  EXPECT_NE(a.state_hash, c.state_hash);
  std::int64_t teleported = 0;
  for (std::int64_t n : a.teleports) teleported += n;
  EXPECT_GT(teleported, 4);  // about 10 expected
  EXPECT_EQ(a.steps, std::lround(2.0 / Make()->model().physics.step));
  EXPECT_EQ(a.checks, 2);
}

// Pinned as tests/reliability/pinned_hash_test.cpp pins the shipped worlds: the suite's sanitizer
// pass (clang) must end on gcc's state. Every teleport kind and the random play's free-ball point
// draw more than one number for one placement; drawn inside one call's arguments, their order was
// the compiler's, and clang's runs went elsewhere (0d16828 and the commit after it). Re-record
// when a change moves the physics, and say why.
TEST_F(DivA, ASeedGivesOneRunWhicheverCompilerBuiltIt) {
  SoakOptions o;
  o.sim_seconds = 10.0;
  o.teleport_interval = 0.2;
  o.seed = 5;
  auto world = Make();
  const SoakReport r = RunSoak(*world, o, nullptr, nullptr);
  for (std::int64_t n : r.teleports) EXPECT_GT(n, 0) << "every kind of teleport drawn";
  char hash[24];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(r.state_hash));
  EXPECT_STREQ(hash, "1e236c8140a9db7e");
}

TEST_F(DivA, ARunReportsEachFindingWithItsTimeAndObjectAndPutsTheObjectBack) {
  auto world = Make();
  SoakOptions o;
  o.sim_seconds = 2.0;
  o.warmup = 0.0;
  // Wheels and the ball rest a fraction of a millimetre in the carpet: a limit of -1 mm flags
  // each robot and the ball. Only that check runs, so nothing else is found.
  o.checks.limits.carpet_penetration = -0.001;
  o.checks.finite = o.checks.speed = o.checks.walls = o.checks.overlap = false;
  std::vector<SoakFinding> seen;
  int progress_calls = 0;
  const SoakReport r = RunSoak(*world, o, [&](const SoakProgress& p) {
    ++progress_calls;
    EXPECT_GT(p.rss_mb, 0.0);
  }, [&](const SoakFinding& f) { seen.push_back(f); });
  EXPECT_EQ(progress_calls, 2);
  ASSERT_EQ(r.finding_count, static_cast<std::int64_t>(seen.size()));
  EXPECT_EQ(r.finding_count, 2 * 23) << "the ball and every robot, at each of the two checks";
  EXPECT_EQ(r.by_issue[static_cast<int>(StateIssue::kUnderCarpet)], r.finding_count);
  EXPECT_EQ(r.replaced, r.finding_count);
  EXPECT_DOUBLE_EQ(seen.front().sim_time, 1.0);
  EXPECT_EQ(seen.front().violation.object.name, "ball");
  EXPECT_EQ(seen[1].violation.object.name, "robot blue 0");
  EXPECT_NE(seen[1].violation.part.find("carpet_contact"), std::string::npos) << seen[1].violation.part;
  EXPECT_EQ(seen.back().violation.object.name, "robot yellow 10");
  EXPECT_DOUBLE_EQ(seen.back().sim_time, 2.0);
  EXPECT_FALSE(r.Pass());
  const std::string summary = FormatSummary(r);
  EXPECT_NE(summary.find("findings: 46 (under the carpet 46)"), std::string::npos) << summary;
  EXPECT_NE(summary.find("verdict: FAIL"), std::string::npos) << summary;
}

TEST_F(DivA, AtTheFastSettingsNoWheelSinksIntoTheCarpetInRandomPlay) {
  // Div A at the validated fast settings (5 ms, 10 / 2 iterations, one contact per pair), random
  // play only, every wheel's and the ball's depth in the carpet checked each simulated second.
  // When QuickStep's island search started from a robot's newest wheel, that wheel sank 10-13 mm
  // (135 findings in these 120 s at the 10 mm limit); since, the deepest has been 2.6-4.2 mm (it
  // moves with every change to the play's trajectories: two sweeps leave a wheel's carpet row
  // loosely converged).
  WorldModel model = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/div-a.yaml");
  model.transports.clear();
  PhysicsOverrides fast;
  fast.step = 0.005;
  fast.solver_iterations = 10;
  fast.solver_iterations_without_ball = 2;
  fast.max_contacts = 1;
  fast.ApplyTo(model.physics);
  World world(model, registry, log, false);
  SoakOptions o;
  o.sim_seconds = 120.0;
  o.teleport_interval = 1e9;  // none
  o.checks.finite = o.checks.speed = o.checks.walls = o.checks.overlap = false;
  o.checks.limits.carpet_penetration = 0.005;  // 4.2 mm the deepest measured
  double deepest = 0.0;
  const SoakReport r = RunSoak(world, o, nullptr, [&](const SoakFinding& f) {
    ADD_FAILURE() << f.sim_time << " s: " << f.violation.object.name << " " << f.violation.part << " "
                  << 1e3 * f.violation.value << " mm into the carpet";
    deepest = std::max(deepest, f.violation.value);
  });
  EXPECT_EQ(r.checks, 120);
  EXPECT_EQ(r.finding_count, 0) << "deepest " << 1e3 * deepest << " mm";
}

// A robot knocked onto two wheels rocks back: leaning past 20° for a moment is not tipped over.
// One that lies on its side is, once it has lain there for `tipped_for`.
// At precise, where the knocks below were measured: this is the soak's counting, not the physics.
TEST_F(DivA, ARobotRockingOntoTwoWheelsIsNotTippedOverOneThatFallsIs) {
  const auto run = [&](double roll_rate, double tipped_for, double* max_lean, double* final_lean) {
    auto world = Make("precise");
    PositionEvent knock;
    knock.target = Target::Robot({Team::kBlue, 3});
    knock.angular_velocity = Vec3(roll_rate, 0.0, 0.0);
    world->events().Post(knock);
    SoakOptions o;
    o.sim_seconds = 3.0;
    o.check_period = 0.0;      // every step: the rock is seen at its peak
    o.teleport_interval = 1e9;  // none
    o.tipped_for = tipped_for;
    o.checks.finite = o.checks.speed = o.checks.walls = o.checks.overlap = o.checks.carpet = false;
    *max_lean = 0.0;
    o.after_step = [&](const World& w) {
      for (const RobotState& r : w.GroundTruth().robots) {
        if (r.id.team != Team::kBlue || r.id.id != 3) continue;
        *final_lean = std::acos(std::clamp((r.pose.orientation * Vec3::UnitZ()).z(), -1.0, 1.0));
        *max_lean = std::max(*max_lean, *final_lean);
      }
    };
    std::vector<SoakFinding> seen;
    RunSoak(*world, o, nullptr, [&](const SoakFinding& f) { seen.push_back(f); });
    return seen;
  };
  double max_lean = 0, final_lean = 0;
  // Knocked at 22 rad/s about its forward axis, the robot leans 33° and is back on four wheels
  // within half a second: what the fast soak's robots put onto one another do.
  EXPECT_TRUE(run(22.0, 0.5, &max_lean, &final_lean).empty());
  EXPECT_GT(max_lean, 0.45);
  EXPECT_LT(final_lean, 0.05);
  // The same rock counted at once is a finding: the check sees it.
  const std::vector<SoakFinding> counted = run(22.0, 0.0, &max_lean, &final_lean);
  ASSERT_EQ(counted.size(), 1u);
  EXPECT_EQ(counted[0].violation.issue, StateIssue::kTipped);
  // Knocked at 30 rad/s it falls onto its side (past 90°): found once it has lain there 0.5 s.
  const std::vector<SoakFinding> fallen = run(30.0, 0.5, &max_lean, &final_lean);
  EXPECT_GT(max_lean, 1.4);
  ASSERT_EQ(fallen.size(), 1u);
  EXPECT_EQ(fallen[0].violation.issue, StateIssue::kTipped);
  EXPECT_EQ(fallen[0].violation.object.name, "robot blue 3");
  EXPECT_GE(fallen[0].sim_time, 0.5);
  EXPECT_LT(fallen[0].sim_time, 1.0);
}

TEST_F(DivA, MemoryIsJudgedAfterTheWarmUp) {
  auto world = Make();
  SoakOptions o;
  o.sim_seconds = 3.0;
  o.warmup = 2.0;
  const SoakReport r = RunSoak(*world, o, nullptr, nullptr);
  EXPECT_DOUBLE_EQ(r.warmup_seconds, 2.0);
  EXPECT_GT(r.rss_warm_mb, 0.0);
  EXPECT_GE(r.rss_peak_mb, r.rss_end_mb);
  EXPECT_NEAR(r.rss_growth, r.rss_end_mb / r.rss_warm_mb - 1.0, 1e-12);
  // Not judged when the run ends inside the warm-up.
  auto other = Make();
  o.warmup = 10.0;
  const SoakReport early = RunSoak(*other, o, nullptr, nullptr);
  EXPECT_EQ(early.rss_warm_mb, 0.0);
  EXPECT_EQ(early.rss_growth, 0.0);
  EXPECT_NE(FormatSummary(early).find("memory: not judged"), std::string::npos);
}

}  // namespace
}  // namespace ubersim::kernel::soak
