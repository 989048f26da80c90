// SPDX-License-Identifier: Apache-2.0
#include "tracker_packets.hpp"

#include <cmath>
#include <cstdio>
#include <random>

#include "referee_engine.hpp"

namespace ubersim::match {
namespace {

}  // namespace

std::string UuidFromSeed(std::uint64_t seed) {
  std::mt19937_64 rng(seed ^ 0x7472'6163'6b65'72ULL);  // "tracker": another stream than the world's
  const std::uint64_t a = rng(), b = rng();
  char text[40];
  std::snprintf(text, sizeof text, "%08x-%04x-4%03x-%04x-%012llx", static_cast<unsigned>(a >> 32),
                static_cast<unsigned>((a >> 16) & 0xffff), static_cast<unsigned>(a & 0x0fff),
                static_cast<unsigned>(0x8000 | ((b >> 48) & 0x3fff)),
                static_cast<unsigned long long>(b & 0xffffffffffffULL));
  return text;
}

TrackerWrapperPacket TrackedPacket(const WorldSnapshot& truth, std::uint32_t frame_number, std::int64_t unix_offset_ns,
                                   const TrackerSource& source, const TrackerNoise* noise) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  const auto jitter = [&](double sigma) { return noise != nullptr && sigma > 0 ? sigma * gauss(*noise->rng) : 0.0; };
  TrackerWrapperPacket packet;
  packet.set_uuid(source.uuid);
  packet.set_source_name(source.name);
  TrackedFrame* frame = packet.mutable_tracked_frame();
  frame->set_frame_number(frame_number);
  frame->set_timestamp(static_cast<double>(truth.sim_time_ns + unix_offset_ns) * 1e-9);
  TrackedBall* ball = frame->add_balls();
  const Vec3& p = truth.ball.pose.position;
  const Vec3& v = truth.ball.twist.linear;
  // The tracker's ball height is that of its centre above the carpet less the radius: 0 when it rolls.
  const double ball_sigma = noise != nullptr ? noise->ball_position_sigma : 0.0;
  ball->mutable_pos()->set_x(static_cast<float>(p.x() + jitter(ball_sigma)));
  ball->mutable_pos()->set_y(static_cast<float>(p.y() + jitter(ball_sigma)));
  ball->mutable_pos()->set_z(static_cast<float>(std::max(0.0, p.z() - truth.ball.radius)));
  ball->mutable_vel()->set_x(static_cast<float>(v.x()));
  ball->mutable_vel()->set_y(static_cast<float>(v.y()));
  ball->mutable_vel()->set_z(static_cast<float>(v.z()));
  ball->set_visibility(1.0f);
  for (const RobotState& r : truth.robots) {
    if (!r.present) continue;
    TrackedRobot* t = frame->add_robots();
    t->mutable_robot_id()->set_id(static_cast<unsigned>(r.id.id));
    t->mutable_robot_id()->set_team(WireTeam(r.id.team));
    const double robot_sigma = noise != nullptr ? noise->robot_position_sigma : 0.0;
    const double yaw_sigma = noise != nullptr ? noise->robot_orientation_sigma : 0.0;
    t->mutable_pos()->set_x(static_cast<float>(r.pose.position.x() + jitter(robot_sigma)));
    t->mutable_pos()->set_y(static_cast<float>(r.pose.position.y() + jitter(robot_sigma)));
    t->set_orientation(static_cast<float>(std::remainder(r.pose.Yaw() + jitter(yaw_sigma), 2 * M_PI)));
    t->mutable_vel()->set_x(static_cast<float>(r.twist.linear.x()));
    t->mutable_vel()->set_y(static_cast<float>(r.twist.linear.y()));
    t->set_vel_angular(static_cast<float>(r.twist.angular.z()));
    t->set_visibility(1.0f);
  }
  frame->add_capabilities(CAPABILITY_DETECT_FLYING_BALLS);
  return packet;
}

}  // namespace ubersim::match
