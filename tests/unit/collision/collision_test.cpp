// SPDX-License-Identifier: Apache-2.0
// The collision manager must report exactly the touching pairs a brute-force all-pairs test
// finds, less pairs inside one subtree line (ancestor/descendant or same node), two static
// geometries, or two geometries of one body — for every broadphase.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "../../common/random_scene.hpp"
#include "collision/collision.hpp"
#include "physics/ode_handles.hpp"

namespace ubersim::kernel {
namespace {

using PairSet = std::set<std::pair<std::string, std::string>>;

std::pair<std::string, std::string> Key(const GeomImpl& a, const GeomImpl& b) {
  std::string x = a.owner().Path() + ":" + a.Name();
  std::string y = b.owner().Path() + ":" + b.Name();
  if (y < x) std::swap(x, y);
  return {x, y};
}

// Written independently of CollisionManager::MayCollide on purpose.
bool InOneLine(const NodeImpl* a, const NodeImpl* b) {
  for (const NodeImpl* n = a; n; n = n->parent()) {
    if (n == b) return true;
  }
  for (const NodeImpl* n = b; n; n = n->parent()) {
    if (n == a) return true;
  }
  return false;
}

PairSet BruteForce(SceneGraph& graph) {
  std::vector<GeomImpl*> all;
  graph.Root().ForEachGeom([&](GeomImpl& g) { all.push_back(&g); });
  PairSet out;
  dContactGeom contacts[8];
  for (std::size_t i = 0; i < all.size(); ++i) {
    for (std::size_t j = i + 1; j < all.size(); ++j) {
      GeomImpl& a = *all[i];
      GeomImpl& b = *all[j];
      if (InOneLine(&a.owner(), &b.owner())) continue;
      if (!a.body() && !b.body()) continue;
      if (a.body() && a.body() == b.body()) continue;
      if (dCollide(a.id(), b.id(), 8, contacts, sizeof(dContactGeom)) > 0) out.insert(Key(a, b));
    }
  }
  return out;
}

PairSet Reported(CollisionManager& cm) {
  PairSet out;
  for (auto [a, b] : cm.TouchingPairs()) {
    const bool inserted = out.insert(Key(*a, *b)).second;
    EXPECT_TRUE(inserted) << "pair reported twice: " << Key(*a, *b).first << " / " << Key(*a, *b).second;
  }
  return out;
}

class CollisionAgainstBruteForce : public ::testing::TestWithParam<Broadphase> {};

TEST_P(CollisionAgainstBruteForce, RandomNestedScenesGiveExactlyTheBruteForcePairs) {
  OdeLibrary ode;
  std::mt19937_64 rng(20260422);
  std::size_t total_pairs = 0;
  for (int scene = 0; scene < 300; ++scene) {
    OdeWorld world(dWorldCreate());
    SceneGraph graph(world.get());
    CollisionManager cm(graph, GetParam(), 8);
    testing::BuildRandomScene(graph, rng);
    const PairSet expected = BruteForce(graph);
    const PairSet got = Reported(cm);
    total_pairs += expected.size();
    ASSERT_EQ(got, expected) << "scene " << scene << " with broadphase " << ToString(GetParam());
  }
  // The scenes must actually collide, or the comparison proves nothing.
  EXPECT_GT(total_pairs, 1000u);
}

INSTANTIATE_TEST_SUITE_P(ExactBroadphases, CollisionAgainstBruteForce,
                         ::testing::Values(Broadphase::kSceneGraph, Broadphase::kSweepAndPrune, Broadphase::kField),
                         [](const auto& info) { return std::string(ToString(info.param)); });

// Bodies of a few geometries each (spheres and boxes off the body's origin, as a robot's wheel
// contacts, shell and dribbler) at random heights and tilts over a carpet: the field broadphase
// tests a body's boxes against the carpet once for all of them before any alone, and must still
// find every geometry the brute force finds touching it.
TEST(CollisionAgainstBruteForceOnACarpet, FieldFindsEveryGeometryTouchingThePlane) {
  OdeLibrary ode;
  std::mt19937_64 rng(20261202);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::size_t plane_pairs = 0, box_plane_pairs = 0, bodies_partly_down = 0;
  for (int scene = 0; scene < 200; ++scene) {
    OdeWorld world(dWorldCreate());
    SceneGraph graph(world.get());
    CollisionManager cm(graph, Broadphase::kField, 8);
    graph.Root().AddChild("field").AddGeom(GeomSpec{"carpet", Shape::Plane(Vec3::UnitZ(), 0), {}, {}, {}, true}, nullptr);
    for (int r = 0; r < 6; ++r) {
      SceneNode& node = graph.Root().AddChild("body" + std::to_string(r));
      BodySpec spec;
      spec.name = "chassis";
      spec.mass = MassSpec::Solid(Shape::Box(0.1, 0.1, 0.1), 1.0);
      // Mostly standing a little above the carpet, some tilted far enough to put a box into it.
      const double tilt = 0.6 * unit(rng);
      spec.pose = Pose{Vec3(0.5 * r, 0.3 * unit(rng), 0.03 + 0.03 * unit(rng)),
                       Quat(Eigen::AngleAxisd(tilt, Vec3(unit(rng), unit(rng), 0.2).normalized()))};
      Body& body = node.AddBody(spec);
      node.AddGeom(GeomSpec{"wheel", Shape::Sphere(0.03), Pose{Vec3(0.05, 0.05, -0.01), Quat::Identity()}, {}, {}, true},
                   &body);
      node.AddGeom(GeomSpec{"shell", Shape::Box(0.16, 0.16, 0.08), Pose{Vec3(0, 0, 0.05), Quat::Identity()}, {}, {}, true},
                   &body);
      node.AddGeom(GeomSpec{"bar", Shape::Box(0.02, 0.1, 0.02),
                            Pose{Vec3(0.09, 0, 0.01), Quat(Eigen::AngleAxisd(0.3, Vec3::UnitY()))}, {}, {}, true},
                   &body);
    }
    const PairSet expected = BruteForce(graph);
    ASSERT_EQ(Reported(cm), expected) << "scene " << scene;
    std::set<std::string> down;
    for (const auto& [a, b] : expected) {
      const bool a_carpet = a.ends_with(":carpet"), b_carpet = b.ends_with(":carpet");
      if (a_carpet == b_carpet) continue;
      const std::string& other = a_carpet ? b : a;
      ++plane_pairs;
      if (!other.ends_with(":wheel")) {
        ++box_plane_pairs;
        down.insert(other.substr(0, other.find(':')));
      }
    }
    bodies_partly_down += down.size();
  }
  // Both outcomes must occur, or the comparison proves nothing: boxes on the carpet, and bodies
  // standing clear of it on their spheres.
  EXPECT_GT(box_plane_pairs, 100u);
  EXPECT_GT(bodies_partly_down, 100u);
  EXPECT_LT(box_plane_pairs, plane_pairs);
}

// ODE 0.16.2's hash space misses pairs whose boxes straddle a cell boundary at 0 (see
// docs/collision.md): it must never invent a pair, and the misses are counted and reported.
TEST(CollisionAgainstBruteForceOdeHash, ReportsOnlyTrueTouchingPairs) {
  OdeLibrary ode;
  std::mt19937_64 rng(20260422);
  std::size_t expected_total = 0, missed = 0;
  for (int scene = 0; scene < 300; ++scene) {
    OdeWorld world(dWorldCreate());
    SceneGraph graph(world.get());
    CollisionManager cm(graph, Broadphase::kHash, 8);
    testing::BuildRandomScene(graph, rng);
    const PairSet expected = BruteForce(graph);
    const PairSet got = Reported(cm);
    for (const auto& p : got) ASSERT_TRUE(expected.count(p)) << "scene " << scene << ": invented pair";
    expected_total += expected.size();
    missed += expected.size() - got.size();
  }
  EXPECT_GT(expected_total, 1000u);
  std::printf("ODE hash space missed %zu of %zu touching pairs\n", missed, expected_total);
  ::testing::Test::RecordProperty("ode_hash_missed_pairs", static_cast<int>(missed));
}

// The smallest case of the hash-space miss: two boxes overlapping in the cell at the origin.
TEST(CollisionAgainstBruteForceOdeHash, SceneGraphFindsThePairOdeHashMisses) {
  OdeLibrary ode;
  OdeWorld world(dWorldCreate());
  SceneGraph graph(world.get());
  auto add_box = [&](const char* name, const Vec3& lo, const Vec3& hi) {
    SceneNode& n = graph.Root().AddChild(name);
    BodySpec b;
    b.name = name;
    b.pose.position = 0.5 * (lo + hi);
    b.mass = MassSpec::Solid(Shape::Sphere(0.1), 1.0);
    Body& body = n.AddBody(b);
    const Vec3 size = hi - lo;
    n.AddGeom(GeomSpec{"box", Shape::Box(size.x(), size.y(), size.z()), {}, {}, {}, true}, &body);
  };
  add_box("a", Vec3(-0.26, 0.237, 0.125), Vec3(0.274, 0.771, 0.659));
  add_box("b", Vec3(0.0297, 0.256, -0.0302), Vec3(0.683, 1.059, 0.763));
  CollisionManager cm(graph, Broadphase::kSceneGraph, 4);
  EXPECT_EQ(cm.TouchingPairs().size(), 1u);
  cm.SetBroadphase(Broadphase::kSweepAndPrune);
  EXPECT_EQ(cm.TouchingPairs().size(), 1u);
}

// Builds a small explicit scene: robot (chassis + wheel child) touching a box, and a ball.
struct SmallScene {
  OdeLibrary ode;
  OdeWorld world{dWorldCreate()};
  SceneGraph graph{world.get()};
};

TEST(CollisionManager, NeverPairsANodeWithItsOwnDescendants) {
  SmallScene s;
  CollisionManager cm(s.graph, Broadphase::kSceneGraph, 4);
  SceneNode& robot = s.graph.Root().AddChild("robot");
  BodySpec chassis_spec;
  chassis_spec.name = "chassis";
  chassis_spec.mass = MassSpec::Solid(Shape::Cylinder(0.09, 0.14), 2.0);
  Body& chassis = robot.AddBody(chassis_spec);
  robot.AddGeom(GeomSpec{"shell", Shape::Cylinder(0.09, 0.14), {}, {}, {}, true}, &chassis);
  SceneNode& wheel_node = robot.AddChild("wheel");
  BodySpec wheel_spec;
  wheel_spec.name = "wheel";
  wheel_spec.mass = MassSpec::Solid(Shape::Cylinder(0.03, 0.01), 0.1);
  wheel_spec.pose.position = Vec3(0.07, 0, 0);  // overlaps the chassis on purpose
  Body& wheel = wheel_node.AddBody(wheel_spec);
  wheel_node.AddGeom(GeomSpec{"tyre", Shape::Cylinder(0.03, 0.01), {}, {}, {}, true}, &wheel);
  EXPECT_TRUE(cm.TouchingPairs().empty());

  // A second robot's wheel in the same place does collide with the first chassis.
  SceneNode& other = s.graph.Root().AddChild("other");
  BodySpec other_spec = wheel_spec;
  other_spec.name = "other_wheel";
  Body& other_wheel = other.AddBody(other_spec);
  other.AddGeom(GeomSpec{"tyre", Shape::Cylinder(0.03, 0.01), {}, {}, {}, true}, &other_wheel);
  const auto pairs = cm.TouchingPairs();
  EXPECT_EQ(pairs.size(), 2u);  // other tyre vs shell and vs the first tyre
}

TEST(CollisionManager, ContactJointsUseTheMaterialPairTable) {
  SmallScene s;
  CollisionManager cm(s.graph, Broadphase::kSceneGraph, 4);
  SurfaceMaterial carpet;
  carpet.name = "carpet";
  carpet.mu = 0.9;
  SurfaceMaterial ball;
  ball.name = "ball";
  ball.mu = 0.1;
  s.graph.Root().AddChild("field").AddGeom(
      GeomSpec{"carpet", Shape::Plane(Vec3::UnitZ(), 0), {}, carpet, {}, true}, nullptr);
  SceneNode& ball_node = s.graph.Root().AddChild("ball");
  BodySpec b;
  b.name = "ball";
  b.mass = MassSpec::Solid(Shape::Sphere(0.0215), 0.046);
  b.pose.position = Vec3(0, 0, 0.02);  // slightly sunk: touching
  Body& body = ball_node.AddBody(b);
  ball_node.AddGeom(GeomSpec{"ball", Shape::Sphere(0.0215), {}, ball, {}, true}, &body);

  EXPECT_NEAR(cm.materials().Resolve(carpet, ball).mu, 0.3, 1e-12);  // sqrt(0.9 * 0.1)
  SurfaceMaterial pair;
  pair.mu = 0.35;
  pair.bounce = 0.56;
  cm.materials().SetPair("ball", "carpet", pair);
  const SurfaceMaterial resolved = cm.materials().Resolve(ball, carpet);
  EXPECT_DOUBLE_EQ(resolved.mu, 0.35);
  EXPECT_DOUBLE_EQ(resolved.bounce, 0.56);
  EXPECT_EQ(resolved.name, "ball|carpet");

  cm.Collide();
  EXPECT_EQ(cm.stats().touching_pairs, 1u);
  EXPECT_GE(cm.stats().contacts, 1u);
  cm.ClearContacts();
}

TEST(CollisionManager, ObserversSeeContactsAndMayDropThem) {
  SmallScene s;
  CollisionManager cm(s.graph, Broadphase::kSceneGraph, 4);
  s.graph.Root().AddChild("field").AddGeom(
      GeomSpec{"carpet", Shape::Plane(Vec3::UnitZ(), 0), {}, {}, {}, true}, nullptr);
  SceneNode& n = s.graph.Root().AddChild("thing");
  BodySpec b;
  b.name = "b";
  b.mass = MassSpec::Solid(Shape::Sphere(0.05), 0.1);
  b.pose.position = Vec3(0, 0, 0.04);
  Body& body = n.AddBody(b);
  auto& g = static_cast<GeomImpl&>(n.AddGeom(GeomSpec{"s", Shape::Sphere(0.05), {}, {}, {}, true}, &body));
  int seen = 0;
  Vec3 normal = Vec3::Zero();
  g.AddObserver([&](const Contact& c, SurfaceMaterial&, bool& accept) {
    ++seen;
    normal = c.normal;
    EXPECT_EQ(c.own, &g);
    EXPECT_FALSE(c.other_is_ball);
    accept = false;
  });
  cm.Collide();
  EXPECT_GE(seen, 1);
  EXPECT_EQ(cm.stats().contacts, 0u);  // dropped by the observer
  EXPECT_NEAR(normal.z(), 1.0, 1e-9);  // from the carpet into the sphere
}

// Surfaces are cached per pair of geometries: a changed material or material table must show in
// the very next contacts.
TEST(CollisionManager, AChangedMaterialOrTableShowsInTheNextContacts) {
  SmallScene s;
  CollisionManager cm(s.graph, Broadphase::kSweepAndPrune, 4);
  SurfaceMaterial carpet;
  carpet.name = "carpet";
  carpet.mu = 0.9;
  s.graph.Root().AddChild("field").AddGeom(GeomSpec{"carpet", Shape::Plane(Vec3::UnitZ(), 0), {}, carpet, {}, true},
                                           nullptr);
  SceneNode& n = s.graph.Root().AddChild("thing");
  BodySpec b;
  b.name = "b";
  b.mass = MassSpec::Solid(Shape::Sphere(0.05), 0.1);
  b.pose.position = Vec3(0, 0, 0.049);
  Body& body = n.AddBody(b);
  SurfaceMaterial rubber;
  rubber.name = "rubber";
  rubber.mu = 0.1;
  auto& g = static_cast<GeomImpl&>(n.AddGeom(GeomSpec{"s", Shape::Sphere(0.05), {}, rubber, {}, true}, &body));
  double mu = -1;
  g.AddObserver([&](const Contact&, SurfaceMaterial& m, bool&) { mu = m.mu; });
  auto collide = [&] {
    mu = -1;
    cm.Collide();
    cm.ClearContacts();
    return mu;
  };
  EXPECT_NEAR(collide(), 0.3, 1e-12);  // sqrt(0.9 · 0.1)
  EXPECT_NEAR(collide(), 0.3, 1e-12);  // cached
  rubber.mu = 0.4;
  g.SetMaterial(rubber);
  EXPECT_NEAR(collide(), 0.6, 1e-12);  // sqrt(0.9 · 0.4)
  SurfaceMaterial pair;
  pair.mu = 0.25;
  cm.materials().SetPair("rubber", "carpet", pair);
  EXPECT_DOUBLE_EQ(collide(), 0.25);
}

// The surface cache stays bounded when more pairs touch than it holds (a long run brings ever
// new pairs of robot parts together), and the surfaces stay right across its clearing.
TEST(CollisionManager, TheSurfaceCacheStaysBoundedAndRight) {
  SmallScene s;
  CollisionManager cm(s.graph, Broadphase::kSweepAndPrune, 4);
  SurfaceMaterial carpet;
  carpet.name = "carpet";
  carpet.mu = 0.9;
  s.graph.Root().AddChild("field").AddGeom(GeomSpec{"carpet", Shape::Plane(Vec3::UnitZ(), 0), {}, carpet, {}, true},
                                           nullptr);
  SurfaceMaterial rubber;
  rubber.name = "rubber";
  rubber.mu = 0.1;
  // 100 spheres in one heap: 4950 pairs among them, 100 with the carpet.
  std::vector<double> seen;
  for (int i = 0; i < 100; ++i) {
    SceneNode& n = s.graph.Root().AddChild("thing" + std::to_string(i));
    BodySpec b;
    b.name = "b";
    b.mass = MassSpec::Solid(Shape::Sphere(0.05), 0.1);
    b.pose.position = Vec3(0.001 * i, 0, 0.049);
    Body& body = n.AddBody(b);
    auto& g = static_cast<GeomImpl&>(n.AddGeom(GeomSpec{"s", Shape::Sphere(0.05), {}, rubber, {}, true}, &body));
    if (i == 0) g.AddObserver([&](const Contact&, SurfaceMaterial& m, bool&) { seen.push_back(m.mu); });
  }
  for (int step = 0; step < 3; ++step) {
    seen.clear();
    cm.Collide();
    cm.ClearContacts();
    EXPECT_LE(cm.cached_surfaces(), 4096u);
    ASSERT_EQ(seen.size(), 100u);  // 99 spheres and the carpet
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 0.1), 99);
    EXPECT_EQ(std::count_if(seen.begin(), seen.end(), [](double mu) { return std::abs(mu - 0.3) < 1e-12; }), 1);
  }
  EXPECT_GT(cm.cached_surfaces(), 0u);
}

// The soak's memory finding: over an hour ever new pairs touch, and a cache of every pair that
// ever touched grew by about 1.8 kB a simulated second. Pairs that stopped touching are swept
// out; pairs still touching stay.
TEST(CollisionManager, TheSurfaceCacheForgetsPairsThatStoppedTouching) {
  SmallScene s;
  CollisionManager cm(s.graph, Broadphase::kSweepAndPrune, 4);
  s.graph.Root().AddChild("field").AddGeom(GeomSpec{"carpet", Shape::Plane(Vec3::UnitZ(), 0), {}, {}, {}, true},
                                           nullptr);
  std::vector<Body*> bodies;
  for (int i = 0; i < 10; ++i) {  // five touching pairs of spheres resting on the carpet
    SceneNode& n = s.graph.Root().AddChild("thing" + std::to_string(i));
    BodySpec b;
    b.name = "b";
    b.mass = MassSpec::Solid(Shape::Sphere(0.05), 0.1);
    b.pose.position = Vec3(1.0 * (i / 2) + 0.09 * (i % 2), 0, 0.049);
    bodies.push_back(&n.AddBody(b));
    n.AddGeom(GeomSpec{"s", Shape::Sphere(0.05), {}, {}, {}, true}, bodies.back());
  }
  auto pass = [&] {
    cm.Collide();
    cm.ClearContacts();
  };
  pass();
  EXPECT_EQ(cm.cached_surfaces(), 15u);  // five sphere pairs, ten spheres on the carpet
  // Part every pair but the first: the parted pairs' surfaces go within two sweep intervals.
  for (int i = 3; i < 10; i += 2) {
    Pose p = bodies[static_cast<std::size_t>(i)]->GetPose();
    p.position.y() = 0.5;
    bodies[static_cast<std::size_t>(i)]->SetPose(p);
  }
  for (std::uint64_t k = 0; k < CollisionManager::kSurfaceCacheSweepPasses / 2; ++k) pass();
  EXPECT_EQ(cm.cached_surfaces(), 15u) << "not yet stale";
  for (std::uint64_t k = 0; k < 2 * CollisionManager::kSurfaceCacheSweepPasses; ++k) pass();
  EXPECT_EQ(cm.cached_surfaces(), 11u) << "the first pair and the ten carpet contacts stay";
}

// A body whose box lies wholly above the carpet is never narrow-tested against it (a trimesh
// chassis would test every vertex); one that reaches down to it is.
std::size_t NarrowTestsWithBoxAt(double z) {
  SmallScene s;
  CollisionManager cm(s.graph, Broadphase::kSweepAndPrune, 4);
  s.graph.Root().AddChild("field").AddGeom(
      GeomSpec{"carpet", Shape::Plane(Vec3::UnitZ(), 0), {}, {}, {}, true}, nullptr);
  SceneNode& n = s.graph.Root().AddChild("thing");
  BodySpec b;
  b.name = "b";
  b.mass = MassSpec::Solid(Shape::Box(0.1, 0.1, 0.1), 1.0);
  b.pose.position = Vec3(0, 0, z);
  Body& body = n.AddBody(b);
  n.AddGeom(GeomSpec{"box", Shape::Box(0.1, 0.1, 0.1), {}, {}, {}, true}, &body);
  cm.Collide();
  return cm.stats().narrow_tests;
}

TEST(CollisionManager, SkipsThePlaneForABoxWhollyAboveIt) {
  EXPECT_EQ(NarrowTestsWithBoxAt(0.051), 0u);  // bottom 1 mm above the carpet
  EXPECT_EQ(NarrowTestsWithBoxAt(0.049), 1u);  // bottom 1 mm into it
}

// A geometry's scope decides before the narrow phase: a carpet-only sphere resting on the carpet
// and against a box touches only the carpet; a no-planes one only the box.
std::set<std::string> TouchedBy(ContactScope scope, Broadphase broadphase) {
  SmallScene s;
  CollisionManager cm(s.graph, broadphase, 4);
  s.graph.Root().AddChild("field").AddGeom(
      GeomSpec{"carpet", Shape::Plane(Vec3::UnitZ(), 0), {}, {}, {}, true}, nullptr);
  s.graph.Root().AddChild("block").AddGeom(
      GeomSpec{"box", Shape::Box(0.1, 0.1, 0.1), Pose{Vec3(0.09, 0, 0.05), Quat::Identity()}, {}, {}, true}, nullptr);
  SceneNode& n = s.graph.Root().AddChild("thing");
  BodySpec b;
  b.name = "b";
  b.mass = MassSpec::Solid(Shape::Sphere(0.05), 0.1);
  b.pose.position = Vec3(0, 0, 0.049);  // 1 mm into the carpet and 1 mm into the box
  Body& body = n.AddBody(b);
  GeomSpec sphere{"s", Shape::Sphere(0.05), {}, {}, {}, true};
  sphere.scope = scope;
  auto& g = static_cast<GeomImpl&>(n.AddGeom(sphere, &body));
  std::set<std::string> touched;
  g.AddObserver([&](const Contact& c, SurfaceMaterial&, bool&) { touched.insert(c.other->Name()); });
  cm.Collide();
  return touched;
}

TEST(CollisionManager, ContactScopesDropPairsBeforeTheNarrowPhase) {
  for (Broadphase bp : {Broadphase::kSceneGraph, Broadphase::kSweepAndPrune, Broadphase::kField}) {
    EXPECT_EQ(TouchedBy(ContactScope::kAll, bp), (std::set<std::string>{"carpet", "box"})) << ToString(bp);
    EXPECT_EQ(TouchedBy(ContactScope::kPlanesOnly, bp), std::set<std::string>{"carpet"}) << ToString(bp);
    EXPECT_EQ(TouchedBy(ContactScope::kNoPlanes, bp), std::set<std::string>{"box"}) << ToString(bp);
  }
}

// A 6.5 m/s ball at a 1 cm thin wall, stepped at 5 ms: 32.5 mm a step, more than the ball's
// radius. Without the swept test it crosses the wall between two steps; with it, it bounces.
double BallXAfterShotAtThinWall(bool swept) {
  SmallScene s;
  dWorldSetGravity(s.world.get(), 0, 0, 0);
  constexpr double kStep = 0.005;
  CollisionManager cm(s.graph, Broadphase::kSweepAndPrune, 4);
  cm.SetSweptBallStep(swept ? kStep : 0.0);
  SurfaceMaterial hard;
  hard.bounce = 0.5;
  s.graph.Root().AddChild("wall").AddGeom(
      GeomSpec{"wall", Shape::Box(0.01, 1.0, 1.0), Pose{Vec3(0.3, 0, 0), Quat::Identity()}, hard, {}, true},
      nullptr);
  SceneNode& ball_node = s.graph.Root().AddChild("ball");
  BodySpec b;
  b.name = "ball";
  b.mass = MassSpec::Solid(Shape::Sphere(0.0215), 0.046);
  b.pose.position = Vec3(0.0113, 0, 0);  // the wall's face is crossed mid-step, not at a step's end
  b.twist.linear = Vec3(6.5, 0, 0);
  Body& body = ball_node.AddBody(b);
  static_cast<GeomImpl&>(ball_node.AddGeom(GeomSpec{"ball", Shape::Sphere(0.0215), {}, hard, {}, true}, &body))
      .set_is_ball(true);
  std::size_t swept_contacts = 0;
  for (int i = 0; i < 40; ++i) {  // 0.2 s: 1.3 m of flight
    cm.Collide();
    swept_contacts += cm.stats().swept_contacts;
    dWorldQuickStep(s.world.get(), kStep);
    cm.ClearContacts();
  }
  EXPECT_EQ(swept_contacts > 0, swept);
  return body.GetPose().position.x();
}

TEST(CollisionManager, AFastBallIsSweptAndCannotCrossAThinWallBetweenSteps) {
  EXPECT_GT(BallXAfterShotAtThinWall(false), 0.3) << "the check must be able to fail: unswept, it crosses";
  EXPECT_LT(BallXAfterShotAtThinWall(true), 0.3 - 0.005 - 0.0215 + 1e-3) << "swept, it bounces off the wall";
}

// A conveyor: a static slab whose observer says its surface moves at 0.5 m/s along +x. A box
// resting on it is dragged up to that speed by friction (ODE attaches a static geometry's
// contact the other way round: the sign must survive that), and a box on a still slab stays put.
// Body against body is the dribbler's case (tests/parts/dribbler_test.cpp).
double BoxSpeedOnConveyor(double belt_speed, Broadphase broadphase) {
  SmallScene s;
  constexpr double kStep = 0.001;
  dWorldSetGravity(s.world.get(), 0, 0, -9.81);
  CollisionManager cm(s.graph, broadphase, 4);
  auto& slab = static_cast<GeomImpl&>(s.graph.Root().AddChild("slab").AddGeom(
      GeomSpec{"slab", Shape::Box(2.0, 1.0, 0.1), Pose{Vec3(0, 0, -0.05), Quat::Identity()}, {}, {}, true}, nullptr));
  slab.AddObserver([&](const Contact&, SurfaceMaterial& m, bool&) { m.surface_velocity = Vec3(belt_speed, 0, 0); });
  SceneNode& box_node = s.graph.Root().AddChild("box");
  BodySpec b;
  b.name = "box";
  b.mass = MassSpec::Solid(Shape::Box(0.1, 0.1, 0.1), 1.0);
  b.pose.position = Vec3(0, 0, 0.0499);
  Body& body = box_node.AddBody(b);
  box_node.AddGeom(GeomSpec{"box", Shape::Box(0.1, 0.1, 0.1), {}, {}, {}, true}, &body);
  for (int i = 0; i < 500; ++i) {  // 0.5 s: mu 0.5 reaches 0.5 m/s in about 0.1 s
    cm.Collide();
    dWorldQuickStep(s.world.get(), kStep);
    cm.ClearContacts();
  }
  EXPECT_LT(std::abs(body.GetTwist().linear.y()), 1e-4) << "dragged sideways";
  return body.GetTwist().linear.x();
}

TEST(CollisionManager, AMovingSurfaceDragsWhatRestsOnIt) {
  for (Broadphase bp : {Broadphase::kSceneGraph, Broadphase::kSweepAndPrune, Broadphase::kField}) {
    EXPECT_NEAR(BoxSpeedOnConveyor(0.5, bp), 0.5, 1e-3) << ToString(bp);
    EXPECT_NEAR(BoxSpeedOnConveyor(-0.5, bp), -0.5, 1e-3) << ToString(bp);
    EXPECT_NEAR(BoxSpeedOnConveyor(0.0, bp), 0.0, 1e-4) << ToString(bp);
  }
}

TEST(CollisionManager, BroadphaseNamesRoundTrip) {
  for (Broadphase b : {Broadphase::kSceneGraph, Broadphase::kHash, Broadphase::kSweepAndPrune, Broadphase::kField}) {
    EXPECT_EQ(ParseBroadphase(ToString(b)), b);
  }
  EXPECT_THROW(ParseBroadphase("octree"), std::invalid_argument);
}

}  // namespace
}  // namespace ubersim::kernel

namespace ubersim::kernel {
namespace {

// The kernel's own sphere-plane test must give dCollide's contact bit for bit, in both orders,
// for tilted planes, spheres on bodies with and without an offset, touching or not.
TEST(CollideSphereAndPlane, GivesDCollidesContactBitForBit) {
  OdeLibrary ode;
  OdeWorld world(dWorldCreate());
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int touching = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Vec3 n(u(rng), u(rng), u(rng));
    if (n.norm() < 1e-3) continue;
    n.normalize();
    OdeGeom plane(dCreatePlane(nullptr, n.x(), n.y(), n.z(), 0.1 * u(rng)));
    const double radius = 0.02 + 0.03 * (u(rng) + 1.0);
    OdeGeom sphere(dCreateSphere(nullptr, radius));
    OdeBody body(dBodyCreate(world.get()));
    dBodySetPosition(body.get(), 0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng));
    dGeomSetBody(sphere.get(), body.get());
    if (trial % 2) dGeomSetOffsetPosition(sphere.get(), 0.01 * u(rng), 0.01 * u(rng), 0.01 * u(rng));
    for (const bool sphere_first : {true, false}) {
      const dGeomID first = sphere_first ? sphere.get() : plane.get();
      const dGeomID second = sphere_first ? plane.get() : sphere.get();
      dContactGeom expected{}, got{};
      const int n_expected = dCollide(first, second, 1, &expected, sizeof(dContactGeom));
      const int n_got = CollideSphereAndPlane(first, second, got);
      ASSERT_EQ(n_got, n_expected) << "trial " << trial;
      if (n_expected == 0) continue;
      ++touching;
      for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(got.pos[i], expected.pos[i]) << "trial " << trial;
        EXPECT_EQ(got.normal[i], expected.normal[i]) << "trial " << trial;
      }
      EXPECT_EQ(got.depth, expected.depth);
      EXPECT_EQ(got.g1, expected.g1);
      EXPECT_EQ(got.g2, expected.g2);
      EXPECT_EQ(got.side1, expected.side1);
      EXPECT_EQ(got.side2, expected.side2);
    }
  }
  // Both outcomes were tried, in numbers.
  EXPECT_GT(touching, 400);
  EXPECT_LT(touching, 3600);
}

}  // namespace
}  // namespace ubersim::kernel
