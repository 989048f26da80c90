// SPDX-License-Identifier: Apache-2.0
// `ubersim calibrate`: a field's log in, fitted model files and a report out. Reads the session,
// builds the tracks, fits ball, robots and cameras, writes the files, the report and (with
// `check`) the simulator's replay of the same manoeuvres beside the recording.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ball_fit.hpp"
#include "log_session.hpp"
#include "model_output.hpp"
#include "session_tracks.hpp"

namespace ubersim::calibrate {

/// What to fit and where to write it.
struct CalibrateOptions {
  std::vector<std::string> logs;             ///< the session's log files
  std::filesystem::path out_dir;             ///< report and model files go here
  std::filesystem::path base_world;          ///< the world file whose models are fitted over
  bool geometry_models = false;              ///< announce the fitted ball model in the vision geometry
  bool check = false;                        ///< replay the manoeuvres in the simulator with the fitted files
  std::vector<std::string> plugin_paths;     ///< for `check`
  BallFitOptions ball;                       ///< the ball fit's settings
  bool dump_tracks = false;                  ///< also write the tracks the fits saw as CSV (tracks/)
};

/// What came of it.
struct CalibrationOutcome {
  CalibrationFits fits;                      ///< everything fitted
  ModelFiles files;                          ///< what was written
  std::filesystem::path report;              ///< report.md
  std::vector<std::string> problems;         ///< what could not be fitted, and why
  bool anything_fitted = false;              ///< at least one of ball, robots, cameras had enough data
  double seconds_reading = 0, seconds_fitting = 0;  ///< wall time, s
  double seconds_ball = 0, seconds_robots = 0, seconds_cameras = 0;  ///< each fit's own wall time, s
};

/// Runs the calibration; `progress` gets a line per stage. Throws sslog::LogFormatError for a
/// damaged log (file, record, byte offset) and std::runtime_error for other unreadable input.
CalibrationOutcome Calibrate(const CalibrateOptions& options, const std::function<void(const std::string&)>& progress);

}  // namespace ubersim::calibrate
