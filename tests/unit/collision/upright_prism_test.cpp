// SPDX-License-Identifier: Apache-2.0
// Two upright robot shells meet in CollideUprightPrisms: it must find the same depth and normal
// as a brute-force separating-axis search over the outline's own polygon, agree with ODE's
// mesh-against-mesh test on touching or not, and step aside (-1) for a tilted shell.
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "physics/ode_handles.hpp"
#include "physics/scene_graph.hpp"
#include "collision/upright_prism.hpp"

namespace ubersim::kernel {
namespace {

const FlatFrontPrism kShell{0.09, 0.07, 0.0655};   // the modern robot's
const FlatFrontPrism kRound{0.09, 0.09, 0.0655};   // no flat face

// The outline of the shell's mesh seen from above (its ring's vertices), at `pose`.
std::vector<Eigen::Vector2d> Outline(const FlatFrontPrism& p, const Pose& pose) {
  std::vector<Eigen::Vector2d> out;
  const Shape mesh = FlatFrontPrismMesh(p);
  for (const Vec3& v : mesh.vertices) {
    if (v.z() > 0 || v.head<2>().norm() < 1e-9) continue;  // one ring; not the cap centre
    const Vec3 w = pose.Transform(v);
    out.emplace_back(w.x(), w.y());
  }
  return out;
}

// Least overlap over 20000 directions and the direction (from a to b) that gives it.
double BruteForceDepth(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b,
                       Eigen::Vector2d& normal) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 20000; ++i) {
    const double angle = 2.0 * M_PI * i / 20000;
    const Eigen::Vector2d n(std::cos(angle), std::sin(angle));
    double max_a = -1e9, min_b = 1e9;
    for (const auto& p : a) max_a = std::max(max_a, n.dot(p));
    for (const auto& p : b) min_b = std::min(min_b, n.dot(p));
    if (max_a - min_b < best) {
      best = max_a - min_b;
      normal = n;
    }
  }
  return best;
}

Pose Upright(double x, double y, double yaw) { return Pose::FromYaw(Vec3(x, y, 0.08), yaw); }

TEST(UprightPrism, DepthAndNormalMatchABruteForceSearch) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> near(-0.2, 0.2), turn(-M_PI, M_PI);
  int touching = 0, face_cases = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const FlatFrontPrism& shape_b = trial % 4 == 3 ? kRound : kShell;
    const Pose pa = Upright(0, 0, turn(rng));
    const Pose pb = Upright(near(rng), near(rng), turn(rng));
    dContactGeom contacts[4];
    const int n = CollideUprightPrisms(kShell, pa, shape_b, pb, 4, contacts);
    ASSERT_GE(n, 0);
    Eigen::Vector2d normal;
    const double depth = BruteForceDepth(Outline(kShell, pa), Outline(shape_b, pb), normal);
    // The mesh's chords lie up to 0.33 mm inside the arc; 20000 directions add a micrometre.
    if (depth > 0.5e-3) {
      ASSERT_GT(n, 0) << "trial " << trial << ": brute force finds " << depth << " m";
      EXPECT_NEAR(contacts[0].depth, depth, 0.7e-3) << "trial " << trial;
      // Normal out of b into a: against the brute force's a-to-b direction.
      EXPECT_GT(-(contacts[0].normal[0] * normal.x() + contacts[0].normal[1] * normal.y()), std::cos(0.1))
          << "trial " << trial;
      EXPECT_EQ(contacts[0].normal[2], 0.0);
      ++touching;
      face_cases += n == 4;
    } else if (depth < -0.5e-3) {
      EXPECT_EQ(n, 0) << "trial " << trial << ": apart by " << -depth << " m";
    }
  }
  EXPECT_GT(touching, 100);  // the random placements must test contacts, not only gaps
  RecordProperty("touching", touching);
  RecordProperty("face_to_face", face_cases);
}

TEST(UprightPrism, FacesPressedTogetherTouchAlongTheirSharedStretch) {
  // Face to face, 1 mm into each other, offset 1 cm sideways: four contacts at the ends of the
  // shared stretch of face, at the bottom and top of the shared height.
  const Pose pa = Upright(0, 0, 0);
  const Pose pb = Upright(0.139, 0.01, M_PI);
  dContactGeom c[4];
  ASSERT_EQ(CollideUprightPrisms(kShell, pa, kShell, pb, 4, c), 4);
  const double half_width = std::sqrt(0.09 * 0.09 - 0.07 * 0.07);
  double y_min = 1, y_max = -1;
  for (const dContactGeom& k : c) {
    EXPECT_NEAR(k.depth, 0.001, 1e-9);
    EXPECT_NEAR(k.normal[0], -1.0, 1e-9);  // out of b (in front, +x) into a
    EXPECT_NEAR(k.pos[0], 0.0695, 1e-9);
    y_min = std::min(y_min, k.pos[1]);
    y_max = std::max(y_max, k.pos[1]);
  }
  EXPECT_NEAR(y_min, -half_width + 0.01, 1e-9);
  EXPECT_NEAR(y_max, half_width, 1e-9);
  EXPECT_EQ(CollideUprightPrisms(kShell, pa, kShell, pb, 1, c), 1);  // one, in the middle
  EXPECT_NEAR(c[0].pos[1], 0.005, 1e-9);
  EXPECT_NEAR(c[0].pos[2], 0.08, 1e-9);
}

// A flat face pressed against a round back touches it where the disc is deepest: on the line
// through the disc's centre along the face's normal, whichever the face or the disc is (a or b).
// The contact sat midway between the face's corner and the disc instead, up to 28 mm off that
// line: the push spun the round robot up and two robots sank 17 mm into each other (the fast
// soak's seed 3).
TEST(UprightPrism, AFaceAgainstADiscTouchesOnTheDiscsCentreLine) {
  for (const double sideways : {0.0, 0.02, -0.035, 0.05}) {
    const Pose face = Upright(0, 0, 0);                       // face at x = 0.07, facing +x
    const Pose disc = Upright(0.159, sideways, M_PI / 2);      // round back 1 mm into it
    dContactGeom c[4];
    for (const bool face_first : {true, false}) {
      const int n = face_first ? CollideUprightPrisms(kShell, face, kRound, disc, 4, c)
                               : CollideUprightPrisms(kRound, disc, kShell, face, 4, c);
      ASSERT_EQ(n, 2) << "bottom and top, one spot each";
      for (int i = 0; i < n; ++i) {
        EXPECT_NEAR(c[i].depth, 0.001, 1e-9);
        EXPECT_NEAR(std::abs(c[i].normal[0]), 1.0, 1e-9) << "along the face's normal";
        EXPECT_NEAR(c[i].pos[1], sideways, 1e-9) << "on the disc's centre line, face first " << face_first;
        EXPECT_NEAR(c[i].pos[0], 0.0695, 1e-9) << "midway between the face and the disc's deepest point";
      }
    }
  }
}

TEST(UprightPrism, AgreesWithOdesMeshTestOnTouching) {
  OdeLibrary ode;
  OdeWorld world(dWorldCreate());
  SceneGraph graph(world.get());
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> near(-0.2, 0.2), turn(-M_PI, M_PI);
  int agreed = 0, touching = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Pose pa = Upright(0, 0, turn(rng));
    const Pose pb = Upright(near(rng), near(rng), turn(rng));
    SceneNode& node = graph.Root().AddChild("t" + std::to_string(trial));
    auto& a = static_cast<GeomImpl&>(node.AddGeom(GeomSpec{"a", FlatFrontPrismMesh(kShell), pa, {}, {}, true}, nullptr));
    auto& b = static_cast<GeomImpl&>(node.AddGeom(GeomSpec{"b", FlatFrontPrismMesh(kShell), pb, {}, {}, true}, nullptr));
    dContactGeom mesh[64], ours[4];
    const bool mesh_touch = dCollide(a.id(), b.id(), 64, mesh, sizeof(dContactGeom)) > 0;
    const int n = CollideUprightPrisms(kShell, a.GetPose(), kShell, b.GetPose(), 4, ours);
    Eigen::Vector2d normal;
    const double depth = BruteForceDepth(Outline(kShell, pa), Outline(kShell, pb), normal);
    if (std::abs(depth) < 1e-3) continue;  // within the mesh's chord error either answer is right
    EXPECT_EQ(n > 0, mesh_touch) << "trial " << trial << ", depth " << depth;
    agreed += (n > 0) == mesh_touch;
    touching += mesh_touch;
  }
  EXPECT_GT(touching, 50);
  EXPECT_GT(agreed, 250);
}

TEST(UprightPrism, ATiltedShellIsLeftToTheGeneralTest) {
  dContactGeom c[4];
  const Pose pa = Upright(0, 0, 0);
  Pose tilted = Upright(0.15, 0, 0);
  tilted.orientation = Quat(Eigen::AngleAxisd(0.5 * kUprightTilt, Vec3::UnitY()));
  EXPECT_GE(CollideUprightPrisms(kShell, pa, kShell, tilted, 4, c), 0);
  tilted.orientation = Quat(Eigen::AngleAxisd(2.0 * kUprightTilt, Vec3::UnitY()));
  EXPECT_EQ(CollideUprightPrisms(kShell, pa, kShell, tilted, 4, c), -1);
  EXPECT_EQ(CollideUprightPrisms(kShell, tilted, kShell, pa, 4, c), -1);
}

// Put nearly onto each other (a teleport), a shell leaning 2° has its bottom cut 2.3 mm one side
// of the other's centre and its top cut 2.3 mm the other side: each level's least overlap points
// the other way, and the two contacts made a couple that rolled both robots over in a step (the
// fast soak's tipped robots). Both levels push along one direction, each with its own depth.
TEST(UprightPrism, ShellsPutOntoEachOtherPushAlongOneDirectionAtBothLevels) {
  dContactGeom c[4];
  const Pose pa = Upright(0, 0, 0);
  Pose leaning = Upright(0, 0, 0);
  leaning.orientation = Quat(Eigen::AngleAxisd(2.0 * M_PI / 180.0, Vec3::UnitY()));
  const int n = CollideUprightPrisms(kRound, pa, kRound, leaning, 4, c);
  ASSERT_EQ(n, 2);
  const Vec3 first(c[0].normal[0], c[0].normal[1], c[0].normal[2]);
  EXPECT_NEAR(first.z(), 0.0, 1e-12);
  EXPECT_NEAR(first.norm(), 1.0, 1e-9);
  EXPECT_NE(c[0].pos[2], c[1].pos[2]) << "one contact at each level";
  const Vec3 second(c[1].normal[0], c[1].normal[1], c[1].normal[2]);
  EXPECT_GT(first.dot(second), 0.999) << "the levels push the same way";
  // Along x, where the cuts are offset: the deeper level's own depth, and the other's along it
  // (both nearly the two radii: the shells are almost wholly inside each other).
  EXPECT_NEAR(std::abs(first.x()), 1.0, 1e-9);
  for (int i = 0; i < 2; ++i) {
    EXPECT_GT(c[i].depth, 2 * 0.09 - 0.006);
    EXPECT_LT(c[i].depth, 2 * 0.09 + 0.006);
  }
}

TEST(UprightPrism, ALeaningShellTouchesWhereItLeans) {
  // Round shells 1 mm apart; a leans 0.05 rad toward b: its top reaches 3.3 mm further, its
  // bottom 3.3 mm less. They touch at the top only, 2.3 mm deep; the bottom, 4.3 mm apart, is
  // written too, with its gap as a depth below zero (speculative: it holds once the gap closes).
  Pose leaning = Upright(0, 0, 0);
  leaning.orientation = Quat(Eigen::AngleAxisd(0.05, Vec3::UnitY()));
  const Pose upright = Upright(0.181, 0, 0);
  dContactGeom c[4];
  ASSERT_EQ(CollideUprightPrisms(kRound, leaning, kRound, upright, 4, c), 2);
  const double reach = kRound.half_height * std::cos(0.05) * std::tan(0.05);
  const dContactGeom& top = c[0].pos[2] > c[1].pos[2] ? c[0] : c[1];
  const dContactGeom& bottom = c[0].pos[2] > c[1].pos[2] ? c[1] : c[0];
  EXPECT_NEAR(top.depth, reach - 0.001, 1e-5);
  EXPECT_NEAR(top.pos[2], 0.08 + kRound.half_height * std::cos(0.05), 1e-9);
  EXPECT_NEAR(top.normal[0], -1.0, 1e-9);
  EXPECT_NEAR(bottom.depth, -(reach + 0.001), 1e-5);
  EXPECT_NEAR(bottom.pos[2], 0.08 - kRound.half_height * std::cos(0.05), 1e-9);
  EXPECT_NEAR(bottom.normal[0], -1.0, 1e-9);
  // The bottom contact sits on the bottom's cross-sections, 3.3 mm back with the lean.
  EXPECT_NEAR(top.pos[0] - bottom.pos[0], reach, 1e-4);
}

// Two robots arriving at a touch within the same step touch at one level only (the other a
// hair apart, by the lean their driving gives them): both levels are written, or a crash pushed
// at the shells' bottoms alone, below the centres of mass, and threw both robots over. Leaning
// farther apart than 1 cm at the other level, it is left out.
TEST(UprightPrism, ALevelNearlyTouchingIsWrittenWithItsGap) {
  dContactGeom c[4];
  Pose tilted = Upright(0, 0, 0);
  tilted.orientation = Quat(Eigen::AngleAxisd(0.001, Vec3::UnitY()));  // top 0.07 mm toward b, bottom away
  ASSERT_EQ(CollideUprightPrisms(kRound, tilted, kRound, Upright(0.18, 0, 0), 4, c), 2);
  EXPECT_GE(std::max(c[0].depth, c[1].depth), 0.0);
  EXPECT_LT(std::min(c[0].depth, c[1].depth), 0.0);
  EXPECT_GT(std::min(c[0].depth, c[1].depth), -0.0002);
  tilted.orientation = Quat(Eigen::AngleAxisd(0.2, Vec3::UnitY()));  // 13 mm in at the top, 13 mm apart below
  ASSERT_EQ(CollideUprightPrisms(kRound, tilted, kRound, Upright(0.18, 0, 0), 4, c), 1);
  EXPECT_GT(c[0].depth, 0.0);
}

TEST(UprightPrism, ShellsAtDifferentHeightsDoNotTouch) {
  dContactGeom c[4];
  EXPECT_EQ(CollideUprightPrisms(kShell, Upright(0, 0, 0), kShell, Pose::FromYaw(Vec3(0.1, 0, 0.3), 0), 4, c), 0);
}

// A box's outline seen from above, at its pose.
std::vector<Eigen::Vector2d> BoxOutline(const Vec3& size, const Pose& pose) {
  std::vector<Eigen::Vector2d> out;
  for (int k = 0; k < 4; ++k) {
    const Vec3 w = pose.Transform(Vec3((k & 1 ? -0.5 : 0.5) * size.x(), (k & 2 ? -0.5 : 0.5) * size.y(), 0.0));
    out.emplace_back(w.x(), w.y());
  }
  return out;
}

TEST(UprightPrismWithBox, DepthAndNormalMatchABruteForceSearch) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> near(-0.25, 0.25), turn(-M_PI, M_PI), thickness(0.01, 0.3);
  int touching = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const FlatFrontPrism& shell = trial % 4 == 3 ? kRound : kShell;
    const Pose ps = Upright(near(rng), near(rng), turn(rng));
    const Vec3 size(thickness(rng), thickness(rng) + 0.2, 0.16);
    const Pose pb = Pose::FromYaw(Vec3(0, 0, 0.08), turn(rng));
    dContactGeom c[4];
    const int n = CollideUprightPrismWithBox(shell, ps, size, pb, 4, c);
    ASSERT_GE(n, 0) << "trial " << trial;
    Eigen::Vector2d normal;  // from the shell to the box
    const double depth = BruteForceDepth(Outline(shell, ps), BoxOutline(size, pb), normal);
    if (depth > 0.5e-3) {
      ASSERT_GT(n, 0) << "trial " << trial << ": brute force finds " << depth << " m";
      for (int i = 0; i < n; ++i) {
        EXPECT_NEAR(c[i].depth, depth, 0.7e-3) << "trial " << trial;
        // Out of the box into the shell: against the brute force's shell-to-box direction.
        EXPECT_GT(-(c[i].normal[0] * normal.x() + c[i].normal[1] * normal.y()), std::cos(0.1)) << "trial " << trial;
        EXPECT_EQ(c[i].normal[2], 0.0);
        // Where they touch lies within reach of both: inside the box grown by the depth and
        // inside the shell's disc grown by it.
        const Vec3 local = pb.orientation.conjugate() * (Vec3(c[i].pos[0], c[i].pos[1], 0.08) - pb.position);
        EXPECT_LT(std::abs(local.x()), 0.5 * size.x() + depth + 1e-9) << "trial " << trial;
        EXPECT_LT(std::abs(local.y()), 0.5 * size.y() + depth + 1e-9) << "trial " << trial;
        EXPECT_LT(std::hypot(c[i].pos[0] - ps.position.x(), c[i].pos[1] - ps.position.y()), shell.radius + 1e-9);
      }
      ++touching;
    } else if (depth < -0.5e-3) {
      EXPECT_EQ(n, 0) << "trial " << trial << ": apart by " << -depth << " m";
    }
  }
  EXPECT_GT(touching, 100);
}

TEST(UprightPrismWithBox, AShellPushedIntoAThinWallFromBehindIsPushedBackOut) {
  // The soak's finding: a robot put 4 mm into a goal's 2 cm back wall from behind. ODE's mesh
  // test took the hollow shell's far side and pushed it through and over; the way out is back.
  const Vec3 wall(0.02, 1.2, 0.16);
  const Pose wall_pose = Pose::FromYaw(Vec3(6.19, 0, 0.08), 0);
  const double behind = 6.2 + 0.09 - 0.004;
  for (double yaw : {0.0, 0.5 * M_PI, 2.0}) {  // the arc toward the wall
    dContactGeom c[4];
    const int n = CollideUprightPrismWithBox(kShell, Upright(behind, -0.319, yaw), wall, wall_pose, 4, c);
    ASSERT_EQ(n, 2) << "yaw " << yaw;  // one spot, at the bottom and the top
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(c[i].normal[0], 1.0, 1e-12) << "yaw " << yaw;
      EXPECT_NEAR(c[i].depth, 0.004, 1e-12) << "yaw " << yaw;
      EXPECT_NEAR(c[i].pos[0], 6.2 - 0.002, 1e-9);
      EXPECT_NEAR(c[i].pos[1], -0.319, 1e-9);
    }
  }
  // The flat face toward the wall reaches 2 cm less far: apart.
  dContactGeom c[4];
  EXPECT_EQ(CollideUprightPrismWithBox(kShell, Upright(behind, -0.319, M_PI), wall, wall_pose, 4, c), 0);
  // Its face pressed flat against the wall: the ends of the face at the bottom and the top.
  ASSERT_EQ(CollideUprightPrismWithBox(kShell, Upright(6.2 + 0.07 - 0.001, 0, M_PI), wall, wall_pose, 4, c), 4);
  EXPECT_NEAR(std::abs(c[0].pos[1]), std::sqrt(0.09 * 0.09 - 0.07 * 0.07), 1e-9);
  EXPECT_NEAR(c[0].depth, 0.001, 1e-12);
  // One contact allowed: the face's middle, half way up.
  ASSERT_EQ(CollideUprightPrismWithBox(kShell, Upright(6.2 + 0.07 - 0.001, 0, M_PI), wall, wall_pose, 1, c), 1);
  EXPECT_NEAR(c[0].pos[1], 0.0, 1e-9);
  EXPECT_NEAR(c[0].pos[2], 0.08, 1e-9);
}

// A robot leaning into a wall as it drives into it touches at the top first: the bottom, a few
// millimetres off, is written too with its gap (speculative), as two shells' levels are. With the
// top contact alone the wall's push acted above the centre of mass only.
TEST(UprightPrismWithBox, AShellLeaningIntoAWallGetsItsOtherLevelWithItsGap) {
  const Vec3 wall(0.02, 1.2, 0.16);
  const Pose wall_pose = Pose::FromYaw(Vec3(6.19, 0, 0.08), 0);
  Pose leaning = Upright(6.2 + 0.09 + 0.001, 0, 0.5 * M_PI);  // the arc toward the wall, 1 mm off
  leaning.orientation = Quat(Eigen::AngleAxisd(-0.05, Vec3::UnitY())) * leaning.orientation;  // top toward it
  const double reach = kShell.half_height * std::cos(0.05) * std::tan(0.05);
  dContactGeom c[4];
  ASSERT_EQ(CollideUprightPrismWithBox(kShell, leaning, wall, wall_pose, 4, c), 2);
  const dContactGeom& top = c[0].pos[2] > c[1].pos[2] ? c[0] : c[1];
  const dContactGeom& bottom = c[0].pos[2] > c[1].pos[2] ? c[1] : c[0];
  EXPECT_NEAR(top.depth, reach - 0.001, 1e-5);
  EXPECT_NEAR(bottom.depth, -(reach + 0.001), 1e-5);
  EXPECT_NEAR(bottom.normal[0], 1.0, 1e-9);
  // Leaning 0.2 rad, the bottom is 1 cm and more off: the top alone.
  leaning.orientation = Quat(Eigen::AngleAxisd(-0.2, Vec3::UnitY())) * Pose::FromYaw(Vec3::Zero(), 0.5 * M_PI).orientation;
  ASSERT_EQ(CollideUprightPrismWithBox(kShell, leaning, wall, wall_pose, 4, c), 1);
  EXPECT_GT(c[0].depth, 0.0);
}

TEST(UprightPrismWithBox, TiltedBoxesLeaningShellsAndWallTopsAreLeftToTheGeneralTest) {
  dContactGeom c[4];
  const Vec3 wall(0.02, 1.0, 0.1);
  Pose tilted = Pose::FromYaw(Vec3(0.1, 0, 0.05), 0);
  tilted.orientation = Quat(Eigen::AngleAxisd(0.2, Vec3::UnitX()));
  EXPECT_EQ(CollideUprightPrismWithBox(kShell, Upright(0, 0, 0), wall, tilted, 4, c), -1);
  Pose leaning = Upright(0, 0, 0);
  leaning.orientation = Quat(Eigen::AngleAxisd(2.0 * kUprightTilt, Vec3::UnitY()));
  EXPECT_EQ(CollideUprightPrismWithBox(kShell, leaning, wall, Pose::FromYaw(Vec3(0.1, 0, 0.05), 0), 4, c), -1);
  // A shell whose bottom is 5 mm into a 10 cm wall's top, its centre over the wall.
  const Pose on_top = Pose::FromYaw(Vec3(0.0, 0.0, 0.1 + kShell.half_height - 0.005), 0);
  EXPECT_EQ(CollideUprightPrismWithBox(kShell, on_top, wall, Pose::FromYaw(Vec3(0, 0, 0.05), 0), 4, c), -1);
  // Above the wall: apart.
  const Pose above = Pose::FromYaw(Vec3(0.0, 0.0, 0.1 + kShell.half_height + 0.005), 0);
  EXPECT_EQ(CollideUprightPrismWithBox(kShell, above, wall, Pose::FromYaw(Vec3(0, 0, 0.05), 0), 4, c), 0);
}

// The ball against a shell taken as a solid: outside it the nearest point of the outline (round
// wall, flat face, the face's corner, top), inside it out through the side, never the bottom.
TEST(UprightPrism, ABallMeetsTheShellAsTheSolidItStandsFor) {
  const Pose at = Upright(0, 0, 0);  // centre 0.08 m up: the shell spans 0.0145 to 0.1455 m
  const double r = 0.0215;
  dContactGeom c;
  // Behind it, 10 mm into the round wall: pushed straight back.
  ASSERT_EQ(CollideFlatFrontPrismWithSphere(kShell, at, Vec3(-0.1015, 0, 0.0215), r, &c), 1);
  EXPECT_NEAR(c.depth, 0.01, 1e-12);
  EXPECT_NEAR(c.normal[0], -1.0, 1e-12);
  EXPECT_NEAR(c.pos[0], -0.09, 1e-12);
  // In front, 5 mm into the flat face: pushed straight forward.
  ASSERT_EQ(CollideFlatFrontPrismWithSphere(kShell, at, Vec3(0.0865, 0.01, 0.0215), r, &c), 1);
  EXPECT_NEAR(c.depth, 0.005, 1e-12);
  EXPECT_NEAR(c.normal[0], 1.0, 1e-12);
  // Off the face's corner (0.07, 0.0566): the corner is the nearest point.
  const Vec3 corner(0.07, std::sqrt(0.09 * 0.09 - 0.07 * 0.07), 0.0215);
  const Vec3 out(std::cos(0.35), std::sin(0.35), 0.0);  // between the face's normal and the wall's (39°)
  ASSERT_EQ(CollideFlatFrontPrismWithSphere(kShell, at, corner + 0.02 * out, r, &c), 1);
  EXPECT_NEAR(c.depth, 0.0015, 1e-12);
  EXPECT_NEAR(c.normal[0], out.x(), 1e-9);
  EXPECT_NEAR(c.normal[1], out.y(), 1e-9);
  // Apart: no contact.
  EXPECT_EQ(CollideFlatFrontPrismWithSphere(kShell, at, Vec3(-0.112, 0, 0.0215), r, &c), 0);
  // Resting on the top: pushed up.
  ASSERT_EQ(CollideFlatFrontPrismWithSphere(kShell, at, Vec3(0.0, 0.02, 0.1455 + 0.02), r, &c), 1);
  EXPECT_NEAR(c.normal[2], 1.0, 1e-12);
  // Inside (what a ball through the hollow mesh ended as, 49 mm from the centre): out through
  // the round wall (41 mm away), not the bottom (7 mm away).
  ASSERT_EQ(CollideFlatFrontPrismWithSphere(kShell, at, Vec3(-0.049, 0, 0.0215), r, &c), 1);
  EXPECT_NEAR(c.normal[0], -1.0, 1e-12);
  EXPECT_NEAR(c.normal[2], 0.0, 1e-12);
  EXPECT_NEAR(c.depth, r + 0.041, 1e-12);
  // A shell leaning 5° away from the ball, its edge lifted above the ball's centre: the edge
  // still pushes the ball back, nearly level, where a ray from its centre passes under.
  const Pose leaning{Vec3(0, 0, 0.08), Eigen::Quaterniond(Eigen::AngleAxisd(5.0 * M_PI / 180.0, Vec3::UnitY()))};
  const Vec3 edge = leaning.Transform(Vec3(-0.09, 0, -0.0655));
  ASSERT_GT(edge.z(), 0.0215);
  ASSERT_EQ(CollideFlatFrontPrismWithSphere(kShell, leaning, Vec3(edge.x() - 0.01, 0, 0.0215), r, &c), 1);
  EXPECT_LT(c.normal[0], -0.9);
  EXPECT_GT(c.depth, 0.005);
  // Centred a rounding error outside the surface: half in, out along the surface's normal (it
  // was no contact, and a placed ball searched for a free spot stopped half inside the face).
  ASSERT_EQ(CollideFlatFrontPrismWithSphere(kShell, at, Vec3(0.07 + 1e-15, 0.01, 0.0215), r, &c), 1);
  EXPECT_NEAR(c.depth, r, 1e-12);
  EXPECT_NEAR(c.normal[0], 1.0, 1e-12);
  ASSERT_EQ(CollideFlatFrontPrismWithSphere(kShell, at, Vec3(-0.09 - 1e-15, 0, 0.0215), r, &c), 1);
  EXPECT_NEAR(c.depth, r, 1e-12);
  EXPECT_NEAR(c.normal[0], -1.0, 1e-12);
}

}  // namespace
}  // namespace ubersim::kernel
