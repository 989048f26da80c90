// SPDX-License-Identifier: Apache-2.0
// Robots composed by the kernel from a model: chassis, plugin parts built into the scene graph,
// command and position events, a part that throws while stepping.
#include <cmath>
#include <sstream>

#include <gtest/gtest.h>

#include "../../common/test_world.hpp"
#include "ubersim/plugin.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/world.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel {
namespace {

// A drive in the test binary: pushes the chassis toward the commanded local velocity and adds a
// wheel node (a child with its own body on a hinge) so teleports must move it too.
class PushDrive final : public Drive {
 public:
  void Configure(RobotContext& ctx) override {
    ctx_ = &ctx;
    gain_ = ctx.Params().GetDouble("gain", 20.0);
    SceneNode& wheel_node = ctx.Node().AddChild("wheel");
    BodySpec w;
    w.name = "wheel";
    w.mass = MassSpec::Solid(Shape::Cylinder(0.03, 0.01), 0.05);
    const Pose chassis = ctx.Chassis().GetPose();
    w.pose = chassis.Compose(Pose{Vec3(0.1, 0, -0.03), Quat::Identity()});
    wheel_ = &wheel_node.AddBody(w);
    JointSpec j;
    j.name = "axle";
    j.kind = JointKind::kFixed;
    j.parent = &ctx.Chassis();
    j.child = wheel_;
    wheel_node.AddJoint(j);
  }
  void SetCommand(const MoveCommand& command) override {
    const auto* local = std::get_if<LocalVelocityCommand>(&command);
    if (!local) throw PluginError("PushDrive takes local velocities only");
    target_ = Vec3(local->forward, local->left, 0);
  }
  // The chassis velocity in the robot frame and one made-up wheel speed, or a defect on request.
  DriveFeedback Feedback() const override {
    if (feedback_defect_ == Defect::kThrow) throw std::runtime_error("encoder bus timed out");
    DriveFeedback f;
    const Body& c = ctx_->Chassis();
    f.local_velocity.linear = c.GetPose().orientation.inverse() * c.GetTwist().linear;
    f.wheel_speeds = {feedback_defect_ == Defect::kNaN ? std::nan("") : 42.0};
    return f;
  }
  enum class Defect { kNone, kThrow, kNaN };
  static Defect feedback_defect_;
  void PreStep(const StepInfo&) override {
    if (throw_in_prestep_) throw std::runtime_error("motor controller exploded");
    Body& c = ctx_->Chassis();
    const Vec3 target_world = c.GetPose().orientation * target_;
    Vec3 error = target_world - c.GetTwist().linear;
    error.z() = 0;
    c.AddForce(error * gain_ * c.Mass());
  }
  static bool throw_in_prestep_;

 private:
  RobotContext* ctx_ = nullptr;
  Body* wheel_ = nullptr;
  double gain_ = 20;
  Vec3 target_ = Vec3::Zero();
};
bool PushDrive::throw_in_prestep_ = false;
PushDrive::Defect PushDrive::feedback_defect_ = PushDrive::Defect::kNone;

void* CreatePushDrive() { return static_cast<Drive*>(new PushDrive()); }
void DestroyPushDrive(void* p) { delete static_cast<Drive*>(p); }
const PluginDescriptor kPushDrive{kPluginAbiWord, sizeof(PluginDescriptor), PluginKind::kDrive,
                                  kSdkVersionMajor, kSdkVersionMinor, "push_drive", "1.0",
                                  kBuildTag, R"({"type":"object"})", &CreatePushDrive,
                                  &DestroyPushDrive};

WorldModel OneRobotWorld() {
  WorldModel w = testing::BallWorld(Vec3(2, 2, 0));
  auto robot = std::make_shared<RobotModel>();
  robot->file = "<code>";
  robot->name = "pusher";
  robot->body = RobotBodyInfo{2.0, 0.09, 0.15, 0.07, 0.0};
  robot->surface.name = "robot";
  robot->drive = ComponentModel{"push_drive", ParamView::FromJson(R"({"gain": 30})")};
  w.robots.push_back(RobotPlacement{{Team::kBlue, 3}, robot, -1.0, 0.5, 0.0, true});
  SurfaceMaterial slick;
  slick.mu = 0.0;  // the push drive slides the chassis: no carpet friction
  w.material_pairs.push_back({"robot", "carpet", slick});
  return w;
}

struct Fixture {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kDebug};
  PluginRegistry registry{{}};
  Fixture() { registry.Add(kPushDrive); }
};

TEST(Robot, IsBuiltUnderItsTeamWithThePluginsParts) {
  Fixture f;
  World world(OneRobotWorld(), f.registry, f.log, false);
  NodeImpl* node = WorldAttorney::Scene(world).Find("blue/3");
  ASSERT_NE(node, nullptr);
  EXPECT_NE(node->FindBody("chassis"), nullptr);
  EXPECT_NE(WorldAttorney::Scene(world).Find("blue/3/wheel"), nullptr);
  const WorldSnapshot s = world.GroundTruth();
  ASSERT_EQ(s.robots.size(), 1u);
  EXPECT_EQ(s.robots[0].id, (RobotId{Team::kBlue, 3}));
  EXPECT_NEAR(s.robots[0].pose.position.x(), -1.0, 1e-12);
  EXPECT_NEAR(s.robots[0].pose.position.z(), 0.075, 1e-12);  // half its height above the carpet
}

TEST(Robot, CommandEventsReachTheDrive) {
  Fixture f;
  World world(OneRobotWorld(), f.registry, f.log, false);
  world.events().Post(CommandEvent{{Team::kBlue, 3}, LocalVelocityCommand{1.0, 0.0, 0.0}, {}, {}});
  for (int i = 0; i < 1000; ++i) world.Step();
  const RobotState r = world.GroundTruth().robots[0];
  EXPECT_NEAR(r.twist.linear.x(), 1.0, 0.02);
  EXPECT_NEAR(r.twist.linear.y(), 0.0, 0.02);
  EXPECT_GT(r.pose.position.x(), -0.2);  // about 0.97 m in 1 s
  EXPECT_EQ(world.event_counters().applied, 1);
}

TEST(Robot, ACommandThePartRefusesIsCountedAndLogged) {
  Fixture f;
  World world(OneRobotWorld(), f.registry, f.log, false);
  world.events().Post(CommandEvent{{Team::kBlue, 3}, GlobalVelocityCommand{1, 0, 0}, {}, {}});
  world.events().Post(CommandEvent{{Team::kBlue, 3}, {}, KickCommand{3.0, 0.0}, {}});
  world.ProcessEvents();
  EXPECT_EQ(world.event_counters().rejected, 2);
  EXPECT_NE(f.text.str().find("local velocities only"), std::string::npos);
  EXPECT_NE(f.text.str().find("robot has no kicker"), std::string::npos);
}

TEST(Robot, TeleportMovesEveryBodyOfTheRobotRigidly) {
  Fixture f;
  World world(OneRobotWorld(), f.registry, f.log, false);
  for (int i = 0; i < 10; ++i) world.Step();
  Body* wheel = WorldAttorney::Scene(world).Find("blue/3/wheel")->FindBody("wheel");
  world.events().Post(PositionEvent{Target::Robot({Team::kBlue, 3}), Vec3(1.0, -1.0, 5.0),
                                    M_PI / 2, std::nullopt, std::nullopt, std::nullopt});
  world.ProcessEvents();
  const Pose chassis = WorldAttorney::Scene(world).Find("blue/3")->FindBody("chassis")->GetPose();
  EXPECT_NEAR(chassis.position.x(), 1.0, 1e-9);
  EXPECT_NEAR(chassis.position.y(), -1.0, 1e-9);
  EXPECT_NEAR(chassis.position.z(), 0.075, 1e-9);  // z ignored: back on the carpet
  EXPECT_NEAR(chassis.Yaw(), M_PI / 2, 1e-9);
  // The wheel sat 0.1 m ahead of the centre; turned by 90° it is now 0.1 m to the left (+y).
  EXPECT_NEAR(wheel->GetPose().position.x(), 1.0, 1e-3);
  EXPECT_NEAR(wheel->GetPose().position.y(), -0.9, 1e-3);
}

TEST(Robot, TakenOffTheFieldItNeitherMovesNorCollides) {
  Fixture f;
  WorldModel model = OneRobotWorld();
  model.ball_start = Vec3(-1.0, 0.5, 0.0);  // inside the robot
  World world(model, f.registry, f.log, false);
  world.events().Post(PositionEvent{Target::Robot({Team::kBlue, 3}), std::nullopt, std::nullopt,
                                    std::nullopt, std::nullopt, false});
  world.events().Post(CommandEvent{{Team::kBlue, 3}, LocalVelocityCommand{1.0, 0.0, 0.0}, {}, {}});
  for (int i = 0; i < 200; ++i) world.Step();
  const WorldSnapshot s = world.GroundTruth();
  EXPECT_FALSE(s.robots[0].present);
  EXPECT_NEAR(s.robots[0].pose.position.x(), -1.0, 1e-9);       // frozen
  EXPECT_NEAR(s.ball.pose.position.x(), -1.0, 1e-6);             // not pushed out of the robot
}

TEST(Robot, APartThatThrowsWhileSteppingIsSwitchedOffAndTheWorldGoesOn) {
  Fixture f;
  WorldModel model = OneRobotWorld();
  model.on_plugin_fault = "disable";  // carry on without it (tests/reliability covers "stop")
  World world(model, f.registry, f.log, false);
  PushDrive::throw_in_prestep_ = true;
  world.events().Post(PositionEvent{Target::Ball(), std::nullopt, std::nullopt, Vec3(1, 0, 0),
                                    std::nullopt, std::nullopt});
  for (int i = 0; i < 100; ++i) world.Step();
  PushDrive::throw_in_prestep_ = false;
  EXPECT_EQ(world.clock().steps(), 100);
  EXPECT_GT(WorldAttorney::Ball(world).GetPose().position.x(), 2.05);  // the rest of the world kept going
  const std::string log = f.text.str();
  EXPECT_NE(log.find("robot blue 3 drive 'push_drive' (<in-process>): PreStep threw std::runtime_error: motor "
                     "controller exploded; this drive is switched off"),
            std::string::npos)
      << log;
  EXPECT_EQ(f.log.count(LogLevel::kError), 1);  // reported once, not every step
}

TEST(Robot, TheDrivesFeedbackIsInTheGroundTruth) {
  Fixture f;
  World world(OneRobotWorld(), f.registry, f.log, false);
  world.events().Post(CommandEvent{{Team::kBlue, 3}, LocalVelocityCommand{0.0, 0.5, 0.0}, {}, {}});
  for (int i = 0; i < 500; ++i) world.Step();
  const RobotState r = world.GroundTruth().robots[0];
  ASSERT_TRUE(r.drive);
  EXPECT_EQ(r.drive->wheel_speeds, std::vector<double>{42.0});
  EXPECT_NEAR(r.drive->local_velocity.linear.y(), 0.5, 0.02);  // what the drive measured
  EXPECT_NEAR(r.drive->local_velocity.linear.x(), 0.0, 0.02);

  // Off the field a robot reports nothing.
  world.events().Post(PositionEvent{Target::Robot({Team::kBlue, 3}), std::nullopt, std::nullopt,
                                    std::nullopt, std::nullopt, false});
  world.ProcessEvents();
  EXPECT_FALSE(world.GroundTruth().robots[0].drive);
}

// Kinematics is the ground truth's poses and velocities, bit for bit, without asking the parts.
TEST(Robot, KinematicsIsTheGroundTruthWithoutThePartsReports) {
  Fixture f;
  World world(OneRobotWorld(), f.registry, f.log, false);
  world.events().Post(CommandEvent{{Team::kBlue, 3}, LocalVelocityCommand{0.3, 0.5, 1.0}, {}, {}});
  for (int i = 0; i < 200; ++i) world.Step();
  const WorldSnapshot truth = world.GroundTruth();
  const WorldSnapshot kinematics = world.Kinematics();
  ASSERT_EQ(kinematics.robots.size(), truth.robots.size());
  ASSERT_EQ(kinematics.robots.size(), 1u);
  const RobotState& k = kinematics.robots[0];
  const RobotState& t = truth.robots[0];
  EXPECT_EQ(k.id, t.id);
  EXPECT_TRUE(k.present);
  EXPECT_EQ(k.pose.position, t.pose.position);
  EXPECT_EQ(k.pose.orientation.coeffs(), t.pose.orientation.coeffs());
  EXPECT_EQ(k.twist.linear, t.twist.linear);
  EXPECT_EQ(k.twist.angular, t.twist.angular);
  EXPECT_GT(k.twist.linear.norm(), 0.1);  // moving: the comparison compares something
  EXPECT_EQ(kinematics.ball.pose.position, truth.ball.pose.position);
  EXPECT_EQ(kinematics.step, truth.step);
  ASSERT_TRUE(t.drive);
  EXPECT_FALSE(k.drive);
}

TEST(Robot, ADriveWhoseFeedbackThrowsOrIsNotFiniteIsSwitchedOff) {
  for (PushDrive::Defect defect : {PushDrive::Defect::kThrow, PushDrive::Defect::kNaN}) {
    Fixture f;
    WorldModel model = OneRobotWorld();
    model.on_plugin_fault = "disable";
    World world(model, f.registry, f.log, false);
    PushDrive::feedback_defect_ = defect;
    const WorldSnapshot s = world.GroundTruth();
    PushDrive::feedback_defect_ = PushDrive::Defect::kNone;
    EXPECT_FALSE(s.robots[0].drive);
    ASSERT_EQ(world.faults().size(), 1u);
    EXPECT_EQ(world.faults()[0].phase, "Feedback");
    const std::string why = defect == PushDrive::Defect::kThrow ? "threw std::runtime_error: encoder bus timed out"
                                                                 : "reported a non-finite wheel speed or velocity";
    EXPECT_EQ(world.faults()[0].what, why);
    EXPECT_FALSE(world.GroundTruth().robots[0].drive) << "switched off: asked no more";
    EXPECT_EQ(world.faults().size(), 1u);
  }
}

TEST(Robot, PlacingTheSameRobotTwiceIsRefused) {
  Fixture f;
  WorldModel model = OneRobotWorld();
  model.robots.push_back(model.robots[0]);
  EXPECT_THROW(World(model, f.registry, f.log, false), std::runtime_error);
}

}  // namespace
}  // namespace ubersim::kernel
