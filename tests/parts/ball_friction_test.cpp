// SPDX-License-Identifier: Apache-2.0
// The ball's friction on the carpet acts against its slip as a whole (Coulomb's cone), not up to
// mu·N in each of two directions (ODE's pyramid). A ball spinning in place under a dribbler
// skids forward on the carpet; carried sideways, it must feel only the sideways share of that
// friction, or no dribbler could turn with it. At both physics profiles.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "parts_world.hpp"

namespace ubersim::kernel {
namespace {

class BallOnCarpet : public ::testing::TestWithParam<std::string> {};

INSTANTIATE_TEST_SUITE_P(Profiles, BallOnCarpet, ::testing::ValuesIn(PhysicsProfileNames()),
                         [](const auto& info) { return info.param; });

TEST_P(BallOnCarpet, FrictionOpposesTheWholeSlip) {
  PartsWorld w(GetParam());
  const double r = w.BallRadius(), g = 9.81, mu = 0.35;  // ball|carpet, div-b.yaml
  // Spinning backwards in place (the carpet slips under it at 40·r = 0.86 m/s along x) and moving
  // sideways at 0.3 m/s.
  const double spin = -40.0, side = 0.3;
  w.world->events().Post(PositionEvent{Target::Ball(), Vec3(1.0, 1.0, r), std::nullopt, Vec3(0, side, 0),
                                       Vec3(0, spin, 0), std::nullopt});
  w.Run(0.005);  // settle the contact
  const double vy0 = w.BallTwist().linear.y();
  const double t = 0.02;
  w.Run(t);
  const double decel = (vy0 - w.BallTwist().linear.y()) / t;
  // Cone: the sideways share of mu·g, side / |slip| ≈ 0.33 of it; pyramid: all of it.
  const double slip = std::hypot(-spin * r, side);
  EXPECT_NEAR(decel, mu * g * side / slip, 0.25 * mu * g * side / slip);
  EXPECT_LT(decel, 0.5 * mu * g);
  // And a plain skid (no sideways motion) still slows at mu·g.
  PartsWorld s(GetParam());
  s.world->events().Post(PositionEvent{Target::Ball(), Vec3(1.0, 1.0, r), std::nullopt, Vec3(2.0, 0, 0),
                                       Vec3::Zero(), std::nullopt});
  s.Run(0.005);
  const double v0 = s.BallTwist().linear.x();
  s.Run(t);
  EXPECT_NEAR((v0 - s.BallTwist().linear.x()) / t, mu * g, 0.1 * mu * g);
}

}  // namespace
}  // namespace ubersim::kernel
