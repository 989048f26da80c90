// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cmath>
#include <random>
#include <string>

#include "physics/field_builder.hpp"
#include "physics/scene_graph.hpp"
#include "test_world.hpp"

// An SSL-shaped scene for the collision benchmark: the Div B field, the ball, and robots with a
// chassis and four wheel child nodes, scattered over the field (some touching).
namespace ubersim::testing {

/// Builds field, ball and `robots_per_team` × 2 four-wheel robots into `graph`.
inline void BuildSslScene(kernel::SceneGraph& graph, int robots_per_team, std::mt19937_64& rng,
                          double field_half_length = 4.5, double field_half_width = 3.0) {
  kernel::NodeImpl& root = graph.Root();
  kernel::BuildField(*DivBField(), static_cast<kernel::NodeImpl&>(root.AddChild("field")));
  kernel::BuildBall(*GolfBall(), Vec3(0.1, 0.05, 0),
                    static_cast<kernel::NodeImpl&>(root.AddChild("ball")));
  std::uniform_real_distribution<double> x(-field_half_length, field_half_length);
  std::uniform_real_distribution<double> y(-field_half_width, field_half_width);
  std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
  for (const char* team : {"blue", "yellow"}) {
    SceneNode& team_node = root.AddChild(team);
    for (int id = 0; id < robots_per_team; ++id) {
      SceneNode& robot = team_node.AddChild(std::to_string(id));
      const Pose pose = Pose::FromYaw(Vec3(x(rng), y(rng), 0.075), yaw(rng));
      BodySpec chassis;
      chassis.name = "chassis";
      chassis.mass = MassSpec::Solid(Shape::Cylinder(0.09, 0.13), 2.0);
      chassis.pose = pose;
      Body& c = robot.AddBody(chassis);
      robot.AddGeom(GeomSpec{"shell", Shape::Cylinder(0.09, 0.13), {}, {}, {}, true}, &c);
      const double angles[4] = {60, 135, 225, 300};
      for (int w = 0; w < 4; ++w) {
        const double a = angles[w] * M_PI / 180.0;
        SceneNode& wheel_node = robot.AddChild("wheel" + std::to_string(w));
        BodySpec wheel;
        wheel.name = "wheel";
        wheel.mass = MassSpec::Solid(Shape::Cylinder(0.027, 0.01), 0.05);
        // Wheel axis radial: the cylinder's z axis points from the centre out.
        const Quat q = pose.orientation * Quat::FromTwoVectors(Vec3::UnitZ(), Vec3(std::cos(a), std::sin(a), 0));
        wheel.pose = Pose{pose.Transform(Vec3(0.078 * std::cos(a), 0.078 * std::sin(a), -0.048)), q};
        Body& wb = wheel_node.AddBody(wheel);
        wheel_node.AddGeom(GeomSpec{"tyre", Shape::Cylinder(0.027, 0.01), {}, {}, {}, true}, &wb);
      }
    }
  }
}

}  // namespace ubersim::testing
