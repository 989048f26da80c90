// SPDX-License-Identifier: Apache-2.0
#include "shared/random_play.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "ubersim/kernel/field.hpp"

namespace ubersim::apps {

using kernel::RobotPlacement;

namespace {

constexpr std::int64_t kRadioPeriodNs = 10'000'000;   // 100 Hz, as teams send
constexpr std::int64_t kBallCheckNs = 1'500'000'000;  // keep the ball in play this often
constexpr double kMaxSpeed = 3.0;                     // m/s
constexpr double kBallSpeed = 6.5;                    // m/s, the rules' limit

}  // namespace

RandomPlay::RandomPlay(World& world, std::uint64_t seed, std::optional<Team> team) : world_(world), rng_(seed) {
  const FieldGeometry& f = world.model().field->geometry;
  half_length_ = 0.5 * f.field_length;
  half_width_ = 0.5 * f.field_width;
  const std::vector<RobotState> robots = world.Kinematics().robots;
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const RobotState& r = robots[i];
    if (team && r.id.team != *team) continue;
    Player p;
    p.id = r.id;
    p.index = i;
    for (const RobotPlacement& placed : world.model().robots) {
      if (placed.id == r.id) {
        p.dribbler = placed.model->dribbler.has_value();
        p.kicker = placed.model->kicker.has_value();
      }
    }
    NewTarget(p, 0);
    players_.push_back(p);
  }
}

void RandomPlay::NewTarget(Player& p, std::int64_t now_ns) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> speed(0.5, kMaxSpeed);
  std::uniform_int_distribution<std::int64_t> hold(500'000'000, 2'000'000'000);
  p.target_x = unit(rng_) * (half_length_ - 0.2);
  p.target_y = unit(rng_) * (half_width_ - 0.2);
  p.speed = speed(rng_);
  p.turn = unit(rng_) * 4.0;
  p.next_target_ns = now_ns + hold(rng_);
}

bool RandomPlay::BeforeStep() {
  const std::int64_t now = world_.clock().time_ns();
  if (now < next_radio_ns_ && now < next_ball_ns_) return false;
  bool ball_moved = false;
  // Poses only: the parts' reports (drive feedback above all) would be most of this play's cost.
  const WorldSnapshot s = world_.Kinematics();
  if (now >= next_radio_ns_) {
    next_radio_ns_ = now + kRadioPeriodNs;
    std::bernoulli_distribution kick(0.02);
    for (Player& p : players_) {
      if (p.index >= s.robots.size()) continue;
      if (now >= p.next_target_ns) NewTarget(p, now);
      const Vec3 at = s.robots[p.index].pose.position;
      const Vec3 to(p.target_x - at.x(), p.target_y - at.y(), 0.0);
      const double distance = to.norm();
      // Slow down over the last half metre, as a path controller would.
      const double v = distance > 1e-6 ? std::min(p.speed, 2.0 * distance) / distance : 0.0;
      CommandEvent c;
      c.robot = p.id;
      c.move = GlobalVelocityCommand{to.x() * v, to.y() * v, p.turn};
      if (p.dribbler) c.dribbler_speed = 100.0;
      if (p.kicker && kick(rng_)) c.kick = KickCommand{4.0, 0.0};
      world_.events().Post(std::move(c));
    }
  }
  if (now >= next_ball_ns_) {
    next_ball_ns_ = now + kBallCheckNs;
    const Vec3 ball = s.ball.pose.position;
    const bool outside = std::abs(ball.x()) > half_length_ || std::abs(ball.y()) > half_width_;
    if (outside || s.ball.twist.linear.norm() < 0.5) {
      std::uniform_real_distribution<double> unit(-1.0, 1.0);
      std::uniform_real_distribution<double> angle(-M_PI, M_PI);
      PositionEvent e;
      e.target = Target::Ball();
      if (outside) e.position = FreeBallPoint(s);
      const double a = angle(rng_);
      e.velocity = Vec3(kBallSpeed * std::cos(a), kBallSpeed * std::sin(a), 0.0);
      world_.events().Post(e);
      ball_moved = true;
    }
  }
  return ball_moved;
}

Vec3 RandomPlay::FreeBallPoint(const WorldSnapshot& s) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double ball_radius = world_.model().ball->radius;
  Vec3 p = Vec3::Zero();
  for (int attempt = 0; attempt < 100; ++attempt) {
    // One draw a statement: the order of a call's arguments is the compiler's, and a seed must
    // give one play whatever built it (clang's sanitizer build played div-b otherwise). y first,
    // as gcc evaluated the old one-call form: the runs recorded with it stay as they were.
    const double y = unit(rng_) * half_width_ * 0.8;
    const double x = unit(rng_) * half_length_ * 0.8;
    p = Vec3(x, y, 0.0);
    const bool clear = std::none_of(s.robots.begin(), s.robots.end(), [&](const RobotState& r) {
      return (r.pose.position - p).head<2>().norm() < r.radius + ball_radius + 0.05;
    });
    if (clear) return p;
  }
  return p;  // a field full of robots: the last try
}

}  // namespace ubersim::apps
