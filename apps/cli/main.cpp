// SPDX-License-Identifier: Apache-2.0
// The `ubersim` command: looks the first word up in the command table (commands.hpp) and runs
// that command; an error out of it gets its exit code from the one map (exit_codes.hpp).
#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "exit_codes.hpp"

int main(int argc, char** argv) {
  using namespace ubersim::cli;
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) {
    std::cout << TopHelp();
    return kExitUsage;
  }
  const Command* command = FindCommand(args[0]);
  if (!command) {
    std::cerr << "ubersim: unknown command '" << args[0] << "'\n\n" << TopHelp();
    return kExitUsage;
  }
  args.erase(args.begin());
  return RunGuarded(command->name, [&] { return command->run(args); });
}
