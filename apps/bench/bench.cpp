// SPDX-License-Identifier: Apache-2.0
#include "bench.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "bare_ode_mirror.hpp"

namespace ubersim::kernel::bench {
namespace {

using SteadyClock = std::chrono::steady_clock;

double Seconds(std::int64_t ns) { return static_cast<double>(ns) * 1e-9; }

// CPU time this thread has used, s.
double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

StepTimings Minus(const StepTimings& a, const StepTimings& b) {
  return StepTimings{a.events_ns - b.events_ns,       a.plugins_ns - b.plugins_ns,
                     a.collision_ns - b.collision_ns, a.physics_ns - b.physics_ns,
                     a.transports_ns - b.transports_ns, a.perception_ns - b.perception_ns};
}

}  // namespace

std::vector<BenchResult> RunBench(const BenchOptions& options, PluginRegistry& registry,
                                  const ModelLoader& loader, Log& log,
                                  const std::function<void(const std::string&, double)>& progress) {
  std::vector<BenchResult> results;
  for (const auto& file : options.worlds) {
    WorldModel model = LoadTrialWorld(loader, file, options.physics, options.robot_model);
    if (!options.with_transports) model.transports.clear();  // headless: no sockets by default
    model.local_only = true;  // a measurement sends to nobody else

    BenchResult r;
    r.world = model.name;
    r.file = file.string();
    r.robots = static_cast<int>(model.robots.size());
    r.profile = model.physics.profile;
    r.physics_step = model.physics.step;
    r.solver_iterations = model.physics.solver_iterations;
    r.solver_iterations_without_ball = model.physics.IterationsWithoutBall();
    r.max_contacts = model.physics.max_contacts;
    r.rss_before_mb = ResidentMegabytes();

    World world(model, registry, log, /*start_transports=*/options.with_transports);
    std::unique_ptr<BareOdeMirror> mirror;
    if (options.baseline) mirror = std::make_unique<BareOdeMirror>(world, options.seed);
    if (mirror) {
      r.bodies = mirror->bodies();
      r.geoms = mirror->geoms();
      r.joints = mirror->joints();
    }
    RandomPlay play(world, options.seed);
    const auto steps = static_cast<std::int64_t>(std::llround(options.sim_seconds / world.clock().step_seconds()));
    const std::int64_t report_every = std::max<std::int64_t>(1, steps / 50);
    double peak = ResidentMegabytes();

    // Kernel and baseline take turns, a stretch of steps each, each timed on its own: the
    // baseline's motors follow the kernel's (set by the drive plugins), its one-body robots the
    // kernel's and its ball the random play's kicks, recorded step by step, so both worlds drive
    // the same way and make about the same contacts. Stretches, not single steps: stepped in
    // lockstep, each world ran on the processor caches the other had just filled.
    constexpr std::size_t kStretch = 250;
    const StepTimings before = world.timings();
    SteadyClock::duration kernel_time{}, baseline_time{};
    const double cpu_start = ThreadCpuSeconds();
    const auto loop_start = SteadyClock::now();
    for (std::int64_t i = 0; i < steps; ++i) {
      const bool ball_moved = play.BeforeStep();
      const auto t0 = SteadyClock::now();
      world.Step();
      const auto t1 = SteadyClock::now();
      kernel_time += t1 - t0;
      if (mirror) {
        mirror->Record(ball_moved);
        if (mirror->recorded() == kStretch || i + 1 == steps) {
          baseline_time += mirror->StepRecorded();
        }
      }
      if (i % report_every == 0) {
        peak = std::max(peak, ResidentMegabytes());
        if (progress) progress(r.world, static_cast<double>(i) / static_cast<double>(steps));
      }
    }
    const double loop_wall = std::chrono::duration<double>(SteadyClock::now() - loop_start).count();
    if (loop_wall > 0) r.cpu_share = std::clamp((ThreadCpuSeconds() - cpu_start) / loop_wall, 0.01, 1.0);
    r.wall_seconds = std::chrono::duration<double>(kernel_time).count();
    const StepTimings t = Minus(world.timings(), before);
    r.sim_seconds = world.clock().seconds();
    r.real_time_factor = r.sim_seconds / r.wall_seconds;
    r.steps_per_second = static_cast<double>(steps) / r.wall_seconds;
    r.step_microseconds = 1e6 * r.wall_seconds / static_cast<double>(steps);
    r.split.collision = Seconds(t.collision_ns) / r.wall_seconds;
    r.split.physics = Seconds(t.physics_ns) / r.wall_seconds;
    r.split.plugins = Seconds(t.plugins_ns) / r.wall_seconds;
    r.split.perception = Seconds(t.perception_ns) / r.wall_seconds;
    r.split.transports = Seconds(t.transports_ns) / r.wall_seconds;
    r.split.events = Seconds(t.events_ns) / r.wall_seconds;
    r.split.other = std::max(0.0, 1.0 - r.split.collision - r.split.physics - r.split.plugins -
                                      r.split.perception - r.split.transports - r.split.events);
    r.rss_peak_mb = std::max(peak, ResidentMegabytes());
    if (mirror) {
      r.baseline = true;
      r.baseline_wall_seconds = std::chrono::duration<double>(baseline_time).count();
      r.baseline_real_time_factor = r.sim_seconds / r.baseline_wall_seconds;
      r.kernel_overhead = r.wall_seconds / r.baseline_wall_seconds - 1.0;
    }
    if (progress) progress(r.world, 1.0);
    results.push_back(r);
  }
  return results;
}

namespace {
std::string Fixed1(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", x);
  return b;
}
}  // namespace

std::string FormatTable(const std::vector<BenchResult>& results) {
  std::ostringstream out;
  char line[512];
  std::snprintf(line, sizeof line, "%-10s %-8s %6s %7s %5s %9s %10s %8s | %6s %6s %6s %6s %6s %6s %6s | %8s | %9s %9s\n",
                "world", "profile", "robots", "step ms", "iter", "real-time", "steps/s", "µs/step", "coll", "ode",
                "plugin", "percep", "transp", "events", "other", "peak MB", "bare ODE", "overhead");
  out << line;
  for (const BenchResult& r : results) {
    char baseline[64] = "-";
    char overhead[64] = "-";
    if (r.baseline) {
      std::snprintf(baseline, sizeof baseline, "%.1f×", r.baseline_real_time_factor);
      std::snprintf(overhead, sizeof overhead, "%+.1f %%", 100.0 * r.kernel_overhead);
    }
    std::snprintf(line, sizeof line,
                  "%-10s %-8s %6d %7.2f %5s %8.1f× %10.0f %8.1f | %5.1f%% %5.1f%% %5.1f%% %5.1f%% %5.1f%% %5.1f%% %5.1f%% | %8.1f | %9s %9s\n",
                  r.world.c_str(), r.profile.c_str(), r.robots, r.physics_step * 1e3, r.Iterations().c_str(), r.real_time_factor,
                  r.steps_per_second, r.step_microseconds, 100 * r.split.collision, 100 * r.split.physics,
                  100 * r.split.plugins, 100 * r.split.perception, 100 * r.split.transports, 100 * r.split.events,
                  100 * r.split.other,
                  r.rss_peak_mb, baseline, overhead);
    out << line;
  }
  for (const BenchResult& r : results) {
    if (r.cpu_share >= 0.95) continue;
    std::snprintf(line, sizeof line,
                  "%s: the bench thread was on a CPU %.0f %% of the time (other work on the machine): by CPU "
                  "time %.1f× real time%s\n",
                  r.world.c_str(), 100 * r.cpu_share, r.real_time_factor / r.cpu_share,
                  r.baseline ? (", bare ODE " + Fixed1(r.baseline_real_time_factor / r.cpu_share) + "×").c_str() : "");
    out << line;
  }
  return out.str();
}

std::string FormatMarkdown(const std::vector<BenchResult>& results, const std::string& machine,
                           const std::string& command) {
  std::ostringstream out;
  out << "Machine: " << machine << "\n\nCommand: `" << command << "`\n\n";
  out << "| world | profile | robots | bodies / geoms / joints | step | iterations | contacts per pair | real-time factor | steps/s | collision | ODE step | plugins | perception | transports | events | other | peak memory | bare ODE | kernel overhead |\n";
  out << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  char line[1024];
  for (const BenchResult& r : results) {
    char baseline[64] = "-";
    char overhead[64] = "-";
    if (r.baseline) {
      std::snprintf(baseline, sizeof baseline, "%.1f×", r.baseline_real_time_factor);
      std::snprintf(overhead, sizeof overhead, "%+.0f %%", 100.0 * r.kernel_overhead);
    }
    std::snprintf(line, sizeof line,
                  "| %s | %s | %d | %d / %d / %d | %.2f ms | %s | %d | **%.1f×** | %.0f | %.0f %% | %.0f %% | %.0f %% | %.0f %% | %.0f %% | %.0f %% | %.0f %% | %.1f MB | %s | %s |\n",
                  r.world.c_str(), r.profile.c_str(), r.robots, r.bodies, r.geoms, r.joints, r.physics_step * 1e3,
                  r.Iterations().c_str(), r.max_contacts, r.real_time_factor, r.steps_per_second, 100 * r.split.collision,
                  100 * r.split.physics, 100 * r.split.plugins, 100 * r.split.perception, 100 * r.split.transports,
                  100 * r.split.events,
                  100 * r.split.other, r.rss_peak_mb, baseline, overhead);
    out << line;
  }
  for (const BenchResult& r : results) {
    if (r.cpu_share >= 0.95) continue;
    out << "\n" << r.world << ": the bench thread was on a CPU " << Fixed1(100 * r.cpu_share)
        << " % of the time (other work on the machine): by CPU time " << Fixed1(r.real_time_factor / r.cpu_share)
        << "× real time";
    if (r.baseline) out << ", bare ODE " << Fixed1(r.baseline_real_time_factor / r.cpu_share) << "×";
    out << ".\n";
  }
  return out.str();
}

}  // namespace ubersim::kernel::bench
