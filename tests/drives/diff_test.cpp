// SPDX-License-Identifier: Apache-2.0
// The diff drive on the paper's CMDragons 2003 differential robot: stands level; steady forward,
// backward and turning speeds within 3 % of the command; an arc of radius v/ω; speed-up
// following the 2 m/s² limit within 5 % without wheel slip; braking after the command timeout;
// wheel-speed commands (2 accepted, 3 refused); sideways commands dropped with a warning; the
// motor's rotor inertia on the wheels' axles. What a team meets is checked at both physics
// profiles.
#include <cmath>
#include <filesystem>
#include <ostream>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <ode/ode.h>

#include "../common/edited_model_file.hpp"
#include "diff_world.hpp"
#include "physics/scene_graph.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel {
namespace {

constexpr double kWheelRadius = 0.03;      // m, as in the robot file
constexpr double kWheelSeparation = 0.14;  // m, as in the robot file

// Angle between the robot's up axis and the world's, rad.
double Tilt(const RobotState& r) {
  const Vec3 up = r.pose.orientation * Vec3::UnitZ();
  return std::acos(std::clamp(up.z(), -1.0, 1.0));
}

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

// Mean local velocity and spin over the next `n` × 10 ms while still commanding `c`.
struct Measured {
  Vec3 local = Vec3::Zero();
  double spin = 0;
};
Measured Average(DiffWorld& w, const MoveCommand& c, int n = 50) {
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

class DiffDrive : public ::testing::TestWithParam<std::string> {};

TEST_P(DiffDrive, StandsLevelOnWheelsAndCastersWithoutDrifting) {
  DiffWorld w(GetParam());
  w.Run(1.0);
  const RobotState r = w.Robot();
  EXPECT_NEAR(r.pose.position.x(), -3.0, 0.001);
  EXPECT_NEAR(r.pose.position.y(), 0.0, 0.001);
  EXPECT_NEAR(r.pose.position.z(), 0.045, 0.002);  // the centre of mass height
  EXPECT_LT(Tilt(r), 0.2 * M_PI / 180);
  EXPECT_LT(r.twist.linear.head<2>().norm(), 0.005);
  // At fast the chassis buzzes on its wheels and caster springs in a 4-step cycle, up to
  // 7.6 mm/s vertically (25 µm) measured; it stays where it was put.
  EXPECT_LT(std::abs(r.twist.linear.z()), GetParam() == "fast" ? 0.01 : 0.005);
  EXPECT_LT(std::abs(r.twist.angular.z()), 0.01);
}

struct VelocityCase {
  const char* name;
  double forward, angular;
  double start_x;  // m; backward runs start mid-field
};
// gtest names a failing case by its name, not by its bytes.
void PrintTo(const VelocityCase& c, std::ostream* os) { *os << c.name; }

class DiffSteadyVelocity : public ::testing::TestWithParam<std::tuple<std::string, VelocityCase>> {};

TEST_P(DiffSteadyVelocity, WithinThreePercentOfTheCommand) {
  const VelocityCase c = std::get<1>(GetParam());
  DiffWorld w(std::get<0>(GetParam()), c.start_x);
  const LocalVelocityCommand cmd{c.forward, 0.0, c.angular};
  w.Drive(cmd, 1.5);
  const Vec3 before = w.Robot().pose.position;
  const Measured m = Average(w, cmd);
  if (c.forward != 0) {
    EXPECT_NEAR(m.local.x(), c.forward, 0.03 * std::abs(c.forward)) << c.name;
  } else {
    // Turning on the spot: the centre stays put.
    EXPECT_LT((w.Robot().pose.position - before).head<2>().norm(), 0.01) << c.name;
  }
  EXPECT_NEAR(m.local.y(), 0.0, 0.02) << c.name;
  if (c.angular != 0) {
    EXPECT_NEAR(m.spin, c.angular, 0.03 * std::abs(c.angular)) << c.name;
  } else {
    EXPECT_NEAR(m.spin, 0.0, 0.02) << c.name;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Commands, DiffSteadyVelocity,
    ::testing::Combine(::testing::ValuesIn(PhysicsProfileNames()),
                       ::testing::Values(VelocityCase{"forward", 1.0, 0.0, -3.0},
                                         VelocityCase{"full_speed", 2.0, 0.0, -3.5},
                                         VelocityCase{"backward", -1.0, 0.0, 0.0},
                                         VelocityCase{"turning", 0.0, 4.0, -3.0},
                                         VelocityCase{"turning_fast", 0.0, -8.0, -3.0})),
    [](const auto& info) { return std::get<0>(info.param) + "_" + std::get<1>(info.param).name; });

TEST_P(DiffDrive, AnArcHasRadiusSpeedOverTurnRate) {
  DiffWorld w(GetParam(), 0.0, 0.0);
  const LocalVelocityCommand cmd{0.8, 0.0, 2.0};  // 0.4 m radius, the figure-8's kind of turn
  w.Drive(cmd, 1.0);
  // Fit a circle (algebraic least squares) to the path over the next 2 s, about 1.3 turns.
  std::vector<Vec3> path;
  for (int k = 0; k < 200; ++k) {
    w.Drive(cmd, 0.01);
    path.push_back(w.Robot().pose.position);
  }
  Eigen::MatrixXd a(static_cast<Eigen::Index>(path.size()), 3);
  Eigen::VectorXd b(static_cast<Eigen::Index>(path.size()));
  for (std::size_t i = 0; i < path.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    a.row(r) << 2 * path[i].x(), 2 * path[i].y(), 1.0;
    b(r) = path[i].x() * path[i].x() + path[i].y() * path[i].y();
  }
  const Eigen::Vector3d s = a.colPivHouseholderQr().solve(b);  // cx, cy, r² − cx² − cy²
  const double radius = std::sqrt(s(2) + s(0) * s(0) + s(1) * s(1));
  EXPECT_NEAR(radius, 0.4, 0.03 * 0.4);
  double worst = 0;
  for (const Vec3& p : path) worst = std::max(worst, std::abs(std::hypot(p.x() - s(0), p.y() - s(1)) - radius));
  EXPECT_LT(worst, 0.01);  // a circle, not a spiral
}

TEST_P(DiffDrive, SpeedUpFollowsTheAccelerationLimitWithoutWheelSlip) {
  DiffWorld w(GetParam(), -3.5);
  // Commanded 2 m/s forward: with the paper's 2 m/s² the robot needs 1 s.
  std::vector<double> t, v;
  double worst_slip = 0;
  for (int k = 0; k < 120; ++k) {
    w.Drive(LocalVelocityCommand{2.0, 0.0, 0.0}, 0.01);
    t.push_back(0.01 * (k + 1));
    v.push_back(w.LocalVelocity().x());
    // Slip: the wheels' rim speed (their encoders, in the drive's feedback) against the chassis speed.
    const std::vector<double> rates = w.world->GroundTruth().robots.at(0).drive->wheel_speeds;
    const double rim = 0.5 * kWheelRadius * (rates.at(0) + rates.at(1));
    worst_slip = std::max(worst_slip, std::abs(rim - v.back()));
  }
  // Fit the slope between 20 % and 80 % of the final speed.
  double st = 0, sv = 0, stt = 0, stv = 0;
  int n = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (v[i] < 0.4 || v[i] > 1.6) continue;
    st += t[i]; sv += v[i]; stt += t[i] * t[i]; stv += t[i] * v[i]; ++n;
  }
  ASSERT_GT(n, 20);
  const double slope = (n * stv - st * sv) / (n * stt - st * st);
  EXPECT_NEAR(slope, 2.0, 0.05 * 2.0);
  // The slip band at both profiles: with wheel bodies at fast the wheels slipped up to 44 mm/s
  // early in the ramp (their friction unconverged at 6 solver iterations); contact wheels on the
  // chassis grip within the band.
  EXPECT_LT(worst_slip, 0.03);
  EXPECT_NEAR(v.back(), 2.0, 0.03 * 2.0);
  EXPECT_LT(Tilt(w.Robot()), 1.0 * M_PI / 180);  // the casters keep it level
}

TEST_P(DiffDrive, BrakesToAStopAfterTheCommandTimeout) {
  DiffWorld w(GetParam());
  w.Drive(LocalVelocityCommand{1.5, 0.0, 0.0}, 1.5);
  EXPECT_GT(w.LocalVelocity().x(), 1.45);
  // The last command was 10 ms ago: 80 ms later it still holds (timeout 0.1 s) …
  w.Run(0.08);
  EXPECT_GT(w.LocalVelocity().x(), 1.45);
  // … then the servo brakes at 4 m/s² (0.375 s from 1.5 m/s).
  w.Run(0.5);
  EXPECT_LT(w.Robot().twist.linear.norm(), 0.02);
  EXPECT_LT(std::abs(w.Robot().twist.angular.z()), 0.05);
}

TEST_P(DiffDrive, FollowsTwoWheelSpeedsLeftThenRight) {
  DiffWorld w(GetParam(), 0.0);
  const double left = 10, right = 20;  // rad/s
  const Measured m = (w.Drive(WheelSpeedCommand{{left, right}}, 1.0), Average(w, WheelSpeedCommand{{left, right}}));
  const double v = 0.5 * kWheelRadius * (left + right);
  const double omega = kWheelRadius * (right - left) / kWheelSeparation;
  EXPECT_NEAR(m.local.x(), v, 0.03 * v);
  EXPECT_NEAR(m.spin, omega, 0.03 * omega);
  EXPECT_EQ(w.world->event_counters().rejected, 0);
}

TEST(DiffDriveModel, WheelSpeedCommandWithThreeSpeedsIsRefused) {
  DiffWorld w("fast");
  w.world->events().Post(CommandEvent{{Team::kBlue, 0}, WheelSpeedCommand{{1.0, 2.0, 3.0}}, {}, {}});
  w.world->ProcessEvents();
  EXPECT_EQ(w.world->event_counters().rejected, 1);
  EXPECT_NE(w.text.str().find("3 speeds, this robot has 2 wheels"), std::string::npos) << w.text.str();
}

TEST_P(DiffDrive, SidewaysCommandIsFollowedWithoutTheLateralPartAndWarnedRarely) {
  DiffWorld w(GetParam());
  const LocalVelocityCommand cmd{0.5, 1.0, 0.0};
  w.Drive(cmd, 1.5);  // 150 commands
  const Measured m = Average(w, cmd);
  EXPECT_NEAR(m.local.x(), 0.5, 0.03 * 0.5);
  EXPECT_NEAR(m.local.y(), 0.0, 0.01);
  EXPECT_NEAR(m.spin, 0.0, 0.02);
  const std::string log = w.text.str();
  const int warnings = Count(log, "cannot move sideways");
  // 2 s of commands at 100 Hz, at most one warning per simulated second.
  EXPECT_GE(warnings, 1) << log;
  EXPECT_LE(warnings, 2) << log;
  EXPECT_EQ(w.world->event_counters().rejected, 0);
}

TEST_P(DiffDrive, GlobalCommandIsTurnedIntoTheRobotFrame) {
  DiffWorld w(GetParam(), 0.0, -2.0, M_PI / 2);  // facing +y
  const GlobalVelocityCommand along{0.0, 1.0, 0.0};
  w.Drive(along, 1.5);
  const Measured m = Average(w, along);
  EXPECT_NEAR(m.local.x(), 1.0, 0.03);
  EXPECT_NEAR(m.local.y(), 0.0, 0.02);
  EXPECT_EQ(Count(w.text.str(), "cannot move sideways"), 0) << w.text.str();

  // Across the heading: nothing a diff robot can follow; it stays and warns.
  DiffWorld across(GetParam(), 0.0, 0.0, M_PI / 2);
  const GlobalVelocityCommand sideways{1.0, 0.0, 0.0};
  across.Drive(sideways, 1.0);
  EXPECT_LT(across.Robot().twist.linear.norm(), 0.02);
  EXPECT_NEAR(across.Robot().pose.position.x(), 0.0, 0.01);
  EXPECT_GE(Count(across.text.str(), "cannot move sideways"), 1) << across.text.str();
}

INSTANTIATE_TEST_SUITE_P(BothProfiles, DiffDrive, ::testing::ValuesIn(PhysicsProfileNames()),
                         [](const auto& info) { return info.param; });

// The motor's rotor turns with the wheel through its gears: `motor.rotor_inertia` adds to each
// wheel's inertia about its axle and nothing to its mass, as on the omni drive (with wheel
// bodies: the contact wheels' spin is the drive's, tests/unit/physics/fixed_mass_test.cpp).
TEST(DiffDriveModel, TheRotorAddsInertiaAboutTheAxleOnly) {
  const double rotor = 2.0e-5;
  const std::string file = testing::EditedModelFile(
      kDiffRobot, "  motor:\n", "  motor:\n    rotor_inertia: 2.0e-5\n", "ubersim-diff-rotor-robot");
  const std::string bodies = testing::EditedModelFile(file, "  plugin: diff\n", "  plugin: diff\n  wheel_bodies: true\n",
                                                      "ubersim-diff-rotor-bodies-robot");
  DiffWorld w("fast", -3.0, 0.0, 0.0, bodies);
  std::filesystem::remove(file);
  std::filesystem::remove(bodies);
  const double r = kWheelRadius, width = 0.012, mass = 0.05;  // models/robots/cmdragons-2003-diff.yaml
  int wheels = 0;
  WorldAttorney::Scene(*w.world).Root().ForEachBody([&](BodyImpl& b) {
    if (b.Name() != "wheel") return;
    ++wheels;
    dMass m;
    dBodyGetMass(b.id(), &m);
    EXPECT_DOUBLE_EQ(m.mass, mass);
    EXPECT_NEAR(m.I[2 * 4 + 2], 0.5 * mass * r * r + rotor, 1e-12);  // the cylinder's axis is the axle
    EXPECT_NEAR(m.I[0], mass * (3 * r * r + width * width) / 12, 1e-12);
  });
  EXPECT_EQ(wheels, 2);
}

// By default the wheels are contacts on the chassis: no wheel bodies, and their mass is the
// chassis' (1.4 kg and two 0.05 kg wheels).
TEST(DiffDriveModel, ContactWheelsAddTheirMassToTheChassis) {
  DiffWorld w("fast", -3.0);
  int bodies = 0;
  double mass = 0;
  WorldAttorney::Scene(*w.world).Root().ForEachBody([&](BodyImpl& b) {
    if (b.Name() == "wheel") ++bodies;
    if (b.Name() == "chassis") mass = b.Mass();
  });
  EXPECT_EQ(bodies, 0);
  EXPECT_DOUBLE_EQ(mass, 1.5);
}

}  // namespace
}  // namespace ubersim::kernel
