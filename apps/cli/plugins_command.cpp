// SPDX-License-Identifier: Apache-2.0
// `ubersim plugins`: the plugin search path, the plugins found in it and the files refused.
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "command_line.hpp"
#include "commands.hpp"
#include "exit_codes.hpp"
#include "world_loading.hpp"

namespace ubersim::cli {

namespace po = boost::program_options;

int PluginsCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim plugins [options]\n\n"
      "Lists every plugin library found in the search path (--plugin-path, $UBERSIM_PLUGIN_PATH,\n"
      "the plugins built beside this executable, the install prefix): id, kind, version, SDK,\n"
      "file; then the libraries it refused and why.\n\noptions");
  std::vector<std::string> plugin_paths;
  desc.add_options()("help,h", "this help")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR (repeatable)");
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "plugins", desc, vm)) return *done;
  const WorldLoading loading = LoadingFor({}, plugin_paths);
  kernel::PluginRegistry& registry = *loading.registry;
  const auto result = registry.Scan();
  std::cout << "search path:\n";
  for (const auto& p : registry.SearchPaths()) std::cout << "  " << p.string() << "\n";
  std::printf("%-24s %-10s %-10s %-5s %s\n", "PLUGIN", "KIND", "VERSION", "SDK", "FILE");
  for (const auto& p : result.plugins) {
    std::printf("%-24s %-10s %-10s %-5s %s\n", p.id.c_str(), ToString(p.kind), p.version.c_str(),
                p.sdk_version.c_str(), p.file.string().c_str());
  }
  if (result.plugins.empty()) std::cout << "(no plugins found)\n";
  for (const auto& problem : result.problems) std::cerr << "refused: " << problem << "\n";
  return result.problems.empty() ? kExitOk : kExitPlugin;
}

}  // namespace ubersim::cli
