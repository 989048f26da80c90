// SPDX-License-Identifier: Apache-2.0
#include "commands.hpp"

#include <algorithm>
#include <iostream>

#include "ubersim/version.hpp"
#include "exit_codes.hpp"

namespace ubersim::cli {
namespace {

// Width of the first column of the command list, in characters (not bytes: "…" is one).
constexpr std::size_t kNameColumn = 17;

// The characters of UTF-8 `text` (its bytes less the continuation bytes).
std::size_t Characters(const std::string& text) {
  std::size_t n = 0;
  for (const char c : text) n += (static_cast<unsigned char>(c) & 0xC0) != 0x80 ? 1 : 0;
  return n;
}

}  // namespace

const std::vector<Command>& Commands() {
  static const std::vector<Command> commands = {
      {"run", "[WORLD]", "run a world (default: models/worlds/div-b.yaml) in real time", RunCommand},
      {"validate", "FILE…", "check model files (world, field, ball, robot) against their schemas", ValidateCommand},
      {"plugins", "", "list every plugin found in the plugin search path", PluginsCommand},
      {"validate-physics", "", "run the physics validation scenarios, write the report and plots",
       ValidatePhysicsCommand},
      {"bench", "[WORLD…]", "step worlds as fast as possible and measure them against bare ODE", BenchCommand},
      {"batch", "[WORLD…]", "run many seeded worlds at once on worker processes", BatchCommand},
      {"soak", "[WORLD]", "run a world for long under random play and teleports, checking its state", SoakCommand},
      {"match", "[WORLD] --yellow CMD --blue CMD", "a refereed match between two teams' programs; writes the result as JSON", MatchCommand},
      {"replay", "FILE", "play an SSL log file (.log, .log.gz) onto the league's multicast groups", ReplayCommand},
      {"calibrate", "LOG…", "fit ball, robot and camera models to a field's SSL log; writes model files and a report", CalibrateCommand},
      {"--help", "", nullptr, HelpCommand},
      {"-h", "", nullptr, HelpCommand},
      {"help", "", nullptr, HelpCommand},
      {"--version", "", nullptr, VersionCommand},
  };
  return commands;
}

const Command* FindCommand(const std::string& name) {
  for (const Command& c : Commands()) {
    if (name == c.name) return &c;
  }
  return nullptr;
}

std::string TopHelp() {
  std::string help =
      "ÜberSim — RoboCup Small Size League simulator\n"
      "\n"
      "usage: ubersim <command> [options]\n"
      "\n"
      "commands:\n";
  for (const Command& c : Commands()) {
    if (!c.summary) continue;
    std::string left = std::string(c.name) + (*c.arguments ? std::string(" ") + c.arguments : "");
    left += std::string(kNameColumn - std::min(kNameColumn - 1, Characters(left)), ' ');
    help += "  " + left + c.summary + "\n";
  }
  help += "\n`ubersim <command> --help` describes a command's options.\n";
  return help + ExitCodesHelp();
}

int HelpCommand(const std::vector<std::string>&) {
  std::cout << TopHelp();
  return kExitOk;
}

int VersionCommand(const std::vector<std::string>&) {
  std::cout << "ubersim " << UBERSIM_VERSION << " (SDK " << kSdkVersionMajor << "." << kSdkVersionMinor
            << ", plugin ABI " << kPluginAbiVersion << ")\n";
  return kExitOk;
}

}  // namespace ubersim::cli
