// SPDX-License-Identifier: Apache-2.0
// The perception pipeline (frame rate, latency, noise, drop-outs, coverage, the airborne ball's
// projection) and the radio link (latency, loss), on synthetic ground truth and in a world.
#include <cmath>
#include <map>
#include <sstream>

#include <gtest/gtest.h>

#include "../../common/test_world.hpp"
#include "ubersim/kernel/logging.hpp"
#include "perception/radio_link.hpp"
#include "perception/vision_pipeline.hpp"
#include "ubersim/kernel/world.hpp"

namespace ubersim::kernel {
namespace {

WorldSnapshot Truth(std::int64_t t_ns, const Vec3& ball = Vec3(0.5, -0.25, 0.0215)) {
  WorldSnapshot s;
  s.sim_time_ns = t_ns;
  s.ball.pose.position = ball;
  s.ball.radius = 0.0215;
  RobotState r;
  r.id = {Team::kYellow, 4};
  r.pose = Pose::FromYaw(Vec3(-1.0, 1.0, 0.05), 0.3);
  s.robots.push_back(r);
  return s;
}

PerceptionModel OneCamera(double rate, double latency) {
  PerceptionModel m;
  m.frame_rate = rate;
  m.latency = latency;
  m.cameras = CameraGrid(1, 10.4, 7.4, 6.0);
  return m;
}

// Steps synthetic time in 1 ms and collects what leaves.
std::vector<VisionFrame> Frames(PerceptionPipeline& p, double seconds, const Vec3& ball = Vec3(0.5, -0.25, 0.0215)) {
  std::vector<VisionFrame> out;
  for (std::int64_t t = 1'000'000; t <= static_cast<std::int64_t>(seconds * 1e9); t += 1'000'000) {
    if (p.CaptureDue(t)) p.Capture(Truth(t, ball));
    for (VisionFrame& f : p.Release(t)) out.push_back(std::move(f));
  }
  return out;
}

TEST(Perception, FramesComeAtTheFrameRateAndLeaveAfterTheLatency) {
  PerceptionPipeline p(OneCamera(75.0, 0.035), 1);
  const std::vector<VisionFrame> frames = Frames(p, 2.0);
  // 2 s at 75 Hz, less those still in flight: captures at k/75 s, sent 35 ms later.
  EXPECT_EQ(frames.size(), 147u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].frame_number, i);
    EXPECT_EQ(frames[i].t_sent_ns - frames[i].t_capture_ns, 35'000'000);
    // Captured on the first step at or after k/75 s.
    const double nominal = (i + 1) / 75.0;
    EXPECT_GE(frames[i].t_capture_ns, static_cast<std::int64_t>(nominal * 1e9) - 1);
    EXPECT_LT(frames[i].t_capture_ns, static_cast<std::int64_t>(nominal * 1e9) + 1'000'000);
  }
}

TEST(Perception, IdealFramesAreExactAndProjectAnAirborneBallOntoTheCarpet) {
  PerceptionPipeline p(OneCamera(60.0, 0.0), 1);
  const Vec3 flying(1.0, 0.5, 0.0215 + 0.6);  // 0.6 m up, 6 m below the camera at (0, 0)
  const std::vector<VisionFrame> frames = Frames(p, 0.1, flying);
  ASSERT_FALSE(frames.empty());
  const VisionFrame& f = frames.front();
  EXPECT_EQ(f.t_sent_ns, f.t_capture_ns);
  ASSERT_EQ(f.balls.size(), 1u);
  // The camera's ray through the ball meets the carpet 6 / 5.4 times as far out.
  EXPECT_NEAR(f.balls[0].x, 1.0 * 6.0 / 5.4, 1e-12);
  EXPECT_NEAR(f.balls[0].y, 0.5 * 6.0 / 5.4, 1e-12);
  ASSERT_EQ(f.robots.size(), 1u);
  EXPECT_EQ(f.robots[0].id, (RobotId{Team::kYellow, 4}));
  EXPECT_DOUBLE_EQ(f.robots[0].x, -1.0);
  EXPECT_NEAR(f.robots[0].yaw, 0.3, 1e-12);
}

TEST(Perception, NoiseHasTheConfiguredSpreadAndTheSameSeedGivesTheSameNoise) {
  PerceptionModel m = OneCamera(100.0, 0.0);
  m.ball_position_sigma = 0.003;
  m.robot_orientation_sigma = 0.02;
  PerceptionPipeline a(m, 7), b(m, 7), c(m, 8);
  const auto fa = Frames(a, 20.0), fb = Frames(b, 20.0), fc = Frames(c, 20.0);
  ASSERT_EQ(fa.size(), 2000u);
  double sx = 0, sxx = 0, syaw = 0;
  for (const VisionFrame& f : fa) {
    const double dx = f.balls.at(0).x - 0.5;
    sx += dx;
    sxx += dx * dx;
    syaw += std::pow(f.robots.at(0).yaw - 0.3, 2);
  }
  const double n = static_cast<double>(fa.size());
  EXPECT_NEAR(sx / n, 0.0, 0.0003);                  // unbiased (3 σ/√n ≈ 0.0002)
  EXPECT_NEAR(std::sqrt(sxx / n), 0.003, 0.0003);    // σ within 10 %
  EXPECT_NEAR(std::sqrt(syaw / n), 0.02, 0.002);
  EXPECT_EQ(fa[100].balls[0].x, fb[100].balls[0].x);  // same seed, same noise, bit for bit
  EXPECT_NE(fa[100].balls[0].x, fc[100].balls[0].x);
}

TEST(Perception, DetectionsDropAtTheConfiguredRate) {
  PerceptionModel m = OneCamera(100.0, 0.0);
  m.ball_drop = 0.2;
  m.robot_drop = 0.05;
  PerceptionPipeline p(m, 3);
  const auto frames = Frames(p, 50.0);
  ASSERT_EQ(frames.size(), 5000u);
  double balls = 0, robots = 0;
  for (const VisionFrame& f : frames) {
    balls += static_cast<double>(f.balls.size());
    robots += static_cast<double>(f.robots.size());
  }
  EXPECT_NEAR(1.0 - balls / 5000, 0.2, 0.02);
  EXPECT_NEAR(1.0 - robots / 5000, 0.05, 0.01);
}

TEST(Perception, EachCameraReportsItsPartOfTheFieldPlusTheOverlap) {
  PerceptionModel m = OneCamera(60.0, 0.0);
  m.cameras = CameraGrid(2, 10.4, 7.4, 6.0);  // one per half: x < 0 and x > 0
  m.camera_overlap = 0.3;
  ASSERT_EQ(m.cameras.size(), 2u);
  EXPECT_DOUBLE_EQ(m.cameras[0].position.x(), -2.6);
  EXPECT_DOUBLE_EQ(m.cameras[1].position.x(), 2.6);
  PerceptionPipeline p(m, 1);
  std::map<int, int> balls_seen;  // camera -> frames with the ball
  for (const VisionFrame& f : Frames(p, 0.5, Vec3(0.2, 0, 0.0215))) balls_seen[f.camera_id] += !f.balls.empty();
  EXPECT_EQ(balls_seen[0], balls_seen[1]);  // 0.2 m past the middle: both see it
  EXPECT_GT(balls_seen[0], 0);
  PerceptionPipeline q(m, 1);
  balls_seen.clear();
  for (const VisionFrame& f : Frames(q, 0.5, Vec3(0.5, 0, 0.0215))) balls_seen[f.camera_id] += !f.balls.empty();
  EXPECT_EQ(balls_seen[0], 0);  // 0.5 m past the middle: only the right camera
  EXPECT_GT(balls_seen[1], 0);
}

TEST(Radio, CommandsWaitTheirLatencyAndSomeAreLost) {
  RadioModel m;
  m.latency = 0.003;
  RadioLink link(m, 1);
  EXPECT_TRUE(link.Send(CommandEvent{{Team::kBlue, 1}, {}, {}, 1.0}, 10'000'000));
  EXPECT_TRUE(link.Deliver(12'999'999).empty());
  const auto due = link.Deliver(13'000'000);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(*due[0].dribbler_speed, 1.0);

  m.latency = 0;
  m.loss = 0.1;
  RadioLink lossy(m, 5);
  int lost = 0;
  for (int i = 0; i < 10000; ++i) lost += !lossy.Send(CommandEvent{}, i);
  EXPECT_NEAR(lost / 10000.0, 0.1, 0.01);
}

TEST(Radio, AWorldAppliesCommandsOnlyAfterTheRadioLatency) {
  WorldModel model = testing::BallWorld();
  auto robot = std::make_shared<RobotModel>();
  robot->file = "<code>";
  robot->name = "no-parts";
  robot->body = RobotBodyInfo{2.0, 0.09, 0.15, 0.07, 0.0};
  model.robots.push_back(RobotPlacement{{Team::kBlue, 0}, robot, 0, 1, 0, true});
  model.radio.latency = 0.005;
  std::ostringstream text;
  StreamLog log(text, LogLevel::kWarning);
  PluginRegistry registry({});
  World w(model, registry, log, false);
  // The robot has no dribbler, so the command is refused when it arrives — and only then.
  w.events().Post(CommandEvent{{Team::kBlue, 0}, {}, {}, 10.0});
  for (int i = 0; i < 4; ++i) w.Step();
  EXPECT_EQ(w.event_counters().rejected, 0);
  for (int i = 0; i < 2; ++i) w.Step();
  EXPECT_EQ(w.event_counters().rejected, 1);
  EXPECT_NE(text.str().find("robot has no dribbler"), std::string::npos) << text.str();
}

// A ball-only world (ball at (1, 1)) with one camera, collecting the frames that leave it.
struct ObservedWorld {
  std::ostringstream text;
  StreamLog log{text, LogLevel::kWarning};
  PluginRegistry registry{{}};
  World w;
  std::vector<VisionFrame> frames;
  ObservedWorld(double rate, double latency) : w(Model(rate, latency), registry, log, false) {
    w.SetVisionObserver([this](const VisionFrame& f) { frames.push_back(f); });
  }
  static WorldModel Model(double rate, double latency) {
    WorldModel model = testing::BallWorld(Vec3(1, 1, 0));
    model.perception = OneCamera(rate, latency);
    return model;
  }
};

TEST(Perception, AWorldHandsItsFramesToTheObserver) {
  ObservedWorld o(75.0, 0.02);
  World& w = o.w;
  std::vector<VisionFrame>& frames = o.frames;
  for (int i = 0; i < 1000; ++i) w.Step();
  EXPECT_EQ(frames.size(), 73u);  // captures at k/75 s up to 1 s, less the 20 ms in flight
  ASSERT_EQ(frames.back().balls.size(), 1u);
  EXPECT_NEAR(frames.back().balls[0].x, 1.0, 1e-3);
}

TEST(Perception, ARealismEventChangesLatencyNoiseAndRadioWhileRunning) {
  ObservedWorld o(100.0, 0.02);
  World& w = o.w;
  std::vector<VisionFrame>& frames = o.frames;
  RealismEvent bad;
  bad.ball_drop = 1.5;
  w.events().Post(bad);
  RealismEvent negative;
  negative.vision_latency = -0.01;
  w.events().Post(negative);
  w.ProcessEvents();
  EXPECT_EQ(w.event_counters().rejected, 2);
  EXPECT_DOUBLE_EQ(w.perception().latency, 0.02);  // unchanged

  RealismEvent e;
  e.vision_latency = 0.005;
  e.ball_position_noise = 0.01;
  e.radio_loss = 1.0;
  w.events().Post(e);
  for (int i = 0; i < 200; ++i) w.Step();
  ASSERT_FALSE(frames.empty());
  EXPECT_EQ(frames.back().t_sent_ns - frames.back().t_capture_ns, 5'000'000);
  EXPECT_GT(std::abs(frames.back().balls.at(0).x - 1.0), 1e-6);  // noisy now
  w.events().Post(CommandEvent{{Team::kBlue, 0}, {}, {}, 1.0});
  w.Step();
  EXPECT_EQ(w.event_counters().lost, 0);  // unknown robot: refused before the radio
  EXPECT_EQ(w.event_counters().rejected, 3);
}

}  // namespace
}  // namespace ubersim::kernel
