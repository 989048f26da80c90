// SPDX-License-Identifier: Apache-2.0
// LoneBodyStepper: a body no joint touches, stepped by the kernel, ends every step bit for bit
// where QuickStep puts it; IsLoneBody leaves to ODE what the stepper does not reproduce.
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <ode/ode.h>

#include "physics/lone_body.hpp"
#include "physics/ode_handles.hpp"
#include "quickstep_twin.hpp"

namespace {

using ubersim::kernel::IsLoneBody;
using ubersim::kernel::LoneBodyStepper;
using ubersim::kernel::OdeLibrary;
using ubersim::kernel::OdeSpace;
using ubersim::kernel::OdeWorld;
using ubersim::test::StateDifference;

constexpr double kStep = 0.005;

OdeWorld MakeWorld() { return ubersim::test::MakeTiltedWorld(0.3); }

// A body with a random inertia tensor (a box turned arbitrarily: off-diagonal terms), pose and
// velocities, the same in both worlds.
struct Twin {
  dBodyID kernel;
  dBodyID ode;
};

Twin MakeTwin(dWorldID kernel_world, dWorldID ode_world, std::mt19937_64& rng, int index) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  dMass mass;
  dMassSetBoxTotal(&mass, 0.05 + 3.0 * (u(rng) + 1.0), 0.02 + 0.2 * (u(rng) + 1.0), 0.02 + 0.2 * (u(rng) + 1.0),
                   0.02 + 0.2 * (u(rng) + 1.0));
  dMatrix3 turn;
  dRFromEulerAngles(turn, 3 * u(rng), 3 * u(rng), 3 * u(rng));
  dMassRotate(&mass, turn);
  dQuaternion q = {u(rng), u(rng), u(rng), u(rng)};
  dNormalize4(q);
  const std::array<double, 3> p = {u(rng), u(rng), 1 + u(rng)};
  const std::array<double, 3> v = {6 * u(rng), 6 * u(rng), 3 * u(rng)};
  const std::array<double, 3> w = {20 * u(rng), 20 * u(rng), 40 * u(rng)};
  Twin t{dBodyCreate(kernel_world), dBodyCreate(ode_world)};
  for (dBodyID b : {t.kernel, t.ode}) {
    dBodySetMass(b, &mass);
    dBodySetPosition(b, p[0], p[1], p[2]);
    dBodySetQuaternion(b, q);
    dBodySetLinearVel(b, v[0], v[1], v[2]);
    dBodySetAngularVel(b, w[0], w[1], w[2]);
    if (index % 5 == 1) dBodySetGravityMode(b, 0);       // a body gravity does not pull
    if (index % 7 == 2) dBodySetGyroscopicMode(b, 0);    // one without gyroscopic torque
  }
  return t;
}

TEST(LoneBodyStepper, EndsEveryStepBitForBitWhereQuickStepPutsTheBody) {
  OdeLibrary ode;
  OdeWorld kernel_world = MakeWorld(), ode_world = MakeWorld();
  std::mt19937_64 rng(20261124);
  std::vector<Twin> twins;
  for (int i = 0; i < 40; ++i) twins.push_back(MakeTwin(kernel_world.get(), ode_world.get(), rng, i));
  std::vector<std::array<dReal, 4>> start;
  for (const Twin& t : twins) {
    const dReal* q = dBodyGetQuaternion(t.kernel);
    start.push_back({q[0], q[1], q[2], q[3]});
  }

  LoneBodyStepper stepper;
  dVector3 gravity;
  dWorldGetGravity(kernel_world.get(), gravity);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int step = 0; step < 400; ++step) {
    for (const Twin& t : twins) {
      // The pushes a drive adds before a step (none on some steps: the zero path too).
      if (step % 3 == 0) continue;
      const std::array<double, 6> push = {20 * u(rng), 20 * u(rng), 20 * u(rng), u(rng), u(rng), u(rng)};
      for (dBodyID b : {t.kernel, t.ode}) {
        dBodyAddForce(b, push[0], push[1], push[2]);
        dBodyAddTorque(b, push[3], push[4], push[5]);
      }
    }
    for (const Twin& t : twins) {
      ASSERT_TRUE(IsLoneBody(t.kernel));
      stepper.Step(t.kernel, gravity, kStep);
    }
    // QuickStep draws nothing from its generator for islands without constraints: the kernel
    // skipping QuickStep leaves the generator as QuickStep would.
    dRandSetSeed(7);
    dWorldQuickStep(ode_world.get(), kStep);
    ASSERT_EQ(dRandGetSeed(), 7UL);
    for (std::size_t i = 0; i < twins.size(); ++i) {
      ASSERT_EQ(StateDifference(twins[i].kernel, twins[i].ode), "") << "body " << i << ", step " << step;
    }
  }
  // The comparison had something to compare: every body turned (and gravity or its pushes
  // moved it).
  for (std::size_t i = 0; i < twins.size(); ++i) {
    const dReal* q = dBodyGetQuaternion(twins[i].kernel);
    EXPECT_GT(std::abs(q[0] - start[i][0]) + std::abs(q[1] - start[i][1]) + std::abs(q[2] - start[i][2]), 0.01)
        << "body " << i;
  }
}

// A one-body robot drives level, turning about its vertical principal axis: its momentum lies
// along the turn and the gyroscopic torque is zero. The stepper skips computing it there: the
// body stays exactly level and within rounding (QuickStep's implicit form leaves a last bit in
// the turn rate) of where QuickStep puts it. Tilted a little, the same body is not taken by the
// shortcut and ends every step bit for bit where QuickStep puts it.
TEST(LoneBodyStepper, ALevelBodyTurningAboutItsVerticalAxisSkipsOnlyAZeroGyroscopicTorque) {
  OdeLibrary ode;
  OdeWorld kernel_world = MakeWorld(), ode_world = MakeWorld();
  dWorldSetGravity(kernel_world.get(), 0, 0, 0);  // carried by its wheels
  dWorldSetGravity(ode_world.get(), 0, 0, 0);
  dMass mass;
  dMassSetCylinderTotal(&mass, 2.5, 3, 0.09, 0.15);  // axis along z: a robot's chassis
  std::vector<Twin> twins;
  for (double tilt : {0.0, 0.02}) {
    Twin t{dBodyCreate(kernel_world.get()), dBodyCreate(ode_world.get())};
    for (dBodyID b : {t.kernel, t.ode}) {
      dBodySetMass(b, &mass);
      dBodySetPosition(b, 0.3, -0.2, 0.05);
      dQuaternion q = {std::cos(0.4), std::sin(tilt), 0, std::sin(0.4)};
      dNormalize4(q);
      dBodySetQuaternion(b, q);
      dBodySetLinearVel(b, 1.5, 0.5, 0);
      dBodySetAngularVel(b, 0, 0, 7.3);
    }
    twins.push_back(t);
  }
  LoneBodyStepper stepper;
  const dReal none[3] = {0, 0, 0};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int step = 0; step < 400; ++step) {
    const double fx = 20 * u(rng), fy = 20 * u(rng), tz = u(rng);
    for (const Twin& t : twins) {
      for (dBodyID b : {t.kernel, t.ode}) {
        dBodyAddForce(b, fx, fy, 0);
        dBodyAddTorque(b, 0, 0, tz);
      }
      stepper.Step(t.kernel, none, kStep);
    }
    dWorldQuickStep(ode_world.get(), kStep);
    ASSERT_EQ(StateDifference(twins[1].kernel, twins[1].ode), "") << "tilted, step " << step;
    for (int k = 0; k < 3; ++k) {
      ASSERT_NEAR(dBodyGetPosition(twins[0].kernel)[k], dBodyGetPosition(twins[0].ode)[k], 1e-12) << k;
      ASSERT_NEAR(dBodyGetAngularVel(twins[0].kernel)[k], dBodyGetAngularVel(twins[0].ode)[k], 1e-12) << k;
    }
  }
  const dReal* q = dBodyGetQuaternion(twins[0].kernel);
  const dReal* w = dBodyGetAngularVel(twins[0].kernel);
  EXPECT_EQ(q[1], 0.0);
  EXPECT_EQ(q[2], 0.0);
  EXPECT_EQ(w[0], 0.0);
  EXPECT_EQ(w[1], 0.0);
  EXPECT_GT(std::abs(w[2]), 1.0);  // still turning: the case the shortcut takes
  // The tilted one did wobble: its turn is not about a principal axis.
  EXPECT_NE(dBodyGetAngularVel(twins[1].kernel)[0], 0.0);
}

// The level body's shortcut (LoneBodyStepper::Step on a one-body robot driving level, turning
// about its vertical principal axis) ends every step bit for bit where the stepper's general
// way (StepAnyPose) puts it: under gravity carried by its wheels, turning, with pushes in the
// plane and torques about the vertical, and a step with no torque (the shortcut declines it).
TEST(LoneBodyStepper, ALevelBodysShortcutEndsEveryStepWhereTheGeneralStepPutsIt) {
  OdeLibrary ode;
  OdeWorld shortcut_world = MakeWorld(), general_world = MakeWorld();
  for (dWorldID w : {shortcut_world.get(), general_world.get()}) dWorldSetGravity(w, 0, 0, -9.81);
  dMass mass;
  dMassSetCylinderTotal(&mass, 2.5, 3, 0.09, 0.15);
  std::vector<Twin> twins;
  for (double yaw : {0.0, 0.4, -2.9}) {
    Twin t{dBodyCreate(shortcut_world.get()), dBodyCreate(general_world.get())};
    for (dBodyID b : {t.kernel, t.ode}) {
      dBodySetMass(b, &mass);
      dBodySetPosition(b, 0.3, -0.2, 0.05);
      dQuaternion q = {std::cos(yaw / 2), 0, 0, std::sin(yaw / 2)};
      dBodySetQuaternion(b, q);
      dBodySetLinearVel(b, 1.5, 0.5, 0);
    }
    twins.push_back(t);
  }
  LoneBodyStepper shortcut, general;
  dVector3 gravity;
  dWorldGetGravity(shortcut_world.get(), gravity);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int step = 0; step < 400; ++step) {
    const double fx = 20 * u(rng), fy = 20 * u(rng), tz = step % 50 == 7 ? 0.0 : u(rng);
    for (const Twin& t : twins) {
      for (dBodyID b : {t.kernel, t.ode}) {
        dBodyAddForce(b, fx, fy, 2.5 * 9.81);  // carried by its wheels
        dBodyAddTorque(b, 0, 0, tz);
      }
      shortcut.Step(t.kernel, gravity, kStep);
      general.StepAnyPose(t.ode, gravity, kStep);
      ASSERT_EQ(StateDifference(t.kernel, t.ode), "") << "step " << step;
    }
  }
  EXPECT_GT(shortcut.LevelSteps(), 1100U) << "the shortcut was taken";
  EXPECT_LT(shortcut.LevelSteps(), 1200U) << "and declined without a torque about the vertical";
  EXPECT_EQ(general.LevelSteps(), 0U);
  for (const Twin& t : twins) EXPECT_GT(std::abs(dBodyGetAngularVel(t.kernel)[2]), 0.01) << "it turned";
}

TEST(LoneBodyStepper, TellsTheGeometriesTheBodyMoved) {
  OdeLibrary ode;
  OdeWorld world = MakeWorld();
  OdeSpace space(dSimpleSpaceCreate(nullptr));
  dBodyID ball = dBodyCreate(world.get());
  dMass mass;
  dMassSetSphereTotal(&mass, 0.046, 0.0215);
  dBodySetMass(ball, &mass);
  dBodySetPosition(ball, 0, 0, 1);
  dBodySetLinearVel(ball, 6.5, 0, 0);
  dGeomID sphere = dCreateSphere(space.get(), 0.0215);
  dGeomSetBody(sphere, ball);
  dReal before[6];
  dGeomGetAABB(sphere, before);  // computed now, and clean until the body moves

  LoneBodyStepper stepper;
  dVector3 gravity;
  dWorldGetGravity(world.get(), gravity);
  stepper.Step(ball, gravity, kStep);
  dReal after[6];
  dGeomGetAABB(sphere, after);
  EXPECT_DOUBLE_EQ(after[0], dBodyGetPosition(ball)[0] - 0.0215);
  EXPECT_GT(after[0] - before[0], 0.03) << "the bounding box moved with the ball";
}

TEST(IsLoneBody, LeavesToOdeWhatTheStepperDoesNotReproduce) {
  OdeLibrary ode;
  OdeWorld world = MakeWorld();
  auto body = [&] { return ubersim::test::MakeBall(world.get()); };
  EXPECT_TRUE(IsLoneBody(body()));

  // Each case: what makes the body QuickStep's, set on a fresh body.
  const std::vector<std::pair<const char*, std::function<void(dBodyID)>>> cases = {
      {"a joint (a contact too)", [&](dBodyID b) { dJointAttach(dJointCreateBall(world.get(), nullptr), b, nullptr); }},
      {"disabled (QuickStep does not step it)", [](dBodyID b) { dBodyDisable(b); }},
      {"kinematic", [](dBodyID b) { dBodySetKinematic(b); }},
      {"finite rotation", [](dBodyID b) { dBodySetFiniteRotationMode(b, 1); }},
      {"linear damping", [](dBodyID b) { dBodySetLinearDamping(b, 0.01); }},
      {"angular damping", [](dBodyID b) { dBodySetAngularDamping(b, 0.01); }},
      {"a cap on the angular speed", [](dBodyID b) { dBodySetMaxAngularSpeed(b, 100); }},
  };
  for (const auto& [what, make] : cases) {
    dBodyID b = body();
    make(b);
    EXPECT_FALSE(IsLoneBody(b)) << what;
  }
}

// `count` bodies of random shapes, masses and states in `world` (the kernel's side of MakeTwin's
// pairs), drawn from `seed`.
std::vector<dBodyID> RandomBodies(dWorldID world, std::uint64_t seed, int count) {
  std::mt19937_64 rng(seed);
  std::vector<dBodyID> bodies;
  for (int i = 0; i < count; ++i) bodies.push_back(MakeTwin(world, world, rng, i).kernel);
  return bodies;
}

TEST(InverseInertiaCache, GivesTheMassOdeStoredAndFollowsANewOne) {
  // The cache reads a body's mass, inverse inertia and inverse mass where ODE keeps them: they
  // must be what dBodyGetMass and dBodySetMass's inverse give, and stay so when the mass changes.
  OdeLibrary ode;
  OdeWorld world = MakeWorld();
  ubersim::kernel::InverseInertiaCache cache;
  const std::vector<dBodyID> bodies = RandomBodies(world.get(), 11, 5);
  const auto expect_ode_mass = [&](dBodyID b, const char* when) {
    dMass m;
    dBodyGetMass(b, &m);
    dMatrix3 inverse;
    if (dInvertPDMatrix(m.I, inverse, 3) == 0) dRSetIdentity(inverse);
    const ubersim::kernel::BodyMass got = cache.Of(b);
    EXPECT_EQ(std::memcmp(got.mass, &m, sizeof m), 0) << when;
    for (int k = 0; k < 12; ++k) {
      if (k % 4 != 3) {
        EXPECT_EQ(got.inverse_inertia[k], inverse[k]) << when << ", element " << k;
      }
    }
    EXPECT_EQ(got.inverse_mass, dRecip(m.mass)) << when;
  };
  for (int round = 0; round < 2; ++round) {
    for (dBodyID b : bodies) expect_ode_mass(b, "as made");
  }
  dMass heavier;
  dMassSetBoxTotal(&heavier, 7.5, 0.3, 0.1, 0.05);
  dBodySetMass(bodies[2], &heavier);
  for (dBodyID b : bodies) expect_ode_mass(b, "after a new mass");
  EXPECT_EQ(cache.Of(bodies[2]).mass->mass, 7.5);
  // With Debian's ODE (0.16.2: dxBody holds mass, invI, invMass, then the position) the values
  // are read in place, not from the cache's fallback copy.
  EXPECT_EQ(cache.Of(bodies[0]).inverse_inertia + 12, dBodyGetPosition(bodies[0]) - 1)
      << "ODE's body layout is not the one the cache reads: it falls back to computing the inverse";
}

TEST(InverseInertiaCache, GivesEachBodysOwnArraysWhateverTheOrderOfAsking) {
  // The arrays the cache hands out are the getters' own, for the body asked about: in the order
  // of the step before (the first look), in another order, and for a body made since.
  OdeLibrary ode;
  OdeWorld world = MakeWorld();
  ubersim::kernel::InverseInertiaCache cache;
  std::vector<dBodyID> bodies = RandomBodies(world.get(), 12, 5);
  const dBodyID unseen = bodies.back();  // asked about only at the end
  bodies.pop_back();
  const auto expect_getters = [&](dBodyID b, const char* when) {
    ubersim::kernel::BodyStorage s;
    const ubersim::kernel::BodyMass m = cache.Of(b, s);
    EXPECT_EQ(s.position, dBodyGetPosition(b)) << when;
    EXPECT_EQ(s.quaternion, dBodyGetQuaternion(b)) << when;
    EXPECT_EQ(s.rotation, dBodyGetRotation(b)) << when;
    EXPECT_EQ(s.arrays.linear, dBodyGetLinearVel(b)) << when;
    EXPECT_EQ(s.arrays.angular, dBodyGetAngularVel(b)) << when;
    EXPECT_EQ(s.arrays.force, dBodyGetForce(b)) << when;
    EXPECT_EQ(s.arrays.torque, dBodyGetTorque(b)) << when;
    EXPECT_EQ(m.mass, cache.Of(b).mass) << when;
  };
  for (dBodyID b : bodies) expect_getters(b, "first sight");
  for (dBodyID b : bodies) expect_getters(b, "the same order");
  for (auto it = bodies.rbegin(); it != bodies.rend(); ++it) expect_getters(*it, "the reverse order");
  bodies.insert(bodies.begin() + 1, unseen);
  for (dBodyID b : bodies) expect_getters(b, "with a body made since");
}

}  // namespace
