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

// The robots' drives, "omni" or "omni+diff".
std::string Drives(const WorldModel& model) {
  std::vector<std::string> drives;
  for (const RobotPlacement& p : model.robots) {
    const std::string d = p.model && p.model->drive ? p.model->drive->plugin : "none";
    if (std::find(drives.begin(), drives.end(), d) == drives.end()) drives.push_back(d);
  }
  std::string out;
  for (const std::string& d : drives) out += (out.empty() ? "" : "+") + d;
  return out;
}

std::string Label(const std::string& world, std::optional<int> robot_count) {
  return robot_count ? world + " ×" + std::to_string(*robot_count) : world;
}

// The timed run of one world with its own robots, or `robot_count` of them.
BenchResult TimedRun(const BenchOptions& options, const std::filesystem::path& file, std::optional<int> robot_count,
                     PluginRegistry& registry, const ModelLoader& loader, Log& log,
                     const std::function<void(const std::string&, double)>& progress) {
  WorldModel model = LoadTrialWorld(loader, file, options.physics, options.robot_model);
  if (robot_count) PlaceRobots(model, *robot_count);
  if (!options.with_transports) model.transports.clear();  // headless: no sockets by default
  model.local_only = true;  // a measurement sends to nobody else

  BenchResult r;
  r.world = model.name;
  r.file = file.string();
  r.robots = static_cast<int>(model.robots.size());
  r.drive = Drives(model);
  const std::string label = Label(r.world, robot_count);
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
  std::uint64_t contacts = 0, touching = 0, narrow = 0;
  for (std::int64_t i = 0; i < steps; ++i) {
    const bool ball_moved = play.BeforeStep();
    const auto t0 = SteadyClock::now();
    world.Step();
    const auto t1 = SteadyClock::now();
    kernel_time += t1 - t0;
    // The collision pass's counts of the step just made (outside the timed part).
    const KernelCollisionCounts collided = LastCollisionCounts(world);
    contacts += collided.contacts;
    touching += collided.touching_pairs;
    narrow += collided.narrow_tests;
    if (mirror) {
      mirror->Record(ball_moved);
      if (mirror->recorded() == kStretch || i + 1 == steps) {
        baseline_time += mirror->StepRecorded();
      }
    }
    if (i % report_every == 0) {
      peak = std::max(peak, ResidentMegabytes());
      if (progress) progress(label, static_cast<double>(i) / static_cast<double>(steps));
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
  r.contacts_per_step = static_cast<double>(contacts) / static_cast<double>(steps);
  r.touching_pairs_per_step = static_cast<double>(touching) / static_cast<double>(steps);
  r.narrow_tests_per_step = static_cast<double>(narrow) / static_cast<double>(steps);
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
  if (progress) progress(label, 1.0);
  return r;
}

// The timed run, then (when asked) the callgrind runs, once its world is gone.
BenchResult RunOne(const BenchOptions& options, const std::filesystem::path& file, std::optional<int> robot_count,
                   PluginRegistry& registry, const ModelLoader& loader, Log& log,
                   const std::function<void(const std::string&, double)>& progress) {
  BenchResult r = TimedRun(options, file, robot_count, registry, loader, log, progress);
  if (!options.instructions) return r;
  CallgrindRun run;
  run.valgrind = options.instructions->valgrind;
  run.program = options.instructions->program;
  run.arguments = CallgrindArguments(options, file, robot_count);
  run.arguments.insert(run.arguments.end(), options.instructions->extra_arguments.begin(),
                       options.instructions->extra_arguments.end());
  run.short_seconds = options.instructions->short_seconds;
  run.long_seconds = options.instructions->long_seconds;
  run.physics_step = r.physics_step;
  const std::string label = Label(r.world, robot_count) + " under callgrind";
  if (progress) progress(label, 0.0);
  r.instructions = MeasureInstructions(run);
  if (progress) progress(label, 1.0);
  return r;
}

}  // namespace

std::vector<std::string> CallgrindArguments(const BenchOptions& options, const std::filesystem::path& world,
                                            std::optional<int> robot_count) {
  auto number = [](double x) {
    char b[40];
    std::snprintf(b, sizeof b, "%.17g", x);
    return std::string(b);
  };
  std::vector<std::string> a = {"bench", std::filesystem::absolute(world).string(), "--no-baseline", "--seed",
                                std::to_string(options.seed)};
  if (robot_count) a.insert(a.end(), {"--robot-count", std::to_string(*robot_count)});
  if (options.robot_model) a.insert(a.end(), {"--robot", std::filesystem::absolute(*options.robot_model).string()});
  const PhysicsOverrides& p = options.physics;
  if (p.profile) a.insert(a.end(), {"--profile", *p.profile});
  if (p.step) a.insert(a.end(), {"--physics-step", number(*p.step)});
  if (p.solver_iterations) a.insert(a.end(), {"--solver-iterations", std::to_string(*p.solver_iterations)});
  if (p.solver_iterations_without_ball) {
    a.insert(a.end(), {"--solver-iterations-without-ball", std::to_string(*p.solver_iterations_without_ball)});
  }
  if (p.max_contacts) a.insert(a.end(), {"--max-contacts", std::to_string(*p.max_contacts)});
  if (options.with_transports) a.push_back("--with-transports");
  return a;
}

std::vector<BenchResult> RunBench(const BenchOptions& options, PluginRegistry& registry,
                                  const ModelLoader& loader, Log& log,
                                  const std::function<void(const std::string&, double)>& progress) {
  std::vector<BenchResult> results;
  for (const auto& file : options.worlds) {
    if (options.robot_counts.empty()) {
      results.push_back(RunOne(options, file, std::nullopt, registry, loader, log, progress));
    }
    for (int count : options.robot_counts) {
      results.push_back(RunOne(options, file, count, registry, loader, log, progress));
    }
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

namespace {
// Instructions per step (3 decimals) or per simulated second (1), in millions; "-" when not counted.
std::string Millions(const BenchResult& r, double InstructionFigures::*figure) {
  if (!r.instructions) return "-";
  char b[32];
  std::snprintf(b, sizeof b, figure == &InstructionFigures::per_step ? "%.3f" : "%.1f",
                (*r.instructions).*figure * 1e-6);
  return b;
}
}  // namespace

std::string FormatWorkTable(const std::vector<BenchResult>& results) {
  std::ostringstream out;
  char line[512];
  std::snprintf(line, sizeof line, "%-10s %-8s %-10s %6s %8s %9s %11s %11s %9s %8s %8s | %6s %6s %6s %6s %6s\n", "world",
                "profile", "drive", "robots", "µs/step", "real-time", "Minstr/step", "Minstr/sim s", "contacts",
                "pairs", "narrow", "coll", "ode", "plugin", "percep", "other");
  out << line;
  for (const BenchResult& r : results) {
    const TimeSplit& s = r.split;
    std::snprintf(line, sizeof line,
                  "%-10s %-8s %-10s %6d %8.1f %8.1f× %11s %11s %9.1f %8.1f %8.1f | %5.1f%% %5.1f%% %5.1f%% %5.1f%% %5.1f%%\n",
                  r.world.c_str(), r.profile.c_str(), r.drive.c_str(), r.robots, r.step_microseconds,
                  r.real_time_factor, Millions(r, &InstructionFigures::per_step).c_str(),
                  Millions(r, &InstructionFigures::per_sim_second).c_str(), r.contacts_per_step,
                  r.touching_pairs_per_step, r.narrow_tests_per_step, 100 * s.collision, 100 * s.physics,
                  100 * s.plugins, 100 * s.perception, 100 * (s.transports + s.events + s.other));
    out << line;
  }
  out << "contacts: contact joints a step; pairs: geometry pairs touching; narrow: pairs the narrow phase tested "
         "(means per step)\n";
  for (const BenchResult& r : results) {
    if (!r.instructions) continue;
    const InstructionFigures& f = *r.instructions;
    std::snprintf(line, sizeof line,
                  "%s, %d robots: callgrind counted %llu instructions in %.6g s and %llu in %.6g s simulated\n",
                  r.world.c_str(), r.robots, static_cast<unsigned long long>(f.short_total), f.short_seconds,
                  static_cast<unsigned long long>(f.long_total), f.long_seconds);
    out << line;
  }
  return out.str();
}

std::string FormatWorkMarkdown(const std::vector<BenchResult>& results) {
  std::ostringstream out;
  out << "| world | profile | drive | robots | µs per step | real-time factor | instructions per step | "
         "instructions per simulated s | contacts per step | touching pairs | narrow-phase tests | collision | "
         "ODE step | plugins | perception | other |\n";
  out << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  char line[1024];
  for (const BenchResult& r : results) {
    const TimeSplit& s = r.split;
    const std::string per_step = r.instructions ? Millions(r, &InstructionFigures::per_step) + " M" : "-";
    const std::string per_second = r.instructions ? Millions(r, &InstructionFigures::per_sim_second) + " M" : "-";
    std::snprintf(line, sizeof line,
                  "| %s | %s | %s | %d | %.1f | %.1f× | %s | %s | %.1f | %.1f | %.1f | %.0f %% | %.0f %% | %.0f %% | "
                  "%.0f %% | %.0f %% |\n",
                  r.world.c_str(), r.profile.c_str(), r.drive.c_str(), r.robots, r.step_microseconds,
                  r.real_time_factor, per_step.c_str(), per_second.c_str(), r.contacts_per_step,
                  r.touching_pairs_per_step, r.narrow_tests_per_step, 100 * s.collision, 100 * s.physics,
                  100 * s.plugins, 100 * s.perception, 100 * (s.transports + s.events + s.other));
    out << line;
  }
  return out.str();
}

std::string FormatCsv(const std::vector<BenchResult>& results) {
  std::ostringstream out;
  out << "world,profile,drive,robots,physics_step_s,sim_seconds,us_per_step,real_time_factor,cpu_share,"
         "instructions_per_step,instructions_per_sim_second,contacts_per_step,touching_pairs_per_step,"
         "narrow_tests_per_step,collision,physics,plugins,perception,transports,events,other\n";
  out.precision(10);
  for (const BenchResult& r : results) {
    const TimeSplit& s = r.split;
    out << r.world << ',' << r.profile << ',' << r.drive << ',' << r.robots << ',' << r.physics_step << ','
        << r.sim_seconds << ',' << r.step_microseconds << ',' << r.real_time_factor << ',' << r.cpu_share << ',';
    if (r.instructions) {
      out << r.instructions->per_step << ',' << r.instructions->per_sim_second << ',';
    } else {
      out << ",,";
    }
    out << r.contacts_per_step << ',' << r.touching_pairs_per_step << ',' << r.narrow_tests_per_step << ','
        << s.collision << ',' << s.physics << ',' << s.plugins << ',' << s.perception << ',' << s.transports << ','
        << s.events << ',' << s.other << '\n';
  }
  return out.str();
}

}  // namespace ubersim::kernel::bench
