// SPDX-License-Identifier: Apache-2.0
// The ssl_simulation transport's protocol mapping, framing and simulation-thread bridge, without
// sockets: wire messages in, events and SimulatorErrors out, in the units the kernel uses.
#include <cmath>
#include <functional>
#include <limits>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "transport_common/delimited.hpp"
#include "error_codes.hpp"
#include "mapping.hpp"
#include "ssl_simulation_custom_ubersim.pb.h"
#include "sim_bridge.hpp"
#include "ssl_simulation_config.pb.h"
#include "ssl_simulation_custom_erforce.pb.h"

// Inside the project's namespace: the wire messages' global Team and RobotId must not win lookup.
namespace ubersim::ssl_simulation {
using transport::DelimitedDecoder;
using transport::EncodeDelimited;
namespace {

// Blue and yellow robots 0..5 are on the field; 6 and 7 in the world but off it.
Presence SixEach(const RobotId& id) {
  if (id.id >= 0 && id.id < 6) return Presence::kOnField;
  return id.id < 8 ? Presence::kOffField : Presence::kAbsent;
}

const MappingOptions kOptions{};

bool HasCode(const std::vector<WireError>& errors, const std::string& code) {
  for (const auto& e : errors) {
    if (e.code == code) return true;
  }
  return false;
}

template <typename T>
const T& As(const Event& e) {
  const T* p = std::get_if<T>(&e);
  EXPECT_NE(p, nullptr);
  static const T empty{};
  return p ? *p : empty;
}

TEST(SslSimulationMapping, TeleportBallPlacesAndStopsIt) {
  SimulatorCommand c;
  TeleportBall* b = c.mutable_control()->mutable_teleport_ball();
  b->set_x(1.5f);
  b->set_y(-0.5f);
  const Mapped m = MapSimulatorCommand(c, SixEach, kOptions);
  ASSERT_TRUE(m.errors.empty());
  ASSERT_EQ(m.events.size(), 1u);
  const auto& e = As<PositionEvent>(m.events[0]);
  EXPECT_TRUE(e.target.is_ball);
  ASSERT_TRUE(e.position);
  EXPECT_FLOAT_EQ(e.position->x(), 1.5f);
  EXPECT_FLOAT_EQ(e.position->y(), -0.5f);
  EXPECT_EQ(e.position->z(), 0.0);  // the kernel rests it on the carpet
  EXPECT_FALSE(e.velocity);         // and stops it
}

TEST(SslSimulationMapping, TeleportBallVelocitySlidesOrRolls) {
  SimulatorCommand c;
  TeleportBall* b = c.mutable_control()->mutable_teleport_ball();
  b->set_x(0);
  b->set_y(0);
  b->set_vx(2.0f);
  b->set_vy(1.0f);
  Mapped m = MapSimulatorCommand(c, SixEach, kOptions);
  ASSERT_EQ(m.events.size(), 1u);
  {
    const auto& e = As<PositionEvent>(m.events[0]);
    ASSERT_TRUE(e.velocity && e.angular_velocity);
    EXPECT_DOUBLE_EQ(e.velocity->x(), 2.0);
    EXPECT_DOUBLE_EQ(e.velocity->z(), 0.0);
    EXPECT_EQ(*e.angular_velocity, Vec3::Zero());  // slides
  }
  b->set_roll(true);
  MappingOptions o;
  o.ball_radius = 0.02;
  m = MapSimulatorCommand(c, SixEach, o);
  ASSERT_TRUE(m.errors.empty());
  const auto& e = As<PositionEvent>(m.events[0]);
  // Rolling without slip: ω = (−vy, vx, 0) / r.
  EXPECT_NEAR(e.angular_velocity->x(), -1.0 / 0.02, 1e-9);
  EXPECT_NEAR(e.angular_velocity->y(), 2.0 / 0.02, 1e-9);
  // The contact point stands still.
  const Vec3 contact = *e.velocity + e.angular_velocity->cross(Vec3(0, 0, -0.02));
  EXPECT_LT(contact.norm(), 1e-9);
}

TEST(SslSimulationMapping, ABadBallTeleportSkipsTheBallOnly) {
  SimulatorCommand c;
  c.mutable_control()->mutable_teleport_ball()->set_x(1.0f);
  TeleportRobot* r = c.mutable_control()->add_teleport_robot();
  r->mutable_id()->set_id(1);
  r->mutable_id()->set_team(::BLUE);
  r->set_x(0);
  r->set_y(0);
  Mapped m = MapSimulatorCommand(c, SixEach, kOptions);
  ASSERT_EQ(m.events.size(), 1u);  // the valid robot teleport still applies
  EXPECT_FALSE(As<PositionEvent>(m.events[0]).target.is_ball);
  ASSERT_EQ(m.errors.size(), 1u);
  EXPECT_EQ(m.errors[0].code, codes::kPartialCoord);

  c.mutable_control()->mutable_teleport_ball()->set_y(std::numeric_limits<float>::quiet_NaN());
  m = MapSimulatorCommand(c, SixEach, kOptions);
  EXPECT_EQ(m.events.size(), 1u);
  EXPECT_TRUE(HasCode(m.errors, codes::kNonFinite));
  c.mutable_control()->mutable_teleport_ball()->set_y(std::numeric_limits<float>::infinity());
  EXPECT_TRUE(HasCode(MapSimulatorCommand(c, SixEach, kOptions).errors, codes::kNonFinite));
}

TEST(SslSimulationMapping, UnsupportedBallOptionsSkipOnlyTheBall) {
  for (int which = 0; which < 2; ++which) {
    SimulatorCommand c;
    TeleportBall* b = c.mutable_control()->mutable_teleport_ball();
    b->set_x(1);
    b->set_y(1);
    if (which == 0) b->set_teleport_safely(true); else b->set_by_force(true);
    TeleportRobot* r = c.mutable_control()->add_teleport_robot();
    r->mutable_id()->set_id(2);
    r->mutable_id()->set_team(::YELLOW);
    r->set_orientation(1.0f);
    const Mapped m = MapSimulatorCommand(c, SixEach, kOptions);
    EXPECT_TRUE(HasCode(m.errors, which == 0 ? codes::kTeleportSafely : codes::kByForce));
    ASSERT_EQ(m.events.size(), 1u);
    EXPECT_FALSE(As<PositionEvent>(m.events[0]).target.is_ball);
  }
  // by_force=false alone (the protocol's "stop forcing") is a quiet no-op.
  SimulatorCommand c;
  c.mutable_control()->mutable_teleport_ball()->set_by_force(false);
  const Mapped m = MapSimulatorCommand(c, SixEach, kOptions);
  EXPECT_TRUE(m.errors.empty());
  EXPECT_TRUE(m.events.empty());
}

TEST(SslSimulationMapping, TeleportRobot) {
  SimulatorCommand c;
  TeleportRobot* r = c.mutable_control()->add_teleport_robot();
  r->mutable_id()->set_id(3);
  r->mutable_id()->set_team(::YELLOW);
  r->set_x(-1.0f);
  r->set_y(2.0f);
  r->set_orientation(0.5f);
  r->set_v_x(1.0f);
  r->set_v_angular(2.0f);
  r->set_present(true);
  const Mapped m = MapSimulatorCommand(c, SixEach, kOptions);
  ASSERT_TRUE(m.errors.empty());
  ASSERT_EQ(m.events.size(), 1u);
  const auto& e = As<PositionEvent>(m.events[0]);
  EXPECT_EQ(e.target.robot, (RobotId{Team::kYellow, 3}));
  EXPECT_DOUBLE_EQ(e.position->x(), -1.0);
  EXPECT_DOUBLE_EQ(e.position->y(), 2.0);
  EXPECT_FLOAT_EQ(static_cast<float>(*e.yaw), 0.5f);
  EXPECT_DOUBLE_EQ(e.velocity->x(), 1.0);
  EXPECT_DOUBLE_EQ(e.velocity->y(), 0.0);
  EXPECT_DOUBLE_EQ(e.angular_velocity->z(), 2.0);
  EXPECT_TRUE(*e.present);

  // Taking a robot off the field needs nothing else.
  SimulatorCommand off;
  TeleportRobot* o = off.mutable_control()->add_teleport_robot();
  o->mutable_id()->set_id(0);
  o->mutable_id()->set_team(::BLUE);
  o->set_present(false);
  const Mapped mo = MapSimulatorCommand(off, SixEach, kOptions);
  ASSERT_EQ(mo.events.size(), 1u);
  const auto& eo = As<PositionEvent>(mo.events[0]);
  EXPECT_FALSE(*eo.present);
  EXPECT_FALSE(eo.position || eo.yaw || eo.velocity);
}

TEST(SslSimulationMapping, TeleportRobotErrors) {
  auto one = [](auto setup) {
    SimulatorCommand c;
    TeleportRobot* r = c.mutable_control()->add_teleport_robot();
    r->mutable_id()->set_id(1);
    r->mutable_id()->set_team(::BLUE);
    setup(*r);
    return MapSimulatorCommand(c, SixEach, kOptions);
  };
  auto skipped_with = [](const Mapped& m, const char* code) {
    EXPECT_TRUE(m.events.empty()) << code;
    ASSERT_EQ(m.errors.size(), 1u) << code;
    EXPECT_EQ(m.errors[0].code, code);
  };
  skipped_with(one([](TeleportRobot& r) { r.mutable_id()->set_id(16); }), codes::kInvalidRobotId);
  skipped_with(one([](TeleportRobot& r) { r.mutable_id()->set_team(::UNKNOWN); }), codes::kInvalidTeam);
  skipped_with(one([](TeleportRobot& r) { r.mutable_id()->clear_team(); }), codes::kInvalidTeam);
  skipped_with(one([](TeleportRobot& r) { r.mutable_id()->clear_id(); }), codes::kMissingField);
  skipped_with(one([](TeleportRobot& r) { r.set_x(1); }), codes::kPartialCoord);
  skipped_with(one([](TeleportRobot& r) { r.set_y(1); }), codes::kPartialCoord);
  skipped_with(one([](TeleportRobot& r) { r.set_orientation(std::nanf("")); }), codes::kNonFinite);
  skipped_with(one([](TeleportRobot& r) { r.set_v_x(INFINITY); }), codes::kNonFinite);
  skipped_with(one([](TeleportRobot& r) { r.set_by_force(true); }), codes::kByForce);
  // A new robot needs a place to come on.
  skipped_with(one([](TeleportRobot& r) {
                 r.mutable_id()->set_id(9);
                 r.set_present(true);
               }),
               codes::kCreateNoPosition);
}

// A robot that is not on the field, with present unset (or false), is a quiet no-op, as on
// grSim; present: true puts it on (or builds it) and asks the world for an answer.
TEST(SslSimulationMapping, RobotsNotOnTheFieldAreLeftAloneUnlessAskedToComeOn) {
  SimulatorCommand c;
  for (int id = 0; id < 16; ++id) {  // the clearing command of a client written for grSim
    TeleportRobot* r = c.mutable_control()->add_teleport_robot();
    r->mutable_id()->set_id(static_cast<std::uint32_t>(id));
    r->mutable_id()->set_team(::BLUE);
    r->set_x(-5.0f);
    r->set_y(0.2f * static_cast<float>(id));
  }
  Mapped m = MapSimulatorCommand(c, SixEach, kOptions);
  EXPECT_TRUE(m.errors.empty());
  ASSERT_EQ(m.events.size(), 6u);  // 0..5 move; 6, 7 (off the field) and 8..15 (absent) do not
  for (const Event& e : m.events) EXPECT_LT(As<PositionEvent>(e).target.robot.id, 6);

  SimulatorCommand on;
  for (int id : {3, 6, 9}) {
    TeleportRobot* r = on.mutable_control()->add_teleport_robot();
    r->mutable_id()->set_id(static_cast<std::uint32_t>(id));
    r->mutable_id()->set_team(::YELLOW);
    r->set_x(1.0f);
    r->set_y(2.0f);
    r->set_present(true);
  }
  m = MapSimulatorCommand(on, SixEach, kOptions);
  EXPECT_TRUE(m.errors.empty());
  ASSERT_EQ(m.events.size(), 3u);
  for (const Event& e : m.events) {
    EXPECT_TRUE(*As<PositionEvent>(e).present);
    EXPECT_TRUE(WantsAnswer(e));
  }
  // Off: no answer needed.
  on.mutable_control()->mutable_teleport_robot(0)->set_present(false);
  m = MapSimulatorCommand(on, SixEach, kOptions);
  EXPECT_FALSE(WantsAnswer(m.events[0]));
}

TEST(SslSimulationMapping, SimulationSpeed) {
  SimulatorCommand c;
  c.mutable_control()->set_simulation_speed(2.0f);
  Mapped m = MapSimulatorCommand(c, SixEach, kOptions);
  ASSERT_EQ(m.events.size(), 1u);
  EXPECT_EQ(As<ClockEvent>(m.events[0]).action, ClockEvent::Action::kSetSpeed);
  EXPECT_DOUBLE_EQ(As<ClockEvent>(m.events[0]).speed_factor, 2.0);
  for (float bad : {0.0f, -1.0f, std::nanf("")}) {
    c.mutable_control()->set_simulation_speed(bad);
    m = MapSimulatorCommand(c, SixEach, kOptions);
    EXPECT_TRUE(m.events.empty());
    EXPECT_TRUE(HasCode(m.errors, codes::kInvalidValue));
  }
}

SimulatorCommand WithRealism(const RealismConfigErForce& r, const std::string& url) {
  SimulatorCommand c;
  google::protobuf::Any* any = c.mutable_config()->mutable_realism_config()->add_custom();
  any->set_type_url(url);
  any->set_value(r.SerializeAsString());
  return c;
}

TEST(SslSimulationMapping, RealismErForceEveryFieldReachesItsEvent) {
  // Fields 1–18 of RealismConfigErForce (reference/ssl-protocols.md §6.1), each set.
  RealismConfigErForce r;
  r.set_stddev_ball_p(0.002f);               // 1
  r.set_stddev_robot_p(0.003f);              // 2
  r.set_stddev_robot_phi(0.01f);             // 3
  r.set_stddev_ball_area(6.5f);              // 4
  r.set_enable_invisible_ball(true);         // 5
  r.set_ball_visibility_threshold(0.4f);     // 6
  r.set_camera_overlap(0.5f);                // 7
  r.set_dribbler_ball_detections(0.05f);     // 8
  r.set_camera_position_error(0.1f);         // 9
  r.set_robot_command_loss(0.03f);           // 10
  r.set_robot_response_loss(0.1f);           // 11
  r.set_missing_ball_detections(0.05f);      // 12
  r.set_vision_delay(35000000);              // 13
  r.set_vision_processing_time(10000000);    // 14
  r.set_simulate_dribbling(false);           // 15
  r.set_object_position_offset(0.02f);       // 16
  r.set_missing_robot_detections(0.02f);     // 17
  r.set_command_delay(3000000);              // 18
  for (const char* url : {"type.googleapis.com/RealismConfigErForce", "type.googleapis.com/sslsim.RealismConfigErForce"}) {
    const Mapped m = MapSimulatorCommand(WithRealism(r, url), SixEach, kOptions);
    EXPECT_TRUE(m.errors.empty()) << url;  // nothing is left out as unsupported
    ASSERT_EQ(m.events.size(), 1u) << url;
    const auto& e = As<RealismEvent>(m.events[0]);
    ASSERT_TRUE(e.ball_position_noise && e.robot_position_noise && e.robot_orientation_noise && e.ball_area_noise &&
                e.ball_occlusion && e.ball_visibility_threshold && e.camera_overlap && e.dribbler_false_balls &&
                e.camera_position_error && e.radio_loss && e.radio_response_loss && e.ball_drop &&
                e.vision_latency && e.processing_time && e.held_ball && e.object_offset && e.robot_drop &&
                e.radio_latency);
    EXPECT_NEAR(*e.ball_position_noise, 0.002, 1e-9);        // m
    EXPECT_NEAR(*e.robot_position_noise, 0.003, 1e-9);       // m
    EXPECT_NEAR(*e.robot_orientation_noise, 0.01, 1e-9);     // rad
    EXPECT_NEAR(*e.ball_area_noise, 6.5, 1e-9);              // px
    EXPECT_TRUE(*e.ball_occlusion);
    EXPECT_NEAR(*e.ball_visibility_threshold, 0.4, 1e-7);
    EXPECT_NEAR(*e.camera_overlap, 0.5, 1e-9);               // m
    EXPECT_NEAR(*e.dribbler_false_balls, 0.05, 1e-9);        // 1/s per robot
    EXPECT_NEAR(*e.camera_position_error, 0.1, 1e-7);        // m
    EXPECT_NEAR(*e.radio_loss, 0.03, 1e-9);
    EXPECT_NEAR(*e.radio_response_loss, 0.1, 1e-7);
    EXPECT_NEAR(*e.ball_drop, 0.05, 1e-9);
    EXPECT_DOUBLE_EQ(*e.vision_latency, 0.035);              // ns → s
    EXPECT_DOUBLE_EQ(*e.processing_time, 0.010);             // ns → s
    EXPECT_TRUE(*e.held_ball);                               // simulate_dribbling false: held
    EXPECT_NEAR(*e.object_offset, 0.02, 1e-9);               // m
    EXPECT_NEAR(*e.robot_drop, 0.02, 1e-9);
    EXPECT_DOUBLE_EQ(*e.radio_latency, 0.003);               // ns → s
  }
}

TEST(SslSimulationMapping, RealismSetsOnlyTheFieldsItHas) {
  RealismConfigErForce r;
  r.set_simulate_dribbling(true);  // physical dribbling: the ball is not held
  r.set_enable_invisible_ball(false);
  Mapped m = MapSimulatorCommand(WithRealism(r, "RealismConfigErForce"), SixEach, kOptions);
  ASSERT_TRUE(m.errors.empty());
  ASSERT_EQ(m.events.size(), 1u);
  {
    const auto& e = As<RealismEvent>(m.events[0]);
    ASSERT_TRUE(e.held_ball && e.ball_occlusion);
    EXPECT_FALSE(*e.held_ball);
    EXPECT_FALSE(*e.ball_occlusion);
    EXPECT_FALSE(e.vision_latency || e.processing_time || e.ball_area_noise || e.radio_response_loss ||
                 e.ball_visibility_threshold || e.camera_position_error || e.object_offset ||
                 e.dribbler_false_balls);
  }
  // Zeros are values too: they switch a setting off.
  RealismConfigErForce zeros;
  zeros.set_stddev_ball_area(0.0f);
  zeros.set_vision_processing_time(0);
  m = MapSimulatorCommand(WithRealism(zeros, "RealismConfigErForce"), SixEach, kOptions);
  ASSERT_TRUE(m.errors.empty());
  ASSERT_EQ(m.events.size(), 1u);
  {
    const auto& e = As<RealismEvent>(m.events[0]);
    ASSERT_TRUE(e.ball_area_noise && e.processing_time);
    EXPECT_EQ(*e.ball_area_noise, 0.0);
    EXPECT_EQ(*e.processing_time, 0.0);
  }
  // An empty message asks for nothing.
  m = MapSimulatorCommand(WithRealism(RealismConfigErForce{}, "RealismConfigErForce"), SixEach, kOptions);
  EXPECT_TRUE(m.errors.empty());
  EXPECT_TRUE(m.events.empty());
}

TEST(SslSimulationMapping, RealismRefusesAWholeMessageWithAnInvalidValue) {
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<std::pair<const char*, std::function<void(RealismConfigErForce&)>>> bad = {
      {"stddev_ball_p", [&](auto& r) { r.set_stddev_ball_p(-0.001f); }},
      {"stddev_ball_area", [&](auto& r) { r.set_stddev_ball_area(-1.0f); }},
      {"stddev_ball_area", [&](auto& r) { r.set_stddev_ball_area(nan); }},
      {"ball_visibility_threshold", [&](auto& r) { r.set_ball_visibility_threshold(1.5f); }},
      {"dribbler_ball_detections", [&](auto& r) { r.set_dribbler_ball_detections(-0.1f); }},
      {"camera_position_error", [&](auto& r) { r.set_camera_position_error(inf); }},
      {"robot_response_loss", [&](auto& r) { r.set_robot_response_loss(1.01f); }},
      {"robot_response_loss", [&](auto& r) { r.set_robot_response_loss(-0.1f); }},
      {"missing_ball_detections", [&](auto& r) { r.set_missing_ball_detections(1.5f); }},
      {"vision_delay", [&](auto& r) { r.set_vision_delay(-5); }},
      {"vision_processing_time", [&](auto& r) { r.set_vision_processing_time(11'000'000'000); }},
      {"vision_processing_time", [&](auto& r) { r.set_vision_processing_time(-1); }},
      {"object_position_offset", [&](auto& r) { r.set_object_position_offset(-0.02f); }},
      {"command_delay", [&](auto& r) { r.set_command_delay(20'000'000'000u); }},
  };
  for (const auto& [name, spoil] : bad) {
    RealismConfigErForce r;
    r.set_vision_delay(20000000);  // valid, but not applied beside an invalid value
    r.set_stddev_ball_area(6.5f);
    spoil(r);
    const Mapped m = MapSimulatorCommand(WithRealism(r, "RealismConfigErForce"), SixEach, kOptions);
    EXPECT_TRUE(m.events.empty()) << name;
    ASSERT_EQ(m.errors.size(), 1u) << name;
    EXPECT_EQ(m.errors[0].code, codes::kInvalidValue) << name;
    EXPECT_NE(m.errors[0].message.find(name), std::string::npos) << m.errors[0].message;
    EXPECT_FALSE(HasCode(m.errors, codes::kRealismFields)) << name;
  }

  RealismConfigErForce r;
  r.set_vision_delay(20000000);
  SimulatorCommand garbled = WithRealism(r, "RealismConfigErForce");
  garbled.mutable_config()->mutable_realism_config()->mutable_custom(0)->set_value("\xff\xff\xff");
  EXPECT_TRUE(HasCode(MapSimulatorCommand(garbled, SixEach, kOptions).errors, codes::kUnreadable));
}

TEST(SslSimulationMapping, ConfigBecomesEventsTheWorldAnswers) {
  SimulatorCommand c;
  SSL_GeometryFieldSize* f = c.mutable_config()->mutable_geometry()->mutable_field();
  f->set_field_length(12000);
  f->set_field_width(9000);
  f->set_goal_width(1800);
  f->set_goal_depth(180);
  f->set_boundary_width(300);
  RobotSpecs* s = c.mutable_config()->add_robot_specs();
  s->mutable_id()->set_id(3);
  s->mutable_id()->set_team(::BLUE);
  s->set_radius(0.085f);
  s->set_max_linear_kick_speed(5.0f);
  s->mutable_limits()->set_vel_absolute_max(2.5f);
  RobotWheelAngles* w = s->mutable_wheel_angles();
  w->set_front_right(1.0f);  // clockwise from forward: the drive's 2π − 1, counter-clockwise
  w->set_back_right(2.0f);
  w->set_back_left(4.0f);
  w->set_front_left(5.0f);
  RobotSpecErForce erforce;
  erforce.set_shoot_radius(0.0815f);
  erforce.set_dribbler_width(0.07f);
  google::protobuf::Any* custom = s->add_custom();
  custom->set_type_url("RobotSpecErForce");  // bare, as ssl-simulation-controller sends it
  custom->set_value(erforce.SerializeAsString());
  c.mutable_config()->set_vision_port(10006);
  google::protobuf::Any* any = c.mutable_config()->mutable_realism_config()->add_custom();
  any->set_type_url("type.googleapis.com/RealismConfigGrSim");
  const Mapped m = MapSimulatorCommand(c, SixEach, kOptions);
  ASSERT_EQ(m.errors.size(), 1u);
  EXPECT_EQ(m.errors[0].code, codes::kUnknownRealism);
  ASSERT_EQ(m.events.size(), 3u);
  const auto& field = As<FieldEvent>(m.events[0]);
  EXPECT_DOUBLE_EQ(field.field_length, 12.0);
  EXPECT_DOUBLE_EQ(field.boundary_width, 0.3);
  EXPECT_FALSE(field.penalty_area_depth);
  const auto& spec = As<RobotSpecEvent>(m.events[1]);
  EXPECT_EQ(spec.robot, (RobotId{Team::kBlue, 3}));
  EXPECT_NEAR(*spec.spec.radius, 0.085, 1e-7);
  EXPECT_FALSE(spec.spec.height);  // unset: the model's (the proto's default 0.15 is not a value)
  EXPECT_NEAR(*spec.spec.max_flat_kick_speed, 5.0, 1e-7);
  EXPECT_NEAR(*spec.spec.max_speed, 2.5, 1e-7);
  EXPECT_NEAR(*spec.spec.dribbler_width, 0.07, 1e-7);
  EXPECT_NEAR(*spec.spec.center_to_dribbler, 0.0815 - kOptions.ball_radius, 1e-7);
  ASSERT_TRUE(spec.spec.wheel_angles);
  // Protocol order FR, BR, BL, FL goes to drive wheels 3, 2, 1, 0.
  EXPECT_NEAR((*spec.spec.wheel_angles)[3], 2 * M_PI - 1.0, 1e-6);
  EXPECT_NEAR((*spec.spec.wheel_angles)[0], 2 * M_PI - 5.0, 1e-6);
  const auto& port = As<TransportSettingEvent>(m.events[2]);
  EXPECT_EQ(port.name, "vision_port");
  EXPECT_EQ(port.value, 10006);
  for (const Event& e : m.events) EXPECT_TRUE(WantsAnswer(e));

  // The world's answers, each with its code.
  EXPECT_EQ(AnswerErrors(m.events[1], EventAnswer{{"mass -1 kg: must be > 0"}, {"height (no place)"}})[0].code,
            codes::kInvalidSpec);
  EXPECT_EQ(AnswerErrors(m.events[1], EventAnswer{{}, {"height (no place)"}})[0].code, codes::kUnmappedSpec);
  EXPECT_EQ(AnswerErrors(m.events[0], EventAnswer{{"no field of that size"}, {}})[0].code, codes::kGeometry);
  EXPECT_EQ(AnswerErrors(m.events[2], EventAnswer{{"no vision transport"}, {}})[0].code, codes::kVisionPort);
  EXPECT_TRUE(AnswerErrors(m.events[2], EventAnswer{}).empty());

  // A spec for id 16, a geometry without its sizes: those items only.
  SimulatorCommand bad;
  bad.mutable_config()->add_robot_specs()->mutable_id()->set_id(16);
  bad.mutable_config()->mutable_robot_specs(0)->mutable_id()->set_team(::YELLOW);
  bad.mutable_config()->mutable_geometry();
  const Mapped mb = MapSimulatorCommand(bad, SixEach, kOptions);
  EXPECT_TRUE(mb.events.empty());
  EXPECT_TRUE(HasCode(mb.errors, codes::kInvalidRobotId));
  EXPECT_TRUE(HasCode(mb.errors, codes::kMissingField));
}

TEST(SslSimulationMapping, RobotCommandUnits) {
  RobotControl rc;
  RobotCommand* c = rc.add_robot_commands();
  c->set_id(4);
  c->mutable_move_command()->mutable_local_velocity()->set_forward(1.0f);
  c->mutable_move_command()->mutable_local_velocity()->set_left(-0.5f);
  c->mutable_move_command()->mutable_local_velocity()->set_angular(2.0f);
  c->set_kick_speed(10.0f);
  c->set_kick_angle(45.0f);
  c->set_dribbler_speed(600.0f);
  const MappedRobotControl m = MapRobotControl(rc, Team::kYellow, SixEach, kOptions);
  ASSERT_TRUE(m.errors.empty());
  ASSERT_EQ(m.events.size(), 1u);
  const auto& e = As<CommandEvent>(m.events[0]);
  EXPECT_EQ(e.robot, (RobotId{Team::kYellow, 4}));
  const auto& v = std::get<LocalVelocityCommand>(*e.move);
  EXPECT_DOUBLE_EQ(v.forward, 1.0);
  EXPECT_DOUBLE_EQ(v.left, -0.5);
  EXPECT_DOUBLE_EQ(v.angular, 2.0);
  EXPECT_DOUBLE_EQ(e.kick->speed, 10.0);            // the kicker clamps, not the transport
  EXPECT_NEAR(e.kick->angle, M_PI / 4, 1e-12);      // degrees → rad
  EXPECT_NEAR(*e.dribbler_speed, 600.0 * 2 * M_PI / 60, 1e-9);  // rpm → rad/s
  EXPECT_EQ(m.commanded_ids, std::vector<std::uint32_t>{4});
}

TEST(SslSimulationMapping, MoveKinds) {
  RobotControl rc;
  RobotCommand* g = rc.add_robot_commands();
  g->set_id(0);
  g->mutable_move_command()->mutable_global_velocity()->set_x(1);
  g->mutable_move_command()->mutable_global_velocity()->set_y(2);
  g->mutable_move_command()->mutable_global_velocity()->set_angular(3);
  RobotCommand* w = rc.add_robot_commands();
  w->set_id(1);
  MoveWheelVelocity* wv = w->mutable_move_command()->mutable_wheel_velocity();
  wv->set_front_right(1);
  wv->set_back_right(2);
  wv->set_back_left(3);
  wv->set_front_left(4);
  MappedRobotControl m = MapRobotControl(rc, Team::kBlue, SixEach, kOptions);
  ASSERT_TRUE(m.errors.empty());
  ASSERT_EQ(m.events.size(), 2u);
  const auto& gv = std::get<GlobalVelocityCommand>(*As<CommandEvent>(m.events[0]).move);
  EXPECT_DOUBLE_EQ(gv.y, 2.0);
  // Default order: drive wheels listed counter-clockwise from the front left (60°, 135°, 225°, 300°).
  const auto& ws = std::get<WheelSpeedCommand>(*As<CommandEvent>(m.events[1]).move);
  EXPECT_EQ(ws.wheel_speeds, (std::vector<double>{4, 3, 2, 1}));

  MappingOptions off;
  off.wheel_order.clear();
  m = MapRobotControl(rc, Team::kBlue, SixEach, off);
  EXPECT_TRUE(HasCode(m.errors, codes::kWheelVelocity));
  ASSERT_EQ(m.events.size(), 1u);  // the global-velocity robot still moves
}

TEST(SslSimulationMapping, ABadRobotCommandSkipsThatRobotOnly) {
  auto two = [](auto setup) {
    RobotControl rc;
    RobotCommand* good = rc.add_robot_commands();
    good->set_id(0);
    good->mutable_move_command()->mutable_local_velocity()->set_forward(1);
    good->mutable_move_command()->mutable_local_velocity()->set_left(0);
    good->mutable_move_command()->mutable_local_velocity()->set_angular(0);
    RobotCommand* bad = rc.add_robot_commands();
    bad->set_id(1);
    setup(*bad);
    return MapRobotControl(rc, Team::kBlue, SixEach, kOptions);
  };
  auto refused_with = [](const MappedRobotControl& m, const char* code) {
    ASSERT_EQ(m.events.size(), 1u) << code;  // robot 0 still moves
    EXPECT_EQ(As<CommandEvent>(m.events[0]).robot.id, 0) << code;
    ASSERT_EQ(m.errors.size(), 1u) << code;
    EXPECT_EQ(m.errors[0].code, code);
  };
  refused_with(two([](RobotCommand& c) { c.set_id(7); }), codes::kUnknownRobot);  // off the field
  refused_with(two([](RobotCommand& c) { c.set_id(12); }), codes::kUnknownRobot);  // not in the world
  refused_with(two([](RobotCommand& c) { c.set_kick_speed(NAN); }), codes::kNonFinite);
  refused_with(two([](RobotCommand& c) { c.set_dribbler_speed(-INFINITY); }), codes::kNonFinite);
  refused_with(two([](RobotCommand& c) {
                 auto* v = c.mutable_move_command()->mutable_local_velocity();
                 v->set_forward(NAN);
                 v->set_left(0);
                 v->set_angular(0);
               }),
               codes::kNonFinite);
  refused_with(two([](RobotCommand& c) { c.mutable_move_command(); }), codes::kMissingField);
  refused_with(two([](RobotCommand& c) { c.set_kick_speed(-1); }), codes::kInvalidValue);
  refused_with(two([](RobotCommand& c) {
                 c.set_kick_speed(3);
                 c.set_kick_angle(95);
               }),
               codes::kInvalidValue);
  // The ids are still known, so the response can give feedback for the robots that exist.
  const MappedRobotControl m = two([](RobotCommand& c) { c.set_id(7); });
  EXPECT_EQ(m.commanded_ids, (std::vector<std::uint32_t>{0, 7}));
}

TEST(SslSimulationMapping, ResponseHasFeedbackForEachCommandedRobot) {
  auto report = [](const RobotId& id) -> std::optional<RobotReport> {
    if (SixEach(id) != Presence::kOnField) return std::nullopt;
    RobotReport r;
    r.dribbler_ball_contact = id.id == 2;
    if (id.id == 2) {
      DriveFeedback d;
      d.wheel_speeds = {10.5, -20.25, 30.0, -40.0};
      d.local_velocity.linear = Vec3(1.5, -0.25, 0);
      d.local_velocity.angular = Vec3(0, 0, 2.0);
      r.drive = d;
    }
    return r;
  };
  const RobotControlResponse r = BuildRobotControlResponse(
      {2, 3, 9}, Team::kBlue, report, {WireError{codes::kUnknownRobot, "no robot blue 9"}});
  ASSERT_EQ(r.feedback_size(), 2);
  EXPECT_EQ(r.feedback(0).id(), 2u);
  EXPECT_TRUE(r.feedback(0).dribbler_ball_contact());
  EXPECT_EQ(r.feedback(1).id(), 3u);
  EXPECT_TRUE(r.feedback(1).has_dribbler_ball_contact());
  EXPECT_FALSE(r.feedback(1).dribbler_ball_contact());
  ASSERT_EQ(r.errors_size(), 1);
  EXPECT_EQ(r.errors(0).code(), codes::kUnknownRobot);
  EXPECT_TRUE(r.IsInitialized());

  // The drive's measurements travel in custom, under ÜberSim's own message type.
  ASSERT_TRUE(r.feedback(0).has_custom());
  EXPECT_EQ(r.feedback(0).custom().type_url(), "type.googleapis.com/UberSimDriveFeedback");
  UberSimDriveFeedback d;
  ASSERT_TRUE(r.feedback(0).custom().UnpackTo(&d));
  ASSERT_EQ(d.wheel_speeds_size(), 4);
  EXPECT_FLOAT_EQ(d.wheel_speeds(0), 10.5f);
  EXPECT_FLOAT_EQ(d.wheel_speeds(1), -20.25f);
  EXPECT_FLOAT_EQ(d.wheel_speeds(3), -40.0f);
  EXPECT_FLOAT_EQ(d.forward(), 1.5f);
  EXPECT_FLOAT_EQ(d.left(), -0.25f);
  EXPECT_FLOAT_EQ(d.angular(), 2.0f);
  // A robot whose drive reports nothing (none, or switched off) sends no custom.
  EXPECT_FALSE(r.feedback(1).has_custom());
}

TEST(SslSimulationMapping, ParseMessageKinds) {
  RobotControl rc;
  rc.add_robot_commands()->set_id(1);
  const std::string good = rc.SerializeAsString();
  RobotControl out;
  EXPECT_FALSE(ParseMessage(good.data(), good.size(), 1024, out));

  const std::string big(2000, '\0');
  auto e = ParseMessage(big.data(), big.size(), 1024, out);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->code, codes::kOversized);

  const std::string garbage = "\xff\xff\xff\xff\xff\xff\xff";
  e = ParseMessage(garbage.data(), garbage.size(), 1024, out);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->code, codes::kUnreadable);

  // Truncated inside the nested RobotCommand.
  RobotControl longer;
  RobotCommand* c = longer.add_robot_commands();
  c->set_id(1);
  c->set_kick_speed(3);
  const std::string whole = longer.SerializeAsString();
  e = ParseMessage(whole.data(), whole.size() - 2, 1024, out);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->code, codes::kUnreadable);

  // A RobotCommand without its required id: well-formed, read; that command is refused on its own.
  RobotControl missing;
  missing.add_robot_commands()->set_kick_speed(1);
  RobotCommand* fine = missing.add_robot_commands();
  fine->set_id(2);
  fine->set_dribbler_speed(100);
  const std::string partial = missing.SerializePartialAsString();
  EXPECT_FALSE(ParseMessage(partial.data(), partial.size(), 1024, out));
  const MappedRobotControl m = MapRobotControl(out, Team::kBlue, SixEach, kOptions);
  ASSERT_EQ(m.errors.size(), 1u);
  EXPECT_EQ(m.errors[0].code, codes::kMissingField);
  ASSERT_EQ(m.events.size(), 1u);
  EXPECT_EQ(As<CommandEvent>(m.events[0]).robot.id, 2);
}

TEST(SslSimulationMapping, ResponseLeavesOutRobotsWhoseFeedbackTheRadioLost) {
  auto report = [](const RobotId& id) -> std::optional<RobotReport> {
    if (SixEach(id) != Presence::kOnField) return std::nullopt;
    RobotReport r;
    r.feedback_lost = id.id == 1 || id.id == 4;  // robot_response_loss drew these
    return r;
  };
  const RobotControlResponse r = BuildRobotControlResponse({0, 1, 3, 4}, Team::kYellow, report, {});
  ASSERT_EQ(r.feedback_size(), 2);
  EXPECT_EQ(r.feedback(0).id(), 0u);
  EXPECT_EQ(r.feedback(1).id(), 3u);
  EXPECT_EQ(r.errors_size(), 0);  // a lost answer is silence, not an error
  // Every answer lost: the response still comes (it carries the errors), with no feedback.
  const RobotControlResponse none = BuildRobotControlResponse(
      {1, 4}, Team::kYellow, report, {WireError{codes::kUnknownRobot, "no robot yellow 9"}});
  EXPECT_EQ(none.feedback_size(), 0);
  EXPECT_EQ(none.errors_size(), 1);
}

TEST(SslSimulationMapping, DetectionFrameInMillimetres) {
  VisionFrame f;
  f.camera_id = 1;
  f.frame_number = 42;
  f.t_capture_ns = 1'500'000'000;
  f.t_sent_ns = 1'535'000'000;
  f.balls.push_back(DetectedBall{0.25, -1.0, 0.0, 0.9, 118.6});
  f.balls.push_back(DetectedBall{0.5, 0.5, 0.0, 1.0, 0.4});
  f.robots.push_back(DetectedRobot{RobotId{Team::kBlue, 3}, 1.0, 2.0, 0.5, 1.0});
  f.robots.push_back(DetectedRobot{RobotId{Team::kYellow, 5}, -1.0, 0.0, -3.0, 1.0});
  const SSL_DetectionFrame d = ToDetectionFrame(f);
  EXPECT_TRUE(d.IsInitialized());
  EXPECT_EQ(d.camera_id(), 1u);
  EXPECT_EQ(d.frame_number(), 42u);
  EXPECT_DOUBLE_EQ(d.t_capture(), 1.5);
  EXPECT_DOUBLE_EQ(d.t_sent(), 1.535);
  ASSERT_EQ(d.balls_size(), 2);
  EXPECT_FLOAT_EQ(d.balls(0).x(), 250.0f);
  EXPECT_FLOAT_EQ(d.balls(0).y(), -1000.0f);
  ASSERT_TRUE(d.balls(0).has_area());
  EXPECT_EQ(d.balls(0).area(), 119u);  // the blob's area, whole pixels
  EXPECT_EQ(d.balls(1).area(), 0u);
  ASSERT_EQ(d.robots_blue_size(), 1);
  ASSERT_EQ(d.robots_yellow_size(), 1);
  EXPECT_EQ(d.robots_blue(0).robot_id(), 3u);
  EXPECT_FLOAT_EQ(d.robots_blue(0).x(), 1000.0f);
  EXPECT_FLOAT_EQ(d.robots_blue(0).orientation(), 0.5f);
  EXPECT_EQ(d.robots_yellow(0).robot_id(), 5u);
}

TEST(SslSimulationFraming, RoundTripInPieces) {
  const std::string a(300, 'a');  // a two-byte length prefix
  const std::string b;            // an empty message is a valid empty request
  const std::string c = "ccc";
  const std::string stream = EncodeDelimited(a) + EncodeDelimited(b) + EncodeDelimited(c);
  EXPECT_EQ(static_cast<unsigned char>(stream[0]), 0xac);  // 300 = 0b10_0101100
  EXPECT_EQ(static_cast<unsigned char>(stream[1]), 0x02);
  DelimitedDecoder d(1000);
  std::vector<std::string> got;
  std::string msg, err;
  for (char ch : stream) {  // one byte at a time: every split point
    d.Append(std::string_view(&ch, 1));
    for (;;) {
      const auto s = d.Next(msg, err);
      ASSERT_NE(s, DelimitedDecoder::Status::kError) << err;
      if (s == DelimitedDecoder::Status::kNeedMore) break;
      got.push_back(msg);
    }
  }
  EXPECT_EQ(got, (std::vector<std::string>{a, b, c}));
  EXPECT_EQ(d.Buffered(), 0u);
}

TEST(SslSimulationFraming, BadPrefixesAreFinal) {
  std::string msg, err;
  DelimitedDecoder too_long(1000);
  too_long.Append("\xff\xff\xff\xff\xff\x01");
  EXPECT_EQ(too_long.Next(msg, err), DelimitedDecoder::Status::kError);
  EXPECT_NE(err.find("prefix"), std::string::npos);
  too_long.Append(EncodeDelimited("ok"));
  EXPECT_EQ(too_long.Next(msg, err), DelimitedDecoder::Status::kError);  // stays broken

  DelimitedDecoder too_big(1000);
  too_big.Append(EncodeDelimited(std::string(1001, 'x')).substr(0, 3));  // the prefix is enough
  EXPECT_EQ(too_big.Next(msg, err), DelimitedDecoder::Status::kError);
  EXPECT_NE(err.find("larger"), std::string::npos);
}

WorldSnapshot Snap(std::int64_t step, bool contact) {
  WorldSnapshot s;
  s.step = step;
  s.sim_time_ns = step * 1'000'000;
  RobotState r;
  r.id = RobotId{Team::kBlue, 0};
  r.dribbler_ball_contact = contact;
  s.robots.push_back(r);
  return s;
}

TEST(SslSimulationBridge, KnowsRobotsAndStepLength) {
  SimBridge b;
  EXPECT_FALSE(b.HasState());
  EXPECT_EQ(b.StepNs(), 0);
  EXPECT_FALSE(b.Report(RobotId{Team::kBlue, 0}));
  b.OnPublish(Snap(5, true));
  EXPECT_TRUE(b.HasState());
  EXPECT_EQ(b.StepNs(), 1'000'000);
  ASSERT_TRUE(b.Report(RobotId{Team::kBlue, 0}));
  EXPECT_TRUE(b.Report(RobotId{Team::kBlue, 0})->dribbler_ball_contact);
  EXPECT_FALSE(b.Report(RobotId{Team::kBlue, 0})->drive);
  EXPECT_FALSE(b.Report(RobotId{Team::kBlue, 0})->feedback_lost);
  // The radio's lost answers of a step reach the report, and the next step's state replaces them.
  WorldSnapshot lost = Snap(6, true);
  for (RobotState& r : lost.robots) r.feedback_lost = true;
  b.OnPublish(lost);
  EXPECT_TRUE(b.Report(RobotId{Team::kBlue, 0})->feedback_lost);
  b.OnPublish(Snap(7, true));
  EXPECT_FALSE(b.Report(RobotId{Team::kBlue, 0})->feedback_lost);
  EXPECT_FALSE(b.Exists(RobotId{Team::kYellow, 0}));
}

TEST(SslSimulationBridge, ArmedRunCollectsFramesUntilItsLastStep) {
  SimBridge b;
  VisionFrame before;
  before.frame_number = 1;
  b.OnVisionFrame(before);  // not armed: dropped
  b.Arm(3);
  std::thread sim([&] {
    for (int i = 1; i <= 4; ++i) {
      VisionFrame f;
      f.frame_number = static_cast<std::uint32_t>(10 + i);
      b.OnVisionFrame(f);
      b.OnPublish(Snap(i, false));
    }
  });
  const auto r = b.Wait(std::chrono::seconds(5));
  sim.join();
  ASSERT_TRUE(r);
  ASSERT_EQ(r->frames.size(), 3u);  // the fourth step's frame came after the run
  EXPECT_EQ(r->frames.front().frame_number, 11u);
  EXPECT_EQ(r->frames.back().frame_number, 13u);
  EXPECT_EQ(r->step, 3);
  EXPECT_EQ(r->sim_time_ns, 3'000'000);

  b.Arm(2);
  b.OnPublish(Snap(5, false));
  EXPECT_FALSE(b.Wait(std::chrono::milliseconds(20)));  // one step short: times out
}

}  // namespace
}  // namespace ubersim::ssl_simulation
