// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "ubersim/math.hpp"

namespace ubersim {
inline namespace v1 {

/// The two SSL teams.
enum class Team : std::uint8_t { kBlue, kYellow };

/// "blue" or "yellow".
inline const char* ToString(Team t) { return t == Team::kBlue ? "blue" : "yellow"; }

/// Identifies one robot: team and shirt number.
struct RobotId {
  Team team = Team::kBlue;  ///< team
  int id = 0;               ///< robot id (0..15 in SSL)
  /// Equality on team and id.
  friend bool operator==(const RobotId&, const RobotId&) = default;
};

/// "blue 3", "yellow 0": how every message names a robot.
inline std::string ToString(const RobotId& id) { return std::string(ToString(id.team)) + " " + std::to_string(id.id); }

/// What an event is about: the ball or one robot.
struct Target {
  bool is_ball = true;   ///< true: the ball; false: `robot`
  RobotId robot;         ///< the robot, when !is_ball
  /// Names the ball.
  static Target Ball() { return Target{}; }
  /// Names a robot.
  static Target Robot(RobotId r) { return Target{false, r}; }
};

/// What became of an event that asked for an answer (EventReply): applied as a whole when
/// `errors` is empty.
struct EventAnswer {
  std::vector<std::string> errors;     ///< why it (or a part of it) was refused, one entry each
  std::vector<std::string> unapplied;  ///< what it asked for that the world does not model (it was left out)
};

/// Called once, on the simulation thread, with what became of an event; may be empty.
using EventReply = std::function<void(const EventAnswer&)>;

/// Position event (the paper's): teleports the ball or a robot. Unset fields stay as they are.
/// A robot not in the world with `present` true is built from its team's robot model and put on
/// the field (robot ids 0..15); then `position` is needed.
struct PositionEvent {
  Target target;                        ///< what to move
  std::optional<Vec3> position;         ///< new position, m (robots: z ignored, put on carpet)
  std::optional<double> yaw;            ///< new heading, rad (robots)
  std::optional<Vec3> velocity;         ///< new linear velocity, m/s
  std::optional<Vec3> angular_velocity; ///< new angular velocity, rad/s
  std::optional<bool> present;          ///< robots: false takes it off the field, true puts it on
  EventReply reply = {};                ///< optional: what became of it
};

/// A robot's specifications as its team announces them (the simulation protocol's RobotSpecs),
/// SI. Unset fields keep the team's robot model's value.
struct RobotSpec {
  std::optional<double> radius;                    ///< chassis radius, m
  std::optional<double> height;                    ///< chassis height, m
  std::optional<double> mass;                      ///< kg
  std::optional<double> center_to_dribbler;        ///< centre to the front flat (dribbler), m
  std::optional<double> max_flat_kick_speed;       ///< m/s
  std::optional<double> max_chip_kick_speed;       ///< m/s
  std::optional<double> max_speed;                 ///< m/s
  std::optional<double> max_angular_speed;         ///< rad/s
  std::optional<double> max_acceleration;          ///< speeding up, m/s²
  std::optional<double> max_angular_acceleration;  ///< speeding up, rad/s²
  std::optional<double> max_deceleration;          ///< braking, m/s²
  std::optional<double> max_angular_deceleration;  ///< braking, rad/s²
  /// Wheel angles, rad, counter-clockwise from the robot's forward direction, in the order of
  /// the drive's wheels.
  std::optional<std::vector<double>> wheel_angles;
  std::optional<double> dribbler_width;            ///< usable width of the dribbler bar, m
  /// Equality on every field.
  friend bool operator==(const RobotSpec&, const RobotSpec&) = default;
};

/// Robot spec event: from now on robot `robot` is built from its team's robot model with `spec`
/// over it, checked like a model file. A robot on the field is rebuilt at once, keeping its pose
/// and velocity; one not in the world is built so when it comes on.
struct RobotSpecEvent {
  RobotId robot;     ///< which robot
  RobotSpec spec;    ///< the values over the team's model
  EventReply reply = {};  ///< optional: errors per value, values the model has no place for
};

/// The field size a client asks for (the simulation protocol's geometry), m. The world
/// rebuilds its field when one of its known fields has that size, keeping the robots and ball.
struct FieldEvent {
  double field_length = 0;   ///< between the goal lines
  double field_width = 0;    ///< between the touch lines
  double goal_width = 0;     ///< between the posts
  double goal_depth = 0;     ///< goal line to goal back
  double boundary_width = 0; ///< touch line to wall
  std::optional<double> penalty_area_depth;  ///< when given
  std::optional<double> penalty_area_width;  ///< when given
  EventReply reply = {};                     ///< optional: applied, or why not
};

/// A transport setting changed while running (e.g. "vision_port" from the simulation protocol):
/// offered to every transport (Transport::OnSetting); answered with an error when none takes it.
struct TransportSettingEvent {
  std::string name;        ///< e.g. "vision_port"
  std::int64_t value = 0;  ///< the new value
  EventReply reply = {};   ///< optional: taken, or why not
};

/// Wheel speeds, rad/s, in the order of the drive's wheels.
struct WheelSpeedCommand { std::vector<double> wheel_speeds; };
/// Velocity in the robot frame: forward (x), left (y), m/s; counter-clockwise, rad/s.
struct LocalVelocityCommand { double forward = 0, left = 0, angular = 0; };
/// Velocity in the field frame, m/s, and angular velocity, rad/s.
struct GlobalVelocityCommand { double x = 0, y = 0, angular = 0; };
/// A robot move command in any of the three forms the SSL simulation protocol has.
using MoveCommand = std::variant<WheelSpeedCommand, LocalVelocityCommand, GlobalVelocityCommand>;

/// A kick: speed (m/s) and elevation angle (rad; 0 = flat).
struct KickCommand {
  double speed = 0.0;  ///< requested ball speed, m/s (the kicker clamps it)
  double angle = 0.0;  ///< elevation, rad: 0 flat, > 0 chip
};

/// Command event (the paper's): carries a robot's move/kick/dribble command to its plugins.
struct CommandEvent {
  RobotId robot;                          ///< which robot
  std::optional<MoveCommand> move;        ///< new move command
  std::optional<KickCommand> kick;        ///< kick now if possible
  std::optional<double> dribbler_speed;   ///< roller speed, rad/s (0 stops it)
};

/// State of one object as a query returns it.
struct ObjectState {
  bool found = false;       ///< false when the target does not exist
  bool present = true;      ///< robots: on the field
  Pose pose;                ///< world pose
  Twist twist;              ///< world velocity
};

/// Query event (the paper's): reads an object's pose and velocity back; answered on the
/// simulation thread after the step, by calling `reply`.
struct QueryEvent {
  Target target;                                  ///< what to read
  std::function<void(const ObjectState&)> reply;  ///< called once with the answer
};

/// Clock control: pause, resume, single step, speed factor, reset to the world file's state.
struct ClockEvent {
  /// What to do.
  enum class Action { kPause, kResume, kStep, kSetSpeed, kReset };
  Action action = Action::kPause;  ///< the action
  double speed_factor = 1.0;       ///< kSetSpeed: sim seconds per wall second (0 = as fast as possible)
  int steps = 1;                   ///< kStep: how many physics steps
};

/// Realism event: changes the simulated vision and radio while the world runs (the simulation
/// protocol's realism settings). Unset fields stay as they are; values must be finite and >= 0,
/// probabilities <= 1, or the event is refused.
struct RealismEvent {
  std::optional<double> vision_latency;           ///< capture to send, s
  std::optional<double> ball_position_noise;      ///< σ on the ball's x, y, m
  std::optional<double> robot_position_noise;     ///< σ on robots' x, y, m
  std::optional<double> robot_orientation_noise;  ///< σ on robots' heading, rad
  std::optional<double> ball_drop;                ///< probability a camera frame misses the ball
  std::optional<double> robot_drop;               ///< probability a camera frame misses a robot
  std::optional<double> camera_overlap;           ///< how far a camera sees past its part, m
  std::optional<double> radio_latency;            ///< command arrival to effect, s
  std::optional<double> radio_loss;               ///< probability a command is lost
  std::optional<double> radio_response_loss;      ///< probability a robot's feedback is lost
  std::optional<bool> ball_occlusion;             ///< robots between ball and camera hide (part of) it
  std::optional<double> ball_visibility_threshold;  ///< visible fraction below which the ball is not reported
  std::optional<double> ball_area_noise;          ///< σ on the ball blob's area, pixels
  std::optional<double> dribbler_false_balls;     ///< false ball detections at a dribbler corner, 1/s per robot
  std::optional<double> camera_position_error;    ///< m, in the reported camera positions only
  std::optional<double> object_offset;            ///< m, systematic offset of reported positions
  std::optional<double> processing_time;          ///< t_sent − t_capture in the frames, s
  std::optional<bool> held_ball;                  ///< dribblers hold the ball by a constraint (no slipping)
};

/// Any event a transport or tool can post to the kernel.
using Event = std::variant<PositionEvent, CommandEvent, QueryEvent, ClockEvent, RealismEvent, RobotSpecEvent,
                           FieldEvent, TransportSettingEvent>;

/// Where events go. Post is thread-safe; the kernel applies events at the start of the next step,
/// on the simulation thread, in the order they were posted.
class EventSink {
 public:
  virtual ~EventSink() = default;
  /// Queues an event for the next step.
  virtual void Post(Event event) = 0;
};

}  // namespace v1
}  // namespace ubersim
