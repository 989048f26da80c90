// SPDX-License-Identifier: Apache-2.0
// `ubersim bench --instructions`: the instructions a simulated second costs, counted by
// callgrind, which the machine's noise does not move. The bench runs its own binary twice under
// `valgrind --tool=callgrind`, a short and a long run of the same world and options; the
// difference of the two totals leaves out the start-up (loading, building the world) that both
// share (docs/performance.md).
#pragma once

#include <cstdint>
#include <filesystem>
#include <istream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace ubersim::kernel::bench {

/// What the two callgrind runs of one world counted.
struct InstructionFigures {
  double short_seconds = 0, long_seconds = 0;     ///< simulated time of the two runs, s
  std::int64_t short_steps = 0, long_steps = 0;   ///< their physics steps
  std::uint64_t short_total = 0, long_total = 0;  ///< callgrind's total (Ir) of each run
  double per_sim_second = 0;  ///< (long_total − short_total) / the simulated time between them
  double per_step = 0;        ///< (long_total − short_total) / the steps between them
};

/// How to run the bench under callgrind.
struct CallgrindRun {
  std::filesystem::path valgrind;     ///< the valgrind executable
  std::filesystem::path program;      ///< the ubersim binary to run under it
  /// Its arguments, "bench" first, without --duration (MeasureInstructions adds it). They must
  /// name one world and --no-baseline.
  std::vector<std::string> arguments;
  double short_seconds = 2.0;         ///< simulated s of the short run
  double long_seconds = 12.0;         ///< simulated s of the long run
  double physics_step = 0.001;        ///< s, to count the steps each run makes
};

/// A callgrind run that failed: what failed and the tail of valgrind's output.
class CallgrindError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The total instruction count of a callgrind output file: its `summary:` line, else its
/// `totals:` line (the first event, Ir); nothing when it has neither.
std::optional<std::uint64_t> CallgrindTotal(std::istream& callgrind_out);

/// The valgrind executable: /usr/bin/valgrind (Debian's), else the first `valgrind` on PATH;
/// nothing when there is none (it is not installed).
std::optional<std::filesystem::path> FindValgrind();

/// The running program's own executable (/proc/self/exe resolved: valgrind must be given the
/// binary, not the link, which would name valgrind itself once it runs).
std::filesystem::path SelfExecutable();

/// Runs `run.program` twice under `valgrind --tool=callgrind`, for run.short_seconds and
/// run.long_seconds, one after the other, their output (valgrind's and the program's) into files
/// in a temporary folder removed afterwards, and returns the figures. Throws CallgrindError when
/// a run fails or writes no total, with the end of its output.
InstructionFigures MeasureInstructions(const CallgrindRun& run);

}  // namespace ubersim::kernel::bench
