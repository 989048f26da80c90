// SPDX-License-Identifier: Apache-2.0
#include "exit_codes.hpp"

#include <iostream>

#include "ubersim/error.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"
#include "ubersim/kernel/snapshot.hpp"
#include "run_overrides.hpp"

namespace ubersim::cli {
namespace {

// An exception's exit code and the words put before its message.
struct Mapped {
  int code;
  const char* prefix;
  std::string what;
};

// The map: each kind of error the commands let out, its code and how it is introduced.
Mapped Map(std::exception_ptr error) {
  try {
    std::rethrow_exception(error);
  } catch (const UsageError& e) {
    return {kExitUsage, "", e.what()};
  } catch (const kernel::OverrideError& e) {  // run: a flag that does not fit the world
    return {kExitUsage, "", e.what()};
  } catch (const kernel::PluginLookupError& e) {  // a model file names a plugin not found or refused
    return {kExitPlugin, "plugin error: ", e.what()};
  } catch (const kernel::ModelError& e) {
    return {kExitModel, "invalid model: ", e.what()};
  } catch (const ParamError& e) {  // a model file's parameter missing or of the wrong type
    return {kExitModel, "invalid model: ", e.what()};
  } catch (const kernel::PluginLoadError& e) {  // not found, refused by the loader, constructor threw
    return {kExitPlugin, "plugin error: ", e.what()};
  } catch (const PluginError& e) {  // refused its parameters, failed to configure or start
    return {kExitPlugin, "plugin error: ", e.what()};
  } catch (const kernel::SnapshotError& e) {
    return {kExitRuntime, "snapshot: ", e.what()};
  } catch (const std::exception& e) {
    return {kExitRuntime, "", e.what()};
  } catch (...) {
    return {kExitRuntime, "", "an exception that is not a std::exception"};
  }
}

}  // namespace

int ExitCodeFor(std::exception_ptr error) { return Map(error).code; }

std::string DescribeError(std::exception_ptr error) {
  const Mapped m = Map(error);
  return m.prefix + m.what;
}

int RunGuarded(const std::string& command, const std::function<int()>& body) {
  try {
    return body();
  } catch (...) {
    std::cerr << "ubersim " << command << ": " << DescribeError(std::current_exception()) << "\n";
    return ExitCodeFor(std::current_exception());
  }
}

const char* ExitCodesHelp() {
  return "exit codes: 0 ok, 1 runtime error, 2 bad usage, 3 invalid model file, 4 plugin error,\n"
         "            5 a validated physics number outside its band, 6 soak: a state-check finding\n"
         "            or memory growth, 7 run: a plugin fault stopped the world (crash report\n"
         "            and snapshot written), 8 match: a team's program ended or stopped sending\n"
         "            commands (the result file says which), 9 calibrate: too little data in the log\n"
         "            to fit anything (the report says what is missing)\n";
}

}  // namespace ubersim::cli
