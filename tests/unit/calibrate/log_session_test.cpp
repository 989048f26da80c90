// SPDX-License-Identifier: Apache-2.0
// Reading a field's log for calibration: camera frames of several cameras in capture order and
// SI units, the cameras' positions from the geometry, commands (local and global) on the same
// clock, a datagram recorded twice, undecodable payloads, and damaged files with their place.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "log_session.hpp"
#include "session_tracks.hpp"
#include "ssl_log.hpp"
#include "ssl_simulation_robot_control.pb.h"
#include "ssl_vision_wrapper.pb.h"
#include "vision_packets.hpp"

namespace {

namespace fs = std::filesystem;
using namespace ubersim::calibrate;

constexpr std::int64_t kUnix0 = 1'700'000'000'000'000'000LL;  // ns

fs::path TempFile(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("ubersim_log_session_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

std::string Detection(int camera, int frame, double t_capture, double latency, double ball_x_mm, double robot_x_mm) {
  SSL_WrapperPacket p;
  auto* d = p.mutable_detection();
  d->set_camera_id(camera);
  d->set_frame_number(frame);
  d->set_t_capture(t_capture);
  d->set_t_sent(t_capture + latency);
  auto* b = d->add_balls();
  b->set_confidence(0.9f);
  b->set_x(static_cast<float>(ball_x_mm));
  b->set_y(1000);
  b->set_pixel_x(0);
  b->set_pixel_y(0);
  b->set_area(80);
  auto* r = d->add_robots_blue();
  r->set_confidence(1);
  r->set_robot_id(3);
  r->set_x(static_cast<float>(robot_x_mm));
  r->set_y(-500);
  r->set_orientation(1.5f);
  r->set_pixel_x(0);
  r->set_pixel_y(0);
  return p.SerializeAsString();
}

// The geometry as ÜberSim's vision transport builds it: two cameras 6 m up over the halves.
std::string Geometry() {
  ubersim::ssl_vision::GeometryInputs in;
  in.field.field_length = 9.0;
  in.field.field_width = 6.0;
  in.field.goal_width = 1.0;
  in.field.goal_depth = 0.18;
  in.field.boundary_width = 0.3;
  in.cameras = {{0, ubersim::Vec3(-2.25, 0, 6)}, {1, ubersim::Vec3(2.25, 0, 6)}};
  return ubersim::ssl_vision::GeometryPacket(in).SerializeAsString();
}

std::string Commands(double forward, bool global) {
  RobotControl c;
  auto* r = c.add_robot_commands();
  r->set_id(3);
  if (global) {
    auto* g = r->mutable_move_command()->mutable_global_velocity();
    g->set_x(static_cast<float>(forward));
    g->set_y(0);
    g->set_angular(0);
  } else {
    auto* l = r->mutable_move_command()->mutable_local_velocity();
    l->set_forward(static_cast<float>(forward));
    l->set_left(0);
    l->set_angular(0.5f);
  }
  return c.SerializeAsString();
}

// Two cameras at 50 Hz, camera 1 half a frame after camera 0; frames written in send order. The
// commands go to a second file, as a team's software records them beside the recorder's log (in
// one file a writer would raise their stamps to the frames' later receive times).
fs::path WriteSession(const std::string& name, int frames, bool duplicate = false) {
  const fs::path file = TempFile(name);
  ubersim::sslog::LogWriter commands((file.string() + ".commands"));
  ubersim::sslog::LogWriter w(file.string());
  const double t0 = kUnix0 * 1e-9;
  w.Write(kUnix0, ubersim::sslog::MessageType::kVision2014, Geometry());
  for (int i = 0; i < frames; ++i) {
    for (int cam : {0, 1}) {
      const double t = t0 + 0.02 * i + 0.01 * cam;
      const std::int64_t received = kUnix0 + static_cast<std::int64_t>((0.02 * i + 0.01 * cam + 0.03) * 1e9);
      const std::string bytes = Detection(cam, 100 + i, t, 0.025, 1000.0 * 0.02 * i, 10.0 * i);
      w.Write(received, ubersim::sslog::MessageType::kVision2014, bytes);
      if (duplicate && i == 5 && cam == 1) w.Write(received, ubersim::sslog::MessageType::kVision2014, bytes);
    }
    commands.Write(kUnix0 + static_cast<std::int64_t>(0.02 * i * 1e9), kRobotControlBlueRecord, Commands(1.0 + i, i % 2 == 1));
  }
  w.Write(kUnix0, ubersim::sslog::MessageType::kReferee2013, "referee bytes");
  w.Close();
  return file;
}

TEST(LogSession, FramesOfAllCamerasInCaptureOrderInSiUnits) {
  const fs::path file = WriteSession("plain.log", 20);
  const LogSession s = ReadLogSession({file.string(), file.string() + ".commands"});
  ASSERT_EQ(s.frames.size(), 40u);
  for (std::size_t i = 1; i < s.frames.size(); ++i) EXPECT_LE(s.frames[i - 1].t_capture, s.frames[i].t_capture);
  EXPECT_EQ(s.frames[0].camera_id, 0);
  EXPECT_EQ(s.frames[1].camera_id, 1);
  EXPECT_NEAR(s.frames[1].t_capture, 0.01, 1e-6);
  EXPECT_NEAR(s.frames[2].t_sent - s.frames[2].t_capture, 0.025, 1e-6);
  EXPECT_NEAR(s.frames[2].t_received - s.frames[2].t_capture, 0.03, 1e-6);
  EXPECT_EQ(s.frames[2].frame_number, 101);
  ASSERT_EQ(s.frames[2].balls.size(), 1u);
  EXPECT_NEAR(s.frames[2].balls[0].x, 0.02, 1e-6);  // mm on the wire, m here
  EXPECT_NEAR(s.frames[2].balls[0].y, 1.0, 1e-6);
  EXPECT_DOUBLE_EQ(s.frames[2].balls[0].area, 80);
  ASSERT_EQ(s.frames[2].robots.size(), 1u);
  EXPECT_EQ(s.frames[2].robots[0].robot, (RobotKey{TeamColour::kBlue, 3}));
  EXPECT_NEAR(s.frames[2].robots[0].y, -0.5, 1e-6);
  EXPECT_NEAR(s.frames[2].robots[0].yaw, 1.5, 1e-6);
  ASSERT_EQ(s.cameras.size(), 2u);
  EXPECT_NEAR(s.cameras.at(1).x(), 2.25, 1e-6);
  EXPECT_NEAR(s.cameras.at(1).z(), 6.0, 1e-6);
  ASSERT_TRUE(s.field.has_value());
  EXPECT_NEAR(s.field->length, 9.0, 1e-9);
  EXPECT_EQ(s.counts.other_records, 1);
  EXPECT_EQ(s.counts.command_records, 20);
  EXPECT_NEAR(s.duration(), 0.39, 1e-6);
}

TEST(LogSession, CommandsOnTheCaptureClockAndGlobalOnesTurnedIntoTheRobotsFrame) {
  const fs::path file = WriteSession("commands.log", 20);
  const LogSession s = ReadLogSession({file.string(), file.string() + ".commands"});
  const RobotKey robot{TeamColour::kBlue, 3};
  ASSERT_EQ(s.commands.at(robot).size(), 20u);
  EXPECT_NEAR(s.commands.at(robot)[4].t, 0.08, 1e-6);
  EXPECT_NEAR(s.commands.at(robot)[4].forward, 5.0, 1e-6);
  EXPECT_NEAR(s.commands.at(robot)[4].angular, 0.5, 1e-6);
  const SessionTracks tracks = BuildTracks(s);
  const std::vector<CommandSample> local = LocalCommands(s, tracks, robot);
  ASSERT_EQ(local.size(), 20u);
  // Command 5 asked (6, 0) m/s in the field's frame of a robot heading 1.5 rad: mostly to its right.
  EXPECT_NEAR(local[5].forward, 6.0 * std::cos(1.5), 1e-5);
  EXPECT_NEAR(local[5].left, -6.0 * std::sin(1.5), 1e-5);
}

TEST(LogSession, AFrameRecordedTwiceIsKeptOnce) {
  const LogSession s = ReadLogSession({WriteSession("twice.log", 20, /*duplicate=*/true).string()});
  EXPECT_EQ(s.frames.size(), 40u);
  EXPECT_EQ(s.counts.duplicate_frames, 1);
}

TEST(LogSession, TheBallTrackLeavesAShortLivedFalseBallOut) {
  const fs::path file = TempFile("false_ball.log");
  {
    ubersim::sslog::LogWriter w(file.string());
    for (int i = 0; i < 60; ++i) {
      SSL_WrapperPacket p;
      p.ParseFromString(Detection(0, i, kUnix0 * 1e-9 + 0.02 * i, 0.02, 20.0 * i, 0));
      if (i == 30 || i == 31) {
        auto* f = p.mutable_detection()->add_balls();
        f->set_confidence(0.5f);
        f->set_x(-3000);
        f->set_y(-2000);
        f->set_pixel_x(0);
        f->set_pixel_y(0);
      }
      w.Write(kUnix0 + 20'000'000LL * i, ubersim::sslog::MessageType::kVision2014, p.SerializeAsString());
    }
  }
  const LogSession s = ReadLogSession({file.string()});
  const SessionTracks t = BuildTracks(s);
  EXPECT_EQ(t.ball.size(), 60u);
  EXPECT_EQ(t.false_balls, 2);
  for (const auto& p : t.ball) EXPECT_GT(p.x, -0.01);
  // The robot stands at (0, -0.5): the ball at (0.4, 1) is 1.56 m away.
  EXPECT_NEAR(t.NearestRobot(0.4, 0.4, 1.0), std::hypot(0.4, 1.5), 1e-6);
  EXPECT_TRUE(std::isinf(t.NearestRobot(100.0, 0, 0)));
}

TEST(LogSession, ATruncatedLogNamesTheRecordAndItsByteOffset) {
  const fs::path file = WriteSession("cut.log", 20);
  const auto size = fs::file_size(file);
  fs::resize_file(file, size - 30);
  try {
    ReadLogSession({file.string()});
    FAIL() << "a truncated log was read";
  } catch (const ubersim::sslog::LogFormatError& e) {
    EXPECT_GT(e.record_number, 1);
    EXPECT_GT(e.byte_offset, 16);
    EXPECT_NE(std::string(e.what()).find("record " + std::to_string(e.record_number) + " at byte"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

TEST(LogSession, UndecodablePayloadsAreCountedAndTooManyRefuseTheFile) {
  const fs::path few = TempFile("few_bad.log");
  {
    ubersim::sslog::LogWriter w(few.string());
    for (int i = 0; i < 30; ++i) {
      w.Write(kUnix0 + 20'000'000LL * i, ubersim::sslog::MessageType::kVision2014,
              i == 7 ? std::string("\xff\xff\xff\xff garbage", 12) : Detection(0, i, kUnix0 * 1e-9 + 0.02 * i, 0.02, 0, 0));
    }
  }
  const LogSession s = ReadLogSession({few.string()});
  EXPECT_EQ(s.frames.size(), 29u);
  EXPECT_EQ(s.counts.undecodable, 1);
  EXPECT_NE(s.counts.first_undecodable.find("record 8 at byte"), std::string::npos) << s.counts.first_undecodable;

  const fs::path many = TempFile("many_bad.log");
  {
    ubersim::sslog::LogWriter w(many.string());
    for (int i = 0; i < 30; ++i) {
      w.Write(kUnix0 + 20'000'000LL * i, ubersim::sslog::MessageType::kVision2014,
              i % 3 == 0 ? std::string("\xff\xff\xff\xff garbage", 12) : Detection(0, i, kUnix0 * 1e-9 + 0.02 * i, 0.02, 0, 0));
    }
  }
  try {
    ReadLogSession({many.string()});
    FAIL() << "a log of garbage was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("record 1 at byte 16"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("10 of 30 vision records"), std::string::npos) << e.what();
  }
}

TEST(LogSession, ALogWithoutCameraFramesSaysSo) {
  const fs::path file = TempFile("referee_only.log");
  {
    ubersim::sslog::LogWriter w(file.string());
    w.Write(kUnix0, ubersim::sslog::MessageType::kReferee2013, "x");
  }
  try {
    ReadLogSession({file.string()});
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no vision detection frame"), std::string::npos) << e.what();
  }
}

}  // namespace
