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

/// A log played back (`ubersim replay FILE --viewer`), in the hello: the page shows its time slider.
struct ReplayInfo {
  std::string file;         ///< the log's name
  double duration = 0;      ///< s from the first record to the last
  double start_unix = 0;    ///< the first record's time stamp, Unix s
  bool sending = false;     ///< the records also go onto the network, in step with the slider
  double min_speed = 0.25;  ///< the speeds the replay accepts
  double max_speed = 8;
};

/// Where a replay stands, in the state's status.
struct ReplayStatus {
  double t = 0;          ///< s since the log's first record
  double duration = 0;   ///< s
  double speed = 1;      ///< times the recorded rate
  bool playing = false;  ///< time runs (false: paused, or stopped at the end)
};

/// What the status bar shows.
struct ViewerStatus {
  double real_time_factor = 0;         ///< sim s per wall s, last second
  double vision_rate = 0;              ///< frames per second per camera, last second
  int cameras = 0;                     ///< cameras that sent frames in the last second
  int clients = 0;                     ///< connected browsers
  bool paused = false;                 ///< sim time stands still
  std::optional<double> speed_factor;  ///< last speed set through the viewer (0: as fast as possible)
  std::optional<double> referee_age;   ///< wall s since the last Referee message, none before the first
  std::optional<ReplayStatus> replay;  ///< a replay's position (only when replaying a log)
};

/// The hello message: world name, sample rate, field geometry and cameras, and where the viewer
/// listens for the referee ("224.5.23.1:10003"; empty: it does not, and the page shows no match).
/// The match itself comes in "referee" messages (viewer_referee.hpp). `replay`: the log a replay
/// plays (the hello then has a "replay" member; a live world's has none).
std::string EncodeHello(const std::string& world, double rate, const FieldGeometry& field,
                        const std::vector<CameraInfo>& cameras, const std::string& referee = {},
                        const ReplayInfo* replay = nullptr);

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

/// A page's command to a replay: at most one of seek, playing and speed is set.
struct ReplayCommand {
  std::string cmd;                 ///< "seek", "play", "pause" or "speed" ("" when unreadable)
  std::optional<std::int64_t> id;  ///< the page's id, echoed back
  std::optional<double> seek;      ///< s since the first record, within [0, duration]
  std::optional<bool> playing;     ///< play (true) or pause (false)
  std::optional<double> speed;     ///< times the recorded rate
  std::string error;               ///< non-empty: refused, nothing changes
};

/// Parses and checks one page message to a replay (JSON text); never throws. "seek" {"t": s}
/// (clamped to the log), "play" (or "resume"), "pause", "speed" {"factor": f} within the info's
/// speeds. The live world's commands (move, kick, step, reset) are refused: a log cannot change.
ReplayCommand DecodeReplayCommand(std::string_view text, const ReplayInfo& replay);

}  // namespace ubersim::viewer
