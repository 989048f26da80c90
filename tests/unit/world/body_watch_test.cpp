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

TEST(BodyWatch, EveryAccumulatingCallOnAnyWatchedBodyLeadsToASweep) {
  TwoBodies t;
  const double inf = std::numeric_limits<double>::infinity();
  const auto poisoned = [&](auto&& call) {
    EXPECT_TRUE(t.watch.AllFinite());               // clean, and remembered as clean
    dBodySetTorque(t.chassis->id(), inf, 0, 0);     // behind the SDK's back: not seen...
    EXPECT_TRUE(t.watch.AllFinite());
    call();                                         // ...until a call adds to a watched body
    const bool finite = t.watch.AllFinite();
    dBodySetTorque(t.chassis->id(), 0, 0, 0);
    return !finite;
  };
  EXPECT_TRUE(poisoned([&] { t.chassis->AddForce(Vec3(1, 0, 0)); }));
  EXPECT_TRUE(poisoned([&] { t.chassis->AddForceAtPoint(Vec3(1, 0, 0), Vec3(0, 1, 0)); }));
  EXPECT_TRUE(poisoned([&] { t.chassis->AddTorque(Vec3(0, 0, 1)); }));
  EXPECT_TRUE(poisoned([&] { t.ball->ApplyImpulse(Vec3(0.1, 0, 0)); }));
}

}  // namespace
}  // namespace ubersim::kernel
