// SPDX-License-Identifier: Apache-2.0
// Convex polyhedra in the scene graph: a prism rests on the carpet at its true height, stops the
// ball, and touches a cylinder; shapes ODE would get wrong are refused with the reason.
#include <cmath>
#include <sstream>

#include <gtest/gtest.h>

#include "../../common/test_world.hpp"
#include "ubersim/error.hpp"
#include "collision/collision.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/world.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel {
namespace {

// A regular hexagon of circumradius r, counter-clockwise.
std::vector<Vec3> Hexagon(double r) {
  std::vector<Vec3> out;
  for (int i = 0; i < 6; ++i) out.emplace_back(r * std::cos(i * M_PI / 3), r * std::sin(i * M_PI / 3), 0);
  return out;
}

struct Scene {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kWarning};
  PluginRegistry registry{{}};
  World world{testing::BallWorld(Vec3(3, 2, 0)), registry, log, false};

  Body& AddPrism(const std::string& name, const Vec3& at, double length = 0.1) {
    SceneNode& node = WorldAttorney::Scene(world).Root().AddChild(name);
    BodySpec b;
    b.name = name;
    b.mass = MassSpec::Solid(Shape::Box(0.2, 0.2, length), 1.0);
    b.pose.position = at;
    Body& body = node.AddBody(b);
    GeomSpec g;
    g.name = "shell";
    g.shape = Shape::Prism(Hexagon(0.1), length);
    node.AddGeom(g, &body);
    return body;
  }
};

TEST(Convex, APrismRestsOnTheCarpetAtItsHeight) {
  Scene s;
  Body& prism = s.AddPrism("prism", Vec3(0, 0, 0.3), 0.1);
  for (int i = 0; i < 2000; ++i) s.world.Step();
  EXPECT_NEAR(prism.GetPose().position.z(), 0.05, 0.001);  // half its length, less the contact layer
  EXPECT_LT(prism.GetTwist().linear.norm(), 1e-3);
}

TEST(Convex, APrismStopsTheBallAndIsPushedByIt) {
  Scene s;
  Body& prism = s.AddPrism("prism", Vec3(0, 0, 0.05), 0.1);
  s.world.events().Post(PositionEvent{Target::Ball(), Vec3(-0.5, 0, 0.0215), std::nullopt, Vec3(4, 0, 0),
                                      Vec3::Zero(), std::nullopt});
  double closest = 1e9;
  for (int i = 0; i < 400; ++i) {
    s.world.Step();
    closest = std::min(closest, std::abs(WorldAttorney::Ball(s.world).GetPose().position.x() - prism.GetPose().position.x()));
  }
  // The hexagon's flat side faces -x at its inradius 0.0866 m: the ball's centre stays outside.
  EXPECT_GT(closest, 0.0866 + 0.0215 - 0.006);
  EXPECT_LT(WorldAttorney::Ball(s.world).GetTwist().linear.x(), 0.0);  // bounced back
  EXPECT_GT(prism.GetPose().position.x(), 0.001);        // and pushed the prism
}

TEST(Convex, ShapesODEWouldGetWrongAreRefused) {
  Scene s;
  SceneNode& node = WorldAttorney::Scene(s.world).Root().AddChild("bad");
  GeomSpec g;
  g.name = "dent";
  std::vector<Vec3> dented = Hexagon(0.1);
  dented[1] *= 0.3;  // a reflex corner
  g.shape = Shape::Prism(dented, 0.1);
  try {
    node.AddGeom(g, nullptr);
    FAIL() << "a non-convex prism was accepted";
  } catch (const PluginError& e) {
    EXPECT_NE(std::string(e.what()).find("geometry 'dent': convex shape is not convex"), std::string::npos) << e.what();
  }
  g.name = "clockwise";
  std::vector<Vec3> clockwise = Hexagon(0.1);
  std::reverse(clockwise.begin(), clockwise.end());
  g.shape = Shape::Prism(clockwise, 0.1);
  EXPECT_THROW(node.AddGeom(g, nullptr), PluginError);
  g.name = "indices";
  g.shape = Shape::Prism(Hexagon(0.1), 0.1);
  g.shape.indices[3] = 99;
  EXPECT_THROW(node.AddGeom(g, nullptr), PluginError);
  EXPECT_THROW(Shape::Prism({Vec3::Zero(), Vec3::UnitX()}, 0.1), PluginError);
}

TEST(Convex, AManyCorneredPrismRestsLevelOnFourSpreadContacts) {
  // A robot-like shell: a 33-corner outline. ODE reports its resting contacts in corner order,
  // all along one side; the collision manager keeps a spread four, so it stands level.
  Scene s;
  SceneNode& node = WorldAttorney::Scene(s.world).Root().AddChild("shell");
  BodySpec b;
  b.name = "shell";
  b.mass = MassSpec::Solid(Shape::Cylinder(0.09, 0.13), 2.5);
  b.pose.position = Vec3(0, 0, 0.066);
  Body& body = node.AddBody(b);
  std::vector<Vec3> outline;
  for (int i = 0; i <= 32; ++i) {
    const double a = 0.68 + (2 * M_PI - 1.36) * i / 32;
    outline.emplace_back(0.09 * std::cos(a), 0.09 * std::sin(a), 0);
  }
  GeomSpec g;
  g.name = "shell";
  g.shape = Shape::Prism(outline, 0.13);
  node.AddGeom(g, &body);
  for (int i = 0; i < 3000; ++i) s.world.Step();
  const Vec3 up = body.GetPose().orientation * Vec3::UnitZ();
  EXPECT_GT(up.z(), std::cos(0.5 * M_PI / 180)) << "tilted by " << std::acos(up.z()) * 180 / M_PI << "°";
  EXPECT_NEAR(body.GetPose().position.z(), 0.065, 0.001);
}

TEST(SpreadContacts, KeepsTheDeepestAndThenTheFarthestPoints) {
  // 12 candidate points along a quarter circle, as ODE lists them, the deepest in the middle.
  std::vector<dContactGeom> c(kContactCandidates);
  for (int i = 0; i < 12; ++i) {
    const double a = 0.5 * M_PI * i / 11;
    c[static_cast<std::size_t>(i)].pos[0] = std::cos(a);
    c[static_cast<std::size_t>(i)].pos[1] = std::sin(a);
    c[static_cast<std::size_t>(i)].pos[2] = 0;
    c[static_cast<std::size_t>(i)].depth = i == 5 ? 0.002 : 0.001;
  }
  ASSERT_EQ(SpreadContacts(c, 12, 3), 3);
  // The deepest (5), then the ends farthest from it (0 and 11), in their original order.
  EXPECT_DOUBLE_EQ(c[0].pos[0], 1.0);
  EXPECT_NEAR(c[1].pos[0], std::cos(0.5 * M_PI * 5 / 11), 1e-12);
  EXPECT_NEAR(c[2].pos[1], 1.0, 1e-12);
  EXPECT_EQ(SpreadContacts(c, 2, 4), 2);  // fewer than kept: untouched
}

}  // namespace
}  // namespace ubersim::kernel
