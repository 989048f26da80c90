// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <memory>

#include "ubersim/kernel/model.hpp"

// A Div B world built in code (no model files), so kernel tests do not depend on the loader.
namespace ubersim::testing {

/// Div B field (physics.md §1) with 0.1 m walls.
inline std::shared_ptr<kernel::FieldModel> DivBField() {
  auto f = std::make_shared<kernel::FieldModel>();
  f->file = "<code>";
  kernel::FieldModel& m = *f;
  m.geometry.name = "div-b";
  m.geometry.field_length = 9.0;
  m.geometry.field_width = 6.0;
  m.geometry.boundary_width = 0.3;
  m.geometry.goal_width = 1.0;
  m.geometry.goal_depth = 0.18;
  m.geometry.goal_height = 0.16;
  m.geometry.carpet_length = 9.6;
  m.geometry.carpet_width = 6.6;
  m.goal_wall_thickness = 0.02;
  m.wall = kernel::WallModel{0.1, 0.05, 0.0};
  m.carpet.name = "carpet";
  m.carpet.mu = 0.8;
  m.wall_surface.name = "wall";
  m.goal_surface.name = "goal";
  return f;
}

/// 43 mm, 46 g golf ball.
inline std::shared_ptr<kernel::BallModel> GolfBall() {
  auto b = std::make_shared<kernel::BallModel>();
  b->file = "<code>";
  b->name = "golf";
  b->radius = 0.0215;
  b->mass = 0.046;
  b->inertia_factor = 0.4;
  b->surface.name = "ball";
  return b;
}

/// A world with the Div B field, the golf ball at `ball_start`, no robots, 1 ms steps.
inline kernel::WorldModel BallWorld(const Vec3& ball_start = Vec3::Zero()) {
  kernel::WorldModel w;
  w.file = "<code>";
  w.name = "test";
  w.field = DivBField();
  w.ball = GolfBall();
  w.ball_start = ball_start;
  w.physics.step = 0.001;
  SurfaceMaterial ball_carpet;
  ball_carpet.mu = 0.35;
  ball_carpet.bounce = 0.56;
  ball_carpet.bounce_velocity = 0.1;
  ball_carpet.rolling_friction = 0.0011;
  w.material_pairs.push_back({"ball", "carpet", ball_carpet});
  SurfaceMaterial ball_wall;
  ball_wall.mu = 0.2;
  ball_wall.bounce = 0.6;
  ball_wall.bounce_velocity = 0.05;
  w.material_pairs.push_back({"ball", "wall", ball_wall});
  SurfaceMaterial ball_goal;
  ball_goal.mu = 0.3;
  ball_goal.bounce = 0.2;
  w.material_pairs.push_back({"ball", "goal", ball_goal});
  return w;
}

}  // namespace ubersim::testing
