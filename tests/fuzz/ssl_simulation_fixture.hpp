// SPDX-License-Identifier: Apache-2.0
// What the ssl_simulation fuzz targets share: the transport's bridge after one published step of
// the fuzz world, and the mapping options the transport derives from it.
#pragma once

#include <cstddef>

#include "fuzz_world.hpp"
#include "mapping.hpp"
#include "sim_bridge.hpp"

namespace ubersim::fuzz {

/// The transport's default max_message_size, bytes.
constexpr std::size_t kMaxMessage = 16384;

/// The bridge as the simulation thread leaves it after publishing Snapshot().
inline const ssl_simulation::SimBridge& Bridge() {
  static ssl_simulation::SimBridge bridge;
  static const bool published = (bridge.OnPublish(Snapshot()), true);
  (void)published;
  return bridge;
}

/// Where a robot is, as the transport asks once a state is known.
inline ssl_simulation::Presence Where(const RobotId& id) {
  if (!Bridge().Exists(id)) return ssl_simulation::Presence::kAbsent;
  return Bridge().OnField(id) ? ssl_simulation::Presence::kOnField : ssl_simulation::Presence::kOffField;
}

/// The mapping options of a world file that keeps the default wheel order (`wheels` true) or
/// switches wheel_velocity off.
inline ssl_simulation::MappingOptions Options(bool wheels) {
  ssl_simulation::MappingOptions o;
  if (!wheels) o.wheel_order.clear();
  o.ball_radius = Bridge().BallRadius();
  return o;
}

}  // namespace ubersim::fuzz
