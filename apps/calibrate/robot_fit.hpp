// SPDX-License-Identifier: Apache-2.0
// The robot fit of `ubersim calibrate`: a robot's drive limits (top speed, acceleration and
// braking along and across its heading, the same for turning) and its command latency, from its
// track and, when the log has them, the velocity commands its team sent.
//
// The model is the simulator's velocity servo (sdk/include/ubersim/servo.hpp): a command takes
// effect after a latency L; the setpoint then ramps toward it (speed-clamped) at the acceleration
// limit when speeding up and at the brake limit when slowing down; the measured motion follows
// the setpoint through a first-order lag τ (the wheels' own dynamics). Each step the fit looks at
// is one such ramp on one component (forward, left or angular): a level v0, a straight ramp from
// the onset to its end, a level P. It is fitted to the detections' positions (projected on the
// component's axis, or the heading for turns) rather than to differentiated velocities, so the
// smoothing window blurs no corner: a variable-projection least-squares fit (levels, slope and a
// position offset per camera linear, onset and ramp end searched).
//
// With commands: steps are where a command changes one component and then holds (min_hold),
// from steady motion, the other components staying steady; latency = onset − the change, the
// slope → accel or brake by whether the robot sped up or slowed down, a plateau below the command
// → top speed. Per-step values are combined by their median, with a 95 % interval from their
// spread (samples = steps). L and τ shift the onset alike; only the corners' rounding (≈ aτ²/2 of
// position, half a millimetre at 4.5 m/s² and 15 ms) tells them apart, so τ is fitted once for
// the robot (profile of the summed misfit over τ on the largest steps) and L is the onset under
// that τ; L + τ is far better determined than either, and the latency's interval carries τ's.
// (Latency from the linear steps alone when there are six: positions pin an onset down several
// times better than headings.)
// Without commands (best effort): ramps are where the smoothed acceleration (robot frame) stays
// above a threshold; the same ramp model gives their slopes; the limits are the upper half of
// those slopes (a game's planner often asks less than the robot can), the top speed the fastest
// sustained levels (no telling a cap from a chosen cruise speed); no latency, no lag.
// Detections that jump off their neighbours (ghosts, swapped ids) are dropped first.
#pragma once

#include <string>
#include <vector>

#include "samples.hpp"

namespace ubersim::calibrate {

/// What a robot's fit works from.
struct RobotFitInput {
  RobotKey robot;                       ///< whose
  std::vector<TrackPoint> track;        ///< time-ordered detections (all cameras), x, y, yaw
  std::vector<CommandSample> commands;  ///< time-ordered local-velocity commands; empty when the log has none
};

/// Knobs of the robot fit; the defaults suit a calibration session of 60–100 Hz commands.
struct RobotFitOptions {
  // Steps (with commands).
  double min_hold = 0.3;             ///< s a command must hold after a change to make a step
  double min_prior_hold = 0.2;       ///< s the command before a change must have held (steady motion before)
  double linear_tolerance = 0.02;    ///< m/s: command changes up to this are repeats of one setpoint
  double angular_tolerance = 0.05;   ///< rad/s: the same for the angular command
  double min_linear_step = 0.3;      ///< m/s: smallest linear velocity change fitted
  double min_angular_step = 1.0;     ///< rad/s: smallest angular velocity change fitted
  double max_command_gap = 0.2;      ///< s without a command sample ends a step
  double max_latency = 0.3;          ///< s: latest onset searched after a change
  double pre_window = 0.12;          ///< s of track before a change that the fit also uses
  double max_window = 2.5;           ///< s of track after a change at most fitted
  double speed_limit_margin = 0.05;  ///< a plateau at least this fraction below its command is the top speed
  double wheel_lag = -1;             ///< s, the motion's first-order lag behind the setpoint; < 0: fitted
  double max_wheel_lag = 0.05;       ///< s, largest lag searched
  int max_lag_segments = 60;         ///< largest steps the lag is fitted on
  // Ramps (without commands).
  double detect_half_window = 0.1;   ///< s, half window of the local fits that find ramps and plateaus and check steadiness
  double grid_step = 0.01;           ///< s between those fits
  double ramp_linear_accel = 1.5;    ///< m/s², sustained acceleration that makes a ramp
  double ramp_angular_accel = 8.0;   ///< rad/s²
  double min_ramp_duration = 0.1;    ///< s above the threshold
  double plateau_duration = 0.3;     ///< s a steady velocity must last to be a plateau
  double min_plateau_speed = 0.3;    ///< m/s: slower steady motion is no plateau
  double min_plateau_angular = 1.0;  ///< rad/s
  // Both.
  double smoothing_half_window = 0.05;  ///< s, half window of the local fits for initial guesses and plots
  double min_ramp_time = 0.05;       ///< s: a shorter fitted ramp gives no slope
  double min_plateau_time = 0.1;     ///< s the level after a ramp must be seen to count as reached
  double max_turn = 0.1;             ///< rad the heading may turn during a linear step or ramp
  double steady_linear = 0.1;        ///< m/s a linear velocity may drift and count as steady
  double steady_angular = 0.5;       ///< rad/s the same for the turn rate
  double max_track_gap = 0.15;       ///< s without a detection inside a step's window rejects it
  double fit_tolerance = 2.5;        ///< residual RMS above this times the typical one rejects a step
  double min_track_duration = 3.0;   ///< s of track below which nothing is fitted
  int min_samples = 2;               ///< steps an estimate needs
  int max_segments = 800;            ///< steps (the largest) or ramps (spread over the log) fitted at most
};

/// The velocity component a step or ramp changes.
enum class MotionAxis : int { kForward = 0, kLeft = 1, kAngular = 2 };

/// "forward", "left", "angular".
const char* AxisName(MotionAxis axis);

/// One step (with commands) or ramp (without) the fit looked at, used or not.
struct SegmentRecord {
  MotionAxis axis = MotionAxis::kForward;  ///< component changed
  double t_change = 0;          ///< s: the command's change (with commands) or the ramp window's start
  double t_end = 0;             ///< s: the end of the window fitted
  double command_before = 0;    ///< m/s or rad/s, the component's command before (0 without commands)
  double command_after = 0;     ///< m/s or rad/s, after
  double onset = 0;             ///< s: the fitted setpoint starts ramping
  double ramp_end = 0;          ///< s: it reaches its level
  double v_start = 0;           ///< m/s or rad/s, level before the ramp
  double v_end = 0;             ///< m/s or rad/s, level after it
  double slope = 0;             ///< m/s² or rad/s², |v_end − v_start| / ramp time
  bool speeding_up = true;      ///< an acceleration (true) or a braking (false)
  bool plateau_reached = false; ///< the level after the ramp was seen
  bool speed_limited = false;   ///< the level stayed below the command: a top-speed sample
  double rms = 0;               ///< m or rad, residual RMS of the position fit
  int points = 0;               ///< detections fitted
  bool used = false;            ///< it entered the estimates
  std::string reason;           ///< why not (empty when used)
};

/// A robot's fitted drive limits and latency.
struct RobotFit {
  RobotKey robot;                  ///< whose
  bool enough_data = false;        ///< something was estimated
  std::vector<std::string> problems;  ///< sentences on what could not be estimated and why
  bool from_commands = false;      ///< commands were used
  Estimate top_speed;              ///< m/s
  Estimate accel_along, brake_along;    ///< m/s², along the heading, positive
  Estimate accel_across, brake_across;  ///< m/s², across it
  Estimate angular_top_speed;      ///< rad/s
  Estimate angular_accel, angular_brake;  ///< rad/s²
  Estimate latency;                ///< s, command sent → setpoint moves (only from commands)
  /// s, latency + wheel lag: command sent → motion under way. Far better determined than either
  /// part (only the corners' rounding tells them apart): what a world's radio.latency takes.
  Estimate response_delay;
  Estimate wheel_lag;              ///< s, the motion's first-order lag behind the setpoint (only from commands)
  std::vector<SegmentRecord> segments;  ///< every step or ramp considered, time-ordered
};

/// Fits one robot. Linear in the track's and commands' lengths (at most max_segments fits).
RobotFit FitRobot(const RobotFitInput& input, const RobotFitOptions& options = {});

/// The robot's part of the report: "### blue 3", the estimates with intervals, the steps used
/// and rejected, and plots "robot-blue-3-*.svg" of measured robot-frame velocity with the fitted
/// model's response.
ReportSection RobotReport(const RobotFit& fit, const RobotFitInput& input);

}  // namespace ubersim::calibrate
