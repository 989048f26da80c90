// SPDX-License-Identifier: Apache-2.0
// `ubersim validate FILE…`: checks model files against their schemas and their plugins' schemas.
#include <algorithm>
#include <iostream>
#include <string>
#include <vector>

#include "command_line.hpp"
#include "commands.hpp"
#include "exit_codes.hpp"
#include "world_loading.hpp"

namespace ubersim::cli {

namespace po = boost::program_options;

int ValidateCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim validate FILE… [options]\n\n"
      "Checks each model file (its kind: world, field, ball or robot) and the files it names\n"
      "against the schemas and the plugins' own schemas; prints file:line:column: key: reason\n"
      "for each problem. Exit code 3 when any file is invalid.\n\noptions");
  std::vector<std::string> files, plugin_paths;
  desc.add_options()("help,h", "this help")
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
      const WorldLoading loading = LoadingFor({f}, plugin_paths, /*lenient=*/true);
      const std::string kind = loading.loader.Validate(f);
      std::cout << "ok: " << f << " (" << kind << ")\n";
    } catch (const kernel::ModelError& e) {
      status = std::max(status, ExitCodeFor(std::current_exception()));
      std::cout << e.what() << "\n";  // it names the file, line and column
    } catch (const std::exception& e) {
      status = std::max(status, ExitCodeFor(std::current_exception()));
      std::cout << f << ": " << e.what() << "\n";
    }
  }
  return status;
}

}  // namespace ubersim::cli
