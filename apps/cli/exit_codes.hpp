// SPDX-License-Identifier: Apache-2.0
// The exit codes of `ubersim` (docs/cli.md) and the one map from an error to its code: every
// command ends through it, so the same error gives the same code whatever the command.
#pragma once

#include <exception>
#include <functional>
#include <stdexcept>
#include <string>

namespace ubersim::cli {

constexpr int kExitOk = 0;           ///< ok
constexpr int kExitRuntime = 1;      ///< runtime error (cannot find models/, a snapshot refused, …)
constexpr int kExitUsage = 2;        ///< bad usage (unknown command or option, bad value)
constexpr int kExitModel = 3;        ///< invalid model file
constexpr int kExitPlugin = 4;       ///< plugin error (not found, refused by the loader, failed to configure or start)
constexpr int kExitOutOfBand = 5;    ///< validate-physics: a number outside its band
constexpr int kExitSoakFailed = 6;   ///< soak: a state-check finding, or memory growth
constexpr int kExitPluginFault = 7;  ///< run: a plugin fault stopped the world (crash report written)
constexpr int kExitTeamFailed = 8;   ///< match: a team's program ended or stopped sending commands
constexpr int kExitTooLittleData = 9;  ///< calibrate: the log holds too little of anything to fit

/// A bad value on the command line, found while a command runs: exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The exit code for `error`: the one map from an exception's type to a code (exit_codes.cpp).
int ExitCodeFor(std::exception_ptr error);

/// What `error` says, prefixed with its kind ("invalid model: …", "plugin error: …").
std::string DescribeError(std::exception_ptr error);

/// Runs `body` and returns its exit code; an exception out of it is printed on stderr as
/// "ubersim COMMAND: " + DescribeError, and ends with ExitCodeFor.
int RunGuarded(const std::string& command, const std::function<int()>& body);

/// The exit codes as `ubersim --help` lists them.
const char* ExitCodesHelp();

}  // namespace ubersim::cli
