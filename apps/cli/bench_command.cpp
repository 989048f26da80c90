// SPDX-License-Identifier: Apache-2.0
// `ubersim bench [WORLD…]`: steps worlds headless as fast as possible under random play and
// measures them, and the same bodies stepped with ODE alone.
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "ubersim/kernel/data_paths.hpp"
#include "ubersim/kernel/logging.hpp"
#include "bench.hpp"
#include "command_line.hpp"
#include "commands.hpp"
#include "exit_codes.hpp"
#include "progress.hpp"
#include "world_loading.hpp"

namespace ubersim::cli {
namespace {

namespace po = boost::program_options;
namespace bench = kernel::bench;

}  // namespace

int BenchCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim bench [WORLD…] [options]\n\n"
      "Steps each WORLD (a file, or a shipped world's name; default: ssl-2003 div-b div-a)\n"
      "headless and as fast as possible\n"
      "for a fixed simulated time, every robot driving seeded random commands and the ball in\n"
      "play, and prints per world: real-time factor, steps per second, where the time goes, peak\n"
      "memory, and the kernel's overhead over the same bodies, joints and contacts stepped with\n"
      "ODE alone (docs/performance.md).\n\noptions");
  double duration = 10.0;
  std::uint64_t seed = 1;
  PhysicsFlags physics_flags;
  std::string robot, markdown;
  std::vector<std::string> worlds, plugin_paths;
  desc.add_options()("help,h", "this help")
      ("duration", po::value<double>(&duration)->default_value(duration), "simulated seconds per world")
      ("seed", po::value<std::uint64_t>(&seed)->default_value(seed), "seed of the random play")
      ("no-baseline", "skip the bare-ODE baseline")
      ("robot", po::value<std::string>(&robot), "put this robot model file in every robot's place")
      ("markdown", po::value<std::string>(&markdown), "also write the results as Markdown to FILE")
      ("with-transports", "also start the worlds' transports (viewer, SSL-Vision, …), to measure what publishing costs; their ports must be free")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR for plugins (repeatable)");
  physics_flags.AddTo(desc);
  po::options_description hidden;
  hidden.add_options()("world", po::value<std::vector<std::string>>(&worlds));
  po::positional_options_description pos;
  pos.add("world", -1);
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "bench", desc, vm, &hidden, &pos)) return *done;
  if (!(duration > 0)) {
    std::cerr << "ubersim bench: --duration must be > 0\n";
    return kExitUsage;
  }
  bench::BenchOptions options;
  if (!physics_flags.Read(vm, "bench", options.physics)) return kExitUsage;
  options.sim_seconds = duration;
  options.seed = seed;
  options.baseline = vm.count("no-baseline") == 0;
  if (vm.count("robot")) options.robot_model = robot;
  options.with_transports = vm.count("with-transports") > 0;
  if (worlds.empty()) {
    for (const char* w : {"ssl-2003", "div-b", "div-a"}) {
      options.worlds.push_back(kernel::DataDir() / "models" / "worlds" / (std::string(w) + ".yaml"));
    }
  } else {
    for (const std::string& w : worlds) options.worlds.push_back(WorldFileOf(w));
  }
  std::ostringstream warnings;
  // Random commands draw warnings (a diff robot told to strafe): expected here, not shown.
  kernel::StreamLog log(warnings, LogLevel::kError);
  const WorldLoading loading = LoadingFor(options.worlds, plugin_paths);
  ProgressLine progress;
  const auto results = bench::RunBench(options, *loading.registry, loading.loader, log,
                                       [&](const std::string& world, double f) {
                                         progress.Redraw(world + " " + Bar(f) + " " +
                                                         std::to_string(static_cast<int>(f * 100)) + " %");
                                       });
  progress.Clear();
  std::cout << bench::FormatTable(results);
  std::cout << "machine: " << bench::MachineDescription() << "\n";
  std::cout << "process peak resident memory: " << bench::PeakResidentMegabytes() << " MB\n";
  if (!markdown.empty()) {
    std::ofstream(markdown) << bench::FormatMarkdown(results, bench::MachineDescription(),
                                                     CommandLineText("bench", args));
    std::cout << "markdown: " << markdown << "\n";
  }
  if (!warnings.str().empty()) std::cerr << warnings.str();
  return kExitOk;
}

}  // namespace ubersim::cli
