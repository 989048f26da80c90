// SPDX-License-Identifier: Apache-2.0
// The camera fit: the vision system's realism measured in a field's log, per camera — frame rate,
// capture jitter, latency and processing stamp, detection noise (and its growth away from the
// nadir), drop-outs, false balls — and across the cameras (unsynchronised phases, overlap), as
// the world's `perception:` keys take them (docs/model-files.md). Pure math on samples.hpp's types.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "samples.hpp"

namespace ubersim::calibrate {

/// What the camera fit reads: the log's frames and the objects' tracks through them.
struct CameraFitInput {
  /// Every camera frame of the log, ordered by t_capture (cameras interleave), one session clock, s.
  const std::vector<CameraFrame>* frames = nullptr;
  /// The ball's track: the detections chosen as THE ball, time-ordered, all cameras (camera_id
  /// says whose). The frames' other ball detections are false balls or another ball.
  std::vector<TrackPoint> ball;
  /// Each robot's track: its detections, all cameras, time-ordered.
  std::map<RobotKey, std::vector<TrackPoint>> robots;
  /// Camera positions by id from the log's geometry, m (may be empty: no growth with distance then).
  std::map<int, Eigen::Vector3d> cameras;
  /// m, robot centre to its dribbler's front (false balls at dribblers sit at its corners).
  double robot_front = 0.07;
};

/// How the camera fit looks at the data. The defaults suit 30–100 Hz cameras.
struct CameraFitOptions {
  // Noise: each detection against a local quadratic (position, heading) through the same camera's
  // neighbouring detections of the same object.
  int noise_neighbours = 5;            ///< detections each side of the one judged, at most
  double noise_half_window = 0.15;     ///< s, at most this far from the one judged
  int noise_min_points = 7;            ///< a fit needs this many (and 2 on each side)
  double outlier_sigmas = 4.5;         ///< a detection this many σ off, or a fit this bad, is not smooth motion
  std::size_t max_noise_fits = 600000; ///< per camera and object kind; above this every k-th detection is judged
  double distance_bin = 0.1;           ///< m, bins of distance from the nadir (noise growth)
  double min_distance_span = 1.0;      ///< m the bins must span for a growth fit
  int min_noise_samples = 200;         ///< residuals below this: no noise estimate
  int jackknife_blocks = 20;           ///< time blocks for the noise intervals (residuals are correlated)
  // Drop-outs.
  int drop_max_gap_frames = 6;         ///< a camera's sightings of an object this many frames apart or less bound a run
  double area_cell = 0.1;              ///< m: the hull of the cells where a camera detected things (3+) is where it sees
  double area_margin = 0.2;            ///< m, a drop counts only this deep inside that hull
  int min_drop_trials = 200;           ///< frames below this: no drop estimate
  // False balls.
  double ball_match_radius = 0.03;     ///< m, a ball detection this near the ball's track is the ball
  double robot_radius = 0.09;          ///< m, places the dribbler's corners on the robot's outline
  double dribbler_radius = 0.03;       ///< m, a false ball this near a dribbler corner is the dribbler's
  double second_ball_cell = 0.05;      ///< m, detections chained cell to neighbouring cell…
  double second_ball_link = 0.2;       ///< s …this close in time…
  double second_ball_seconds = 1.0;    ///< s …over this long are another ball, not false balls
  // Timing.
  int jitter_chunk_frames = 256;       ///< frames per local line fit of t_capture on frame_number
  double min_duration = 10;            ///< s of log below which the fit says there is not enough data
};

/// Curves behind a camera's plots.
struct CameraCurves {
  std::vector<double> residual_mm;        ///< robot position residual bins' centres (at the nadir's σ), mm
  std::vector<double> residual_density;   ///< measured density per mm
  std::vector<double> residual_gaussian;  ///< the fitted Gaussian's density per mm
  std::vector<double> jitter_t;           ///< s, frames' capture times (a subsample)
  std::vector<double> jitter_ms;          ///< t_capture less the camera's regular schedule, ms
  std::vector<double> distance;           ///< m from the nadir, bins with data
  std::vector<double> sigma_mm;           ///< robot position σ in each bin, mm
  std::vector<double> sigma_fit_mm;       ///< σ₀(1 + g·d) at each bin, mm (empty: no growth fit)
};

/// One camera's measured realism; an Estimate with samples 0 was not estimated (problems say why).
struct CameraStats {
  int camera_id = 0;
  int frames = 0;                    ///< frames of this camera in the log
  int dropped_frames = 0;            ///< frames lost: skipped by its counter, or a period without a frame or a skip
  double duration = 0;               ///< s, its first to last capture
  Estimate frame_rate;               ///< Hz, from the fitted t_capture per frame_number
  Estimate capture_jitter;           ///< s, σ of t_capture about the camera's regular schedule
  Estimate latency;                  ///< s, t_received − t_capture (median)
  Estimate processing_time;          ///< s, t_sent − t_capture (median)
  Estimate robot_position_noise;     ///< m, σ on x and y at the nadir (with the growth below) or overall
  Estimate robot_orientation_noise;  ///< rad, σ on the heading, likewise
  Estimate ball_position_noise;      ///< m, σ on x and y of the ball while it moves smoothly, likewise
  Estimate robot_drop;               ///< fraction of frames missing a robot this camera sees
  Estimate ball_drop;                ///< fraction of frames missing the ball this camera sees
  Estimate false_balls_per_second;   ///< ball detections neither the ball, nor at a dribbler, nor another ball
  Estimate dribbler_false_balls;     ///< 1/s per robot in view: false balls at a dribbler corner
  Estimate noise_growth_per_metre;   ///< 1/m: σ(d) = σ₀(1 + g·d), d from the nadir (robot positions)
  int second_ball_detections = 0;    ///< ball detections explained as another ball (still or slow)
  CameraCurves curves;               ///< for the report's plots
};

/// The vision system as the log shows it.
struct CameraFit {
  std::vector<CameraStats> cameras;     ///< by camera id
  bool unsynchronised = false;          ///< cameras' capture phases differ
  double phase_difference = 0;          ///< s, median time from a frame to the nearest frame of another camera
  Estimate overlap;                     ///< m, how far each camera sees past the border it shares with another
  std::vector<std::string> problems;    ///< what could not be estimated and why, one sentence each
  bool enough_data = false;             ///< frame rate, latency, robot noise and drop-outs were estimated
};

/// Measures every camera of `input`. Roughly linear in the log's size; noise fits are subsampled
/// above options.max_noise_fits per camera and kind.
CameraFit FitCameras(const CameraFitInput& input, const CameraFitOptions& options = {});

/// The world-level `perception:` values: one number per key (weighted median over cameras, weights
/// their frames), only keys that were estimated: frame_rate, latency, processing_time,
/// noise.robot_position, noise.robot_orientation, noise.ball_position, noise.growth_per_metre,
/// drop.robot, drop.ball, capture_jitter, dribbler_false_balls, camera_overlap. When noise was
/// estimated but no growth (no camera positions), noise.growth_per_metre is 0: the σ are then
/// over all distances, and a base world's growth must not scale them again.
struct PerceptionValues {
  std::map<std::string, double> keys;   ///< key → value, SI
  bool unsynchronised_cameras = false;  ///< the fit's verdict
};
PerceptionValues PerceptionFromFit(const CameraFit& fit);

/// The report's camera section: a table per camera ("### Camera 0") with every estimate and its
/// interval, the cameras together, and plots (camera-<id>-residuals.svg, camera-<id>-jitter.svg,
/// camera-<id>-noise-distance.svg).
ReportSection CameraReport(const CameraFit& fit);

}  // namespace ubersim::calibrate
