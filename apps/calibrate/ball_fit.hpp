// SPDX-License-Identifier: Apache-2.0
// The ball part of `ubersim calibrate`: from a real field's ball track, the league's two-phase
// straight-kick model (acc_slide, acc_roll, k_switch) with 95 % intervals, the ÜberSim ball-carpet
// contact parameters that reproduce it (mu, rolling_friction, inertia_factor), and the fixed-loss
// chip model's dampings from the chips in the log. Pure math: no files, no protobuf.
#pragma once

#include <cstddef>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "samples.hpp"

namespace ubersim::calibrate {

/// What the ball fit reads: the ball's track, the robots that may touch it and the cameras.
struct BallFitInput {
  /// The ball track: time-ordered detections, one per camera frame that saw it (cameras interleave;
  /// overlapping cameras may give two points at nearly the same time; noisy; drop-outs). False
  /// balls already removed; a few stray detections are tolerated.
  std::vector<TrackPoint> ball;
  /// Distance (m) from (x, y) to the nearest robot centre at time t (s); +inf when no robot is
  /// known. May be empty: no robots.
  std::function<double(double t, double x, double y)> robot_distance;
  /// Camera positions by camera id, m. An airborne ball is reported where the camera's ray through
  /// it meets the carpet, so chips need them.
  std::map<int, Eigen::Vector3d> cameras;
  double ball_radius = 0.0215;  ///< m
  std::string source;           ///< the log's name, for the report
};

/// Knobs of the ball fit. The defaults suit league vision (60–75 Hz per camera, σ of a few mm).
struct BallFitOptions {
  double reach = 0.25;        ///< m, ball-to-robot-centre distance under which a robot may touch it
  int min_runs = 4;           ///< fewer usable free runs: not enough data, no fit
  double min_speed = 0.3;     ///< m/s, below this a run ends (too slow to tell)
  double max_gap = 0.15;      ///< s, a longer gap in the detections ends a run
  double turn_angle = 0.1745; ///< rad (10°), a sharper turn of the motion ends a run (wall, touch)
  double speed_jump = 0.3;    ///< m/s, a rise in speed at least this large ends a run (a kick)
  double min_duration = 0.3;  ///< s, shorter runs are rejected
  int min_points = 10;        ///< runs with fewer detections are rejected
  /// m, robot centre to ball centre when a robot kicks: dates a kick the cameras did not see
  /// (the ball hidden at the robot) from where the run's start extrapolates back to the robot.
  double kick_contact = 0.10;
  double outlier_sigmas = 3.5;   ///< detections further off the fit than this many σ are dropped
  double run_rms_factor = 2.5;   ///< runs whose rms exceeds this × the typical run's are rejected
  double chip_min_apex = 0.02;   ///< m, a candidate chip whose first hop is lower is not a chip
  double min_hop_height = 0.01;  ///< m, once a hop would be lower than this the chipped ball rolls
  double gravity = 9.81;         ///< m/s²
};

/// One candidate free run of the ball (rolling, or a chip's flight), used or rejected, with its fit.
struct BallRun {
  /// Its detections: [first, last) of input.ball with non-finite detections left out and stably
  /// sorted by time (so input.ball's own indices when it is time-ordered and finite, as it should be).
  std::size_t first = 0, last = 0;
  double t_begin = 0, t_end = 0;    ///< s, first and last detection
  int points = 0;                   ///< detections the fit used (outliers dropped)
  double start_speed = 0;           ///< m/s at t_begin (fitted; before the fit a local estimate)
  double heading = 0;               ///< rad, direction of motion, world frame
  double x0 = 0, y0 = 0;            ///< m, ground runs: the line's origin (s = 0); chips: launch point
  bool airborne = false;            ///< a chip, fitted with the hop model
  bool kick_seen = false;           ///< the run starts at a dated kick, so it constrains k_switch
  bool used = false;                ///< in the final fit
  /// What starts and ends it: "robot" (leaves or enters a robot's reach), "kick" (speed jumps up),
  /// "turn" (wall, unseen touch), "gap", "slow" (below min_speed), "track" (its end), "chip landing",
  /// "rolling" (a chip's end); a dated kick adds how it was dated.
  std::string begins, ends;
  std::string reason;               ///< why it is rejected (empty when used)
  double rms = 0;                   ///< m, residual rms under the final fit (0: not fitted)
  // Ground runs: along the line from (x0, y0) in direction heading, the position at time t is the
  // two-phase law from (t_ref, s_ref, v_ref): sliding at acc_slide for slide_time, then rolling.
  double t_ref = 0;       ///< s: the kick instant (kick_seen), else t_begin; chips: launch time
  double s_ref = 0;       ///< m, position along the line at t_ref
  double v_ref = 0;       ///< m/s, speed at t_ref (the kick speed when kick_seen)
  double slide_time = 0;  ///< s, sliding after t_ref before rolling (0: rolling throughout)
  // Chips: launched at t_ref from (x0, y0) with this velocity; `hops` landings, then it rolls.
  double launch_vx = 0, launch_vy = 0, launch_vz = 0;  ///< m/s
  int hops = 0;       ///< flights before it rolls
  double apex = 0;    ///< m, height of the first flight
};

/// The ball fit: the league's models with 95 % intervals, the ÜberSim parameters, and every run.
struct BallFit {
  bool enough_data = false;               ///< false: estimates are not given (samples == 0)
  std::vector<std::string> problems;      ///< sentences for the reader, e.g. too few runs
  Estimate acc_slide, acc_roll, k_switch; ///< two-phase model; decelerations negative, m/s²
  Estimate mu;                            ///< ball-carpet friction: acc_slide = −mu·g
  Estimate rolling_friction;              ///< ρ, m: acc_roll = −ρ·g/((1+k)·r)
  Estimate inertia_factor;                ///< k, I = k·m·r²: k_switch = 1/(1+k)
  Estimate damping_z, damping_xy_first_hop, damping_xy_other_hops;  ///< chips; samples = chips
  std::vector<BallRun> runs;              ///< every candidate, used and rejected, in time order
  double rms_residual = 0;                ///< m, along-line residual rms of the used ground runs
  double noise = 0;                       ///< m, detection noise σ (one coordinate) the fit found
};

/// Finds the ball's free runs and chips in the track and fits the ball models to them.
BallFit FitBall(const BallFitInput& input, const BallFitOptions& options = {});

/// The report's ball section: estimates, derived ÜberSim parameters, the runs table and plots
/// (files "ball-*.svg").
ReportSection BallReport(const BallFit& fit, const BallFitInput& input);

}  // namespace ubersim::calibrate
