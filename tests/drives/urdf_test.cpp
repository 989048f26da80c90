// SPDX-License-Identifier: Apache-2.0
// A robot whose chassis comes from URDF with a mesh shell drives like its YAML twin; bad URDF and
// unreadable meshes are reported with file, line and reason.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>

#include <gtest/gtest.h>

#include "omni_world.hpp"
#include "model/urdf.hpp"
#include "world/world_attorney.hpp"

namespace ubersim::kernel {
namespace {

namespace fs = std::filesystem;
constexpr const char* kUrdfRobot = UBERSIM_SOURCE_DIR "/models/robots/ssl-omni-2026-urdf.yaml";
constexpr const char* kUrdf = UBERSIM_SOURCE_DIR "/models/robots/urdf/ssl-omni-2026.urdf";

TEST(Urdf, TheShippedRobotHasAMeshShellAndTheRightMass) {
  const UrdfRobot r = LoadUrdf(kUrdf);
  ASSERT_EQ(r.links.size(), 1u);
  EXPECT_EQ(r.links[0].name, "base_link");
  EXPECT_DOUBLE_EQ(r.links[0].mass.mass, 2.3);
  EXPECT_NEAR(r.links[0].inertial_origin.position.z(), 0.05, 1e-12);
  ASSERT_EQ(r.links[0].collisions.size(), 1u);
  const Shape& shell = r.links[0].collisions[0].shape;
  EXPECT_EQ(shell.kind, Shape::Kind::kTriangleMesh);
  EXPECT_EQ(shell.indices.size(), 196u * 3);
  double max_x = -1, min_x = 1;
  for (const Vec3& v : shell.vertices) {
    max_x = std::max(max_x, v.x());
    min_x = std::min(min_x, v.x());
  }
  EXPECT_NEAR(max_x, 0.07, 1e-6);   // the flat front
  EXPECT_NEAR(min_x, -0.09, 1e-4);  // the round back
}

struct Twins : ::testing::TestWithParam<std::tuple<std::string, LocalVelocityCommand>> {};

TEST_P(Twins, UrdfRobotDrivesLikeItsYamlTwin) {
  const std::string& profile = std::get<0>(GetParam());
  OmniWorld yaml(profile, kOmniRobot);
  OmniWorld urdf(profile, kUrdfRobot);
  const LocalVelocityCommand c = std::get<1>(GetParam());
  yaml.Drive(c, 1.5);
  urdf.Drive(c, 1.5);
  const Vec3 vy = yaml.LocalVelocity(), vu = urdf.LocalVelocity();
  const double speed = std::hypot(c.forward, c.left);
  // Both within the 3 % validation band of the command, so of each other. Turning on the spot
  // the centre moves 3 mm/s at most, at fast 10 mm/s: two solver sweeps lean the wheel-body robot
  // 1.5° on its hinges (docs/collision.md) and its centre circles 2.6 mm off the axis (7.8 mm/s
  // measured at 3 rad/s, both twins alike).
  const double band = speed > 0 ? 0.03 * speed : profile == "fast" ? 0.01 : 0.003;
  EXPECT_NEAR(vu.x(), c.forward, band);
  EXPECT_NEAR(vu.y(), c.left, band);
  EXPECT_NEAR(vu.x(), vy.x(), band);
  EXPECT_NEAR(vu.y(), vy.y(), band);
  EXPECT_NEAR(urdf.Robot().twist.angular.z(), c.angular, 0.03 * std::max(1.0, std::abs(c.angular)));
  EXPECT_NEAR(urdf.Robot().pose.position.z(), yaml.Robot().pose.position.z(), 0.002);
}

INSTANTIATE_TEST_SUITE_P(Commands, Twins,
                         ::testing::Combine(BothProfiles(),
                                            ::testing::Values(LocalVelocityCommand{1.0, 0.0, 0.0},
                                                              LocalVelocityCommand{0.0, 1.0, 0.0},
                                                              LocalVelocityCommand{0.0, 0.0, 3.0})),
                         [](const auto& info) {
                           const LocalVelocityCommand& c = std::get<1>(info.param);
                           const char* what = c.angular != 0 ? "turning" : c.left != 0 ? "sideways" : "forward";
                           return std::get<0>(info.param) + "_" + what;
                         });

class UrdfBall : public ::testing::TestWithParam<std::string> {};

TEST_P(UrdfBall, TheMeshShellCollidesWithTheBall) {
  OmniWorld w(GetParam(), kUrdfRobot);
  // Roll the ball at the robot's flat front (robot at x = -2 facing +x).
  w.world->events().Post(PositionEvent{Target::Ball(), Vec3(-1.5, 0.0, 0.0), std::nullopt,
                                       Vec3(-2.0, 0.0, 0.0), Vec3(0, -2.0 / 0.0215, 0), std::nullopt, {}});
  double min_x = 0;
  for (int i = w.Steps(0.6); i > 0; --i) {
    w.world->Step();
    min_x = std::min(min_x, WorldAttorney::Ball(*w.world).GetPose().position.x());
  }
  EXPECT_GT(min_x, -2.0 + 0.07 + 0.0215 - 0.003) << "the ball went into the shell";
  EXPECT_GT(WorldAttorney::Ball(*w.world).GetTwist().linear.x(), 0.1) << "the ball should bounce back";
}

INSTANTIATE_TEST_SUITE_P(BothProfiles, UrdfBall, BothProfiles(), ProfileName);

fs::path WriteTemp(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / ("ubersim_urdf_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

TEST(Urdf, XmlErrorsNameTheLine) {
  const fs::path f = WriteTemp("broken.urdf", "<robot name=\"x\">\n  <link name=\"a\">\n  </linc>\n</robot>\n");
  try {
    LoadUrdf(f);
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.file(), f.string());
    EXPECT_EQ(e.line(), 3) << e.what();
    EXPECT_NE(std::string(e.what()).find("XML error"), std::string::npos) << e.what();
  }
}

TEST(Urdf, AMissingMeshNamesTheMeshElementAndTheLink) {
  const fs::path f = WriteTemp("nomesh.urdf",
      "<robot name=\"x\">\n"
      "  <link name=\"base_link\">\n"
      "    <inertial><mass value=\"1\"/><inertia ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial>\n"
      "    <collision><geometry>\n"
      "      <mesh filename=\"no-such-shell.stl\"/>\n"
      "    </geometry></collision>\n"
      "  </link>\n"
      "</robot>\n");
  try {
    LoadUrdf(f);
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 5) << e.what();
    EXPECT_EQ(e.key(), "link 'base_link'");
    EXPECT_NE(e.reason().find("no-such-shell.stl"), std::string::npos) << e.what();
  }
}

TEST(Urdf, ALinkWithoutMassIsRefused) {
  const fs::path f = WriteTemp("nomass.urdf", "<robot name=\"x\">\n  <link name=\"base_link\"/>\n</robot>\n");
  try {
    LoadUrdf(f);
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 2) << e.what();
    EXPECT_NE(e.reason().find("positive mass"), std::string::npos) << e.what();
  }
}

TEST(Urdf, ANonRobotDocumentIsRefusedWithUrdfdomsReason) {
  const fs::path f = WriteTemp("notrobot.urdf", "<robot>\n</robot>\n");
  EXPECT_THROW(LoadUrdf(f), ModelError);
}

}  // namespace
}  // namespace ubersim::kernel
