// SPDX-License-Identifier: Apache-2.0
// IslandStepper: the ball's islands get their iterations, the others theirs, each exactly as if
// stepped alone; bodies disabled before a step stay so; lone bodies as QuickStep steps them; a
// robot's island searched from its chassis (limbs held back), so its wheels stay on the carpet.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <ode/ode.h>

#include "physics/island_stepper.hpp"
#include "physics/ode_handles.hpp"

namespace {

using ubersim::kernel::IslandStepper;
using ubersim::kernel::IterationDemand;
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

TEST(IslandStepper, AnIslandAskingForMoreIterationsGetsThemInAPassOfItsOwn) {
  OdeLibrary ode;
  // Three chains: one with the ball (10), one asking for 6 through its middle link, one plain (2).
  OdeWorld all = MakeWorld();
  Chain with_ball(all.get(), 0.0), asking(all.get(), 1.0), plain(all.get(), 2.0);
  std::vector<dBodyID> bodies = with_ball.links;
  for (const Chain* c : {&asking, &plain}) bodies.insert(bodies.end(), c->links.begin(), c->links.end());
  const std::vector<dBodyID> balls{with_ball.links.back()};
  const std::vector<IterationDemand> demands{{asking.links[2], 6}, {plain.links[0], 1}};  // 1: below 2, no effect
  IslandStepper stepper;
  stepper.SetIterations(10, 2);

  // The references: each chain alone with the count its island should get, passes highest first.
  OdeWorld alone_10 = MakeWorld(), alone_6 = MakeWorld(), alone_2 = MakeWorld();
  dWorldSetQuickStepNumIterations(alone_10.get(), 10);
  dWorldSetQuickStepNumIterations(alone_6.get(), 6);
  dWorldSetQuickStepNumIterations(alone_2.get(), 2);
  Chain ref_ball(alone_10.get(), 0.0), ref_asking(alone_6.get(), 1.0), ref_plain(alone_2.get(), 2.0);

  unsigned long seed = 777;
  for (int i = 0; i < 200; ++i) {
    dRandSetSeed(seed);
    stepper.Step(all.get(), bodies, balls, kStep, {}, demands);
    const unsigned long after = dRandGetSeed();
    dRandSetSeed(seed);
    dWorldQuickStep(alone_10.get(), kStep);
    dWorldQuickStep(alone_6.get(), kStep);
    dWorldQuickStep(alone_2.get(), kStep);
    seed = dRandGetSeed();
    ASSERT_EQ(after, seed) << "the passes drew differently from the generator, step " << i;
  }
  ExpectSameState(with_ball.links, ref_ball.links);
  ExpectSameState(asking.links, ref_asking.links);
  ExpectSameState(plain.links, ref_plain.links);
  EXPECT_GT(plain.Stretch(2.0), 2 * asking.Stretch(1.0)) << "the check can fail: 6 iterations hold better than 2";

  // A demand above the ball's count wins when the two share an island.
  OdeWorld shared = MakeWorld(), ref = MakeWorld();
  Chain chain(shared.get(), 0.0);
  dWorldSetQuickStepNumIterations(ref.get(), 30);
  Chain ref_chain(ref.get(), 0.0);
  for (int i = 0; i < 50; ++i) {
    dRandSetSeed(1);
    stepper.Step(shared.get(), chain.links, {chain.links.back()}, kStep, {}, {{chain.links[0], 30}});
    dRandSetSeed(1);
    dWorldQuickStep(ref.get(), kStep);
  }
  ExpectSameState(chain.links, ref_chain.links);
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
  // With limbs (bodies 2, 6 and 7 hang from older ones), QuickStep's search starts from the
  // others; the reference holds the same limbs back from one plain QuickStep.
  for (bool with_limbs : {false, true}) {
    Scene stepped, reference;
    const std::vector<char> limbs = with_limbs ? ubersim::kernel::FindLimbs(stepped.bodies) : std::vector<char>{};
    IslandStepper stepper;
    stepper.SetIterations(5, 5);
    dWorldSetQuickStepNumIterations(reference.world.get(), 5);
    for (int i = 0; i < 3; ++i) {
      stepper.Step(stepped.world.get(), stepped.bodies, {}, kStep, limbs);
      for (std::size_t k = 0; k < limbs.size(); ++k) {
        if (limbs[k]) dBodyDisable(reference.bodies[k]);
      }
      dWorldQuickStep(reference.world.get(), kStep);
      EXPECT_EQ(GeomOrder(stepped.space.get()), GeomOrder(reference.space.get())) << "step " << i << " limbs " << with_limbs;
      dSpaceClean(stepped.space.get());
      dSpaceClean(reference.space.get());
    }
    ExpectSameState(stepped.bodies, reference.bodies);
    for (dBodyID b : reference.bodies) EXPECT_TRUE(dBodyIsEnabled(b)) << "QuickStep enabled the limbs it reached";
  }
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

namespace {

// A four-wheel omni robot as the omni drive builds it: a 2.3 kg chassis made first, then four
// 50 g wheels on motorised axles, each touching the carpet (a plane) at one point that grips
// across its axle only.
struct OmniRobot {
  static constexpr double kWheelRadius = 0.029;
  dWorldID world;
  OdeSpace space{dSimpleSpaceCreate(nullptr)};
  dGeomID carpet = dCreatePlane(space.get(), 0, 0, 1, 0);
  dJointGroupID contacts = dJointGroupCreate(0);
  dBodyID chassis;
  std::vector<dBodyID> wheels;
  std::vector<dGeomID> tyres;
  std::vector<dJointID> axles;
  std::vector<dBodyID> bodies;  // newest first

  explicit OmniRobot(dWorldID w) : world(w) {
    chassis = dBodyCreate(w);
    dMass m;
    dMassSetCylinderTotal(&m, 2.3, 3, 0.09, 0.13);
    dBodySetMass(chassis, &m);
    dBodySetPosition(chassis, 0, 0, 0.05);
    for (double angle_deg : {60.0, 135.0, 225.0, 300.0}) {
      const double a = angle_deg * M_PI / 180.0;
      const double c = std::cos(a), s = std::sin(a);
      dBodyID wheel = dBodyCreate(w);
      dMassSetCylinderTotal(&m, 0.05, 3, kWheelRadius, 0.01);
      dBodySetMass(wheel, &m);
      dBodySetPosition(wheel, 0.079 * c, 0.079 * s, kWheelRadius);
      dGeomID tyre = dCreateSphere(space.get(), kWheelRadius);
      dGeomSetBody(tyre, wheel);
      dJointID axle = dJointCreateHinge(w, nullptr);
      dJointAttach(axle, chassis, wheel);
      dJointSetHingeAnchor(axle, 0.079 * c, 0.079 * s, kWheelRadius);
      dJointSetHingeAxis(axle, c, s, 0);  // radial: the wheel rolls around the robot
      wheels.push_back(wheel);
      tyres.push_back(tyre);
      axles.push_back(axle);
    }
    bodies.assign(wheels.rbegin(), wheels.rend());
    bodies.push_back(chassis);
  }
  ~OmniRobot() { dJointGroupDestroy(contacts); }

  // Each wheel's contact with the carpet (one point), made newest wheel last, as a broadphase
  // that met them in creation order would.
  void Collide() {
    dJointGroupEmpty(contacts);
    for (std::size_t i = 0; i < tyres.size(); ++i) {
      dContact c{};
      if (dCollide(tyres[i], carpet, 1, &c.geom, sizeof(dContact)) == 0) continue;
      const dReal* axis = dBodyGetPosition(wheels[i]);
      const dReal* centre = dBodyGetPosition(chassis);
      // Grips along its rolling direction (across the axle, in the carpet's plane) only.
      double fx = -(axis[1] - centre[1]), fy = axis[0] - centre[0];
      const double n = std::hypot(fx, fy);
      c.fdir1[0] = fx / n;
      c.fdir1[1] = fy / n;
      c.surface.mode = dContactMu2 | dContactFDir1 | dContactApprox1;
      c.surface.mu = 1.0;
      c.surface.mu2 = 0.0;
      dJointAttach(dJointCreateContact(world, contacts, &c), wheels[i], nullptr);
    }
  }

  // Deepest any wheel is into the carpet, m.
  double DeepestWheel() const {
    double deepest = 0;
    for (dBodyID w : wheels) deepest = std::max(deepest, kWheelRadius - dBodyGetPosition(w)[2]);
    return deepest;
  }
};

// Drives the robot for 10 s at two solver iterations (the fast settings' robots away from the
// ball), its wheel speeds changing every 0.2 s; returns the deepest wheel's depth after the first
// second.
double DeepestWheelWhileDriving(bool with_limbs) {
  OdeWorld w = MakeWorld();
  dWorldSetERP(w.get(), 0.2);
  dWorldSetCFM(w.get(), 1e-7);
  dWorldSetContactSurfaceLayer(w.get(), 0.0005);
  dWorldSetContactMaxCorrectingVel(w.get(), 3.0);
  OmniRobot robot(w.get());
  IslandStepper stepper;
  stepper.SetIterations(2, 2);
  const std::vector<char> limbs = with_limbs ? ubersim::kernel::FindLimbs(robot.bodies) : std::vector<char>{};
  unsigned long speeds = 7;
  double deepest = 0;
  for (int step = 0; step < 2000; ++step) {
    if (step % 40 == 0) {
      for (dJointID axle : robot.axles) {
        speeds = speeds * 6364136223846793005UL + 1442695040888963407UL;
        dJointSetHingeParam(axle, dParamVel, static_cast<double>(speeds >> 40) / (1UL << 24) * 120.0 - 60.0);
        dJointSetHingeParam(axle, dParamFMax, 0.3);
      }
    }
    robot.Collide();
    stepper.Step(w.get(), robot.bodies, {}, kStep, limbs);
    if (step >= 200) deepest = std::max(deepest, robot.DeepestWheel());
  }
  return deepest;
}

TEST(IslandStepper, ARobotsWheelsStayOnTheCarpetAtTwoIterations) {
  OdeLibrary ode;
  // With the chassis as its island's root, the axles are solved before the carpet contacts;
  // started from the newest wheel, that wheel's contact came first and it sank (11.5 mm
  // measured, against 1.9 mm).
  EXPECT_LT(DeepestWheelWhileDriving(true), 0.003);
  EXPECT_GT(DeepestWheelWhileDriving(false), 0.008) << "the row order no longer matters: this test shows nothing";
}

TEST(IslandStepper, FindLimbsFlagsTheBodiesHangingFromOlderOnes) {
  OdeLibrary ode;
  OdeWorld w = MakeWorld();
  OmniRobot robot(w.get());
  dBodyID ball = FreeBody(w.get(), 1.0, 0.0);
  // A contact from the chassis to the ball, made after both: contacts make no limb.
  dJointGroupID group = dJointGroupCreate(0);
  dContact c{};
  dJointAttach(dJointCreateContact(w.get(), group, &c), robot.chassis, ball);
  std::vector<dBodyID> bodies{ball};
  bodies.insert(bodies.end(), robot.bodies.begin(), robot.bodies.end());
  EXPECT_EQ(ubersim::kernel::FindLimbs(bodies), (std::vector<char>{0, 1, 1, 1, 1, 0}));
  dJointGroupDestroy(group);
}

TEST(IslandStepper, HeldLimbsAreSteppedWithTheirRootAndLeftEnabled) {
  OdeLibrary ode;
  // Limbs or not, every body moves; one limb cut loose after FindLimbs (its joint destroyed)
  // is enabled again after the step, not left behind for good.
  OdeWorld w = MakeWorld();
  Chain chain(w.get(), 0.0);
  std::vector<dBodyID> bodies(chain.links.rbegin(), chain.links.rend());
  const std::vector<char> limbs = ubersim::kernel::FindLimbs(bodies);
  EXPECT_EQ(limbs, (std::vector<char>{1, 1, 1, 1, 1, 0}));
  dJointDestroy(dBodyGetJoint(chain.links.back(), 0));  // the last link's joint to the one before
  IslandStepper stepper;
  stepper.SetIterations(5, 5);
  stepper.Step(w.get(), bodies, {}, kStep, limbs);
  for (dBodyID b : bodies) EXPECT_TRUE(dBodyIsEnabled(b));
  for (std::size_t i = 0; i + 1 < chain.links.size(); ++i) {
    EXPECT_LT(dBodyGetLinearVel(chain.links[i])[2], 0.0) << "link " << i << " moved";
  }
}

}  // namespace
