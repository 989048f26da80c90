// SPDX-License-Identifier: Apache-2.0
// What ssl_vision and grsim put on and take off the wire, without sockets.
#include <cmath>
#include <numbers>
#include <variant>

#include <gtest/gtest.h>

#include "grsim_translator.hpp"
#include "vision_packets.hpp"

namespace {

using namespace ubersim;

TEST(VisionPackets, DetectionInMillimetresWithEveryRequiredField) {
  VisionFrame f;
  f.camera_id = 2;
  f.frame_number = 41;
  f.t_capture_ns = 1'000'000'000;
  f.t_sent_ns = 1'035'000'000;
  f.balls.push_back(DetectedBall{0.5, -0.25, 0.0, 0.9, 6.49});
  f.robots.push_back(DetectedRobot{{Team::kYellow, 3}, 1.0, 2.0, 0.5, 1.0});
  transport::WireClock clock(transport::TimestampMode::kSim);
  const CameraInfo camera{2, Vec3(1.0, 2.0, 6.0)};
  const ssl_vision::CameraIntrinsics k;
  const SSL_WrapperPacket p = ssl_vision::DetectionPacket(f, clock, k, &camera, {{{1, 3}, 0.15}});
  ASSERT_TRUE(p.IsInitialized()) << p.InitializationErrorString();
  const SSL_DetectionFrame& d = p.detection();
  EXPECT_EQ(d.camera_id(), 2u);
  EXPECT_EQ(d.frame_number(), 41u);
  EXPECT_NEAR(d.t_sent() - d.t_capture(), 0.035, 1e-12);
  ASSERT_EQ(d.balls_size(), 1);
  EXPECT_FLOAT_EQ(d.balls(0).x(), 500.0f);
  EXPECT_FLOAT_EQ(d.balls(0).y(), -250.0f);
  EXPECT_FLOAT_EQ(d.balls(0).confidence(), 0.9f);
  EXPECT_FALSE(d.balls(0).has_z());  // projected onto the carpet, as the real system reports it
  ASSERT_TRUE(d.balls(0).has_area());
  EXPECT_EQ(d.balls(0).area(), 6u);  // the kernel's blob area, rounded to whole pixels
  ASSERT_EQ(d.robots_yellow_size(), 1);
  EXPECT_EQ(d.robots_blue_size(), 0);
  const SSL_DetectionRobot& r = d.robots_yellow(0);
  EXPECT_EQ(r.robot_id(), 3u);
  EXPECT_FLOAT_EQ(r.orientation(), 0.5f);
  EXPECT_FLOAT_EQ(r.height(), 150.0f);
  EXPECT_FLOAT_EQ(r.pixel_x(), 300.0f);  // right under the camera: the principal point
  EXPECT_FLOAT_EQ(r.pixel_y(), 300.0f);
  EXPECT_FLOAT_EQ(d.balls(0).pixel_x(), static_cast<float>(300.0 + 390.0 * -0.5 / 6.0));

  const SSL_WrapperPacket empty = ssl_vision::DetectionPacket(VisionFrame{}, clock, k, nullptr, {});
  EXPECT_TRUE(empty.IsInitialized());  // a camera that saw nothing still reports its frame
}

TEST(VisionPackets, GeometryFromTheFieldAndCameras) {
  ssl_vision::GeometryInputs in;
  in.field.field_length = 9.0;
  in.field.field_width = 6.0;
  in.field.carpet_length = 10.2;
  in.field.lines.push_back({"TopTouchLine", -4.5, 3.0, 4.5, 3.0, 0.01});
  in.field.lines.push_back({"GoalOutline", 0, 0, 1, 1, 0.01});
  in.field.arcs.push_back({"CenterCircle", 0, 0, 0.5, 0, 2 * std::numbers::pi, 0.01});
  in.cameras.push_back(CameraInfo{0, Vec3(-2.25, 0, 6)});
  in.cameras.push_back(CameraInfo{1, Vec3(2.25, 0, 6)});
  const SSL_WrapperPacket p = ssl_vision::GeometryPacket(in);
  ASSERT_TRUE(p.IsInitialized()) << p.InitializationErrorString();
  const SSL_GeometryFieldSize& f = p.geometry().field();
  EXPECT_EQ(f.field_length(), 9000);
  EXPECT_EQ(f.boundary_width_goal_line(), 600);
  EXPECT_EQ(f.field_lines(0).type(), TopTouchLine);
  EXPECT_FALSE(f.field_lines(1).has_type());
  EXPECT_EQ(f.field_arcs(0).type(), CenterCircle);
  EXPECT_FLOAT_EQ(f.ball_radius(), 21.5f);
  ASSERT_EQ(p.geometry().calib_size(), 2);
  EXPECT_FLOAT_EQ(p.geometry().calib(1).derived_camera_world_tx(), 2250.0f);
  EXPECT_FLOAT_EQ(p.geometry().calib(1).derived_camera_world_tz(), 6000.0f);
  EXPECT_DOUBLE_EQ(p.geometry().models().straight_two_phase().acc_slide(), -3.43);
  EXPECT_DOUBLE_EQ(p.geometry().models().chip_fixed_loss().damping_z(), 0.55);
}

grsim::WorldView TwoRobots() {
  grsim::WorldView w;
  w.known = true;
  w.robots = {{Team::kBlue, 0}, {Team::kYellow, 1}};
  w.ball_position = Vec3(1, 2, 0.0215);
  w.ball_velocity = Vec3(0.5, 0, 0);
  w.half_length = 5;
  w.half_width = 3.5;
  return w;
}

grSim_Packet Command(int id, bool yellow) {
  grSim_Packet p;
  p.mutable_commands()->set_timestamp(0);
  p.mutable_commands()->set_isteamyellow(yellow);
  grSim_Robot_Command* c = p.mutable_commands()->add_robot_commands();
  c->set_id(id);
  c->set_kickspeedx(0);
  c->set_kickspeedz(0);
  c->set_veltangent(1.0f);
  c->set_velnormal(-0.5f);
  c->set_velangular(2.0f);
  c->set_spinner(false);
  c->set_wheelsspeed(false);
  return p;
}

TEST(GrsimTranslator, CommandsBecomeLocalVelocityKickAndDribbler) {
  grsim::Translator t(100.0);
  std::vector<Event> events;
  std::vector<std::string> rejects;
  grSim_Packet p = Command(1, true);
  p.mutable_commands()->mutable_robot_commands(0)->set_kickspeedx(3.0f);
  p.mutable_commands()->mutable_robot_commands(0)->set_kickspeedz(4.0f);
  p.mutable_commands()->mutable_robot_commands(0)->set_spinner(true);
  t.Translate(p, TwoRobots(), events, rejects);
  ASSERT_TRUE(rejects.empty()) << rejects[0];
  ASSERT_EQ(events.size(), 1u);
  const auto& c = std::get<CommandEvent>(events[0]);
  EXPECT_EQ(c.robot, (RobotId{Team::kYellow, 1}));
  const auto& v = std::get<LocalVelocityCommand>(*c.move);
  EXPECT_DOUBLE_EQ(v.forward, 1.0);
  EXPECT_DOUBLE_EQ(v.left, -0.5);
  EXPECT_DOUBLE_EQ(v.angular, 2.0);
  ASSERT_TRUE(c.kick);
  EXPECT_DOUBLE_EQ(c.kick->speed, 5.0);
  EXPECT_DOUBLE_EQ(c.kick->angle, std::atan2(4.0, 3.0));
  EXPECT_DOUBLE_EQ(*c.dribbler_speed, 100.0);
  // Spinner unchanged: the dribbler is not told again; no kick asked: none sent.
  events.clear();
  p.mutable_commands()->mutable_robot_commands(0)->set_kickspeedx(0);
  p.mutable_commands()->mutable_robot_commands(0)->set_kickspeedz(0);
  t.Translate(p, TwoRobots(), events, rejects);
  EXPECT_FALSE(std::get<CommandEvent>(events[0]).dribbler_speed);
  EXPECT_FALSE(std::get<CommandEvent>(events[0]).kick);

  events.clear();
  grSim_Packet w = Command(0, false);
  auto* rc = w.mutable_commands()->mutable_robot_commands(0);
  rc->set_wheelsspeed(true);
  rc->set_wheel1(1);
  rc->set_wheel2(2);
  rc->set_wheel3(3);
  t.Translate(w, TwoRobots(), events, rejects);
  EXPECT_EQ(std::get<WheelSpeedCommand>(*std::get<CommandEvent>(events[0]).move).wheel_speeds,
            (std::vector<double>{1, 2, 3}));
}

TEST(GrsimTranslator, BadEntriesAreLeftOutWithAReason) {
  grsim::Translator t(100.0);
  std::vector<Event> events;
  std::vector<std::string> rejects;
  t.Translate(Command(1, false), TwoRobots(), events, rejects);  // blue 1 does not exist
  grSim_Packet nan = Command(0, false);
  nan.mutable_commands()->mutable_robot_commands(0)->set_veltangent(NAN);
  t.Translate(nan, TwoRobots(), events, rejects);
  grSim_Packet wheels = Command(0, false);
  wheels.mutable_commands()->mutable_robot_commands(0)->set_wheelsspeed(true);
  t.Translate(wheels, TwoRobots(), events, rejects);
  grSim_Packet off;
  auto* r = off.mutable_replacement()->add_robots();
  r->set_x(9);
  r->set_y(0);
  r->set_dir(0);
  r->set_id(0);
  r->set_yellowteam(false);
  t.Translate(off, TwoRobots(), events, rejects);
  EXPECT_TRUE(events.empty());
  ASSERT_EQ(rejects.size(), 4u);
  EXPECT_EQ(rejects[0], "command for blue 1: no blue 1 in this world (wrong team? there is a yellow 1)");
  EXPECT_EQ(rejects[1], "command for blue 0: a value is NaN or infinite");
  EXPECT_EQ(rejects[2], "command for blue 0: wheelsspeed is set but wheel1 is missing");
  EXPECT_NE(rejects[3].find("off the carpet"), std::string::npos) << rejects[3];
}

// As on grSim, every id 0..15 has a robot: a replacement puts one not in the world on the
// field (turnon unset or true), turning off one that is not there is a quiet no-op.
TEST(GrsimTranslator, ReplacementsBringRobotsOnAsGrSimDoes) {
  grsim::Translator t(100.0);
  std::vector<Event> events;
  std::vector<std::string> rejects;
  grSim_Packet p;
  for (std::uint32_t id : {5u, 6u, 16u}) {
    auto* r = p.mutable_replacement()->add_robots();
    r->set_x(1);
    r->set_y(0.2 * id);
    r->set_dir(90);
    r->set_id(id);
    r->set_yellowteam(true);
    if (id == 6) r->set_turnon(false);
  }
  t.Translate(p, TwoRobots(), events, rejects);
  ASSERT_EQ(events.size(), 1u);
  const auto& e = std::get<PositionEvent>(events[0]);
  EXPECT_EQ(e.target.robot, (RobotId{Team::kYellow, 5}));
  EXPECT_TRUE(*e.present);
  ASSERT_EQ(rejects.size(), 1u);
  EXPECT_NE(rejects[0].find("robot ids are 0..15"), std::string::npos) << rejects[0];
}

TEST(GrsimTranslator, ReplacementsInDegreesAndUnsetBallFieldsKept) {
  grsim::Translator t(100.0);
  std::vector<Event> events;
  std::vector<std::string> rejects;
  grSim_Packet p;
  p.mutable_replacement()->mutable_ball()->set_x(-1.0);
  auto* r = p.mutable_replacement()->add_robots();
  r->set_x(1);
  r->set_y(-1);
  r->set_dir(90);
  r->set_id(1);
  r->set_yellowteam(true);
  r->set_turnon(false);
  t.Translate(p, TwoRobots(), events, rejects);
  ASSERT_EQ(events.size(), 2u);
  const auto& ball = std::get<PositionEvent>(events[0]);
  EXPECT_TRUE(ball.target.is_ball);
  EXPECT_EQ(*ball.position, Vec3(-1.0, 2.0, 0.0215));   // y kept
  EXPECT_EQ(*ball.velocity, Vec3(0.5, 0.0, 0.0));       // velocity kept
  const auto& robot = std::get<PositionEvent>(events[1]);
  EXPECT_EQ(robot.target.robot, (RobotId{Team::kYellow, 1}));
  EXPECT_DOUBLE_EQ(*robot.yaw, std::numbers::pi / 2);
  EXPECT_FALSE(*robot.present);
}

TEST(GrsimStatus, FirstReportHasEveryRobotThenOnlyChanges) {
  grsim::Translator t(100.0);
  grsim::StatusTracker status;
  RobotState blue, yellow;
  blue.id = {Team::kBlue, 0};
  yellow.id = {Team::kYellow, 1};
  blue.kicker_ready = true;
  status.Observe({blue, yellow}, t);
  auto first = status.TakeChanged();
  EXPECT_EQ(first.first.robots_status_size(), 1);
  EXPECT_EQ(first.second.robots_status_size(), 1);
  auto none = status.TakeChanged();
  EXPECT_EQ(none.first.robots_status_size() + none.second.robots_status_size(), 0);
  // Blue 0 touches the ball and its kicker fires (a flat kick: no chip asked).
  blue.dribbler_ball_contact = true;
  blue.kicker_ready = false;
  status.Observe({blue, yellow}, t);
  auto kicked = status.TakeChanged();
  ASSERT_EQ(kicked.first.robots_status_size(), 1);
  EXPECT_TRUE(kicked.first.robots_status(0).infrared());
  EXPECT_TRUE(kicked.first.robots_status(0).flat_kick());
  EXPECT_FALSE(kicked.first.robots_status(0).chip_kick());
  EXPECT_EQ(kicked.second.robots_status_size(), 0);
  // The kick is reported once: the next report says it is over.
  status.Observe({blue, yellow}, t);
  auto after = status.TakeChanged();
  ASSERT_EQ(after.first.robots_status_size(), 1);
  EXPECT_FALSE(after.first.robots_status(0).flat_kick());
}

}  // namespace
