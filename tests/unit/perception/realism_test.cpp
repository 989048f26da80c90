// SPDX-License-Identifier: Apache-2.0
// The league's realism in the perception pipeline (reference/ssl-protocols.md §6.1) and what
// ÜberSim adds: a ball hidden by robots (ray-cast), its blob area, false balls at dribblers,
// offsets, processing time, unsynchronised cameras, noise growing from the nadir, motion blur.
#include <cmath>
#include <set>

#include <gtest/gtest.h>

#include "perception/occlusion.hpp"
#include "perception/vision_pipeline.hpp"

namespace ubersim::kernel {
namespace {

constexpr double kBallRadius = 0.0215;

RobotState RobotAt(double x, double y, double yaw = 0.0, int id = 1) {
  RobotState r;
  r.id = {Team::kBlue, id};
  r.pose = Pose::FromYaw(Vec3(x, y, 0.075), yaw);
  r.radius = 0.09;
  r.height = 0.15;
  return r;
}

WorldSnapshot Scene(std::int64_t t_ns, const Vec3& ball, std::vector<RobotState> robots, const Vec3& velocity = Vec3::Zero()) {
  WorldSnapshot s;
  s.sim_time_ns = t_ns;
  s.ball.pose.position = ball;
  s.ball.twist.linear = velocity;
  s.ball.radius = kBallRadius;
  s.robots = std::move(robots);
  return s;
}

// One camera 6 m above (cx, 0), seeing the whole Div B carpet.
PerceptionModel Camera(double cx = 0.0) {
  PerceptionModel m;
  m.frame_rate = 100.0;
  CameraModel c;
  c.position = Vec3(cx, 0, 6);
  c.x_min = -5.2, c.x_max = 5.2, c.y_min = -3.7, c.y_max = 3.7;
  m.cameras.push_back(c);
  return m;
}

// Frames of `seconds` of the same scene, stepped in 1 ms.
std::vector<VisionFrame> Frames(PerceptionPipeline& p, double seconds, const WorldSnapshot& scene,
                                const std::vector<double>& fronts = {}) {
  std::vector<VisionFrame> out;
  for (std::int64_t t = 1'000'000; t <= static_cast<std::int64_t>(seconds * 1e9); t += 1'000'000) {
    WorldSnapshot s = scene;
    s.sim_time_ns = t;
    if (p.CaptureDue(t)) p.Capture(s, fronts);
    for (VisionFrame& f : p.Release(t)) out.push_back(std::move(f));
  }
  return out;
}

TEST(Occlusion, ASegmentThroughARobotIsBlockedAndOneBesideOrAboveItIsNot) {
  RobotHull hull;  // at the origin, 0.09 m radius, 0.15 m high
  EXPECT_TRUE(SegmentHitsHull(Vec3(-1, 0, 0.05), Vec3(1, 0, 0.05), hull));
  EXPECT_FALSE(SegmentHitsHull(Vec3(-1, 0.1, 0.05), Vec3(1, 0.1, 0.05), hull));  // beside
  EXPECT_FALSE(SegmentHitsHull(Vec3(-1, 0, 0.2), Vec3(1, 0, 0.2), hull));        // above
  EXPECT_TRUE(SegmentHitsHull(Vec3(0, 0, 0.3), Vec3(0, 0, -0.1), hull));         // down through the top
  EXPECT_FALSE(SegmentHitsHull(Vec3(0.5, 0, 0.05), Vec3(0.2, 0, 6.0), hull));    // ends before it
  // The flat front: a ray just in front of the chord misses a robot cut at 0.07 m.
  hull.front = 0.07;
  EXPECT_FALSE(SegmentHitsHull(Vec3(0.08, -1, 0.05), Vec3(0.08, 1, 0.05), hull));
  hull.heading = M_PI;  // turned round: that side is now its round back
  EXPECT_TRUE(SegmentHitsHull(Vec3(0.08, -1, 0.05), Vec3(0.08, 1, 0.05), hull));
}

TEST(Occlusion, ABallBehindARobotIsHiddenAndAHalfHiddenOneIsSeenAtItsVisibleCentroid) {
  const Vec3 camera(0, 0, 6);
  // The ball 3 m out, on the carpet; a robot just in front of it towards the camera's nadir.
  const Vec3 ball(3.0, 0.0, kBallRadius);
  // The ray from the ball's centre to the camera climbs 2 mm per 1 mm: 0.15 m up at 0.075 m in.
  // A robot standing 0.1 m nearer the camera hides all of it.
  const BallVisibility behind = VisibleBall(ball, kBallRadius, camera, {RobotAt(2.9, 0.0)}, {});
  EXPECT_EQ(behind.fraction, 0.0);
  // Nobody near: all of it.
  const BallVisibility clear = VisibleBall(ball, kBallRadius, camera, {RobotAt(2.0, 1.0)}, {});
  EXPECT_EQ(clear.fraction, 1.0);
  EXPECT_TRUE(clear.centroid.isApprox(ball));
  // A robot whose edge runs through the ball's line of sight (its side at y = 0): about half,
  // and what is seen lies on the free side (y > 0).
  const BallVisibility half = VisibleBall(ball, kBallRadius, camera, {RobotAt(2.9, -0.09)}, {});
  EXPECT_GT(half.fraction, 0.2);
  EXPECT_LT(half.fraction, 0.9);
  EXPECT_GT(half.centroid.y(), 0.003);
  // A robot off the field hides nothing.
  RobotState gone = RobotAt(2.9, 0.0);
  gone.present = false;
  EXPECT_EQ(VisibleBall(ball, kBallRadius, camera, {gone}, {}).fraction, 1.0);
}

TEST(Realism, AHiddenBallIsNotReportedBelowTheThresholdAndAPartlyHiddenOneAtItsVisiblePart) {
  PerceptionModel m = Camera();
  m.ball_occlusion = true;
  m.ball_visibility_threshold = 0.4;
  const Vec3 ball(3.0, 0.0, kBallRadius);
  {
    PerceptionPipeline p(m, 1);
    const auto frames = Frames(p, 0.1, Scene(0, ball, {RobotAt(2.9, 0.0)}));
    ASSERT_FALSE(frames.empty());
    for (const VisionFrame& f : frames) EXPECT_TRUE(f.balls.empty());
  }
  {
    PerceptionPipeline p(m, 1);
    const auto frames = Frames(p, 0.1, Scene(0, ball, {RobotAt(2.9, -0.09)}));
    ASSERT_FALSE(frames.empty());
    ASSERT_EQ(frames[0].balls.size(), 1u);
    const BallVisibility seen = VisibleBall(ball, kBallRadius, Vec3(0, 0, 6), {RobotAt(2.9, -0.09)}, {});
    ASSERT_GT(seen.fraction, 0.4);
    ASSERT_LT(seen.fraction, 1.0);
    // Reported at its visible part's centroid, on the camera's ray (the ball is on the carpet).
    EXPECT_NEAR(frames[0].balls[0].y, seen.centroid.y() * 6.0 / (6.0 - (seen.centroid.z() - kBallRadius)), 1e-9);
    EXPECT_GT(frames[0].balls[0].y, 0.003);
    // Its blob is the part of a whole ball's that is seen.
    PerceptionPipeline whole(Camera(), 1);
    const auto free = Frames(whole, 0.1, Scene(0, ball, {}));
    EXPECT_NEAR(frames[0].balls[0].area, seen.fraction * free[0].balls[0].area, 1e-9);
  }
  // Without occlusion the robot hides nothing.
  PerceptionPipeline off(Camera(), 1);
  EXPECT_EQ(Frames(off, 0.1, Scene(0, ball, {RobotAt(2.9, 0.0)}))[0].balls.size(), 1u);
}

TEST(Realism, TheBlobAreaShrinksWithDistanceAndHasTheConfiguredNoise) {
  PerceptionModel m = Camera();
  PerceptionPipeline exact(m, 1);
  const double near = Frames(exact, 0.05, Scene(0, Vec3(0, 0, kBallRadius), {}))[0].balls[0].area;
  // 390 px focal length: π (390 · 0.0215 / 5.98)² ≈ 6.2 px² right below the camera.
  EXPECT_NEAR(near, M_PI * std::pow(390.0 * kBallRadius / (6.0 - kBallRadius), 2), 1e-6);
  PerceptionPipeline exact_far(m, 1);
  EXPECT_LT(Frames(exact_far, 0.05, Scene(0, Vec3(4, 3, kBallRadius), {}))[0].balls[0].area, near);
  m.ball_area_sigma = 2.0;
  PerceptionPipeline noisy(m, 5);
  const auto frames = Frames(noisy, 20.0, Scene(0, Vec3(0, 0, kBallRadius), {}));
  double s = 0, ss = 0;
  for (const VisionFrame& f : frames) {
    const double d = f.balls.at(0).area - near;
    s += d, ss += d * d;
  }
  const double n = static_cast<double>(frames.size());
  EXPECT_NEAR(std::sqrt(ss / n - (s / n) * (s / n)), 2.0, 0.2);  // the area clipped at 0 leaves σ near
}

TEST(Realism, FalseBallsAppearAtTheDribblerCornersAtTheConfiguredRate) {
  PerceptionModel m = Camera();
  m.dribbler_false_balls = 2.0;  // per robot per second
  PerceptionPipeline p(m, 9);
  const std::vector<RobotState> robots = {RobotAt(1.0, 1.0, 0.0, 1), RobotAt(-2.0, 0.5, M_PI / 2, 2)};
  const double front = 0.07;
  const double seconds = 100.0;
  const auto frames = Frames(p, seconds, Scene(0, Vec3(-3, -2, kBallRadius), robots), {front, front});
  const double side = std::sqrt(0.09 * 0.09 - front * front);
  std::set<std::pair<long, long>> corners;
  int false_balls = 0;
  for (const VisionFrame& f : frames) {
    for (const DetectedBall& b : f.balls) {
      if (std::hypot(b.x + 3, b.y + 2) < 1e-9) continue;  // the real ball
      ++false_balls;
      // At a corner of one of the two dribblers.
      const bool at_one = std::hypot(b.x - (1.0 + front), std::abs(b.y - 1.0) - side) < 1e-9 ||
                          std::hypot(std::abs(b.x + 2.0) - side, b.y - (0.5 + front)) < 1e-9;
      EXPECT_TRUE(at_one) << b.x << ", " << b.y;
      corners.insert({std::lround(b.x * 1000), std::lround(b.y * 1000)});
    }
  }
  // 2 per second per robot over 100 s, two robots: about 400 (Poisson, σ ≈ 20).
  EXPECT_NEAR(false_balls, 2.0 * seconds * 2, 80);
  EXPECT_EQ(corners.size(), 4u);  // both corners of both robots
}

TEST(Realism, OffsetsAndProcessingTimeChangeOnlyWhatIsReported) {
  PerceptionModel m = Camera(3.0);  // a camera above x = 3 m: the offset points +x
  m.object_offset = 0.02;
  m.latency = 0.035;
  m.processing_time = 0.010;
  PerceptionPipeline p(m, 1);
  const auto frames = Frames(p, 0.2, Scene(0, Vec3(1, 1, kBallRadius), {RobotAt(-1.0, 0.5)}));
  ASSERT_FALSE(frames.empty());
  const VisionFrame& f = frames[0];
  EXPECT_NEAR(f.balls.at(0).x, 1.0 + 0.02, 1e-9);
  EXPECT_NEAR(f.balls.at(0).y, 1.0, 1e-9);
  EXPECT_NEAR(f.robots.at(0).x, -1.0 + 0.02, 1e-9);
  EXPECT_EQ(f.t_sent_ns - f.t_capture_ns, 10'000'000);  // what the frame says
  // It still left 35 ms after the true capture: the first capture is at 10 ms.
  EXPECT_EQ(f.t_sent_ns, 10'000'000 + 35'000'000);
}

TEST(Realism, UnsynchronisedCamerasEachKeepTheirRateOnTheirOwnPhase) {
  PerceptionModel m = Camera(-2.0);
  m.cameras.push_back(Camera(2.0).cameras[0]);
  m.cameras[1].id = 1;
  m.frame_rate = 50.0;  // 20 ms
  m.unsynchronised_cameras = true;
  m.capture_jitter = 0.0005;
  PerceptionPipeline p(m, 4);
  const auto frames = Frames(p, 4.0, Scene(0, Vec3(0, 0, kBallRadius), {}));
  std::vector<std::int64_t> captures[2];
  for (const VisionFrame& f : frames) captures[f.camera_id].push_back(f.t_capture_ns);
  ASSERT_NEAR(captures[0].size(), 200u, 2u);
  ASSERT_NEAR(captures[1].size(), 200u, 2u);
  // Each camera 50 Hz on average, its intervals jittered by a millisecond or so.
  std::set<std::int64_t> intervals;
  for (std::size_t i = 1; i < captures[0].size(); ++i) intervals.insert(captures[0][i] - captures[0][i - 1]);
  EXPECT_GT(intervals.size(), 1u);
  for (std::int64_t d : intervals) EXPECT_NEAR(static_cast<double>(d), 20e6, 3.1e6);
  // The two cameras' phases differ: their frames interleave instead of coming in pairs.
  const std::int64_t phase0 = captures[0][10] % 20'000'000, phase1 = captures[1][10] % 20'000'000;
  EXPECT_GT(std::llabs(phase0 - phase1), 1'500'000);
  // And the frames still leave in the order of their send times.
  for (std::size_t i = 1; i < frames.size(); ++i) EXPECT_LE(frames[i - 1].t_sent_ns, frames[i].t_sent_ns);
  // Synchronised cameras capture together.
  m.unsynchronised_cameras = false;
  m.capture_jitter = 0.0;
  PerceptionPipeline together(m, 4);
  const auto paired = Frames(together, 0.1, Scene(0, Vec3(0, 0, kBallRadius), {}));
  ASSERT_GE(paired.size(), 2u);
  EXPECT_EQ(paired[0].t_capture_ns, paired[1].t_capture_ns);
}

TEST(Realism, NoiseGrowsWithTheDistanceFromTheCamerasNadir) {
  PerceptionModel m = Camera();
  m.robot_position_sigma = 0.002;
  m.noise_growth = 0.25;  // per metre
  const auto spread = [&](double x) {
    PerceptionPipeline p(m, 2);
    const auto frames = Frames(p, 20.0, Scene(0, Vec3(-4, -3, kBallRadius), {RobotAt(x, 0.0)}));
    double ss = 0;
    for (const VisionFrame& f : frames) ss += std::pow(f.robots.at(0).x - x, 2);
    return std::sqrt(ss / static_cast<double>(frames.size()));
  };
  EXPECT_NEAR(spread(0.0), 0.002, 0.0002);
  EXPECT_NEAR(spread(4.0), 0.002 * 2.0, 0.0004);  // 1 + 0.25 · 4
}

TEST(Realism, AFastBallIsReportedHalfItsExposureTravelBehindWithALongerBlob) {
  PerceptionModel m = Camera();
  m.exposure = 0.004;
  PerceptionPipeline p(m, 1);
  const auto frames = Frames(p, 0.05, Scene(0, Vec3(1, 0, kBallRadius), {}, Vec3(5, 0, 0)));
  PerceptionPipeline still(Camera(), 1);
  const auto resting = Frames(still, 0.05, Scene(0, Vec3(1, 0, kBallRadius), {}));
  // 5 m/s over 4 ms: 2 cm of travel, seen 1 cm behind.
  EXPECT_NEAR(frames.at(0).balls.at(0).x, 1.0 - 0.01, 1e-9);
  EXPECT_GT(frames[0].balls[0].area, 1.5 * resting.at(0).balls.at(0).area);
}

TEST(Realism, WithEverythingOffTheFramesAreThoseOfBefore) {
  // The new settings draw no random numbers when they are off: the noise stream stays.
  PerceptionModel m = Camera();
  m.ball_position_sigma = 0.003;
  m.robot_position_sigma = 0.002;
  m.robot_drop = 0.1;
  PerceptionPipeline a(m, 7);
  m.ball_occlusion = true;  // a setting that draws nothing
  PerceptionPipeline b(m, 7);
  const WorldSnapshot scene = Scene(0, Vec3(1, 1, kBallRadius), {RobotAt(-1, 0)});
  const auto fa = Frames(a, 1.0, scene), fb = Frames(b, 1.0, scene);
  ASSERT_EQ(fa.size(), fb.size());
  for (std::size_t i = 0; i < fa.size(); ++i) {
    ASSERT_EQ(fa[i].balls.size(), fb[i].balls.size());
    if (!fa[i].balls.empty()) {
      EXPECT_EQ(fa[i].balls[0].x, fb[i].balls[0].x);
    }
  }
}

TEST(Realism, AnObjectsNoiseIsItsOwnWhoeverElseIsInView) {
  // Each object draws from its own stream (the seed, the camera, the frame, the object): robot 5
  // and the ball are reported alike whether robot 0, listed before them, is on the field, off it
  // or in view. With one stream for the frame, robot 0's draws came first and moved theirs.
  PerceptionModel m = Camera();
  m.ball_position_sigma = 0.003;
  m.robot_position_sigma = 0.002;
  m.robot_orientation_sigma = 0.02;
  m.robot_drop = 0.1;
  const Vec3 ball(1, 1, kBallRadius);
  const RobotState watched = RobotAt(-1, 0, 0.3, 5);
  RobotState other = RobotAt(2, -1, 0.0, 0);
  const auto run = [&](std::vector<RobotState> robots) {
    PerceptionPipeline p(m, 7);
    return Frames(p, 1.0, Scene(0, ball, std::move(robots)));
  };
  const auto alone = run({watched});
  const auto with_other = run({other, watched});
  other.present = false;
  const auto with_other_off = run({other, watched});
  ASSERT_EQ(alone.size(), 100u);
  ASSERT_EQ(with_other.size(), alone.size());
  ASSERT_EQ(with_other_off.size(), alone.size());
  const auto report_of = [](const VisionFrame& f, int id) -> const DetectedRobot* {
    for (const DetectedRobot& r : f.robots) {
      if (r.id.id == id) return &r;
    }
    return nullptr;
  };
  int seen = 0, moved = 0;
  for (std::size_t i = 0; i < alone.size(); ++i) {
    for (const auto* frames : {&with_other, &with_other_off}) {
      const VisionFrame& f = (*frames)[i];
      ASSERT_EQ(f.balls.size(), 1u);
      EXPECT_EQ(f.balls[0].x, alone[i].balls.at(0).x) << "frame " << i;
      EXPECT_EQ(f.balls[0].y, alone[i].balls[0].y) << "frame " << i;
      const DetectedRobot* a = report_of(alone[i], 5);
      const DetectedRobot* b = report_of(f, 5);
      ASSERT_EQ(a == nullptr, b == nullptr) << "frame " << i << ": dropped in one run only";
      if (!a) continue;
      ++seen;
      EXPECT_EQ(b->x, a->x) << "frame " << i;
      EXPECT_EQ(b->y, a->y) << "frame " << i;
      EXPECT_EQ(b->yaw, a->yaw) << "frame " << i;
    }
    const DetectedRobot* r = report_of(alone[i], 5);
    if (r && r->x != -1.0) ++moved;
  }
  EXPECT_GT(seen, 150);   // about 90 % of 2 × 100 frames
  EXPECT_GT(moved, 80);   // and there is noise to compare
  // Robot 0 in view has noise of its own, not robot 5's.
  const DetectedRobot* zero = report_of(with_other[0], 0);
  const DetectedRobot* five = report_of(with_other[0], 5);
  if (zero && five) {
    EXPECT_NE(zero->x - 2.0, five->x + 1.0);
  }
}

}  // namespace
}  // namespace ubersim::kernel
