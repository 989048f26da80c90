// SPDX-License-Identifier: Apache-2.0
// The fitted model files: the base world's ball, robot and world files rewritten with the fitted
// keys (everything else as the base has it), each headed by a comment naming the log, the data
// used and the intervals. Paths inside them are made relative to the output folder.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "ball_fit.hpp"
#include "camera_fit.hpp"
#include "robot_fit.hpp"
#include "samples.hpp"

#include <Eigen/Core>

namespace ubersim::calibrate {

/// Everything a calibration fitted.
struct CalibrationFits {
  std::string source;                 ///< the log file(s), for the comments
  BallFit ball;                       ///< the ball
  std::vector<RobotFit> robots;       ///< every robot with data
  CameraFit cameras;                  ///< the vision system
  PerceptionValues perception;        ///< the `perception:` keys from `cameras`
  /// The cameras where the log's geometry puts them, m (the world's `perception.cameras`).
  std::map<int, Eigen::Vector3d> camera_positions;
  double field_length = 0, field_width = 0;  ///< m, from the geometry (0: unknown)
  /// Command-to-motion delay over the robots (latency + wheel lag, the world's `radio.latency`);
  /// samples 0 when unknown.
  Estimate latency;
};

/// The files written, absolute.
struct ModelFiles {
  std::filesystem::path world;                          ///< world.yaml
  std::filesystem::path ball;                           ///< ball.yaml (empty: not fitted)
  std::map<RobotKey, std::filesystem::path> robots;     ///< robot-blue-3.yaml …
};

/// Writes world.yaml (and ball.yaml, robot-*.yaml for what was fitted) into `out_dir`, from the
/// world file `base_world`. `geometry_models`: the world's ssl_vision transports announce the
/// fitted ball models (SSL_GeometryModels). A fitted value outside the model's range is not
/// written; `problems` (may be null) gets a sentence for it. Throws std::runtime_error naming the
/// file when a base file cannot be read or an output cannot be written.
ModelFiles WriteModelFiles(const std::filesystem::path& base_world, const std::filesystem::path& out_dir,
                           const CalibrationFits& fits, bool geometry_models, std::vector<std::string>* problems);

/// The base world's ball as the fits need it.
struct BaseBall {
  double inertia_factor = 0.4;  ///< I = k·m·r²
  double radius = 0.0215;       ///< m
};

/// The ball file `base_world` names (its inertia and radius; the defaults when it names none).
/// Throws std::runtime_error naming the file when it cannot be read.
BaseBall ReadBaseBall(const std::filesystem::path& base_world);

/// The rolling resistance ρ (m) that gives the rolling deceleration `acc_roll` (negative, m/s²) to
/// a ball of inertia factor k and radius r rolling without slip: a_r = −ρ·g/((1 + k)·r).
Estimate RollingFriction(const Estimate& acc_roll, double k, double radius);

/// "0.1234 [0.1200, 0.1268] (41 runs)": an estimate as the comments and the report give it.
std::string Describe(const Estimate& e, const char* what_samples);

}  // namespace ubersim::calibrate
