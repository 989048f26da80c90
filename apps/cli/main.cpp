// SPDX-License-Identifier: Apache-2.0
// The `ubersim` command: run a world, validate model files, list plugins.
#include <unistd.h>

#include <atomic>
#include <optional>
#include <algorithm>
#include <map>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <chrono>

#include <boost/program_options.hpp>

#include "ubersim/error.hpp"
#include "ubersim/version.hpp"
#include "ubersim/kernel/runner.hpp"
#include "ubersim/kernel/data_paths.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"
#include "ubersim/kernel/snapshot.hpp"
#include "ubersim/kernel/world.hpp"
#include "ubersim/validation/report.hpp"
#include "ubersim/validation/scenarios.hpp"
#include "batch.hpp"
#include "bench.hpp"
#include "run_overrides.hpp"
#include "soak.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace ubersim;
using namespace ubersim::kernel;

namespace {

// Exit codes, documented in `ubersim --help` and docs/cli.md.
constexpr int kExitOk = 0;
constexpr int kExitRuntime = 1;
constexpr int kExitUsage = 2;
constexpr int kExitModel = 3;
constexpr int kExitPlugin = 4;
constexpr int kExitOutOfBand = 5;
constexpr int kExitSoakFailed = 6;

constexpr int kExitPluginFault = 7;  // run: a plugin fault stopped the world; report written

// Process-wide state, set by signal handlers and read by the run loop: stop (SIGINT, SIGTERM)
// and save a snapshot (SIGUSR1). (The crash guard keeps its own, crash_report.hpp.)
std::atomic<bool>& StopRequested() {
  static std::atomic<bool> stop{false};
  return stop;
}
std::atomic<bool>& SnapshotRequested() {
  static std::atomic<bool> save{false};
  return save;
}
extern "C" void OnSignal(int) { StopRequested().store(true); }
extern "C" void OnSnapshotSignal(int) { SnapshotRequested().store(true); }

const char* kTopHelp =
    "ÜberSim — RoboCup Small Size League simulator\n"
    "\n"
    "usage: ubersim <command> [options]\n"
    "\n"
    "commands:\n"
    "  run [WORLD]      run a world (default: models/worlds/div-b.yaml) in real time\n"
    "  validate FILE…   check model files (world, field, ball, robot) against their schemas\n"
    "  plugins          list every plugin found in the plugin search path\n"
    "  validate-physics run the physics validation scenarios, write the report and plots\n"
    "  bench [WORLD…]   step worlds as fast as possible and measure them against bare ODE\n"
    "  batch [WORLD…]   run many seeded worlds at once on worker processes\n"
    "  soak [WORLD]     run a world for long under random play and teleports, checking its state\n"
    "\n"
    "`ubersim <command> --help` describes a command's options.\n"
    "exit codes: 0 ok, 1 runtime error, 2 bad usage, 3 invalid model file, 4 plugin error,\n"
    "            5 a validated physics number outside its band, 6 soak: a state-check finding\n"
    "            or memory growth, 7 run: a plugin fault stopped the world (crash report\n"
    "            and snapshot written)\n";

// Parses a command's `args` against `desc`, plus `hidden` and `positional` for its positional
// arguments. Returns the exit code when the command ends here (a usage error: the message and
// the options; --help: the options), nothing when it goes on.
std::optional<int> ParseCommandLine(const std::vector<std::string>& args, const char* command,
                                    const po::options_description& desc, po::variables_map& vm,
                                    const po::options_description* hidden = nullptr,
                                    const po::positional_options_description* positional = nullptr) {
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

std::vector<fs::path> ToPaths(const std::vector<std::string>& v) {
  return std::vector<fs::path>(v.begin(), v.end());
}

// --physics-step, --solver-iterations, --solver-iterations-without-ball, --max-contacts: one
// meaning and one check for every command that tries other physics settings than the world files'.
struct PhysicsFlags {
  double step = 0;
  int iterations = 0;
  int iterations_without_ball = 0;
  int contacts = 0;

  void AddTo(po::options_description& desc) {
    desc.add_options()
        ("physics-step", po::value<double>(&step), "instead of the world files' physics step, s")
        ("solver-iterations", po::value<int>(&iterations), "instead of the world files' QuickStep iterations")
        ("solver-iterations-without-ball", po::value<int>(&iterations_without_ball),
         "QuickStep iterations of the islands no ball belongs to (default: --solver-iterations)")
        ("max-contacts", po::value<int>(&contacts), "instead of the world files' contacts per geometry pair");
  }
  // The settings given; false (with the reason on stderr) when one is out of range.
  bool Read(const po::variables_map& vm, const std::string& command, PhysicsOverrides& out) const {
    if ((vm.count("physics-step") && !(step > 0 && step <= 0.02)) || (vm.count("solver-iterations") && iterations < 1) ||
        (vm.count("solver-iterations-without-ball") && iterations_without_ball < 1) ||
        (vm.count("max-contacts") && (contacts < 1 || contacts > 16))) {
      std::cerr << "ubersim " << command
                << ": 0 < --physics-step <= 0.02, --solver-iterations >= 1, --solver-iterations-without-ball >= 1, "
                   "--max-contacts 1..16\n";
      return false;
    }
    if (vm.count("physics-step")) out.step = step;
    if (vm.count("solver-iterations")) out.solver_iterations = iterations;
    if (vm.count("solver-iterations-without-ball")) out.solver_iterations_without_ball = iterations_without_ball;
    if (vm.count("max-contacts")) out.max_contacts = contacts;
    return true;
  }
};

// A world argument: a file, or the name of a shipped world ("div-a").
fs::path WorldFileOf(const std::string& arg) {
  const fs::path shipped = DataDir() / "models" / "worlds" / (arg + ".yaml");
  return !fs::exists(arg) && fs::exists(shipped) ? shipped : fs::path(arg);
}

// The world file's own plugin_paths, read before the full load (its plugins' schemas need them).
std::vector<fs::path> WorldPluginPaths(const fs::path& world_file) {
  std::vector<fs::path> out;
  const ParamView root(ParseYamlFile(world_file));
  if (!root.Has("plugin_paths") || !root["plugin_paths"].IsArray()) return out;
  const ParamView list = root["plugin_paths"];
  for (std::size_t i = 0; i < list.Size(); ++i) {
    fs::path p = list.At(i).AsString();
    if (p.is_relative()) p = world_file.parent_path() / p;
    out.push_back(p);
  }
  return out;
}

// Where plugins are looked for: the worlds' own plugin_paths, then --plugin-path (cli.md).
std::vector<fs::path> PluginSearchPath(const std::vector<fs::path>& worlds, const std::vector<std::string>& plugin_paths) {
  std::vector<fs::path> search;
  for (const auto& w : worlds) {
    for (const auto& p : WorldPluginPaths(w)) search.push_back(p);
  }
  for (const auto& p : ToPaths(plugin_paths)) search.push_back(p);
  return PluginRegistry::DefaultSearchPaths(search);
}

PluginSchemaLookup LookupIn(PluginRegistry& registry) {
  return [&registry](PluginKind kind, const std::string& id) {
    return registry.Find(kind, id).schema_json;
  };
}

int RunCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim run [WORLD] [options]\n\n"
      "Runs WORLD (default models/worlds/div-b.yaml) in real time, printing where it publishes\n"
      "(the browser viewer's address among them) and a live status line (sim time, real-time\n"
      "factor). Ctrl-C stops it. --restore starts from a snapshot; --snapshot-out saves one when\n"
      "the run ends and on SIGUSR1. A plugin fault under the world's on_plugin_fault: stop ends\n"
      "the run with exit code 7, a crash report and a snapshot in --crash-dir; so does a crash\n"
      "(a fatal signal: the report holds the last periodic snapshot).\n\noptions");
  std::string world_arg;
  double duration = 0, speed = 1.0;
  std::string log_level = "info";
  std::vector<std::string> plugin_paths;
  std::vector<std::string> skipped_transports;
  std::string restore_file, snapshot_out, crash_dir = ".";
  double crash_snapshot_interval = 1.0;
  RunOverrides overrides;
  desc.add_options()("help,h", "this help")
      ("fast", "run as fast as possible instead of real time")
      ("speed", po::value<double>(&speed)->default_value(1.0), "speed factor (sim s per wall s)")
      ("duration", po::value<double>(&duration)->default_value(0), "stop after SECONDS of simulated time (0: run until stopped)")
      ("paused", "start paused")
      ("quiet,q", "no status line")
      ("local-only", "keep every transport on loopback (127.0.0.1): nothing sent to or reachable from another machine")
      ("realism", po::value<std::string>(&overrides.realism),
       "vision and radio preset: ÜberSim's ideal, 2003, realistic, or the league's None, Friendly, RC2021, Realistic "
       "(what it asks for that is not modelled is listed at start)")
      ("field,g", po::value<std::string>(&overrides.field),
       "field: div-a or div-b (also ER-Force's 2020, 2023, 2023B); the formation scales with it")
      ("vision-port", po::value<int>(), "SSL-Vision multicast port (default 10020; 10006 as real ssl-vision)")
      ("vision-address", po::value<std::string>(&overrides.vision_address), "SSL-Vision multicast group (default 224.5.23.2)")
      ("control-port", po::value<int>(), "simulation protocol: SimulatorCommand port (default 10300)")
      ("blue-port", po::value<int>(), "simulation protocol: blue team's RobotControl port (default 10301)")
      ("yellow-port", po::value<int>(), "simulation protocol: yellow team's RobotControl port (default 10302)")
      ("grsim-port", po::value<int>(), "grSim protocol command port (default 20011)")
      ("viewer-port", po::value<int>(), "browser viewer port (default 8080)")
      ("no-viewer", "do not start the browser viewer (the same as --no-transport viewer)")
      ("no-transport", po::value<std::vector<std::string>>(&skipped_transports), "do not start the world's transport ID (repeatable)")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR for plugins (repeatable)")
      ("log-level", po::value<std::string>(&log_level)->default_value("info"), "debug, info, warning or error")
      ("restore", po::value<std::string>(&restore_file), "start from the snapshot FILE (of this world)")
      ("snapshot-out", po::value<std::string>(&snapshot_out), "save a snapshot to FILE when the run ends and on SIGUSR1")
      ("crash-dir", po::value<std::string>(&crash_dir)->default_value("."), "where crash reports and their snapshots go")
      ("crash-snapshot-interval", po::value<double>(&crash_snapshot_interval)->default_value(1.0),
       "simulated seconds between the in-memory snapshots a crash report writes (0: none)");
  po::options_description hidden;
  hidden.add_options()("world", po::value<std::string>(&world_arg));
  po::positional_options_description pos;
  pos.add("world", 1);
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "run", desc, vm, &hidden, &pos)) return *done;
  if (duration < 0 || speed < 0 || !(crash_snapshot_interval >= 0)) {
    std::cerr << "ubersim run: --duration, --speed and --crash-snapshot-interval must be >= 0\n";
    return kExitUsage;
  }
  LogLevel level = LogLevel::kInfo;
  if (log_level == "debug") level = LogLevel::kDebug;
  else if (log_level == "warning") level = LogLevel::kWarning;
  else if (log_level == "error") level = LogLevel::kError;
  else if (log_level != "info") {
    std::cerr << "ubersim run: unknown --log-level '" << log_level << "'\n";
    return kExitUsage;
  }
  StreamLog log(std::cerr, level);

  fs::path world_file;
  try {
    world_file = world_arg.empty() ? DefaultWorldFile() : WorldFileOf(world_arg);
  } catch (const std::exception& e) {
    std::cerr << "ubersim run: " << e.what() << "\n";
    return kExitRuntime;
  }
  try {
    PluginRegistry registry(PluginSearchPath({world_file}, plugin_paths));
    const ModelLoader loader(ModelLoader::DefaultSchemaDir(), LookupIn(registry));
    WorldModel model = loader.LoadWorld(world_file);
    overrides.local_only = vm.count("local-only") > 0;
    for (const char* port : {"vision", "control", "blue", "yellow", "grsim", "viewer"}) {
      if (vm.count(std::string(port) + "-port")) overrides.ports[port] = vm[std::string(port) + "-port"].as<int>();
    }
    try {
      for (const std::string& note : ApplyRunOverrides(overrides, model, loader, registry)) {
        std::cerr << "ubersim: " << note << "\n";
      }
    } catch (const OverrideError& e) {
      std::cerr << "ubersim run: " << e.what() << "\n";
      return kExitUsage;
    }
    if (vm.count("no-viewer")) skipped_transports.push_back("viewer");
    for (const std::string& id : skipped_transports) {
      const auto removed = std::erase_if(model.transports, [&](const TransportModel& t) { return t.plugin == id; });
      if (removed == 0 && id != "viewer") {
        std::cerr << "ubersim run: --no-transport " << id << ": the world has no such transport\n";
        return kExitUsage;
      }
      if (removed > 0) std::cerr << "ubersim: transport " << id << " not started (--no-" << (id == "viewer" ? "viewer" : "transport") << ")\n";
    }
    World world(model, registry, log);
    if (!restore_file.empty()) {
      world.Restore(ReadSnapshotFile(restore_file));
      std::cerr << "ubersim: restored " << restore_file << ": step " << world.clock().steps() << ", sim time "
                << world.clock().seconds() << " s\n";
    }

    std::cerr << "ubersim: world '" << model.name << "' from " << world_file.string() << ": "
              << model.robots.size() << " robots, field " << model.field->geometry.name
              << ", ball " << model.ball->name << ", physics step "
              << model.physics.step * 1e3 << " ms, broadphase " << model.physics.broadphase << "\n";
    const auto endpoints = world.TransportEndpoints();
    if (endpoints.empty()) {
      std::cerr << "ubersim: publishing nowhere (the world file configures no transports)\n";
    }
    for (const auto& e : endpoints) std::cerr << "ubersim: publishing " << e << "\n";

    RunOptions options;
    options.duration = duration;
    options.speed_factor = vm.count("fast") ? 0.0 : speed;
    options.start_paused = vm.count("paused") > 0;
    const bool quiet = vm.count("quiet") > 0;
    const bool tty = isatty(STDERR_FILENO) != 0;
    options.status_interval = tty ? 0.25 : 2.0;
    std::signal(SIGINT, OnSignal);
    std::signal(SIGTERM, OnSignal);
    std::signal(SIGUSR1, OnSnapshotSignal);

    std::string command_line = "ubersim run";
    for (const std::string& a : args) command_line += " " + a;
    const RunDescription run{std::string("ubersim ") + UBERSIM_VERSION, model.name, world_file.string(), command_line};
    const CrashFiles crash_files = CrashFilesIn(crash_dir, model.name);
    // A crash (a fatal signal) writes the last of these snapshots, kept in memory.
    CrashGuard guard(crash_files, run);
    guard.Install();
    const auto crash_interval_ns = static_cast<std::int64_t>(crash_snapshot_interval * 1e9 + 0.5);
    std::int64_t next_crash_snapshot_ns = world.clock().time_ns();
    const auto save_snapshot = [&](const char* why) {
      try {
        WriteSnapshotFile(snapshot_out, world.Save());
        std::cerr << "ubersim: snapshot of step " << world.clock().steps() << " written to " << snapshot_out << " ("
                  << why << ")\n";
      } catch (const std::exception& e) {
        std::cerr << "ubersim: no snapshot written: " << e.what() << "\n";
      }
    };
    options.between_steps = [&] {
      if (SnapshotRequested().exchange(false)) {
        if (snapshot_out.empty()) {
          std::cerr << "ubersim: SIGUSR1: no --snapshot-out given, nothing saved\n";
        } else {
          save_snapshot("SIGUSR1");
        }
      }
      if (crash_interval_ns > 0 && world.clock().time_ns() >= next_crash_snapshot_ns) {
        guard.Update(world);
        next_crash_snapshot_ns = world.clock().time_ns() + crash_interval_ns;
      }
    };
    const RunStatus final_status = RunWorld(world, options, StopRequested(), [&](const RunStatus& s) {
      if (quiet) return;
      char line[160];
      std::snprintf(line, sizeof line, "sim %10.3f s | real-time factor %7.2f | steps %lld%s",
                    s.sim_time, s.real_time_factor, static_cast<long long>(s.steps),
                    s.paused ? " | paused" : "");
      if (tty && !s.finished) {
        std::cerr << '\r' << line << "\033[K" << std::flush;
      } else {
        std::cerr << (tty ? "\r" : "") << line << '\n';
      }
    });
    std::cerr << "ubersim: stopped at sim time " << final_status.sim_time << " s after "
              << final_status.steps << " steps\n";
    if (!snapshot_out.empty()) save_snapshot(world.stopped() ? "the world stopped" : "end of run");
    if (world.stopped()) {
      WriteFaultReport(world, crash_files, run);
      std::cerr << "ubersim: a plugin fault stopped the world (on_plugin_fault: stop); crash report "
                << crash_files.report.string() << ", snapshot " << crash_files.snapshot.string() << "\n";
      return kExitPluginFault;
    }
    return kExitOk;
  } catch (const ModelError& e) {
    std::cerr << "ubersim run: invalid model: " << e.what() << "\n";
    return kExitModel;
  } catch (const SnapshotError& e) {
    std::cerr << "ubersim run: snapshot: " << e.what() << "\n";
    return kExitRuntime;
  } catch (const PluginLoadError& e) {
    std::cerr << "ubersim run: plugin error: " << e.what() << "\n";
    return kExitPlugin;
  } catch (const PluginError& e) {
    std::cerr << "ubersim run: plugin error: " << e.what() << "\n";
    return kExitPlugin;
  } catch (const std::exception& e) {
    std::cerr << "ubersim run: " << e.what() << "\n";
    return kExitRuntime;
  }
}

int ValidateCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim validate FILE… [options]\n\n"
      "Checks each model file (its kind: world, field, ball or robot) and the files it names\n"
      "against the schemas and the plugins' own schemas; prints file:line:column: key: reason\n"
      "for each problem. Exit code 3 when any file is invalid.\n\noptions");
  std::vector<std::string> files, plugin_paths;
  desc.add_options()("help,h", "this help")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR for plugins (repeatable)");
  po::options_description hidden;
  hidden.add_options()("file", po::value<std::vector<std::string>>(&files));
  po::positional_options_description pos;
  pos.add("file", -1);
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "validate", desc, vm, &hidden, &pos)) return *done;
  if (files.empty()) {
    std::cerr << "ubersim validate: name at least one file\n\n" << desc << "\n";
    return kExitUsage;
  }
  int failed = 0;
  for (const std::string& f : files) {
    try {
      std::vector<fs::path> search = ToPaths(plugin_paths);
      std::vector<fs::path> from_world;
      try {
        from_world = WorldPluginPaths(f);
      } catch (const std::exception&) {
        // Not a readable world: the full validation below reports the problem properly.
      }
      search.insert(search.begin(), from_world.begin(), from_world.end());
      PluginRegistry registry(PluginRegistry::DefaultSearchPaths(search));
      const ModelLoader loader(ModelLoader::DefaultSchemaDir(), LookupIn(registry));
      const std::string kind = loader.Validate(f);
      std::cout << "ok: " << f << " (" << kind << ")\n";
    } catch (const ModelError& e) {
      ++failed;
      std::cout << e.what() << "\n";
    } catch (const std::exception& e) {
      ++failed;
      std::cout << f << ": " << e.what() << "\n";
    }
  }
  return failed ? kExitModel : kExitOk;
}

int PluginsCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim plugins [options]\n\n"
      "Lists every plugin library found in the search path (--plugin-path, $UBERSIM_PLUGIN_PATH,\n"
      "the plugins built beside this executable, the install prefix): id, kind, version, SDK,\n"
      "file; then the libraries it refused and why.\n\noptions");
  std::vector<std::string> plugin_paths;
  desc.add_options()("help,h", "this help")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR (repeatable)");
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "plugins", desc, vm)) return *done;
  PluginRegistry registry(PluginRegistry::DefaultSearchPaths(ToPaths(plugin_paths)));
  const auto result = registry.Scan();
  std::cout << "search path:\n";
  for (const auto& p : registry.SearchPaths()) std::cout << "  " << p.string() << "\n";
  std::printf("%-24s %-10s %-10s %-5s %s\n", "PLUGIN", "KIND", "VERSION", "SDK", "FILE");
  for (const auto& p : result.plugins) {
    std::printf("%-24s %-10s %-10s %-5s %s\n", p.id.c_str(), ToString(p.kind), p.version.c_str(),
                p.sdk_version.c_str(), p.file.string().c_str());
  }
  if (result.plugins.empty()) std::cout << "(no plugins found)\n";
  for (const auto& problem : result.problems) std::cerr << "refused: " << problem << "\n";
  return result.problems.empty() ? kExitOk : kExitPlugin;
}

int ValidatePhysicsCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim validate-physics [options]\n\n"
      "Runs the physics validation scenarios (ball slide/roll, chip flight and bounces, shots\n"
      "against robots and walls, drives, dribbler, kicker, the 2003 paper's experiments) on the\n"
      "shipped model files, prints each number against its published band, and writes a report\n"
      "(README.md) with SVG plots. Exit code 5 when a number is outside its band.\n\noptions");
  std::string out = "docs/validation";
  std::vector<std::string> only, plugin_paths;
  PhysicsFlags physics_flags;
  desc.add_options()("help,h", "this help")
      ("out", po::value<std::string>(&out)->default_value(out), "folder for README.md and the plots")
      ("only", po::value<std::vector<std::string>>(&only), "run only scenario ID (repeatable)")
      ("list", "list the scenarios and exit")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR for plugins (repeatable)");
  physics_flags.AddTo(desc);  // other settings need --out: the default folder is the shipped report
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "validate-physics", desc, vm)) return *done;
  PhysicsOverrides physics;
  if (!physics_flags.Read(vm, "validate-physics", physics)) return kExitUsage;
  if (physics.Any() && vm["out"].defaulted()) {
    std::cerr << "ubersim validate-physics: give --out DIR when trying other physics settings ("
              << out << " holds the report of the shipped settings)\n";
    return kExitUsage;
  }
  if (vm.count("list")) {
    for (const auto& s : validation::AllScenarios()) std::printf("%-24s %s\n", s.id.c_str(), s.title.c_str());
    return kExitOk;
  }
  std::vector<const validation::Scenario*> chosen;
  try {
    for (const std::string& id : only) chosen.push_back(&validation::FindScenario(id));
  } catch (const std::out_of_range& e) {
    std::cerr << "ubersim validate-physics: " << e.what() << "\n";
    return kExitUsage;
  }
  if (chosen.empty()) {
    for (const auto& s : validation::AllScenarios()) chosen.push_back(&s);
  }
  try {
    std::ostringstream warnings;
    StreamLog log(warnings, LogLevel::kWarning);
    PluginRegistry registry(PluginRegistry::DefaultSearchPaths(ToPaths(plugin_paths)));
    validation::Environment env{DataDir() / "models", ModelLoader::DefaultSchemaDir(), &registry, &log, {}};
    env.physics = physics;
    std::vector<validation::ScenarioResult> results;
    int out_of_band = 0;
    for (const validation::Scenario* s : chosen) {
      const auto t0 = std::chrono::steady_clock::now();
      results.push_back(s->run(env));
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const validation::ScenarioResult& r = results.back();
      int ok = 0;
      for (const auto& m : r.metrics) ok += m.Pass() ? 1 : 0;
      std::printf("%-4s %-24s %d/%zu in band  (%.1f s)\n", r.Pass() ? "ok" : "OUT", r.id.c_str(), ok,
                  r.metrics.size(), seconds);
      for (const auto& m : r.metrics) {
        if (m.Pass()) continue;
        ++out_of_band;
        std::printf("       %s = %.4g %s, band %.4g … %.4g (%s)\n", m.name.c_str(), m.value, m.unit.c_str(),
                    m.low, m.high, m.basis.c_str());
      }
      std::fflush(stdout);
    }
    std::string command = "ubersim validate-physics";
    for (const std::string& a : args) command += " " + a;
    validation::WriteReport(out, results, command);
    std::printf("report: %s\n", (fs::path(out) / "README.md").string().c_str());
    if (!warnings.str().empty()) std::cerr << warnings.str();
    return out_of_band ? kExitOutOfBand : kExitOk;
  } catch (const ModelError& e) {
    std::cerr << "ubersim validate-physics: invalid model: " << e.what() << "\n";
    return kExitModel;
  } catch (const PluginLoadError& e) {
    std::cerr << "ubersim validate-physics: plugin error: " << e.what() << "\n";
    return kExitPlugin;
  } catch (const std::exception& e) {
    std::cerr << "ubersim validate-physics: " << e.what() << "\n";
    return kExitRuntime;
  }
}

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
  try {
    options.sim_seconds = duration;
    options.seed = seed;
    options.baseline = vm.count("no-baseline") == 0;
    if (vm.count("robot")) options.robot_model = robot;
    options.with_transports = vm.count("with-transports") > 0;
    if (worlds.empty()) {
      for (const char* w : {"ssl-2003", "div-b", "div-a"}) {
        options.worlds.push_back(DataDir() / "models" / "worlds" / (std::string(w) + ".yaml"));
      }
    } else {
      for (const std::string& w : worlds) options.worlds.push_back(WorldFileOf(w));
    }
    std::ostringstream warnings;
    // Random commands draw warnings (a diff robot told to strafe): expected here, not shown.
    StreamLog log(warnings, LogLevel::kError);
    PluginRegistry registry(PluginSearchPath(options.worlds, plugin_paths));
    const ModelLoader loader(ModelLoader::DefaultSchemaDir(), LookupIn(registry));
    const bool tty = isatty(STDERR_FILENO) != 0;
    const auto results = bench::RunBench(options, registry, loader, log, [&](const std::string& world, double f) {
      if (!tty) return;
      const int width = 30;
      const int done = static_cast<int>(f * width);
      std::cerr << "\r" << world << " [" << std::string(done, '#') << std::string(width - done, ' ') << "] "
                << static_cast<int>(f * 100) << " %\033[K" << std::flush;
    });
    if (tty) std::cerr << "\r\033[K";
    std::string command = "ubersim bench";
    for (const std::string& a : args) command += " " + a;
    std::cout << bench::FormatTable(results);
    std::cout << "machine: " << bench::MachineDescription() << "\n";
    std::cout << "process peak resident memory: " << bench::PeakResidentMegabytes() << " MB\n";
    if (!markdown.empty()) {
      std::ofstream(markdown) << bench::FormatMarkdown(results, bench::MachineDescription(), command);
      std::cout << "markdown: " << markdown << "\n";
    }
    if (!warnings.str().empty()) std::cerr << warnings.str();
    return kExitOk;
  } catch (const ModelError& e) {
    std::cerr << "ubersim bench: invalid model: " << e.what() << "\n";
    return kExitModel;
  } catch (const PluginLoadError& e) {
    std::cerr << "ubersim bench: plugin error: " << e.what() << "\n";
    return kExitPlugin;
  } catch (const PluginError& e) {
    std::cerr << "ubersim bench: plugin error: " << e.what() << "\n";
    return kExitPlugin;
  } catch (const std::exception& e) {
    std::cerr << "ubersim bench: " << e.what() << "\n";
    return kExitRuntime;
  }
}

// One line that redraws itself on a terminal: a bar, jobs done, percent, time left.
class ProgressBar {
 public:
  explicit ProgressBar(bool tty) : tty_(tty), start_(std::chrono::steady_clock::now()) {}
  void Update(const std::string& what, std::size_t done, std::size_t total, double fraction) {
    if (!tty_) return;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const int width = 30;
    const int filled = std::clamp(static_cast<int>(fraction * width), 0, width);
    char eta[32] = "";
    if (fraction > 0.02 && fraction < 1.0) std::snprintf(eta, sizeof eta, ", %.0f s left", elapsed * (1.0 / fraction - 1.0));
    std::fprintf(stderr, "\r%s [%s%s] %zu/%zu worlds, %3.0f %%%s\033[K", what.c_str(), std::string(filled, '#').c_str(),
                 std::string(width - filled, ' ').c_str(), done, total, fraction * 100.0, eta);
    std::fflush(stderr);
  }
  void Clear() {
    if (tty_) std::fprintf(stderr, "\r\033[K");
  }

 private:
  bool tty_;
  std::chrono::steady_clock::time_point start_;
};

int BatchCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim batch [WORLD…] [options]\n\n"
      "Runs COUNT copies of each WORLD (a file or a shipped world's name; default div-b), each\n"
      "with its own seed (random play, noise), headless and as fast as possible, spread over\n"
      "WORKERS processes; prints each world's figures and final state hash (the same seed gives\n"
      "the same hash, whatever the number of workers) and the total throughput.\n\noptions");
  int count = 4, workers = static_cast<int>(std::max(1L, sysconf(_SC_NPROCESSORS_ONLN)));
  double duration = 10.0;
  PhysicsFlags physics_flags;
  std::uint64_t seed = 1;
  std::string robot;
  std::vector<std::string> worlds, plugin_paths;
  desc.add_options()("help,h", "this help")
      ("count", po::value<int>(&count)->default_value(count), "copies of each world (seeds SEED, SEED+1, …)")
      ("workers", po::value<int>(&workers)->default_value(workers), "worker processes (default: the cores)")
      ("duration", po::value<double>(&duration)->default_value(duration), "simulated seconds per world")
      ("seed", po::value<std::uint64_t>(&seed)->default_value(seed), "first seed")
      ("robot", po::value<std::string>(&robot), "put this robot model file in every robot's place")
      ("scaling", "run once on 1 worker, then on WORKERS, and print the speed-up (and check the hashes agree)")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR for plugins (repeatable)");
  physics_flags.AddTo(desc);
  po::options_description hidden;
  hidden.add_options()("world", po::value<std::vector<std::string>>(&worlds));
  po::positional_options_description pos;
  pos.add("world", -1);
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "batch", desc, vm, &hidden, &pos)) return *done;
  if (count < 1 || workers < 1 || !(duration > 0)) {
    std::cerr << "ubersim batch: --count >= 1, --workers >= 1, --duration > 0\n";
    return kExitUsage;
  }
  PhysicsOverrides physics;
  if (!physics_flags.Read(vm, "batch", physics)) return kExitUsage;
  if (worlds.empty()) worlds.push_back("div-b");
  try {
    std::vector<fs::path> files;
    for (const std::string& w : worlds) files.push_back(WorldFileOf(w));
    PluginRegistry registry(PluginSearchPath(files, plugin_paths));
    const ModelLoader loader(ModelLoader::DefaultSchemaDir(), LookupIn(registry));
    // Load every model here first: a broken file is reported once, before any worker starts.
    std::vector<WorldModel> models;
    for (const auto& f : files) {
      WorldModel m = bench::LoadTrialWorld(loader, f, physics,
                                           vm.count("robot") ? std::optional<std::string>(robot) : std::nullopt);
      m.transports.clear();
      models.push_back(std::move(m));
    }
    batch::BatchOptions options;
    options.sim_seconds = duration;
    options.workers = workers;
    std::map<std::string, std::size_t> model_of;
    for (std::size_t w = 0; w < files.size(); ++w) {
      model_of[files[w].string()] = w;
      for (int k = 0; k < count; ++k) {
        options.jobs.push_back(batch::BatchJob{files[w], seed + static_cast<std::uint64_t>(options.jobs.size())});
      }
    }
    std::ostringstream warnings;
    StreamLog log(warnings, LogLevel::kError);
    const batch::WorldFactory factory = [&](const batch::BatchJob& job) {
      WorldModel m = models.at(model_of.at(job.world.string()));
      m.seed = job.seed;
      return std::make_unique<World>(m, registry, log, /*start_transports=*/false);
    };
    const bool tty = isatty(STDERR_FILENO) != 0;
    auto run = [&](int n) {
      options.workers = n;
      ProgressBar bar(tty);
      const std::string label = std::to_string(n) + (n == 1 ? " worker " : " workers");
      batch::BatchSummary s = batch::RunBatch(options, factory, [&](std::size_t done, std::size_t total, double f) {
        bar.Update(label, done, total, f);
      });
      bar.Clear();
      return s;
    };
    std::optional<batch::BatchSummary> single;
    if (vm.count("scaling")) single = run(1);
    const batch::BatchSummary summary = run(workers);

    std::printf("%4s %-10s %6s %8s %8s %10s  %s\n", "job", "world", "seed", "sim s", "wall s", "real-time", "state hash");
    for (const batch::BatchJobResult& j : summary.jobs) {
      if (!j.error.empty()) {
        std::printf("%4zu %-10s %6llu  FAILED: %s\n", j.index, j.world.c_str(), static_cast<unsigned long long>(j.seed),
                    j.error.c_str());
        continue;
      }
      std::printf("%4zu %-10s %6llu %8.2f %8.2f %9.1f×  %016llx\n", j.index, j.world.c_str(),
                  static_cast<unsigned long long>(j.seed), j.sim_seconds, j.wall_seconds, j.sim_seconds / j.wall_seconds,
                  static_cast<unsigned long long>(j.state_hash));
    }
    std::printf("%zu worlds on %d worker process%s: %.1f simulated s in %.2f wall s, throughput %.1f× real time\n",
                summary.jobs.size(), summary.workers, summary.workers == 1 ? "" : "es", summary.sim_seconds,
                summary.wall_seconds, summary.Throughput());
    int status = summary.Failed() ? kExitRuntime : kExitOk;
    if (single) {
      std::printf("1 worker: throughput %.1f× real time; %d workers: %.1f×; speed-up %.2f\n", single->Throughput(),
                  summary.workers, summary.Throughput(), summary.Throughput() / single->Throughput());
      for (std::size_t i = 0; i < summary.jobs.size(); ++i) {
        if (summary.jobs[i].state_hash != single->jobs[i].state_hash) {
          std::printf("job %zu: state hash differs between 1 and %d workers: not deterministic\n", i, summary.workers);
          status = kExitRuntime;
        }
      }
    }
    if (summary.Failed()) std::cerr << "ubersim batch: " << summary.Failed() << " worlds failed\n";
    return status;
  } catch (const ModelError& e) {
    std::cerr << "ubersim batch: invalid model: " << e.what() << "\n";
    return kExitModel;
  } catch (const PluginLoadError& e) {
    std::cerr << "ubersim batch: plugin error: " << e.what() << "\n";
    return kExitPlugin;
  } catch (const std::exception& e) {
    std::cerr << "ubersim batch: " << e.what() << "\n";
    return kExitRuntime;
  }
}

int SoakCommand(const std::vector<std::string>& args) {
  po::options_description desc(
      "usage: ubersim soak [WORLD] [options]\n\n"
      "Runs WORLD (a file or a shipped world's name; default div-a) headless and as fast as\n"
      "possible for --duration simulated seconds under seeded random play and random teleports\n"
      "(robots and the ball onto other robots, into walls and goals, at up to 3 m/s and 6.5 m/s),\n"
      "and checks the state every simulated second: no NaN or infinite value, nothing outside\n"
      "the walls or under the carpet, no robot inside another, nothing impossibly fast; and the\n"
      "resident memory stays flat after a warm-up. Prints each finding with its simulated time,\n"
      "progress, and a summary. Exit code 6 on any finding or memory growth of 5 % or more.\n\noptions");
  double duration = 3600.0, interval = 0.5, wall_overlap = 0.5;
  std::uint64_t seed = 1;
  PhysicsFlags physics_flags;
  std::string world_arg = "div-a", robot;
  std::vector<std::string> plugin_paths;
  desc.add_options()("help,h", "this help")
      ("duration", po::value<double>(&duration)->default_value(duration), "simulated seconds")
      ("seed", po::value<std::uint64_t>(&seed)->default_value(seed), "seed of the random play and the teleports")
      ("teleport-interval", po::value<double>(&interval)->default_value(interval), "mean simulated seconds between teleports")
      ("wall-overlap", po::value<double>(&wall_overlap)->default_value(wall_overlap),
       "how far into a wall a robot is teleported, as a share of the wall's thickness (0..1)")
      ("robot", po::value<std::string>(&robot), "put this robot model file in every robot's place")
      ("quiet,q", "no progress lines")
      ("log-teleports", "print every teleport with its simulated time (to chase a finding)")
      ("plugin-path", po::value<std::vector<std::string>>(&plugin_paths), "also search DIR for plugins (repeatable)");
  physics_flags.AddTo(desc);
  po::options_description hidden;
  hidden.add_options()("world", po::value<std::string>(&world_arg));
  po::positional_options_description pos;
  pos.add("world", 1);
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "soak", desc, vm, &hidden, &pos)) return *done;
  if (!(duration > 0) || !(interval > 0) || !(wall_overlap >= 0 && wall_overlap <= 1)) {
    std::cerr << "ubersim soak: --duration and --teleport-interval must be > 0, --wall-overlap 0..1\n";
    return kExitUsage;
  }
  PhysicsOverrides physics;
  if (!physics_flags.Read(vm, "soak", physics)) return kExitUsage;
  try {
    const fs::path file = WorldFileOf(world_arg);
    PluginRegistry registry(PluginSearchPath({file}, plugin_paths));
    const ModelLoader loader(ModelLoader::DefaultSchemaDir(), LookupIn(registry));
    WorldModel model = bench::LoadTrialWorld(loader, file, physics,
                                             vm.count("robot") ? std::optional<std::string>(robot) : std::nullopt);
    model.transports.clear();  // headless
    // Plugins' warnings and errors are shown as they come; none is expected.
    StreamLog log(std::cerr, LogLevel::kWarning);
    World world(model, registry, log, /*start_transports=*/false);
    soak::SoakOptions options;
    options.sim_seconds = duration;
    options.seed = seed;
    options.teleport_interval = interval;
    options.wall_overlap = wall_overlap;
    if (vm.count("log-teleports")) {
      options.on_teleport = [](double t, const char* what, const PositionEvent& e) {
        const std::string who = e.target.is_ball
                                    ? std::string("ball")
                                    : std::string(e.target.robot.team == Team::kBlue ? "robot blue " : "robot yellow ") +
                                          std::to_string(e.target.robot.id);
        const Vec3 p = e.position.value_or(Vec3::Constant(NAN));
        const Vec3 v = e.velocity.value_or(Vec3::Zero());
        std::printf("t = %.3f s: teleport (%s): %s to (%.3f, %.3f, %.3f) m, yaw %.3f rad, velocity (%.2f, %.2f, %.2f) m/s\n", t,
                    what, who.c_str(), p.x(), p.y(), p.z(), e.yaw.value_or(0.0), v.x(), v.y(), v.z());
      };
    }
    std::printf("soak %s (%s): %.0f s simulated, seed %llu, %zu robots, physics step %.2f ms\n", model.name.c_str(),
                file.string().c_str(), duration, static_cast<unsigned long long>(seed), model.robots.size(),
                model.physics.step * 1e3);
    std::fflush(stdout);
    const bool quiet = vm.count("quiet") > 0;
    const bool tty = isatty(STDERR_FILENO) != 0;
    double next_line = 0;
    const auto report = soak::RunSoak(
        world, options,
        [&](const soak::SoakProgress& p) {
          if (quiet) return;
          char line[200];
          std::snprintf(line, sizeof line, "sim %7.0f / %.0f s | wall %7.1f s | %5.2f× real time | %6.1f MB | %lld findings",
                        p.sim_time, p.sim_seconds, p.wall_seconds, p.sim_time / std::max(p.wall_seconds, 1e-9), p.rss_mb,
                        static_cast<long long>(p.findings));
          if (tty) {
            std::fprintf(stderr, "\r%s\033[K", line);
          } else if (p.sim_time >= next_line) {  // a log file: one line a simulated minute
            std::fprintf(stderr, "%s\n", line);
            next_line = p.sim_time + 60.0;
          }
          std::fflush(stderr);
        },
        [&](const soak::SoakFinding& f) {
          if (tty && !quiet) std::fprintf(stderr, "\r\033[K");
          std::printf("t = %.3f s: %s: %s\n", f.sim_time, ToString(f.violation.issue), f.violation.Describe().c_str());
          std::fflush(stdout);
        });
    if (tty && !quiet) std::fprintf(stderr, "\r\033[K");
    std::cout << soak::FormatSummary(report);
    return report.Pass() ? kExitOk : kExitSoakFailed;
  } catch (const ModelError& e) {
    std::cerr << "ubersim soak: invalid model: " << e.what() << "\n";
    return kExitModel;
  } catch (const PluginLoadError& e) {
    std::cerr << "ubersim soak: plugin error: " << e.what() << "\n";
    return kExitPlugin;
  } catch (const PluginError& e) {
    std::cerr << "ubersim soak: plugin error: " << e.what() << "\n";
    return kExitPlugin;
  } catch (const std::exception& e) {
    std::cerr << "ubersim soak: " << e.what() << "\n";
    return kExitRuntime;
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    std::cout << kTopHelp;
    return args.empty() ? kExitUsage : kExitOk;
  }
  if (args[0] == "--version") {
    std::cout << "ubersim " << UBERSIM_VERSION << " (SDK " << kSdkVersionMajor << "."
              << kSdkVersionMinor << ", plugin ABI " << kPluginAbiVersion << ")\n";
    return kExitOk;
  }
  const std::string command = args[0];
  args.erase(args.begin());
  if (command == "run") return RunCommand(args);
  if (command == "validate") return ValidateCommand(args);
  if (command == "plugins") return PluginsCommand(args);
  if (command == "validate-physics") return ValidatePhysicsCommand(args);
  if (command == "bench") return BenchCommand(args);
  if (command == "batch") return BatchCommand(args);
  if (command == "soak") return SoakCommand(args);
  std::cerr << "ubersim: unknown command '" << command << "'\n\n" << kTopHelp;
  return kExitUsage;
}
