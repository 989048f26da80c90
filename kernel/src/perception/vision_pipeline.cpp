// SPDX-License-Identifier: Apache-2.0
#include "perception/vision_pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace ubersim::kernel {
namespace {

std::int64_t Ns(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e9)); }

double WrapAngle(double a) {
  a = std::fmod(a + M_PI, 2 * M_PI);
  if (a < 0) a += 2 * M_PI;
  return a - M_PI;
}

// The vision's own random stream from the world's seed (the radio's is another: radio_link.cpp).
constexpr std::uint64_t kVisionStream = 0x5653494f4e000001ULL;

}  // namespace

PerceptionPipeline::PerceptionPipeline(PerceptionModel model, std::uint64_t seed)
    : model_(std::move(model)),
      seed_(seed),
      period_ns_(std::max<std::int64_t>(1, Ns(1.0 / model_.frame_rate))),
      latency_ns_(Ns(model_.latency)) {
  Reset();
}

void PerceptionPipeline::Reset(std::uint64_t seed) {
  seed_ = seed;
  Reset();
}

void PerceptionPipeline::Reset() {
  next_capture_ns_.assign(model_.cameras.size(), period_ns_);
  frame_numbers_.assign(model_.cameras.size(), 0);
  in_flight_.clear();
  rng_.seed(seed_ ^ kVisionStream);
}

void PerceptionPipeline::Configure(const PerceptionModel& model) {
  const double rate = model_.frame_rate;
  const std::vector<CameraModel> cameras = model_.cameras;
  model_ = model;
  model_.frame_rate = rate;
  model_.cameras = cameras;
  latency_ns_ = Ns(model_.latency);
}

void PerceptionPipeline::SetCameras(std::vector<CameraModel> cameras) {
  const std::int64_t next = next_capture_ns_.empty()
                                ? period_ns_
                                : *std::min_element(next_capture_ns_.begin(), next_capture_ns_.end());
  std::vector<std::int64_t> schedule(cameras.size(), next);
  std::vector<std::uint32_t> numbers(cameras.size(), 0);
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    for (std::size_t j = 0; j < model_.cameras.size(); ++j) {
      if (model_.cameras[j].id == cameras[i].id) {
        schedule[i] = next_capture_ns_[j];
        numbers[i] = frame_numbers_[j];
      }
    }
  }
  model_.cameras = std::move(cameras);
  next_capture_ns_ = std::move(schedule);
  frame_numbers_ = std::move(numbers);
}

bool PerceptionPipeline::CaptureDue(std::int64_t now_ns) const {
  return std::any_of(next_capture_ns_.begin(), next_capture_ns_.end(),
                     [now_ns](std::int64_t t) { return t <= now_ns; });
}

void PerceptionPipeline::Capture(const WorldSnapshot& truth) {
  for (std::size_t c = 0; c < model_.cameras.size(); ++c) {
    if (next_capture_ns_[c] > truth.sim_time_ns) continue;
    in_flight_.push_back(Frame(c, truth));
    // The next frame on the camera's own schedule (a long step skips frames, as a slow PC would).
    while (next_capture_ns_[c] <= truth.sim_time_ns) next_capture_ns_[c] += period_ns_;
  }
}

PerceptionState PerceptionPipeline::SaveState() const {
  PerceptionState s;
  s.model = model_;
  s.next_capture_ns = next_capture_ns_;
  s.frame_numbers = frame_numbers_;
  s.in_flight.assign(in_flight_.begin(), in_flight_.end());
  std::ostringstream rng;
  rng << rng_;  // the standard's round-trip text form of the engine
  s.rng = rng.str();
  return s;
}

void PerceptionPipeline::RestoreState(const PerceptionState& s) {
  if (s.next_capture_ns.size() != model_.cameras.size() || s.frame_numbers.size() != model_.cameras.size()) {
    throw std::invalid_argument("the saved vision state has " + std::to_string(s.next_capture_ns.size()) +
                                " cameras, this world " + std::to_string(model_.cameras.size()));
  }
  std::mt19937_64 rng;
  std::istringstream in(s.rng);
  in >> rng;
  if (!in) throw std::invalid_argument("the saved vision noise generator is unreadable");
  // Only what realism events change comes from the snapshot; the rest is the world file's.
  PerceptionModel m = model_;
  m.latency = s.model.latency;
  m.ball_position_sigma = s.model.ball_position_sigma;
  m.robot_position_sigma = s.model.robot_position_sigma;
  m.robot_orientation_sigma = s.model.robot_orientation_sigma;
  m.ball_drop = s.model.ball_drop;
  m.robot_drop = s.model.robot_drop;
  m.camera_overlap = s.model.camera_overlap;
  Configure(m);
  next_capture_ns_ = s.next_capture_ns;
  frame_numbers_ = s.frame_numbers;
  in_flight_.assign(s.in_flight.begin(), s.in_flight.end());
  rng_ = rng;
}

std::vector<VisionFrame> PerceptionPipeline::Release(std::int64_t now_ns) {
  std::vector<VisionFrame> out;
  while (!in_flight_.empty() && in_flight_.front().t_sent_ns <= now_ns) {
    out.push_back(std::move(in_flight_.front()));
    in_flight_.pop_front();
  }
  return out;
}

bool PerceptionPipeline::Sees(const CameraModel& c, double x, double y) const {
  const double o = model_.camera_overlap;
  return x >= c.x_min - o && x <= c.x_max + o && y >= c.y_min - o && y <= c.y_max + o;
}

VisionFrame PerceptionPipeline::Frame(std::size_t index, const WorldSnapshot& truth) {
  const CameraModel& cam = model_.cameras[index];
  std::normal_distribution<double> unit_noise(0.0, 1.0);
  std::uniform_real_distribution<double> chance(0.0, 1.0);
  VisionFrame f;
  f.camera_id = cam.id;
  f.frame_number = frame_numbers_[index]++;
  f.t_capture_ns = truth.sim_time_ns;
  f.t_sent_ns = truth.sim_time_ns + latency_ns_;
  // Every random number is drawn whether or not it is used, so one object's drop-out does not
  // shift the noise of everything after it.
  const BallState& b = truth.ball;
  const double ball_noise_x = unit_noise(rng_), ball_noise_y = unit_noise(rng_);
  const bool ball_lost = chance(rng_) < model_.ball_drop;
  if (Sees(cam, b.pose.position.x(), b.pose.position.y()) && !ball_lost) {
    // A camera sees an airborne ball where its ray through the ball meets the carpet.
    const double h = std::clamp(b.pose.position.z() - b.radius, 0.0, 0.9 * cam.position.z());
    const double scale = cam.position.z() / (cam.position.z() - h);
    DetectedBall d;
    d.x = cam.position.x() + (b.pose.position.x() - cam.position.x()) * scale +
          model_.ball_position_sigma * ball_noise_x;
    d.y = cam.position.y() + (b.pose.position.y() - cam.position.y()) * scale +
          model_.ball_position_sigma * ball_noise_y;
    d.z = 0.0;
    f.balls.push_back(d);
  }
  for (const RobotState& r : truth.robots) {
    const double nx = unit_noise(rng_), ny = unit_noise(rng_), nyaw = unit_noise(rng_);
    const bool lost = chance(rng_) < model_.robot_drop;
    if (!r.present || lost || !Sees(cam, r.pose.position.x(), r.pose.position.y())) continue;
    DetectedRobot d;
    d.id = r.id;
    d.x = r.pose.position.x() + model_.robot_position_sigma * nx;
    d.y = r.pose.position.y() + model_.robot_position_sigma * ny;
    d.yaw = WrapAngle(r.pose.Yaw() + model_.robot_orientation_sigma * nyaw);
    f.robots.push_back(d);
  }
  return f;
}

}  // namespace ubersim::kernel
