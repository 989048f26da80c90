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

}  // namespace ubersim::apps
