// SPDX-License-Identifier: Apache-2.0
#include "perception/vision_pipeline.hpp"

#include "perception/occlusion.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <boost/random/normal_distribution.hpp>

namespace ubersim::kernel {
namespace {

std::int64_t Ns(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e9)); }

double WrapAngle(double a) {
  a += M_PI;
  // fmod returns an a in [0, 2π) as it is: the call (most of this function's cost) is needed
  // only outside, and the result is the same to the bit either way.
  if (!(a >= 0 && a < 2 * M_PI)) {
    a = std::fmod(a, 2 * M_PI);
    if (a < 0) a += 2 * M_PI;
  }
  return a - M_PI;
}

// The vision's own random stream from the world's seed (the radio's is another: radio_link.cpp).
constexpr std::uint64_t kVisionStream = 0x5653494f4e000001ULL;
// The cameras' frame phases: a stream of their own, so that they do not move the noise.
constexpr std::uint64_t kPhaseStream = 0x5048415345000003ULL;
// The camera lens's focal length in pixels that ER-Force's simulator computes the ball blob's
// area with (reference/ssl-protocols.md §6.2).
constexpr double kFocalLengthPx = 390.0;

// SplitMix64's finaliser (Steele, Lea and Flood 2014): a 64-bit value's bits mixed into all others.
std::uint64_t Mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// The random numbers of one object in one camera frame: SplitMix64 from a key of the world's
// seed, the camera, the frame and the object. An object's noise depends on nothing else, so a
// camera draws only for what it sees (half the field, in Division A), and no object's drop-out,
// coming into view or leaving shifts another's noise. A standard uniform random bit generator.
class ObjectDraws {
 public:
  using result_type = std::uint64_t;
  ObjectDraws(std::uint64_t frame_key, std::uint64_t object) : state_(Mix(frame_key ^ Mix(object))) {}
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return ~result_type{0}; }
  result_type operator()() { return Mix(state_ += 0x9e3779b97f4a7c15ULL); }

 private:
  std::uint64_t state_;
};

// The key of a robot's draws (the ball's is 0): its team and id, whatever its place in the list.
std::uint64_t ObjectKey(const RobotId& id) {
  return 1 + (static_cast<std::uint64_t>(id.team == Team::kBlue ? 0 : 1) << 32) + static_cast<std::uint32_t>(id.id);
}

// The area in pixels of a whole ball of `radius` at `at`, seen by a camera at `camera`.
double BallDiscArea(const Vec3& camera, const Vec3& at, double radius) {
  const double disc_px = kFocalLengthPx * radius / std::max(0.1, (camera - at).norm());
  return M_PI * disc_px * disc_px;
}

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
  // Synchronised cameras all capture on one grid; unsynchronised ones each on its own phase.
  phase_ns_.assign(model_.cameras.size(), 0);
  if (model_.unsynchronised_cameras) {
    std::mt19937_64 phases(seed_ ^ kPhaseStream);
    std::uniform_int_distribution<std::int64_t> phase(0, period_ns_ - 1);
    for (std::int64_t& p : phase_ns_) p = phase(phases);
  }
  next_capture_ns_.resize(model_.cameras.size());
  for (std::size_t c = 0; c < next_capture_ns_.size(); ++c) next_capture_ns_[c] = period_ns_ + phase_ns_[c];
  frame_numbers_.assign(model_.cameras.size(), 0);
  in_flight_.clear();
  rng_.seed(seed_ ^ kVisionStream);
}

std::int64_t PerceptionPipeline::NextCapture(std::size_t c, std::int64_t now_ns) {
  // The camera's next frame on its own grid after now (a long step skips frames, as a slow PC
  // would), then its jitter: drawn only when there is some, so that none leaves the noise as it was.
  const std::int64_t phase = c < phase_ns_.size() ? phase_ns_[c] : 0;
  if (model_.capture_jitter <= 0) return phase + ((now_ns - phase) / period_ns_ + 1) * period_ns_;
  // With jitter a capture may come before its grid point: the frame just taken is the grid
  // point nearest to now, the next one the grid point after it.
  const std::int64_t taken = (now_ns - phase + period_ns_ / 2) / period_ns_;
  std::normal_distribution<double> jitter(0.0, model_.capture_jitter);
  const double half = 0.45 * static_cast<double>(period_ns_) * 1e-9;  // frames keep their order
  const std::int64_t next = phase + (taken + 1) * period_ns_ + Ns(std::clamp(jitter(rng_), -half, half));
  return std::max(next, now_ns + 1);
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
  std::vector<std::int64_t> phases(cameras.size(), 0);
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    for (std::size_t j = 0; j < model_.cameras.size() && j < phase_ns_.size(); ++j) {
      if (model_.cameras[j].id == cameras[i].id) phases[i] = phase_ns_[j];
    }
  }
  model_.cameras = std::move(cameras);
  phase_ns_ = std::move(phases);
  next_capture_ns_ = std::move(schedule);
  frame_numbers_ = std::move(numbers);
}

bool PerceptionPipeline::CaptureDue(std::int64_t now_ns) const {
  return std::any_of(next_capture_ns_.begin(), next_capture_ns_.end(),
                     [now_ns](std::int64_t t) { return t <= now_ns; });
}

void PerceptionPipeline::Capture(const WorldSnapshot& truth, const std::vector<double>& front_distances) {
  for (std::size_t c = 0; c < model_.cameras.size(); ++c) {
    if (next_capture_ns_[c] > truth.sim_time_ns) continue;
    VisionFrame f = Frame(c, truth, front_distances);
    // Frames leave in the order of their send times (unsynchronised cameras interleave).
    auto at = in_flight_.end();
    while (at != in_flight_.begin() && std::prev(at)->t_sent_ns > f.t_sent_ns) --at;
    in_flight_.insert(at, std::move(f));
    next_capture_ns_[c] = NextCapture(c, truth.sim_time_ns);
  }
}

Vec3 ReportedCameraPosition(const PerceptionModel& model, const CameraModel& camera) {
  // The direction the league's camera_position_error offsets the positions in (§6.1).
  static const Vec3 direction = Vec3(0.3, 0.7, 0.05).normalized();
  return camera.position + model.camera_position_error * direction;
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
  m.ball_occlusion = s.model.ball_occlusion;
  m.ball_visibility_threshold = s.model.ball_visibility_threshold;
  m.ball_area_sigma = s.model.ball_area_sigma;
  m.dribbler_false_balls = s.model.dribbler_false_balls;
  m.camera_position_error = s.model.camera_position_error;
  m.object_offset = s.model.object_offset;
  m.processing_time = s.model.processing_time;
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

Vec3 PerceptionPipeline::Reported(const CameraModel& cam, const Vec3& at, double radius) const {
  // A camera sees an airborne ball where its ray through the ball meets the carpet.
  const double h = std::clamp(at.z() - radius, 0.0, 0.9 * cam.position.z());
  const double scale = cam.position.z() / (cam.position.z() - h);
  Vec3 p(cam.position.x() + (at.x() - cam.position.x()) * scale, cam.position.y() + (at.y() - cam.position.y()) * scale,
         0.0);
  return p;
}

VisionFrame PerceptionPipeline::Frame(std::size_t index, const WorldSnapshot& truth,
                                      const std::vector<double>& front_distances) {
  const CameraModel& cam = model_.cameras[index];
  // Boost's normal distribution (the ziggurat) draws a fifth of what the standard library's
  // polar method costs, logarithm and all: a frame draws three for every robot.
  boost::random::normal_distribution<double> unit_noise(0.0, 1.0);
  std::uniform_real_distribution<double> chance(0.0, 1.0);
  VisionFrame f;
  f.camera_id = cam.id;
  f.frame_number = frame_numbers_[index]++;
  const std::uint64_t frame_key = Mix(Mix(Mix(seed_ ^ kVisionStream) ^ index) ^ f.frame_number);
  f.t_sent_ns = truth.sim_time_ns + latency_ns_;
  // The capture time the frame reports: the true one, or the sending time less the processing
  // time the league's presets give (which is shorter than the whole delay).
  f.t_capture_ns = model_.processing_time ? f.t_sent_ns - Ns(*model_.processing_time) : truth.sim_time_ns;
  // Noise grows away from the camera's nadir; every position shifts from the field's centre
  // towards the camera (none for a camera above the centre).
  const auto growth = [&](double x, double y) {
    // Not std::hypot: its overflow guard costs ten times the arithmetic, for distances of metres.
    const double dx = x - cam.position.x(), dy = y - cam.position.y();
    return 1.0 + model_.noise_growth * std::sqrt(dx * dx + dy * dy);
  };
  Vec3 offset = Vec3::Zero();
  if (model_.object_offset > 0 && std::hypot(cam.position.x(), cam.position.y()) > 1e-6) {
    offset = model_.object_offset * Vec3(cam.position.x(), cam.position.y(), 0.0).normalized();
  }
  // Each object's random numbers come from its own stream (ObjectDraws), drawn in a fixed order
  // whether or not they are used; what a setting adds is drawn only when it is on.
  const BallState& b = truth.ball;
  f.robots.reserve(truth.robots.size());  // grown once, not doubled from one
  ObjectDraws ball_draws(frame_key, 0);
  const bool ball_in_view = Sees(cam, b.pose.position.x(), b.pose.position.y());
  const double ball_noise_x = ball_in_view ? unit_noise(ball_draws) : 0.0;
  const double ball_noise_y = ball_in_view ? unit_noise(ball_draws) : 0.0;
  const bool ball_lost = ball_in_view && chance(ball_draws) < model_.ball_drop;
  const double area_noise = ball_in_view && model_.ball_area_sigma > 0 ? unit_noise(ball_draws) : 0.0;
  if (ball_in_view && !ball_lost) {
    BallVisibility seen;
    seen.centroid = b.pose.position;
    if (model_.ball_occlusion) {
      seen = VisibleBall(b.pose.position, b.radius, cam.position, truth.robots, front_distances);
    }
    if (!model_.ball_occlusion || seen.fraction >= model_.ball_visibility_threshold) {
      // A moving ball smears over the exposure: its blob's centroid half the travel behind.
      const Vec3 travel = b.twist.linear * model_.exposure;
      const Vec3 p = Reported(cam, seen.centroid - 0.5 * travel, b.radius);
      const double sigma = model_.ball_position_sigma * growth(p.x(), p.y());
      DetectedBall d;
      d.x = p.x() + sigma * ball_noise_x + offset.x();
      d.y = p.y() + sigma * ball_noise_y + offset.y();
      d.z = 0.0;
      // The blob: the ball's disc at its distance from the camera, the part of it seen, longer by
      // the smear, with noise.
      const double smear = 1.0 + 2.0 * travel.head<2>().norm() / (M_PI * b.radius);
      d.area = std::max(0.0, BallDiscArea(cam.position, b.pose.position, b.radius) * seen.fraction * smear +
                                 model_.ball_area_sigma * area_noise);
      f.balls.push_back(d);
    }
  }
  for (std::size_t i = 0; i < truth.robots.size(); ++i) {
    const RobotState& r = truth.robots[i];
    if (!r.present || !Sees(cam, r.pose.position.x(), r.pose.position.y())) continue;
    ObjectDraws draws(frame_key, ObjectKey(r.id));
    const double nx = unit_noise(draws);
    const double ny = unit_noise(draws);
    const double nyaw = unit_noise(draws);
    const bool lost = chance(draws) < model_.robot_drop;
    // A false ball at a corner of its dribbler: the light barrier's red diode, seen as a ball.
    bool false_ball = false, left_corner = false;
    if (model_.dribbler_false_balls > 0) {
      false_ball = chance(draws) < model_.dribbler_false_balls / model_.frame_rate;
      left_corner = chance(draws) < 0.5;
    }
    if (false_ball && i < front_distances.size()) {
      const double front = front_distances[i];
      const double side = std::sqrt(std::max(0.0, r.radius * r.radius - front * front)) * (left_corner ? 1 : -1);
      const double yaw = r.pose.Yaw();
      DetectedBall d;
      d.x = r.pose.position.x() + front * std::cos(yaw) - side * std::sin(yaw) + offset.x();
      d.y = r.pose.position.y() + front * std::sin(yaw) + side * std::cos(yaw) + offset.y();
      d.area = BallDiscArea(cam.position, r.pose.position, b.radius);
      f.balls.push_back(d);
    }
    if (lost) continue;
    const double sigma = growth(r.pose.position.x(), r.pose.position.y());
    DetectedRobot d;
    d.id = r.id;
    d.x = r.pose.position.x() + model_.robot_position_sigma * sigma * nx + offset.x();
    d.y = r.pose.position.y() + model_.robot_position_sigma * sigma * ny + offset.y();
    d.yaw = WrapAngle(r.pose.Yaw() + model_.robot_orientation_sigma * sigma * nyaw);
    f.robots.push_back(d);
  }
  // Several ball detections in a frame come in no particular order, as from ssl-vision.
  if (f.balls.size() > 1) std::shuffle(f.balls.begin(), f.balls.end(), rng_);
  return f;
}

}  // namespace ubersim::kernel
