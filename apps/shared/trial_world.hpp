// SPDX-License-Identifier: Apache-2.0
// Trial worlds: a world file as bench, batch and soak run it (other physics, one robot for all).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "ubersim/kernel/model.hpp"

namespace ubersim::apps {

using kernel::ModelLoader;
using kernel::PhysicsOverrides;
using kernel::WorldModel;

/// A world file as bench and batch run it: other physics settings, and every robot replaced by
/// `robot_file` when given. Its transports are left as the file has them.
WorldModel LoadTrialWorld(const ModelLoader& loader, const std::filesystem::path& file,
                          const PhysicsOverrides& physics, const std::optional<std::string>& robot_file);

/// The most robots PlaceRobots puts on a field: ids 0..15 in each team, as in the SSL.
constexpr int kMaxTrialRobots = 32;

/// Puts `count` robots on `model`'s field instead of its own (bench's scaling with the robots):
/// blue ids 0.. in the half x < 0 facing +x, yellow in the other, a team the first half of the
/// count (blue one more when it is odd), each team on an even grid over its half outside the
/// centre circle, so none starts inside another. Each robot takes its team's model from the
/// world's first robot of that team, else `teams:`, else any robot's. Throws
/// std::invalid_argument when count is outside 1..kMaxTrialRobots or the grid's cells would be
/// too small for the robots.
void PlaceRobots(WorldModel& model, int count);

}  // namespace ubersim::apps
