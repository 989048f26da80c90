// SPDX-License-Identifier: Apache-2.0
// `ubersim validate-physics`: the physics validation scenarios against their published bands,
// with the report and its plots.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "ubersim/kernel/data_paths.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/validation/report.hpp"
#include "ubersim/validation/scenarios.hpp"
#include "command_line.hpp"
#include "commands.hpp"
#include "exit_codes.hpp"
#include "world_loading.hpp"

namespace ubersim::cli {
namespace {

namespace po = boost::program_options;
namespace fs = std::filesystem;

// The scenarios `only` names (all when none); an unknown id is a usage error.
std::vector<const validation::Scenario*> ChosenScenarios(const std::vector<std::string>& only) {
  std::vector<const validation::Scenario*> chosen;
  try {
    for (const std::string& id : only) chosen.push_back(&validation::FindScenario(id));
  } catch (const std::out_of_range& e) {
    throw UsageError(e.what());
  }
  if (chosen.empty()) {
    for (const auto& s : validation::AllScenarios()) chosen.push_back(&s);
  }
  return chosen;
}

// Runs one scenario and prints its line and each number outside its band; returns its result.
validation::ScenarioResult RunScenario(const validation::Scenario& s, const validation::Environment& env,
                                       int& out_of_band) {
  const auto t0 = std::chrono::steady_clock::now();
  validation::ScenarioResult r = s.run(env);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  int ok = 0;
  for (const auto& m : r.metrics) ok += m.Pass() ? 1 : 0;
  std::printf("%-4s %-24s %d/%zu in band  (%.1f s)\n", r.Pass() ? "ok" : "OUT", r.id.c_str(), ok, r.metrics.size(),
              seconds);
  for (const auto& m : r.metrics) {
    if (m.Pass()) continue;
    ++out_of_band;
    std::printf("       %s = %.4g %s, band %.4g … %.4g (%s)\n", m.name.c_str(), m.value, m.unit.c_str(), m.low, m.high,
                m.basis.c_str());
  }
  std::fflush(stdout);
  return r;
}

}  // namespace

int ValidatePhysicsCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim validate-physics [options]\n\n"
      "Runs the physics validation scenarios (ball slide/roll, chip flight and bounces, shots\n"
      "against robots and walls, drives, dribbler, kicker, the 2003 paper's experiments) on the\n"
      "shipped model files, prints each number against its published band, and writes a report\n"
      "(README.md) with SVG plots. Exit code 5 when a number is outside its band.\n\noptions");
  std::string out = "docs/validation";
  std::vector<std::string> only, plugin_paths;
  std::string robot_file;
  PhysicsFlags physics_flags;
  desc.add_options()("help,h", "this help")
      ("out", po::value<std::string>(&out)->default_value(out), "folder for README.md and the plots")
      ("only", po::value<std::vector<std::string>>(&only), "run only scenario ID (repeatable)")
      ("list", "list the scenarios and exit")
      ("robot", po::value<std::string>(&robot_file),
       "run the drive, kicker and dribbler scenarios on robot FILE instead, against its own limits (needs --out)")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR for plugins (repeatable)");
  physics_flags.AddTo(desc);  // other settings need --out: the default folder is the shipped report
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "validate-physics", desc, vm)) return *done;
  kernel::PhysicsOverrides physics;
  if (!physics_flags.Read(vm, "validate-physics", physics)) return kExitUsage;
  if (!robot_file.empty() && vm["out"].defaulted()) {
    std::cerr << "ubersim validate-physics: give --out DIR with --robot (" << out
              << " holds the report of the shipped models)\n";
    return kExitUsage;
  }
  if (physics.Any() && vm["out"].defaulted()) {
    std::cerr << "ubersim validate-physics: give --out DIR when trying other physics settings ("
              << out << " holds the report of the shipped settings)\n";
    return kExitUsage;
  }
  if (vm.count("list")) {
    for (const auto& s : validation::AllScenarios()) std::printf("%-24s %s\n", s.id.c_str(), s.title.c_str());
    return kExitOk;
  }
  std::ostringstream warnings;
  kernel::StreamLog log(warnings, LogLevel::kWarning);
  const WorldLoading loading = LoadingFor({}, plugin_paths);  // the scenarios' worlds are the shipped ones
  validation::Environment env{kernel::DataDir() / "models", kernel::ModelLoader::DefaultSchemaDir(),
                              loading.registry.get(), &log, physics};
  std::vector<validation::Scenario> robot_scenarios;
  std::vector<const validation::Scenario*> chosen;
  if (!robot_file.empty()) {
    robot_scenarios = validation::RobotScenarios(env, robot_file);
    for (const auto& s : robot_scenarios) chosen.push_back(&s);
  } else {
    chosen = ChosenScenarios(only);
  }
  std::vector<validation::ScenarioResult> results;
  int out_of_band = 0;
  for (const validation::Scenario* s : chosen) results.push_back(RunScenario(*s, env, out_of_band));
  validation::WriteReport(out, results, CommandLineText("validate-physics", args));
  std::printf("report: %s\n", (fs::path(out) / "README.md").string().c_str());
  if (!warnings.str().empty()) std::cerr << warnings.str();
  return out_of_band ? kExitOutOfBand : kExitOk;
}

}  // namespace ubersim::cli
