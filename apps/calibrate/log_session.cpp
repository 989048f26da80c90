// SPDX-License-Identifier: Apache-2.0
#include "log_session.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "ssl_log.hpp"
#include "ssl_simulation_robot_control.pb.h"
#include "ssl_vision_wrapper.pb.h"

namespace ubersim::calibrate {
namespace {

constexpr double kMm = 1e-3;  // the wire's millimetres

std::string Place(const sslog::LogReader& reader) {
  std::ostringstream o;
  o << reader.Path() << ": record " << reader.Records() << " at byte " << reader.RecordOffset();
  return o.str();
}

// A frame as read, before the session's clock zero is known: absolute times in ns.
struct RawFrame {
  CameraFrame frame;
  std::int64_t capture_ns = 0, sent_ns = 0, received_ns = 0;
};

struct RawCommand {
  RobotKey robot;
  std::int64_t sent_ns = 0;
  CommandSample sample;
  bool global = false;
};

std::int64_t Nanoseconds(double seconds) { return std::llround(seconds * 1e9); }

void ReadDetection(const SSL_DetectionFrame& d, std::int64_t received_ns, std::int64_t record,
                   std::vector<RawFrame>& out) {
  RawFrame raw;
  CameraFrame& f = raw.frame;
  f.camera_id = static_cast<int>(d.camera_id());
  f.frame_number = d.frame_number();
  f.record = record;
  raw.capture_ns = Nanoseconds(d.t_capture());
  raw.sent_ns = Nanoseconds(d.t_sent());
  raw.received_ns = received_ns;
  for (const auto& b : d.balls()) {
    f.balls.push_back({b.x() * kMm, b.y() * kMm, static_cast<double>(b.area()), b.confidence()});
  }
  auto robots = [&](const auto& list, TeamColour team) {
    for (const auto& r : list) {
      if (!r.has_robot_id()) continue;  // a pattern ssl-vision could not identify
      RobotDetection det;
      det.robot = {team, static_cast<int>(r.robot_id())};
      det.x = r.x() * kMm;
      det.y = r.y() * kMm;
      det.yaw = r.has_orientation() ? r.orientation() : std::numeric_limits<double>::quiet_NaN();
      det.confidence = r.confidence();
      f.robots.push_back(det);
    }
  };
  robots(d.robots_blue(), TeamColour::kBlue);
  robots(d.robots_yellow(), TeamColour::kYellow);
  out.push_back(std::move(raw));
}

void ReadGeometry(const SSL_GeometryData& g, LogSession& session) {
  for (const auto& c : g.calib()) {
    if (c.has_derived_camera_world_tx() && c.has_derived_camera_world_ty() && c.has_derived_camera_world_tz()) {
      session.cameras[static_cast<int>(c.camera_id())] = Eigen::Vector3d(
          c.derived_camera_world_tx() * kMm, c.derived_camera_world_ty() * kMm, c.derived_camera_world_tz() * kMm);
    }
  }
  if (g.has_field()) {
    session.field = FieldSize{g.field().field_length() * kMm, g.field().field_width() * kMm};
  }
}

void ReadCommands(const RobotControl& control, TeamColour team, std::int64_t sent_ns, std::vector<RawCommand>& out) {
  constexpr double kRpmToRadPerSecond = 2 * 3.14159265358979323846 / 60;
  for (const auto& c : control.robot_commands()) {
    RawCommand raw;
    raw.robot = {team, static_cast<int>(c.id())};
    raw.sent_ns = sent_ns;
    CommandSample& s = raw.sample;
    if (c.has_move_command()) {
      const auto& m = c.move_command();
      if (m.has_local_velocity()) {
        s.forward = m.local_velocity().forward();
        s.left = m.local_velocity().left();
        s.angular = m.local_velocity().angular();
      } else if (m.has_global_velocity()) {
        s.forward = m.global_velocity().x();
        s.left = m.global_velocity().y();
        s.angular = m.global_velocity().angular();
        raw.global = true;
      } else {
        continue;  // wheel speeds: the drive's own affair, not a velocity to fit against
      }
    }
    s.kick_speed = c.kick_speed();
    s.kick_angle = c.kick_angle() * 3.14159265358979323846 / 180;
    s.dribbler_speed = c.dribbler_speed() * kRpmToRadPerSecond;
    out.push_back(raw);
  }
}

void ReadFile(const std::string& path, LogSession& session, std::vector<RawFrame>& frames,
              std::vector<RawCommand>& commands) {
  sslog::LogReader reader(path);
  std::int64_t vision_records = 0;
  std::int64_t undecodable = 0;
  SSL_WrapperPacket packet;
  RobotControl control;
  while (auto record = reader.Next()) {
    ++session.counts.records;
    const auto bad = [&] {
      ++undecodable;
      if (session.counts.first_undecodable.empty()) session.counts.first_undecodable = Place(reader);
    };
    if (record->type == static_cast<std::int32_t>(sslog::MessageType::kVision2014)) {
      ++vision_records;
      if (!packet.ParseFromString(record->payload)) {
        bad();
        continue;
      }
      if (packet.has_detection()) ReadDetection(packet.detection(), record->timestamp_ns, reader.Records(), frames);
      if (packet.has_geometry()) {
        ++session.counts.geometry_packets;
        ReadGeometry(packet.geometry(), session);
      }
    } else if (record->type == kRobotControlBlueRecord || record->type == kRobotControlYellowRecord) {
      ++session.counts.command_records;
      if (!control.ParseFromString(record->payload)) {
        bad();
        continue;
      }
      ReadCommands(control, record->type == kRobotControlBlueRecord ? TeamColour::kBlue : TeamColour::kYellow,
                   record->timestamp_ns, commands);
    } else {
      ++session.counts.other_records;
    }
  }
  session.counts.undecodable += undecodable;
  if (vision_records > 0 && undecodable * 10 > vision_records) {
    std::ostringstream o;
    o << session.counts.first_undecodable << ": " << undecodable << " of " << vision_records
      << " vision records do not parse as SSL_WrapperPacket: not a vision log, or a damaged one";
    throw std::runtime_error(o.str());
  }
}

}  // namespace

double LogSession::duration() const { return frames.empty() ? 0.0 : frames.back().t_capture - frames.front().t_capture; }

LogSession ReadLogSession(const std::vector<std::string>& paths) {
  LogSession session;
  session.paths = paths;
  std::vector<RawFrame> raw;
  std::vector<RawCommand> commands;
  for (const auto& path : paths) ReadFile(path, session, raw, commands);
  if (raw.empty()) {
    std::string names;
    for (const auto& p : paths) names += (names.empty() ? "" : ", ") + p;
    throw std::runtime_error(names + ": no vision detection frame (record type 4, SSL_VISION_2014): nothing to fit");
  }
  std::stable_sort(raw.begin(), raw.end(), [](const RawFrame& a, const RawFrame& b) { return a.capture_ns < b.capture_ns; });
  session.t0_ns = raw.front().capture_ns;
  const auto seconds = [&](std::int64_t ns) { return static_cast<double>(ns - session.t0_ns) * 1e-9; };
  // A recorder listening on two interfaces records each datagram twice: one frame per camera,
  // frame number and capture time.
  std::set<std::tuple<int, std::int64_t, std::int64_t>> seen;
  session.frames.reserve(raw.size());
  for (auto& r : raw) {
    if (!seen.emplace(r.frame.camera_id, r.frame.frame_number, r.capture_ns).second) {
      ++session.counts.duplicate_frames;
      continue;
    }
    r.frame.t_capture = seconds(r.capture_ns);
    r.frame.t_sent = seconds(r.sent_ns);
    r.frame.t_received = seconds(r.received_ns);
    session.frames.push_back(std::move(r.frame));
  }
  session.counts.detection_frames = static_cast<std::int64_t>(session.frames.size());
  std::stable_sort(commands.begin(), commands.end(),
                   [](const RawCommand& a, const RawCommand& b) { return a.sent_ns < b.sent_ns; });
  for (auto& c : commands) {
    c.sample.t = seconds(c.sent_ns);
    session.commands[c.robot].push_back(c.sample);
    session.command_is_global[c.robot].push_back(c.global);
  }
  return session;
}

}  // namespace ubersim::calibrate
