// SPDX-License-Identifier: Apache-2.0
// The omni drive on the modern four-wheel robot: steady speeds forward, sideways, diagonally and
// turning within 3 % of the command; speed-up following the acceleration limit within 5 %;
// braking to a stop after the command timeout, at both physics profiles; the motor's rotor
// inertia on the wheel's axle.
#include <cmath>
#include <filesystem>
#include <ostream>
#include <sstream>
#include <string>
#include <tuple>

#include <gtest/gtest.h>

#include <ode/ode.h>

#include "../common/edited_model_file.hpp"
#include "omni_world.hpp"
#include "physics/scene_graph.hpp"
#include "ubersim/wheel.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel {
namespace {

class OmniDrive : public ::testing::TestWithParam<std::string> {};

TEST_P(OmniDrive, RestsOnItsWheelsWithoutDrifting) {
  OmniWorld w(GetParam());
  w.Run(1.0);
  const RobotState r = w.Robot();
  EXPECT_NEAR(r.pose.position.x(), -2.0, 0.002);
  EXPECT_NEAR(r.pose.position.y(), 0.0, 0.002);
  // chassis centre: clearance 0.015 + half of (0.146 - 0.015)
  EXPECT_NEAR(r.pose.position.z(), 0.05, 0.003);  // the centre of mass height
  EXPECT_LT(r.twist.linear.norm(), 0.005);
}

struct VelocityCase {
  const char* name;
  double forward, left, angular;
};
// gtest names a failing case by its name, not by its bytes.
void PrintTo(const VelocityCase& c, std::ostream* os) { *os << c.name; }

class OmniSteadyVelocity : public ::testing::TestWithParam<std::tuple<std::string, VelocityCase>> {};

TEST_P(OmniSteadyVelocity, WithinThreePercentOfTheCommand) {
  const VelocityCase c = std::get<1>(GetParam());
  OmniWorld w(std::get<0>(GetParam()));
  w.Drive(LocalVelocityCommand{c.forward, c.left, c.angular}, 1.5);
  // Average over the next 0.5 s.
  Vec3 sum = Vec3::Zero();
  double spin = 0;
  const int n = 50;
  for (int k = 0; k < n; ++k) {
    w.Drive(LocalVelocityCommand{c.forward, c.left, c.angular}, 0.01);
    sum += w.LocalVelocity();
    spin += w.Robot().twist.angular.z();
  }
  const Vec3 v = sum / n;
  spin /= n;
  const double speed = std::hypot(c.forward, c.left);
  if (speed > 0) {
    EXPECT_NEAR(v.x(), c.forward, 0.03 * speed) << c.name;
    EXPECT_NEAR(v.y(), c.left, 0.03 * speed) << c.name;
  }
  if (c.angular != 0) {
    EXPECT_NEAR(spin, c.angular, 0.03 * std::abs(c.angular)) << c.name;
  } else {
    EXPECT_NEAR(spin, 0.0, 0.05) << c.name;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Commands, OmniSteadyVelocity,
    ::testing::Combine(BothProfiles(),
                       ::testing::Values(VelocityCase{"forward", 1.0, 0.0, 0.0},
                                         VelocityCase{"fast_forward", 2.5, 0.0, 0.0},
                                         VelocityCase{"sideways", 0.0, 1.0, 0.0},
                                         VelocityCase{"diagonal", 1.0, -1.0, 0.0},
                                         VelocityCase{"turning", 0.0, 0.0, 4.0},
                                         // Driving while turning keeps its course (AheadOfTheTurn):
                                         // without it 0.458 m/s sideways at fast.
                                         VelocityCase{"driving_and_turning", 1.0, 0.5, 2.0})),
    [](const auto& info) { return std::get<0>(info.param) + "_" + std::get<1>(info.param).name; });

TEST_P(OmniDrive, SpeedUpFollowsTheAccelerationLimit) {
  OmniWorld w(GetParam());
  // Commanded 2 m/s forward: with a 3 m/s² limit the robot needs 0.667 s.
  std::vector<double> t, v;
  for (int k = 0; k < 60; ++k) {
    w.Drive(LocalVelocityCommand{2.0, 0.0, 0.0}, 0.01);
    t.push_back(0.01 * (k + 1));
    v.push_back(w.LocalVelocity().x());
  }
  // Fit the slope between 20 % and 80 % of the final speed.
  double st = 0, sv = 0, stt = 0, stv = 0;
  int n = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (v[i] < 0.4 || v[i] > 1.6) continue;
    st += t[i]; sv += v[i]; stt += t[i] * t[i]; stv += t[i] * v[i]; ++n;
  }
  ASSERT_GT(n, 10);
  const double slope = (n * stv - st * sv) / (n * stt - st * st);
  EXPECT_NEAR(slope, 3.0, 0.05 * 3.0);
}

TEST_P(OmniDrive, BrakesToAStopAfterTheCommandTimeout) {
  OmniWorld w(GetParam());
  w.Drive(LocalVelocityCommand{1.5, 0.0, 0.0}, 1.0);
  EXPECT_GT(w.LocalVelocity().x(), 1.4);
  // No more commands: after 0.1 s the servo brakes at 6 m/s² (0.25 s from 1.5 m/s).
  w.Run(0.6);
  EXPECT_LT(w.Robot().twist.linear.norm(), 0.02);
}

INSTANTIATE_TEST_SUITE_P(BothProfiles, OmniDrive, BothProfiles(), ProfileName);

TEST(OmniDriveModel, WheelSpeedCommandMustMatchTheWheelCount) {
  OmniWorld w("fast");
  w.world->events().Post(CommandEvent{{Team::kBlue, 0}, WheelSpeedCommand{{1.0, 2.0, 3.0}}, {}, {}});
  w.world->ProcessEvents();
  EXPECT_EQ(w.world->event_counters().rejected, 1);
  EXPECT_NE(w.text.str().find("3 speeds, this robot has 4 wheels"), std::string::npos) << w.text.str();
}

// The motor's rotor turns with the wheel through its gears: the model's rotor_inertia adds to the
// wheel's inertia about its axle, and nothing to its mass (the motor rides on the chassis). With
// wheel bodies (`wheel_bodies: true`) that is the body's; contact wheels step it themselves
// (tests/unit/physics/fixed_mass_test.cpp).
TEST(OmniDriveModel, TheRotorAddsInertiaAboutTheAxleOnly) {
  const std::string file = testing::EditedModelFile(kOmniRobot, "  plugin: omni\n", "  plugin: omni\n  wheel_bodies: true\n",
                                                    "ubersim-omni-wheel-bodies-robot");
  OmniWorld w("fast", file);
  std::filesystem::remove(file);
  Body* wheel = WorldAttorney::Scene(*w.world).Find("blue/0/wheel0")->FindBody("wheel");
  ASSERT_NE(wheel, nullptr);
  dMass m;
  dBodyGetMass(static_cast<BodyImpl*>(wheel)->id(), &m);
  const double r = 0.029, width = 0.01, mass = 0.05, rotor = 1.6e-4;  // models/robots/ssl-omni-2026.yaml
  EXPECT_DOUBLE_EQ(m.mass, mass);
  // The cylinder's axis (body z) is the axle.
  EXPECT_NEAR(m.I[2 * 4 + 2], 0.5 * mass * r * r + rotor, 1e-12);
  EXPECT_NEAR(m.I[0], mass * (3 * r * r + width * width) / 12, 1e-12);
  EXPECT_NEAR(m.I[1 * 4 + 1], mass * (3 * r * r + width * width) / 12, 1e-12);
}

// By default each wheel is a contact on the chassis: no wheel body, and the chassis carries the
// robot's 2.5 kg (2.3 kg and four 0.05 kg wheels).
TEST(OmniDriveModel, ContactWheelsAddTheirMassToTheChassis) {
  OmniWorld w("fast");
  EXPECT_EQ(WorldAttorney::Scene(*w.world).Find("blue/0/wheel0")->FindBody("wheel"), nullptr);
  Body* chassis = WorldAttorney::Scene(*w.world).Find("blue/0")->FindBody("chassis");
  ASSERT_NE(chassis, nullptr);
  EXPECT_DOUBLE_EQ(chassis->Mass(), 2.5);
}

// The modern robot's wheels lie inside its shell (outer rim 88.9 mm from the centre, the shell
// 90 mm; the front wheels' rims 67 mm forward, the flat front 70 mm) and the shell comes down to
// 15 mm, below a resting ball's centre: nothing but the carpet reaches them, so they carry no
// tyre geometry, only their carpet contact.
TEST(OmniDriveModel, TheShellShieldsTheWheelsFromAllButTheCarpet) {
  OmniWorld w("fast");
  for (int i = 0; i < 4; ++i) {
    const NodeImpl* wheel = WorldAttorney::Scene(*w.world).Find("blue/0/wheel" + std::to_string(i));
    ASSERT_NE(wheel, nullptr);
    EXPECT_EQ(wheel->FindGeom("tyre"), nullptr) << "wheel " << i;
    EXPECT_NE(wheel->FindGeom("carpet_contact"), nullptr) << "wheel " << i;
  }
  RobotBodyInfo body;
  body.radius = 0.09;
  body.front_distance = 0.07;
  body.ground_clearance = 0.015;
  const double ball = 0.0215;
  auto wheel_at = [](double angle_deg, double distance) {
    const double a = angle_deg * M_PI / 180;
    WheelSpec spec;
    spec.centre = Vec3(std::cos(a), std::sin(a), 0) * distance + Vec3(0, 0, -0.021);
    spec.axle = -Vec3(std::cos(a), std::sin(a), 0);
    spec.radius = 0.029;
    spec.width = 0.01;
    return spec;
  };
  EXPECT_TRUE(ShellShieldsWheel(body, ball, wheel_at(135, 0.079)));
  EXPECT_TRUE(ShellShieldsWheel(body, ball, wheel_at(60, 0.079)));
  EXPECT_FALSE(ShellShieldsWheel(body, ball, wheel_at(135, 0.080)));  // rim 0.2 mm from the shell
  EXPECT_FALSE(ShellShieldsWheel(body, ball, wheel_at(45, 0.079)));   // rim past the flat front
  RobotBodyInfo high = body;
  high.ground_clearance = 0.025;  // a ball could roll under the shell
  EXPECT_FALSE(ShellShieldsWheel(high, ball, wheel_at(135, 0.079)));
  WheelSpec tilted = wheel_at(135, 0.079);
  tilted.axle = Vec3(1, 0, 1);  // not horizontal: the disc's extent is not worked out
  EXPECT_FALSE(ShellShieldsWheel(body, ball, tilted));
}

}  // namespace
}  // namespace ubersim::kernel
