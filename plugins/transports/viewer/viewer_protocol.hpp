// SPDX-License-Identifier: Apache-2.0
// The viewer's WebSocket messages (JSON, SI units): the world going out, the page's commands
// coming in. No sockets here, so it is tested on its own (docs/viewer.md describes the format).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <ubersim/events.hpp>
#include <ubersim/world_state.hpp>

namespace ubersim::viewer {

/// The part of a robot the page draws.
struct RobotSample {
  RobotId id;                    ///< team and id
  bool present = true;           ///< on the field
  double x = 0, y = 0, yaw = 0;  ///< m, rad
  double vx = 0, vy = 0, w = 0;  ///< m/s, rad/s
  bool contact = false;          ///< dribbler touches the ball
  bool kicker_ready = false;     ///< kicker charged
  double radius = 0.09, height = 0.15;  ///< m
  bool has_drive = false;        ///< the drive reported (the fields below are valid)
  std::vector<double> wheel_speeds;  ///< the drive's measured wheel speeds, rad/s
  double drive_forward = 0, drive_left = 0, drive_angular = 0;  ///< its measured velocity, robot frame

  /// Takes pose and velocity (a snapshot's, or a query's answer while paused).
  void SetMotion(const Pose& pose, const Twist& twist) {
    x = pose.position.x();
    y = pose.position.y();
    yaw = pose.Yaw();
    vx = twist.linear.x();
    vy = twist.linear.y();
    w = twist.angular.z();
  }
};

/// The world as the page draws it: a compact copy of one snapshot.
struct WorldSample {
  std::int64_t step = 0;         ///< physics steps
  std::int64_t sim_time_ns = 0;  ///< simulated time
  Vec3 ball_position = Vec3::Zero();  ///< m
  Vec3 ball_velocity = Vec3::Zero();  ///< m/s
  double ball_radius = 0.0215;        ///< m
  std::vector<RobotSample> robots;    ///< blue first, then yellow
};

/// Copies what the page needs out of a snapshot (kept cheap: it runs on the simulation thread).
void SampleSnapshot(const WorldSnapshot& snapshot, WorldSample& out);

/// What the status bar shows.
struct ViewerStatus {
  double real_time_factor = 0;         ///< sim s per wall s, last second
  double vision_rate = 0;              ///< frames per second per camera, last second
  int cameras = 0;                     ///< cameras that sent frames in the last second
  int clients = 0;                     ///< connected browsers
  bool paused = false;                 ///< sim time stands still
  std::optional<double> speed_factor;  ///< last speed set through the viewer (0: as fast as possible)
  std::optional<double> referee_age;   ///< wall s since the last Referee message, none before the first
};

/// The hello message: world name, sample rate, field geometry and cameras, and where the viewer
/// listens for the referee ("224.5.23.1:10003"; empty: it does not, and the page shows no match).
/// The match itself comes in "referee" messages (viewer_referee.hpp).
std::string EncodeHello(const std::string& world, double rate, const FieldGeometry& field,
                        const std::vector<CameraInfo>& cameras, const std::string& referee = {});

/// The state message: the sample, each camera's latest frame and the status.
std::string EncodeState(const WorldSample& sample, const std::vector<VisionFrame>& frames,
                        const ViewerStatus& status);

/// A reply to a command: ack, or error with a message.
std::string EncodeReply(std::string_view cmd, const std::optional<std::int64_t>& id,
                        const std::string& error = {});

/// A decoded page command: the events to post, or why it was refused.
struct DecodedCommand {
  std::string cmd;                  ///< the command's name ("" when unreadable)
  std::optional<std::int64_t> id;   ///< the page's id, echoed back
  std::vector<Event> events;        ///< what to post, in order
  std::optional<double> speed_factor;  ///< set by "speed"
  std::optional<bool> paused;       ///< set by "pause" / "resume" / "step"
  std::string error;                ///< non-empty: refused, nothing to post
};

/// Limits a command must respect.
struct CommandLimits {
  double half_length = 6.0;   ///< |x| of a placed object, m (the carpet's half length)
  double half_width = 4.5;    ///< |y|, m
  double max_ball_speed = 10; ///< kick speed, m/s
  int max_steps = 100000;     ///< one step command
  double max_speed_factor = 1000;  ///< speed command
};

/// Parses and checks one page message (JSON text); never throws.
DecodedCommand DecodeCommand(std::string_view text, const CommandLimits& limits);

}  // namespace ubersim::viewer
