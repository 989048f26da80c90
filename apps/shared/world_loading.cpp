// SPDX-License-Identifier: Apache-2.0
#include "shared/world_loading.hpp"

#include "ubersim/kernel/data_paths.hpp"

namespace ubersim::apps {

namespace fs = std::filesystem;
using kernel::ModelLoader;
using kernel::PluginRegistry;

fs::path WorldFileOf(const std::string& arg) {
  const fs::path shipped = kernel::DataDir() / "models" / "worlds" / (arg + ".yaml");
  return !fs::exists(arg) && fs::exists(shipped) ? shipped : fs::path(arg);
}

namespace {

// The plugin folders the world file names (its plugin_paths), read by the model loader with no
// plugin lookup: the world's plugins can be found only once these folders are known.
std::vector<fs::path> WorldPluginPaths(const fs::path& world_file) {
  const ModelLoader without_plugins(ModelLoader::DefaultSchemaDir(), nullptr);
  return without_plugins.LoadWorld(world_file).plugin_paths;
}

}  // namespace

WorldLoading LoadingFor(const std::vector<fs::path>& worlds, const std::vector<std::string>& plugin_paths,
                        bool lenient) {
  std::vector<fs::path> search;
  for (const fs::path& world : worlds) {
    try {
      for (const fs::path& p : WorldPluginPaths(world)) search.push_back(p);
    } catch (const std::exception&) {
      if (!lenient) throw;  // rethrown as it was: its exit code is its own
    }
  }
  search.insert(search.end(), plugin_paths.begin(), plugin_paths.end());
  auto registry = std::make_unique<PluginRegistry>(PluginRegistry::DefaultSearchPaths(search));
  PluginRegistry* r = registry.get();
  ModelLoader loader(ModelLoader::DefaultSchemaDir(),
                     [r](PluginKind kind, const std::string& id) { return r->Find(kind, id).schema_json; });
  return WorldLoading{std::move(registry), std::move(loader)};
}

LoadedWorld LoadWorldWithPlugins(const fs::path& file, const std::vector<std::string>& plugin_paths) {
  WorldLoading loading = LoadingFor({file}, plugin_paths);
  kernel::WorldModel model = loading.loader.LoadWorld(file);
  return LoadedWorld{std::move(loading), std::move(model)};
}

}  // namespace ubersim::apps
