// SPDX-License-Identifier: Apache-2.0
// IslandStepper: the ball's islands get their iterations, the others theirs, each exactly as if
// stepped alone; bodies disabled before a step stay so.
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <ode/ode.h>

#include "ubersim/kernel/island_stepper.hpp"
#include "ubersim/kernel/ode_handles.hpp"

namespace {

using ubersim::kernel::IslandStepper;
using ubersim::kernel::OdeLibrary;
using ubersim::kernel::OdeSpace;
using ubersim::kernel::OdeWorld;

constexpr double kStep = 0.005;
constexpr int kLinks = 6;

// A chain hanging from a fixed point by ball joints, held out horizontally at start, its links
// alternately 50 g and 2.5 kg: the mass ratio that makes QuickStep converge slowly.
struct Chain {
  std::vector<dBodyID> links;

  Chain(dWorldID w, double y) {
    for (int i = 0; i < kLinks; ++i) {
      dBodyID b = dBodyCreate(w);
      dMass m;
      dMassSetSphereTotal(&m, i % 2 ? 2.5 : 0.05, 0.02);
      dBodySetMass(b, &m);
      dBodySetPosition(b, 0.1 * (i + 1), y, 1.0);
      dJointID j = dJointCreateBall(w, nullptr);
      dJointAttach(j, b, i ? links.back() : nullptr);
      dJointSetBallAnchor(j, 0.1 * i, y, 1.0);
      links.push_back(b);
    }
  }
  // Largest distance between two neighbouring links beyond their 0.1 m: the joints' error.
  double Stretch(double y) const {
    double worst = 0;
    std::array<double, 3> prev{0.0, y, 1.0};
    for (dBodyID b : links) {
      const dReal* p = dBodyGetPosition(b);
      worst = std::max(worst, std::abs(std::hypot(p[0] - prev[0], p[1] - prev[1], p[2] - prev[2]) - 0.1));
      prev = {p[0], p[1], p[2]};
    }
    return worst;
  }
};

OdeWorld MakeWorld() {
  OdeWorld w(dWorldCreate());
  dWorldSetGravity(w.get(), 0, 0, -9.81);
  dWorldSetAutoDisableFlag(w.get(), 0);
  return w;
}

void ExpectSameState(const std::vector<dBodyID>& a, const std::vector<dBodyID>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(dBodyGetPosition(a[i])[k], dBodyGetPosition(b[i])[k]) << "link " << i;
      EXPECT_EQ(dBodyGetLinearVel(a[i])[k], dBodyGetLinearVel(b[i])[k]) << "link " << i;
    }
  }
}

TEST(IslandStepper, EachIslandIsSteppedAsIfAloneWithItsOwnIterations) {
  OdeLibrary ode;
  // One world with both chains; the last link of the first one is "the ball".
  OdeWorld both = MakeWorld();
  Chain with_ball(both.get(), 0.0);
  Chain without_ball(both.get(), 1.0);
  std::vector<dBodyID> bodies = with_ball.links;
  bodies.insert(bodies.end(), without_ball.links.begin(), without_ball.links.end());
  const std::vector<dBodyID> balls{with_ball.links.back()};
  IslandStepper stepper;
  stepper.SetIterations(20, 1);

  // The references: each chain alone, stepped with the iterations its island should get, the
  // second from where the first left QuickStep's random generator (as the second pass does).
  OdeWorld alone_20 = MakeWorld(), alone_1 = MakeWorld();
  dWorldSetQuickStepNumIterations(alone_20.get(), 20);
  dWorldSetQuickStepNumIterations(alone_1.get(), 1);
  Chain ref_with_ball(alone_20.get(), 0.0);
  Chain ref_without_ball(alone_1.get(), 1.0);

  unsigned long seed = 12345;
  for (int i = 0; i < 200; ++i) {
    dRandSetSeed(seed);
    stepper.Step(both.get(), bodies, balls, kStep);
    const unsigned long after_split = dRandGetSeed();

    dRandSetSeed(seed);
    dWorldQuickStep(alone_20.get(), kStep);
    dWorldQuickStep(alone_1.get(), kStep);
    seed = dRandGetSeed();
    ASSERT_EQ(after_split, seed) << "the passes drew differently from the generator, step " << i;
  }
  ExpectSameState(with_ball.links, ref_with_ball.links);
  ExpectSameState(without_ball.links, ref_without_ball.links);
  // The check can fail: the iterations make a difference in this scene.
  EXPECT_GT(without_ball.Stretch(1.0), 5 * with_ball.Stretch(0.0));
}

// A free body: no joint, so it is its own island, stepped by the kernel (LoneBodyStepper).
dBodyID FreeBody(dWorldID w, double x, double spin) {
  dBodyID b = dBodyCreate(w);
  dMass m;
  dMassSetBoxTotal(&m, 2.5, 0.18, 0.15, 0.14);
  dBodySetMass(b, &m);
  dBodySetPosition(b, x, 3.0, 2.0);
  dBodySetLinearVel(b, 1.0, -2.0, 0.5);
  dBodySetAngularVel(b, 0.3, spin, 7.0);
  return b;
}

TEST(IslandStepper, LoneBodiesAndALoneBallAreSteppedAsQuickStepWould) {
  OdeLibrary ode;
  // The chain is the only island QuickStep still solves; the ball is in flight (no contact) and
  // three robots drive free: the first pass has nothing left for QuickStep.
  OdeWorld both = MakeWorld();
  Chain chain(both.get(), 1.0);
  dBodyID ball = FreeBody(both.get(), -1.0, 40.0);
  std::vector<dBodyID> robots;
  for (int i = 0; i < 3; ++i) robots.push_back(FreeBody(both.get(), 1.0 + i, 2.0 * i));
  std::vector<dBodyID> bodies = chain.links;
  bodies.push_back(ball);
  bodies.insert(bodies.end(), robots.begin(), robots.end());
  IslandStepper stepper;
  stepper.SetIterations(20, 1);

  // The reference: QuickStep steps everything, the chain with the other islands' iterations.
  OdeWorld ref = MakeWorld();
  dWorldSetQuickStepNumIterations(ref.get(), 1);
  Chain ref_chain(ref.get(), 1.0);
  dBodyID ref_ball = FreeBody(ref.get(), -1.0, 40.0);
  std::vector<dBodyID> ref_robots;
  for (int i = 0; i < 3; ++i) ref_robots.push_back(FreeBody(ref.get(), 1.0 + i, 2.0 * i));

  for (int i = 0; i < 200; ++i) {
    dRandSetSeed(4321);
    stepper.Step(both.get(), bodies, {ball}, kStep);
    const unsigned long after_split = dRandGetSeed();
    dRandSetSeed(4321);
    dWorldQuickStep(ref.get(), kStep);
    ASSERT_EQ(after_split, dRandGetSeed()) << "step " << i;
    for (dBodyID b : bodies) ASSERT_TRUE(dBodyIsEnabled(b)) << "a paused body was left paused, step " << i;
  }
  ExpectSameState(chain.links, ref_chain.links);
  ExpectSameState({ball}, {ref_ball});
  ExpectSameState(robots, ref_robots);
  EXPECT_LT(dBodyGetPosition(ball)[2], 1.0) << "the ball fell";
}

// The order of a space's geometries: the index each was given (dGeomSetData), front to back.
std::vector<std::intptr_t> GeomOrder(dSpaceID space) {
  std::vector<std::intptr_t> order;
  for (int i = 0; i < dSpaceGetNumGeoms(space); ++i) {
    order.push_back(reinterpret_cast<std::intptr_t>(dGeomGetData(dSpaceGetGeom(space, i))));
  }
  return order;
}

TEST(IslandStepper, GeometriesAreToldTheyMovedInQuickStepsOrder) {
  OdeLibrary ode;
  // Free bodies between linked pairs, each body with a sphere in a simple space, which puts a
  // moved geometry at its front: the space's order afterwards is the order of the moves. The
  // broadphase's lists, and so the order of contacts, depend on it.
  struct Scene {
    OdeWorld world = MakeWorld();
    OdeSpace space{dSimpleSpaceCreate(nullptr)};
    std::vector<dBodyID> bodies;  // newest first, as IslandStepper::Step wants them
    Scene() {
      std::vector<dBodyID> created;
      for (int i = 0; i < 9; ++i) {
        dBodyID b = FreeBody(world.get(), 0.5 * i, 0.1 * i);
        dGeomID g = dCreateSphere(space.get(), 0.05);
        dGeomSetBody(g, b);
        dGeomSetData(g, reinterpret_cast<void*>(static_cast<std::intptr_t>(i)));
        created.push_back(b);
      }
      // Bodies 1-2 and 5-7 linked: islands of QuickStep's; 0, 3, 4 and 8 free.
      for (auto [a, b] : {std::pair{1, 2}, std::pair{5, 6}, std::pair{6, 7}}) {
        dJointAttach(dJointCreateBall(world.get(), nullptr), created[a], created[b]);
      }
      bodies.assign(created.rbegin(), created.rend());
      dSpaceClean(space.get());
    }
  };
  Scene stepped, reference;
  IslandStepper stepper;
  stepper.SetIterations(5, 5);
  dWorldSetQuickStepNumIterations(reference.world.get(), 5);
  for (int i = 0; i < 3; ++i) {
    stepper.Step(stepped.world.get(), stepped.bodies, {}, kStep);
    dWorldQuickStep(reference.world.get(), kStep);
    EXPECT_EQ(GeomOrder(stepped.space.get()), GeomOrder(reference.space.get())) << "step " << i;
    dSpaceClean(stepped.space.get());
    dSpaceClean(reference.space.get());
  }
  ExpectSameState(stepped.bodies, reference.bodies);
}

TEST(IslandStepper, EqualIterationsAreOneQuickStep) {
  OdeLibrary ode;
  OdeWorld a = MakeWorld(), b = MakeWorld();
  Chain ca(a.get(), 0.0), cb(b.get(), 0.0);
  dWorldSetQuickStepNumIterations(b.get(), 7);
  IslandStepper stepper;
  stepper.SetIterations(7, 7);
  for (int i = 0; i < 100; ++i) {
    dRandSetSeed(99);
    stepper.Step(a.get(), ca.links, {ca.links.back()}, kStep);
    dRandSetSeed(99);
    dWorldQuickStep(b.get(), kStep);
  }
  ExpectSameState(ca.links, cb.links);
}

TEST(IslandStepper, BodiesDisabledBeforeTheStepStaySo) {
  OdeLibrary ode;
  OdeWorld w = MakeWorld();
  Chain with_ball(w.get(), 0.0);
  dBodyID parked = dBodyCreate(w.get());  // a robot taken off the field: disabled, in mid-air
  dMass m;
  dMassSetSphereTotal(&m, 1.0, 0.05);
  dBodySetMass(parked, &m);
  dBodySetPosition(parked, 5, 5, 1);
  dBodyDisable(parked);
  std::vector<dBodyID> bodies = with_ball.links;
  bodies.push_back(parked);
  IslandStepper stepper;
  stepper.SetIterations(20, 5);
  for (int i = 0; i < 50; ++i) stepper.Step(w.get(), bodies, {with_ball.links.back()}, kStep);
  EXPECT_FALSE(dBodyIsEnabled(parked));
  EXPECT_EQ(dBodyGetPosition(parked)[2], 1.0);
  for (dBodyID b : with_ball.links) EXPECT_TRUE(dBodyIsEnabled(b));
  EXPECT_LT(dBodyGetPosition(with_ball.links.back())[2], 1.0) << "the chain swung down";
}

}  // namespace
