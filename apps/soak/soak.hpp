// SPDX-License-Identifier: Apache-2.0
// `ubersim soak`: steps a world as fast as possible for a long simulated time under seeded random
// play and random teleports, checks its state every simulated second (state_check.hpp) and
// watches the process's resident memory. Deterministic for a seed: the same world and seed give
// the same findings and the same final state.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "teleports.hpp"
#include "ubersim/kernel/state_check.hpp"
#include "ubersim/kernel/world.hpp"

namespace ubersim::kernel::soak {

/// What to run.
struct SoakOptions {
  double sim_seconds = 3600.0;     ///< simulated time, s
  std::uint64_t seed = 1;          ///< random play and teleports
  double check_period = 1.0;       ///< simulated seconds between state checks
  double teleport_interval = 0.5;  ///< mean simulated seconds between teleports
  /// How far into a wall a robot is teleported: a share of the wall's thickness (see
  /// RandomTeleports). Past half, the robot shells' hollow mesh may hold a robot in the wall
  /// (docs/reliability.md).
  double wall_overlap = 0.5;
  /// Simulated seconds after a teleport during which the teleported object (and a robot it was
  /// put onto) may still overlap others: the physics needs a few steps to push them apart. The
  /// shipped worlds undo penetrations at up to 3 m/s, which parts a 0.18 m overlap within about
  /// 60 ms; 0.25 s is four times that, and a robot still inside another after it is a failure.
  double grace = 0.25;
  /// A robot is tipped over when it leans past the limit at checks this many simulated seconds
  /// apart or more (with the default check period: at two checks in a row). A robot knocked onto
  /// two wheels by a crash rocks back within 0.1–0.3 s; one that stays leaning has fallen.
  double tipped_for = 0.5;
  /// Memory is judged from this simulated time on, s (< 0: a fifth of the run, at most 300 s).
  /// Until then the process's memory climbs to its working size: ODE's step arena and the
  /// contact buffers grow to the biggest pile-up seen so far, the allocator settles.
  double warmup = -1.0;
  double max_rss_growth = 0.05;    ///< largest allowed growth of resident memory after the warm-up
  StateCheckOptions checks;        ///< which checks, which limits
  /// Optional: sees every teleport as it is posted (simulated time, s; what; the event).
  std::function<void(double, const char*, const PositionEvent&)> on_teleport;
  /// Optional: called after every step, to trace a finding step by step.
  std::function<void(const World&)> after_step;
};

/// A state-check finding at a simulated time.
struct SoakFinding {
  double sim_time = 0;        ///< s
  StateViolation violation;   ///< what, where, how bad
};

/// Where a run is.
struct SoakProgress {
  double sim_time = 0;       ///< s simulated so far
  double sim_seconds = 0;    ///< s to simulate in all
  double wall_seconds = 0;   ///< s of wall time so far
  double rss_mb = 0;         ///< resident memory now, MB
  std::int64_t findings = 0; ///< findings so far
};

/// The outcome.
struct SoakReport {
  std::string world;                   ///< world name
  double sim_seconds = 0;              ///< simulated, s
  double wall_seconds = 0;             ///< spent, s
  std::int64_t steps = 0;              ///< physics steps
  std::int64_t checks = 0;             ///< state checks run
  std::array<std::int64_t, kTeleportKinds> teleports{};  ///< by kind
  std::int64_t replaced = 0;           ///< objects put back after a finding
  std::vector<SoakFinding> findings;   ///< the first kKeptFindings findings
  std::int64_t finding_count = 0;      ///< all findings
  std::array<std::int64_t, kStateIssues> by_issue{};  ///< findings by StateIssue
  bool stopped_early = false;          ///< a non-finite state ended the run
  double warmup_seconds = 0;           ///< when memory judging began, s
  double rss_warm_mb = 0;              ///< resident memory at the end of the warm-up, MB
  double rss_end_mb = 0;               ///< at the end, MB
  double rss_peak_mb = 0;              ///< highest seen after the warm-up, MB
  double rss_growth = 0;               ///< rss_end / rss_warm − 1
  double max_rss_growth = 0.05;        ///< the allowed growth
  std::uint64_t state_hash = 0;        ///< World::StateHash at the end

  static constexpr std::size_t kKeptFindings = 1000;  ///< findings kept in full
  /// No finding and memory within bounds.
  bool Pass() const { return finding_count == 0 && !stopped_early && rss_growth < max_rss_growth; }
};

/// Runs `world` (built without transports) for options.sim_seconds. Calls `on_finding` for each
/// finding as it is made and `progress` after every check. After a finding the object is put
/// back somewhere free at rest (so the run goes on testing the rest); a non-finite state ends the run.
SoakReport RunSoak(World& world, const SoakOptions& options, const std::function<void(const SoakProgress&)>& progress,
                   const std::function<void(const SoakFinding&)>& on_finding);

/// The report as text: counts, findings by kind, memory, verdict.
std::string FormatSummary(const SoakReport& report);

}  // namespace ubersim::kernel::soak
