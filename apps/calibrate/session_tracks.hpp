// SPDX-License-Identifier: Apache-2.0
// The objects in a session's frames: the ball's track (detections chained frame to frame across
// the cameras; short-lived chains are false balls) and each robot's track, plus the questions the
// fits ask of them (how far is the nearest robot).
#pragma once

#include <map>
#include <vector>

#include "log_session.hpp"
#include "samples.hpp"

namespace ubersim::calibrate {

/// How detections are chained into the ball's track.
struct BallTrackingOptions {
  double gate = 0.05;               ///< m: a detection joins a chain within this of its prediction…
  double max_ball_speed = 9.0;      ///< m/s: …widened by this speed times the time since its last point
  double max_gap = 0.3;             ///< s: a chain unseen this long ends
  int min_points = 8;               ///< chains shorter than this are false balls
};

/// Every object's track in a session.
struct SessionTracks {
  std::vector<TrackPoint> ball;                         ///< the ball (real chains), time-ordered
  std::int64_t false_balls = 0;                         ///< detections in chains too short to be a ball
  std::map<RobotKey, std::vector<TrackPoint>> robots;   ///< each robot's detections, time-ordered
  /// Distance from (x, y) to the nearest robot centre at time t (interpolated), m; +inf when no
  /// robot is seen within 0.2 s of t.
  double NearestRobot(double t, double x, double y) const;
};

/// Builds the tracks of `session`'s frames.
SessionTracks BuildTracks(const LogSession& session, const BallTrackingOptions& options = {});

/// The session's commands for `robot` in its own frame: global-velocity ones turned by the
/// robot's heading (from its track) when they were sent; dropped when the heading is unknown then.
std::vector<CommandSample> LocalCommands(const LogSession& session, const SessionTracks& tracks, const RobotKey& robot);

}  // namespace ubersim::calibrate
