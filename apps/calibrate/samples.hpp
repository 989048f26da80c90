// SPDX-License-Identifier: Apache-2.0
// What `ubersim calibrate` fits from: a field's log turned into plain samples, SI units, times in
// seconds on the session's capture clock (0 at the log's first camera frame). log_session.cpp
// reads them out of an SSL log; the fits (ball_fit, robot_fit, camera_fit) know nothing of files
// or protobuf, so their tests feed them directly.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ubersim/validation/result.hpp"

namespace ubersim::calibrate {

/// Team of a robot, as the SSL wire numbers them.
enum class TeamColour : int { kBlue = 0, kYellow = 1 };

/// A robot on the field: its team and its id.
struct RobotKey {
  TeamColour team = TeamColour::kBlue;  ///< team
  int id = 0;                           ///< 0..15
  friend bool operator<(const RobotKey& a, const RobotKey& b) {
    return a.team != b.team ? a.team < b.team : a.id < b.id;
  }
  friend bool operator==(const RobotKey& a, const RobotKey& b) { return a.team == b.team && a.id == b.id; }
};

/// "blue 3": a robot as the report names it.
std::string RobotName(const RobotKey& robot);

/// One ball detection of one camera frame.
struct BallDetection {
  double x = 0, y = 0;      ///< where the camera reports it on the carpet, m
  double area = 0;          ///< blob area, px (0 when the log has none)
  double confidence = 1;    ///< ssl-vision's confidence, 0..1
};

/// One robot detection of one camera frame.
struct RobotDetection {
  RobotKey robot;           ///< whose
  double x = 0, y = 0;      ///< m
  double yaw = 0;           ///< rad (NaN when the log has no orientation)
  double confidence = 1;    ///< 0..1
};

/// One camera frame as the log holds it: its times and everything it saw.
struct CameraFrame {
  int camera_id = 0;                   ///< the camera
  std::int64_t frame_number = 0;       ///< the camera's own frame counter
  double t_capture = 0;                ///< capture time, s (session clock)
  double t_sent = 0;                   ///< the frame's own send stamp, s (session clock)
  double t_received = 0;               ///< the recorder's receive time, s (session clock, see LogSession)
  std::vector<BallDetection> balls;    ///< every ball blob, false ones included
  std::vector<RobotDetection> robots;  ///< every robot seen
  std::int64_t record = 0;             ///< the log record it came from (1-based), for messages
};

/// One sample of a track: a detection chosen as the object, with its frame's time and camera.
struct TrackPoint {
  double t = 0;             ///< capture time, s
  double x = 0, y = 0;      ///< m
  double yaw = 0;           ///< rad (robots; 0 for the ball)
  int camera_id = 0;        ///< which camera saw it
};

/// A command the team's software sent to a robot, as recorded beside the vision.
struct CommandSample {
  double t = 0;                                   ///< when it was sent, s (session clock)
  double forward = 0, left = 0, angular = 0;      ///< local velocity asked for, m/s and rad/s
  double kick_speed = 0;                          ///< m/s, 0 none
  double kick_angle = 0;                          ///< rad, 0 flat
  double dribbler_speed = 0;                      ///< rad/s
};

/// An estimate with its 95 % confidence interval; `samples` says how much data it rests on.
struct Estimate {
  double value = 0;  ///< best estimate, SI
  double low = 0;    ///< interval's lower end
  double high = 0;   ///< interval's upper end
  int samples = 0;   ///< runs, segments or detections it rests on (0: not estimated)
  bool ok() const { return samples > 0; }
};

/// A part of the report: Markdown (headings from level 3 down) and the plots it refers to by file.
struct ReportSection {
  std::string markdown;                        ///< text, tables, ![](file.svg) references
  std::vector<validation::Plot> plots;         ///< written beside report.md
};

}  // namespace ubersim::calibrate
