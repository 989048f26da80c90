// SPDX-License-Identifier: Apache-2.0
#include "mapping.hpp"

#include <cmath>
#include <string_view>

#include <google/protobuf/message_lite.h>

#include "error_codes.hpp"
#include "ssl_simulation_custom_erforce.pb.h"
#include "ssl_simulation_custom_ubersim.pb.h"
#include "transport_common/wire_units.hpp"

namespace ubersim::ssl_simulation {
namespace {


// Collects one error per skipped item.
class Errors {
 public:
  explicit Errors(Mapped& out) : out_(out) {}
  void Add(const char* code, std::string message) { out_.errors.push_back({code, std::move(message)}); }

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

constexpr std::uint32_t kMaxRobotId = 15;  // the rules' ids per team

void MapTeleportBall(const TeleportBall& b, const MappingOptions& options, Errors& errors,
                     std::vector<Event>& events) {
  if (b.teleport_safely()) {
    errors.Add(codes::kTeleportSafely, "teleport_ball.teleport_safely is not supported; the ball was not moved");
    return;
  }
  if (b.by_force()) {
    errors.Add(codes::kByForce, "teleport_ball.by_force is not supported; the ball was not moved");
    return;
  }
  if (!AllFinite({b.x(), b.y(), b.z(), b.vx(), b.vy(), b.vz()})) {
    errors.Add(codes::kNonFinite, "teleport_ball has a NaN or infinite value; the ball was not moved");
    return;
  }
  if (b.has_x() != b.has_y() || (b.has_z() && !b.has_x())) {
    errors.Add(codes::kPartialCoord, "teleport_ball needs x and y together (z only with them); the ball was not moved");
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

// The robot an item names (`item`: "teleport_robot", "robot_specs"), or nullopt with one error:
// id unset, a team that is neither BLUE nor YELLOW, an id above 15.
std::optional<RobotId> ItemRobot(bool has_id, const ::RobotId& wire, const char* item, Errors& errors) {
  if (!has_id || !wire.has_id()) {
    errors.Add(codes::kMissingField, std::string("a ") + item + " has no id.id; it was skipped");
    return std::nullopt;
  }
  const std::optional<Team> team = ToTeam(wire);
  if (!team) {
    errors.Add(codes::kInvalidTeam, std::string(item) + " " + std::to_string(wire.id()) +
                                        ": id.team must be BLUE or YELLOW; it was skipped");
    return std::nullopt;
  }
  if (wire.id() > kMaxRobotId) {
    errors.Add(codes::kInvalidRobotId, std::string(item) + " " + ToString(*team) + " " + std::to_string(wire.id()) +
                                           ": robot ids are 0..15; it was skipped");
    return std::nullopt;
  }
  return RobotId{*team, static_cast<int>(wire.id())};
}

void MapTeleportRobot(const TeleportRobot& t, const RobotLookup& robots, Errors& errors,
                      std::vector<Event>& events) {
  const std::optional<RobotId> robot = ItemRobot(t.has_id(), t.id(), "teleport_robot", errors);
  if (!robot) return;
  const RobotId id = *robot;
  const Presence where = robots(id);
  const bool on = t.has_present() && t.present();
  // A robot that is not on the field and is not asked to come on: nothing to move, as on grSim
  // (a client clearing ids 0..15 out of the way moves the robots there are and nothing else).
  if (where != Presence::kOnField && !on) return;
  if (t.by_force()) {
    errors.Add(codes::kByForce, "teleport_robot.by_force is not supported; " + ToString(id) + " was not moved");
    return;
  }
  if (!AllFinite({t.x(), t.y(), t.orientation(), t.v_x(), t.v_y(), t.v_angular()})) {
    errors.Add(codes::kNonFinite, "teleport_robot for " + ToString(id) + " has a NaN or infinite value; it was not moved");
    return;
  }
  if (t.has_x() != t.has_y()) {
    errors.Add(codes::kPartialCoord, "teleport_robot for " + ToString(id) + " needs x and y together; it was not moved");
    return;
  }
  if (where == Presence::kAbsent && !t.has_x()) {
    errors.Add(codes::kCreateNoPosition, "robot " + ToString(id) + " is not in the world: present needs x and y to put it on");
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

// RealismConfigErForce → RealismEvent, every field (docs/interfaces.md): ns become s,
// simulate_dribbling false becomes a held ball. One invalid value refuses the whole message, so a
// preset is never applied in part.
void MapErForceRealism(const RealismConfigErForce& r, Errors& errors, std::vector<Event>& events) {
  RealismEvent e;
  bool any = false;
  std::string invalid;
  auto refuse = [&](const char* name) { invalid += std::string(invalid.empty() ? "" : ", ") + name; };
  // Lengths, σ and rates: finite and >= 0.
  auto non_negative = [&](bool has, float v, const char* name, std::optional<double>& into) {
    if (!has) return;
    if (!std::isfinite(v) || v < 0) refuse(name);
    into = v;
    any = true;
  };
  auto probability = [&](bool has, float v, const char* name, std::optional<double>& into) {
    if (!has) return;
    if (!std::isfinite(v) || v < 0 || v > 1) refuse(name);
    into = v;
    any = true;
  };
  auto nanoseconds = [&](bool has, double ns, const char* name, std::optional<double>& into) {
    if (!has) return;
    if (ns < 0 || ns > 10e9) refuse(name);
    into = ns * 1e-9;
    any = true;
  };
  auto flag = [&](bool has, bool v, std::optional<bool>& into) {
    if (!has) return;
    into = v;
    any = true;
  };
  // In the proto's field order, 1–18.
  non_negative(r.has_stddev_ball_p(), r.stddev_ball_p(), "stddev_ball_p", e.ball_position_noise);
  non_negative(r.has_stddev_robot_p(), r.stddev_robot_p(), "stddev_robot_p", e.robot_position_noise);
  non_negative(r.has_stddev_robot_phi(), r.stddev_robot_phi(), "stddev_robot_phi", e.robot_orientation_noise);
  non_negative(r.has_stddev_ball_area(), r.stddev_ball_area(), "stddev_ball_area", e.ball_area_noise);
  flag(r.has_enable_invisible_ball(), r.enable_invisible_ball(), e.ball_occlusion);
  probability(r.has_ball_visibility_threshold(), r.ball_visibility_threshold(), "ball_visibility_threshold",
              e.ball_visibility_threshold);
  non_negative(r.has_camera_overlap(), r.camera_overlap(), "camera_overlap", e.camera_overlap);
  non_negative(r.has_dribbler_ball_detections(), r.dribbler_ball_detections(), "dribbler_ball_detections",
               e.dribbler_false_balls);
  non_negative(r.has_camera_position_error(), r.camera_position_error(), "camera_position_error",
               e.camera_position_error);
  probability(r.has_robot_command_loss(), r.robot_command_loss(), "robot_command_loss", e.radio_loss);
  probability(r.has_robot_response_loss(), r.robot_response_loss(), "robot_response_loss",
              e.radio_response_loss);
  probability(r.has_missing_ball_detections(), r.missing_ball_detections(), "missing_ball_detections",
              e.ball_drop);
  nanoseconds(r.has_vision_delay(), static_cast<double>(r.vision_delay()), "vision_delay", e.vision_latency);
  nanoseconds(r.has_vision_processing_time(), static_cast<double>(r.vision_processing_time()),
              "vision_processing_time", e.processing_time);
  if (r.has_simulate_dribbling()) {
    e.held_ball = !r.simulate_dribbling();  // "perfect" dribbling: the ball held by a constraint
    any = true;
  }
  non_negative(r.has_object_position_offset(), r.object_position_offset(), "object_position_offset",
               e.object_offset);
  probability(r.has_missing_robot_detections(), r.missing_robot_detections(), "missing_robot_detections",
              e.robot_drop);
  nanoseconds(r.has_command_delay(), static_cast<double>(r.command_delay()), "command_delay", e.radio_latency);

  if (!invalid.empty()) {
    errors.Add(codes::kInvalidValue,
               "RealismConfigErForce not applied: " + invalid + " must be finite, >= 0 (probabilities <= 1, delays <= 10 s)");
    return;
  }
  if (any) events.emplace_back(std::move(e));
}

// One RobotSpecs → RobotSpecEvent (SI already; wheel angles into the drive's order and sense).
void MapRobotSpecs(const RobotSpecs& r, const MappingOptions& options, Errors& errors, std::vector<Event>& events) {
  const std::optional<RobotId> robot = ItemRobot(r.has_id(), r.id(), "robot_specs", errors);
  if (!robot) return;
  const RobotId id = *robot;
  if (!r.IsInitialized()) {
    errors.Add(codes::kMissingField, "robot_specs of " + ToString(id) + " lacks " + r.InitializationErrorString() +
                                         "; not applied");
    return;
  }
  RobotSpecEvent e;
  e.robot = id;
  RobotSpec& spec = e.spec;
  std::vector<double> values;
  auto take = [&](bool has, float v, std::optional<double>& into) {
    if (!has) return;
    into = v;
    values.push_back(v);
  };
  take(r.has_radius(), r.radius(), spec.radius);
  take(r.has_height(), r.height(), spec.height);
  take(r.has_mass(), r.mass(), spec.mass);
  take(r.has_center_to_dribbler(), r.center_to_dribbler(), spec.center_to_dribbler);
  take(r.has_max_linear_kick_speed(), r.max_linear_kick_speed(), spec.max_flat_kick_speed);
  take(r.has_max_chip_kick_speed(), r.max_chip_kick_speed(), spec.max_chip_kick_speed);
  if (r.has_limits()) {
    const RobotLimits& l = r.limits();
    take(l.has_acc_speedup_absolute_max(), l.acc_speedup_absolute_max(), spec.max_acceleration);
    take(l.has_acc_speedup_angular_max(), l.acc_speedup_angular_max(), spec.max_angular_acceleration);
    take(l.has_acc_brake_absolute_max(), l.acc_brake_absolute_max(), spec.max_deceleration);
    take(l.has_acc_brake_angular_max(), l.acc_brake_angular_max(), spec.max_angular_deceleration);
    take(l.has_vel_absolute_max(), l.vel_absolute_max(), spec.max_speed);
    take(l.has_vel_angular_max(), l.vel_angular_max(), spec.max_angular_speed);
  }
  if (r.has_wheel_angles()) {
    // The protocol's angles run clockwise from forward, front_right first; the drive's run
    // counter-clockwise, in its own wheel order (wheel_velocity_order maps one to the other).
    const RobotWheelAngles& w = r.wheel_angles();
    const double clockwise[4] = {w.front_right(), w.back_right(), w.back_left(), w.front_left()};
    if (options.wheel_order.size() != 4) {
      errors.Add(codes::kUnmappedSpec, "robot_specs of " + ToString(id) +
                                           ": wheel_angles not applied (this world sets no wheel_velocity_order)");
    } else {
      std::vector<double> ccw(4, 0.0);
      for (int i = 0; i < 4; ++i) {
        double a = std::fmod(-clockwise[i], 2 * M_PI);
        if (a < 0) a += 2 * M_PI;
        ccw[static_cast<std::size_t>(options.wheel_order[static_cast<std::size_t>(i)])] = a;
        values.push_back(clockwise[i]);
      }
      spec.wheel_angles = std::move(ccw);
    }
  }
  std::vector<std::string> unknown;
  for (const google::protobuf::Any& any : r.custom()) {
    const std::string_view name = LastSegment(any.type_url());
    if (name != "RobotSpecErForce" && name != "sslsim.RobotSpecErForce") {
      unknown.emplace_back(name);
      continue;
    }
    RobotSpecErForce erforce;
    if (!erforce.ParseFromString(any.value())) {
      errors.Add(codes::kUnreadable, "robot_specs of " + ToString(id) + ": RobotSpecErForce does not parse; not applied");
      return;
    }
    take(erforce.has_dribbler_width(), erforce.dribbler_width(), spec.dribbler_width);
    // shoot_radius: centre to the ball's centre with the ball against the front, i.e. the front
    // flat plus a ball radius; it sets the front only when center_to_dribbler does not.
    if (erforce.has_shoot_radius()) {
      values.push_back(erforce.shoot_radius());
      const double front = erforce.shoot_radius() - options.ball_radius;
      if (!spec.center_to_dribbler) {
        spec.center_to_dribbler = front;
      } else if (std::abs(*spec.center_to_dribbler - front) > 0.001) {
        errors.Add(codes::kUnmappedSpec, "robot_specs of " + ToString(id) + ": RobotSpecErForce.shoot_radius " +
                                             std::to_string(erforce.shoot_radius()) +
                                             " m not applied: center_to_dribbler sets the front");
      }
    }
  }
  if (!unknown.empty()) {
    std::string list;
    for (const auto& u : unknown) list += (list.empty() ? "'" : ", '") + u + "'";
    errors.Add(codes::kUnmappedSpec, "robot_specs of " + ToString(id) + ": custom spec types not known: " + list +
                                         " (RobotSpecErForce is)");
  }
  for (double v : values) {
    if (!std::isfinite(v)) {
      errors.Add(codes::kNonFinite, "robot_specs of " + ToString(id) + " has a NaN or infinite value; not applied");
      return;
    }
  }
  events.emplace_back(std::move(e));
}

void MapGeometry(const SSL_GeometryData& g, Errors& errors, std::vector<Event>& events) {
  const SSL_GeometryFieldSize& f = g.field();
  if (!g.has_field() || !f.IsInitialized()) {
    errors.Add(codes::kMissingField, "config.geometry lacks field sizes (" + f.InitializationErrorString() +
                                         "); the field was not changed");
    return;
  }
  FieldEvent e;
  e.field_length = transport::MmToMetres(f.field_length());
  e.field_width = transport::MmToMetres(f.field_width());
  e.goal_width = transport::MmToMetres(f.goal_width());
  e.goal_depth = transport::MmToMetres(f.goal_depth());
  e.boundary_width = transport::MmToMetres(f.boundary_width());
  if (f.has_penalty_area_depth()) e.penalty_area_depth = transport::MmToMetres(f.penalty_area_depth());
  if (f.has_penalty_area_width()) e.penalty_area_width = transport::MmToMetres(f.penalty_area_width());
  events.emplace_back(std::move(e));
}

void MapConfig(const SimulatorConfig& c, const MappingOptions& options, Errors& errors, std::vector<Event>& events) {
  if (c.has_geometry()) MapGeometry(c.geometry(), errors, events);
  for (const RobotSpecs& r : c.robot_specs()) MapRobotSpecs(r, options, errors, events);
  if (c.has_vision_port()) {
    if (c.vision_port() == 0 || c.vision_port() > 65535) {
      errors.Add(codes::kInvalidValue, "vision_port " + std::to_string(c.vision_port()) + " is not a port (1..65535)");
    } else {
      TransportSettingEvent e;
      e.name = "vision_port";
      e.value = c.vision_port();
      events.emplace_back(std::move(e));
    }
  }
  for (const google::protobuf::Any& any : c.realism_config().custom()) {
    const std::string_view name = LastSegment(any.type_url());
    if (name != "RealismConfigErForce" && name != "sslsim.RealismConfigErForce") {
      errors.Add(codes::kUnknownRealism, "realism_config type '" + std::string(name) +
                                              "' is not known (RealismConfigErForce is)");
      continue;
    }
    RealismConfigErForce r;
    if (!r.ParseFromString(any.value())) {
      errors.Add(codes::kUnreadable, "realism_config RealismConfigErForce does not parse");
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
        errors.Add(codes::kWheelVelocity, "wheel_velocity is switched off in this world (move of " + ToString(id) +
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
  errors.Add(codes::kMissingField, "move_command of " + ToString(id) + " names no command; its command was skipped");
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

Mapped MapSimulatorCommand(const SimulatorCommand& command, const RobotLookup& robots,
                           const MappingOptions& options) {
  Mapped out;
  Errors errors(out);
  if (command.has_control()) {
    const SimulatorControl& c = command.control();
    if (c.has_teleport_ball()) MapTeleportBall(c.teleport_ball(), options, errors, out.events);
    for (const TeleportRobot& t : c.teleport_robot()) MapTeleportRobot(t, robots, errors, out.events);
    if (c.has_simulation_speed()) {
      const double s = c.simulation_speed();
      if (!std::isfinite(s) || s <= 0 || s > 1000) {
        errors.Add(codes::kInvalidValue, "simulation_speed must be in (0, 1000]; the speed was not changed");
      } else {
        ClockEvent e;
        e.action = ClockEvent::Action::kSetSpeed;
        e.speed_factor = s;
        out.events.emplace_back(e);
      }
    }
  }
  if (command.has_config()) MapConfig(command.config(), options, errors, out.events);
  return out;
}

MappedRobotControl MapRobotControl(const RobotControl& control, Team team, const RobotLookup& robots,
                                   const MappingOptions& options) {
  MappedRobotControl out;
  Errors errors(out);
  for (const RobotCommand& rc : control.robot_commands()) {
    if (!rc.has_id()) {
      errors.Add(codes::kMissingField, "a robot command has no id; it was skipped");
      continue;
    }
    const RobotId id{team, static_cast<int>(rc.id())};
    bool named = false;
    for (std::uint32_t seen : out.commanded_ids) named = named || seen == rc.id();
    if (!named) out.commanded_ids.push_back(rc.id());
    if (rc.id() > kMaxRobotId || robots(id) != Presence::kOnField) {
      errors.Add(codes::kUnknownRobot, "no robot " + ToString(id) + " on the field; its command was skipped");
      continue;
    }
    if (!rc.IsInitialized()) {
      errors.Add(codes::kMissingField, "command for " + ToString(id) + " lacks " + rc.InitializationErrorString() +
                                           "; it was skipped");
      continue;
    }
    if (!AllFinite({rc.kick_speed(), rc.kick_angle(), rc.dribbler_speed()}) ||
        (rc.has_move_command() && !FiniteMove(rc.move_command()))) {
      errors.Add(codes::kNonFinite, "command for " + ToString(id) + " has a NaN or infinite value; it was skipped");
      continue;
    }
    if (rc.has_kick_speed() && rc.kick_speed() != 0.0f &&
        (rc.kick_speed() < 0 || rc.kick_angle() < 0 || rc.kick_angle() >= 90)) {
      errors.Add(codes::kInvalidValue, "kick of " + ToString(id) +
                                           ": kick_speed must be >= 0 and kick_angle in [0, 90) degrees; its command was skipped");
      continue;
    }
    CommandEvent e;
    e.robot = id;
    if (rc.has_move_command()) e.move = MapMove(rc.move_command(), options, id, errors);
    if (rc.has_kick_speed() && rc.kick_speed() != 0.0f) {
      e.kick = KickCommand{rc.kick_speed(), transport::DegToRad(rc.kick_angle())};
    }
    if (rc.has_dribbler_speed()) e.dribbler_speed = transport::RpmToRadPerS(rc.dribbler_speed());
    if (e.move || e.kick || e.dribbler_speed) out.events.emplace_back(std::move(e));
  }
  return out;
}

bool WantsAnswer(const Event& event) {
  if (const auto* p = std::get_if<PositionEvent>(&event)) return !p->target.is_ball && p->present && *p->present;
  return std::holds_alternative<RobotSpecEvent>(event) || std::holds_alternative<FieldEvent>(event) ||
         std::holds_alternative<TransportSettingEvent>(event);
}

std::vector<WireError> AnswerErrors(const Event& event, const EventAnswer& answer) {
  const char* code = codes::kRobotNotBuilt;
  std::string what = "TeleportRobot";
  if (const auto* s = std::get_if<RobotSpecEvent>(&event)) {
    code = codes::kInvalidSpec;
    what = "robot_specs of " + ToString(s->robot);
  } else if (std::holds_alternative<FieldEvent>(event)) {
    code = codes::kGeometry;
    what = "geometry";
  } else if (std::holds_alternative<TransportSettingEvent>(event)) {
    code = codes::kVisionPort;
    what = "vision_port";
  }
  std::vector<WireError> out;
  for (const std::string& e : answer.errors) out.push_back({code, what + ": " + e});
  if (!answer.unapplied.empty()) {
    std::string list;
    for (const std::string& u : answer.unapplied) list += (list.empty() ? "" : "; ") + u;
    out.push_back({codes::kUnmappedSpec, what + ": not applied: " + list});
  }
  return out;
}

RobotControlResponse BuildRobotControlResponse(const std::vector<std::uint32_t>& ids, Team team,
                                               const RobotReportLookup& report,
                                               const std::vector<WireError>& errors) {
  RobotControlResponse r;
  for (std::uint32_t id : ids) {
    const std::optional<RobotReport> robot =
        id > kMaxRobotId ? std::nullopt : report(RobotId{team, static_cast<int>(id)});
    if (!robot || robot->feedback_lost) continue;  // the radio lost its answer
    RobotFeedback* f = r.add_feedback();
    f->set_id(id);
    f->set_dribbler_ball_contact(robot->dribbler_ball_contact);
    if (robot->drive) {
      UberSimDriveFeedback d;
      for (double w : robot->drive->wheel_speeds) d.add_wheel_speeds(static_cast<float>(w));
      d.set_forward(static_cast<float>(robot->drive->local_velocity.linear.x()));
      d.set_left(static_cast<float>(robot->drive->local_velocity.linear.y()));
      d.set_angular(static_cast<float>(robot->drive->local_velocity.angular.z()));
      f->mutable_custom()->PackFrom(d);
    }
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
    o->set_area(transport::WholePixels(b.area));  // the blob in the image, whole pixels
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
  return std::nullopt;
}

}  // namespace ubersim::ssl_simulation
