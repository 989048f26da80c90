// SPDX-License-Identifier: Apache-2.0
// What the commands share in reading their command lines: parsing against their options (with
// --help and usage errors handled alike) and the physics flags several of them take.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <boost/program_options.hpp>

#include "ubersim/kernel/model.hpp"
#include "ubersim/log.hpp"

namespace ubersim::cli {

/// Parses a command's `args` against `desc`, plus `hidden` and `positional` for its positional
/// arguments. Returns the exit code when the command ends here (a usage error: the message and
/// the options; --help: the options), nothing when it goes on.
std::optional<int> ParseCommandLine(const std::vector<std::string>& args, const char* command,
                                    const boost::program_options::options_description& desc,
                                    boost::program_options::variables_map& vm,
                                    const boost::program_options::options_description* hidden = nullptr,
                                    const boost::program_options::positional_options_description* positional = nullptr);

/// --vision-port, --control-port, --blue-port, --yellow-port, --grsim-port, --viewer-port: the
/// transports' ports of the commands that start them (run, match).
void AddPortFlags(boost::program_options::options_description& desc);
/// The port flags given, by name without "-port" ("vision" → 10006), into `ports`.
void ReadPortFlags(const boost::program_options::variables_map& vm, std::map<std::string, int>& ports);

/// The --log-level: debug, info, warning or error; throws UsageError for another word.
LogLevel LogLevelOf(const std::string& name);

/// "ubersim COMMAND ARGS…": the command line as typed, for reports.
std::string CommandLineText(const std::string& command, const std::vector<std::string>& args);

/// --profile, --physics-step, --solver-iterations, --solver-iterations-without-ball,
/// --max-contacts: one meaning and one check for every command that tries other physics settings
/// than the world files'.
struct PhysicsFlags {
  std::string profile;              ///< --profile
  double step = 0;                  ///< --physics-step
  int iterations = 0;               ///< --solver-iterations
  int iterations_without_ball = 0;  ///< --solver-iterations-without-ball
  int contacts = 0;                 ///< --max-contacts

  /// Adds the five flags to `desc`.
  void AddTo(boost::program_options::options_description& desc);
  /// Why the flags given cannot be used (an unknown profile, a value out of range), or nothing.
  std::optional<std::string> Problem(const boost::program_options::variables_map& vm) const;
  /// The settings given; false (with the reason on stderr) when one is out of range.
  bool Read(const boost::program_options::variables_map& vm, const std::string& command,
            kernel::PhysicsOverrides& out) const;
};

}  // namespace ubersim::cli
