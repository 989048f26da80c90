// SPDX-License-Identifier: Apache-2.0
#include "field_view.hpp"

namespace ubersim::match {

FieldView ViewOf(const WorldSnapshot& truth) {
  FieldView v;
  v.t_ns = truth.sim_time_ns;
  const Vec3& b = truth.ball.pose.position;
  v.ball = {b.x(), b.y()};
  v.ball_z = b.z();
  v.ball_vel = {truth.ball.twist.linear.x(), truth.ball.twist.linear.y()};
  v.ball_vz = truth.ball.twist.linear.z();
  v.ball_radius = truth.ball.radius;
  v.robots.reserve(truth.robots.size());
  for (const RobotState& r : truth.robots) {
    RobotView rv;
    rv.id = r.id;
    rv.present = r.present;
    rv.pos = {r.pose.position.x(), r.pose.position.y()};
    rv.vel = {r.twist.linear.x(), r.twist.linear.y()};
    rv.radius = r.radius;
    v.robots.push_back(rv);
  }
  return v;
}

}  // namespace ubersim::match
