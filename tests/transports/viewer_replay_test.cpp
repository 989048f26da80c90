// SPDX-License-Identifier: Apache-2.0
// `ubersim replay FILE --viewer`: a log shown in the browser viewer with a time slider.
//
// First the log's time line (apps/cli/replay_timeline.cpp, compiled in) on logs written here:
// the cameras merged within 50 ms, the geometry in metres, the referee at most ten times a
// second, times that never go back, a damaged file. Then the command as a user runs it, on a log
// written by `ubersim run --referee builtin --record` (Division A: two cameras), talked to over
// the viewer's WebSocket as the page does: the field, positions that match the log's detections
// at a seek time, the referee state, seek, play, pause and speed, the end of the log; with --send
// the datagrams on loopback follow the slider; a damaged log gives the located error a replay
// onto the network gives. Loopback only, ports of this test's own (443xx), every run local-only.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "../common/multicast_receiver.hpp"
#include "../common/referee_messages.hpp"
#include "../common/run_ubersim.hpp"
#include "../common/temp_dir.hpp"
#include "replay_timeline.hpp"
#include "ssl_gc_referee_message.pb.h"
#include "ssl_log.hpp"
#include "ssl_vision_wrapper.pb.h"
#include "viewer_ws_client.hpp"

namespace {

namespace fs = std::filesystem;
using ubersim::cli::LogTimeline;
using ubersim::sslog::LogReader;
using ubersim::sslog::LogRecord;
using ubersim::sslog::LogWriter;
using ubersim::testing::CliResult;
using ubersim::testing::ParseJson;
using ubersim::testing::Receiver;
using ubersim::testing::RunUbersim;
using ubersim::testing::WsClient;
using namespace std::chrono_literals;

constexpr std::int64_t kT0 = 1'700'000'000'000'000'000;  // Unix ns of the logs written here
constexpr std::int64_t kMs = 1'000'000;

fs::path TempDir() { return ubersim::testing::ProcessTempDir("ubersim_viewer_replay_test"); }
[[maybe_unused]] ::testing::Environment* const kRemoveTempDir =
    ::testing::AddGlobalTestEnvironment(new ubersim::testing::RemoveDirAtEnd(TempDir()));

std::string ReadBytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// ---------------------------------------------------------------------------------------------
// Packets for the logs written here (mm, as on the wire).

struct Seen {
  const char* team;  // "blue", "yellow"
  int id;
  double x, y;  // mm
  std::optional<double> yaw;
  double confidence = 1.0;
};

std::string VisionFrame(int camera, std::uint32_t number, const std::vector<Seen>& robots,
                        const std::vector<std::pair<double, double>>& balls = {}) {
  SSL_WrapperPacket p;
  SSL_DetectionFrame* f = p.mutable_detection();
  f->set_frame_number(number);
  f->set_t_capture(1.0);
  f->set_t_sent(1.0);
  f->set_camera_id(static_cast<std::uint32_t>(camera));
  for (const auto& [x, y] : balls) {
    SSL_DetectionBall* b = f->add_balls();
    b->set_confidence(0.9f);
    b->set_x(static_cast<float>(x));
    b->set_y(static_cast<float>(y));
    b->set_pixel_x(0);
    b->set_pixel_y(0);
  }
  for (const Seen& s : robots) {
    SSL_DetectionRobot* r = std::string(s.team) == "blue" ? f->add_robots_blue() : f->add_robots_yellow();
    r->set_confidence(static_cast<float>(s.confidence));
    r->set_robot_id(static_cast<std::uint32_t>(s.id));
    r->set_x(static_cast<float>(s.x));
    r->set_y(static_cast<float>(s.y));
    if (s.yaw) r->set_orientation(static_cast<float>(*s.yaw));
    r->set_pixel_x(0);
    r->set_pixel_y(0);
  }
  return p.SerializeAsString();
}

std::string GeometryPacket(int field_length_mm, int camera_x_mm) {
  SSL_WrapperPacket p;
  SSL_GeometryFieldSize* f = p.mutable_geometry()->mutable_field();
  f->set_field_length(field_length_mm);
  f->set_field_width(9000);
  f->set_goal_width(1800);
  f->set_goal_depth(180);
  f->set_boundary_width(300);
  f->set_penalty_area_depth(1800);
  f->set_penalty_area_width(3600);
  f->set_ball_radius(21.5f);
  f->set_max_robot_radius(90);
  SSL_FieldLineSegment* l = f->add_field_lines();
  l->set_name("TopTouchLine");
  l->mutable_p1()->set_x(-6000);
  l->mutable_p1()->set_y(4500);
  l->mutable_p2()->set_x(6000);
  l->mutable_p2()->set_y(4500);
  l->set_thickness(10);
  SSL_FieldCircularArc* a = f->add_field_arcs();
  a->set_name("CenterCircle");
  a->mutable_center()->set_x(0);
  a->mutable_center()->set_y(0);
  a->set_radius(500);
  a->set_a1(0);
  a->set_a2(6.2831855f);
  a->set_thickness(10);
  SSL_GeometryCameraCalibration* c = p.mutable_geometry()->add_calib();
  c->set_camera_id(1);
  c->set_focal_length(500);
  c->set_principal_point_x(390);
  c->set_principal_point_y(290);
  c->set_distortion(0);
  c->set_q0(0);
  c->set_q1(0);
  c->set_q2(0);
  c->set_q3(1);
  c->set_tx(0);
  c->set_ty(0);
  c->set_tz(0);
  c->set_derived_camera_world_tx(static_cast<float>(camera_x_mm));
  c->set_derived_camera_world_ty(0);
  c->set_derived_camera_world_tz(6000);
  return p.SerializeAsString();
}

std::string RefereeMessage(std::uint32_t counter, std::int64_t stage_time_left_us, bool with_event = false) {
  Referee r = ubersim::testing::HaltedReferee(1, "Y", "B");
  r.set_stage(Referee::NORMAL_FIRST_HALF);
  r.set_stage_time_left(stage_time_left_us);
  r.set_command(Referee::STOP);
  r.set_command_counter(counter);
  if (with_event) {
    GameEvent* e = r.add_game_events();
    e->set_type(GameEvent::BALL_LEFT_FIELD_TOUCH_LINE);
    e->mutable_ball_left_field_touch_line()->set_by_team(YELLOW);
    e->mutable_ball_left_field_touch_line()->set_by_bot(3);
  }
  return r.SerializeAsString();
}

fs::path WriteLog(const std::string& name, const std::vector<LogRecord>& records) {
  const fs::path file = TempDir() / name;
  LogWriter writer(file.string());
  for (const LogRecord& r : records) writer.Write(r.timestamp_ns, r.type, r.payload);
  writer.Close();
  return file;
}

const ubersim::viewer::RobotSample* RobotIn(const ubersim::viewer::WorldSample& s, ubersim::Team team, int id) {
  for (const auto& r : s.robots) {
    if (r.id.team == team && r.id.id == id) return &r;
  }
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
// The time line

TEST(ReplayTimeline, MergesEachCamerasLatestFrameWithinFiftyMilliseconds) {
  const fs::path file = WriteLog(
      "merge.log",
      {
          // Camera 0 at 0 ms: blue 1 twice (the more confident counts), a yellow robot, the ball.
          {kT0, 4,
           VisionFrame(0, 100,
                       {{"blue", 1, 1000, 0, 3.1, 1.0}, {"blue", 1, 3000, 0, 0.0, 0.2}, {"yellow", 2, -500, 200, 1.0}},
                       {{100, 50}})},
          // Camera 1 at 10 ms: blue 1 a centimetre on, its heading across ±π; a ball 5 cm off the first.
          {kT0 + 10 * kMs, 4, VisionFrame(1, 200, {{"blue", 1, 1010, 0, -3.1, 1.0}}, {{150, 50}})},
          // Camera 1 at 40 ms: blue 3 without a heading.
          {kT0 + 40 * kMs, 4, VisionFrame(1, 201, {{"blue", 3, 0, -1000, std::nullopt}})},
      });
  const auto tl = LogTimeline::Load(file.string());
  ASSERT_FALSE(tl->Damage()) << tl->Damage()->what();
  EXPECT_EQ(tl->DurationNs(), 40 * kMs);
  EXPECT_EQ(tl->FirstUnixNs(), kT0);
  EXPECT_EQ(tl->Count().vision_frames, 3);
  EXPECT_EQ(tl->Count().detections, 7);

  ubersim::viewer::WorldSample s;
  std::vector<ubersim::VisionFrame> frames;
  // At 20 ms both cameras' frames count: blue 1 halfway between them, heading π (not 0).
  tl->SampleAt(20 * kMs, s, frames);
  EXPECT_EQ(s.sim_time_ns, 20 * kMs);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].camera_id, 0);
  EXPECT_EQ(frames[0].frame_number, 100u);
  EXPECT_EQ(frames[0].robots.size(), 3u) << "the page's Cameras overlay gets every detection";
  EXPECT_EQ(frames[1].t_capture_ns, 10 * kMs) << "a frame's time on the log's time line";
  ASSERT_EQ(s.robots.size(), 2u);
  const auto* blue1 = RobotIn(s, ubersim::Team::kBlue, 1);
  ASSERT_TRUE(blue1);
  EXPECT_NEAR(blue1->x, 1.005, 1e-6);
  EXPECT_NEAR(blue1->y, 0.0, 1e-6);
  EXPECT_NEAR(std::abs(blue1->yaw), M_PI, 1e-3);
  EXPECT_TRUE(std::isnan(blue1->vx)) << "a detection has no velocity";
  EXPECT_NEAR(blue1->radius, 0.09, 1e-9) << "no geometry: the default robot radius";
  EXPECT_EQ(s.robots[0].id.team, ubersim::Team::kBlue) << "blue first";
  const auto* yellow2 = RobotIn(s, ubersim::Team::kYellow, 2);
  ASSERT_TRUE(yellow2);
  EXPECT_NEAR(yellow2->x, -0.5, 1e-6);
  EXPECT_NEAR(yellow2->yaw, 1.0, 1e-4);
  // The ball: both cameras' detections, 5 cm apart, averaged; lifted to lie on the carpet.
  EXPECT_NEAR(s.ball_position.x(), 0.125, 1e-6);
  EXPECT_NEAR(s.ball_position.y(), 0.05, 1e-6);
  EXPECT_NEAR(s.ball_position.z(), 0.0215, 1e-9);

  // At 55 ms camera 0's frame is 55 ms old: out of the window; camera 1's latest is its second.
  tl->SampleAt(55 * kMs, s, frames);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].frame_number, 201u);
  ASSERT_EQ(s.robots.size(), 1u);
  EXPECT_EQ(s.robots[0].id.id, 3);
  EXPECT_TRUE(std::isnan(s.robots[0].yaw)) << "no heading seen";
  EXPECT_TRUE(std::isnan(s.ball_position.x())) << "nobody sees the ball";
  // Before the first frame and 50 ms after the last, nothing.
  tl->SampleAt(-1, s, frames);
  EXPECT_TRUE(s.robots.empty() && frames.empty());
  tl->SampleAt(91 * kMs, s, frames);
  EXPECT_TRUE(s.robots.empty() && frames.empty());
  EXPECT_EQ(tl->FramesBetween(0, 40 * kMs), 2);
  EXPECT_EQ(tl->FramesBetween(-1, 40 * kMs), 3);
}

TEST(ReplayTimeline, TheGeometryInMetresEachDistinctOneFromWhenItCame) {
  const fs::path file = WriteLog("geometry.log", {
                                                     {kT0, 4, VisionFrame(0, 1, {{"blue", 0, 0, 0, 0.0}})},
                                                     {kT0 + 1000 * kMs, 4, GeometryPacket(12000, 3000)},
                                                     {kT0 + 2000 * kMs, 4, GeometryPacket(12000, 3000)},
                                                     {kT0 + 5000 * kMs, 4, GeometryPacket(9000, -2000)},
                                                 });
  const auto tl = LogTimeline::Load(file.string());
  EXPECT_EQ(tl->Count().geometries, 3);
  std::size_t index = 99;
  // Before the first geometry came, the first one: the field does not change when it arrives.
  const LogTimeline::Geometry& first = tl->GeometryAt(0, &index);
  EXPECT_EQ(index, 0u);
  EXPECT_DOUBLE_EQ(first.field.field_length, 12.0);
  EXPECT_DOUBLE_EQ(first.field.field_width, 9.0);
  EXPECT_DOUBLE_EQ(first.field.carpet_length, 12.6);
  EXPECT_DOUBLE_EQ(first.field.carpet_width, 9.6);
  EXPECT_DOUBLE_EQ(first.field.penalty_area_depth, 1.8);
  ASSERT_EQ(first.field.lines.size(), 1u);
  EXPECT_DOUBLE_EQ(first.field.lines[0].x1, -6.0);
  EXPECT_DOUBLE_EQ(first.field.lines[0].thickness, 0.01);
  ASSERT_EQ(first.field.arcs.size(), 1u);
  EXPECT_DOUBLE_EQ(first.field.arcs[0].radius, 0.5);
  ASSERT_EQ(first.cameras.size(), 1u);
  EXPECT_EQ(first.cameras[0].id, 1);
  EXPECT_DOUBLE_EQ(first.cameras[0].position.x(), 3.0);
  EXPECT_DOUBLE_EQ(first.cameras[0].position.z(), 6.0);
  EXPECT_NEAR(first.ball_radius, 0.0215, 1e-9);
  // The same geometry again is not kept; a different one is, from when it came.
  EXPECT_EQ(&tl->GeometryAt(4999 * kMs, &index), &first);
  const LogTimeline::Geometry& second = tl->GeometryAt(5000 * kMs, &index);
  EXPECT_EQ(index, 1u);
  EXPECT_DOUBLE_EQ(second.field.field_length, 9.0);
  EXPECT_DOUBLE_EQ(second.cameras.at(0).position.x(), -2.0);

  // Without geometry: Division B's field.
  const auto none = LogTimeline::Load(WriteLog("no-geometry.log", {{kT0, 4, VisionFrame(0, 1, {})}}).string());
  EXPECT_DOUBLE_EQ(none->GeometryAt(0).field.field_length, 9.0);
  EXPECT_DOUBLE_EQ(none->GeometryAt(0).field.carpet_width, 6.6);
}

TEST(ReplayTimeline, TheRefereeAtMostTenTimesASecondTheNewestAndTheLastKept) {
  // 40 messages a second for 1 s, the stage clock counting down; an event in the tenth.
  std::vector<LogRecord> records;
  for (int i = 0; i < 40; ++i) {
    records.push_back({kT0 + i * 25 * kMs, 3, RefereeMessage(i < 20 ? 1 : 2, 300'000'000 - i * 25'000, i == 9)});
  }
  records.push_back({kT0 + 1000 * kMs, 3, "not a Referee message"});
  const auto tl = LogTimeline::Load(WriteLog("referee.log", records).string());
  EXPECT_EQ(tl->Count().referee_messages, 40);
  EXPECT_EQ(tl->Count().undecodable, 1);
  EXPECT_GE(tl->Count().referee_states, 10);
  EXPECT_LE(tl->Count().referee_states, 11);
  std::size_t index = 99;
  EXPECT_EQ(tl->RefereeAt(-1, &index), "");
  EXPECT_EQ(index, 0u);
  // At any time: a message from at most 100 ms before it (plus one message's spacing).
  for (std::int64_t t = 0; t <= 975 * kMs; t += 5 * kMs) {
    const rapidjson::Document d = ParseJson(tl->RefereeAt(t));
    ASSERT_TRUE(d.IsObject()) << t;
    EXPECT_STREQ(d["type"].GetString(), "referee");
    const double left = d["stage_time_left"].GetDouble();  // s
    const double sent_at_ms = (300.0 - left) / 0.025 * 25;  // which message: its time
    EXPECT_LE(sent_at_ms, static_cast<double>(t) / kMs + 1e-6) << t;
    EXPECT_GE(sent_at_ms, static_cast<double>(t) / kMs - 125 - 1e-6) << t;
    EXPECT_EQ(d["command_counter"].GetUint(), sent_at_ms < 500 ? 1u : 2u) << t;
  }
  // The last message is kept, however soon after the one before.
  EXPECT_DOUBLE_EQ(ParseJson(tl->RefereeAt(1000 * kMs))["stage_time_left"].GetDouble(), 300.0 - 39 * 0.025);
  // The event of the tenth message stays as the last one after it ("current": false), as live.
  const rapidjson::Document later = ParseJson(tl->RefereeAt(900 * kMs));
  ASSERT_TRUE(later["game_event"].IsObject());
  EXPECT_STREQ(later["game_event"]["type"].GetString(), "BALL_LEFT_FIELD_TOUCH_LINE");
  EXPECT_FALSE(later["game_event"]["current"].GetBool());
  // Messages every 25 ms: never silent; 2 s after the last, 2 s.
  EXPECT_EQ(tl->RefereeAgeAt(500 * kMs), 0);
  EXPECT_EQ(tl->RefereeAgeAt(2975 * kMs), 2000 * kMs);
  EXPECT_FALSE(tl->RefereeAgeAt(-1));
}

TEST(ReplayTimeline, TimeNeverGoesBackAndCheckpointsComeBeforeTheirTime) {
  // Time stamps that go back (a recorder's clock set back) count as the one before; records of
  // other types have no time; checkpoints every second of it.
  std::vector<LogRecord> records;
  std::int64_t ts = kT0;
  for (int i = 0; i < 100; ++i) {
    ts += (i % 10 == 9) ? -300 * kMs : 100 * kMs;
    records.push_back({ts, i % 7 == 3 ? 1002 : 4, VisionFrame(0, static_cast<std::uint32_t>(i), {})});
  }
  const fs::path file = WriteLog("time.log", records);
  const auto tl = LogTimeline::Load(file.string());
  EXPECT_EQ(tl->Count().records, 100);
  // The records' times as the time line counts them, and each record's offset.
  std::vector<std::int64_t> times, offsets;
  std::int64_t last = 0;
  std::optional<std::int64_t> first;
  LogReader reader(file.string());
  while (auto r = reader.Next()) {
    offsets.push_back(reader.RecordOffset());
    if (r->type != 4) {
      times.push_back(-1);
      continue;
    }
    if (!first) first = r->timestamp_ns;
    last = std::max(last, r->timestamp_ns - *first);
    times.push_back(last);
  }
  EXPECT_EQ(tl->DurationNs(), last);
  // For any t, the checkpoint's record has no earlier time after it... and every record before
  // it is earlier than t: the wire playback starts there and loses nothing.
  for (std::int64_t t = 0; t <= last; t += 50 * kMs) {
    const LogTimeline::Checkpoint& cp = tl->CheckpointAt(t);
    EXPECT_LE(cp.t_ns, t);
    EXPECT_GE(cp.t_ns, t - 1500 * kMs) << "a checkpoint every second";
    ASSERT_LT(cp.records_before, static_cast<std::int64_t>(offsets.size()));
    EXPECT_EQ(offsets[cp.records_before], cp.offset);
    EXPECT_EQ(times[cp.records_before], cp.t_ns);
    for (std::int64_t i = 0; i < cp.records_before; ++i) EXPECT_LT(times[i], t) << "record " << i + 1;
  }
}

TEST(ReplayTimeline, ADamagedFileKeepsWhatCameBeforeAndSaysWhere) {
  std::vector<LogRecord> records;
  for (int i = 0; i < 10; ++i) {
    records.push_back({kT0 + i * 100 * kMs, 4, VisionFrame(0, i, {{"blue", 0, i * 10.0, 0, 0.0}})});
  }
  const fs::path whole = WriteLog("whole.log", records);
  const std::string bytes = ReadBytes(whole);
  const fs::path cut = TempDir() / "cut.log";
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() - 5);
  std::string expected;
  try {
    LogReader reader(cut.string());
    while (reader.Next()) {
    }
  } catch (const ubersim::sslog::LogFormatError& e) {
    expected = e.what();
  }
  ASSERT_FALSE(expected.empty());
  const auto tl = LogTimeline::Load(cut.string());
  ASSERT_TRUE(tl->Damage());
  EXPECT_EQ(tl->Damage()->what(), expected);
  EXPECT_EQ(tl->Damage()->record_number, 10);
  EXPECT_EQ(tl->Count().vision_frames, 9);
  EXPECT_EQ(tl->DurationNs(), 800 * kMs);
  EXPECT_THROW(LogTimeline::Load((TempDir() / "missing.log").string()), std::runtime_error);
}

// ---------------------------------------------------------------------------------------------
// `ubersim replay LOG --viewer`, as a user runs it

// `ubersim ARGS` in the background, its output in a file; SIGINT ends it as Ctrl-C does.
class Background {
 public:
  explicit Background(const std::string& args) : output_(TempDir() / ("ubersim-" + std::to_string(++count_) + ".txt")) {
    const std::string cmd = "exec " UBERSIM_BINARY_DIR "/bin/ubersim " + args + " > " + output_.string() + " 2>&1";
    pid_ = ::fork();
    if (pid_ == 0) {
      ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
  }
  ~Background() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Background(const Background&) = delete;
  Background& operator=(const Background&) = delete;

  std::string Output() const { return ReadBytes(output_); }
  // Waits until the output holds `text` (or the process ended, or 60 s passed).
  bool WaitFor(const std::string& text) {
    const auto until = std::chrono::steady_clock::now() + 60s;
    while (std::chrono::steady_clock::now() < until) {
      if (Output().find(text) != std::string::npos) return true;
      if (pid_ > 0 && ::waitpid(pid_, &status_, WNOHANG) == pid_) {
        pid_ = -1;
        return Output().find(text) != std::string::npos;
      }
      std::this_thread::sleep_for(20ms);
    }
    return false;
  }
  // SIGINT, then its exit code (-1: it had to be killed).
  int Interrupt() {
    if (pid_ > 0) {
      ::kill(pid_, SIGINT);
      const auto until = std::chrono::steady_clock::now() + 20s;
      while (::waitpid(pid_, &status_, WNOHANG) != pid_) {
        if (std::chrono::steady_clock::now() > until) {
          ::kill(pid_, SIGKILL);
          ::waitpid(pid_, &status_, 0);
          pid_ = -1;
          return -1;
        }
        std::this_thread::sleep_for(10ms);
      }
      pid_ = -1;
    }
    return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
  }

 private:
  static inline int count_ = 0;
  fs::path output_;
  pid_t pid_ = -1;
  int status_ = 0;
};

// A TCP port free on loopback now.
std::uint16_t FreeTcpPort() {
  boost::asio::io_context io;
  boost::asio::ip::tcp::acceptor a(io, {boost::asio::ip::make_address("127.0.0.1"), 0});
  return a.local_endpoint().port();
}

// The log as the test reads it, independently of the time line: vision frames and Referee
// messages at their time (ns since the first record of types 2 to 5, never going back).
struct ReadLog {
  struct Frame {
    std::int64_t t;
    SSL_DetectionFrame detection;
  };
  std::vector<Frame> frames;
  std::vector<std::pair<std::int64_t, Referee>> referee;
  std::vector<std::pair<std::int64_t, std::string>> vision_payloads;
  std::optional<SSL_GeometryData> geometry;
  std::int64_t duration = 0;

  explicit ReadLog(const fs::path& file) {
    LogReader reader(file.string());
    std::optional<std::int64_t> first;
    std::int64_t t = 0;
    while (auto r = reader.Next()) {
      if (r->type < 2 || r->type > 5) continue;
      if (!first) first = r->timestamp_ns;
      t = std::max(t, r->timestamp_ns - *first);
      if (r->type == 4) {
        vision_payloads.emplace_back(t, r->payload);
        SSL_WrapperPacket p;
        EXPECT_TRUE(p.ParseFromString(r->payload));
        if (p.has_geometry() && !geometry) geometry = p.geometry();
        if (p.has_detection()) frames.push_back({t, p.detection()});
      } else if (r->type == 3) {
        Referee m;
        EXPECT_TRUE(m.ParseFromString(r->payload));
        referee.emplace_back(t, m);
      }
    }
    duration = t;
  }

  // What the page should show at t: each camera's latest frame within 50 ms, each robot's
  // detections (the most confident per camera) averaged by confidence. {"blue 3": (x, y) m}.
  std::map<std::string, std::pair<double, double>> RobotsAt(std::int64_t t) const {
    std::map<int, const SSL_DetectionFrame*> latest;
    for (const Frame& f : frames) {
      if (f.t <= t && t - f.t <= 50 * kMs) latest[static_cast<int>(f.detection.camera_id())] = &f.detection;
    }
    std::map<std::string, std::tuple<double, double, double>> sums;  // w, wx, wy
    for (const auto& [camera, d] : latest) {
      std::map<std::string, const SSL_DetectionRobot*> best;
      for (const auto& [team, robots] :
           {std::pair{"blue", &d->robots_blue()}, std::pair{"yellow", &d->robots_yellow()}}) {
        for (const SSL_DetectionRobot& r : *robots) {
          const std::string key = std::string(team) + " " + std::to_string(r.robot_id());
          if (!best[key] || r.confidence() > best[key]->confidence()) best[key] = &r;
        }
      }
      for (const auto& [key, r] : best) {
        auto& [w, x, y] = sums[key];
        const double c = std::max(1.0, std::round(static_cast<double>(r->confidence()) * 255));
        w += c;
        x += c * r->x() / 1000;
        y += c * r->y() / 1000;
      }
    }
    std::map<std::string, std::pair<double, double>> out;
    for (const auto& [key, s] : sums) out[key] = {std::get<1>(s) / std::get<0>(s), std::get<2>(s) / std::get<0>(s)};
    return out;
  }
};

class ReplayViewer : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    log_ = new fs::path(TempDir() / "match.log.gz");
    // Division A: two cameras, their images overlapping at the halfway line. Its own ports, no viewer.
    const CliResult r = RunUbersim(
        "run div-a --local-only --no-viewer --no-transport ssl_simulation --no-transport grsim --fast --duration 12 "
        "-q --referee builtin --tracker --vision-port 44306 --referee-port 44303 --tracker-port 44310 --record " +
        log_->string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    read_ = new ReadLog(*log_);
  }
  static void TearDownTestSuite() {
    delete read_;
    delete log_;
  }

  // Reads states until one is at t (s) and paused; nullopt if none in 300 messages. The last
  // referee message read on the way goes to `referee`.
  static std::optional<rapidjson::Document> StateAt(WsClient& page, double t, rapidjson::Document* referee = nullptr) {
    for (int i = 0; i < 300; ++i) {
      rapidjson::Document d = ParseJson(page.Read());
      if (referee && std::string(d["type"].GetString()) == "referee") referee->CopyFrom(d, referee->GetAllocator());
      if (std::string(d["type"].GetString()) != "state") continue;
      const auto& r = d["status"]["replay"];
      if (!r["playing"].GetBool() && std::abs(r["t"].GetDouble() - t) < 1e-3) return d;
    }
    return std::nullopt;
  }

  // The next state (skipping other messages).
  static rapidjson::Document NextState(WsClient& page) { return page.ReadType("state"); }

  // The last state of those that arrive in the next `wall` seconds: reading all the while, so
  // what the sockets' buffers held from before is read too, and the last one is fresh.
  static rapidjson::Document LatestStateAfter(WsClient& page, std::chrono::milliseconds wall) {
    const auto until = std::chrono::steady_clock::now() + wall;
    rapidjson::Document last = NextState(page);
    while (std::chrono::steady_clock::now() < until) last = NextState(page);
    return last;
  }

  static inline fs::path* log_ = nullptr;
  static inline ReadLog* read_ = nullptr;
};

TEST_F(ReplayViewer, ThePageGetsTheFieldThePositionsAtASeekTimeAndTheMatch) {
  ASSERT_TRUE(read_->geometry);
  ASSERT_GE(read_->frames.size(), 1000u);
  const std::uint16_t port = FreeTcpPort();
  Background replay("replay " + log_->string() + " --viewer --viewer-port " + std::to_string(port) + " --local-only");
  ASSERT_TRUE(replay.WaitFor("(open it in a browser; Ctrl-C stops)")) << replay.Output();
  EXPECT_NE(replay.Output().find("nothing is sent (add --send to send it too)"), std::string::npos) << replay.Output();
  EXPECT_NE(replay.Output().find("viewer: http://127.0.0.1:" + std::to_string(port) + "/"), std::string::npos);
  WsClient page(port);

  // The hello: the log's field in metres, its cameras, the replay's duration.
  const rapidjson::Document hello = page.ReadType("hello");
  const SSL_GeometryFieldSize& f = read_->geometry->field();
  EXPECT_DOUBLE_EQ(hello["field"]["field_length"].GetDouble(), f.field_length() / 1000.0);
  EXPECT_DOUBLE_EQ(hello["field"]["field_width"].GetDouble(), f.field_width() / 1000.0);
  EXPECT_DOUBLE_EQ(hello["field"]["goal_width"].GetDouble(), f.goal_width() / 1000.0);
  EXPECT_DOUBLE_EQ(hello["field"]["carpet_length"].GetDouble(), (f.field_length() + 2 * f.boundary_width()) / 1000.0);
  EXPECT_EQ(hello["field"]["lines"].Size(), static_cast<unsigned>(f.field_lines_size()));
  EXPECT_EQ(hello["field"]["arcs"].Size(), static_cast<unsigned>(f.field_arcs_size()));
  EXPECT_EQ(hello["cameras"].Size(), static_cast<unsigned>(read_->geometry->calib_size()));
  ASSERT_TRUE(hello.HasMember("replay"));
  EXPECT_STREQ(hello["replay"]["file"].GetString(), "match.log.gz");
  EXPECT_NEAR(hello["replay"]["duration"].GetDouble(), static_cast<double>(read_->duration) * 1e-9, 1e-6);
  EXPECT_FALSE(hello["replay"]["sending"].GetBool());
  EXPECT_TRUE(hello["referee"].IsString()) << "the log has Referee messages: the page shows the match";

  // Paused at 7.5 s, then at 3.25 s: the robots where the cameras saw them then.
  page.Send(R"({"cmd":"pause","id":1})");
  rapidjson::Document referee;
  for (const double seek : {7.5, 3.25}) {
    page.Send(R"({"cmd":"seek","t":)" + std::to_string(seek) + "}");
    const auto state = StateAt(page, seek, &referee);
    ASSERT_TRUE(state) << "no paused state at " << seek << " s";
    EXPECT_NEAR((*state)["t"].GetDouble(), seek, 1e-4);
    const auto expected = read_->RobotsAt(static_cast<std::int64_t>(seek * 1e9));
    ASSERT_GE(expected.size(), 20u) << "Division A: 22 robots, nearly all seen";
    std::set<std::string> shown;
    for (const auto& r : (*state)["robots"].GetArray()) {
      const std::string key = std::string(r["team"].GetString()) + " " + std::to_string(r["id"].GetInt());
      shown.insert(key);
      ASSERT_TRUE(expected.count(key)) << key << " at " << seek << " s";
      EXPECT_NEAR(r["x"].GetDouble(), expected.at(key).first, 0.0015) << key << " at " << seek << " s";
      EXPECT_NEAR(r["y"].GetDouble(), expected.at(key).second, 0.0015) << key << " at " << seek << " s";
      EXPECT_TRUE(r["vx"].IsNull());
    }
    EXPECT_EQ(shown.size(), expected.size()) << "at " << seek << " s";
    EXPECT_EQ((*state)["vision"].Size(), 2u) << "both cameras' frames, for the Cameras overlay";
    EXPECT_TRUE((*state)["ball"]["x"].IsNumber());
    EXPECT_FALSE((*state)["status"]["paused"].IsFalse());
  }
  // Noise: the two times' detections differ, so matching both shows the seek found its frames.
  EXPECT_NE(read_->RobotsAt(7'500'000'000), read_->RobotsAt(3'250'000'000));

  // The match at 3.25 s: a Referee message of the log from at most 100 ms (and one message) before.
  ASSERT_TRUE(referee.IsObject() && referee.HasMember("stage_time_left")) << "no referee message";
  // A page that connects now gets the same at once, after the hello.
  WsClient second(port);
  second.ReadType("hello");
  const rapidjson::Document caught_up = second.ReadType("referee");
  EXPECT_TRUE(caught_up == referee) << "a new page's match is not the one shown";
  const double left = referee["stage_time_left"].GetDouble();
  bool found = false;
  for (const auto& [t, m] : read_->referee) {
    if (t <= 3'250'000'000 && t >= 3'250'000'000 - 130 * kMs &&
        std::abs(static_cast<double>(m.stage_time_left()) * 1e-6 - left) < 1e-6) {
      found = true;
      EXPECT_EQ(referee["command_counter"].GetUint(), m.command_counter());
      EXPECT_STREQ(referee["command"].GetString(), Referee::Command_Name(m.command()).c_str());
      EXPECT_STREQ(referee["stage"].GetString(), Referee::Stage_Name(m.stage()).c_str());
    }
  }
  EXPECT_TRUE(found) << "stage_time_left " << left << " s is no Referee message's of the 130 ms before 3.25 s";
  replay.Interrupt();
}

TEST_F(ReplayViewer, PlayPauseSpeedAndTheEndOfTheLog) {
  const std::uint16_t port = FreeTcpPort();
  Background replay("replay " + log_->string() + " --viewer --viewer-port " + std::to_string(port) +
                    " --local-only --speed 2");
  ASSERT_TRUE(replay.WaitFor("(open it in a browser; Ctrl-C stops)")) << replay.Output();
  WsClient page(port);
  page.ReadType("hello");
  // It plays at once, at --speed.
  rapidjson::Document s = NextState(page);
  EXPECT_TRUE(s["status"]["replay"]["playing"].GetBool());
  EXPECT_DOUBLE_EQ(s["status"]["replay"]["speed"].GetDouble(), 2.0);

  // Paused: time stands still.
  page.Send(R"({"cmd":"pause"})");
  ASSERT_STREQ(page.ReadType("ack")["cmd"].GetString(), "pause");
  const double paused_at = LatestStateAfter(page, 100ms)["status"]["replay"]["t"].GetDouble();
  s = LatestStateAfter(page, 300ms);
  EXPECT_FALSE(s["status"]["replay"]["playing"].GetBool());
  EXPECT_DOUBLE_EQ(s["status"]["replay"]["t"].GetDouble(), paused_at);
  EXPECT_TRUE(s["status"]["paused"].GetBool());

  // Played at 4 times the recorded rate: the log's time runs four times as fast as the wall's.
  page.Send(R"({"cmd":"speed","factor":4})");
  page.Send(R"({"cmd":"play"})");
  EXPECT_STREQ(page.ReadType("ack")["cmd"].GetString(), "speed");
  EXPECT_STREQ(page.ReadType("ack")["cmd"].GetString(), "play");
  s = LatestStateAfter(page, 100ms);
  const auto wall0 = std::chrono::steady_clock::now();
  const double t0 = s["status"]["replay"]["t"].GetDouble();
  s = LatestStateAfter(page, 600ms);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const double rate = (s["status"]["replay"]["t"].GetDouble() - t0) / wall;
  EXPECT_TRUE(s["status"]["replay"]["playing"].GetBool());
  EXPECT_DOUBLE_EQ(s["status"]["replay"]["speed"].GetDouble(), 4.0);
  EXPECT_GT(rate, 3.0) << "log s per wall s";
  EXPECT_LT(rate, 4.6) << "log s per wall s";

  // At the end it stops there; play starts it again from the beginning.
  const double duration = static_cast<double>(read_->duration) * 1e-9;
  page.Send(R"({"cmd":"seek","t":)" + std::to_string(duration - 0.2) + "}");
  ASSERT_TRUE(StateAt(page, duration)) << "no state stopped at the end";
  page.Send(R"({"cmd":"play"})");
  s = NextState(page);
  for (int i = 0; i < 50 && !s["status"]["replay"]["playing"].GetBool(); ++i) s = NextState(page);
  EXPECT_TRUE(s["status"]["replay"]["playing"].GetBool());
  EXPECT_LT(s["status"]["replay"]["t"].GetDouble(), 1.0);

  // What would change a world is refused, saying why; a bad speed too.
  page.Send(R"({"cmd":"move","target":"ball","x":0,"y":0,"id":9})");
  rapidjson::Document e = page.ReadType("error");
  EXPECT_EQ(e["id"].GetInt(), 9);
  EXPECT_NE(std::string(e["message"].GetString()).find("a replay shows a log as it was recorded"), std::string::npos);
  page.Send(R"({"cmd":"speed","factor":100})");
  EXPECT_NE(std::string(page.ReadType("error")["message"].GetString()).find("0.25 to 8"), std::string::npos);

  EXPECT_EQ(replay.Interrupt(), 0) << replay.Output();
  EXPECT_NE(replay.Output().find("loaded " + log_->string() + ": "), std::string::npos) << replay.Output();
}

TEST_F(ReplayViewer, WithSendTheDatagramsFollowTheSlider) {
  const std::uint16_t port = FreeTcpPort();
  const int vision_port = 44326;
  Receiver vision(vision_port, {"224.5.23.2"});
  ASSERT_TRUE(vision.Ok());
  Background replay("replay " + log_->string() + " --viewer --send --viewer-port " + std::to_string(port) +
                    " --local-only --vision-port " + std::to_string(vision_port) +
                    " --referee-port 44323 --tracker-port 44330 --vision-legacy-port 44325");
  ASSERT_TRUE(replay.WaitFor("(open it in a browser; Ctrl-C stops)")) << replay.Output();
  EXPECT_NE(replay.Output().find("vision (type 4): udp multicast 224.5.23.2:44326 via lo 127.0.0.1 (local only)"),
            std::string::npos)
      << replay.Output();
  WsClient page(port);
  EXPECT_TRUE(page.ReadType("hello")["replay"]["sending"].GetBool());
  // It sends at once, from the start: the log's first vision datagrams.
  const auto first = vision.Receive(5, std::chrono::steady_clock::now() + 5s);
  ASSERT_EQ(first.size(), 5u);
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_TRUE(first[i] == read_->vision_payloads[i].second) << i;

  // Paused: nothing goes out.
  page.Send(R"({"cmd":"pause"})");
  page.ReadType("ack");
  std::this_thread::sleep_for(200ms);
  vision.Receive(100000, std::chrono::steady_clock::now());  // what went out before the pause
  page.Send(R"({"cmd":"seek","t":6})");
  page.ReadType("ack");
  EXPECT_TRUE(vision.Receive(1, std::chrono::steady_clock::now() + 300ms).empty()) << "sent while paused";

  // Played from 6 s: the log's vision datagrams from 6 s on, in order, none skipped.
  page.Send(R"({"cmd":"play"})");
  const auto got = vision.Receive(40, std::chrono::steady_clock::now() + 10s);
  ASSERT_EQ(got.size(), 40u);
  std::size_t from = 0;
  while (read_->vision_payloads[from].first < 6'000'000'000) ++from;
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_TRUE(got[i] == read_->vision_payloads[from + i].second) << "datagram " << i << " after the seek";
  }
  // Back to 1 s: it goes on from there.
  page.Send(R"({"cmd":"seek","t":1})");
  std::this_thread::sleep_for(100ms);
  page.Send(R"({"cmd":"pause"})");
  page.ReadType("ack");
  std::this_thread::sleep_for(100ms);
  const auto back = vision.Receive(100000, std::chrono::steady_clock::now());
  std::size_t at1 = 0;
  while (read_->vision_payloads[at1].first < 1'000'000'000) ++at1;
  bool jumped = false;
  for (std::size_t i = 0; i < back.size() && !jumped; ++i) jumped = back[i] == read_->vision_payloads[at1].second;
  EXPECT_TRUE(jumped) << "the datagram at 1 s went out after the seek back (" << back.size() << " received)";

  EXPECT_EQ(replay.Interrupt(), 0) << replay.Output();
  EXPECT_NE(replay.Output().find("sent "), std::string::npos) << replay.Output();
}

TEST_F(ReplayViewer, ADamagedLogGivesTheSameLocatedErrorAndShowsWhatCameBefore) {
  const std::string bytes = ReadBytes(*log_);
  const fs::path cut = TempDir() / "cut.log.gz";
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  // What a replay onto the network says (its own ports, as fast as possible).
  const CliResult wire = RunUbersim("replay " + cut.string() +
                                    " --local-only --speed 0 --vision-port 44346 --referee-port 44343 "
                                    "--tracker-port 44350 --vision-legacy-port 44345");
  EXPECT_EQ(wire.exit_code, 1) << wire.output;
  const std::size_t at = wire.output.find("ubersim replay: " + cut.string() + ": record ");
  ASSERT_NE(at, std::string::npos) << wire.output;
  const std::string error = wire.output.substr(at, wire.output.find('\n', at) - at);
  EXPECT_NE(error.find(" at byte "), std::string::npos) << error;

  const std::uint16_t port = FreeTcpPort();
  Background replay("replay " + cut.string() + " --viewer --viewer-port " + std::to_string(port) + " --local-only");
  ASSERT_TRUE(replay.WaitFor("(open it in a browser; Ctrl-C stops)")) << replay.Output();
  EXPECT_NE(replay.Output().find(error + "\n"), std::string::npos) << replay.Output() << "\nexpected: " << error;
  WsClient page(port);
  const rapidjson::Document hello = page.ReadType("hello");
  const double shown = hello["replay"]["duration"].GetDouble();
  EXPECT_GT(shown, 1.0);
  EXPECT_LT(shown, static_cast<double>(read_->duration) * 1e-9) << "the records before the damage";
  EXPECT_EQ(replay.Interrupt(), 1) << replay.Output();
}

TEST_F(ReplayViewer, BadUsageIsRefusedSayingWhy) {
  const std::pair<std::string, std::string> cases[] = {
      {" --send", "--send is for --viewer"},
      {" --viewer-port 9000", "--viewer-port is for --viewer"},
      {" --viewer --speed 0", "the viewer plays 0.25 to 8 times the recorded rate"},
      {" --viewer --speed 16", "the viewer plays 0.25 to 8 times the recorded rate"},
      {" --viewer --local-only --viewer-address 0.0.0.0", "with --local-only: the page would be reachable"},
  };
  for (const auto& [flags, message] : cases) {
    const CliResult r = RunUbersim("replay " + log_->string() + flags);
    EXPECT_EQ(r.exit_code, 2) << flags << ": " << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << flags << ": " << r.output;
  }
  // A port that is taken: named, with what to do.
  boost::asio::io_context io;
  boost::asio::ip::tcp::acceptor taken(io, {boost::asio::ip::make_address("127.0.0.1"), 0});
  const CliResult r = RunUbersim("replay " + log_->string() + " --viewer --local-only --viewer-port " +
                                 std::to_string(taken.local_endpoint().port()));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("cannot listen on 127.0.0.1:" + std::to_string(taken.local_endpoint().port())),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("choose another with --viewer-port"), std::string::npos) << r.output;
}

}  // namespace
