// SPDX-License-Identifier: Apache-2.0
// The check after each plugin call: it sweeps the watched values only when a call added to a
// body's velocity, force or torque since the last clean check, the only SDK writes that can
// turn finite arguments into a non-finite value.
#include <limits>

#include <gtest/gtest.h>

#include "world/fault_monitor.hpp"
#include "physics/ode_handles.hpp"
#include "physics/scene_graph.hpp"

namespace ubersim::kernel {
namespace {

struct TwoBodies {
  TwoBodies() : graph(world.get()) {
    BodySpec b;
    b.mass = MassSpec::Solid(Shape::Sphere(0.05), 1.0);
    b.name = "chassis";
    chassis = static_cast<BodyImpl*>(&graph.Root().AddBody(b));
    b.name = "ball";
    ball = static_cast<BodyImpl*>(&graph.Root().AddBody(b));
    watch.Add(*chassis);
    watch.Add(*ball);
  }
  OdeLibrary ode;
  OdeWorld world{dWorldCreate()};
  SceneGraph graph;
  BodyImpl* chassis = nullptr;
  BodyImpl* ball = nullptr;
  BodyWatch watch;
};

TEST(BodyWatch, AnOverflowingSumOfFiniteForcesIsCaught) {
  TwoBodies t;
  EXPECT_TRUE(t.watch.AllFinite());
  t.chassis->AddForce(Vec3(1e308, 0, 0));
  EXPECT_TRUE(t.watch.AllFinite());
  t.chassis->AddForce(Vec3(1e308, 0, 0));
  EXPECT_FALSE(t.watch.AllFinite());
  dBodySetForce(t.chassis->id(), 0, 0, 0);  // repaired
  EXPECT_TRUE(t.watch.AllFinite());
}

TEST(BodyWatch, EachAccumulatingCallThatLeavesItsSumNonFiniteIsSeen) {
  TwoBodies t;
  const double inf = std::numeric_limits<double>::infinity();
  // `poison` makes the value `call` adds to infinite behind the SDK's back (the SDK refuses an
  // infinite argument): the call's finite addition then leaves a non-finite sum.
  const auto seen = [&](auto&& poison, auto&& call) {
    EXPECT_TRUE(t.watch.AllFinite());  // clean, and remembered as clean
    poison();
    EXPECT_TRUE(t.watch.AllFinite());  // not written through the SDK: not looked for
    call();
    const bool finite = t.watch.AllFinite();
    dBodySetForce(t.chassis->id(), 0, 0, 0);
    dBodySetTorque(t.chassis->id(), 0, 0, 0);
    dBodySetLinearVel(t.ball->id(), 0, 0, 0);
    return !finite;
  };
  const auto force = [&] { dBodySetForce(t.chassis->id(), inf, 0, 0); };
  const auto torque = [&] { dBodySetTorque(t.chassis->id(), inf, 0, 0); };
  EXPECT_TRUE(seen(force, [&] { t.chassis->AddForce(Vec3(1, 0, 0)); }));
  EXPECT_TRUE(seen(force, [&] { t.chassis->AddForceAtPoint(Vec3(1, 0, 0), Vec3(0, 1, 0)); }));
  EXPECT_TRUE(seen(torque, [&] { t.chassis->AddForceAtPoint(Vec3(1, 0, 0), Vec3(0, 1, 0)); }));
  EXPECT_TRUE(seen(torque, [&] { t.chassis->AddTorque(Vec3(0, 0, 1)); }));
  EXPECT_TRUE(seen([&] { dBodySetLinearVel(t.ball->id(), inf, 0, 0); }, [&] { t.ball->ApplyImpulse(Vec3(0.1, 0, 0)); }));
}

TEST(BodyWatch, ACallWhoseSumStaysFiniteCostsNoLook) {
  // The check after a drive's push reads one counter: a call leaving finite sums does not make
  // the watch look at every value (so a value made infinite behind the SDK's back stays unseen).
  TwoBodies t;
  EXPECT_TRUE(t.watch.AllFinite());
  dBodySetTorque(t.chassis->id(), std::numeric_limits<double>::infinity(), 0, 0);
  t.chassis->AddForce(Vec3(1, 0, 0));
  t.ball->ApplyImpulse(Vec3(0.1, 0, 0));
  EXPECT_TRUE(t.watch.AllFinite());
  t.chassis->AddTorque(Vec3(0, 0, 1));  // adds to the infinite torque: seen
  EXPECT_FALSE(t.watch.AllFinite());
}

}  // namespace
}  // namespace ubersim::kernel
