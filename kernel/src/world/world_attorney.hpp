// SPDX-License-Identifier: Apache-2.0
// The one door to a World's insides (Drake's "attorney"): the scene graph, the collision manager,
// the ball body and the ODE world, for the kernel's own unit tests, the state checks and the
// bench's bare-ODE mirror. Only targets linking ubersim_kernel_internal can include it.
#pragma once

#include <ode/ode.h>

#include "ubersim/kernel/world.hpp"
#include "collision/collision.hpp"
#include "physics/scene_graph.hpp"
#include "world/world_impl.hpp"

namespace ubersim::kernel {

/// Reaches the few internals of a World that white-box code needs.
class WorldAttorney {
 public:
  /// The world's implementation (everything it owns).
  static WorldImpl& Impl(World& world) { return *world.impl_; }
  /// The world's implementation, read-only.
  static const WorldImpl& Impl(const World& world) { return *world.impl_; }
  /// The scene graph: every node, body, geometry and joint.
  static SceneGraph& Scene(World& world) { return world.impl_->scene(); }
  /// The scene graph, read-only.
  static const SceneGraph& Scene(const World& world) { return world.impl_->scene(); }
  /// The collision manager.
  static CollisionManager& Collision(World& world) { return world.impl_->collision(); }
  /// The ball's body.
  static BodyImpl& Ball(World& world) { return world.impl_->ball(); }
  /// The ODE world.
  static dWorldID OdeWorld(const World& world) { return world.impl_->ode_world(); }
};

}  // namespace ubersim::kernel
