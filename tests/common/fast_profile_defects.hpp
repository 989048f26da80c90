// SPDX-License-Identifier: Apache-2.0
#pragma once

// What the fast physics profile still gets wrong, found by running every drive and part test at
// both profiles (docs/performance.md, "What keeps fast from being the default"). The tests that
// meet one of these skip at fast, naming it; the shipped worlds stay at precise until each is
// fixed and its skips are gone. Each is measured, with its cause as far as it is known.
namespace ubersim::testing {

/// Wheel-body robots at two solver sweeps (the islands without the ball): the chassis sags 6.8 mm
/// on its wheel hinges, tips 1.5° nose down and creeps 6.7 mm/s at rest (precise: 0.06 mm/s); a
/// braking robot swings back and turns; the dribbler bar, 7 mm low, pushes a ball put at rest in
/// the mouth out at 0.3 m/s. 4 sweeps: 2.7 mm and 1.1 mm/s; 10: 0.9 mm. The cause is the mass
/// ratio of 0.05 kg wheels under a 2.3 kg chassis (0.2 kg wheels: 1.2 mm, 0.24°), not the load,
/// the contacts or the motors (docs/performance.md).
inline constexpr const char* kWheelRobotSagsAtTwoSweeps =
    "fast profile: wheel-body robots sag 6.8 mm on their hinges and creep 6.7 mm/s at two solver sweeps";

/// The 2003 differential robot at its 6 sweeps (min_solver_iterations): its wheels slip while
/// their motors hold the commanded rates, so it turns 7 % short on the spot and an arc wanders
/// 35 mm off its circle; 10 sweeps meet every band.
inline constexpr const char* kDiffRobotSlipsAtSixSweeps =
    "fast profile: the differential robot's wheels slip at 6 solver sweeps (turns 7 % short)";

}  // namespace ubersim::testing
