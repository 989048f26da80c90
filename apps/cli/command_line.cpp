// SPDX-License-Identifier: Apache-2.0
#include "command_line.hpp"

#include <algorithm>
#include <iostream>

#include "exit_codes.hpp"

namespace ubersim::cli {

namespace po = boost::program_options;

std::optional<int> ParseCommandLine(const std::vector<std::string>& args, const char* command,
                                    const po::options_description& desc, po::variables_map& vm,
                                    const po::options_description* hidden,
                                    const po::positional_options_description* positional) {
  po::options_description all;
  all.add(desc);
  if (hidden) all.add(*hidden);
  try {
    po::command_line_parser parser(args);
    parser.options(all);
    if (positional) parser.positional(*positional);
    po::store(parser.run(), vm);
    po::notify(vm);
  } catch (const std::exception& e) {
    std::cerr << "ubersim " << command << ": " << e.what() << "\n\n" << desc << "\n";
    return kExitUsage;
  }
  if (vm.count("help")) {
    std::cout << desc << "\n";
    return kExitOk;
  }
  return std::nullopt;
}

std::string CommandLineText(const std::string& command, const std::vector<std::string>& args) {
  std::string text = "ubersim " + command;
  for (const std::string& a : args) text += " " + a;
  return text;
}

void AddPortFlags(po::options_description& desc) {
  desc.add_options()
      ("vision-port", po::value<int>(), "SSL-Vision multicast port (default 10020; 10006 as real ssl-vision)")
      ("control-port", po::value<int>(), "simulation protocol: SimulatorCommand port (default 10300)")
      ("blue-port", po::value<int>(), "simulation protocol: blue team's RobotControl port (default 10301)")
      ("yellow-port", po::value<int>(), "simulation protocol: yellow team's RobotControl port (default 10302)")
      ("grsim-port", po::value<int>(), "grSim protocol command port (default 20011)")
      ("viewer-port", po::value<int>(), "browser viewer port (default 8080)");
}

void ReadPortFlags(const po::variables_map& vm, std::map<std::string, int>& ports) {
  for (const char* port : {"vision", "control", "blue", "yellow", "grsim", "viewer"}) {
    const std::string flag = std::string(port) + "-port";
    if (vm.count(flag)) ports[port] = vm[flag].as<int>();
  }
}

LogLevel LogLevelOf(const std::string& name) {
  if (name == "debug") return LogLevel::kDebug;
  if (name == "info") return LogLevel::kInfo;
  if (name == "warning") return LogLevel::kWarning;
  if (name == "error") return LogLevel::kError;
  throw UsageError("unknown --log-level '" + name + "'");
}

void PhysicsFlags::AddTo(po::options_description& desc) {
  std::string names;
  for (const std::string& n : kernel::PhysicsProfileNames()) names += (names.empty() ? "" : ", ") + n;
  desc.add_options()
      ("profile", po::value<std::string>(&profile),
       ("physics profile instead of the world files' (" + names + "); keys a world file sets itself still apply").c_str())
      ("physics-step", po::value<double>(&step), "instead of the world files' physics step, s")
      ("solver-iterations", po::value<int>(&iterations), "instead of the world files' QuickStep iterations")
      ("solver-iterations-without-ball", po::value<int>(&iterations_without_ball),
       "QuickStep iterations of the islands no ball belongs to (default: --solver-iterations)")
      ("max-contacts", po::value<int>(&contacts), "instead of the world files' contacts per geometry pair");
}

std::optional<std::string> PhysicsFlags::Problem(const po::variables_map& vm) const {
  if (vm.count("profile")) {
    const auto& names = kernel::PhysicsProfileNames();
    if (std::find(names.begin(), names.end(), profile) == names.end()) {
      std::string list;
      for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
      return "no physics profile '" + profile + "' (there are: " + list + ")";
    }
  }
  if ((vm.count("physics-step") && !(step > 0 && step <= 0.02)) || (vm.count("solver-iterations") && iterations < 1) ||
      (vm.count("solver-iterations-without-ball") && iterations_without_ball < 1) ||
      (vm.count("max-contacts") && (contacts < 1 || contacts > 16))) {
    return "0 < --physics-step <= 0.02, --solver-iterations >= 1, --solver-iterations-without-ball >= 1, "
           "--max-contacts 1..16";
  }
  return std::nullopt;
}

bool PhysicsFlags::Read(const po::variables_map& vm, const std::string& command, kernel::PhysicsOverrides& out) const {
  if (const auto why = Problem(vm)) {
    std::cerr << "ubersim " << command << ": " << *why << "\n";
    return false;
  }
  if (vm.count("profile")) out.profile = profile;
  if (vm.count("physics-step")) out.step = step;
  if (vm.count("solver-iterations")) out.solver_iterations = iterations;
  if (vm.count("solver-iterations-without-ball")) out.solver_iterations_without_ball = iterations_without_ball;
  if (vm.count("max-contacts")) out.max_contacts = contacts;
  return true;
}

}  // namespace ubersim::cli
