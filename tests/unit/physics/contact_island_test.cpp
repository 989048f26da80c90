// SPDX-License-Identifier: Apache-2.0
// ContactIslandStepper: a body whose only joints are contacts with the static world, stepped by
// the kernel, ends every step bit for bit where QuickStep puts it, with every kind of contact the
// kernel makes (friction directions, surface motion, bounce, rolling friction, slip, softness);
// IsStaticContactIsland and IslandStepper leave every other island to QuickStep (bodies touching
// each other, a hinge, damping) and the generator's draws as QuickStep's.
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
#include "physics/island_stepper.hpp"
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

// Where a twin starts: at random on the floor, or at `at` with small velocities (a stack, a ball
// against a box).
struct Placement {
  bool ball = false;
  bool fixed = false;            // placed at `at`, barely moving
  std::array<double, 3> at{};
};

// A ball (sphere) or a robot-sized box, dropped or resting on the floor, sliding and spinning.
Twin MakeTwin(dWorldID kw, dSpaceID ks, dWorldID ow, dSpaceID os, std::mt19937_64& rng, int index,
              const Placement& where) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const bool ball = where.ball;
  dMass mass;
  if (ball) {
    dMassSetSphereTotal(&mass, 0.046, 0.0215);
  } else {
    dMassSetBoxTotal(&mass, 2.5, 0.18, 0.17, 0.14);
    const double dx = 0.01 * u(rng);
    const double dy = 0.01 * u(rng);
    dMassTranslate(&mass, dx, dy, -0.02);  // off-centre: off-diagonal terms
    dMassTranslate(&mass, -mass.c[0], -mass.c[1], -mass.c[2]);
  }
  dQuaternion q = {1, 0.05 * u(rng), 0.05 * u(rng), where.fixed ? 0.05 * u(rng) : u(rng)};
  dNormalize4(q);
  const double z = ball ? 0.0215 + 0.01 * (u(rng) + 1) : 0.07 + 0.004 * u(rng);
  std::array<double, 3> p = {3 * u(rng), 2 * u(rng), z};
  std::array<double, 3> v = {3 * u(rng), 3 * u(rng), u(rng)};
  std::array<double, 3> w = {ball ? 100 * u(rng) : u(rng), ball ? 100 * u(rng) : u(rng), 10 * u(rng)};
  if (where.fixed) {
    p = where.at;
    v = {0.1 * u(rng), 0.1 * u(rng), 0};
    w = {0, 0, 0.2 * u(rng)};
  }
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

// Makes the contacts of two geometries in both worlds (found in the kernel's world: the bodies
// are where the other world's are), the kernel's through its log: a null body is the static world.
struct Contacts {
  dWorldID ode_world;
  dJointGroupID ode_group;
  StaticContactLog& log;  // makes the kernel's
  void Make(dGeomID a, dGeomID b, dBodyID ka, dBodyID kb, dBodyID oa, dBodyID ob, const dReal* axis, int kind,
            int step) {
    std::array<dContactGeom, 8> hits{};
    const int n = dCollide(a, b, 8, hits.data(), sizeof(dContactGeom));
    for (int h = 0; h < n; ++h) {
      dContact c{};
      c.geom = hits[static_cast<std::size_t>(h)];
      c.surface = Surface(kind, step, axis, c.fdir1);
      log.Make(c, ka, kb);
      dJointAttach(dJointCreateContact(ode_world, ode_group, &c), oa, ob);
    }
  }
};

// The body's x axis, level and of unit length: a wheel's friction direction.
std::array<dReal, 4> LevelAxis(dBodyID body) {
  const dReal* r = dBodyGetRotation(body);
  const dReal length = std::sqrt(r[0] * r[0] + r[4] * r[4]);
  return {r[0] / length, r[4] / length, 0, 0};
}

// Touches each body to the floor, and the listed pairs to each other.
void MakeContacts(const std::vector<Twin>& twins, const std::vector<std::pair<int, int>>& pairs, int step,
                  dGeomID kernel_floor, Contacts& contacts) {
  for (std::size_t i = 0; i < twins.size(); ++i) {
    const Twin& t = twins[i];
    const auto axis = LevelAxis(t.kernel);
    // Half the bodies meet the floor as the contact's second geometry: ODE turns the normal round.
    const bool reversed = (i / 2 + static_cast<std::size_t>(step) / 30) % 2 == 1;
    if (reversed) {
      contacts.Make(kernel_floor, t.kernel_geom, nullptr, t.kernel, nullptr, t.ode, axis.data(), static_cast<int>(i),
                    step);
    } else {
      contacts.Make(t.kernel_geom, kernel_floor, t.kernel, nullptr, t.ode, nullptr, axis.data(), static_cast<int>(i),
                    step);
    }
  }
  for (const auto& [i, j] : pairs) {
    const Twin& a = twins[static_cast<std::size_t>(i)];
    const Twin& b = twins[static_cast<std::size_t>(j)];
    const auto axis = LevelAxis(a.kernel);
    contacts.Make(a.kernel_geom, b.kernel_geom, a.kernel, b.kernel, a.ode, b.ode, axis.data(), i + j, step);
  }
}

// Two worlds with a floor: the kernel's, stepped by the kernel's steppers, and its twin,
// stepped by QuickStep; the bodies made in both, the contacts made in both.
class TwinWorlds : public ::testing::Test {
 protected:
  TwinWorlds() {
    kernel_floor_ = dCreatePlane(kernel_space_.get(), 0, 0, 1, 0);
    dCreatePlane(ode_space_.get(), 0, 0, 1, 0);
    log_.Bind(kernel_world_.get(), kernel_contacts_.get());
    log_.KeepStaticContacts(true);
  }
  int Add(const Placement& where) {
    const int index = static_cast<int>(twins_.size());
    twins_.push_back(
        MakeTwin(kernel_world_.get(), kernel_space_.get(), ode_world_.get(), ode_space_.get(), rng_, index, where));
    return index;
  }
  // The pushes a drive adds before a step, on the first `count` bodies (none on some steps: the
  // zero path too).
  void Push(std::size_t count, int step) {
    if (step % 4 == 0) return;
    for (std::size_t i = 0; i < count; ++i) {
      const std::array<double, 6> push = {5 * u_(rng_), 5 * u_(rng_), 2 * u_(rng_), 0.1 * u_(rng_), 0.1 * u_(rng_), 0.2 * u_(rng_)};
      for (dBodyID b : {twins_[i].kernel, twins_[i].ode}) {
        dBodyAddForce(b, push[0], push[1], push[2]);
        dBodyAddTorque(b, push[3], push[4], push[5]);
      }
    }
  }
  // QuickStep steps the twin from the generator's `seed`, which must end where the kernel's step
  // left it (`kernel_seed`); then the contacts go and every body is compared.
  void StepTwinAndCompare(unsigned long seed, unsigned long kernel_seed, int iterations, int step) {
    dRandSetSeed(seed);
    dWorldSetQuickStepNumIterations(ode_world_.get(), iterations);
    dWorldQuickStep(ode_world_.get(), kStep);
    ASSERT_EQ(kernel_seed, dRandGetSeed()) << "the same draws from ODE's generator, step " << step;
    dJointGroupEmpty(kernel_contacts_.get());
    dJointGroupEmpty(ode_contacts_.get());
    log_.Clear();
    for (std::size_t i = 0; i < twins_.size(); ++i) {
      ASSERT_EQ(StateDifference(twins_[i].kernel, twins_[i].ode), "") << "body " << i << ", step " << step;
    }
  }
  // Four sweeps as a robot's island, ten as the ball's at the fast profile (QuickStep shuffles
  // its rows before the ninth), twenty as at the precise one.
  static int Iterations(int step) { return std::array{4, 10, 20}[static_cast<std::size_t>(step / 10) % 3]; }

  OdeLibrary ode_;
  OdeWorld kernel_world_ = MakeWorld(), ode_world_ = MakeWorld();
  OdeSpace kernel_space_{dSimpleSpaceCreate(nullptr)}, ode_space_{dSimpleSpaceCreate(nullptr)};
  OdeJointGroup kernel_contacts_{dJointGroupCreate(0)}, ode_contacts_{dJointGroupCreate(0)};
  dGeomID kernel_floor_ = nullptr;
  StaticContactLog log_;
  Contacts contacts_{ode_world_.get(), ode_contacts_.get(), log_};
  std::mt19937_64 rng_{20261202};
  std::uniform_real_distribution<double> u_{-1.0, 1.0};
  std::vector<Twin> twins_;
};

TEST_F(TwinWorlds, EveryBodyOnTheFloorEndsEveryStepBitForBitWhereQuickStepPutsIt) {
  for (int i = 0; i < 24; ++i) Add(Placement{i % 2 == 0});
  const ContactSolverSettings settings = ContactSolverSettings::Of(kernel_world_.get());
  EXPECT_EQ(settings.sor_w, 1.2);
  dVector3 gravity;
  dWorldGetGravity(kernel_world_.get(), gravity);
  ContactIslandStepper stepper;
  int islands = 0;
  for (int step = 0; step < 450; ++step) {
    const int iterations = Iterations(step);
    Push(twins_.size(), step);
    MakeContacts(twins_, {}, step, kernel_floor_, contacts_);
    // ODE's island order: its body list, newest first. Bodies off the floor are QuickStep's lone
    // islands: the kernel steps them through QuickStep too, in a world of their own here.
    const unsigned long seed = 1000 + static_cast<unsigned long>(step);
    dRandSetSeed(seed);
    std::vector<dBodyID> airborne;
    for (auto it = twins_.rbegin(); it != twins_.rend(); ++it) {
      if (IsStaticContactIsland(it->kernel, log_)) {
        stepper.Step(it->kernel, log_, gravity, settings, iterations, kStep);
        ++islands;
      } else {
        ASSERT_EQ(dBodyGetJoint(it->kernel, 0), nullptr) << "only contacts with the floor here";
        airborne.push_back(it->kernel);
      }
    }
    const unsigned long kernel_seed = dRandGetSeed();
    // The airborne ones: QuickStep alone, every stepped body disabled for it.
    for (const Twin& t : twins_) {
      if (std::find(airborne.begin(), airborne.end(), t.kernel) == airborne.end()) dBodyDisable(t.kernel);
    }
    dWorldSetQuickStepNumIterations(kernel_world_.get(), iterations);
    dWorldQuickStep(kernel_world_.get(), kStep);  // draws nothing: no constraints
    for (const Twin& t : twins_) dBodyEnable(t.kernel);

    StepTwinAndCompare(seed, kernel_seed, iterations, step);
    if (HasFatalFailure()) return;
  }
  // The comparison compared what it is for: most bodies were on the floor most steps, and the
  // boxes still stand on it (the contacts held them up).
  EXPECT_GT(islands, 450 * 24 / 2);
  for (std::size_t i = 1; i < twins_.size(); i += 2) {
    EXPECT_NEAR(dBodyGetPosition(twins_[i].kernel)[2], 0.07, 0.01) << "box " << i;
  }
}

// Through IslandStepper, beside islands QuickStep keeps: boxes stacked and a ball against a box
// (contacts between bodies), a box on a hinge, a damped ball.
TEST_F(TwinWorlds, BesideQuickStepsIslandsEveryBodyEndsEveryStepWhereQuickStepPutsIt) {
  for (int i = 0; i < 16; ++i) Add(Placement{i % 2 == 0});  // alone on the floor
  std::vector<std::pair<int, int>> pairs;
  for (int k = 0; k < 3; ++k) {
    // A box on a box (their contacts link two bodies), and a ball against a box's side.
    const double x = -2.5 + 2.0 * k, y = 2.5;
    const int bottom = Add(Placement{false, true, {x, y, 0.0695}});
    const int top = Add(Placement{false, true, {x + 0.03, y, 0.2085}});
    pairs.emplace_back(top, bottom);
    const int box = Add(Placement{false, true, {x, -2.5, 0.0695}});
    const int ball = Add(Placement{true, true, {x + 0.111, -2.5, 0.0213}});
    pairs.emplace_back(ball, box);
  }
  // A box hinged to the world and a damped ball: islands the kernel leaves to QuickStep.
  const Twin& hinged = twins_[static_cast<std::size_t>(Add(Placement{false, true, {2.5, 0, 0.0695}}))];
  for (auto [w, b] : {std::pair{kernel_world_.get(), hinged.kernel}, std::pair{ode_world_.get(), hinged.ode}}) {
    dJointID h = dJointCreateHinge(w, nullptr);
    dJointAttach(h, b, nullptr);
    dJointSetHingeAnchor(h, 2.5, 0, 0.0695);
    dJointSetHingeAxis(h, 0, 0, 1);
  }
  const Twin& damped = twins_[static_cast<std::size_t>(Add(Placement{true, true, {2.5, 1, 0.0213}}))];
  dBodySetLinearDamping(damped.kernel, 0.05);
  dBodySetLinearDamping(damped.ode, 0.05);

  // ODE's body list: newest first.
  std::vector<dBodyID> bodies;
  for (auto it = twins_.rbegin(); it != twins_.rend(); ++it) bodies.push_back(it->kernel);
  IslandStepper islands;
  islands.SetStaticContacts(&log_);
  islands.SetMoveOrderMatters(false);
  int linked = 0;  // contacts between two bodies made
  for (int step = 0; step < 450; ++step) {
    const int iterations = Iterations(step);
    Push(16, step);  // the bodies alone; the others stay where they touch
    MakeContacts(twins_, pairs, step, kernel_floor_, contacts_);
    for (const auto& [i, j] : pairs) {
      if (dAreConnected(twins_[static_cast<std::size_t>(i)].kernel, twins_[static_cast<std::size_t>(j)].kernel)) {
        ++linked;
      }
    }
    const unsigned long seed = 1000 + static_cast<unsigned long>(step);
    dRandSetSeed(seed);
    islands.SetIterations(iterations, iterations);
    islands.Step(kernel_world_.get(), bodies, {}, kStep);
    const unsigned long kernel_seed = dRandGetSeed();
    StepTwinAndCompare(seed, kernel_seed, iterations, step);
    if (HasFatalFailure()) return;
  }
  // The comparison compared what it is for: bodies touched each other in many steps, and the
  // boxes alone still stand on the floor (the contacts held them up).
  EXPECT_GT(linked, 600);  // of 2700 pair-steps: stacks topple, balls roll off
  // Those pairs were islands of two free bodies linked by contacts: the kernel stepped them.
  EXPECT_GT(islands.LinkedIslandsStepped(), 600u);
  for (std::size_t i = 1; i < 16; i += 2) {
    EXPECT_NEAR(dBodyGetPosition(twins_[i].kernel)[2], 0.07, 0.01) << "box " << i;
  }
}

TEST(IsStaticContactIsland, LeavesToQuickStepWhatTheStepperDoesNotReproduce) {
  OdeLibrary ode;
  OdeWorld world = MakeWorld();
  OdeJointGroup contacts(dJointGroupCreate(0));
  StaticContactLog log;
  log.Bind(world.get(), contacts.get());
  log.KeepStaticContacts(true);
  auto body = [&] { return ubersim::test::MakeBall(world.get()); };
  dContact c{};
  c.geom.normal[2] = 1;
  c.surface.mode = dContactApprox1;
  c.surface.mu = 1;
  auto touch_floor = [&](dBodyID b) { log.Make(c, b, nullptr); };

  dBodyID on_floor = body();
  touch_floor(on_floor);
  touch_floor(on_floor);
  EXPECT_TRUE(IsStaticContactIsland(on_floor, log));
  EXPECT_EQ(dBodyGetJoint(on_floor, 0), nullptr) << "its contacts are not ODE joints";
  EXPECT_FALSE(IsStaticContactIsland(body(), log)) << "no contact: a lone body's";

  dBodyID pushed = body();
  touch_floor(pushed);
  dBodyID other = body();
  log.Make(c, pushed, other);
  EXPECT_FALSE(IsStaticContactIsland(pushed, log)) << "a contact with another body";
  EXPECT_EQ(dBodyGetNumJoints(pushed), 2) << "its contact with the floor made a joint first";
  EXPECT_EQ(dJointGetBody(dBodyGetJoint(pushed, 1), 1), nullptr) << "the floor's, the older";
  touch_floor(pushed);
  EXPECT_EQ(dBodyGetNumJoints(pushed), 3) << "and the ones after it at once";

  dBodyID joined = body();
  touch_floor(joined);
  log.Join(joined);
  EXPECT_FALSE(IsStaticContactIsland(joined, log)) << "made joints for QuickStep";
  EXPECT_EQ(dBodyGetNumJoints(joined), 1);

  dBodyID hinged = body();
  touch_floor(hinged);
  dJointAttach(dJointCreateHinge(world.get(), nullptr), hinged, nullptr);
  EXPECT_FALSE(IsStaticContactIsland(hinged, log)) << "a joint other than a contact";

  dBodyID damped = body();
  touch_floor(damped);
  dBodySetLinearDamping(damped, 0.1);
  EXPECT_FALSE(IsStaticContactIsland(damped, log)) << "damping: left to ODE";

  dBodyID asleep = body();
  touch_floor(asleep);
  dBodyDisable(asleep);
  EXPECT_FALSE(IsStaticContactIsland(asleep, log)) << "disabled";

  // Not keeping them, the log makes every contact an ODE joint at once (QuickStep alone steps).
  log.KeepStaticContacts(false);
  dBodyID plain = body();
  touch_floor(plain);
  EXPECT_EQ(dBodyGetNumJoints(plain), 1);
  EXPECT_FALSE(IsStaticContactIsland(plain, log));
}

}  // namespace
