// SPDX-License-Identifier: Apache-2.0
// The kernel's state checks: the penetration depth they rest on, then each check firing on a
// deliberately broken Div A world and staying quiet on a sound one.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <gtest/gtest.h>

#include <unistd.h>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "collision/penetration.hpp"
#include "ubersim/kernel/plugin_registry.hpp"
#include "ubersim/kernel/state_check.hpp"
#include "ubersim/kernel/world.hpp"
#include "shared/random_play.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------------
// PenetrationDepth

PlacedShape At(const Shape& s, const Vec3& p, double yaw = 0.0) { return PlacedShape(s, Pose::FromYaw(p, yaw)); }

TEST(PenetrationDepth, TwoSpheresOverlapByTheirRadiiLessTheirDistance) {
  const Shape s = Shape::Sphere(0.1);
  EXPECT_NEAR(PenetrationDepth(At(s, Vec3::Zero()), At(s, Vec3(0.15, 0.05, 0.0)), -1.0), 0.2 - std::hypot(0.15, 0.05),
              1e-6);
  // Apart: minus the gap between them.
  EXPECT_NEAR(PenetrationDepth(At(s, Vec3::Zero()), At(s, Vec3(0, 0.3, 0)), -1.0), -0.1, 1e-6);
}

TEST(PenetrationDepth, ASphereInABoxLeavesThroughTheNearestFace) {
  const PlacedShape box = At(Shape::Box(1.0, 0.4, 0.2), Vec3::Zero(), 0.3);
  // 0.05 m inside the +y face along the box's own y axis, sphere radius 0.02: 0.07 m to move out.
  const Vec3 y_axis = Pose::FromYaw(Vec3::Zero(), 0.3).orientation * Vec3::UnitY();
  const PlacedShape ball = At(Shape::Sphere(0.02), 0.15 * y_axis);
  EXPECT_NEAR(PenetrationDepth(ball, box, -1.0), 0.07, 1e-4);
  EXPECT_NEAR(PenetrationDepth(box, ball, -1.0), 0.07, 1e-4);
}

TEST(PenetrationDepth, TiltedCylindersAreSearchedAllRound) {
  // Two long cylinders of radius 0.1 crossing, one along x, one along y tilted up: they overlap
  // by 0.2 m less their axes' distance, along the axes' common normal, a direction none of the
  // cheap guesses (centres, own axes) is.
  const Shape c = Shape::Cylinder(0.1, 1.0);
  const Vec3 axis_b = Vec3(0, 1, 0.2).normalized();
  const Vec3 centre_b(0.02, 0.03, 0.15);
  const PlacedShape a(c, Pose{Vec3::Zero(), Quat::FromTwoVectors(Vec3::UnitZ(), Vec3::UnitX())});
  const PlacedShape b(c, Pose{centre_b, Quat::FromTwoVectors(Vec3::UnitZ(), axis_b)});
  const double axes_apart = std::abs(centre_b.dot(Vec3::UnitX().cross(axis_b).normalized()));
  EXPECT_NEAR(PenetrationDepth(a, b, -1.0), 0.2 - axes_apart, 1e-5);
  // Asked only whether it is deeper than 0.1 m, it may stop at the first direction showing less.
  EXPECT_LE(PenetrationDepth(a, b, 0.1), 0.1);
}

TEST(PenetrationDepth, LowestPointOfATiltedCylinder) {
  const Quat tilt(Eigen::AngleAxisd(M_PI / 4, Vec3::UnitX()));
  const PlacedShape c(Shape::Cylinder(0.1, 0.2), Pose{Vec3(0, 0, 0.5), tilt});
  EXPECT_NEAR(c.Lowest(), 0.5 - 0.1 * std::sqrt(0.5) - 0.1 * std::sqrt(0.5), 1e-9);
}

// ---------------------------------------------------------------------------------------------
// CheckState on Div A

struct DivA : ::testing::Test {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kWarning};
  PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  ModelLoader loader{ModelLoader::DefaultSchemaDir(),
                     [this](PluginKind k, const std::string& id) { return registry.Find(k, id).schema_json; }};
  std::unique_ptr<World> world;

  void SetUp() override { Build(UBERSIM_SOURCE_DIR "/models/worlds/div-a.yaml"); }
  void Build(const std::string& world_file) {
    WorldModel model = loader.LoadWorld(world_file);
    model.transports.clear();
    world = std::make_unique<World>(model, registry, log, false);
  }
  // Walls' inner faces: Div A's carpet is 13.2 × 9.6 m.
  static constexpr double kHalfY = 4.8, kWall = 0.05;

  void Teleport(RobotId id, double x, double y, double yaw) {
    PositionEvent e;
    e.target = Target::Robot(id);
    e.position = Vec3(x, y, 0);
    e.yaw = yaw;
    world->events().Post(e);
    world->ProcessEvents();
  }
  BodyImpl& Body(const std::string& node, const std::string& body) {
    NodeImpl* n = WorldAttorney::Scene(*world).Find(node);
    EXPECT_NE(n, nullptr) << node;
    return *static_cast<BodyImpl*>(n->FindBody(body));
  }
  std::vector<StateViolation> Check(const StateCheckOptions& o = {}) { return CheckState(*world, o); }
  static std::string All(const std::vector<StateViolation>& v) {
    std::string s;
    for (const auto& x : v) s += x.Describe() + "\n";
    return s;
  }
};

// Div A with the robots' wheels as bodies on hinges (`wheel_bodies: true`), for the checks of a
// wheel's own body.
struct DivAWheelBodies : DivA {
  void SetUp() override {
    const std::filesystem::path dir = std::filesystem::temp_directory_path();
    const std::string tag = std::to_string(::getpid());
    robot_file = (dir / ("ubersim-state-check-robot-" + tag + ".yaml")).string();
    world_file = (dir / ("ubersim-state-check-world-" + tag + ".yaml")).string();
    std::string robot = Read(UBERSIM_SOURCE_DIR "/models/robots/ssl-omni-2026.yaml");
    robot.replace(robot.find("  plugin: omni\n"), 14, "  plugin: omni\n  wheel_bodies: true\n");
    std::ofstream(robot_file) << robot;
    std::string w = Read(UBERSIM_SOURCE_DIR "/models/worlds/div-a.yaml");
    for (std::size_t at = w.find("../robots/ssl-omni-2026.yaml"); at != std::string::npos;
         at = w.find("../robots/ssl-omni-2026.yaml", at)) {
      w.replace(at, 28, robot_file);
    }
    for (std::size_t at = w.find("../"); at != std::string::npos; at = w.find("../", at)) {
      w.replace(at, 3, UBERSIM_SOURCE_DIR "/models/");
    }
    std::ofstream(world_file) << w;
    Build(world_file);
  }
  void TearDown() override {
    std::filesystem::remove(robot_file);
    std::filesystem::remove(world_file);
  }
  static std::string Read(const std::string& file) {
    std::ifstream in(file);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  std::string robot_file, world_file;
};

const RobotId kBlue3{Team::kBlue, 3}, kYellow4{Team::kYellow, 4};

TEST_F(DivA, ASoundWorldHasNoFindingsBeforeAndAfterTwoSecondsOfPlay) {
  EXPECT_TRUE(Check().empty()) << All(Check());
  apps::RandomPlay play(*world, 11);
  for (int i = 0; i < 2000; ++i) {
    play.BeforeStep();
    world->Step();
  }
  EXPECT_TRUE(Check().empty()) << All(Check());
}

TEST_F(DivA, ARobotSunkIntoTheCarpetIsNamed) {
  BodyImpl& chassis = Body("blue/3", "chassis");
  Pose p = chassis.GetPose();
  p.position.z() -= 0.06;  // the shell's bottom, 15 mm up, now 45 mm under; its wheels 60 mm
  chassis.SetPose(p);
  const auto found = Check();
  ASSERT_EQ(found.size(), 1u) << All(found);
  EXPECT_EQ(found[0].issue, StateIssue::kUnderCarpet);
  EXPECT_EQ(found[0].object.kind, StateObject::Kind::kRobot);
  EXPECT_EQ(found[0].object.robot, kBlue3);
  EXPECT_EQ(found[0].object.name, "robot blue 3");
  // The first of its parts under the carpet: its first wheel's contact (a contact wheel, on the
  // chassis).
  EXPECT_EQ(found[0].part, "wheel0/carpet_contact");
  EXPECT_NEAR(found[0].value, 0.06, 1e-6);
  EXPECT_NE(found[0].Describe().find("60.0 mm below the carpet"), std::string::npos) << found[0].Describe();
}

TEST_F(DivAWheelBodies, TheBallUnderTheCarpetAndAWheelOnlyJustInIt) {
  Pose b = WorldAttorney::Ball(*world).GetPose();
  b.position.z() = 0.005;  // 16.5 mm under
  WorldAttorney::Ball(*world).SetPose(b);
  BodyImpl& wheel = Body("yellow/1/wheel0", "wheel");
  Pose w = wheel.GetPose();
  w.position.z() -= 0.008;  // within the 10 mm a loaded wheel may sink
  wheel.SetPose(w);
  const auto found = Check();
  ASSERT_EQ(found.size(), 1u) << All(found);
  EXPECT_EQ(found[0].issue, StateIssue::kUnderCarpet);
  EXPECT_EQ(found[0].object.name, "ball");
  EXPECT_NEAR(found[0].value, 0.0165, 1e-6);
}

TEST_F(DivAWheelBodies, ARobotLeaningPastTwentyDegreesHasTippedAWheelTurnedAnyWayHasNot) {
  BodyImpl& chassis = Body("blue/3", "chassis");
  const Pose upright = chassis.GetPose();
  const auto lean = [&](double deg) {
    Pose p = upright;
    p.position.z() += 0.06;  // lifted clear of the carpet: only the lean is wrong
    p.orientation = Quat(Eigen::AngleAxisd(deg * M_PI / 180.0, Vec3::UnitX())) * upright.orientation;
    chassis.SetPose(p);
  };
  lean(15.0);  // braking hard, a crash: still on its wheels
  StateCheckOptions no_carpet;
  no_carpet.carpet = false;
  no_carpet.overlap = false;
  EXPECT_TRUE(Check(no_carpet).empty()) << All(Check(no_carpet));
  lean(25.0);
  const auto found = Check(no_carpet);
  ASSERT_EQ(found.size(), 1u) << All(found);
  EXPECT_EQ(found[0].issue, StateIssue::kTipped);
  EXPECT_EQ(found[0].object.robot, kBlue3);
  EXPECT_EQ(found[0].part, "chassis");
  EXPECT_NEAR(found[0].value, 25.0 * M_PI / 180.0, 1e-6);
  EXPECT_NE(found[0].Describe().find("leaning 25.0° from upright, limit 20.1°"), std::string::npos)
      << found[0].Describe();
  // Wheels turn about their axles: a wheel's own axes point anywhere.
  chassis.SetPose(upright);
  BodyImpl& wheel = Body("yellow/1/wheel0", "wheel");
  Pose w = wheel.GetPose();
  w.orientation = Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY())) * w.orientation;
  wheel.SetPose(w);
  EXPECT_TRUE(Check(no_carpet).empty()) << All(Check(no_carpet));
}

TEST_F(DivA, RobotsInsideEachOtherAreNamedWithTheDepth) {
  // Side by side in y, both facing +x: their round sides meet. 20 mm deep.
  Teleport(kBlue3, 0.0, 1.0, 0.0);
  Teleport(kYellow4, 0.0, 1.0 + 0.16, 0.0);
  auto found = Check();
  ASSERT_EQ(found.size(), 1u) << All(found);
  EXPECT_EQ(found[0].issue, StateIssue::kInsideOther);
  EXPECT_EQ(found[0].object.name, "robot blue 3");
  ASSERT_TRUE(found[0].other.has_value());
  EXPECT_EQ(found[0].other->name, "robot yellow 4");
  EXPECT_EQ(found[0].other->robot, kYellow4);
  EXPECT_NEAR(found[0].value, 0.02, 0.001);  // the shell is a 32-sided polygon: within 0.3 mm

  // 10 mm deep is a contact, not a robot inside another.
  Teleport(kYellow4, 0.0, 1.0 + 0.17, 0.0);
  EXPECT_TRUE(Check().empty()) << All(Check());

  // Flat fronts face to face: they meet at 2 × 0.07 m. 0.12 m apart is 20 mm deep.
  Teleport(kBlue3, 1.0, 1.0, 0.0);
  Teleport(kYellow4, 1.12, 1.0, M_PI);
  found = Check();
  ASSERT_EQ(found.size(), 1u) << All(found);
  EXPECT_NEAR(found[0].value, 0.02, 0.0005);
  // 0.13 m apart, 10 mm: fine; with round sides at that distance it would be 50 mm.
  Teleport(kYellow4, 1.13, 1.0, M_PI);
  EXPECT_TRUE(Check().empty()) << All(Check());
}

TEST_F(DivA, ARobotTakenOffTheFieldOverlapsNothing) {
  Teleport(kBlue3, 0.0, 1.0, 0.0);
  Teleport(kYellow4, 0.0, 1.05, 0.0);
  ASSERT_EQ(Check().size(), 1u);
  PositionEvent off;
  off.target = Target::Robot(kYellow4);
  off.present = false;
  world->events().Post(off);
  world->ProcessEvents();
  EXPECT_TRUE(Check().empty()) << All(Check());
}

TEST_F(DivA, TheBallInsideARobotAndARobotInAWall) {
  Teleport(kBlue3, 2.0, kHalfY - 0.09 + 0.04, 0.0);  // 40 mm into wall_top
  PositionEvent ball;
  ball.position = Vec3(-2.0, 1.0, 0.0);
  world->events().Post(ball);
  world->ProcessEvents();
  Teleport(kYellow4, -2.0, 1.0 + 0.09, 0.0);  // its edge through the ball's centre: 21.5 mm deep
  const auto found = Check();
  ASSERT_EQ(found.size(), 2u) << All(found);
  EXPECT_EQ(found[0].object.name, "ball");
  EXPECT_EQ(found[0].other->name, "robot yellow 4");
  EXPECT_NEAR(found[0].value, 0.0215, 0.001);
  EXPECT_EQ(found[1].object.name, "robot blue 3");
  EXPECT_EQ(found[1].other->kind, StateObject::Kind::kField);
  EXPECT_EQ(found[1].other->name, "wall_top");
  EXPECT_NEAR(found[1].value, 0.04, 0.001);
}

TEST_F(DivA, TheBallBeyondTheWallsOuterFaceIsOutsideInsideTheWallItIsNot) {
  Pose b = WorldAttorney::Ball(*world).GetPose();
  b.position = Vec3(1.0, kHalfY + kWall + 0.1, 0.0215);
  WorldAttorney::Ball(*world).SetPose(b);
  auto found = Check();
  ASSERT_EQ(found.size(), 1u) << All(found);
  EXPECT_EQ(found[0].issue, StateIssue::kOutsideWalls);
  EXPECT_EQ(found[0].object.name, "ball");
  EXPECT_NEAR(found[0].value, 0.1, 1e-9);

  // Its centre in the wall: the wall holds it (and it is deep in the wall), but not outside.
  b.position.y() = kHalfY + 0.03;
  WorldAttorney::Ball(*world).SetPose(b);
  found = Check();
  ASSERT_EQ(found.size(), 1u) << All(found);
  EXPECT_EQ(found[0].issue, StateIssue::kInsideOther);
  // In a goal, behind the goal line, is inside.
  b.position = Vec3(6.1, 0.3, 0.0215);
  WorldAttorney::Ball(*world).SetPose(b);
  EXPECT_TRUE(Check().empty()) << All(Check());
}

TEST_F(DivAWheelBodies, ANanVelocityOnAWheelIsNamedAndSilencesTheRobotsOtherChecks) {
  BodyImpl& wheel = Body("yellow/2/wheel1", "wheel");
  dBodySetLinearVel(wheel.id(), kNan, 0.0, 0.0);
  // Also sunk and too fast (its chassis comes before the wheel): a robot with a broken value
  // gets no other finding.
  BodyImpl& chassis = Body("yellow/2", "chassis");
  Pose p = chassis.GetPose();
  p.position.z() -= 0.1;
  chassis.SetPose(p);
  dBodySetLinearVel(chassis.id(), 50.0, 0.0, 0.0);
  const auto found = Check();
  ASSERT_EQ(found.size(), 1u) << All(found);
  EXPECT_EQ(found[0].issue, StateIssue::kNonFinite);
  EXPECT_EQ(found[0].object.name, "robot yellow 2");
  EXPECT_EQ(found[0].object.robot, (RobotId{Team::kYellow, 2}));
  EXPECT_EQ(found[0].part, "wheel1/wheel");
  EXPECT_NE(found[0].detail.find("velocity (nan, 0, 0)"), std::string::npos) << found[0].detail;
  // Only the finite check: the same finding.
  StateCheckOptions only;
  only.speed = only.carpet = only.walls = only.overlap = false;
  EXPECT_EQ(Check(only).size(), 1u);
}

TEST_F(DivA, AnInfinitePositionAndAnExplodingSpeed) {
  dBodySetPosition(WorldAttorney::Ball(*world).id(), std::numeric_limits<double>::infinity(), 0.0, 0.0215);
  BodyImpl& chassis = Body("blue/0", "chassis");
  dBodySetLinearVel(chassis.id(), 0.0, 45.0, 0.0);
  dBodySetAngularVel(chassis.id(), 0.0, 0.0, 5000.0);
  const auto found = Check();
  ASSERT_EQ(found.size(), 3u) << All(found);
  EXPECT_EQ(found[0].issue, StateIssue::kNonFinite);
  EXPECT_EQ(found[0].object.name, "ball");
  EXPECT_EQ(found[1].issue, StateIssue::kTooFast);
  EXPECT_EQ(found[1].object.name, "robot blue 0");
  EXPECT_EQ(found[1].part, "chassis");
  EXPECT_DOUBLE_EQ(found[1].value, 45.0);
  EXPECT_EQ(found[1].unit, "m/s");
  EXPECT_EQ(found[2].issue, StateIssue::kTooFast);
  EXPECT_DOUBLE_EQ(found[2].value, 5000.0);
  EXPECT_EQ(found[2].unit, "rad/s");
}

}  // namespace
}  // namespace ubersim::kernel
