// SPDX-License-Identifier: Apache-2.0
#include "scripted_team.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ubersim::python {

namespace {

constexpr double kGain = 3.0;         // 1/s: speed per metre of error
constexpr double kTurnGain = 4.0;     // 1/s: turn rate per radian of heading error
constexpr double kMaxSpeed = 2.0;     // m/s: a cautious baseline
constexpr double kMaxTurn = 4.0;      // rad/s
constexpr double kShotSpeed = 5.0;    // m/s
constexpr double kBehindBall = 0.15;  // m behind the ball, on the line to the goal

double Wrap(double a) { return std::remainder(a, 2.0 * M_PI); }

// A field-frame velocity towards (x, y), slowing down over the last third of a metre, turning to `yaw`.
CommandEvent GoTo(const RobotState& r, double x, double y, double yaw) {
  const double dx = x - r.pose.position.x(), dy = y - r.pose.position.y();
  const double distance = std::hypot(dx, dy);
  const double speed = std::min(kMaxSpeed, kGain * distance);
  const double scale = distance > 1e-6 ? speed / distance : 0.0;
  const double turn = std::clamp(kTurnGain * Wrap(yaw - r.pose.Yaw()), -kMaxTurn, kMaxTurn);
  CommandEvent c;
  c.robot = r.id;
  c.move = GlobalVelocityCommand{dx * scale, dy * scale, turn};
  return c;
}

}  // namespace

ScriptedTeam::ScriptedTeam(Team team, double attack_sign) : team_(team), attack_sign_(attack_sign) {}

void ScriptedTeam::Command(kernel::World& world, const WorldSnapshot& now) const {
  const FieldGeometry& f = *now.field;
  const Vec3 ball = now.ball.pose.position;
  const double goal_x = attack_sign_ * 0.5 * f.field_length;
  const RobotState* keeper = nullptr;
  const RobotState* striker = nullptr;
  double nearest = std::numeric_limits<double>::infinity();
  for (const RobotState& r : now.robots) {
    if (r.id.team != team_ || !r.present) continue;
    if (!keeper || r.id.id < keeper->id.id) keeper = &r;
  }
  for (const RobotState& r : now.robots) {
    if (r.id.team != team_ || !r.present || &r == keeper) continue;
    const double d = (r.pose.position - ball).head<2>().norm();
    if (d < nearest) nearest = d, striker = &r;
  }
  if (!striker) striker = keeper;  // a team of one plays forward
  for (const RobotState& r : now.robots) {
    if (r.id.team != team_ || !r.present) continue;
    if (&r == striker) {
      // Behind the ball on the line from the goal's centre through the ball, facing the goal.
      const double aim = std::atan2(-ball.y(), goal_x - ball.x());
      const double bx = ball.x() - kBehindBall * std::cos(aim), by = ball.y() - kBehindBall * std::sin(aim);
      const bool lined_up = std::hypot(r.pose.position.x() - bx, r.pose.position.y() - by) < 0.08 &&
                            std::abs(Wrap(aim - r.pose.Yaw())) < 0.2;
      CommandEvent c = r.dribbler_ball_contact || lined_up ? GoTo(r, ball.x(), ball.y(), aim) : GoTo(r, bx, by, aim);
      c.dribbler_speed = 100.0;
      if (r.dribbler_ball_contact && std::abs(Wrap(aim - r.pose.Yaw())) < 0.15) c.kick = KickCommand{kShotSpeed, 0.0};
      world.events().Post(std::move(c));
    } else if (&r == keeper) {
      // On the own goal line, at the ball's y within the goal.
      const double x = -attack_sign_ * (0.5 * f.field_length - 0.15);
      const double y = std::clamp(ball.y(), -0.5 * f.goal_width, 0.5 * f.goal_width);
      world.events().Post(GoTo(r, x, y, attack_sign_ > 0 ? 0.0 : M_PI));
    } else {
      CommandEvent c;  // stand, so that the radio keeps a command for them
      c.robot = r.id;
      c.move = LocalVelocityCommand{0, 0, 0};
      world.events().Post(std::move(c));
    }
  }
}

}  // namespace ubersim::python
