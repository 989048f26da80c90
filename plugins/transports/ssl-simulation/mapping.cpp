// SPDX-License-Identifier: Apache-2.0
#include "mapping.hpp"

#include <cmath>
#include <string_view>

#include <google/protobuf/message_lite.h>

#include "error_codes.hpp"
#include "ssl_simulation_custom_erforce.pb.h"
#include "transport_common/wire_units.hpp"

namespace ubersim::ssl_simulation {
namespace {

std::string Name(const RobotId& id) { return std::string(ToString(id.team)) + " " + std::to_string(id.id); }

// Collects errors and remembers whether one of them refuses the whole message.
class Errors {
 public:
  explicit Errors(Mapped& out) : out_(out) {}
  // A validation error: nothing of the message applies.
  void Refuse(const char* code, std::string message) {
    out_.refused = true;
    out_.errors.push_back({code, std::move(message)});
  }
  // An unsupported item: skipped, the rest applies.
  void Skip(const char* code, std::string message) { out_.errors.push_back({code, std::move(message)}); }
  bool refused() const { return out_.refused; }

 private:
  Mapped& out_;
};

bool AllFinite(std::initializer_list<double> values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

std::optional<Team> ToTeam(const ::RobotId& id) {
  if (!id.has_team()) return std::nullopt;
  if (id.team() == ::BLUE) return Team::kBlue;
  if (id.team() == ::YELLOW) return Team::kYellow;
  return std::nullopt;
}

void MapTeleportBall(const TeleportBall& b, const MappingOptions& options, Errors& errors,
                     std::vector<Event>& events) {
  if (b.teleport_safely()) {
    errors.Skip(codes::kTeleportSafely, "teleport_ball.teleport_safely is not supported; the ball was not moved");
    return;
  }
  if (b.by_force()) {
    errors.Skip(codes::kByForce, "teleport_ball.by_force is not supported; the ball was not moved");
    return;
  }
  if (!AllFinite({b.x(), b.y(), b.z(), b.vx(), b.vy(), b.vz()})) {
    errors.Refuse(codes::kNonFinite, "teleport_ball has a NaN or infinite value");
    return;
  }
  if (b.has_x() != b.has_y() || (b.has_z() && !b.has_x())) {
    errors.Refuse(codes::kPartialCoord, "teleport_ball needs x and y together (z only with them)");
    return;
  }
  PositionEvent e;
  e.target = Target::Ball();
  // z is the height of the ball's centre; unset or below the radius, the kernel rests it on the carpet.
  if (b.has_x()) e.position = Vec3(b.x(), b.y(), b.has_z() ? b.z() : 0.0);
  const bool moving = b.has_vx() || b.has_vy() || b.has_vz();
  if (moving) {
    const Vec3 v(b.vx(), b.vy(), b.vz());  // unset components are 0
    e.velocity = v;
    // Rolling without slip: the contact point stands still, ω × (−r ẑ) = −v.
    e.angular_velocity = b.roll() ? Vec3(-v.y() / options.ball_radius, v.x() / options.ball_radius, 0.0)
                                  : Vec3::Zero();
  }
  if (e.position || e.velocity) events.emplace_back(std::move(e));
}

void MapTeleportRobot(const TeleportRobot& t, const RobotExists& exists, Errors& errors,
                      std::vector<Event>& events) {
  if (!t.id().has_id()) {
    errors.Refuse(codes::kMissingField, "teleport_robot.id.id is unset");
    return;
  }
  const std::optional<Team> team = ToTeam(t.id());
  if (!team) {
    errors.Refuse(codes::kInvalidTeam, "teleport_robot.id.team must be BLUE or YELLOW");
    return;
  }
  const RobotId id{*team, static_cast<int>(t.id().id())};
  if (t.id().id() > 1000 || !exists(id)) {
    errors.Refuse(codes::kUnknownRobot, "no robot " + Name(id) + " in this world");
    return;
  }
  if (t.by_force()) {
    errors.Skip(codes::kByForce, "teleport_robot.by_force is not supported; " + Name(id) + " was not moved");
    return;
  }
  if (!AllFinite({t.x(), t.y(), t.orientation(), t.v_x(), t.v_y(), t.v_angular()})) {
    errors.Refuse(codes::kNonFinite, "teleport_robot for " + Name(id) + " has a NaN or infinite value");
    return;
  }
  if (t.has_x() != t.has_y()) {
    errors.Refuse(codes::kPartialCoord, "teleport_robot for " + Name(id) + " needs x and y together");
    return;
  }
  PositionEvent e;
  e.target = Target::Robot(id);
  if (t.has_x()) e.position = Vec3(t.x(), t.y(), 0.0);
  if (t.has_orientation()) e.yaw = t.orientation();
  if (t.has_v_x() || t.has_v_y()) e.velocity = Vec3(t.v_x(), t.v_y(), 0.0);
  if (t.has_v_angular()) e.angular_velocity = Vec3(0.0, 0.0, t.v_angular());
  if (t.has_present()) e.present = t.present();
  events.emplace_back(std::move(e));
}

std::string_view LastSegment(std::string_view type_url) {
  const auto slash = type_url.rfind('/');
  return slash == std::string_view::npos ? type_url : type_url.substr(slash + 1);
}

// RealismConfigErForce → RealismEvent; fields the kernel does not model are listed unless they
// ask for what the simulator does anyway (zero offsets, no occlusion, physical dribbling).
void MapErForceRealism(const RealismConfigErForce& r, Errors& errors, std::vector<Event>& events) {
  RealismEvent e;
  std::vector<std::string> unsupported;
  std::string invalid;
  auto length = [&](bool has, float v, const char* name, std::optional<double>& into) {
    if (!has) return;
    if (!std::isfinite(v) || v < 0) invalid += std::string(invalid.empty() ? "" : ", ") + name;
    into = v;
  };
  auto probability = [&](bool has, float v, const char* name, std::optional<double>& into) {
    if (!has) return;
    if (!std::isfinite(v) || v < 0 || v > 1) invalid += std::string(invalid.empty() ? "" : ", ") + name;
    into = v;
  };
  auto nanoseconds = [&](bool has, double ns, const char* name, std::optional<double>& into) {
    if (!has) return;
    if (ns < 0 || ns > 10e9) invalid += std::string(invalid.empty() ? "" : ", ") + name;
    into = ns * 1e-9;
  };
  length(r.has_stddev_ball_p(), r.stddev_ball_p(), "stddev_ball_p", e.ball_position_noise);
  length(r.has_stddev_robot_p(), r.stddev_robot_p(), "stddev_robot_p", e.robot_position_noise);
  length(r.has_stddev_robot_phi(), r.stddev_robot_phi(), "stddev_robot_phi", e.robot_orientation_noise);
  length(r.has_camera_overlap(), r.camera_overlap(), "camera_overlap", e.camera_overlap);
  probability(r.has_missing_ball_detections(), r.missing_ball_detections(), "missing_ball_detections", e.ball_drop);
  probability(r.has_missing_robot_detections(), r.missing_robot_detections(), "missing_robot_detections",
              e.robot_drop);
  probability(r.has_robot_command_loss(), r.robot_command_loss(), "robot_command_loss", e.radio_loss);
  nanoseconds(r.has_vision_delay(), static_cast<double>(r.vision_delay()), "vision_delay", e.vision_latency);
  nanoseconds(r.has_command_delay(), static_cast<double>(r.command_delay()), "command_delay", e.radio_latency);

  auto not_zero = [&](bool has, double v, const char* name) {
    if (has && v != 0.0) unsupported.emplace_back(name);
  };
  not_zero(r.has_stddev_ball_area(), r.stddev_ball_area(), "stddev_ball_area");
  not_zero(r.has_ball_visibility_threshold(), r.ball_visibility_threshold(), "ball_visibility_threshold");
  not_zero(r.has_dribbler_ball_detections(), r.dribbler_ball_detections(), "dribbler_ball_detections");
  not_zero(r.has_camera_position_error(), r.camera_position_error(), "camera_position_error");
  not_zero(r.has_robot_response_loss(), r.robot_response_loss(), "robot_response_loss");
  not_zero(r.has_vision_processing_time(), static_cast<double>(r.vision_processing_time()), "vision_processing_time");
  not_zero(r.has_object_position_offset(), r.object_position_offset(), "object_position_offset");
  if (r.has_enable_invisible_ball() && r.enable_invisible_ball()) unsupported.emplace_back("enable_invisible_ball");
  if (r.has_simulate_dribbling() && !r.simulate_dribbling()) unsupported.emplace_back("simulate_dribbling");

  if (!invalid.empty()) {
    errors.Refuse(codes::kInvalidValue,
                  "RealismConfigErForce: " + invalid + " must be finite, >= 0 (probabilities <= 1, delays <= 10 s)");
    return;
  }
  if (!unsupported.empty()) {
    std::string list;
    for (const auto& u : unsupported) list += (list.empty() ? "" : ", ") + u;
    errors.Skip(codes::kRealismFields, "RealismConfigErForce fields not applied: " + list);
  }
  const bool any = e.vision_latency || e.ball_position_noise || e.robot_position_noise ||
                   e.robot_orientation_noise || e.ball_drop || e.robot_drop || e.camera_overlap ||
                   e.radio_latency || e.radio_loss;
  if (any) events.emplace_back(std::move(e));
}

void MapConfig(const SimulatorConfig& c, Errors& errors, std::vector<Event>& events) {
  if (c.has_geometry()) errors.Skip(codes::kGeometry, "config.geometry is not supported: the field comes from the world file");
  if (c.robot_specs_size() > 0)
    errors.Skip(codes::kRobotSpecs, "config.robot_specs is not supported: robots come from their model files");
  if (c.has_vision_port())
    errors.Skip(codes::kVisionPort, "config.vision_port is not supported: set the vision transport's port in the world file");
  for (const google::protobuf::Any& any : c.realism_config().custom()) {
    const std::string_view name = LastSegment(any.type_url());
    if (name != "RealismConfigErForce" && name != "sslsim.RealismConfigErForce") {
      errors.Skip(codes::kUnknownRealism, "realism_config type '" + std::string(name) +
                                              "' is not known (RealismConfigErForce is)");
      continue;
    }
    RealismConfigErForce r;
    if (!r.ParseFromString(any.value())) {
      errors.Refuse(codes::kUnreadable, "realism_config RealismConfigErForce does not parse");
      continue;
    }
    MapErForceRealism(r, errors, events);
  }
}

std::optional<MoveCommand> MapMove(const RobotMoveCommand& m, const MappingOptions& options, const RobotId& id,
                                   Errors& errors) {
  switch (m.command_case()) {
    case RobotMoveCommand::kLocalVelocity: {
      const MoveLocalVelocity& v = m.local_velocity();
      return LocalVelocityCommand{v.forward(), v.left(), v.angular()};
    }
    case RobotMoveCommand::kGlobalVelocity: {
      const MoveGlobalVelocity& v = m.global_velocity();
      return GlobalVelocityCommand{v.x(), v.y(), v.angular()};
    }
    case RobotMoveCommand::kWheelVelocity: {
      const MoveWheelVelocity& w = m.wheel_velocity();
      if (options.wheel_order.size() != 4) {
        errors.Skip(codes::kWheelVelocity, "wheel_velocity is switched off in this world (move of " + Name(id) +
                                               " not applied)");
        return std::nullopt;
      }
      // Passed through as rad/s (as grSim does): the transport cannot know each robot's wheel radius.
      const double speeds[4] = {w.front_right(), w.back_right(), w.back_left(), w.front_left()};
      WheelSpeedCommand c;
      c.wheel_speeds.assign(4, 0.0);
      for (int i = 0; i < 4; ++i) c.wheel_speeds[static_cast<std::size_t>(options.wheel_order[i])] = speeds[i];
      return c;
    }
    case RobotMoveCommand::COMMAND_NOT_SET: break;
  }
  errors.Refuse(codes::kMissingField, "move_command of " + Name(id) + " names no command");
  return std::nullopt;
}

bool FiniteMove(const RobotMoveCommand& m) {
  switch (m.command_case()) {
    case RobotMoveCommand::kLocalVelocity: {
      const auto& v = m.local_velocity();
      return AllFinite({v.forward(), v.left(), v.angular()});
    }
    case RobotMoveCommand::kGlobalVelocity: {
      const auto& v = m.global_velocity();
      return AllFinite({v.x(), v.y(), v.angular()});
    }
    case RobotMoveCommand::kWheelVelocity: {
      const auto& w = m.wheel_velocity();
      return AllFinite({w.front_right(), w.back_right(), w.back_left(), w.front_left()});
    }
    case RobotMoveCommand::COMMAND_NOT_SET: break;
  }
  return true;
}

}  // namespace

Mapped MapSimulatorCommand(const SimulatorCommand& command, const RobotExists& exists,
                           const MappingOptions& options) {
  Mapped out;
  Errors errors(out);
  if (command.has_control()) {
    const SimulatorControl& c = command.control();
    if (c.has_teleport_ball()) MapTeleportBall(c.teleport_ball(), options, errors, out.events);
    for (const TeleportRobot& t : c.teleport_robot()) MapTeleportRobot(t, exists, errors, out.events);
    if (c.has_simulation_speed()) {
      const double s = c.simulation_speed();
      if (!std::isfinite(s) || s <= 0 || s > 1000) {
        errors.Refuse(codes::kInvalidValue, "simulation_speed must be in (0, 1000]");
      } else {
        ClockEvent e;
        e.action = ClockEvent::Action::kSetSpeed;
        e.speed_factor = s;
        out.events.emplace_back(e);
      }
    }
  }
  if (command.has_config()) MapConfig(command.config(), errors, out.events);
  if (out.refused) out.events.clear();
  return out;
}

MappedRobotControl MapRobotControl(const RobotControl& control, Team team, const RobotExists& exists,
                                   const MappingOptions& options) {
  MappedRobotControl out;
  Errors errors(out);
  for (const RobotCommand& rc : control.robot_commands()) {
    const RobotId id{team, static_cast<int>(rc.id())};
    bool named = false;
    for (std::uint32_t seen : out.commanded_ids) named = named || seen == rc.id();
    if (!named) out.commanded_ids.push_back(rc.id());
    if (rc.id() > 1000 || !exists(id)) {
      errors.Refuse(codes::kUnknownRobot, "no robot " + Name(id) + " in this world");
      continue;
    }
    if (!AllFinite({rc.kick_speed(), rc.kick_angle(), rc.dribbler_speed()}) ||
        (rc.has_move_command() && !FiniteMove(rc.move_command()))) {
      errors.Refuse(codes::kNonFinite, "command for " + Name(id) + " has a NaN or infinite value");
      continue;
    }
    CommandEvent e;
    e.robot = id;
    if (rc.has_move_command()) e.move = MapMove(rc.move_command(), options, id, errors);
    if (rc.has_kick_speed() && rc.kick_speed() != 0.0f) {
      if (rc.kick_speed() < 0 || rc.kick_angle() < 0 || rc.kick_angle() >= 90) {
        errors.Refuse(codes::kInvalidValue, "kick of " + Name(id) + ": kick_speed must be >= 0 and kick_angle in [0, 90) degrees");
        continue;
      }
      e.kick = KickCommand{rc.kick_speed(), transport::DegToRad(rc.kick_angle())};
    }
    if (rc.has_dribbler_speed()) e.dribbler_speed = transport::RpmToRadPerS(rc.dribbler_speed());
    if (e.move || e.kick || e.dribbler_speed) out.events.emplace_back(std::move(e));
  }
  if (out.refused) out.events.clear();
  return out;
}

RobotControlResponse BuildRobotControlResponse(const std::vector<std::uint32_t>& ids, Team team,
                                               const ContactLookup& contact,
                                               const std::vector<WireError>& errors) {
  RobotControlResponse r;
  for (std::uint32_t id : ids) {
    const std::optional<bool> touching =
        id > 1000 ? std::nullopt : contact(RobotId{team, static_cast<int>(id)});
    if (!touching) continue;
    RobotFeedback* f = r.add_feedback();
    f->set_id(id);
    f->set_dribbler_ball_contact(*touching);
  }
  AppendErrors(errors, r.mutable_errors());
  return r;
}

void AppendErrors(const std::vector<WireError>& errors,
                  google::protobuf::RepeatedPtrField<SimulatorError>* out) {
  for (const WireError& e : errors) {
    SimulatorError* s = out->Add();
    s->set_code(e.code);
    s->set_message(e.message);
  }
}

SSL_DetectionFrame ToDetectionFrame(const VisionFrame& frame) {
  SSL_DetectionFrame d;
  d.set_frame_number(frame.frame_number);
  d.set_t_capture(transport::NsToSeconds(frame.t_capture_ns));
  d.set_t_sent(transport::NsToSeconds(frame.t_sent_ns));
  d.set_camera_id(static_cast<std::uint32_t>(frame.camera_id));
  for (const DetectedBall& b : frame.balls) {
    SSL_DetectionBall* o = d.add_balls();
    o->set_confidence(static_cast<float>(b.confidence));
    o->set_x(static_cast<float>(transport::MetresToMm(b.x)));
    o->set_y(static_cast<float>(transport::MetresToMm(b.y)));
    o->set_pixel_x(0.0f);  // no image: the simulator sees the field directly
    o->set_pixel_y(0.0f);
  }
  for (const DetectedRobot& r : frame.robots) {
    SSL_DetectionRobot* o = r.id.team == Team::kBlue ? d.add_robots_blue() : d.add_robots_yellow();
    o->set_confidence(static_cast<float>(r.confidence));
    o->set_robot_id(static_cast<std::uint32_t>(r.id.id));
    o->set_x(static_cast<float>(transport::MetresToMm(r.x)));
    o->set_y(static_cast<float>(transport::MetresToMm(r.y)));
    o->set_orientation(static_cast<float>(r.yaw));
    o->set_pixel_x(0.0f);
    o->set_pixel_y(0.0f);
  }
  return d;
}

std::optional<WireError> ParseMessage(const void* data, std::size_t size, std::size_t max_size,
                                      google::protobuf::MessageLite& message) {
  if (size > max_size) {
    return WireError{codes::kOversized, std::to_string(size) + " bytes, more than the limit of " +
                                            std::to_string(max_size)};
  }
  if (!message.ParsePartialFromArray(data, static_cast<int>(size))) {
    return WireError{codes::kUnreadable, "not a " + message.GetTypeName() + " (" + std::to_string(size) + " bytes)"};
  }
  if (!message.IsInitialized()) {
    return WireError{codes::kMissingField, message.GetTypeName() + " lacks required fields: " +
                                               message.InitializationErrorString()};
  }
  return std::nullopt;
}

}  // namespace ubersim::ssl_simulation
