// SPDX-License-Identifier: Apache-2.0
#include "viewer_protocol.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <rapidjson/document.h>
#include <rapidjson/error/en.h>
#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>

namespace ubersim::viewer {
namespace {

using Writer = rapidjson::Writer<rapidjson::StringBuffer>;

constexpr double kNs = 1e-9;

void Number(Writer& w, const char* key, double value) {
  w.Key(key);
  // JSON has no NaN or infinity; a broken value goes out as null rather than as invalid text.
  if (std::isfinite(value)) w.Double(value); else w.Null();
}

void Team(Writer& w, const RobotId& id) {
  w.Key("team");
  w.String(ToString(id.team));
  w.Key("id");
  w.Int(id.id);
}

void Field(Writer& w, const FieldGeometry& f) {
  w.StartObject();
  w.Key("name");
  w.String(f.name.c_str());
  Number(w, "field_length", f.field_length);
  Number(w, "field_width", f.field_width);
  Number(w, "goal_width", f.goal_width);
  Number(w, "goal_depth", f.goal_depth);
  Number(w, "goal_height", f.goal_height);
  Number(w, "boundary_width", f.boundary_width);
  Number(w, "penalty_area_depth", f.penalty_area_depth);
  Number(w, "penalty_area_width", f.penalty_area_width);
  Number(w, "center_circle_radius", f.center_circle_radius);
  Number(w, "line_thickness", f.line_thickness);
  Number(w, "goal_center_to_penalty_mark", f.goal_center_to_penalty_mark);
  Number(w, "carpet_length", f.carpet_length);
  Number(w, "carpet_width", f.carpet_width);
  w.Key("lines");
  w.StartArray();
  for (const FieldLine& l : f.lines) {
    w.StartObject();
    w.Key("name");
    w.String(l.name.c_str());
    Number(w, "x1", l.x1);
    Number(w, "y1", l.y1);
    Number(w, "x2", l.x2);
    Number(w, "y2", l.y2);
    Number(w, "thickness", l.thickness);
    w.EndObject();
  }
  w.EndArray();
  w.Key("arcs");
  w.StartArray();
  for (const FieldArc& a : f.arcs) {
    w.StartObject();
    w.Key("name");
    w.String(a.name.c_str());
    Number(w, "cx", a.cx);
    Number(w, "cy", a.cy);
    Number(w, "radius", a.radius);
    Number(w, "a1", a.a1);
    Number(w, "a2", a.a2);
    Number(w, "thickness", a.thickness);
    w.EndObject();
  }
  w.EndArray();
  w.EndObject();
}

// Reads the optional integer "id" the page uses to match replies.
std::optional<std::int64_t> ReadId(const rapidjson::Value& doc) {
  const auto it = doc.FindMember("id");
  if (it == doc.MemberEnd() || !it->value.IsInt64()) return std::nullopt;
  return it->value.GetInt64();
}

// A finite number member; error names the key.
std::optional<double> ReadNumber(const rapidjson::Value& doc, const char* key, bool required,
                                 std::string& error) {
  const auto it = doc.FindMember(key);
  if (it == doc.MemberEnd()) {
    if (required) error = std::string("'") + key + "' is missing";
    return std::nullopt;
  }
  if (!it->value.IsNumber() || !std::isfinite(it->value.GetDouble())) {
    error = std::string("'") + key + "' must be a finite number";
    return std::nullopt;
  }
  return it->value.GetDouble();
}

// The "target" of a move: "ball" or {"team": "blue"|"yellow", "id": 0..15}.
std::optional<Target> ReadTarget(const rapidjson::Value& doc, std::string& error) {
  const auto it = doc.FindMember("target");
  if (it == doc.MemberEnd()) {
    error = "'target' is missing";
    return std::nullopt;
  }
  const rapidjson::Value& t = it->value;
  if (t.IsString() && std::string_view(t.GetString()) == "ball") return Target::Ball();
  if (!t.IsObject()) {
    error = "'target' must be \"ball\" or {\"team\": \"blue\"|\"yellow\", \"id\": N}";
    return std::nullopt;
  }
  const auto team = t.FindMember("team");
  const auto id = t.FindMember("id");
  if (team == t.MemberEnd() || !team->value.IsString()) {
    error = "'target.team' must be \"blue\" or \"yellow\"";
    return std::nullopt;
  }
  const std::string_view team_name = team->value.GetString();
  if (team_name != "blue" && team_name != "yellow") {
    error = "'target.team' must be \"blue\" or \"yellow\", not \"" + std::string(team_name) + "\"";
    return std::nullopt;
  }
  if (id == t.MemberEnd() || !id->value.IsInt() || id->value.GetInt() < 0 || id->value.GetInt() > 15) {
    error = "'target.id' must be an integer 0..15";
    return std::nullopt;
  }
  return Target::Robot(RobotId{team_name == "blue" ? Team::kBlue : Team::kYellow, id->value.GetInt()});
}

void DecodeMove(const rapidjson::Value& doc, const CommandLimits& limits, DecodedCommand& out) {
  std::string& error = out.error;
  const auto target = ReadTarget(doc, error);
  if (!target) return;
  const auto x = ReadNumber(doc, "x", true, error);
  if (!x) return;
  const auto y = ReadNumber(doc, "y", true, error);
  if (!y) return;
  if (std::abs(*x) > limits.half_length || std::abs(*y) > limits.half_width) {
    error = "position (" + std::to_string(*x) + ", " + std::to_string(*y) +
            ") m is off the carpet (|x| <= " + std::to_string(limits.half_length) +
            ", |y| <= " + std::to_string(limits.half_width) + ")";
    return;
  }
  PositionEvent e;
  e.target = *target;
  if (target->is_ball) {
    const auto z = ReadNumber(doc, "z", false, error);
    if (!error.empty()) return;
    e.position = Vec3(*x, *y, z.value_or(0.0));  // the kernel lifts it to lie on the carpet
  } else {
    const auto yaw = ReadNumber(doc, "yaw", false, error);
    if (!error.empty()) return;
    e.position = Vec3(*x, *y, 0.0);
    e.yaw = yaw;
  }
  // Placed by hand: at rest, like a ball or robot put down on the field.
  e.velocity = Vec3::Zero();
  e.angular_velocity = Vec3::Zero();
  out.events.emplace_back(std::move(e));
}

void DecodeKick(const rapidjson::Value& doc, const CommandLimits& limits, DecodedCommand& out) {
  std::string& error = out.error;
  const auto vx = ReadNumber(doc, "vx", true, error);
  if (!vx) return;
  const auto vy = ReadNumber(doc, "vy", true, error);
  if (!vy) return;
  const auto vz = ReadNumber(doc, "vz", false, error);
  if (!error.empty()) return;
  const Vec3 v(*vx, *vy, vz.value_or(0.0));
  if (v.norm() > limits.max_ball_speed) {
    error = "kick speed " + std::to_string(v.norm()) + " m/s is above " +
            std::to_string(limits.max_ball_speed) + " m/s";
    return;
  }
  if (v.z() < 0) {
    error = "'vz' must be >= 0 (a kick cannot go into the carpet)";
    return;
  }
  PositionEvent e;
  e.target = Target::Ball();
  e.velocity = v;
  e.angular_velocity = Vec3::Zero();
  out.events.emplace_back(std::move(e));
}

}  // namespace

void SampleSnapshot(const WorldSnapshot& s, WorldSample& out) {
  out.step = s.step;
  out.sim_time_ns = s.sim_time_ns;
  out.ball_position = s.ball.pose.position;
  out.ball_velocity = s.ball.twist.linear;
  out.ball_radius = s.ball.radius;
  out.robots.resize(s.robots.size());
  for (std::size_t i = 0; i < s.robots.size(); ++i) {
    const RobotState& r = s.robots[i];
    RobotSample& o = out.robots[i];
    o.id = r.id;
    o.present = r.present;
    o.SetMotion(r.pose, r.twist);
    o.contact = r.dribbler_ball_contact;
    o.kicker_ready = r.kicker_ready;
    o.radius = r.radius;
    o.height = r.height;
    o.has_drive = r.drive.has_value();
    if (r.drive) {  // assigned, so the storage is reused from one sample to the next
      o.wheel_speeds.assign(r.drive->wheel_speeds.begin(), r.drive->wheel_speeds.end());
      o.drive_forward = r.drive->local_velocity.linear.x();
      o.drive_left = r.drive->local_velocity.linear.y();
      o.drive_angular = r.drive->local_velocity.angular.z();
    } else {
      o.wheel_speeds.clear();
    }
  }
}

std::string EncodeHello(const std::string& world, double rate, const FieldGeometry& field,
                        const std::vector<CameraInfo>& cameras, const std::string& referee,
                        const ReplayInfo* replay) {
  rapidjson::StringBuffer buffer;
  Writer w(buffer);
  w.SetMaxDecimalPlaces(6);
  w.StartObject();
  w.Key("type");
  w.String("hello");
  w.Key("protocol");
  w.Int(1);
  w.Key("world");
  w.String(world.c_str());
  Number(w, "rate", rate);
  w.Key("field");
  Field(w, field);
  w.Key("cameras");
  w.StartArray();
  for (const CameraInfo& c : cameras) {
    w.StartObject();
    w.Key("id");
    w.Int(c.id);
    Number(w, "x", c.position.x());
    Number(w, "y", c.position.y());
    Number(w, "z", c.position.z());
    w.EndObject();
  }
  w.EndArray();
  w.Key("referee");
  if (referee.empty()) w.Null(); else w.String(referee.c_str());
  if (replay) {
    w.Key("replay");
    w.StartObject();
    w.Key("file");
    w.String(replay->file.c_str());
    Number(w, "duration", replay->duration);
    w.Key("start_unix");
    w.Double(replay->start_unix);  // full precision: Unix seconds with their fraction
    w.Key("sending");
    w.Bool(replay->sending);
    Number(w, "min_speed", replay->min_speed);
    Number(w, "max_speed", replay->max_speed);
    w.EndObject();
  }
  w.EndObject();
  return buffer.GetString();
}

std::string EncodeState(const WorldSample& s, const std::vector<VisionFrame>& frames,
                        const ViewerStatus& status) {
  rapidjson::StringBuffer buffer;
  Writer w(buffer);
  // 0.1 mm and 0.1 mrad: finer than any screen, and keeps a Div A message near 4 kB.
  w.SetMaxDecimalPlaces(4);
  w.StartObject();
  w.Key("type");
  w.String("state");
  w.Key("step");
  w.Int64(s.step);
  w.Key("t");
  w.Double(static_cast<double>(s.sim_time_ns) * kNs);
  w.Key("step_dt");
  if (s.step > 0) w.Double(static_cast<double>(s.sim_time_ns) / static_cast<double>(s.step) * kNs);
  else w.Null();
  w.Key("ball");
  w.StartObject();
  Number(w, "x", s.ball_position.x());
  Number(w, "y", s.ball_position.y());
  Number(w, "z", s.ball_position.z());
  Number(w, "vx", s.ball_velocity.x());
  Number(w, "vy", s.ball_velocity.y());
  Number(w, "vz", s.ball_velocity.z());
  Number(w, "r", s.ball_radius);
  w.EndObject();
  w.Key("robots");
  w.StartArray();
  for (const RobotSample& r : s.robots) {
    w.StartObject();
    Team(w, r.id);
    Number(w, "x", r.x);
    Number(w, "y", r.y);
    Number(w, "yaw", r.yaw);
    Number(w, "vx", r.vx);
    Number(w, "vy", r.vy);
    Number(w, "w", r.w);
    w.Key("present");
    w.Bool(r.present);
    w.Key("contact");
    w.Bool(r.contact);
    w.Key("kicker_ready");
    w.Bool(r.kicker_ready);
    Number(w, "r", r.radius);
    Number(w, "h", r.height);
    // What the drive measured of itself (Drive::Feedback), or null without a working drive.
    w.Key("drive");
    if (r.has_drive) {
      w.StartObject();
      Number(w, "forward", r.drive_forward);
      Number(w, "left", r.drive_left);
      Number(w, "angular", r.drive_angular);
      w.Key("wheels");
      w.StartArray();
      for (double speed : r.wheel_speeds) w.Double(speed);  // finite: the kernel checks feedback
      w.EndArray();
      w.EndObject();
    } else {
      w.Null();
    }
    w.EndObject();
  }
  w.EndArray();
  w.Key("vision");
  w.StartArray();
  for (const VisionFrame& f : frames) {
    w.StartObject();
    w.Key("camera");
    w.Int(f.camera_id);
    w.Key("frame");
    w.Uint(f.frame_number);
    w.Key("t_capture");
    w.Double(static_cast<double>(f.t_capture_ns) * kNs);
    w.Key("t_sent");
    w.Double(static_cast<double>(f.t_sent_ns) * kNs);
    w.Key("balls");
    w.StartArray();
    for (const DetectedBall& b : f.balls) {
      w.StartObject();
      Number(w, "x", b.x);
      Number(w, "y", b.y);
      Number(w, "z", b.z);
      w.EndObject();
    }
    w.EndArray();
    w.Key("robots");
    w.StartArray();
    for (const DetectedRobot& r : f.robots) {
      w.StartObject();
      Team(w, r.id);
      Number(w, "x", r.x);
      Number(w, "y", r.y);
      Number(w, "yaw", r.yaw);
      w.EndObject();
    }
    w.EndArray();
    w.EndObject();
  }
  w.EndArray();
  w.Key("status");
  w.StartObject();
  Number(w, "rtf", status.real_time_factor);
  Number(w, "vision_hz", status.vision_rate);
  w.Key("cameras");
  w.Int(status.cameras);
  w.Key("clients");
  w.Int(status.clients);
  w.Key("paused");
  w.Bool(status.paused);
  w.Key("speed");
  if (status.speed_factor) w.Double(*status.speed_factor); else w.Null();
  w.Key("referee_age");
  if (status.referee_age) w.Double(*status.referee_age); else w.Null();
  if (status.replay) {
    const ReplayStatus& r = *status.replay;
    w.Key("replay");
    w.StartObject();
    Number(w, "t", r.t);
    Number(w, "duration", r.duration);
    Number(w, "speed", r.speed);
    w.Key("playing");
    w.Bool(r.playing);
    w.EndObject();
  }
  w.EndObject();
  w.EndObject();
  return buffer.GetString();
}

std::string EncodeReply(std::string_view cmd, const std::optional<std::int64_t>& id,
                        const std::string& error) {
  rapidjson::StringBuffer buffer;
  Writer w(buffer);
  w.StartObject();
  w.Key("type");
  w.String(error.empty() ? "ack" : "error");
  w.Key("cmd");
  w.String(cmd.data(), static_cast<rapidjson::SizeType>(cmd.size()));
  if (id) {
    w.Key("id");
    w.Int64(*id);
  }
  if (!error.empty()) {
    w.Key("message");
    w.String(error.c_str());
  }
  w.EndObject();
  return buffer.GetString();
}

namespace {

// A page's command: a JSON object with "cmd" (and "id", echoed back); its parse into `doc`, `id`
// and `cmd`, or why it cannot be read.
std::string ParseCommandEnvelope(std::string_view text, rapidjson::Document& doc, std::optional<std::int64_t>& id,
                                 std::string& cmd) {
  doc.Parse(text.data(), text.size());
  if (doc.HasParseError()) {
    return std::string("not JSON: ") + rapidjson::GetParseError_En(doc.GetParseError()) + " at offset " +
           std::to_string(doc.GetErrorOffset());
  }
  if (!doc.IsObject()) return "a command must be a JSON object";
  id = ReadId(doc);
  auto member = doc.FindMember("cmd");  // not const: rapidjson's == is ambiguous in C++20 then
  if (member == doc.MemberEnd() || !member->value.IsString()) return "'cmd' is missing or not a string";
  cmd = member->value.GetString();
  return "";
}

}  // namespace

DecodedCommand DecodeCommand(std::string_view text, const CommandLimits& limits) {
  DecodedCommand out;
  rapidjson::Document doc;
  out.error = ParseCommandEnvelope(text, doc, out.id, out.cmd);
  if (!out.error.empty()) return out;
  const std::string& name = out.cmd;
  if (name == "pause" || name == "resume" || name == "reset") {
    ClockEvent e;
    e.action = name == "pause"    ? ClockEvent::Action::kPause
               : name == "resume" ? ClockEvent::Action::kResume
                                  : ClockEvent::Action::kReset;
    if (name != "reset") out.paused = name == "pause";
    out.events.emplace_back(e);
  } else if (name == "step") {
    auto it = doc.FindMember("steps");
    int steps = 1;
    if (it != doc.MemberEnd()) {
      if (!it->value.IsInt() || it->value.GetInt() < 1 || it->value.GetInt() > limits.max_steps) {
        out.error = "'steps' must be an integer 1.." + std::to_string(limits.max_steps);
        return out;
      }
      steps = it->value.GetInt();
    }
    ClockEvent e;
    e.action = ClockEvent::Action::kStep;
    e.steps = steps;
    out.paused = true;
    out.events.emplace_back(e);
  } else if (name == "speed") {
    const auto factor = ReadNumber(doc, "factor", true, out.error);
    if (!factor) return out;
    if (*factor < 0 || *factor > limits.max_speed_factor) {
      out.error = "'factor' must be 0 (as fast as possible) to " +
                  std::to_string(limits.max_speed_factor);
      return out;
    }
    ClockEvent e;
    e.action = ClockEvent::Action::kSetSpeed;
    e.speed_factor = *factor;
    out.speed_factor = *factor;
    out.events.emplace_back(e);
  } else if (name == "move") {
    DecodeMove(doc, limits, out);
  } else if (name == "kick") {
    DecodeKick(doc, limits, out);
  } else {
    out.error = "unknown command '" + name + "' (pause, resume, step, speed, reset, move, kick)";
  }
  if (!out.error.empty()) {
    out.events.clear();
    out.speed_factor.reset();
    out.paused.reset();
  }
  return out;
}

ReplayCommand DecodeReplayCommand(std::string_view text, const ReplayInfo& replay) {
  ReplayCommand out;
  rapidjson::Document doc;
  out.error = ParseCommandEnvelope(text, doc, out.id, out.cmd);
  if (!out.error.empty()) return out;
  const std::string& name = out.cmd;
  if (name == "seek") {
    const auto t = ReadNumber(doc, "t", true, out.error);
    if (t) out.seek = std::clamp(*t, 0.0, replay.duration);  // a slider may round past either end
  } else if (name == "play" || name == "resume" || name == "pause") {
    out.playing = name != "pause";
  } else if (name == "speed") {
    const auto factor = ReadNumber(doc, "factor", true, out.error);
    if (factor && (*factor < replay.min_speed || *factor > replay.max_speed)) {
      char range[64];
      std::snprintf(range, sizeof range, "%g to %g", replay.min_speed, replay.max_speed);
      out.error = std::string("'factor' must be ") + range + " (times the recorded rate)";
    } else if (factor) {
      out.speed = factor;
    }
  } else if (name == "move" || name == "kick" || name == "step" || name == "reset") {
    out.error = "'" + name + "' changes a world; a replay shows a log as it was recorded (seek, play, pause, speed)";
  } else {
    out.error = "unknown command '" + name + "' (seek, play, pause, speed)";
  }
  if (!out.error.empty()) {
    out.seek.reset();
    out.playing.reset();
    out.speed.reset();
  }
  return out;
}

}  // namespace ubersim::viewer
