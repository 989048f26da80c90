// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ubersim/log.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"
#include "ubersim/validation/result.hpp"

namespace ubersim::validation {

/// What a scenario needs: the shipped model files, plugins and a log for warnings.
struct Environment {
  std::filesystem::path models_dir;      ///< folder with fields/, balls/, robots/, worlds/
  std::filesystem::path schema_dir;      ///< folder with the model-file schemas
  kernel::PluginRegistry* registry = nullptr;  ///< finds the robots' plugins
  Log* log = nullptr;                    ///< warnings of the worlds built
  /// Physics settings to try instead of the world files' (`validate-physics --physics-step` …):
  /// every scenario's world gets them, so the bands say whether faster settings keep fidelity.
  kernel::PhysicsOverrides physics;
};

/// A named scenario.
struct Scenario {
  std::string id;                                           ///< e.g. "ball_roll_2"
  std::string title;                                        ///< one line
  std::function<ScenarioResult(const Environment&)> run;    ///< builds its world and measures
};

/// Every scenario, in report order.
const std::vector<Scenario>& AllScenarios();

/// The drive, kicker and dribbler scenarios on a team's own robot file (`validate-physics
/// --robot`): commands and bands scaled to the limits its drive's parameters give; a kicker or
/// dribbler scenario only when it has one. Throws ModelError or PluginLoadError for a bad file.
std::vector<Scenario> RobotScenarios(const Environment& env, const std::filesystem::path& robot_file);
/// The scenario with that id; throws std::out_of_range listing the ids.
const Scenario& FindScenario(const std::string& id);

}  // namespace ubersim::validation
