// SPDX-License-Identifier: Apache-2.0
#include "grsim_translator.hpp"

#include <algorithm>
#include <cmath>

#include "transport_common/wire_units.hpp"

namespace ubersim::grsim {
namespace {

constexpr double kMinKickSpeed = 1e-4;  // m/s; grSim's threshold for "kick"
constexpr double kChipAngle = 1e-3;     // rad; steeper counts as a chip in the status

std::pair<int, int> Key(const RobotId& id) { return {id.team == Team::kBlue ? 0 : 1, id.id}; }

bool Finite(std::initializer_list<double> values) {
  return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

// Empty when the robot may be commanded; otherwise why not.
std::string CheckRobot(const RobotId& id, const WorldView& world) {
  if (!world.known) return {};
  if (std::find(world.robots.begin(), world.robots.end(), id) != world.robots.end()) return {};
  const RobotId other{id.team == Team::kBlue ? Team::kYellow : Team::kBlue, id.id};
  const bool other_team = std::find(world.robots.begin(), world.robots.end(), other) != world.robots.end();
  return "no " + ToString(id) + " in this world" + (other_team ? " (wrong team? there is a " + ToString(other) + ")" : "");
}

std::string CheckOnCarpet(double x, double y, const WorldView& world) {
  if (world.half_length <= 0 || world.half_width <= 0) return {};
  if (std::abs(x) <= world.half_length && std::abs(y) <= world.half_width) return {};
  return "position (" + std::to_string(x) + ", " + std::to_string(y) + ") m is off the carpet";
}

}  // namespace


void Translator::Translate(const grSim_Packet& packet, const WorldView& world, std::vector<Event>& events,
                           std::vector<std::string>& rejects) {
  if (packet.has_commands()) {
    const Team team = packet.commands().isteamyellow() ? Team::kYellow : Team::kBlue;
    for (const grSim_Robot_Command& c : packet.commands().robot_commands()) Command(c, team, world, events, rejects);
  }
  if (packet.has_replacement()) {
    if (packet.replacement().has_ball()) Ball(packet.replacement().ball(), world, events, rejects);
    for (const grSim_RobotReplacement& r : packet.replacement().robots()) Robot(r, world, events, rejects);
  }
}

void Translator::Command(const grSim_Robot_Command& c, Team team, const WorldView& world,
                         std::vector<Event>& events, std::vector<std::string>& rejects) {
  const RobotId id{team, static_cast<int>(std::min<std::uint32_t>(c.id(), 1000000))};
  const std::string where = "command for " + ToString(id) + ": ";
  if (std::string why = CheckRobot(id, world); !why.empty()) {
    rejects.push_back(where + why);
    return;
  }
  if (!Finite({c.kickspeedx(), c.kickspeedz(), c.veltangent(), c.velnormal(), c.velangular(),
               c.wheel1(), c.wheel2(), c.wheel3(), c.wheel4()})) {
    rejects.push_back(where + "a value is NaN or infinite");
    return;
  }
  if (c.kickspeedx() < 0 || c.kickspeedz() < 0) {
    rejects.push_back(where + "negative kick speed");
    return;
  }
  CommandEvent e;
  e.robot = id;
  if (c.wheelsspeed()) {
    // wheel1.. in the drive's wheel order, as many as given from wheel1 on (2, 3 or 4 wheels).
    WheelSpeedCommand w;
    const bool has[] = {c.has_wheel1(), c.has_wheel2(), c.has_wheel3(), c.has_wheel4()};
    const double speed[] = {c.wheel1(), c.wheel2(), c.wheel3(), c.wheel4()};
    for (int i = 0; i < 4 && has[i]; ++i) w.wheel_speeds.push_back(speed[i]);
    if (w.wheel_speeds.empty()) {
      rejects.push_back(where + "wheelsspeed is set but wheel1 is missing");
      return;
    }
    e.move = w;
  } else {
    e.move = LocalVelocityCommand{c.veltangent(), c.velnormal(), c.velangular()};
  }
  if (c.kickspeedx() > kMinKickSpeed || c.kickspeedz() > kMinKickSpeed) {
    const double x = c.kickspeedx(), z = c.kickspeedz();  // in double: the float overloads lose digits
    const KickCommand kick{std::hypot(x, z), std::atan2(z, x)};
    e.kick = kick;
    kick_angle_[Key(id)] = kick.angle;
  }
  // Only a change reaches the dribbler: robots without one are not told "off" 60 times a second.
  bool& spinning = spinner_[Key(id)];
  if (c.spinner() != spinning) {
    spinning = c.spinner();
    e.dribbler_speed = spinning ? spinner_speed_ : 0.0;
  }
  events.emplace_back(std::move(e));
}

void Translator::Ball(const grSim_BallReplacement& b, const WorldView& world, std::vector<Event>& events,
                      std::vector<std::string>& rejects) {
  if (!Finite({b.x(), b.y(), b.vx(), b.vy()})) {
    rejects.push_back("ball replacement: a value is NaN or infinite");
    return;
  }
  // Unset fields keep their current values (grSim's rule).
  PositionEvent e;
  e.target = Target::Ball();
  if (b.has_x() || b.has_y()) {
    const double x = b.has_x() ? b.x() : world.ball_position.x();
    const double y = b.has_y() ? b.y() : world.ball_position.y();
    if (std::string why = CheckOnCarpet(x, y, world); !why.empty()) {
      rejects.push_back("ball replacement: " + why);
      return;
    }
    e.position = Vec3(x, y, world.ball_radius);  // resting on the carpet
    e.angular_velocity = Vec3::Zero();           // no spin, as grSim places it
    e.velocity = world.ball_velocity;            // kept unless vx/vy say otherwise
  }
  if (b.has_vx() || b.has_vy()) {
    e.velocity = Vec3(b.has_vx() ? b.vx() : world.ball_velocity.x(), b.has_vy() ? b.vy() : world.ball_velocity.y(), 0.0);
  }
  if (e.position || e.velocity) events.emplace_back(std::move(e));
}

void Translator::Robot(const grSim_RobotReplacement& r, const WorldView& world, std::vector<Event>& events,
                       std::vector<std::string>& rejects) {
  const RobotId id{r.yellowteam() ? Team::kYellow : Team::kBlue, static_cast<int>(std::min<std::uint32_t>(r.id(), 1000000))};
  const std::string where = "replacement of " + ToString(id) + ": ";
  if (id.id > 15) {
    rejects.push_back(where + "robot ids are 0..15");
    return;
  }
  // As on grSim, every id 0..15 has a robot: one not in the world comes on (turnon, grSim's
  // default, true), and turning off one that is not there does nothing.
  const bool on = r.has_turnon() ? r.turnon() : true;
  if (!on && !CheckRobot(id, world).empty()) return;
  if (!Finite({r.x(), r.y(), r.dir()})) {
    rejects.push_back(where + "a value is NaN or infinite");
    return;
  }
  if (std::string why = CheckOnCarpet(r.x(), r.y(), world); !why.empty()) {
    rejects.push_back(where + why);
    return;
  }
  PositionEvent e;
  e.target = Target::Robot(id);
  e.position = Vec3(r.x(), r.y(), 0.0);
  e.yaw = transport::DegToRad(r.dir());    // grSim sends degrees
  e.present = on;
  events.emplace_back(std::move(e));
}

double Translator::LastKickAngle(const RobotId& robot) const {
  const auto it = kick_angle_.find(Key(robot));
  return it == kick_angle_.end() ? 0.0 : it->second;
}

void StatusTracker::Observe(const std::vector<RobotState>& robots, const Translator& translator) {
  for (const RobotState& r : robots) {
    auto it = std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.id == r.id; });
    if (it == entries_.end()) {
      entries_.push_back(Entry{r.id});
      it = std::prev(entries_.end());
      it->kicker_ready = r.kicker_ready;
    }
    if (it->kicker_ready && !r.kicker_ready) {
      (translator.LastKickAngle(r.id) > kChipAngle ? it->chip_pending : it->flat_pending) = true;
    }
    it->kicker_ready = r.kicker_ready;
    it->infrared = r.dribbler_ball_contact;
  }
}

std::pair<Robots_Status, Robots_Status> StatusTracker::TakeChanged() {
  std::pair<Robots_Status, Robots_Status> out;
  for (Entry& e : entries_) {
    const bool changed = !e.reported || e.infrared != e.last_infrared || e.flat_pending != e.last_flat ||
                         e.chip_pending != e.last_chip;
    if (!changed) continue;
    Robot_Status* s = (e.id.team == Team::kBlue ? out.first : out.second).add_robots_status();
    s->set_robot_id(e.id.id);
    s->set_infrared(e.infrared);
    s->set_flat_kick(e.flat_pending);
    s->set_chip_kick(e.chip_pending);
    e.reported = true;
    e.last_infrared = e.infrared;
    e.last_flat = e.flat_pending;
    e.last_chip = e.chip_pending;
    e.flat_pending = e.chip_pending = false;  // a kick is reported once
  }
  return out;
}

}  // namespace ubersim::grsim
