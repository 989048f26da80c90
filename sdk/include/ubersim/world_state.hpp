// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ubersim/events.hpp"
#include "ubersim/math.hpp"

namespace ubersim {
inline namespace v1 {

/// What a drive measures of itself, as a real robot's firmware would report it.
struct DriveFeedback {
  std::vector<double> wheel_speeds;  ///< measured wheel speeds, rad/s, in the drive's wheel order
  Twist local_velocity;              ///< measured chassis velocity in the robot frame (x forward, y left)
};

/// Ground truth of one robot after a step.
struct RobotState {
  RobotId id;                     ///< team and id
  bool present = true;            ///< on the field
  Pose pose;                      ///< chassis pose, world
  Twist twist;                    ///< chassis velocity, world
  bool dribbler_ball_contact = false;  ///< the dribbler touches the ball
  bool kicker_ready = false;      ///< the kicker is charged
  bool feedback_lost = false;     ///< the radio lost this robot's feedback to its team this step
  double radius = 0.09;           ///< m
  double height = 0.15;           ///< m
  std::optional<DriveFeedback> drive;  ///< the drive's Feedback(); none off the field or without a working drive
};

/// Ground truth of the ball after a step.
struct BallState {
  Pose pose;      ///< world
  Twist twist;    ///< world
  double radius = 0.0215;  ///< m
};

/// A line segment of the field markings, m.
struct FieldLine { std::string name; double x1, y1, x2, y2, thickness; };
/// A circular arc of the field markings, m and rad.
struct FieldArc { std::string name; double cx, cy, radius, a1, a2, thickness; };

/// Field geometry as the SSL geometry packet describes it, m.
struct FieldGeometry {
  std::string name;                 ///< model name, e.g. "div-b"
  double field_length = 0;          ///< between goal-line centres
  double field_width = 0;           ///< between touch-line centres
  double goal_width = 0;            ///< inner width
  double goal_depth = 0;            ///< inner depth
  double goal_height = 0;           ///< wall height
  double boundary_width = 0;        ///< line to wall
  double penalty_area_depth = 0;    ///< defense area depth
  double penalty_area_width = 0;    ///< defense area width
  double center_circle_radius = 0;  ///< m
  double line_thickness = 0;        ///< m
  double goal_center_to_penalty_mark = 0;  ///< m
  double carpet_length = 0;         ///< wall to wall (x)
  double carpet_width = 0;          ///< wall to wall (y)
  std::vector<FieldLine> lines;     ///< markings
  std::vector<FieldArc> arcs;       ///< markings
};

/// Everything a transport may publish after a step: the ground truth and time (the kernel calls
/// it the ground truth, World::GroundTruth; the type keeps its name until the next ABI bump, and
/// "snapshot" elsewhere means a saved-state file).
struct WorldSnapshot {
  std::int64_t step = 0;            ///< physics steps since start
  std::int64_t sim_time_ns = 0;     ///< simulated time, ns
  BallState ball;                   ///< the ball
  std::vector<RobotState> robots;   ///< every robot, blue first then yellow, by id
  const FieldGeometry* field = nullptr;  ///< valid during the call
};

/// One of the simulated overhead cameras.
struct CameraInfo {
  int id = 0;                    ///< camera_id in its frames
  Vec3 position = Vec3::Zero();  ///< where it hangs, field frame, m
};

/// One detected robot in a camera frame (after noise).
struct DetectedRobot {
  RobotId id;           ///< team and id
  double x = 0, y = 0;  ///< m, field frame
  double yaw = 0;       ///< rad
  double confidence = 1.0;  ///< 0..1
};

/// One detected ball in a camera frame (projected onto the carpet as the camera sees it).
struct DetectedBall {
  double x = 0, y = 0, z = 0;  ///< m; z is 0 for a projected ball
  double confidence = 1.0;     ///< 0..1
  double area = 0.0;           ///< the blob's area in the camera image, pixels (0: not modelled)
};

/// What one camera reports for one frame, after noise, drop-outs and latency.
struct VisionFrame {
  int camera_id = 0;                 ///< camera
  std::uint32_t frame_number = 0;    ///< per-camera counter
  std::int64_t t_capture_ns = 0;     ///< sim time the scene was sampled
  std::int64_t t_sent_ns = 0;        ///< sim time the frame leaves (capture + latency)
  std::vector<DetectedBall> balls;   ///< detections
  std::vector<DetectedRobot> robots; ///< detections
};

}  // namespace v1
}  // namespace ubersim
