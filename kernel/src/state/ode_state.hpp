// SPDX-License-Identifier: Apache-2.0
// What ODE carries from one step to the next, read from and written back to a scene graph.
//
// Between two steps ODE keeps: every body's position, quaternion and rotation matrix, velocities,
// accumulated force and torque, and enabled flag; every joint's motor settings and last feedback;
// the collision space's internal order of its geometries (which decides the order of the pairs
// it reports, hence of the contact joints, hence the solver's rows); and the random generator
// QuickStep reorders constraints with (the world keeps that one). It keeps no contact joints
// (the kernel empties them after every step), no solver warm start (ODE 0.16 builds without
// WARM_STARTING) and no auto-disable counters (every world turns auto-disable off). Joint frames
// are fixed when a joint is made, from the bodies' build poses, which a fresh build repeats.
#pragma once

#include <cstdint>

#include "physics/scene_graph.hpp"
#include "ubersim/kernel/snapshot.hpp"

namespace ubersim::kernel {

/// Reads every body, joint and geometry of `graph` (scene-graph order) and the collision
/// space's move order into `out` (bodies, joints, geom_collides, moved_bodies).
void CaptureOdeState(const SceneGraph& graph, SavedState& out);

/// Writes what CaptureOdeState read into `graph`, a fresh build of the same model: doubles bit
/// for bit, and the collision space's order as the original had it. Throws SnapshotError when
/// the bodies, joints or geometries differ from the saved ones (naming the first difference).
void ApplyOdeState(SceneGraph& graph, const SavedState& in);

/// A digest of the scene's structure: every node, body (name and mass), joint (name and kind)
/// and geometry (name and shape kind), in order. Equal for two builds of the same model.
std::uint64_t SceneDigest(const SceneGraph& graph);

}  // namespace ubersim::kernel
