// SPDX-License-Identifier: Apache-2.0
// The field's walls: the walled area a model describes (with its corner cuts), and the static
// wall pieces a world has built (perimeter, corner cuts, goals), for checks and teleports that
// must keep things inside.
#pragma once

#include <string>
#include <vector>

#include "ubersim/math.hpp"
#include "ubersim/kernel/model.hpp"

namespace ubersim::kernel {

class World;

/// Inner half-extents of the walled area (x, y), m.
Vec3 WalledHalfExtents(const FieldModel& field);

/// True when a point (x, y) is inside the walled area, corner cuts included, with `margin` m of
/// slack; goals count as inside.
bool InsideWalls(const FieldModel& field, const Vec3& p, double margin);

/// One static box of the field as built: a perimeter or corner wall, or a goal's wall or net.
struct FieldWall {
  std::string name;  ///< its geometry's name ("wall_top", "left_goal_back", …)
  Pose pose;         ///< centre and orientation (field boxes only turn about z), m
  Vec3 size;         ///< full extents along its own x, y, z, m
};

/// Every static box of `world`'s field, in the order they were built.
std::vector<FieldWall> FieldWalls(const World& world);

}  // namespace ubersim::kernel
