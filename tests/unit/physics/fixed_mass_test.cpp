// SPDX-License-Identifier: Apache-2.0
// Body::AddFixedMass: a part fixed to a body (a contact wheel, which has no body of its own) adds
// its mass and its inertia about the body's centre of mass by parallel axes; the centre of mass
// stays at the body origin, and a part that is not a mass is refused, leaving the body as it was.
// And the contact wheel's own spin: its motor spins the wheel and rotor up within its torque and
// pushes the chassis back by what it spends.
#include <cmath>

#include <gtest/gtest.h>

#include "physics/ode_handles.hpp"
#include "physics/scene_graph.hpp"
#include "ubersim/error.hpp"
#include "ubersim/wheel.hpp"

namespace ubersim::kernel {
namespace {

struct OneBody {
  OneBody() : graph(world.get()) {
    BodySpec b;
    b.name = "chassis";
    b.mass = MassSpec::Solid(Shape::Cylinder(0.09, 0.131), 2.3);
    chassis = static_cast<BodyImpl*>(&graph.Root().AddBody(b));
  }
  dMass Mass() const {
    dMass m;
    dBodyGetMass(chassis->id(), &m);
    return m;
  }
  OdeLibrary ode;
  OdeWorld world{dWorldCreate()};
  SceneGraph graph;
  BodyImpl* chassis = nullptr;
};

double I(const dMass& m, int row, int col) { return m.I[row * 4 + col]; }

TEST(FixedMass, AWheelAddsItsMassAndItsInertiaByParallelAxes) {
  OneBody b;
  const dMass before = b.Mass();
  // A 0.05 kg wheel (r 0.029 m, 0.01 m wide) with its axle along y, 0.079 m ahead and 0.021 m below.
  const double m = 0.05, r = 0.029, w = 0.01;
  const Vec3 at(0.079, 0.0, -0.021);
  b.chassis->AddFixedMass(MassSpec::Solid(Shape::Cylinder(r, w), m),
                          Pose{at, Quat::FromTwoVectors(Vec3::UnitZ(), Vec3::UnitY())});
  const dMass after = b.Mass();
  EXPECT_DOUBLE_EQ(after.mass, 2.35);
  EXPECT_DOUBLE_EQ(b.chassis->Mass(), 2.35);
  const double axial = 0.5 * m * r * r, across = m * (3 * r * r + w * w) / 12;
  // About x: the disc's diameter (across), moved by y² + z² = 0.021².
  EXPECT_NEAR(I(after, 0, 0) - I(before, 0, 0), across + m * at.z() * at.z(), 1e-12);
  // About y: the axle (axial), moved by x² + z².
  EXPECT_NEAR(I(after, 1, 1) - I(before, 1, 1), axial + m * (at.x() * at.x() + at.z() * at.z()), 1e-12);
  EXPECT_NEAR(I(after, 2, 2) - I(before, 2, 2), across + m * at.x() * at.x(), 1e-12);
  // The product of x and z: -m·x·z.
  EXPECT_NEAR(I(after, 0, 2), -m * at.x() * at.z(), 1e-12);
  EXPECT_EQ(after.c[0], 0.0);
  EXPECT_EQ(after.c[2], 0.0);
}

TEST(FixedMass, APartThatIsNoMassIsRefusedAndTheBodyKeepsItsMass) {
  OneBody b;
  MassSpec nothing = MassSpec::Solid(Shape::Sphere(0.01), 0.05);
  nothing.mass = -1.0;
  EXPECT_THROW(b.chassis->AddFixedMass(nothing, Pose{}), PluginError);
  nothing.mass = 0.05;
  EXPECT_THROW(b.chassis->AddFixedMass(nothing, Pose{Vec3(NAN, 0, 0), Quat::Identity()}), PluginError);
  EXPECT_DOUBLE_EQ(b.chassis->Mass(), 2.3);
  EXPECT_DOUBLE_EQ(b.Mass().mass, 2.3);
}

TEST(ContactWheel, TheMotorSpinsTheRotorUpWithinItsTorqueAndTheChassisTakesTheReaction) {
  OneBody b;
  dWorldSetGravity(b.world.get(), 0, 0, 0);
  WheelSpec spec;
  spec.radius = 0.029;
  spec.mass = 0.05;
  spec.rotor_inertia = 1.6e-4;
  spec.axle = Vec3::UnitY();
  ContactWheel wheel(*b.chassis, spec, 0.0, 9.81);  // in the air: nothing touches it
  const double inertia = 0.5 * 0.05 * 0.029 * 0.029 + 1.6e-4, torque = 0.3, dt = 0.001;
  wheel.SetMotor(100.0, torque);
  wheel.Step(dt);
  EXPECT_NEAR(wheel.Rate(), torque * dt / inertia, 1e-9);  // saturated: 1.66 rad/s a step
  const dReal* t = dBodyGetTorque(b.chassis->id());
  EXPECT_NEAR(t[1], -torque, 1e-12);  // the stator pushes the chassis back about the axle
  EXPECT_NEAR(t[0], 0.0, 1e-12);
  for (int i = 0; i < 100; ++i) wheel.Step(dt);
  EXPECT_DOUBLE_EQ(wheel.Rate(), 100.0);  // reached in 60 ms, then held
  // Within its torque the motor holds the rate it is asked for in one step.
  wheel.SetMotor(99.0, torque);
  wheel.Step(dt);
  EXPECT_DOUBLE_EQ(wheel.Rate(), 99.0);
}

}  // namespace
}  // namespace ubersim::kernel
