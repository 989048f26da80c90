// SPDX-License-Identifier: Apache-2.0
// `ubersim bench [WORLD…]`: steps worlds headless as fast as possible under random play and
// measures them, and the same bodies stepped with ODE alone; with --robot-count or --scaling, how
// a step's cost grows with the robots; with --instructions, its cost counted by callgrind.
#include <algorithm>
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

// The robot counts of --scaling: from a small game to more than Div A's 22.
constexpr int kScalingCounts[] = {2, 6, 12, 22, 32};

// "2,6,12" → {2, 6, 12}; throws UsageError naming `option` on anything else.
template <typename T>
std::vector<T> ParseList(const std::string& text, const std::string& option) {
  std::vector<T> out;
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::istringstream one(item);
    T value{};
    if (!(one >> value) || !(one >> std::ws).eof()) {
      throw UsageError("--" + option + ": '" + text + "' is not a comma-separated list of numbers");
    }
    out.push_back(value);
  }
  if (out.empty()) throw UsageError("--" + option + ": empty list");
  return out;
}

}  // namespace

int BenchCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim bench [WORLD…] [options]\n\n"
      "Steps each WORLD (a file, or a shipped world's name; default: ssl-2003 div-b div-a)\n"
      "headless and as fast as possible\n"
      "for a fixed simulated time, every robot driving seeded random commands and the ball in\n"
      "play, and prints per world: real-time factor, steps per second, where the time goes, peak\n"
      "memory, and the kernel's overhead over the same bodies, joints and contacts stepped with\n"
      "ODE alone (docs/performance.md).\n\n"
      "--robot-count N[,N…] runs each world once per count with that many robots on its field\n"
      "(half each team, on a grid) and prints what a step costs against the robots and the\n"
      "contacts they make; --scaling is --robot-count 2,6,12,22,32 on div-a (or the worlds given).\n"
      "--instructions also counts each run's instructions per simulated second under valgrind's\n"
      "callgrind: this binary runs twice more, for the two --instructions-durations and without\n"
      "the baseline, and the difference of the two counts leaves out the start-up.\n\noptions");
  double duration = 10.0;
  std::uint64_t seed = 1;
  PhysicsFlags physics_flags;
  std::string robot, markdown, csv, robot_counts, durations = "2,12";
  std::vector<std::string> worlds, plugin_paths;
  desc.add_options()("help,h", "this help")
      ("duration", po::value<double>(&duration)->default_value(duration), "simulated seconds per world")
      ("seed", po::value<std::uint64_t>(&seed)->default_value(seed), "seed of the random play")
      ("no-baseline", "skip the bare-ODE baseline")
      ("robot", po::value<std::string>(&robot), "put this robot model file in every robot's place")
      ("markdown", po::value<std::string>(&markdown), "also write the results as Markdown to FILE")
      ("csv", po::value<std::string>(&csv), "also write every figure as CSV to FILE (tools/bench_plot.py plots it)")
      ("robot-count", po::value<std::string>(&robot_counts),
       "N[,N…]: run each world with N robots on its field instead of its own (1..32, half each team), once per N")
      ("scaling", "the step's cost against the robots: --robot-count 2,6,12,22,32, world div-a unless given")
      ("instructions", "also count instructions per simulated second and per step under valgrind --tool=callgrind")
      ("instructions-durations", po::value<std::string>(&durations)->default_value(durations),
       "D1,D2: simulated seconds of the two callgrind runs (their difference leaves out the start-up)")
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
  const bool scaling = vm.count("scaling") > 0;
  if (vm.count("robot-count")) {
    options.robot_counts = ParseList<int>(robot_counts, "robot-count");
  } else if (scaling) {
    options.robot_counts.assign(std::begin(kScalingCounts), std::end(kScalingCounts));
  }
  for (int n : options.robot_counts) {
    if (n < 1 || n > bench::kMaxTrialRobots) {
      std::cerr << "ubersim bench: --robot-count: " << n << " robots; 1.." << bench::kMaxTrialRobots
                << " (ids 0..15 in each team)\n";
      return kExitUsage;
    }
  }
  if (vm.count("instructions")) {
    const auto d = ParseList<double>(durations, "instructions-durations");
    if (d.size() != 2 || !(d[0] > 0 && d[1] > d[0])) {
      std::cerr << "ubersim bench: --instructions-durations D1,D2 with 0 < D1 < D2 (default 2,12)\n";
      return kExitUsage;
    }
    const auto valgrind = bench::FindValgrind();
    if (!valgrind) {
      std::cerr << "ubersim bench: --instructions needs valgrind, which is not installed (neither "
                   "/usr/bin/valgrind nor on PATH; on Debian: apt-get install valgrind)\n";
      return kExitRuntime;
    }
    bench::BenchOptions::Instructions counting;
    counting.valgrind = *valgrind;
    counting.program = bench::SelfExecutable();
    counting.short_seconds = d[0];
    counting.long_seconds = d[1];
    for (const std::string& dir : plugin_paths) {
      counting.extra_arguments.insert(counting.extra_arguments.end(),
                                      {"--plugin-path", std::filesystem::absolute(dir).string()});
    }
    options.instructions = counting;
  }
  if (worlds.empty()) {
    const std::vector<std::string> defaults =
        scaling ? std::vector<std::string>{"div-a"} : std::vector<std::string>{"ssl-2003", "div-b", "div-a"};
    for (const std::string& w : defaults) {
      options.worlds.push_back(kernel::DataDir() / "models" / "worlds" / (w + ".yaml"));
    }
  } else {
    for (const std::string& w : worlds) options.worlds.push_back(WorldFileOf(w));
  }
  std::ostringstream warnings;
  // Random commands draw warnings (a diff robot told to strafe): expected here, not shown.
  kernel::StreamLog log(warnings, LogLevel::kError);
  const WorldLoading loading = LoadingFor(options.worlds, plugin_paths);
  // Every count must fit on every field before the first run, not minutes into them.
  for (const auto& file : options.worlds) {
    if (options.robot_counts.empty()) break;
    kernel::WorldModel model = bench::LoadTrialWorld(loading.loader, file, options.physics, options.robot_model);
    for (int n : options.robot_counts) {
      try {
        bench::PlaceRobots(model, n);
      } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("--robot-count: ") + e.what());
      }
    }
  }
  ProgressLine progress;
  const auto results = bench::RunBench(options, *loading.registry, loading.loader, log,
                                       [&](const std::string& world, double f) {
                                         progress.Redraw(world + " " + Bar(f) + " " +
                                                         std::to_string(static_cast<int>(f * 100)) + " %");
                                       });
  progress.Clear();
  std::cout << bench::FormatTable(results);
  // The work a step does: the robots, contacts and instructions beside the clock's figures.
  const bool work = !options.robot_counts.empty() || options.instructions.has_value();
  if (work) std::cout << "\n" << bench::FormatWorkTable(results);
  if (options.instructions) {
    std::cout << "instructions counted by " << options.instructions->valgrind.string() << " --tool=callgrind\n";
  }
  std::cout << "machine: " << bench::MachineDescription() << "\n";
  std::cout << "process peak resident memory: " << bench::PeakResidentMegabytes() << " MB\n";
  if (!markdown.empty()) {
    std::ofstream out(markdown);
    out << bench::FormatMarkdown(results, bench::MachineDescription(), CommandLineText("bench", args));
    if (work) out << "\n" << bench::FormatWorkMarkdown(results);
    std::cout << "markdown: " << markdown << "\n";
  }
  if (!csv.empty()) {
    std::ofstream(csv) << bench::FormatCsv(results);
    std::cout << "csv: " << csv << "\n";
  }
  if (!warnings.str().empty()) std::cerr << warnings.str();
  return kExitOk;
}

}  // namespace ubersim::cli
