// SPDX-License-Identifier: Apache-2.0
// Joints measure their torque only when asked: the solver's feedback costs every joint work
// each step, so an unmeasured joint refuses LastTorque instead of reporting zeros.
#include <string>

#include <gtest/gtest.h>

#include "physics/ode_handles.hpp"
#include "physics/scene_graph.hpp"

namespace ubersim::kernel {
namespace {

// A wheel on a motorised hinge to the world, held at rest against a load torque about its axle.
struct HeldWheel {
  explicit HeldWheel(bool measure_torque) : graph(world.get()) {
    dWorldSetGravity(world.get(), 0, 0, 0);
    BodySpec b;
    b.name = "wheel";
    b.mass = MassSpec::Solid(Shape::Cylinder(0.03, 0.01), 0.05);
    wheel = &graph.Root().AddBody(b);
    JointSpec j;
    j.name = "axle";
    j.kind = JointKind::kHinge;
    j.child = wheel;
    j.axis = Vec3::UnitX();
    j.measure_torque = measure_torque;
    hinge = &graph.Root().AddJoint(j);
    hinge->SetMotor(0.0, 1.0);  // hold still with up to 1 N·m
  }

  void Step(const Vec3& load) {
    wheel->AddTorque(load);
    dWorldQuickStep(world.get(), 0.001);
  }

  OdeLibrary ode;
  OdeWorld world{dWorldCreate()};
  SceneGraph graph;
  Body* wheel = nullptr;
  Joint* hinge = nullptr;
};

TEST(Joint, AMeasuredJointReportsTheTorqueThatHoldsItsChild) {
  HeldWheel w(true);
  for (int i = 0; i < 20; ++i) w.Step(Vec3(0.2, 0.05, 0));
  // The hinge cancels the load on its child: the motor about the axle, the hinge's rows across it.
  const Vec3 t = w.hinge->LastTorque();
  EXPECT_NEAR(t.x(), -0.2, 1e-3);
  EXPECT_NEAR(t.y(), -0.05, 1e-3);
  EXPECT_NEAR(t.z(), 0.0, 1e-3);
  EXPECT_NEAR(w.hinge->Rate(), 0.0, 1e-3);
}

TEST(Joint, AnUnmeasuredJointRefusesLastTorqueAndSaysWhy) {
  HeldWheel w(false);
  w.Step(Vec3(0.2, 0, 0));
  EXPECT_NEAR(w.hinge->Rate(), 0.0, 1e-3);  // the motor holds it all the same
  try {
    (void)w.hinge->LastTorque();
    FAIL() << "LastTorque of an unmeasured joint returned";
  } catch (const PluginError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("joint 'axle'"), std::string::npos) << what;
    EXPECT_NE(what.find("measure_torque"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace ubersim::kernel
