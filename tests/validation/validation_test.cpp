// SPDX-License-Identifier: Apache-2.0
// Every physics-validation scenario, asserted: each number within its published band (the same
// code and bands `ubersim validate-physics` writes into docs/validation/), at the shipped worlds'
// profile (precise) one by one, and all of them again at fast.
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ball_scenarios.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/validation/scenarios.hpp"

namespace ubersim::validation {
namespace {

struct Env {
  std::ostringstream text;
  kernel::StreamLog log{text, LogLevel::kWarning};
  kernel::PluginRegistry registry{{UBERSIM_PLUGIN_BUILD_DIR}};
  Environment env{UBERSIM_SOURCE_DIR "/models", UBERSIM_SOURCE_DIR "/schemas", &registry, &log, {}};
};

// Runs a scenario and checks every metric against its band, naming the ones outside.
ScenarioResult RunAndCheck(const std::string& id) {
  Env e;
  ScenarioResult r = FindScenario(id).run(e.env);
  EXPECT_EQ(r.id, id);
  EXPECT_FALSE(r.metrics.empty());
  for (const Metric& m : r.metrics) {
    EXPECT_TRUE(m.Pass()) << id << ": " << m.name << " = " << m.value << " " << m.unit << ", band " << m.low
                          << " … " << m.high << " (" << m.basis << ")";
  }
  return r;
}

TEST(PhysicsValidation, BallRolledAt2MetresPerSecondSlidesThenRolls) {
  const ScenarioResult r = RunAndCheck("ball_roll_2");
  // The sliding phase is Coulomb friction: μ_k·g with the shipped μ_k = 0.35.
  EXPECT_NEAR(r.Get("sliding_deceleration").value, 0.35 * 9.81, 0.05);
  EXPECT_NEAR(r.Get("stopping_distance").value, 3.0, 0.35);  // physics.md: 2.8–3.5 m at 2 m/s
}

TEST(PhysicsValidation, BallRolledAt5MetresPerSecondSlidesThenRolls) {
  const ScenarioResult r = RunAndCheck("ball_roll_5");
  // Decelerations do not depend on the initial speed.
  EXPECT_NEAR(r.Get("rolling_deceleration").value, 0.359, 0.02);
}

TEST(PhysicsValidation, ChipFlightAndBounces) {
  const ScenarioResult r = RunAndCheck("chip_flight");
  // At least three hops are measured, each losing vertical speed.
  EXPECT_NO_THROW(r.Get("bounce3_damping_z"));
  EXPECT_FALSE(r.plots.empty());
}

TEST(PhysicsValidation, ThousandShotsAtTheSpeedLimitNeverPassThrough) {
  const ScenarioResult r = RunAndCheck("no_tunnelling");
  EXPECT_EQ(r.Get("shots").value, 1000);
  EXPECT_GT(r.Get("deepest_penetration_into_a_robot").value, 0.0);  // the ball did hit robots
}

TEST(PhysicsValidation, TheTunnellingCheckCatchesACoarseStep) {
  // rSim's 25 ms step moves a 6.5 m/s ball 16 cm a step, about a robot's width: shots get through,
  // and the same check that passes at the shipped step must see them.
  Env e;
  const ScenarioResult r = detail::NoTunnelling(e.env, 200, 0.025);
  EXPECT_GT(r.Get("shots_through_a_robot").value, 0);
  EXPECT_FALSE(r.Pass());
}

TEST(PhysicsValidation, OmniRobotHoldsCommandedVelocities) { RunAndCheck("omni_steady_velocity"); }

TEST(PhysicsValidation, OmniRobotSpeedsUpAtItsLimit) { RunAndCheck("omni_acceleration"); }

TEST(PhysicsValidation, OmniForceRobotHoldsCommandedVelocities) {
  const ScenarioResult r = RunAndCheck("omni_force_steady_velocity");
  // One rigid body pushed by the wheel forces: the only steady error is the rollers' drag over
  // the wheels' servo stiffness, about a millimetre per second at precise, five at the shipped
  // fast profile's 5 ms steps (the servo's force is the one that would reach the target in one
  // step): 2.4 and 5.3 mm/s measured.
  EXPECT_NEAR(r.Get("forward_speed").value, 1.0, 0.006);
  EXPECT_NEAR(r.Get("sideways_speed").value, 1.0, 0.006);
  EXPECT_NEAR(r.Get("turning_angular_speed").value, 1.0, 0.001);
}

TEST(PhysicsValidation, OmniForceRobotSpeedsUpAtItsLimit) {
  const ScenarioResult r = RunAndCheck("omni_force_acceleration");
  EXPECT_NEAR(r.Get("acceleration_vs_limit").value, 1.0, 0.01);
  ASSERT_EQ(r.plots.size(), 1u);
  EXPECT_EQ(r.plots[0].file, "omni-force-acceleration.svg");  // not the omni drive's plot
}

TEST(PhysicsValidation, KickerClampsFlatKicksAndChipsAtItsAngle) {
  const ScenarioResult r = RunAndCheck("kicker_speeds");
  EXPECT_NEAR(r.Get("flat_kick_commanded_10").value, 6.5, 0.1);
}

TEST(PhysicsValidation, DribblerHoldsTheBallDrivingAndTurningAndLosesItSpinning) {
  const ScenarioResult r = RunAndCheck("dribbler_hold");
  EXPECT_EQ(r.Get("drive_1m_and_turn_90_held_fraction").value, 1.0);
  EXPECT_EQ(r.Get("fast_spin_8_rad_s_loses_the_ball").value, 1.0);
}

TEST(PhysicsValidation, OmniForceRobotsKickerClampsFlatKicksAndChipsAtItsAngle) {
  const ScenarioResult r = RunAndCheck("omni_force_kicker_speeds");
  EXPECT_NEAR(r.Get("flat_kick_commanded_10").value, 6.5, 0.1);
}

TEST(PhysicsValidation, OmniForceRobotsDribblerHoldsTheBallDrivingAndTurningAndLosesItSpinning) {
  const ScenarioResult r = RunAndCheck("omni_force_dribbler_hold");
  EXPECT_EQ(r.Get("drive_1m_and_turn_90_held_fraction").value, 1.0);
  EXPECT_EQ(r.Get("fast_spin_8_rad_s_loses_the_ball").value, 1.0);
  EXPECT_EQ(r.plots.at(0).file, "omni-force-dribbler-hold.svg");
}

TEST(PhysicsValidation, MecanumRobotHoldsEveryCommandIncludingSideways) {
  const ScenarioResult r = RunAndCheck("mecanum_steady_velocity");
  EXPECT_NEAR(r.Get("sideways_speed").value, 1.0, 0.01);  // rollers at 45°: sideways is possible
  EXPECT_NEAR(r.Get("diagonal_speed").value, 1.0, 0.01);
}

TEST(PhysicsValidation, MecanumRobotAcceleratesAtItsLimit) { RunAndCheck("mecanum_acceleration"); }

TEST(PhysicsValidation, MecanumRobotsSpinUpIsGripLimitedAtMuGCos45) {
  const ScenarioResult r = RunAndCheck("mecanum_grip_limit");
  EXPECT_GT(r.Get("speed_up_vs_mu_g_cos45").value, 0.9);  // the free rollers' drag takes a few %
  EXPECT_EQ(r.plots.at(0).file, "mecanum-grip-limit.svg");
}

TEST(PhysicsValidation, PaperDifferentialRobotAcceleratesAtTwoMetresPerSecondSquared) {
  const ScenarioResult r = RunAndCheck("paper_acceleration");
  ASSERT_EQ(r.plots.size(), 1u);
  EXPECT_EQ(r.plots[0].series.size(), 2u);  // the robot and the commanded profile
}

TEST(PhysicsValidation, PaperFigureEightAtPointEightMetresPerSecond) {
  const ScenarioResult r = RunAndCheck("paper_figure_eight");
  EXPECT_TRUE(r.plots.at(0).equal_axes);  // a path on the field keeps its shape
}

// The fast profile (5 ms, 10 solver iterations for the ball's islands and 2 for the others, one
// contact per pair) keeps every number of every scenario in its band: the ball, the modern robots
// (both drives), the kicker and the dribbler, the mecanum robot and the 2003 paper's differential
// robot. The last two ask for 6 iterations in their model files (min_solver_iterations): at 2 the
// mecanum robot turns 8 % fast and speeds up at 0.81 of its limit, and the differential robot
// reaches 18 % of its acceleration; without the wheels' rotor inertia
// (models/robots/ssl-omni-2026.yaml) the omni robot's sideways speed falls 5 % short. One test
// per scenario, so that ctest runs them side by side.
class AtFast : public ::testing::TestWithParam<std::string> {};

TEST_P(AtFast, TheScenarioKeepsEveryNumber) {
  Env e;
  e.env.physics.profile = "fast";
  const ScenarioResult r = FindScenario(GetParam()).run(e.env);
  EXPECT_FALSE(r.metrics.empty());
  for (const Metric& m : r.metrics) {
    EXPECT_TRUE(m.Pass()) << m.name << " = " << m.value << " " << m.unit << ", band " << m.low << " … " << m.high;
  }
}

std::vector<std::string> ScenarioIds() {
  std::vector<std::string> ids;
  for (const Scenario& s : AllScenarios()) ids.push_back(s.id);
  return ids;
}

INSTANTIATE_TEST_SUITE_P(PhysicsValidation, AtFast, ::testing::ValuesIn(ScenarioIds()),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

TEST(PhysicsValidation, EveryScenarioIsCoveredHere) {
  // A scenario added to the list without a test here would go unasserted.
  const std::vector<std::string> tested = {"ball_roll_2", "ball_roll_5", "chip_flight", "no_tunnelling",
                                           "omni_steady_velocity", "omni_acceleration",
                                           "omni_force_steady_velocity", "omni_force_acceleration",
                                           "mecanum_steady_velocity", "mecanum_acceleration", "mecanum_grip_limit",
                                           "kicker_speeds", "dribbler_hold", "omni_force_kicker_speeds",
                                           "omni_force_dribbler_hold", "paper_acceleration",
                                           "paper_figure_eight"};
  std::vector<std::string> all;
  for (const Scenario& s : AllScenarios()) all.push_back(s.id);
  EXPECT_EQ(all, tested);
  EXPECT_THROW(FindScenario("warp_drive"), std::out_of_range);
}

}  // namespace
}  // namespace ubersim::validation
