// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "ubersim/scene.hpp"
#include "ubersim/kernel/model.hpp"

// A robot body described as URDF (urdfdom) with meshes (assimp), ready to build into the scene
// graph. The root link's frame stands on the carpet (z = 0 at the robot's ground point, x forward).
namespace ubersim::kernel {

/// One collision shape of a link, in the link's frame.
struct UrdfCollision {
  Shape shape;     ///< primitive, or a triangle mesh read with assimp
  Pose origin;     ///< pose in the link frame
};

/// One link: mass properties about its centre of mass, and its collision shapes.
struct UrdfLink {
  std::string name;                      ///< link name
  MassSpec mass;                         ///< mass and inertia about the centre of mass (COM at 0)
  Pose inertial_origin;                  ///< pose of the COM frame in the link frame
  Pose pose;                             ///< link frame relative to the root link, joints at zero
  std::vector<UrdfCollision> collisions; ///< collision shapes
};

/// One joint between two links.
struct UrdfJoint {
  std::string name;    ///< joint name
  JointKind kind;      ///< hinge (revolute, continuous), slider (prismatic) or fixed
  std::string parent;  ///< parent link
  std::string child;   ///< child link
  Vec3 axis;           ///< axis in the child link frame
  double lower = -1e30, upper = 1e30;  ///< limits (rad or m); ±1e30: none
};

/// A parsed URDF: links (root first) and joints.
struct UrdfRobot {
  std::string file;               ///< the URDF file
  std::vector<UrdfLink> links;    ///< root first, then children in joint order
  std::vector<UrdfJoint> joints;  ///< every joint
};

/// Reads a URDF file and every mesh it names. Throws ModelError naming the file, the line and
/// column (XML errors, the element of a bad link or mesh) and the link or joint.
UrdfRobot LoadUrdf(const std::filesystem::path& file);

}  // namespace ubersim::kernel
