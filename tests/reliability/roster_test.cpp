// SPDX-License-Identifier: Apache-2.0
// Robots come and go while a world runs, as in a match: a robot not in the world comes on from
// its team's model (present: true), goes off and comes back; robot specs rebuild a robot from its
// model with their values over it, checked as a model file; snapshots and resets follow.
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "../common/shipped_worlds.hpp"
#include "ubersim/kernel/snapshot.hpp"
#include "ubersim/kernel/world.hpp"

namespace ubersim::kernel {
namespace {

// A Div B world with two robots a team (a lighter world; the others may come on).
WorldModel Small(testing::ShippedWorlds& s) {
  WorldModel m = s.Load("div-b");
  std::vector<RobotPlacement> kept;
  for (const RobotPlacement& p : m.robots) {
    if (p.id.id < 2) kept.push_back(p);
  }
  m.robots = kept;
  m.perception.ball_position_sigma = m.perception.robot_position_sigma = m.perception.robot_orientation_sigma = 0;
  m.perception.ball_drop = m.perception.robot_drop = 0;
  m.radio.loss = 0;
  return m;
}

// Posts `e` with a reply, applies it, and returns the answer.
template <typename E>
EventAnswer Ask(World& world, E e) {
  std::optional<EventAnswer> answer;
  e.reply = [&answer](const EventAnswer& a) { answer = a; };
  world.events().Post(std::move(e));
  world.ProcessEvents();
  EXPECT_TRUE(answer) << "no answer";
  return answer.value_or(EventAnswer{{"no answer"}, {}});
}

PositionEvent Place(Team team, int id, std::optional<bool> present, std::optional<Vec3> at = std::nullopt) {
  PositionEvent e;
  e.target = Target::Robot(RobotId{team, id});
  e.position = at;
  e.present = present;
  return e;
}

const RobotState* Find(const WorldSnapshot& s, Team team, int id) {
  for (const RobotState& r : s.robots) {
    if (r.id == RobotId{team, id}) return &r;
  }
  return nullptr;
}

// Steps `steps` times, sending `commands` every 50 ms (a drive stops 0.1 s after its last one).
// Steps the world for `seconds`, sending the commands at 100 Hz as a team's software does.
void Drive(World& world, const std::vector<CommandEvent>& commands, double seconds) {
  const double dt = world.model().physics.step;
  const int every = std::max(1, static_cast<int>(std::lround(0.01 / dt)));
  const int steps = static_cast<int>(std::lround(seconds / dt));
  for (int i = 0; i < steps; ++i) {
    if (i % every == 0) {
      for (const CommandEvent& c : commands) world.events().Post(c);
    }
    world.Step();
  }
}

CommandEvent Forward(Team team, int id, double speed) {
  CommandEvent c;
  c.robot = RobotId{team, id};
  c.move = LocalVelocityCommand{speed, 0.0, 0.0};
  return c;
}

// Robots the cameras report in the next `steps` steps (after the frames in flight are out).
std::vector<RobotId> Seen(World& world, double seconds) {
  const double dt = world.model().physics.step;
  const int steps = static_cast<int>(std::lround(seconds / dt));
  for (int i = 0; i < std::lround(0.1 / dt); ++i) world.Step();  // frames captured before now: 35 ms latency
  std::vector<RobotId> seen;
  world.SetVisionObserver([&](const VisionFrame& f) {
    for (const DetectedRobot& r : f.robots) {
      if (std::find(seen.begin(), seen.end(), r.id) == seen.end()) seen.push_back(r.id);
    }
  });
  for (int i = 0; i < steps; ++i) world.Step();
  world.SetVisionObserver(nullptr);
  return seen;
}

bool Contains(const std::vector<RobotId>& ids, RobotId id) { return std::find(ids.begin(), ids.end(), id) != ids.end(); }

TEST(Roster, ARobotComesOnGoesOffAndComesBack) {
  testing::ShippedWorlds s;
  World world(Small(s), s.registry, s.log, false);
  ASSERT_EQ(world.robot_count(), 4u);
  const RobotId seven{Team::kBlue, 7};

  EventAnswer a = Ask(world, Place(Team::kBlue, 7, true, Vec3(1.0, 1.5, 0)));
  EXPECT_TRUE(a.errors.empty()) << a.errors.front();
  EXPECT_EQ(world.robot_count(), 5u);
  const WorldSnapshot came_on = world.GroundTruth();
  const RobotState* r = Find(came_on, Team::kBlue, 7);
  ASSERT_NE(r, nullptr);
  EXPECT_TRUE(r->present);
  EXPECT_NEAR(r->pose.position.x(), 1.0, 1e-9);
  EXPECT_NEAR(r->pose.position.y(), 1.5, 1e-9);
  EXPECT_TRUE(Contains(Seen(world, 0.1), seven));

  // It drives like the others: its plugins took the command.
  const double x0 = Find(world.GroundTruth(), Team::kBlue, 7)->pose.position.x();
  Drive(world, {Forward(Team::kBlue, 7, 1.0)}, 1.0);
  EXPECT_GT(Find(world.GroundTruth(), Team::kBlue, 7)->pose.position.x(), x0 + 0.5);

  a = Ask(world, Place(Team::kBlue, 7, false));
  EXPECT_TRUE(a.errors.empty());
  EXPECT_FALSE(Find(world.GroundTruth(), Team::kBlue, 7)->present);
  EXPECT_FALSE(Contains(Seen(world, 0.1), seven));
  // Off the field, a teleport without present is a quiet no-op.
  const Vec3 parked = Find(world.GroundTruth(), Team::kBlue, 7)->pose.position;
  Ask(world, Place(Team::kBlue, 7, std::nullopt, Vec3(-2, -2, 0)));
  EXPECT_EQ(Find(world.GroundTruth(), Team::kBlue, 7)->pose.position, parked);

  a = Ask(world, Place(Team::kBlue, 7, true, Vec3(-1.0, 0.5, 0)));
  EXPECT_TRUE(a.errors.empty());
  EXPECT_TRUE(Find(world.GroundTruth(), Team::kBlue, 7)->present);
  EXPECT_NEAR(Find(world.GroundTruth(), Team::kBlue, 7)->pose.position.x(), -1.0, 0.02);
  EXPECT_TRUE(Contains(Seen(world, 0.1), seven));
  EXPECT_EQ(world.robot_count(), 5u);  // the same robot, not a second one
}

TEST(Roster, ARobotThatCannotComeOnIsAnsweredWhy) {
  testing::ShippedWorlds s;
  World world(Small(s), s.registry, s.log, false);
  EXPECT_NE(Ask(world, Place(Team::kYellow, 16, true, Vec3(0, 0, 0))).errors.at(0).find("robot ids are 0..15"),
            std::string::npos);
  EXPECT_NE(Ask(world, Place(Team::kYellow, 9, true)).errors.at(0).find("a position is needed"), std::string::npos);
  EXPECT_NE(Ask(world, Place(Team::kYellow, 9, true, Vec3(8, 0, 0))).errors.at(0).find("outside the walls"),
            std::string::npos);
  // Not on the field and not asked on: nothing, and no complaint.
  EXPECT_TRUE(Ask(world, Place(Team::kYellow, 9, std::nullopt, Vec3(0, 0, 0))).errors.empty());
  EXPECT_EQ(world.robot_count(), 4u);
}

TEST(Roster, RobotSpecsRebuildTheRobotFromItsModelWithTheirValues) {
  testing::ShippedWorlds s;
  World world(Small(s), s.registry, s.log, false);
  RobotSpecEvent e;
  e.robot = RobotId{Team::kYellow, 1};
  e.spec.radius = 0.085;
  e.spec.max_speed = 1.0;
  e.spec.max_flat_kick_speed = 5.0;
  e.spec.wheel_angles = std::vector<double>{1.0, 2.4, 3.9, 5.3};
  const Vec3 before = Find(world.GroundTruth(), Team::kYellow, 1)->pose.position;
  const EventAnswer a = Ask(world, e);
  EXPECT_TRUE(a.errors.empty()) << a.errors.front();
  EXPECT_TRUE(a.unapplied.empty()) << a.unapplied.front();
  const WorldSnapshot rebuilt = world.GroundTruth();
  const RobotState* r = Find(rebuilt, Team::kYellow, 1);
  ASSERT_NE(r, nullptr);
  EXPECT_DOUBLE_EQ(r->radius, 0.085);
  EXPECT_NEAR((r->pose.position - before).norm(), 0.0, 1e-9);  // where it was
  // The same spec again (a controller repeats them) rebuilds nothing: the robot keeps moving.
  Drive(world, {Forward(Team::kYellow, 1, 0.5)}, 0.3);
  const std::uint64_t before_repeat = world.StateHash();
  EXPECT_TRUE(Ask(world, e).errors.empty());
  EXPECT_EQ(world.StateHash(), before_repeat);
  // Its drive now tops out at 1 m/s however hard it is pushed; another robot does not.
  Drive(world, {Forward(Team::kYellow, 0, 3.0), Forward(Team::kYellow, 1, 3.0)}, 1.5);
  const WorldSnapshot now = world.GroundTruth();
  EXPECT_LT(Find(now, Team::kYellow, 1)->twist.linear.head<2>().norm(), 1.05);
  EXPECT_GT(Find(now, Team::kYellow, 0)->twist.linear.head<2>().norm(), 2.0);
}

TEST(Roster, ImpossibleSpecValuesAreRefusedOneByOneAndChangeNothing) {
  testing::ShippedWorlds s;
  World world(Small(s), s.registry, s.log, false);
  const std::uint64_t before = world.StateHash();
  RobotSpecEvent e;
  e.robot = RobotId{Team::kBlue, 0};
  e.spec.mass = -1.0;
  e.spec.max_speed = 500.0;
  e.spec.radius = 0.09;
  const EventAnswer a = Ask(world, e);
  ASSERT_EQ(a.errors.size(), 2u);
  EXPECT_NE(a.errors[0].find("mass -1 kg"), std::string::npos) << a.errors[0];
  EXPECT_NE(a.errors[0].find("body.mass"), std::string::npos) << a.errors[0];
  EXPECT_NE(a.errors[1].find("max_speed 500 m/s"), std::string::npos) << a.errors[1];
  EXPECT_NE(a.errors[1].find("drive.limits.max_speed"), std::string::npos) << a.errors[1];
  EXPECT_EQ(world.StateHash(), before);
  EXPECT_DOUBLE_EQ(Find(world.GroundTruth(), Team::kBlue, 0)->radius, 0.09);

  // A value no part of the model takes is named, the rest applies.
  RobotSpecEvent wheels;
  wheels.robot = RobotId{Team::kBlue, 0};
  wheels.spec.wheel_angles = std::vector<double>{0.5, 2.5, 4.0};  // three for a four-wheel drive
  EXPECT_NE(Ask(world, wheels).errors.at(0).find("3 angles for a drive with 4 wheels"), std::string::npos);
}

// Drives every robot for 0.3 s, saves (through the file format), drives on for 0.7 s; a world
// built from `model` and restored from the save, driven the same 0.7 s, must end bit for bit where
// `world` did. Returns the restored world.
std::unique_ptr<World> SaveRestoreAndCompare(testing::ShippedWorlds& s, const WorldModel& model, World& world,
                                             const std::string& what) {
  std::vector<CommandEvent> all;
  for (const RobotState& r : world.GroundTruth().robots) {
    CommandEvent c;
    c.robot = r.id;
    c.move = LocalVelocityCommand{1.5, 0.3 * r.id.id, 1.0};
    all.push_back(c);
  }
  Drive(world, all, 0.3);
  const SavedState saved = DecodeSnapshot(EncodeSnapshot(world.Save()), "memory");
  Drive(world, all, 0.7);
  auto restored = std::make_unique<World>(model, s.registry, s.log, false);
  restored->Restore(saved);
  Drive(*restored, all, 0.7);
  EXPECT_EQ(restored->StateHash(), world.StateHash()) << what;
  return restored;
}

TEST(Roster, SnapshotsKeepRobotsThatCameOnAndSpecsAndContinueBitForBit) {
  testing::ShippedWorlds s;
  const WorldModel model = Small(s);
  World world(model, s.registry, s.log, false);
  Ask(world, Place(Team::kYellow, 5, true, Vec3(2.0, -1.0, 0)));
  RobotSpecEvent e;
  e.robot = RobotId{Team::kBlue, 1};
  e.spec.radius = 0.088;
  e.spec.max_speed = 1.5;
  Ask(world, e);
  RobotSpecEvent later;  // for a robot that is not on the field yet
  later.robot = RobotId{Team::kBlue, 9};
  later.spec.max_speed = 2.0;
  Ask(world, later);
  const std::unique_ptr<World> restored_world = SaveRestoreAndCompare(s, model, world, "all at once");
  World& restored = *restored_world;
  EXPECT_EQ(restored.robot_count(), 5u);
  EXPECT_DOUBLE_EQ(Find(restored.GroundTruth(), Team::kBlue, 1)->radius, 0.088);
  // The spec announced for a robot not yet on the field came along too.
  Ask(restored, Place(Team::kBlue, 9, true, Vec3(0, 2, 0)));
  Drive(restored, {Forward(Team::kBlue, 9, 3.0)}, 1.5);
  EXPECT_LT(Find(restored.GroundTruth(), Team::kBlue, 9)->twist.linear.head<2>().norm(), 2.05);
}

// Each kind of change alone, then save, restore and step on: bit for bit. A robot that comes on
// is built where it came on again (its joints' anchors are kept relative to its bodies), also one
// whose team's subtree is not the last; a robot rebuilt after driving, where it was then.
TEST(Roster, ASnapshotAfterEachKindOfChangeContinuesBitForBit) {
  for (int kind = 0; kind < 5; ++kind) {
    testing::ShippedWorlds s;
    const WorldModel model = Small(s);
    World world(model, s.registry, s.log, false);
    if (kind == 1) Ask(world, Place(Team::kYellow, 5, true, Vec3(2.0, -1.0, 0)));
    if (kind == 2) Ask(world, Place(Team::kBlue, 5, true, Vec3(2.0, -1.0, 0)));
    if (kind >= 3) {
      if (kind == 4) Drive(world, {Forward(Team::kBlue, 0, 1.0)}, 0.2);
      RobotSpecEvent e;
      e.robot = RobotId{Team::kBlue, 0};
      e.spec.radius = 0.088;
      Ask(world, e);
    }
    SaveRestoreAndCompare(s, model, world, "kind " + std::to_string(kind));
  }
}

FieldEvent DivASize() {
  FieldEvent e;
  e.field_length = 12.0;
  e.field_width = 9.0;
  e.goal_width = 1.8;
  e.goal_depth = 0.18;
  e.boundary_width = 0.3;
  return e;
}

// A client's geometry of another league size rebuilds the field from the world's fields:, with
// the robots and ball kept; one of no known size is answered with the sizes it knows.
TEST(Roster, TheFieldChangesToAKnownLeagueSizeKeepingRobotsAndBall) {
  testing::ShippedWorlds s;
  const WorldModel model = Small(s);
  World world(model, s.registry, s.log, false);
  const Vec3 blue0 = Find(world.GroundTruth(), Team::kBlue, 0)->pose.position;
  EventAnswer a = Ask(world, DivASize());
  EXPECT_TRUE(a.errors.empty()) << a.errors.front();
  WorldSnapshot now = world.GroundTruth();
  EXPECT_EQ(now.field->name, "div-a");
  EXPECT_DOUBLE_EQ(now.field->field_length, 12.0);
  EXPECT_EQ(world.robot_count(), 4u);
  EXPECT_NEAR((Find(now, Team::kBlue, 0)->pose.position - blue0).norm(), 0.0, 1e-9);
  // A shot along the carpet now travels to the new walls: 5.5 m out, beyond Div B's 4.8 m carpet.
  PositionEvent shot{Target::Ball(), Vec3(4.0, 2.0, 0.0), std::nullopt, Vec3(4.0, 0.0, 0.0), std::nullopt, std::nullopt};
  world.events().Post(shot);
  double furthest = 0;
  for (int i = 0; i < std::lround(0.8 / world.model().physics.step); ++i) {  // 0.8 s
    world.Step();
    furthest = std::max(furthest, world.GroundTruth().ball.pose.position.x());
  }
  EXPECT_GT(furthest, 5.0);
  // The cameras see the new field: the robots are reported.
  EXPECT_FALSE(Seen(world, 0.1).empty());

  FieldEvent odd = DivASize();
  odd.field_length = 7.0;
  a = Ask(world, odd);
  ASSERT_EQ(a.errors.size(), 1u);
  EXPECT_NE(a.errors[0].find("div-a (12.000 × 9.000 m)"), std::string::npos) << a.errors[0];
  EXPECT_NE(a.errors[0].find("div-b (9.000 × 6.000 m)"), std::string::npos) << a.errors[0];

  // Saved and restored with its field; a reset goes back to the world file's.
  Drive(world, {Forward(Team::kBlue, 0, 1.0)}, 0.2);
  const SavedState saved = DecodeSnapshot(EncodeSnapshot(world.Save()), "memory");
  Drive(world, {Forward(Team::kBlue, 0, 1.0)}, 0.3);
  World restored(model, s.registry, s.log, false);
  restored.Restore(saved);
  EXPECT_EQ(restored.GroundTruth().field->name, "div-a");
  Drive(restored, {Forward(Team::kBlue, 0, 1.0)}, 0.3);
  EXPECT_EQ(restored.StateHash(), world.StateHash());
  world.Reset();
  EXPECT_EQ(world.GroundTruth().field->name, "div-b");
}

TEST(Roster, AResetBringsBackTheWorldFilesRobotsWithTheirSpecs) {
  testing::ShippedWorlds s;
  World world(Small(s), s.registry, s.log, false);
  Ask(world, Place(Team::kYellow, 5, true, Vec3(2.0, -1.0, 0)));
  RobotSpecEvent e;
  e.robot = RobotId{Team::kBlue, 0};
  e.spec.radius = 0.087;
  Ask(world, e);
  world.Reset();
  EXPECT_EQ(world.robot_count(), 4u);
  EXPECT_EQ(Find(world.GroundTruth(), Team::kYellow, 5), nullptr);
  EXPECT_DOUBLE_EQ(Find(world.GroundTruth(), Team::kBlue, 0)->radius, 0.087);  // a team's robots stay its robots
}

}  // namespace
}  // namespace ubersim::kernel
