// SPDX-License-Identifier: Apache-2.0
// The commands of `ubersim`: the table main looks a command up in and `ubersim --help` lists,
// and each command's entry point (one file each: run_command.cpp, validate_command.cpp, …).
#pragma once

#include <string>
#include <vector>

namespace ubersim::cli {

/// A command's entry point: the arguments after its name; returns the exit code (exit_codes.hpp).
/// An exception out of it is mapped to its exit code in one place (RunGuarded, called by main).
using CommandFn = int (*)(const std::vector<std::string>& args);

/// One first word of the command line.
struct Command {
  const char* name;       ///< what is typed: "run"
  const char* arguments;  ///< its arguments as the help shows them: "[WORLD]"
  const char* summary;    ///< its line in `ubersim --help`; nullptr: not listed (--help, --version)
  CommandFn run;          ///< runs it
};

/// Every command, in the order `ubersim --help` lists them, then --help, -h, help and --version.
const std::vector<Command>& Commands();

/// The command called `name`, or nullptr.
const Command* FindCommand(const std::string& name);

/// `ubersim --help`: what ÜberSim is, the commands with their summaries, the exit codes.
std::string TopHelp();

/// `ubersim run [WORLD]`: runs a world in real time (run_command.cpp).
int RunCommand(const std::vector<std::string>& args);
/// `ubersim validate FILE…`: checks model files (validate_command.cpp).
int ValidateCommand(const std::vector<std::string>& args);
/// `ubersim plugins`: lists the plugins found in the search path (plugins_command.cpp).
int PluginsCommand(const std::vector<std::string>& args);
/// `ubersim validate-physics`: runs the physics validation scenarios (validate_physics_command.cpp).
int ValidatePhysicsCommand(const std::vector<std::string>& args);
/// `ubersim bench [WORLD…]`: measures worlds against bare ODE (bench_command.cpp).
int BenchCommand(const std::vector<std::string>& args);
/// `ubersim batch [WORLD…]`: many seeded worlds on worker processes (batch_command.cpp).
int BatchCommand(const std::vector<std::string>& args);
/// `ubersim soak [WORLD]`: a long run under random play and teleports (soak_command.cpp).
int SoakCommand(const std::vector<std::string>& args);
/// `ubersim match [WORLD] --yellow CMD --blue CMD`: a refereed match between two programs (match_command.cpp).
int MatchCommand(const std::vector<std::string>& args);
/// `ubersim replay FILE`: plays an SSL log file onto the league's multicast groups (replay_command.cpp).
int ReplayCommand(const std::vector<std::string>& args);
/// `ubersim calibrate LOG…`: fits model files to a field's log (calibrate_command.cpp).
int CalibrateCommand(const std::vector<std::string>& args);
/// `ubersim --help`: prints TopHelp (commands.cpp).
int HelpCommand(const std::vector<std::string>& args);
/// `ubersim --version`: the version, the SDK's and the plugin ABI's (commands.cpp).
int VersionCommand(const std::vector<std::string>& args);

}  // namespace ubersim::cli
