// SPDX-License-Identifier: Apache-2.0
// `ubersim calibrate --check`: the fitted world driven through the log's own manoeuvres — each
// free ball run started where and as fast as the recording's, each robot step replayed from its
// recorded commands — with the simulated trajectories overlaid on the recorded ones and the error.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "log_session.hpp"
#include "model_output.hpp"
#include "robot_fit.hpp"
#include "session_tracks.hpp"

namespace ubersim::calibrate {

/// What the check replays, and in which world.
struct CheckInput {
  std::filesystem::path world;                       ///< the fitted world.yaml
  std::vector<std::string> plugin_paths;             ///< extra plugin folders
  const LogSession* session = nullptr;               ///< the recording
  const SessionTracks* tracks = nullptr;             ///< its objects
  const CalibrationFits* fits = nullptr;             ///< what was fitted (the ball's runs)
  const std::vector<RobotFitInput>* robot_inputs = nullptr;  ///< each robot's track and commands
  int max_ball_runs = 12;                            ///< ball runs replayed at most
  int max_steps_per_robot = 8;                       ///< robot steps replayed per robot at most
  int max_robots = 4;                                ///< robots replayed at most
};

/// Replays and compares; the report's check section (plots "check-*.svg").
ReportSection RunCheck(const CheckInput& input);

}  // namespace ubersim::calibrate
