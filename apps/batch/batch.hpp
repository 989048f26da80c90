// SPDX-License-Identifier: Apache-2.0
// Many independent worlds at once (`ubersim batch`): K seeded worlds spread over T workers,
// each world deterministic on its own (the same job gives the same final state hash whatever
// the number of workers).
//
// Workers are processes, not threads: Debian's ODE 0.16 is built without thread-local storage
// (its configuration lacks ODE_EXT_ou), so its trimesh collider cache and its random generator
// are process-wide and two worlds stepping in two threads of one process would race. A process
// per worker shares nothing, scales the same on the cores, and a world that crashes takes down
// only its own worker, whose jobs are then reported failed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ubersim/kernel/world.hpp"

namespace ubersim::kernel::batch {

/// One world to run: a world file and the seed of its random play (and of its noise).
struct BatchJob {
  std::filesystem::path world;  ///< world file
  std::uint64_t seed = 1;       ///< random play and the world's own seed
};

/// What one job produced.
struct BatchJobResult {
  std::size_t index = 0;         ///< position in BatchOptions::jobs
  std::string world;             ///< world name (or file, when it failed to load)
  std::uint64_t seed = 0;        ///< its seed
  std::int64_t steps = 0;        ///< physics steps run
  double sim_seconds = 0;        ///< simulated
  double wall_seconds = 0;       ///< spent stepping
  std::uint64_t state_hash = 0;  ///< World::StateHash() at the end
  std::string error;             ///< non-empty: the job failed, and why
};

/// The whole run.
struct BatchSummary {
  std::vector<BatchJobResult> jobs;  ///< in job order
  int workers = 1;                   ///< processes used
  double wall_seconds = 0;           ///< from start to the last result
  double sim_seconds = 0;            ///< total simulated time of the jobs that finished
  /// Simulated seconds per wall second, all workers together.
  double Throughput() const { return wall_seconds > 0 ? sim_seconds / wall_seconds : 0; }
  /// Jobs that failed.
  int Failed() const;
};

/// Builds the world of a job (in the worker; may throw: the job fails with the message).
using WorldFactory = std::function<std::unique_ptr<World>(const BatchJob&)>;

/// How to run.
struct BatchOptions {
  std::vector<BatchJob> jobs;  ///< the worlds
  int workers = 1;             ///< processes stepping worlds at once (≥ 1)
  double sim_seconds = 10.0;   ///< simulated time per world, s
};

/// Progress: jobs done, jobs in all, and the fraction of all simulated time done.
using BatchProgress = std::function<void(std::size_t done, std::size_t total, double fraction)>;

/// Runs one job in this process: builds its world, plays seeded random commands for
/// sim_seconds, returns its figures (`report(fraction)` now and then).
BatchJobResult RunJob(const BatchJob& job, std::size_t index, double sim_seconds,
                      const WorldFactory& make_world, const std::function<void(double)>& report);

/// Runs every job on `workers` forked processes (1: still a separate process, so the caller's
/// state is never touched by a crashing world). Results come back over pipes.
BatchSummary RunBatch(const BatchOptions& options, const WorldFactory& make_world,
                      const BatchProgress& progress);

}  // namespace ubersim::kernel::batch
