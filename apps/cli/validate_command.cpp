// SPDX-License-Identifier: Apache-2.0
// `ubersim validate FILE…`: checks model files against their schemas and their plugins' schemas,
// then builds what they describe (without network) so that every plugin's Configure runs: what
// validate accepts, run accepts.
#include <algorithm>
#include <iostream>
#include <string>
#include <vector>

#include "shared/trial_world.hpp"
#include "ubersim/kernel/data_paths.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/world.hpp"

#include "command_line.hpp"
#include "commands.hpp"
#include "exit_codes.hpp"
#include "world_loading.hpp"

namespace ubersim::cli {

namespace po = boost::program_options;

namespace {

// Builds the world `file` describes (a world file: itself; a robot file: the default world with
// every robot built from it), transports left out, so every robot plugin's Configure runs. Throws
// what building throws (PluginError for a Configure that refuses or throws).
void Build(const std::string& kind, const std::string& file, WorldLoading& loading) {
  kernel::WorldModel model;
  if (kind == "world") {
    model = loading.loader.LoadWorld(file);
  } else if (kind == "robot") {
    model = apps::LoadTrialWorld(loading.loader, kernel::DefaultWorldFile(), {}, file);
  } else {
    return;  // a field or ball file: nothing of a plugin's to run
  }
  model.transports.clear();
  kernel::StreamLog log(std::cerr, LogLevel::kError);
  kernel::World world(model, *loading.registry, log, /*start_transports=*/false);
}

}  // namespace

int ValidateCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim validate FILE… [options]\n\n"
      "Checks each model file (its kind: world, field, ball or robot) and the files it names\n"
      "against the schemas and the plugins' own schemas; prints file:line:column: key: reason\n"
      "for each problem. Then builds what a world or robot file describes (a robot file: in the\n"
      "default world), without network, so that every robot plugin's Configure runs: a plugin\n"
      "refusing its parameters is reported as `run` would report it. Exit code 3 when a file is\n"
      "invalid, 4 when a plugin refuses it.\n\noptions");
  std::vector<std::string> files, plugin_paths;
  bool no_build = false;
  desc.add_options()("help,h", "this help")
      ("no-build", po::bool_switch(&no_build), "only check the files against the schemas; build nothing")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR for plugins (repeatable)");
  po::options_description hidden;
  hidden.add_options()("file", po::value<std::vector<std::string>>(&files));
  po::positional_options_description pos;
  pos.add("file", -1);
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "validate", desc, vm, &hidden, &pos)) return *done;
  if (files.empty()) {
    std::cerr << "ubersim validate: name at least one file\n\n" << desc << "\n";
    return kExitUsage;
  }
  int status = kExitOk;
  for (const std::string& f : files) {
    try {
      // Any file: a world's plugin_paths are searched, any other kind is validated below.
      WorldLoading loading = LoadingFor({f}, plugin_paths, /*lenient=*/true);
      const std::string kind = loading.loader.Validate(f);
      if (!no_build) Build(kind, f, loading);
      std::cout << "ok: " << f << " (" << kind << (no_build ? ", not built" : "") << ")\n";
    } catch (const kernel::ModelError& e) {
      status = std::max(status, ExitCodeFor(std::current_exception()));
      std::cout << e.what() << "\n";  // it names the file, line and column
    } catch (const std::exception& e) {
      status = std::max(status, ExitCodeFor(std::current_exception()));
      std::cout << f << ": " << DescribeError(std::current_exception()) << "\n";
    }
  }
  return status;
}

}  // namespace ubersim::cli
