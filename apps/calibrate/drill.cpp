// SPDX-License-Identifier: Apache-2.0
#include "drill.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include "log_session.hpp"
#include "match_session.hpp"
#include "ssl_log.hpp"
#include "ssl_simulation_robot_control.pb.h"

namespace ubersim::calibrate {
namespace {

constexpr double kCommandPeriod = 0.01;  // s: a team's radio sends at 100 Hz

// One part of a robot's drill: drive to a pose, or hold one command for a time.
struct Phase {
  enum class Kind { kGoTo, kHold } kind = Kind::kHold;
  double x = 0, y = 0, yaw = 0;               // kGoTo: the pose, m and rad
  double forward = 0, left = 0, angular = 0;  // kHold: the command, m/s and rad/s
  double duration = 0;                        // kHold: s; kGoTo: at most, s
};

// A robot's lane: the phases it repeats, full speed one round and part speed the next.
std::vector<Phase> Round(double x_start, double y, double speed, double spin, const DrillOptions& o) {
  const auto go = [&](double yaw) { return Phase{Phase::Kind::kGoTo, x_start, y, yaw, 0, 0, 0, 4.0}; };
  const auto hold = [&](double f, double l, double w, double d) { return Phase{Phase::Kind::kHold, 0, 0, 0, f, l, w, d}; };
  const double half_pi = std::numbers::pi / 2;
  return {
      go(0), hold(0, 0, 0, 0.5),
      // Along the heading: out and back.
      hold(speed, 0, 0, o.hold), hold(0, 0, 0, o.rest), hold(-speed, 0, 0, o.hold), hold(0, 0, 0, o.rest),
      // Across it: turned a quarter, so the lane's length is in front of its side.
      go(half_pi), hold(0, 0, 0, 0.3),
      hold(0, -speed, 0, o.hold), hold(0, 0, 0, o.rest), hold(0, speed, 0, o.hold), hold(0, 0, 0, o.rest),
      // About it.
      go(0), hold(0, 0, 0, 0.3),
      hold(0, 0, spin, 0.8 * o.hold), hold(0, 0, 0, o.rest), hold(0, 0, -spin, 0.8 * o.hold), hold(0, 0, 0, o.rest),
  };
}

struct RobotDrill {
  int id = 0;
  double lane_y = 0;
  std::vector<Phase> phases;
  std::size_t phase = 0;
  double phase_start = 0;
  int round = 0;
};

// The command toward a pose: proportional, capped, in the robot's frame.
LocalVelocityCommand Toward(const RobotState& r, const Phase& p) {
  const double dx = p.x - r.pose.position.x(), dy = p.y - r.pose.position.y();
  const double yaw = r.pose.Yaw();
  double vx = 2.5 * dx, vy = 2.5 * dy;
  const double speed = std::hypot(vx, vy);
  if (speed > 1.5) vx *= 1.5 / speed, vy *= 1.5 / speed;
  double turn = std::remainder(p.yaw - yaw, 2 * std::numbers::pi);
  const double c = std::cos(yaw), s = std::sin(yaw);
  return {c * vx + s * vy, -s * vx + c * vy, std::clamp(4.0 * turn, -4.0, 4.0)};
}

bool Arrived(const RobotState& r, const Phase& p) {
  return std::hypot(p.x - r.pose.position.x(), p.y - r.pose.position.y()) < 0.03 &&
         std::abs(std::remainder(p.yaw - r.pose.Yaw(), 2 * std::numbers::pi)) < 0.04 && r.twist.linear.norm() < 0.05;
}

// The ball's part: kicked along its own half of the field, flat or chipped, again and again, by a
// kicker robot put behind it as a team's robot would line up (the fit must see a real kick: the
// ball leaving a robot), or launched by a teleport when the world has no robot to spare.
class BallDrill {
 public:
  BallDrill(const DrillOptions& o, double length, double width, std::optional<RobotId> kicker)
      : options_(o), rng_(o.seed ^ 0x6b69636bULL), kicker_(kicker), x_end_(0.5 * length - 0.5), y_low_(0.45),
        y_high_(0.5 * width - 0.2) {}

  // What to post before the next step: the next launch when it is due, the kick while it is armed.
  std::vector<Event> Next(double t, const BallState& ball, DrillSummary& summary) {
    std::vector<Event> out;
    const double speed = ball.twist.linear.norm();
    if (kick_ && (speed > 0.3 || t - staged_ > 0.4)) kick_.reset();  // kicked (or given up: next launch)
    if (kick_) {
      out.push_back(*kick_);  // refreshed each step until the ball leaves, as a radio repeats it
      return out;
    }
    const Vec3& p = ball.pose.position;
    const bool stopped = speed < 0.05 && t - staged_ > 0.8;
    const bool away = p.y() < y_low_ - 0.15 || std::abs(p.x()) > x_end_ + 0.3;
    if (staged_ >= 0 && !stopped && !(away && t - staged_ > 0.8) && t - staged_ < 8.0) return out;
    staged_ = t;
    ++kicks_;
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const bool chip = options_.chips && kicks_ % 4 == 0;
    const double direction = (kicks_ % 2 == 0) ? 1.0 : -1.0;  // from either end, toward the other
    const double y = y_low_ + 0.2 + unit(rng_) * (y_high_ - y_low_ - 0.4);
    const double angle = (direction > 0 ? 0.0 : std::numbers::pi) + (unit(rng_) - 0.5) * 0.3;  // ±8.6°
    const double v = chip ? 2.5 + 2.0 * unit(rng_) : 1.5 + 4.5 * unit(rng_);
    const double elevation = chip ? std::numbers::pi / 4 : 0.0;
    const Vec3 start(-direction * x_end_, y, 0.0);
    const Vec3 heading(std::cos(angle), std::sin(angle), 0.0);
    (chip ? summary.chips : summary.kicks) += 1;
    PositionEvent b;
    b.target.is_ball = true;
    b.position = start;
    b.angular_velocity = Vec3::Zero();
    if (!kicker_) {
      b.velocity = v * std::cos(elevation) * heading + Vec3(0, 0, v * std::sin(elevation));
      out.push_back(b);
      return out;
    }
    // The kicker stands behind the ball, its face 2 mm from it (0.07 m front, 0.0215 m ball).
    b.velocity = Vec3::Zero();
    PositionEvent r;
    r.target.is_ball = false;
    r.target.robot = *kicker_;
    r.present = true;
    r.position = start - 0.0935 * heading;
    r.yaw = angle;
    r.velocity = Vec3::Zero();
    r.angular_velocity = Vec3::Zero();
    out.push_back(r);
    out.push_back(b);
    CommandEvent k;
    k.robot = *kicker_;
    k.move = LocalVelocityCommand{0, 0, 0};
    k.kick = KickCommand{v, elevation};
    kick_ = k;
    return out;
  }

 private:
  DrillOptions options_;
  std::mt19937_64 rng_;
  std::optional<RobotId> kicker_;
  double x_end_, y_low_, y_high_;
  double staged_ = -1;
  int kicks_ = 0;
  std::optional<CommandEvent> kick_;
};

}  // namespace

DrillSummary RunDrill(kernel::World& world, const std::string& log_path, const DrillOptions& options, Log& log) {
  DrillSummary summary;
  const WorldSnapshot start = world.GroundTruth();
  if (!start.field) throw std::runtime_error("the drill's world has no field");
  const double length = start.field->field_length, width = start.field->field_width;
  const double lane_span = 0.5 * width - 0.55;
  const double lane_start = -0.5 * length + 0.9;  // m: where every lane begins, 0.9 m in from the goal line
  if (options.robots < 0 || options.robots > 16 ||
      (options.robots > 1 && lane_span / (options.robots - 1) < 0.3)) {
    throw std::runtime_error("the drill's " + std::to_string(options.robots) +
                             " robots do not fit in lanes 0.3 m apart on this field's half width");
  }
  std::vector<RobotDrill> robots;
  for (int k = 0; k < options.robots; ++k) {
    const bool there = std::any_of(start.robots.begin(), start.robots.end(), [&](const RobotState& r) {
      return r.id.team == Team::kBlue && r.id.id == k;
    });
    if (!there) throw std::runtime_error("the drill drives blue robots 0.." + std::to_string(options.robots - 1) +
                                         "; the world has no blue " + std::to_string(k));
    RobotDrill d;
    d.id = k;
    d.lane_y = -0.4 - (options.robots > 1 ? lane_span * k / (options.robots - 1) : 0.0);
    d.phases = Round(lane_start, d.lane_y, options.top_speed_command, options.spin_command, options);
    robots.push_back(std::move(d));
  }
  // Everyone else leaves the field; the drill's robots start in their lanes.
  for (const RobotState& r : start.robots) {
    PositionEvent e;
    e.target.is_ball = false;
    e.target.robot = r.id;
    const auto mine = std::find_if(robots.begin(), robots.end(), [&](const RobotDrill& d) {
      return r.id.team == Team::kBlue && r.id.id == d.id;
    });
    if (mine == robots.end()) {
      // The kicker waits off the field until the first kick puts it behind the ball.
      e.present = false;
    } else {
      e.position = Vec3(lane_start, mine->lane_y, 0.0);
      e.yaw = 0.0;
    }
    world.events().Post(e);
  }

  sslog::LogWriter writer(log_path);
  // One clock for the vision and the commands: a team's software on the recorder's machine.
  const std::int64_t offset_ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count() -
      world.clock().time_ns();
  match::MatchOptions session_options;
  session_options.network = false;
  session_options.unix_offset_ns = offset_ns;
  session_options.recorder = [&](std::int64_t unix_ns, match::WireMessage type, const std::string& bytes) {
    writer.Write(unix_ns, static_cast<std::int32_t>(type), bytes);
  };
  // The session records the vision (and the geometry every 3 s) as the vision transport sends it.
  match::MatchSession session(world, session_options, log);

  std::optional<RobotId> kicker;
  for (const RobotState& r : start.robots) {
    if (r.id.team == Team::kYellow && !kicker) kicker = r.id;
  }
  BallDrill ball(options, length, width, kicker);
  double next_command = 0;
  const double t_end = world.clock().seconds() + options.duration;
  while (world.clock().seconds() < t_end && !world.stopped()) {
    const double t = world.clock().seconds();
    const WorldSnapshot truth = world.GroundTruth();
    if (options.kicks) {
      for (Event& e : ball.Next(t, truth.ball, summary)) world.events().Post(std::move(e));
    }
    if (t + 1e-9 >= next_command) {
      next_command += kCommandPeriod;
      RobotControl control;
      for (RobotDrill& d : robots) {
        const auto it = std::find_if(truth.robots.begin(), truth.robots.end(), [&](const RobotState& r) {
          return r.id.team == Team::kBlue && r.id.id == d.id;
        });
        if (it == truth.robots.end()) continue;
        const Phase* p = &d.phases[d.phase];
        const bool done = p->kind == Phase::Kind::kGoTo ? (Arrived(*it, *p) || t - d.phase_start > p->duration)
                                                        : t - d.phase_start >= p->duration - 1e-9;
        if (done) {
          d.phase = (d.phase + 1) % d.phases.size();
          d.phase_start = t;
          if (d.phase == 0) {
            // The next round at the other speed.
            ++d.round;
            const bool part = d.round % 2 == 1;
            d.phases = Round(lane_start, d.lane_y, part ? options.part_speed_command : options.top_speed_command,
                             part ? 0.45 * options.spin_command : options.spin_command, options);
          }
          p = &d.phases[d.phase];
          if (p->kind == Phase::Kind::kHold && (p->forward != 0 || p->left != 0 || p->angular != 0)) ++summary.steps;
        }
        const LocalVelocityCommand command =
            p->kind == Phase::Kind::kGoTo ? Toward(*it, *p) : LocalVelocityCommand{p->forward, p->left, p->angular};
        CommandEvent c;
        c.robot = {Team::kBlue, d.id};
        c.move = command;
        world.events().Post(c);
        RobotCommand* rc = control.add_robot_commands();
        rc->set_id(static_cast<std::uint32_t>(d.id));
        auto* local = rc->mutable_move_command()->mutable_local_velocity();
        local->set_forward(static_cast<float>(command.forward));
        local->set_left(static_cast<float>(command.left));
        local->set_angular(static_cast<float>(command.angular));
      }
      if (options.commands && control.robot_commands_size() > 0) {
        writer.Write(offset_ns + world.clock().time_ns(), kRobotControlBlueRecord, control.SerializeAsString());
      }
    }
    world.Step();
    session.AfterStep();
  }
  writer.Close();
  summary.records = writer.Records();
  return summary;
}

}  // namespace ubersim::calibrate
