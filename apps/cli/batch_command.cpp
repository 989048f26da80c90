// SPDX-License-Identifier: Apache-2.0
// `ubersim batch [WORLD…]`: many seeded copies of worlds on worker processes, their final state
// hashes and the throughput.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/world.hpp"
#include "batch.hpp"
#include "bench.hpp"
#include "command_line.hpp"
#include "commands.hpp"
#include "exit_codes.hpp"
#include "progress.hpp"
#include "world_loading.hpp"

namespace ubersim::cli {
namespace {

namespace po = boost::program_options;
namespace batch = kernel::batch;
namespace bench = kernel::bench;
namespace fs = std::filesystem;
using kernel::WorldModel;

// The progress line's text: a bar, jobs done, percent, time left.
std::string BatchProgress(const std::string& what, std::size_t done, std::size_t total, double fraction,
                          double elapsed) {
  char eta[32] = "";
  if (fraction > 0.02 && fraction < 1.0) std::snprintf(eta, sizeof eta, ", %.0f s left", elapsed * (1.0 / fraction - 1.0));
  char text[256];
  std::snprintf(text, sizeof text, "%s %s %zu/%zu worlds, %3.0f %%%s", what.c_str(), Bar(fraction).c_str(), done, total,
                fraction * 100.0, eta);
  return text;
}

// Runs `options` on `workers` processes with a progress line.
batch::BatchSummary RunWithProgress(batch::BatchOptions options, int workers, const batch::WorldFactory& factory) {
  options.workers = workers;
  ProgressLine progress;
  const auto start = std::chrono::steady_clock::now();
  const std::string label = std::to_string(workers) + (workers == 1 ? " worker " : " workers");
  batch::BatchSummary s = batch::RunBatch(options, factory, [&](std::size_t done, std::size_t total, double f) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    progress.Redraw(BatchProgress(label, done, total, f, elapsed));
  });
  progress.Clear();
  return s;
}

// Prints each job's line and the total; returns the exit code (a failed world: 1).
int PrintSummary(const batch::BatchSummary& summary) {
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
  return summary.Failed() ? kExitRuntime : kExitOk;
}

// --scaling: the speed-up over one worker; 1 when a state hash differs between the two runs.
int PrintScaling(const batch::BatchSummary& single, const batch::BatchSummary& summary) {
  int status = kExitOk;
  std::printf("1 worker: throughput %.1f× real time; %d workers: %.1f×; speed-up %.2f\n", single.Throughput(),
              summary.workers, summary.Throughput(), summary.Throughput() / single.Throughput());
  for (std::size_t i = 0; i < summary.jobs.size(); ++i) {
    if (summary.jobs[i].state_hash != single.jobs[i].state_hash) {
      std::printf("job %zu: state hash differs between 1 and %d workers: not deterministic\n", i, summary.workers);
      status = kExitRuntime;
    }
  }
  return status;
}

}  // namespace

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
  kernel::PhysicsOverrides physics;
  if (!physics_flags.Read(vm, "batch", physics)) return kExitUsage;
  if (worlds.empty()) worlds.push_back("div-b");
  std::vector<fs::path> files;
  for (const std::string& w : worlds) files.push_back(WorldFileOf(w));
  const WorldLoading loading = LoadingFor(files, plugin_paths);
  // Load every model here first: a broken file is reported once, before any worker starts.
  std::vector<WorldModel> models;
  for (const auto& f : files) {
    WorldModel m = bench::LoadTrialWorld(loading.loader, f, physics,
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
  kernel::StreamLog log(warnings, LogLevel::kError);
  const batch::WorldFactory factory = [&](const batch::BatchJob& job) {
    WorldModel m = models.at(model_of.at(job.world.string()));
    m.seed = job.seed;
    return std::make_unique<kernel::World>(m, *loading.registry, log, /*start_transports=*/false);
  };
  std::optional<batch::BatchSummary> single;
  if (vm.count("scaling")) single = RunWithProgress(options, 1, factory);
  const batch::BatchSummary summary = RunWithProgress(options, workers, factory);
  int status = PrintSummary(summary);
  if (single) status = std::max(status, PrintScaling(*single, summary));
  if (summary.Failed()) std::cerr << "ubersim batch: " << summary.Failed() << " worlds failed\n";
  return status;
}

}  // namespace ubersim::cli
