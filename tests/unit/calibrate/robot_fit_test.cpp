// SPDX-License-Identifier: Apache-2.0
// The robot fit against a simulated calibration session: a servo with known limits (far from the
// model file's defaults), a command latency and a first-order wheel lag, integrated at 1 ms and
// seen by two unsynchronised cameras with noise, offsets and drop-outs.
#include "robot_fit.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

namespace ubersim::calibrate {
namespace {

// The robot the test simulates. The servo ramps as sdk/include/ubersim/servo.hpp's VelocityServo
// (speed-up and slow-down limits, the linear target clamped to max_speed); along and across may
// differ (an ellipse between them), which the simulator's isotropic servo is the special case of.
struct Truth {
  double max_speed = 2.2;       // m/s
  double accel_along = 4.5;     // m/s²
  double brake_along = 7.5;
  double accel_across = 3.6;
  double brake_across = 6.3;
  double angular_speed = 7.0;   // rad/s
  double angular_accel = 30.0;  // rad/s²
  double angular_brake = 40.0;
  double latency = 0.045;       // s, command sent → setpoint moves
  double lag = 0.015;           // s, wheels' first-order lag behind the setpoint
};

struct Step {
  double forward = 0, left = 0, angular = 0;  // command, m/s and rad/s
  double hold = 0;                            // s
};

// From standstill: each direction at full (beyond the limits) and partial speed, held 1.3 s, then
// a zero command for 1 s; `repeats` times.
std::vector<Step> CalibrationScript(int repeats) {
  std::vector<Step> script = {{0, 0, 0, 1.0}};
  for (int r = 0; r < repeats; ++r) {
    for (int axis = 0; axis < 3; ++axis) {
      for (double sign : {1.0, -1.0}) {
        for (double size : {1.0, 0.4}) {
          Step s;
          s.hold = 1.3;
          if (axis == 0) s.forward = sign * 3.0 * size;
          if (axis == 1) s.left = sign * 3.0 * size;
          if (axis == 2) s.angular = sign * 9.0 * size;
          script.push_back(s);
          script.push_back({0, 0, 0, 1.0});
        }
      }
    }
  }
  return script;
}

struct Session {
  std::vector<TrackPoint> track;
  std::vector<CommandSample> commands;
};

// Moves `value` toward `target` at `accel` when speeding up, `brake` when slowing or reversing.
double Ramp(double value, double target, double accel, double brake, double dt) {
  const bool slowing = std::abs(target) < std::abs(value) || target * value < 0;
  const double step = (slowing ? brake : accel) * dt;
  return value + std::clamp(target - value, -step, step);
}

Session Simulate(const Truth& truth, const std::vector<Step>& script, unsigned seed, double outlier_rate = 0.0) {
  Session out;
  std::mt19937 random(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  // Commands at 100 Hz (send jitter ±0.3 ms), repeated setpoints.
  double end = 0;
  std::vector<std::pair<double, Step>> schedule;
  for (const Step& s : script) {
    schedule.emplace_back(end, s);
    end += s.hold;
  }
  std::size_t current = 0;
  for (int k = 0; k * 0.01 < end; ++k) {
    const double t = k * 0.01 + 0.0003 * (2 * uniform(random) - 1);
    while (current + 1 < schedule.size() && schedule[current + 1].first <= k * 0.01) ++current;
    const Step& s = schedule[current].second;
    CommandSample c;
    c.t = t;
    c.forward = s.forward;
    c.left = s.left;
    c.angular = s.angular;
    out.commands.push_back(c);
  }
  // Motion at 1 ms.
  const double dt = 0.001;
  const int steps = static_cast<int>(end / dt) + 1;
  std::vector<double> xs(static_cast<std::size_t>(steps)), ys(xs.size()), yaws(xs.size());
  double x = -2.0, y = -1.0, yaw = 0.6;
  double sf = 0, sl = 0, sw = 0;  // setpoint
  double vf = 0, vl = 0, vw = 0;  // motion
  std::size_t next_command = 0;
  double cf = 0, cl = 0, cw = 0;
  const double blend = -std::expm1(-dt / truth.lag);
  for (int i = 0; i < steps; ++i) {
    const double t = i * dt;
    while (next_command < out.commands.size() && out.commands[next_command].t + truth.latency <= t) {
      cf = out.commands[next_command].forward;
      cl = out.commands[next_command].left;
      cw = out.commands[next_command].angular;
      ++next_command;
    }
    double gf = cf, gl = cl;
    const double speed = std::hypot(gf, gl);
    if (speed > truth.max_speed) gf *= truth.max_speed / speed, gl *= truth.max_speed / speed;
    const double gw = std::clamp(cw, -truth.angular_speed, truth.angular_speed);
    const double df = gf - sf, dl = gl - sl, length = std::hypot(df, dl);
    if (length > 0) {
      const bool slowing = std::hypot(gf, gl) < std::hypot(sf, sl) || gf * sf + gl * sl < 0;
      const double af = slowing ? truth.brake_along : truth.accel_along;
      const double al = slowing ? truth.brake_across : truth.accel_across;
      const double limit = 1 / std::hypot(df / length / af, dl / length / al);
      if (length <= limit * dt) {
        sf = gf, sl = gl;
      } else {
        sf += df / length * limit * dt, sl += dl / length * limit * dt;
      }
    }
    sw = Ramp(sw, gw, truth.angular_accel, truth.angular_brake, dt);
    vf += (sf - vf) * blend;
    vl += (sl - vl) * blend;
    vw += (sw - vw) * blend;
    xs[static_cast<std::size_t>(i)] = x;
    ys[static_cast<std::size_t>(i)] = y;
    yaws[static_cast<std::size_t>(i)] = yaw;
    x += (std::cos(yaw) * vf - std::sin(yaw) * vl) * dt;
    y += (std::sin(yaw) * vf + std::cos(yaw) * vl) * dt;
    yaw += vw * dt;
  }
  // Two unsynchronised cameras, 60 and 75 Hz, each with its own small offset; 2 mm and 0.015 rad
  // noise; 5 % of the detections lost.
  struct Camera {
    int id;
    double rate, phase, dx, dy, dyaw;
  };
  const Camera cameras[] = {{0, 60.0, 0.0031, 0.0, 0.0, 0.0}, {1, 75.0, 0.0107, 0.0015, -0.0010, 0.004}};
  for (const Camera& cam : cameras) {
    for (int k = 0;; ++k) {
      const double t = cam.phase + k / cam.rate;
      if (t >= (steps - 2) * dt) break;
      if (uniform(random) < 0.05) continue;
      const auto i = static_cast<std::size_t>(t / dt);
      const double f = t / dt - static_cast<double>(i);
      TrackPoint p;
      p.t = t;
      p.camera_id = cam.id;
      p.x = xs[i] + f * (xs[i + 1] - xs[i]) + cam.dx + 0.002 * unit(random);
      p.y = ys[i] + f * (ys[i + 1] - ys[i]) + cam.dy + 0.002 * unit(random);
      const double true_yaw = yaws[i] + f * (yaws[i + 1] - yaws[i]);
      p.yaw = std::remainder(true_yaw + cam.dyaw + 0.015 * unit(random), 2 * M_PI);
      if (uniform(random) < outlier_rate) p.x += 0.05, p.y -= 0.04, p.yaw += 0.5;  // a ghost
      out.track.push_back(p);
    }
  }
  std::stable_sort(out.track.begin(), out.track.end(), [](const TrackPoint& a, const TrackPoint& b) { return a.t < b.t; });
  return out;
}

RobotFitInput Input(const Session& session, bool with_commands) {
  RobotFitInput input;
  input.robot = {TeamColour::kBlue, 3};
  input.track = session.track;
  if (with_commands) input.commands = session.commands;
  return input;
}

void ExpectNear(const Estimate& e, double truth, double tolerance, bool inside, const char* what) {
  SCOPED_TRACE(what);
  ASSERT_TRUE(e.ok());
  EXPECT_NEAR(e.value, truth, tolerance * truth) << "low " << e.low << " high " << e.high << " n " << e.samples;
  EXPECT_LE(e.low, e.value);
  EXPECT_GE(e.high, e.value);
  if (inside) {
    EXPECT_LE(e.low, truth) << "value " << e.value;
    EXPECT_GE(e.high, truth) << "value " << e.value;
  }
}

void ExpectFinite(const RobotFit& fit) {
  for (const Estimate* e : {&fit.top_speed, &fit.accel_along, &fit.brake_along, &fit.accel_across, &fit.brake_across,
                            &fit.angular_top_speed, &fit.angular_accel, &fit.angular_brake, &fit.latency, &fit.wheel_lag}) {
    EXPECT_TRUE(std::isfinite(e->value) && std::isfinite(e->low) && std::isfinite(e->high));
  }
  for (const SegmentRecord& r : fit.segments) {
    EXPECT_TRUE(std::isfinite(r.slope) && std::isfinite(r.onset) && std::isfinite(r.v_end) && std::isfinite(r.rms));
  }
}

TEST(RobotFit, RecoversLimitsLatencyAndLagFromCommands) {
  const Truth truth;
  const Session session = Simulate(truth, CalibrationScript(2), 7, 0.002);
  const RobotFit fit = FitRobot(Input(session, true));
  for (const auto& p : fit.problems) ADD_FAILURE() << "unexpected problem: " << p;
  ASSERT_TRUE(fit.enough_data);
  EXPECT_TRUE(fit.from_commands);
  ExpectFinite(fit);
  ExpectNear(fit.top_speed, truth.max_speed, 0.03, true, "top speed");
  ExpectNear(fit.accel_along, truth.accel_along, 0.10, true, "accel along");
  ExpectNear(fit.brake_along, truth.brake_along, 0.10, true, "brake along");
  ExpectNear(fit.accel_across, truth.accel_across, 0.10, true, "accel across");
  ExpectNear(fit.brake_across, truth.brake_across, 0.10, true, "brake across");
  ExpectNear(fit.angular_top_speed, truth.angular_speed, 0.03, true, "angular top speed");
  ExpectNear(fit.angular_accel, truth.angular_accel, 0.10, true, "angular accel");
  ExpectNear(fit.angular_brake, truth.angular_brake, 0.10, true, "angular brake");
  ASSERT_TRUE(fit.latency.ok());
  EXPECT_NEAR(fit.latency.value, truth.latency, 0.008);
  EXPECT_LE(fit.latency.low, truth.latency);
  EXPECT_GE(fit.latency.high, truth.latency);
  ASSERT_TRUE(fit.wheel_lag.ok());
  EXPECT_NEAR(fit.wheel_lag.value, truth.lag, 0.008);
  // Every step of the script was found: 2 repeats × 12 steps, each followed by a stop.
  int used = 0;
  for (const SegmentRecord& r : fit.segments) used += r.used ? 1 : 0;
  EXPECT_GE(used, 44);
  EXPECT_EQ(fit.top_speed.samples, 8);  // full-speed linear steps
  EXPECT_EQ(fit.angular_top_speed.samples, 4);
}

// Another robot, so nothing is tuned to one set of numbers: fast, sluggish to start, braking
// less than it accelerates when turning, a long latency and hardly any lag; and ghost detections.
TEST(RobotFit, RecoversAnotherRobot) {
  Truth truth;
  truth.max_speed = 3.6;
  truth.accel_along = truth.accel_across = 2.5;
  truth.brake_along = truth.brake_across = 5.0;
  truth.angular_speed = 12;
  truth.angular_accel = 60;
  truth.angular_brake = 25;
  truth.latency = 0.09;
  truth.lag = 0.004;
  std::vector<Step> script = CalibrationScript(1);
  for (Step& s : script) s.forward *= 1.5, s.left *= 1.5, s.angular *= 1.5, s.hold += s.hold > 1.2 ? 0.6 : 0;
  // With ghosts: 1 % of the detections 5 cm and 0.5 rad off (another robot's blob, a flip).
  const RobotFit fit = FitRobot(Input(Simulate(truth, script, 11, 0.01), true));
  ASSERT_TRUE(fit.enough_data);
  EXPECT_TRUE(std::any_of(fit.problems.begin(), fit.problems.end(),
                          [](const std::string& p) { return p.find("jumped off the track") != std::string::npos; }));
  ExpectNear(fit.top_speed, truth.max_speed, 0.03, true, "top speed");
  ExpectNear(fit.accel_along, truth.accel_along, 0.10, true, "accel along");
  ExpectNear(fit.brake_along, truth.brake_along, 0.10, true, "brake along");
  ExpectNear(fit.accel_across, truth.accel_across, 0.10, true, "accel across");
  ExpectNear(fit.brake_across, truth.brake_across, 0.10, true, "brake across");
  ExpectNear(fit.angular_top_speed, truth.angular_speed, 0.03, true, "angular top speed");
  ExpectNear(fit.angular_accel, truth.angular_accel, 0.10, true, "angular accel");
  ExpectNear(fit.angular_brake, truth.angular_brake, 0.10, true, "angular brake");
  ASSERT_TRUE(fit.latency.ok());
  EXPECT_NEAR(fit.latency.value, truth.latency, 0.008);
}

TEST(RobotFit, WithoutCommandsRecoversLimitsButNoLatency) {
  const Truth truth;
  const RobotFit fit = FitRobot(Input(Simulate(truth, CalibrationScript(2), 7), false));
  ASSERT_TRUE(fit.enough_data);
  EXPECT_FALSE(fit.from_commands);
  ExpectFinite(fit);
  ExpectNear(fit.top_speed, truth.max_speed, 0.15, false, "top speed");
  ExpectNear(fit.accel_along, truth.accel_along, 0.15, false, "accel along");
  ExpectNear(fit.brake_along, truth.brake_along, 0.15, false, "brake along");
  ExpectNear(fit.accel_across, truth.accel_across, 0.15, false, "accel across");
  ExpectNear(fit.brake_across, truth.brake_across, 0.15, false, "brake across");
  ExpectNear(fit.angular_top_speed, truth.angular_speed, 0.15, false, "angular top speed");
  ExpectNear(fit.angular_accel, truth.angular_accel, 0.15, false, "angular accel");
  ExpectNear(fit.angular_brake, truth.angular_brake, 0.15, false, "angular brake");
  EXPECT_FALSE(fit.latency.ok());
  EXPECT_FALSE(fit.wheel_lag.ok());
  EXPECT_TRUE(std::any_of(fit.problems.begin(), fit.problems.end(),
                          [](const std::string& p) { return p.find("latency") != std::string::npos; }));
}

TEST(RobotFit, TooLittleDataSaysSo) {
  const Truth truth;
  // Standing still for 20 s, commands all zero, and without commands.
  const Session still = Simulate(truth, {{0, 0, 0, 20.0}}, 3);
  for (const bool commands : {true, false}) {
    const RobotFit fit = FitRobot(Input(still, commands));
    EXPECT_FALSE(fit.enough_data) << commands;
    EXPECT_FALSE(fit.problems.empty());
    EXPECT_FALSE(fit.top_speed.ok());
    EXPECT_FALSE(fit.latency.ok());
    ExpectFinite(fit);
  }
  // One second of a session that moves.
  Session session = Simulate(truth, CalibrationScript(1), 5);
  const double t0 = 0.9;
  std::erase_if(session.track, [&](const TrackPoint& p) { return p.t < t0 || p.t > t0 + 1.0; });
  std::erase_if(session.commands, [&](const CommandSample& c) { return c.t < t0 || c.t > t0 + 1.0; });
  const RobotFit fit = FitRobot(Input(session, true));
  EXPECT_FALSE(fit.enough_data);
  ASSERT_FALSE(fit.problems.empty());
  EXPECT_NE(fit.problems.front().find("s of track"), std::string::npos) << fit.problems.front();
  ExpectFinite(fit);
  // And nothing at all.
  const RobotFit empty = FitRobot(RobotFitInput{});
  EXPECT_FALSE(empty.enough_data);
  EXPECT_FALSE(empty.problems.empty());
}

TEST(RobotFit, ReportHasTableAndPlots) {
  const Truth truth;
  const Session session = Simulate(truth, CalibrationScript(1), 9);
  const RobotFitInput input = Input(session, true);
  const RobotFit fit = FitRobot(input);
  ASSERT_TRUE(fit.enough_data);
  const ReportSection report = RobotReport(fit, input);
  EXPECT_EQ(report.markdown.rfind("### blue 3\n", 0), 0u);
  EXPECT_NE(report.markdown.find("| top speed | 2.2"), std::string::npos) << report.markdown;
  EXPECT_NE(report.markdown.find("| latency |"), std::string::npos);
  EXPECT_NE(report.markdown.find("#### Steps"), std::string::npos);
  ASSERT_EQ(report.plots.size(), 3u);  // forward, left, angular
  for (const validation::Plot& plot : report.plots) {
    EXPECT_EQ(plot.file.rfind("robot-blue-3-", 0), 0u) << plot.file;
    EXPECT_NE(report.markdown.find("(" + plot.file + ")"), std::string::npos);
    ASSERT_GE(plot.series.size(), 3u);
    EXPECT_TRUE(plot.series.front().points);
    EXPECT_GT(plot.series.front().x.size(), 100u);
    EXPECT_EQ(plot.series.front().x.size(), plot.series.front().y.size());
  }
  // The model follows the measured forward velocity on the forward plot (a rough check of the
  // overlay: means of both over the window agree within 5 %).
  const validation::Plot& forward = report.plots.front();
  const auto mean = [](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / v.size(); };
  const validation::Series* model = nullptr;
  for (const auto& s : forward.series) {
    if (s.label == "forward model") model = &s;
  }
  ASSERT_NE(model, nullptr);
  EXPECT_NEAR(mean(model->y), mean(forward.series.front().y), 0.05 * std::abs(mean(forward.series.front().y)));

  const RobotFitInput blind = Input(session, false);
  const ReportSection without = RobotReport(FitRobot(blind), blind);
  EXPECT_NE(without.markdown.find("without commands"), std::string::npos);
  EXPECT_FALSE(without.plots.empty());
}

}  // namespace
}  // namespace ubersim::calibrate
