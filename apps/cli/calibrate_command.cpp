// SPDX-License-Identifier: Apache-2.0
// `ubersim calibrate LOG…`: fits the ball, the robots and the cameras to a field's SSL log and
// writes model files and a report (docs/calibrate.md); `--drill FILE` records the calibration
// drill in a simulated world instead, as a field's log to try the fit on.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/world.hpp"
#include "calibration.hpp"
#include "command_line.hpp"
#include "commands.hpp"
#include "drill.hpp"
#include "exit_codes.hpp"
#include "shared/trial_world.hpp"
#include "world_loading.hpp"

namespace ubersim::cli {
namespace {

namespace po = boost::program_options;
namespace fs = std::filesystem;

int Drill(const std::string& out, const std::string& world_arg, const std::optional<std::string>& robot,
          const PhysicsFlags& physics_flags, const po::variables_map& vm, const std::vector<std::string>& plugin_paths,
          const calibrate::DrillOptions& options) {
  kernel::PhysicsOverrides physics;
  if (!physics_flags.Read(vm, "calibrate", physics)) return kExitUsage;
  const fs::path file = WorldFileOf(world_arg);
  const WorldLoading loading = LoadingFor({file}, plugin_paths);
  kernel::WorldModel model = apps::LoadTrialWorld(loading.loader, file, physics, robot);
  model.transports.clear();  // headless: the log is the only output
  kernel::StreamLog log(std::cerr, LogLevel::kWarning);
  kernel::World world(model, *loading.registry, log, /*start_transports=*/false);
  std::printf("drill in %s (%s): %.0f s simulated, %d robots, seed %llu, physics %s\n", model.name.c_str(),
              file.string().c_str(), options.duration, options.robots, static_cast<unsigned long long>(options.seed),
              kernel::DescribePhysics(model.physics).c_str());
  std::fflush(stdout);
  const calibrate::DrillSummary s = calibrate::RunDrill(world, out, options, log);
  std::printf("recorded %lld records to %s: %d step commands, %d kicks, %d chips\n", static_cast<long long>(s.records),
              out.c_str(), s.steps, s.kicks, s.chips);
  return kExitOk;
}

}  // namespace

int CalibrateCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim calibrate LOG… [options]\n"
      "       ubersim calibrate --drill FILE [--world WORLD] [--duration S] [options]\n\n"
      "Fits ÜberSim's models to a field's SSL log files (.log, .log.gz; the vision, and the robot\n"
      "commands a team's software recorded beside it as records 1201/1202): the ball's sliding and\n"
      "rolling decelerations and switch (and chip dampings), each robot's top speed, acceleration and\n"
      "braking along and across its heading and in rotation (and its command latency), and each\n"
      "camera's noise, drop-outs, frame rate, jitter, latency and false balls. Writes world.yaml,\n"
      "ball.yaml and robot-*.yaml over the base world's files, and report.md with SVG plots, into\n"
      "--out. Exit code 9 when the log holds too little of anything to fit (the report says what).\n"
      "With --drill, drives the calibration drill in the simulated WORLD instead and records it to\n"
      "FILE as a field's log (docs/calibrate.md).\n\noptions");
  std::string out, world_arg = "div-b", drill, robot;
  std::vector<std::string> logs, plugin_paths;
  calibrate::CalibrateOptions options;
  calibrate::DrillOptions drill_options;
  PhysicsFlags physics_flags;
  desc.add_options()("help,h", "this help")
      ("out,o", po::value<std::string>(&out), "folder for the report and the model files (default: LOG's name + \"-calibration\")")
      ("world", po::value<std::string>(&world_arg)->default_value(world_arg),
       "the world whose files are fitted over (a file or a shipped world's name); with --drill, the world driven")
      ("check", "run the fitted world through the log's manoeuvres and overlay it on the recording in the report")
      ("geometry-models", "the fitted world's vision geometry announces the fitted ball model (SSL_GeometryModels)")
      ("dump-tracks", "also write the tracks the fits saw (ball, robots, commands) as CSV files into --out/tracks")
      ("min-runs", po::value<int>(&options.ball.min_runs)->default_value(options.ball.min_runs),
       "fewest free ball runs the ball fit accepts")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR for plugins (repeatable)")
      ("drill", po::value<std::string>(&drill), "record the calibration drill in WORLD to this log file instead of fitting")
      ("duration", po::value<double>(&drill_options.duration)->default_value(drill_options.duration),
       "--drill: simulated seconds")
      ("robots", po::value<int>(&drill_options.robots)->default_value(drill_options.robots),
       "--drill: blue robots driven, each in its own lane")
      ("seed", po::value<std::uint64_t>(&drill_options.seed)->default_value(drill_options.seed), "--drill: the kicks' seed")
      ("robot", po::value<std::string>(&robot), "--drill: put this robot model file in every robot's place")
      ("no-commands", "--drill: do not record the commands")
      ("no-chips", "--drill: flat kicks only");
  physics_flags.AddTo(desc);
  po::options_description hidden;
  hidden.add_options()("log", po::value<std::vector<std::string>>(&logs));
  po::positional_options_description pos;
  pos.add("log", -1);
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "calibrate", desc, vm, &hidden, &pos)) return *done;

  if (vm.count("drill")) {
    if (!logs.empty()) {
      std::cerr << "ubersim calibrate: --drill records a log; it takes no LOG argument\n";
      return kExitUsage;
    }
    if (!(drill_options.duration > 0)) {
      std::cerr << "ubersim calibrate: --duration must be > 0\n";
      return kExitUsage;
    }
    drill_options.commands = vm.count("no-commands") == 0;
    drill_options.chips = vm.count("no-chips") == 0;
    return Drill(drill, world_arg, vm.count("robot") ? std::optional<std::string>(robot) : std::nullopt, physics_flags,
                 vm, plugin_paths, drill_options);
  }
  if (logs.empty()) {
    std::cerr << "ubersim calibrate: name the log file(s) to fit (or --drill FILE to record one)\n";
    return kExitUsage;
  }
  if (options.ball.min_runs < 1) {
    std::cerr << "ubersim calibrate: --min-runs must be at least 1\n";
    return kExitUsage;
  }
  options.logs = logs;
  if (out.empty()) {
    std::string stem = fs::path(logs.front()).filename().string();
    for (const char* ext : {".gz", ".log"}) {
      if (stem.size() > std::string(ext).size() && stem.substr(stem.size() - std::string(ext).size()) == ext) {
        stem.resize(stem.size() - std::string(ext).size());
      }
    }
    out = stem + "-calibration";
  }
  options.out_dir = out;
  options.base_world = WorldFileOf(world_arg);
  options.geometry_models = vm.count("geometry-models") > 0;
  options.check = vm.count("check") > 0;
  options.dump_tracks = vm.count("dump-tracks") > 0;
  options.plugin_paths = plugin_paths;
  const calibrate::CalibrationOutcome outcome =
      calibrate::Calibrate(options, [](const std::string& line) { std::printf("%s\n", line.c_str()); std::fflush(stdout); });
  for (const auto& p : outcome.problems) std::printf("not fitted: %s\n", p.c_str());
  std::printf("report: %s\n", outcome.report.string().c_str());
  if (!outcome.anything_fitted) {
    std::cerr << "ubersim calibrate: too little data in " << logs.front()
              << " to fit the ball, a robot or the cameras (the report says what is missing)\n";
    return kExitTooLittleData;
  }
  std::printf("world: %s\n", outcome.files.world.string().c_str());
  return kExitOk;
}

}  // namespace ubersim::cli
