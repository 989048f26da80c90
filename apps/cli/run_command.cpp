// SPDX-License-Identifier: Apache-2.0
// `ubersim run [WORLD]`: builds a world with its transports and steps it in real time (or
// faster), with snapshots on request and a crash report when a plugin fault or a crash ends it.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "ubersim/kernel/data_paths.hpp"
#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/runner.hpp"
#include "ubersim/kernel/snapshot.hpp"
#include "ubersim/kernel/world.hpp"
#include "command_line.hpp"
#include "commands.hpp"
#include "exit_codes.hpp"
#include "match_flags.hpp"
#include "progress.hpp"
#include "run_overrides.hpp"
#include "world_loading.hpp"

namespace ubersim::cli {
namespace {

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace ubersim::kernel;

// Process-wide state, set by signal handlers and read by the run loop: stop (SIGINT, SIGTERM)
// and save a snapshot (SIGUSR1). (The crash guard keeps its own: CrashGuard, runner.hpp.)
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

// What the run's command line says beside the world.
struct RunFlags {
  std::string world_arg;
  double duration = 0, speed = 1.0;
  std::string log_level = "info";
  std::vector<std::string> plugin_paths;
  std::vector<std::string> skipped_transports;
  std::string restore_file, snapshot_out, crash_dir = ".";
  double crash_snapshot_interval = 1.0;
  RunOverrides overrides;
  PhysicsFlags physics;
  MatchFlags match;
};

// The run's options, bound to `f`.
po::options_description RunOptionsOf(RunFlags& f) {
  po::options_description desc(
      "usage: ubersim run [WORLD] [options]\n\n"
      "Runs WORLD (default models/worlds/div-b.yaml) in real time, printing where it publishes\n"
      "(the browser viewer's address among them) and a live status line (sim time, real-time\n"
      "factor). Ctrl-C stops it. --restore starts from a snapshot; --snapshot-out saves one when\n"
      "the run ends and on SIGUSR1. A plugin fault under the world's on_plugin_fault: stop ends\n"
      "the run with exit code 7, a crash report and a snapshot in --crash-dir; so does a crash\n"
      "(a fatal signal: the report holds the last periodic snapshot).\n\noptions");
  desc.add_options()("help,h", "this help")
      ("fast", "run as fast as possible instead of real time")
      ("speed", po::value<double>(&f.speed)->default_value(1.0), "speed factor (sim s per wall s)")
      ("duration", po::value<double>(&f.duration)->default_value(0), "stop after SECONDS of simulated time (0: run until stopped)")
      ("paused", "start paused")
      ("quiet,q", "no status line")
      ("local-only", "keep every transport on loopback (127.0.0.1): nothing sent to or reachable from another machine")
      ("realism", po::value<std::string>(&f.overrides.realism),
       "vision and radio preset: ÜberSim's ideal, 2003, realistic, or the league's None, Friendly, RC2021, Realistic "
       "(every RealismConfigErForce field exactly; docs/interfaces.md)")
      ("field,g", po::value<std::string>(&f.overrides.field),
       "field: div-a or div-b (also ER-Force's 2020, 2023, 2023B); the formation scales with it")
      ("vision-address", po::value<std::string>(&f.overrides.vision_address), "SSL-Vision multicast group (default 224.5.23.2)")
      ("no-viewer", "do not start the browser viewer (the same as --no-transport viewer)")
      ("no-transport", po::value<std::vector<std::string>>(&f.skipped_transports), "do not start the world's transport ID (repeatable)")
      ("plugin-path", po::value<std::vector<std::string>>(&f.plugin_paths), "also search DIR for plugins (repeatable)")
      ("log-level", po::value<std::string>(&f.log_level)->default_value("info"), "debug, info, warning or error")
      ("restore", po::value<std::string>(&f.restore_file), "start from the snapshot FILE (of this world)")
      ("snapshot-out", po::value<std::string>(&f.snapshot_out), "save a snapshot to FILE when the run ends and on SIGUSR1")
      ("crash-dir", po::value<std::string>(&f.crash_dir)->default_value("."), "where crash reports and their snapshots go")
      ("crash-snapshot-interval", po::value<double>(&f.crash_snapshot_interval)->default_value(1.0),
       "simulated seconds between the in-memory snapshots a crash report writes (0: none)");
  AddPortFlags(desc);
  f.physics.AddTo(desc);
  po::options_description match("match (docs/match.md)");
  f.match.AddTo(match);
  desc.add(match);
  return desc;
}

// Applies the command line's changes to `model`: the overrides (their notes printed), the
// transports left out. Throws OverrideError, UsageError (a transport the world has not) or ModelError.
void ApplyFlags(RunFlags& f, const po::variables_map& vm, WorldModel& model, const WorldLoading& loading) {
  f.overrides.local_only = vm.count("local-only") > 0;
  f.match.FromWorld(model.match, vm);
  if (!vm["referee-port"].defaulted()) f.overrides.viewer_referee_port = f.match.referee_port;
  ReadPortFlags(vm, f.overrides.ports);
  kernel::PhysicsOverrides physics;
  if (const auto why = f.physics.Problem(vm)) throw UsageError(*why);
  f.physics.Read(vm, "run", physics);
  physics.ApplyTo(model.physics);
  for (const std::string& note : ApplyRunOverrides(f.overrides, model, loading.loader, *loading.registry)) {
    std::cerr << "ubersim: " << note << "\n";
  }
  if (vm.count("no-viewer")) f.skipped_transports.push_back("viewer");
  for (const std::string& id : f.skipped_transports) {
    const auto removed = std::erase_if(model.transports, [&](const TransportModel& t) { return t.plugin == id; });
    if (removed == 0 && id != "viewer") throw UsageError("--no-transport " + id + ": the world has no such transport");
    if (removed > 0) std::cerr << "ubersim: transport " << id << " not started (--no-" << (id == "viewer" ? "viewer" : "transport") << ")\n";
  }
}

// Prints the world loaded and where it publishes.
void PrintWorld(const WorldModel& model, const fs::path& world_file, const World& world) {
  std::cerr << "ubersim: world '" << model.name << "' from " << world_file.string() << ": "
            << model.robots.size() << " robots, field " << model.field->geometry.name
            << ", ball " << model.ball->name << "\n";
  std::cerr << "ubersim: physics " << DescribePhysics(model.physics) << "\n";
  const auto endpoints = world.TransportEndpoints();
  if (endpoints.empty()) std::cerr << "ubersim: publishing nowhere (the world file configures no transports)\n";
  for (const auto& e : endpoints) std::cerr << "ubersim: publishing " << e << "\n";
}

// The status line's text.
std::string StatusText(const RunStatus& s) {
  char line[160];
  std::snprintf(line, sizeof line, "sim %10.3f s | real-time factor %7.2f | steps %lld%s", s.sim_time,
                s.real_time_factor, static_cast<long long>(s.steps), s.paused ? " | paused" : "");
  return line;
}

// Steps `world` until the end of the run: signals, snapshots (--snapshot-out, SIGUSR1), the
// crash guard's periodic snapshot, the status line; then the fault report when a plugin fault
// stopped it. Returns the exit code.
int Step(World& world, const WorldModel& model, const fs::path& world_file, const RunFlags& f,
         const po::variables_map& vm, const std::vector<std::string>& args, Log& log) {
  // The referee, tracker and recorder beside the world (--referee, --tracker, --record).
  std::unique_ptr<sslog::LogWriter> record;
  std::unique_ptr<match::MatchSession> session;
  if (f.match.Any()) {
    session = std::make_unique<match::MatchSession>(world, f.match.Options(model, f.overrides.local_only, record), log);
    for (const auto& e : session->Endpoints()) std::cerr << "ubersim: publishing " << e << "\n";
    if (!session->GameController().empty()) std::cerr << "ubersim: refereed by " << session->GameController() << "\n";
    if (record) std::cerr << "ubersim: recording to " << record->Path() << "\n";
  }
  ProgressLine status(/*shown=*/vm.count("quiet") == 0);
  RunOptions options;
  options.duration = f.duration;
  options.speed_factor = vm.count("fast") ? 0.0 : f.speed;
  options.start_paused = vm.count("paused") > 0;
  options.status_interval = status.OnTerminal() ? 0.25 : 2.0;
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::signal(SIGUSR1, OnSnapshotSignal);

  const RunDescription run{std::string("ubersim ") + UBERSIM_VERSION, model.name, world_file.string(),
                           CommandLineText("run", args)};
  const CrashFiles crash_files = CrashFilesIn(f.crash_dir, model.name);
  // A crash (a fatal signal) writes the last of these snapshots, kept in memory.
  CrashGuard guard(crash_files, run);
  guard.Install();
  const auto crash_interval_ns = static_cast<std::int64_t>(f.crash_snapshot_interval * 1e9 + 0.5);
  std::int64_t next_crash_snapshot_ns = world.clock().time_ns();
  const auto save_snapshot = [&](const char* why) {
    try {
      WriteSnapshotFile(f.snapshot_out, world.Save());
      std::cerr << "ubersim: snapshot of step " << world.clock().steps() << " written to " << f.snapshot_out << " ("
                << why << ")\n";
    } catch (const std::exception& e) {  // the run goes on: a snapshot not saved is no error
      std::cerr << "ubersim: no snapshot written: " << e.what() << "\n";
    }
  };
  options.between_steps = [&] {
    if (session) session->AfterStep();
    if (SnapshotRequested().exchange(false)) {
      if (f.snapshot_out.empty()) {
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
    if (status.OnTerminal() && !s.finished) {
      status.Redraw(StatusText(s));
    } else {
      status.Write(StatusText(s));
    }
  });
  std::cerr << "ubersim: stopped at sim time " << final_status.sim_time << " s after "
            << final_status.steps << " steps\n";
  if (session && session->referee()) {
    const auto& m = session->referee()->message();
    std::cerr << "ubersim: " << m.yellow().name() << " (yellow) " << m.yellow().score() << " : " << m.blue().score() << " "
              << m.blue().name() << " (blue), stage " << Referee::Stage_Name(m.stage()) << "\n";
  }
  if (record) {
    record->Close();
    std::cerr << "ubersim: recorded " << record->Records() << " messages to " << record->Path() << "\n";
  }
  if (!f.snapshot_out.empty()) save_snapshot(world.stopped() ? "the world stopped" : "end of run");
  if (!world.stopped()) return kExitOk;
  WriteFaultReport(world, crash_files, run);
  std::cerr << "ubersim: a plugin fault stopped the world (on_plugin_fault: stop); crash report "
            << crash_files.report.string() << ", snapshot " << crash_files.snapshot.string() << "\n";
  return kExitPluginFault;
}

}  // namespace

int RunCommand(const std::vector<std::string>& args) {
  RunFlags f;
  const po::options_description desc = RunOptionsOf(f);
  po::options_description hidden;
  hidden.add_options()("world", po::value<std::string>(&f.world_arg));
  po::positional_options_description pos;
  pos.add("world", 1);
  po::variables_map vm;
  if (const auto done = ParseCommandLine(args, "run", desc, vm, &hidden, &pos)) return *done;
  if (f.duration < 0 || f.speed < 0 || !(f.crash_snapshot_interval >= 0)) {
    std::cerr << "ubersim run: --duration, --speed and --crash-snapshot-interval must be >= 0\n";
    return kExitUsage;
  }
  StreamLog log(std::cerr, LogLevelOf(f.log_level));

  const fs::path world_file = f.world_arg.empty() ? DefaultWorldFile() : WorldFileOf(f.world_arg);
  LoadedWorld loaded = LoadWorldWithPlugins(world_file, f.plugin_paths);
  WorldModel& model = loaded.model;
  ApplyFlags(f, vm, model, loaded.loading);
  World world(model, *loaded.loading.registry, log);
  for (const std::string& skipped : loaded.loading.registry->Skipped()) log.Warning("plugin library " + skipped);
  if (!f.restore_file.empty()) {
    world.Restore(ReadSnapshotFile(f.restore_file));
    std::cerr << "ubersim: restored " << f.restore_file << ": step " << world.clock().steps() << ", sim time "
              << world.clock().seconds() << " s\n";
  }
  PrintWorld(model, world_file, world);
  return Step(world, model, world_file, f, vm, args, log);
}

}  // namespace ubersim::cli
