// SPDX-License-Identifier: Apache-2.0
// Building the field (carpet, walls, goals) and the ball into the scene graph.
#pragma once

#include "ubersim/kernel/field.hpp"
#include "ubersim/kernel/model.hpp"
#include "physics/scene_graph.hpp"

namespace ubersim::kernel {

/// Builds the field into `node`: the carpet (a plane at z = 0), the perimeter walls (with angled
/// corner walls when the model cuts corners) and both goals (side walls, back wall, roof net),
/// all static. The field's centre is the origin, x along its length.
void BuildField(const FieldModel& field, NodeImpl& node);

/// Builds the ball into `node` as a sphere body resting at `position` (z = 0: on the carpet).
BodyImpl& BuildBall(const BallModel& ball, const Vec3& position, NodeImpl& node);

}  // namespace ubersim::kernel
