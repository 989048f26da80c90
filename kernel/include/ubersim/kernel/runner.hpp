// SPDX-License-Identifier: Apache-2.0
// Running a world: the loop that steps it against the wall clock (or as fast as it can), and what
// a run leaves behind when a plugin fault stops the world or a fatal signal kills the process: a
// text report and the last snapshot beside it, so the moment can be looked at and the run resumed
// (docs/reliability.md).
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "ubersim/kernel/world.hpp"

namespace ubersim::kernel {

/// How a run loop goes.
struct RunOptions {
  /// Stop after this much simulated time from the run's start (a restored world's time counts
  /// from its snapshot), s; 0: until stopped.
  double duration = 0.0;
  double speed_factor = 1.0;  ///< sim s per wall s at start; 0: as fast as possible
  bool start_paused = false;  ///< start paused (clock events resume it)
  double status_interval = 0.5;  ///< wall seconds between status callbacks
  /// Called between steps on the run's thread, also while paused (save a snapshot on request,
  /// keep the crash report's copy fresh); may be empty.
  std::function<void()> between_steps;
};

/// What the status callback gets.
struct RunStatus {
  double sim_time = 0.0;          ///< s
  std::int64_t steps = 0;         ///< physics steps
  double real_time_factor = 0.0;  ///< sim s per wall s over the last interval
  bool paused = false;            ///< paused now
  bool finished = false;          ///< last call of the run
};

/// Steps a world against the wall clock (or as fast as possible), obeying pause, single step,
/// speed and reset from clock events, until the duration is reached, `stop` becomes true or a
/// plugin fault stops the world (World::stopped). Returns the final status.
RunStatus RunWorld(World& world, const RunOptions& options, const std::atomic<bool>& stop,
                   const std::function<void(const RunStatus&)>& on_status);

/// A run's crash report and the snapshot beside it.
struct CrashFiles {
  std::filesystem::path report;    ///< text
  std::filesystem::path snapshot;  ///< the last snapshot (ubersim run --restore takes it)
};

/// `dir`/ubersim-crash-<world>-<UTC time>-<pid>.txt and .snapshot.
CrashFiles CrashFilesIn(const std::filesystem::path& dir, const std::string& world_name);

/// What a report says about the run besides the crash.
struct RunDescription {
  std::string program;       ///< "ubersim 0.1.0"
  std::string world_name;    ///< the world's name
  std::string world_file;    ///< its file
  std::string command_line;  ///< how the run was started
};

/// Writes the report of a world a plugin fault stopped (World::stopped) and, beside it, the
/// snapshot of its state after the step the fault happened in. Throws std::runtime_error (or
/// SnapshotError) naming the file it could not write.
void WriteFaultReport(const World& world, const CrashFiles& files, const RunDescription& run);

/// Reports a fatal signal (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT) with the last periodic
/// snapshot. A handler may do almost nothing safely: no allocation, no locks, no stdio. So the run
/// thread serialises a snapshot into one of two buffers from time to time (Update) and publishes
/// it with one atomic store; the handler only open()s the two files it was given at the start,
/// write()s bytes that already exist, and then lets the signal take its course (default action,
/// re-raised: the exit status and any core dump are the signal's). One guard per process.
class CrashGuard {
 public:
  /// A guard that will write `files`; Install arms it.
  CrashGuard(CrashFiles files, RunDescription run);
  /// Disarms it (the previous handlers come back).
  ~CrashGuard();
  CrashGuard(const CrashGuard&) = delete;
  CrashGuard& operator=(const CrashGuard&) = delete;

  /// Installs the handlers, on an alternate stack (a stack overflow is a SIGSEGV too).
  void Install();
  /// Serialises `world`'s state and makes it what a crash writes (run thread, between steps).
  /// A snapshot that cannot be taken (a part's SaveState throws) keeps the previous one.
  void Update(const World& world);
  /// The step of the snapshot a crash would write; -1 before the first Update.
  std::int64_t snapshot_step() const { return snapshot_step_; }
  /// The files it writes.
  const CrashFiles& files() const { return files_; }

 private:
  struct State;
  CrashFiles files_;
  RunDescription run_;
  std::unique_ptr<State> state_;
  std::int64_t snapshot_step_ = -1;
};

}  // namespace ubersim::kernel
