// SPDX-License-Identifier: Apache-2.0
// `ubersim bench`: steps worlds headless as fast as possible under seeded random play and
// measures real-time factor, steps per second, where the time goes, memory, the contacts a step
// makes, and the kernel's overhead over the same model stepped with ODE alone
// (bare_ode_mirror.hpp); with robot counts, how the step's cost grows with the robots; with
// instructions, what a simulated second costs counted by callgrind (instructions.hpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "ubersim/kernel/logging.hpp"
#include "ubersim/kernel/model.hpp"
#include "ubersim/kernel/plugin_registry.hpp"
#include "ubersim/kernel/world.hpp"
#include "instructions.hpp"
#include "shared/machine.hpp"
#include "shared/random_play.hpp"
#include "shared/trial_world.hpp"

namespace ubersim::kernel::bench {

// What bench shares with batch and soak (apps/shared), under the names they have always had here.
using apps::LoadTrialWorld;
using apps::MachineDescription;
using apps::PlaceRobots;
using apps::kMaxTrialRobots;
using apps::PeakResidentMegabytes;
using apps::RandomPlay;
using apps::ResidentMegabytes;

/// What to run.
struct BenchOptions {
  std::vector<std::filesystem::path> worlds;   ///< world files, run in this order
  double sim_seconds = 10.0;                   ///< simulated time per world, s
  std::uint64_t seed = 1;                      ///< random play and baseline commands
  bool baseline = true;                        ///< also step the bare-ODE baseline
  PhysicsOverrides physics;                    ///< instead of the world files' settings
  std::optional<std::string> robot_model;      ///< replace every robot's model file
  bool with_transports = false;                ///< start the worlds' transports (their ports must be free)
  /// Run each world once per count, with that many robots on its field instead of its own
  /// (PlaceRobots: half each team, on a grid); empty: the world's own robots.
  std::vector<int> robot_counts;
  /// Also count each run's instructions under callgrind (MeasureInstructions).
  struct Instructions {
    std::filesystem::path valgrind;            ///< the valgrind executable (FindValgrind)
    std::filesystem::path program;             ///< the ubersim binary (SelfExecutable)
    double short_seconds = 2.0;                ///< simulated s of the short run
    double long_seconds = 12.0;                ///< simulated s of the long run
    std::vector<std::string> extra_arguments;  ///< for the runs, after the bench's own (--plugin-path DIR …)
  };
  std::optional<Instructions> instructions;
};

/// The `ubersim` arguments that bench `world` as `options` say, with `robot_count` robots (the
/// world's own when empty), without the baseline and without --duration: what the callgrind runs
/// execute. Only the physics keys the command line sets (profile, step, iterations, contacts per
/// pair) are passed on.
std::vector<std::string> CallgrindArguments(const BenchOptions& options, const std::filesystem::path& world,
                                            std::optional<int> robot_count);

/// Shares of the kernel's wall time, 0..1.
struct TimeSplit {
  double collision = 0, physics = 0, plugins = 0, perception = 0, transports = 0, events = 0;
  double other = 0;  ///< the rest: snapshots for the cameras, the random play, the loop
};

/// One world's figures.
struct BenchResult {
  std::string world;           ///< world name
  std::string file;            ///< world file
  int robots = 0;              ///< robots on the field
  std::string profile;         ///< physics profile in force (precise, fast)
  std::string drive;           ///< the robots' drive plugins ("omni", "omni_force"; several joined by "+")
  double physics_step = 0;     ///< s
  int solver_iterations = 0;   ///< QuickStep iterations (islands with the ball)
  int solver_iterations_without_ball = 0;  ///< QuickStep iterations of the other islands
  /// "10", or "10/6" when the islands without the ball take fewer.
  std::string Iterations() const {
    return solver_iterations == solver_iterations_without_ball
               ? std::to_string(solver_iterations)
               : std::to_string(solver_iterations) + "/" + std::to_string(solver_iterations_without_ball);
  }
  int max_contacts = 0;        ///< contacts per geometry pair
  double sim_seconds = 0;      ///< simulated
  double wall_seconds = 0;     ///< spent in World::Step (not in the random play)
  double real_time_factor = 0; ///< sim_seconds / wall_seconds
  double steps_per_second = 0; ///< physics steps per wall second
  double step_microseconds = 0;  ///< wall time per step, µs
  TimeSplit split;             ///< where the time went
  double contacts_per_step = 0;        ///< contact joints the collision pass made, mean per step
  double touching_pairs_per_step = 0;  ///< geometry pairs with a contact, mean per step
  double narrow_tests_per_step = 0;    ///< pairs the narrow phase tested (the broadphase's output), mean per step
  /// Instructions counted by callgrind (BenchOptions::instructions), in separate runs of the same
  /// world and options without the baseline.
  std::optional<InstructionFigures> instructions;
  double rss_before_mb = 0;    ///< resident memory before building the world, MB
  double rss_peak_mb = 0;      ///< highest resident memory seen while it ran, MB
  int bodies = 0, geoms = 0, joints = 0;  ///< ODE objects of the model (from the baseline copy)
  bool baseline = false;       ///< the baseline ran
  double baseline_wall_seconds = 0;       ///< bare ODE, same steps, same motor commands
  double baseline_real_time_factor = 0;   ///< bare ODE
  double kernel_overhead = 0;  ///< kernel wall / baseline wall − 1
  /// Share of the run's wall time the bench thread was on a CPU (its CPU time over its wall
  /// time): under 1 when other work shared the machine. The wall-time figures then read low by
  /// this share; divided by it they are what the step costs in CPU time.
  double cpu_share = 1.0;
};

/// Runs each world for options.sim_seconds (once per robot count when counts are given);
/// `progress(label, fraction)` is called now and then. Throws CallgrindError when a callgrind
/// run fails.
std::vector<BenchResult> RunBench(const BenchOptions& options, PluginRegistry& registry,
                                  const ModelLoader& loader, Log& log,
                                  const std::function<void(const std::string&, double)>& progress);

/// The results as a plain-text table (terminal).
std::string FormatTable(const std::vector<BenchResult>& results);
/// The results as Markdown, with the machine and the command (docs/performance.md).
std::string FormatMarkdown(const std::vector<BenchResult>& results, const std::string& machine,
                           const std::string& command);

/// The work a step does, as a plain-text table: per run the robots, µs per step, the real-time
/// factor, instructions per step and per simulated second (when counted), contacts, touching
/// pairs and narrow-phase tests per step, and the split (bench --robot-count, --instructions).
std::string FormatWorkTable(const std::vector<BenchResult>& results);
/// The same as Markdown.
std::string FormatWorkMarkdown(const std::vector<BenchResult>& results);
/// Every figure of every run as CSV, one header line then one line per run (tools/bench_plot.py).
std::string FormatCsv(const std::vector<BenchResult>& results);

}  // namespace ubersim::kernel::bench
