// SPDX-License-Identifier: Apache-2.0
#include "physics/field_builder.hpp"

#include <cmath>

namespace ubersim::kernel {
namespace {

void AddStaticBox(NodeImpl& node, const std::string& name, const Vec3& size, const Vec3& center,
                  double yaw, const SurfaceMaterial& material) {
  GeomSpec g;
  g.name = name;
  g.shape = Shape::Box(size.x(), size.y(), size.z());
  g.offset = Pose::FromYaw(center, yaw);
  g.material = material;
  node.AddGeom(g, nullptr);
}

}  // namespace

Vec3 WalledHalfExtents(const FieldModel& field) {
  return Vec3(0.5 * field.geometry.carpet_length, 0.5 * field.geometry.carpet_width, 0.0);
}

void BuildField(const FieldModel& field, NodeImpl& node) {
  const FieldGeometry& f = field.geometry;
  GeomSpec carpet;
  carpet.name = "carpet";
  carpet.shape = Shape::Plane(Vec3::UnitZ(), 0.0);
  carpet.material = field.carpet;
  node.AddGeom(carpet, nullptr);

  const Vec3 half = WalledHalfExtents(field);
  const double X = half.x(), Y = half.y();
  const double t = field.wall.thickness, h = field.wall.height;
  const SurfaceMaterial& wall = field.wall_surface;

  // Goals: mouth on the goal line, box of side walls, back wall and a roof (the net on top).
  const double gw = f.goal_width, gd = f.goal_depth, gh = f.goal_height;
  const double gt = field.goal_wall_thickness;
  const double goal_line = 0.5 * f.field_length;
  const bool goal_cuts_wall = goal_line + gd + gt > X;  // goal sticks through the end wall
  for (int side : {-1, 1}) {
    const std::string n = side < 0 ? "left_goal" : "right_goal";
    const double s = side;
    for (int lr : {-1, 1}) {
      AddStaticBox(node, n + (lr < 0 ? "_side_a" : "_side_b"), Vec3(gd + gt, gt, gh),
                   Vec3(s * (goal_line + 0.5 * (gd + gt)), lr * (0.5 * gw + 0.5 * gt), 0.5 * gh),
                   0.0, field.goal_surface);
    }
    AddStaticBox(node, n + "_back", Vec3(gt, gw + 2 * gt, gh),
                 Vec3(s * (goal_line + gd + 0.5 * gt), 0.0, 0.5 * gh), 0.0, field.goal_surface);
    AddStaticBox(node, n + "_roof", Vec3(gd + gt, gw + 2 * gt, 0.005),
                 Vec3(s * (goal_line + 0.5 * (gd + gt)), 0.0, gh + 0.0025), 0.0, field.goal_surface);
  }

  // Perimeter walls, outside the carpet's walled area.
  const double c = field.wall.corner_cut;
  AddStaticBox(node, "wall_top", Vec3(2 * X + 2 * t, t, h), Vec3(0, Y + 0.5 * t, 0.5 * h), 0, wall);
  AddStaticBox(node, "wall_bottom", Vec3(2 * X + 2 * t, t, h), Vec3(0, -Y - 0.5 * t, 0.5 * h), 0, wall);
  for (int side : {-1, 1}) {
    const std::string n = side < 0 ? "wall_left" : "wall_right";
    const double x = side * (X + 0.5 * t);
    if (goal_cuts_wall) {
      // Leave an opening for the goal: two segments from the goal's outer side to the corners.
      const double inner = 0.5 * gw + gt;
      const double len = Y - inner;
      AddStaticBox(node, n + "_a", Vec3(t, len, h), Vec3(x, inner + 0.5 * len, 0.5 * h), 0, wall);
      AddStaticBox(node, n + "_b", Vec3(t, len, h), Vec3(x, -inner - 0.5 * len, 0.5 * h), 0, wall);
    } else {
      AddStaticBox(node, n, Vec3(t, 2 * Y, h), Vec3(x, 0, 0.5 * h), 0, wall);
    }
  }
  if (c > 0) {
    // Short angled walls across the corners; their inner face is the cut line.
    const double len = c * std::sqrt(2.0) + 2 * t;
    int i = 0;
    for (int sx : {-1, 1}) {
      for (int sy : {-1, 1}) {
        const Vec3 outward = Vec3(sx, sy, 0).normalized();
        const Vec3 mid(sx * (X - 0.5 * c), sy * (Y - 0.5 * c), 0.5 * h);
        const Vec3 center = mid + outward * (0.5 * t);
        const double yaw = std::atan2(outward.y(), outward.x());
        AddStaticBox(node, "wall_corner_" + std::to_string(i++), Vec3(t, len, h), center, yaw, wall);
      }
    }
  }
}

bool InsideWalls(const FieldModel& field, const Vec3& p, double margin) {
  const Vec3 half = WalledHalfExtents(field);
  const FieldGeometry& f = field.geometry;
  const double ax = std::abs(p.x()), ay = std::abs(p.y());
  const bool in_goal = ax >= 0.5 * f.field_length &&
                       ax <= 0.5 * f.field_length + f.goal_depth + margin &&
                       ay <= 0.5 * f.goal_width + margin;
  if (in_goal) return true;
  if (ax > half.x() + margin || ay > half.y() + margin) return false;
  const double c = field.wall.corner_cut;
  if (c > 0 && (half.x() - ax) + (half.y() - ay) < c - margin * std::sqrt(2.0)) return false;
  return true;
}

BodyImpl& BuildBall(const BallModel& ball, const Vec3& position, NodeImpl& node) {
  BodySpec b;
  b.name = "ball";
  b.mass.mass = ball.mass;
  const double i = ball.inertia_factor * ball.mass * ball.radius * ball.radius;
  b.mass.inertia_diagonal = Vec3(i, i, i);
  Vec3 p = position;
  if (p.z() <= 0.0) p.z() = ball.radius;
  b.pose.position = p;
  auto& body = static_cast<BodyImpl&>(node.AddBody(b));
  if (ball.linear_damping > 0) dBodySetLinearDamping(body.id(), ball.linear_damping);
  if (ball.angular_damping > 0) dBodySetAngularDamping(body.id(), ball.angular_damping);
  GeomSpec g;
  g.name = "ball";
  g.shape = Shape::Sphere(ball.radius);
  g.material = ball.surface;
  auto& geom = static_cast<GeomImpl&>(node.AddGeom(g, &body));
  geom.set_is_ball(true);
  return body;
}

}  // namespace ubersim::kernel
