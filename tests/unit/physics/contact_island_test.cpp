// SPDX-License-Identifier: Apache-2.0
// ContactIslandStepper: a body whose only joints are contacts with the static world, stepped by
// the kernel, ends every step bit for bit where QuickStep puts it, with every kind of contact the
// kernel makes (friction directions, surface motion, bounce, rolling friction, slip, softness);
// IsStaticContactIsland leaves every other island to QuickStep.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <ode/ode.h>

#include "physics/contact_island.hpp"
#include "physics/ode_handles.hpp"
#include "quickstep_twin.hpp"

namespace {

using namespace ubersim::kernel;  // NOLINT: the stepper, its log and ODE's handles
using ubersim::test::StateDifference;

constexpr double kStep = 0.005;

OdeWorld MakeWorld() {
  OdeWorld w = ubersim::test::MakeTiltedWorld(0.2);
  // Not ODE's defaults: the stepper must take the world's own.
  dWorldSetERP(w.get(), 0.35);
  dWorldSetCFM(w.get(), 3e-6);
  dWorldSetContactSurfaceLayer(w.get(), 0.0005);
  dWorldSetContactMaxCorrectingVel(w.get(), 0.6);
  dWorldSetQuickStepW(w.get(), 1.2);
  return w;
}

// One body in each world, with its geometry in that world's space.
struct Twin {
  dBodyID kernel;
  dBodyID ode;
  dGeomID kernel_geom;
  dGeomID ode_geom;
};

// A ball (sphere) or a robot-sized box, dropped or resting on the floor, sliding and spinning.
Twin MakeTwin(dWorldID kw, dSpaceID ks, dWorldID ow, dSpaceID os, std::mt19937_64& rng, int index) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const bool ball = index % 2 == 0;
  dMass mass;
  if (ball) {
    dMassSetSphereTotal(&mass, 0.046, 0.0215);
  } else {
    dMassSetBoxTotal(&mass, 2.5, 0.18, 0.17, 0.14);
    dMassTranslate(&mass, 0.01 * u(rng), 0.01 * u(rng), -0.02);  // off-centre: off-diagonal terms
    dMassTranslate(&mass, -mass.c[0], -mass.c[1], -mass.c[2]);
  }
  dQuaternion q = {1, 0.05 * u(rng), 0.05 * u(rng), u(rng)};
  dNormalize4(q);
  const double z = ball ? 0.0215 + 0.01 * (u(rng) + 1) : 0.07 + 0.004 * u(rng);
  const std::array<double, 3> p = {3 * u(rng), 2 * u(rng), z};
  const std::array<double, 3> v = {3 * u(rng), 3 * u(rng), u(rng)};
  const std::array<double, 3> w = {ball ? 100 * u(rng) : u(rng), ball ? 100 * u(rng) : u(rng), 10 * u(rng)};
  Twin t{dBodyCreate(kw), dBodyCreate(ow), nullptr, nullptr};
  t.kernel_geom = ball ? dCreateSphere(ks, 0.0215) : dCreateBox(ks, 0.18, 0.17, 0.14);
  t.ode_geom = ball ? dCreateSphere(os, 0.0215) : dCreateBox(os, 0.18, 0.17, 0.14);
  for (auto [b, g] : {std::pair{t.kernel, t.kernel_geom}, std::pair{t.ode, t.ode_geom}}) {
    dBodySetMass(b, &mass);
    dGeomSetBody(g, b);
    dBodySetPosition(b, p[0], p[1], p[2]);
    dBodySetQuaternion(b, q);
    dBodySetLinearVel(b, v[0], v[1], v[2]);
    dBodySetAngularVel(b, w[0], w[1], w[2]);
    if (index % 7 == 3) dBodySetGyroscopicMode(b, 0);
  }
  return t;
}

// The surface of the `index`-th body's contacts at `step`: each kind of contact the kernel makes.
dSurfaceParameters Surface(int index, int step, const dReal* axis, dReal* fdir1) {
  dSurfaceParameters s{};
  int mode = dContactApprox1;
  s.mu = 0.8;
  switch ((index + step / 50) % 9) {
    case 0:  // a wheel: directional friction, the rollers' surface moving
      mode |= dContactMu2 | dContactFDir1 | dContactMotion1 | dContactMotion2;
      s.mu2 = 0.1;
      s.motion1 = 0.7;
      s.motion2 = -0.2;
      dCopyVector3(fdir1, axis);
      break;
    case 1:  // a ball on the carpet: bounce, rolling friction
      mode |= dContactBounce | dContactRolling;
      s.bounce = 0.6;
      s.bounce_vel = 0.05;
      s.rho = s.rho2 = s.rhoN = 0.004;
      break;
    case 2:  // a skidding ball: friction against the slip only, rolling friction per axis
      mode |= dContactMu2 | dContactFDir1 | dContactRolling;
      s.mu2 = 0;
      s.rho = s.rho2 = s.rhoN = 0.004;
      dCopyVector3(fdir1, axis);
      break;
    case 3:  // soft, slipping
      mode |= dContactSoftERP | dContactSoftCFM | dContactSlip1 | dContactSlip2;
      s.soft_erp = 0.5;
      s.soft_cfm = 1e-4;
      s.slip1 = s.slip2 = 0.01;
      break;
    case 4:  // speculative: closing no faster than the gap allows
      mode |= dContactMotionN;
      s.motionN = -0.3;
      break;
    case 5:  // frictionless
      s.mu = 0;
      break;
    case 6:  // ODE's own friction directions, mu2 its own
      mode |= dContactMu2;
      s.mu2 = 0.3;
      break;
    case 7:  // a bounce with the surface moving along its friction direction
      mode |= dContactBounce | dContactFDir1 | dContactMotion1;
      s.bounce = 0.3;
      s.bounce_vel = 0.0;
      s.motion1 = 0.4;
      dCopyVector3(fdir1, axis);
      break;
    default:  // plain Coulomb friction
      break;
  }
  s.mode = mode;
  return s;
}

// Touches each body to the floor in both worlds, with the same contacts (found in the kernel's
// world: the bodies are where the other world's are); the kernel's are logged.
void MakeContacts(const std::vector<Twin>& twins, int step, dGeomID kernel_floor,
                  dWorldID kw, dJointGroupID kg, dWorldID ow, dJointGroupID og, StaticContactLog& log) {
  for (std::size_t i = 0; i < twins.size(); ++i) {
    const Twin& t = twins[i];
    // Half the bodies meet the floor as the contact's second geometry: ODE turns the normal round.
    const bool reversed = (i / 2 + static_cast<std::size_t>(step) / 30) % 2 == 1;
    std::array<dContactGeom, 8> hits{};
    const int n = reversed ? dCollide(kernel_floor, t.kernel_geom, 8, hits.data(), sizeof(dContactGeom))
                           : dCollide(t.kernel_geom, kernel_floor, 8, hits.data(), sizeof(dContactGeom));
    const dReal* r = dBodyGetRotation(t.kernel);
    const dReal axis[4] = {r[0], r[4], 0, 0};  // the body's x axis, level
    dReal length = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1]);
    for (int h = 0; h < n; ++h) {
      dContact c{};
      c.geom = hits[static_cast<std::size_t>(h)];
      dReal dir[4] = {axis[0] / length, axis[1] / length, 0, 0};
      c.surface = Surface(static_cast<int>(i), step, dir, c.fdir1);
      dJointID kj = dJointCreateContact(kw, kg, &c);
      dJointID oj = dJointCreateContact(ow, og, &c);
      if (reversed) {
        dJointAttach(kj, nullptr, t.kernel);
        dJointAttach(oj, nullptr, t.ode);
      } else {
        dJointAttach(kj, t.kernel, nullptr);
        dJointAttach(oj, t.ode, nullptr);
      }
      log.Record(kj, c, reversed);
    }
  }
}

TEST(ContactIslandStepper, EndsEveryStepBitForBitWhereQuickStepPutsTheBody) {
  OdeLibrary ode;
  OdeWorld kernel_world = MakeWorld(), ode_world = MakeWorld();
  OdeSpace kernel_space(dSimpleSpaceCreate(nullptr)), ode_space(dSimpleSpaceCreate(nullptr));
  dGeomID kernel_floor = dCreatePlane(kernel_space.get(), 0, 0, 1, 0);
  dCreatePlane(ode_space.get(), 0, 0, 1, 0);
  OdeJointGroup kernel_contacts(dJointGroupCreate(0)), ode_contacts(dJointGroupCreate(0));
  std::mt19937_64 rng(20261202);
  std::vector<Twin> twins;
  for (int i = 0; i < 24; ++i) {
    twins.push_back(MakeTwin(kernel_world.get(), kernel_space.get(), ode_world.get(), ode_space.get(), rng, i));
  }
  const ContactSolverSettings settings = ContactSolverSettings::Of(kernel_world.get());
  EXPECT_EQ(settings.sor_w, 1.2);
  dVector3 gravity;
  dWorldGetGravity(kernel_world.get(), gravity);
  StaticContactLog log;
  ContactIslandStepper stepper;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int islands = 0;
  for (int step = 0; step < 450; ++step) {
    // Four sweeps as a robot's island, ten as the ball's at the fast profile (QuickStep shuffles
    // its rows before the ninth), twenty as at the precise one.
    const int iterations = std::array{4, 10, 20}[static_cast<std::size_t>(step / 10) % 3];
    for (const Twin& t : twins) {
      if (step % 4 == 0) continue;  // no push on some steps: the zero path too
      const std::array<double, 6> push = {5 * u(rng), 5 * u(rng), 2 * u(rng), 0.1 * u(rng), 0.1 * u(rng), 0.2 * u(rng)};
      for (dBodyID b : {t.kernel, t.ode}) {
        dBodyAddForce(b, push[0], push[1], push[2]);
        dBodyAddTorque(b, push[3], push[4], push[5]);
      }
    }
    MakeContacts(twins, step, kernel_floor, kernel_world.get(), kernel_contacts.get(), ode_world.get(),
                 ode_contacts.get(), log);
    // ODE's island order: its body list, newest first. Bodies off the floor are QuickStep's lone
    // islands: the kernel steps them through QuickStep too, in a world of their own here.
    const unsigned long seed = 1000 + static_cast<unsigned long>(step);
    dRandSetSeed(seed);
    std::vector<dBodyID> airborne;
    for (auto it = twins.rbegin(); it != twins.rend(); ++it) {
      if (IsStaticContactIsland(it->kernel, log)) {
        stepper.Step(it->kernel, log, gravity, settings, iterations, kStep);
        ++islands;
      } else {
        ASSERT_EQ(dBodyGetJoint(it->kernel, 0), nullptr) << "only contacts with the floor here";
        airborne.push_back(it->kernel);
      }
    }
    const unsigned long kernel_seed = dRandGetSeed();
    // The airborne ones: QuickStep alone, every stepped body disabled for it.
    for (const Twin& t : twins) {
      if (std::find(airborne.begin(), airborne.end(), t.kernel) == airborne.end()) dBodyDisable(t.kernel);
    }
    dWorldSetQuickStepNumIterations(kernel_world.get(), iterations);
    dWorldQuickStep(kernel_world.get(), kStep);  // draws nothing: no constraints
    for (const Twin& t : twins) dBodyEnable(t.kernel);

    dRandSetSeed(seed);
    dWorldSetQuickStepNumIterations(ode_world.get(), iterations);
    dWorldQuickStep(ode_world.get(), kStep);
    ASSERT_EQ(kernel_seed, dRandGetSeed()) << "the same draws from ODE's generator, step " << step;
    dJointGroupEmpty(kernel_contacts.get());
    dJointGroupEmpty(ode_contacts.get());
    log.Clear();
    for (std::size_t i = 0; i < twins.size(); ++i) {
      ASSERT_EQ(StateDifference(twins[i].kernel, twins[i].ode), "") << "body " << i << ", step " << step;
    }
  }
  // The comparison compared what it is for: most bodies were on the floor most steps, and the
  // boxes still stand on it (the contacts held them up).
  EXPECT_GT(islands, 450 * 24 / 2);
  for (std::size_t i = 1; i < twins.size(); i += 2) {
    EXPECT_NEAR(dBodyGetPosition(twins[i].kernel)[2], 0.07, 0.01) << "box " << i;
  }
}

TEST(IsStaticContactIsland, LeavesToQuickStepWhatTheStepperDoesNotReproduce) {
  OdeLibrary ode;
  OdeWorld world = MakeWorld();
  OdeJointGroup contacts(dJointGroupCreate(0));
  StaticContactLog log;
  auto body = [&] { return ubersim::test::MakeBall(world.get()); };
  auto touch_floor = [&](dBodyID b, bool logged) {
    dContact c{};
    c.geom.normal[2] = 1;
    c.surface.mode = dContactApprox1;
    c.surface.mu = 1;
    dJointID j = dJointCreateContact(world.get(), contacts.get(), &c);
    dJointAttach(j, b, nullptr);
    if (logged) log.Record(j, c, false);
    return j;
  };
  dBodyID on_floor = body();
  touch_floor(on_floor, true);
  touch_floor(on_floor, true);
  EXPECT_TRUE(IsStaticContactIsland(on_floor, log));
  EXPECT_FALSE(IsStaticContactIsland(body(), log)) << "no contact: a lone body's";

  dBodyID unlogged = body();
  touch_floor(unlogged, true);
  touch_floor(unlogged, false);
  EXPECT_FALSE(IsStaticContactIsland(unlogged, log)) << "a contact the log did not keep";

  dBodyID pushed = body();
  touch_floor(pushed, true);
  dBodyID other = body();
  dContact c{};
  c.surface.mode = dContactApprox1;
  dJointAttach(dJointCreateContact(world.get(), contacts.get(), &c), pushed, other);
  EXPECT_FALSE(IsStaticContactIsland(pushed, log)) << "a contact with another body";

  dBodyID hinged = body();
  touch_floor(hinged, true);
  dJointAttach(dJointCreateHinge(world.get(), nullptr), hinged, nullptr);
  EXPECT_FALSE(IsStaticContactIsland(hinged, log)) << "a joint other than a contact";

  dBodyID off = body();
  dJointDisable(touch_floor(off, true));
  EXPECT_FALSE(IsStaticContactIsland(off, log)) << "a disabled contact";

  dBodyID damped = body();
  touch_floor(damped, true);
  dBodySetLinearDamping(damped, 0.1);
  EXPECT_FALSE(IsStaticContactIsland(damped, log)) << "damping: left to ODE";

  dBodyID asleep = body();
  touch_floor(asleep, true);
  dBodyDisable(asleep);
  EXPECT_FALSE(IsStaticContactIsland(asleep, log)) << "disabled";
}

}  // namespace
