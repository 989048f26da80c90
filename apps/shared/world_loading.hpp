// SPDX-License-Identifier: Apache-2.0
// How every command (and the Python package) gets its worlds: the world files named on the command line, the plugin
// registry searching the worlds' own plugin_paths and --plugin-path (docs/cli.md, plugins), and
// the model loader that checks plugin parameters against that registry.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"

namespace ubersim::apps {

/// The plugin registry and the loader that asks it for the plugins' parameter schemas.
struct WorldLoading {
  std::unique_ptr<kernel::PluginRegistry> registry;  ///< on the heap: the loader keeps its address
  kernel::ModelLoader loader;                        ///< checks plugin parameters with `registry`
};

/// One world file loaded, with the registry and loader it was loaded with.
struct LoadedWorld {
  WorldLoading loading;      ///< its plugins and loader
  kernel::WorldModel model;  ///< the world
};

/// A world argument: a file, or the name of a shipped world ("div-a").
std::filesystem::path WorldFileOf(const std::string& arg);

/// The registry searching each world's plugin_paths, then `plugin_paths` (--plugin-path), then
/// the default search path; and its loader. A world that cannot be read throws ModelError, unless
/// `lenient` (validate: any file, the validation then reports it).
WorldLoading LoadingFor(const std::vector<std::filesystem::path>& worlds, const std::vector<std::string>& plugin_paths,
                        bool lenient = false);

/// The world `file` loaded with its plugins (LoadingFor); throws ModelError, PluginLoadError.
LoadedWorld LoadWorldWithPlugins(const std::filesystem::path& file, const std::vector<std::string>& plugin_paths);

}  // namespace ubersim::apps
