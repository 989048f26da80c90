// SPDX-License-Identifier: Apache-2.0
// The omni_force drive (one rigid body, the wheel forces applied to the chassis) on the modern
// four-wheel robot: it stands as high as on wheels, on supports without friction; holds commanded
// speeds forward, sideways, diagonally and turning; speeds up and brakes at its limits; stops
// after the command timeout; stays level reversing at full speed and against a wall; follows
// wheel-speed commands and reports its wheels; and drives the wheel-body omni drive's path. At
// both physics profiles: the drive's servo reaches its target within one step, whatever the step.
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <ostream>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>
#include <ubersim/servo.hpp>

#include "omni_world.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel {
namespace {

constexpr const char* kForceRobot = UBERSIM_SOURCE_DIR "/models/robots/ssl-omni-2026-force.yaml";
constexpr double kWheelRadius = 0.029;    // m, as in the robot file
constexpr double kWheelDistance = 0.079;  // m, as in the robot file
constexpr double kWheelAngles[] = {60, 135, 225, 300};  // degrees, as in the robot file
constexpr double kMass = 2.5;             // kg, as in the robot file (no wheel bodies)
// m: the centre of mass height (0.05) less the world's contact layer (0.5 mm), where the
// wheel-body robot comes to rest and the one-body robot drops to in its first 10 ms.
constexpr double kRestHeight = 0.0495;

// The rollers' drag on a robot sliding along `dir` (robot frame) over the drive's stiffness along
// it: the steady speed error of the wheels' proportional servo, m/s. Each wheel's rollers resist
// with mu_axle · m·g/4 = 0.05 · 6.13 N across its axle; each wheel pushes back with (m/4)/dt
// newtons per m/s of slip along its rolling direction (dt the physics step, s).
double RollerLag(const Vec3& dir, double dt) {
  double drag = 0, stiffness = 0;
  for (double deg : kWheelAngles) {
    const double a = deg * M_PI / 180;
    const Vec3 rolling(-std::sin(a), std::cos(a), 0), axle(-std::cos(a), -std::sin(a), 0);
    drag += 0.05 * kMass * 9.81 / 4 * std::abs(axle.dot(dir));
    stiffness += kMass / 4 / dt * rolling.dot(dir) * rolling.dot(dir);
  }
  return drag / stiffness;
}

// One robot on the Div B field at (-2, 0) at a physics profile like OmniWorld, with a hook to
// change the world model before it is built.
struct ForceWorld {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kWarning};
  PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  ModelLoader loader{ModelLoader::DefaultSchemaDir(),
                     [this](PluginKind k, const std::string& id) { return registry.Find(k, id).schema_json; }};
  WorldModel model;
  std::unique_ptr<World> world;

  explicit ForceWorld(const std::string& profile, const std::function<void(WorldModel&)>& edit = {},
                      const std::string& robot = kForceRobot) {
    model = loader.LoadWorld(UBERSIM_SOURCE_DIR "/models/worlds/div-b.yaml");
    PhysicsOverrides o;
    o.profile = profile;
    o.ApplyTo(model.physics);
    model.robots.clear();
    model.robots.push_back(RobotPlacement{{Team::kBlue, 0}, loader.LoadRobot(robot), -2.0, 0.0, 0.0, true});
    model.ball_start = Vec3(3.5, 2.5, 0);  // out of the way
    model.radio = RadioModel{};            // the drive is tested, not the radio: no delay, no loss
    if (edit) edit(model);
    world = std::make_unique<World>(model, registry, log, false);
  }
  RobotState Robot() const { return world->GroundTruth().robots.at(0); }
  double Dt() const { return world->model().physics.step; }
  int Steps(double seconds) const { return static_cast<int>(std::lround(seconds / Dt())); }
  // Steps for `seconds` without commands.
  void Run(double seconds) {
    for (int i = Steps(seconds); i > 0; --i) world->Step();
  }
  // Sends the command every 10 ms (a 100 Hz radio) for `seconds`, calling `each` after every step.
  void Drive(const MoveCommand& c, double seconds, const std::function<void()>& each = {}) {
    const int steps = Steps(seconds);
    const int every = std::max(1, Steps(0.01));
    for (int i = 0; i < steps; ++i) {
      if (i % every == 0) world->events().Post(CommandEvent{{Team::kBlue, 0}, c, {}, {}});
      world->Step();
      if (each) each();
    }
  }
  Vec3 LocalVelocity() const {
    const RobotState r = Robot();
    return r.pose.orientation.conjugate() * r.twist.linear;
  }
};

// Angle between the robot's up axis and the world's, rad.
double Tilt(const RobotState& r) {
  const Vec3 up = r.pose.orientation * Vec3::UnitZ();
  return std::acos(std::clamp(up.z(), -1.0, 1.0));
}

// The wheel speeds (rad/s) that drive the robot at (forward, left, angular): each wheel rolls
// perpendicular to its position, counter-clockwise.
std::vector<double> WheelSpeeds(double forward, double left, double angular) {
  std::vector<double> w;
  for (double deg : kWheelAngles) {
    const double a = deg * M_PI / 180;
    w.push_back((-std::sin(a) * forward + std::cos(a) * left + kWheelDistance * angular) / kWheelRadius);
  }
  return w;
}

// Mean local velocity and spin over the next `n` × 10 ms while still commanding `c`.
struct Measured {
  Vec3 local = Vec3::Zero();
  double spin = 0;
};
Measured Average(ForceWorld& w, const MoveCommand& c, int n = 50) {
  Measured m;
  for (int k = 0; k < n; ++k) {
    w.Drive(c, 0.01);
    m.local += w.LocalVelocity();
    m.spin += w.Robot().twist.angular.z();
  }
  m.local /= n;
  m.spin /= n;
  return m;
}

// Least-squares slope of v over t where v is between `low` and `high`.
double Slope(const std::vector<double>& t, const std::vector<double>& v, double low, double high) {
  double st = 0, sv = 0, stt = 0, stv = 0;
  int n = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (v[i] < low || v[i] > high) continue;
    st += t[i]; sv += v[i]; stt += t[i] * t[i]; stv += t[i] * v[i]; ++n;
  }
  EXPECT_GT(n, 10);
  return (n * stv - st * sv) / (n * stt - st * st);
}

class OmniForceDrive : public ::testing::TestWithParam<std::string> {};

TEST_P(OmniForceDrive, IsOneBodyStandingAsHighAsOnWheels) {
  ForceWorld w(GetParam());
  NodeImpl* robot = WorldAttorney::Scene(*w.world).Find("blue/0");
  EXPECT_EQ(robot->FindChild("wheel0"), nullptr);  // no wheel bodies…
  EXPECT_EQ(robot->FindGeom("wheel0"), nullptr);   // …and nothing of the wheels touches the carpet
  w.Run(0.02);
  EXPECT_NEAR(w.Robot().pose.position.z(), kRestHeight, 1e-9);  // put where it rests
  w.Run(0.98);
  const RobotState r = w.Robot();
  // No command: the wheels hold it where it was put.
  EXPECT_NEAR(r.pose.position.x(), -2.0, 1e-5);
  EXPECT_NEAR(r.pose.position.y(), 0.0, 1e-5);
  // Where the wheel-body robot settles, level and still.
  EXPECT_NEAR(r.pose.position.z(), kRestHeight, 1e-9);
  EXPECT_LT(Tilt(r), 1e-7);  // acos resolves 1e-8
  EXPECT_LT(r.twist.linear.norm(), 1e-5);
}

TEST_P(OmniForceDrive, FallsWhenLiftedAndLandsLevelWhereItRests) {
  ForceWorld w(GetParam());
  w.Run(0.02);
  Body& chassis = *WorldAttorney::Scene(*w.world).Find("blue/0")->FindBody("chassis");
  // 5 cm up and tilted 0.05 rad about x (not enough for the shell to touch first): its wheels
  // are off the carpet, nothing holds it.
  chassis.SetPose(Pose{Vec3(-2.0, 0.0, kRestHeight + 0.05), Quat(Eigen::AngleAxisd(0.05, Vec3::UnitX()))});
  const double t = 0.05, dt = w.Dt();
  w.Run(t);  // free fall takes 101 ms
  // ODE's semi-implicit Euler step falls g·t·(t + dt)/2 in t, not g·t²/2 (1.2 mm more at 5 ms).
  EXPECT_NEAR(w.Robot().pose.position.z(), kRestHeight + 0.05 - 0.5 * 9.81 * t * (t + dt), 1e-6);
  EXPECT_NEAR(w.Robot().twist.linear.z(), -9.81 * t, 1e-6);
  EXPECT_NEAR(Tilt(w.Robot()), 0.05, 1e-6);
  w.Run(0.07);  // landed
  const RobotState r = w.Robot();
  EXPECT_NEAR(r.pose.position.z(), kRestHeight, 1e-9);
  EXPECT_LT(Tilt(r), 1e-7);  // acos resolves 1e-8
  EXPECT_LT(std::abs(r.twist.linear.z()), 1e-9);
  EXPECT_LT(r.twist.angular.norm(), 1e-9);
  EXPECT_NEAR(r.pose.position.x(), -2.0, 1e-4);
}

TEST_P(OmniForceDrive, TheWorldsWheelCarpetFrictionIsTheWheelsGripAndTheSupportsHaveNone) {
  // With the table's omni_wheel|carpet pair at zero friction the wheels push nothing (the drive
  // reads its friction from the table, like the omni drive's tyres). A robot set gliding then
  // keeps its speed and spin: the supports it stands on give the carpet no grip of their own.
  ForceWorld w(GetParam(), [](WorldModel& m) {
    for (MaterialPair& p : m.material_pairs) {
      if (p.a == "omni_wheel" || p.b == "omni_wheel") p.surface.mu = p.surface.mu2 = 0.0;
    }
  });
  w.Run(0.1);
  w.world->events().Post(
      PositionEvent{Target::Robot({Team::kBlue, 0}), {}, {}, Vec3(0.5, 0.3, 0), Vec3(0, 0, 1.0), {}, {}});
  w.world->Step();
  w.Drive(LocalVelocityCommand{}, 1.0);  // commanded to stop: with no grip it cannot
  const RobotState r = w.Robot();
  // Even a friction of 0.01 would take 0.1 m/s (20 %) off in this second.
  EXPECT_NEAR(r.twist.linear.x(), 0.5, 0.002);
  EXPECT_NEAR(r.twist.linear.y(), 0.3, 0.002);
  EXPECT_NEAR(r.twist.angular.z(), 1.0, 0.002);
}

struct VelocityCase {
  const char* name;
  double forward, left, angular;
};
// gtest names a failing case by its name, not by its bytes.
void PrintTo(const VelocityCase& c, std::ostream* os) { *os << c.name; }

class OmniForceSteadyVelocity : public ::testing::TestWithParam<std::tuple<std::string, VelocityCase>> {};

TEST_P(OmniForceSteadyVelocity, LagsTheCommandOnlyByTheRollersDrag) {
  const VelocityCase c = std::get<1>(GetParam());
  ForceWorld w(std::get<0>(GetParam()));
  const LocalVelocityCommand cmd{c.forward, c.left, c.angular};
  w.Drive(cmd, 1.5);
  const Measured m = Average(w, cmd);
  const Vec3 want(c.forward, c.left, 0);
  if (want.norm() > 0) {
    // Along the command: short by the rollers' drag over the servo's stiffness (0.47 mm/s
    // forward, 1.03 mm/s sideways at 1 ms); across it and in spin: the drag's small imbalance
    // between the front (60°) and rear (45°) wheels. The servo's stiffness is (m/4)/dt: every lag
    // grows with the step (diagonally at 5 ms: 0.44 mm/s off the model, 1.56 mm/s across, both
    // five times the 1 ms figures).
    const double per_ms = w.Dt() / 0.001;
    const Vec3 dir = want.normalized();
    EXPECT_NEAR(m.local.dot(dir), want.norm() - RollerLag(dir, w.Dt()), 1e-4 * per_ms) << c.name;
    EXPECT_LT((m.local - dir * m.local.dot(dir)).norm(), 1e-3 * per_ms) << c.name;
    EXPECT_NEAR(m.spin, 0.0, 2e-3) << c.name;
  } else {
    EXPECT_LT(m.local.norm(), 1e-4) << c.name;
  }
  if (c.angular != 0) {
    EXPECT_NEAR(m.spin, c.angular, 1e-3 * std::abs(c.angular)) << c.name;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Commands, OmniForceSteadyVelocity,
    ::testing::Combine(BothProfiles(),
                       ::testing::Values(VelocityCase{"forward", 1.0, 0.0, 0.0},
                                         VelocityCase{"fast_forward", 2.5, 0.0, 0.0},
                                         VelocityCase{"sideways", 0.0, 1.0, 0.0},
                                         VelocityCase{"diagonal", 1.0, -1.0, 0.0},
                                         VelocityCase{"turning", 0.0, 0.0, 4.0})),
    [](const auto& info) { return std::get<0>(info.param) + "_" + std::get<1>(info.param).name; });

TEST_P(OmniForceDrive, SpeedsUpAndBrakesAtTheServoLimits) {
  ForceWorld w(GetParam());
  // 2 m/s forward from rest at the 3 m/s² limit (0.67 s), then stop at the 6 m/s² brake limit.
  std::vector<double> t, v;
  for (int k = 0; k < 100; ++k) {
    w.Drive(LocalVelocityCommand{2.0, 0.0, 0.0}, 0.01);
    t.push_back(0.01 * (k + 1));
    v.push_back(w.LocalVelocity().x());
  }
  // The force that tracks the setpoint within a step needs 7.5 N, half the wheels' grip: the
  // robot follows the ramp exactly (the omni drive: within 5 %).
  EXPECT_NEAR(Slope(t, v, 0.4, 1.6), 3.0, 0.01);
  EXPECT_NEAR(v.back(), 2.0 - RollerLag(Vec3::UnitX(), w.Dt()), 1e-4);
  t.clear();
  v.clear();
  for (int k = 0; k < 50; ++k) {
    w.Drive(LocalVelocityCommand{}, 0.01);
    t.push_back(0.01 * (k + 1));
    v.push_back(w.LocalVelocity().x());
  }
  EXPECT_NEAR(Slope(t, v, 0.4, 1.6), -6.0, 0.02);
  EXPECT_LT(std::abs(v.back()), 1e-4);
}

TEST_P(OmniForceDrive, BrakesToAStopAfterTheCommandTimeout) {
  ForceWorld w(GetParam());
  w.Drive(LocalVelocityCommand{1.5, 0.0, 0.0}, 1.0);
  EXPECT_GT(w.LocalVelocity().x(), 1.49);
  // No more commands: for 0.1 s the last one holds, then the servo brakes at 6 m/s² (0.25 s).
  w.Run(0.09);
  EXPECT_GT(w.LocalVelocity().x(), 1.49);
  w.Run(0.27);  // 0.36 s after the last command: 0.1 s + 0.25 s and 10 ms to spare
  EXPECT_LT(w.Robot().twist.linear.norm(), 1e-3);
  const double x = w.Robot().pose.position.x();
  w.Run(0.5);
  EXPECT_NEAR(w.Robot().pose.position.x(), x, 1e-4);  // and stays
}

TEST_P(OmniForceDrive, StaysLevelReversingAtFullSpeedAndAgainstAWall) {
  // The wheels push at the carpet, 5 cm below the centre of mass: braking from 3 m/s to -3 m/s
  // (6 m/s², 15 N) pitches the robot onto its front wheels, and the wall's push pitches it too.
  // Its wheels are rigid: it must neither tip nor bounce. (The wheel-body robot leans up to
  // 6 mrad on its hinges here.)
  ForceWorld w(GetParam());
  w.Run(0.02);  // dropped into place
  double tilt = 0, low = 1, high = 0;
  auto watch = [&] {
    const RobotState r = w.Robot();
    tilt = std::max(tilt, Tilt(r));
    low = std::min(low, r.pose.position.z());
    high = std::max(high, r.pose.position.z());
  };
  w.Drive(LocalVelocityCommand{3, 0, 0}, 1.5, watch);
  w.Drive(LocalVelocityCommand{-3, 0, 0}, 1.5, watch);
  w.Drive(LocalVelocityCommand{0, 3, 0}, 1.5, watch);
  w.Drive(LocalVelocityCommand{0, -3, 0}, 1.5, watch);
  // Wheel speeds reversed at once (no servo ramp): every wheel at its grip limit for 0.3 s.
  w.Drive(WheelSpeedCommand{WheelSpeeds(3, 0, 0)}, 1.0, watch);
  w.Drive(WheelSpeedCommand{WheelSpeeds(-3, 0, 0)}, 1.0, watch);
  EXPECT_NEAR(w.LocalVelocity().x(), -3.0, 0.01);
  // A fresh robot backwards into the wall behind it at 3 m/s, pushing on for a second after.
  ForceWorld wall(GetParam());
  wall.Run(0.02);
  wall.Drive(LocalVelocityCommand{-3, 0, 0}, 2.0, [&] {
    const RobotState r = wall.Robot();
    tilt = std::max(tilt, Tilt(r));
    low = std::min(low, r.pose.position.z());
    high = std::max(high, r.pose.position.z());
  });
  EXPECT_LT(wall.Robot().pose.position.x(), -4.5);
  EXPECT_LT(wall.Robot().twist.linear.norm(), 0.01);
  EXPECT_LT(tilt, 1e-3);  // rad: 0.06°
  EXPECT_GT(low, kRestHeight - 1e-4);
  EXPECT_LT(high, kRestHeight + 1e-4);
}

TEST_P(OmniForceDrive, FollowsWheelSpeedCommands) {
  {
    ForceWorld w(GetParam());
    // Wheel speeds skip the servo's ramp: every wheel pushes at its grip, mu_roll · m·g/4 =
    // 4.9 N, and the rollers drag (0.3 N each across the axles): forward, 4.9 N · (2 sin 60° +
    // 2 sin 45°) - 0.3 N · (2 cos 60° + 2 cos 45°) = 14.71 N: 5.88 m/s² on the chassis' 2.5 kg
    // (the dribbler bar is fixed to the chassis: bar_model surface).
    std::vector<double> t, v;
    w.Drive(WheelSpeedCommand{WheelSpeeds(1.0, 0.0, 0.0)}, 1.0, [&] {
      t.push_back(static_cast<double>(t.size()) * w.Dt());
      v.push_back(w.LocalVelocity().x());
    });
    EXPECT_NEAR(Slope(t, v, 0.2, 0.8), 5.88, 0.02);
    EXPECT_NEAR(w.LocalVelocity().x(), 1.0 - RollerLag(Vec3::UnitX(), w.Dt()), 1e-4);
    EXPECT_LT(std::abs(w.LocalVelocity().y()), 1e-4);
  }
  {
    ForceWorld w(GetParam());
    w.Drive(WheelSpeedCommand{WheelSpeeds(0.0, 0.0, 4.0)}, 0.5);
    EXPECT_NEAR(w.Robot().twist.angular.z(), 4.0, 4e-3);
    EXPECT_LT(w.Robot().twist.linear.norm(), 1e-3);
  }
  {
    ForceWorld w(GetParam());
    w.world->events().Post(CommandEvent{{Team::kBlue, 0}, WheelSpeedCommand{{1.0, 2.0, 3.0}}, {}, {}});
    w.world->ProcessEvents();
    EXPECT_EQ(w.world->event_counters().rejected, 1);
    EXPECT_NE(w.text.str().find("3 speeds, this robot has 4 wheels"), std::string::npos) << w.text.str();
  }
}

TEST_P(OmniForceDrive, WheelsFarOutStillTurnSteadily) {
  // Wheels 0.12 m out on the 0.09 m chassis: at full stiffness the yaw servo would overshoot
  // by more than the error every step (2·0.12²/0.09² = 3.6 > 2) and spin the robot up. The drive
  // softens it; the robot turns at the commanded speed.
  ForceWorld w(GetParam(), [](WorldModel& m) {
    auto robot = std::make_shared<RobotModel>(*m.robots.at(0).model);
    robot->drive->params = ParamView::FromJson(
        R"({"wheels": [{"angle_deg": 60}, {"angle_deg": 135}, {"angle_deg": 225}, {"angle_deg": 300}],
            "wheel_radius": 0.029, "wheel_distance": 0.12})");
    m.robots.at(0).model = robot;
  });
  w.Drive(LocalVelocityCommand{0.0, 0.0, 4.0}, 1.0);
  const Measured m = Average(w, LocalVelocityCommand{0.0, 0.0, 4.0});
  EXPECT_NEAR(m.spin, 4.0, 4e-3);
  EXPECT_LT(m.local.norm(), 1e-3);
}

// A RobotContext over the world's robot, to call a second omni_force instance's Feedback(): the
// world keeps its drives to itself. The probe's supports go into a node of their own and are
// switched off, so it changes nothing in the world.
class ProbeContext final : public RobotContext {
 public:
  ProbeContext(ForceWorld& w, const ParamView& params)
      : node_(WorldAttorney::Scene(*w.world).Root().AddChild("probe")),
        chassis_(*WorldAttorney::Scene(*w.world).Find("blue/0")->FindBody("chassis")),
        body_(w.model.robots.at(0).model->body),
        params_(params),
        log_(w.log) {}
  RobotId Id() const override { return {Team::kBlue, 0}; }
  SceneNode& Node() override { return node_; }
  Body& Chassis() override { return chassis_; }
  const RobotBodyInfo& BodyInfo() const override { return body_; }
  const ParamView& Params() const override { return params_; }
  Log& Logger() override { return log_; }
  double SimTime() const override { return 0; }
  Body* Ball() override { return nullptr; }
  double BallRadius() const override { return 0.0215; }
  Vec3 Gravity() const override { return Vec3(0, 0, -9.81); }
  void ObserveContacts(Geom& own, ContactHandler) override { own.SetCollides(false); }
  SurfaceMaterial CarpetSurface(const SurfaceMaterial& own) const override { return own; }

 private:
  SceneNode& node_;
  Body& chassis_;
  RobotBodyInfo body_;
  ParamView params_;
  Log& log_;
};

TEST_P(OmniForceDrive, ReportsTheWheelsTurningWithTheCarpetAndTheVelocityTheyImply) {
  ForceWorld w(GetParam());
  ProbeContext ctx(w, w.model.robots.at(0).model->drive->params);
  std::shared_ptr<Drive> probe = w.registry.CreateDrive("omni_force");
  probe->Configure(ctx);
  const LocalVelocityCommand cmd{1.0, 0.5, 2.0};
  w.Drive(cmd, 1.0);
  const DriveFeedback f = probe->Feedback();
  ASSERT_EQ(f.wheel_speeds.size(), 4u);
  // Each wheel turns with its contact point (under the wheel centre, on the carpet) along its
  // rolling direction in the carpet's plane: the chassis' whole motion, its slight rocking
  // included.
  const RobotState r = w.Robot();
  for (std::size_t i = 0; i < 4; ++i) {
    const double a = kWheelAngles[i] * M_PI / 180;
    const Vec3 centre = r.pose.Transform(Vec3(kWheelDistance * std::cos(a), kWheelDistance * std::sin(a),
                                              kWheelRadius - 0.05));
    const Vec3 contact = centre - Vec3(0, 0, kWheelRadius);
    Vec3 rolling = r.pose.orientation * Vec3(-std::sin(a), std::cos(a), 0);
    rolling = Vec3(rolling.x(), rolling.y(), 0).normalized();  // along the carpet
    const Vec3 velocity = r.twist.linear + r.twist.angular.cross(contact - r.pose.position);
    EXPECT_NEAR(f.wheel_speeds[i], velocity.dot(rolling) / kWheelRadius, 1e-9) << "wheel " << i;
  }
  // Through the wheel geometry, that is the robot's planar motion: rocking at the mrad/s the
  // 2.2 m/s² of turning gives it moves the contacts, 5 cm below the centre of mass, by µm/s.
  const Vec3 v = w.LocalVelocity();
  const double spin = r.twist.angular.z();
  const std::vector<double> planar = WheelSpeeds(v.x(), v.y(), spin);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(f.wheel_speeds[i], planar[i], 1e-3) << "wheel " << i;
  // A positive speed rolls the robot counter-clockwise: turning left on the spot, all positive.
  for (double s : WheelSpeeds(0, 0, 1)) EXPECT_GT(s, 0);
  EXPECT_NEAR(f.local_velocity.linear.x(), v.x(), 1e-4);
  EXPECT_NEAR(f.local_velocity.linear.y(), v.y(), 1e-4);
  EXPECT_NEAR(f.local_velocity.angular.z(), spin, 1e-4);
  // …and that is the command, within the servo's lag: sideways, the rollers' drag over the
  // wheels' stiffness, which is the force that reaches the target in one step, so in proportion
  // to the step (3.5 mm/s at 1 ms, 17 at 5 ms). Before the drive asked for its velocity in the
  // frame the robot turns to within the step (AheadOfTheTurn), turning added 5 and 10 more.
  EXPECT_NEAR(f.local_velocity.linear.x(), 1.0, 0.002);
  EXPECT_NEAR(f.local_velocity.linear.y(), 0.5, 0.005 * w.Dt() / 0.001);
  EXPECT_NEAR(f.local_velocity.angular.z(), 2.0, 0.01);
}

// The pose an ideal robot reaches: the servo's setpoint integrated (what both drives follow).
struct Ideal {
  VelocityServo servo{ServoLimits{3.0, 3.0, 6.0, 10.0, 50.0, 50.0}};  // the robot file's limits
  double dt = 0.001;  // s, the physics step
  double x = -2.0, y = 0.0, yaw = 0.0;
  void Drive(const MoveCommand& command, double seconds) {
    for (long i = 0; i < std::lround(seconds / dt); ++i) {
      PlanarVelocity target;
      const double c = std::cos(yaw), s = std::sin(yaw);
      if (const auto* l = std::get_if<LocalVelocityCommand>(&command)) {
        target = {Eigen::Vector2d(l->forward, l->left), l->angular};
      } else if (const auto* g = std::get_if<GlobalVelocityCommand>(&command)) {
        target = {Eigen::Vector2d(c * g->x + s * g->y, -s * g->x + c * g->y), g->angular};
      }
      const PlanarVelocity& v = servo.Step(servo.ClampToLimits(target), dt);
      x += dt * (c * v.linear.x() - s * v.linear.y());
      y += dt * (s * v.linear.x() + c * v.linear.y());
      yaw += dt * v.angular;
    }
  }
};

TEST_P(OmniForceDrive, DrivesTheWheelBodyDrivesPath) {
  // Forward, an arc, a global-frame diagonal, stop: 3.5 s within the wheels' grip. Both drives
  // end within a centimetre of the ideal robot and of each other.
  const std::vector<std::pair<MoveCommand, double>> plan = {
      {LocalVelocityCommand{1.0, 0.0, 0.0}, 1.0}, {LocalVelocityCommand{1.0, 0.0, 1.0}, 1.0},
      {GlobalVelocityCommand{0.5, -0.5, 0.0}, 1.0}, {LocalVelocityCommand{}, 0.5}};
  ForceWorld force(GetParam());
  ForceWorld omni(GetParam(), {}, kOmniRobot);
  Ideal ideal;
  ideal.dt = force.Dt();
  for (const auto& [command, seconds] : plan) {
    ideal.Drive(command, seconds);
    force.Drive(command, seconds);
    omni.Drive(command, seconds);
  }
  const RobotState f = force.Robot(), o = omni.Robot();
  // At fast both end further from the ideal robot (whose servo integrates the same 5 ms steps
  // exactly): the one-body robot 10.5 mm, the contact-wheel robot 15.2 mm, over a 3.5 m path.
  const double off = GetParam() == "fast" ? 0.02 : 0.01;
  EXPECT_LT(std::hypot(o.pose.position.x() - ideal.x, o.pose.position.y() - ideal.y), off);
  EXPECT_LT(std::hypot(f.pose.position.x() - ideal.x, f.pose.position.y() - ideal.y), off);
  EXPECT_LT(std::hypot(f.pose.position.x() - o.pose.position.x(), f.pose.position.y() - o.pose.position.y()), off);
  EXPECT_NEAR(f.pose.Yaw(), ideal.yaw, 0.015);
  EXPECT_NEAR(f.pose.Yaw(), o.pose.Yaw(), 0.04);
}

INSTANTIATE_TEST_SUITE_P(BothProfiles, OmniForceDrive, BothProfiles(), ProfileName);

// The SDK's trig-free heading (servo.hpp): a global command turns into the robot frame as cos and
// sin of the yaw would turn it, tilted or not, and a frame pointing straight up heads along x.
TEST(HeadingOf, TurnsAGlobalVectorAsTheYawsCosAndSinDo) {
  for (double yaw = -3.1; yaw < 3.15; yaw += 0.37) {
    for (double tilt : {0.0, 0.3}) {
      const Quat q = Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ())) * Quat(Eigen::AngleAxisd(tilt, Vec3::UnitY()));
      const Eigen::Vector2d h = HeadingOf(q);
      EXPECT_NEAR(h.x(), std::cos(yaw), 1e-12) << yaw << " " << tilt;
      EXPECT_NEAR(h.y(), std::sin(yaw), 1e-12) << yaw << " " << tilt;
      const Eigen::Vector2d local = ToRobotFrame(h, 1.5, -0.5);
      const Eigen::Vector2d by_yaw = ToRobotFrame(Pose{Vec3::Zero(), q}.Yaw(), 1.5, -0.5);
      EXPECT_NEAR(local.x(), by_yaw.x(), 1e-12);
      EXPECT_NEAR(local.y(), by_yaw.y(), 1e-12);
    }
  }
  const Eigen::Vector2d up = HeadingOf(Quat(Eigen::AngleAxisd(-M_PI / 2, Vec3::UnitY())));
  EXPECT_EQ(up, Eigen::Vector2d(1.0, 0.0));
  const auto command = CommandedVelocity(GlobalVelocityCommand{0.0, 2.0, 1.0}, HeadingOf(Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()))));
  EXPECT_NEAR(command.linear.x(), 2.0, 1e-12);  // +y is straight ahead of a robot facing +y
  EXPECT_NEAR(command.linear.y(), 0.0, 1e-12);
  EXPECT_EQ(command.angular, 1.0);
}

// The SDK's inlined quaternion rotation (math.hpp) gives Eigen's q * v to the bit: the wheels and
// every wheel contact use it, and the pinned hashes assume it changes nothing.
TEST(Rotate, TurnsAVectorAsEigensQuaternionProductToTheBit) {
  std::mt19937_64 rng(20261202);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int i = 0; i < 1000; ++i) {
    const Quat q = Quat(unit(rng), unit(rng), unit(rng), unit(rng)).normalized();
    const Vec3 v(unit(rng), unit(rng), unit(rng));
    const Vec3 eigen = q * v;
    const Vec3 ours = Rotate(q, v);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(ours[k], eigen[k]) << "sample " << i << ", component " << k;
  }
  EXPECT_EQ(Rotate(Quat::Identity(), Vec3(1, 2, 3)), Vec3(1, 2, 3));
  const Vec3 quarter = Rotate(Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ())), Vec3::UnitX());
  EXPECT_NEAR(quarter.x(), 0.0, 1e-15);
  EXPECT_NEAR(quarter.y(), 1.0, 1e-15);
}

}  // namespace
}  // namespace ubersim::kernel
