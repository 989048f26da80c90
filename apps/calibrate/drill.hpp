// SPDX-License-Identifier: Apache-2.0
// The calibration drill: the manoeuvres docs/calibrate.md asks a team to drive on its field
// (steps along, across and about the heading at full and part speed, each to a plateau and back
// to rest; free kicks and chips of the ball), driven in a simulated world and recorded as a real
// field's log — the vision as ssl-vision sends it, the commands as a team's software would record
// them (records 1201/1202). `ubersim calibrate --drill` writes one; the tests fit what it wrote.
#pragma once

#include <cstdint>
#include <string>

#include "ubersim/kernel/world.hpp"

namespace ubersim::calibrate {

/// What the drill drives.
struct DrillOptions {
  double duration = 300;         ///< simulated seconds
  int robots = 6;                ///< blue robots driven (0..robots−1), each in its own lane; every other robot leaves
  double top_speed_command = 3.5;      ///< m/s: the full-speed steps (above a robot's top speed, so it saturates)
  double part_speed_command = 1.2;     ///< m/s: the part-speed steps
  double spin_command = 12.0;          ///< rad/s: the full rotation steps
  double hold = 1.6;             ///< s a step's command is held (to reach the plateau)
  double rest = 1.0;             ///< s of zero command after each step
  bool kicks = true;             ///< kick the ball along its own lane, flat
  bool chips = true;             ///< every fourth kick a chip
  bool commands = true;          ///< record the commands (records 1201)
  std::uint64_t seed = 1;        ///< kicks' speeds and directions
};

/// What the drill did.
struct DrillSummary {
  std::int64_t records = 0;      ///< log records written
  int kicks = 0, chips = 0;      ///< ball launches
  int steps = 0;                 ///< step commands given (all robots)
};

/// Drives the drill in `world` (a headless world; its robots' team must have blue robots
/// 0..robots−1) and writes the session to the SSL log `log_path`. Throws std::runtime_error when
/// the world lacks the robots or the file cannot be written.
DrillSummary RunDrill(kernel::World& world, const std::string& log_path, const DrillOptions& options, Log& log);

}  // namespace ubersim::calibrate
