// SPDX-License-Identifier: Apache-2.0
// The SSL simulation protocol as plain functions: wire messages in, kernel events and errors out,
// and world state back into wire messages. No sockets, no threads: the unit tests drive these
// directly. Units change only here (degrees → rad, rpm → rad/s; the protocol itself is in metres
// and seconds; detections are in millimetres).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <ubersim/events.hpp>
#include <ubersim/world_state.hpp>

#include "ssl_simulation_control.pb.h"
#include "ssl_simulation_robot_control.pb.h"
#include "ssl_simulation_robot_feedback.pb.h"
#include "ssl_vision_detection.pb.h"

namespace google::protobuf {
class MessageLite;
}

namespace ubersim::ssl_simulation {

/// One SimulatorError to send back.
struct WireError {
  std::string code;     ///< stable UBERSIM_* code (error_codes.hpp)
  std::string message;  ///< for people
};

/// Settings of the mapping that come from the world file.
struct MappingOptions {
  /// Drive wheel index for the protocol's front_right, back_right, back_left, front_left.
  /// The default fits drives whose wheels are listed counter-clockwise from the front left
  /// (the shipped four-wheel robot: 60°, 135°, 225°, 300°). Empty: wheel_velocity is refused.
  std::vector<int> wheel_order = {3, 2, 1, 0};
  double ball_radius = 0.0215;  ///< m, for `roll`
};

/// Where a robot is.
enum class Presence {
  kAbsent,    ///< not in the world
  kOffField,  ///< in the world, taken off the field
  kOnField,   ///< on the field
};

/// Tells where a robot is.
using RobotLookup = std::function<Presence(const RobotId&)>;

/// What one message turns into: the events of its valid items, one error per invalid item
/// (that item is skipped; the rest applies, as the protocol intends).
struct Mapped {
  std::vector<Event> events;      ///< to post, in order
  std::vector<WireError> errors;  ///< to send back
};

/// The commands of one RobotControl, with the robot ids it named.
struct MappedRobotControl : Mapped {
  std::vector<std::uint32_t> commanded_ids;  ///< every RobotCommand.id, in order, once each
};

/// SimulatorCommand → position, clock and realism events.
Mapped MapSimulatorCommand(const SimulatorCommand& command, const RobotLookup& robots,
                           const MappingOptions& options);

/// RobotControl for `team` (from the port or the sync configuration) → command events.
MappedRobotControl MapRobotControl(const RobotControl& control, Team team, const RobotLookup& robots,
                                   const MappingOptions& options);

/// True for the events whose answer belongs in the reply (robots coming on, robot specs, the
/// field, the vision port): the transport asks the world for it (EventReply).
bool WantsAnswer(const Event& event);

/// The SimulatorErrors of the world's answer to such an event, each with its stable code.
std::vector<WireError> AnswerErrors(const Event& event, const EventAnswer& answer);

/// What one robot's RobotFeedback carries: its dribbler contact and what its drive measured.
struct RobotReport {
  bool dribbler_ball_contact = false;  ///< the dribbler touches the ball
  std::optional<DriveFeedback> drive;  ///< none without a working drive
  bool feedback_lost = false;          ///< the radio lost this robot's answer (robot_response_loss)
};

/// The state one robot's feedback needs; nullopt when the robot is not on the field.
using RobotReportLookup = std::function<std::optional<RobotReport>(const RobotId&)>;

/// Feedback for each commanded robot on the field whose answer the radio did not lose
/// (dribbler_ball_contact, and the drive's measurements as an UberSimDriveFeedback in custom),
/// plus the errors.
RobotControlResponse BuildRobotControlResponse(const std::vector<std::uint32_t>& ids, Team team,
                                               const RobotReportLookup& report,
                                               const std::vector<WireError>& errors);

/// Appends errors to a repeated SimulatorError field.
void AppendErrors(const std::vector<WireError>& errors,
                  google::protobuf::RepeatedPtrField<SimulatorError>* out);

/// One camera frame as an SSL_DetectionFrame: mm, and seconds of simulated time.
SSL_DetectionFrame ToDetectionFrame(const VisionFrame& frame);

/// Parses `size` bytes into `message`; an error when larger than `max_size` or unparseable
/// (UBERSIM_OVERSIZED, UBERSIM_UNREADABLE): nothing of such a message can be trusted. Required
/// fields left unset are the items' business (each such item is refused on its own).
std::optional<WireError> ParseMessage(const void* data, std::size_t size, std::size_t max_size,
                                      google::protobuf::MessageLite& message);

}  // namespace ubersim::ssl_simulation
