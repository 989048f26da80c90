// SPDX-License-Identifier: Apache-2.0
#pragma once

#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/scene_graph.hpp"

namespace ubersim::kernel {

/// Builds the field into `node`: the carpet (a plane at z = 0), the perimeter walls (with angled
/// corner walls when the model cuts corners) and both goals (side walls, back wall, roof net),
/// all static. The field's centre is the origin, x along its length.
void BuildField(const FieldModel& field, NodeImpl& node);

/// Inner half-extents of the walled area (x, y), m.
Vec3 WalledHalfExtents(const FieldModel& field);

/// True when a point (x, y) is inside the walled area, corner cuts included, with `margin` m of
/// slack; goals count as inside.
bool InsideWalls(const FieldModel& field, const Vec3& p, double margin);

/// Builds the ball into `node` as a sphere body resting at `position` (z = 0: on the carpet).
BodyImpl& BuildBall(const BallModel& ball, const Vec3& position, NodeImpl& node);

}  // namespace ubersim::kernel
