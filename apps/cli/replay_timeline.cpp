// SPDX-License-Identifier: Apache-2.0
#include "replay_timeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <span>

#include "ssl_gc_referee_message.pb.h"
#include "ssl_vision_wrapper.pb.h"
#include "viewer_referee.hpp"

namespace ubersim::cli {
namespace {

constexpr double kMm = 1e-3;
constexpr std::int64_t kRefereeSilence = 500'000'000;  // a longer gap between two messages ends a span
constexpr double kBallMergeRadius = 0.2;               // m: another camera's ball this close is the same ball
// The viewer's rate for the match: the game controller sends 40 a second, the scoreboard reads well at 10.
constexpr std::int64_t kRefereeIntervalNs = 100'000'000;

bool Shown(std::int32_t type) { return type >= 2 && type <= 5; }

// mm (a detection's unit) to the int16 kept; a value off any field (or not finite) is clamped.
std::int16_t Mm(float mm) {
  if (!std::isfinite(mm)) return 0;
  return static_cast<std::int16_t>(std::clamp(std::lround(mm), -32767L, 32767L));
}

std::uint8_t Confidence(float c) {
  if (!(c > 0)) return 0;
  return static_cast<std::uint8_t>(std::lround(std::min(1.0f, c) * 255.0f));
}

constexpr double kHeadingUnit = 1e-4;  // rad

LogTimeline::Geometry FromPacket(const SSL_GeometryData& g, std::int64_t t_ns) {
  LogTimeline::Geometry out;
  out.t_ns = t_ns;
  const SSL_GeometryFieldSize& f = g.field();
  FieldGeometry& field = out.field;
  field.name = "";
  field.field_length = f.field_length() * kMm;
  field.field_width = f.field_width() * kMm;
  field.goal_width = f.goal_width() * kMm;
  field.goal_depth = f.goal_depth() * kMm;
  field.goal_height = f.has_goal_height() ? f.goal_height() * kMm : 0.155;
  field.boundary_width = f.boundary_width() * kMm;
  field.penalty_area_depth = f.has_penalty_area_depth() ? f.penalty_area_depth() * kMm : 0;
  field.penalty_area_width = f.has_penalty_area_width() ? f.penalty_area_width() * kMm : 0;
  field.center_circle_radius = f.has_center_circle_radius() ? f.center_circle_radius() * kMm : 0;
  field.line_thickness = f.has_line_thickness() ? f.line_thickness() * kMm : 0.01;
  field.goal_center_to_penalty_mark = f.has_goal_center_to_penalty_mark() ? f.goal_center_to_penalty_mark() * kMm : 0;
  field.carpet_length = field.field_length + 2 * field.boundary_width;
  field.carpet_width = field.field_width + 2 * field.boundary_width;
  for (const SSL_FieldLineSegment& l : f.field_lines()) {
    field.lines.push_back(FieldLine{l.name(), l.p1().x() * kMm, l.p1().y() * kMm, l.p2().x() * kMm, l.p2().y() * kMm,
                                    l.thickness() * kMm});
  }
  for (const SSL_FieldCircularArc& a : f.field_arcs()) {
    field.arcs.push_back(FieldArc{a.name(), a.center().x() * kMm, a.center().y() * kMm, a.radius() * kMm, a.a1(),
                                  a.a2(), a.thickness() * kMm});
  }
  if (f.has_ball_radius() && f.ball_radius() > 0) out.ball_radius = f.ball_radius() * kMm;
  if (f.has_max_robot_radius() && f.max_robot_radius() > 0) out.robot_radius = f.max_robot_radius() * kMm;
  for (const SSL_GeometryCameraCalibration& c : g.calib()) {
    if (!c.has_derived_camera_world_tx() || !c.has_derived_camera_world_ty()) continue;
    out.cameras.push_back(CameraInfo{static_cast<int>(c.camera_id()),
                                     Vec3(c.derived_camera_world_tx() * kMm, c.derived_camera_world_ty() * kMm,
                                          c.derived_camera_world_tz() * kMm)});
  }
  return out;
}

}  // namespace

FieldGeometry DivisionBField() {
  FieldGeometry f;
  f.name = "";
  f.field_length = 9.0;
  f.field_width = 6.0;
  f.goal_width = 1.0;
  f.goal_depth = 0.18;
  f.goal_height = 0.155;
  f.boundary_width = 0.3;
  f.penalty_area_depth = 1.0;
  f.penalty_area_width = 2.0;
  f.center_circle_radius = 0.5;
  f.line_thickness = 0.01;
  f.goal_center_to_penalty_mark = 6.0;
  f.carpet_length = 9.6;
  f.carpet_width = 6.6;
  return f;
}

// ---------------------------------------------------------------------------------------------
// Loading

struct LogTimeline::Loader {
  LogTimeline& tl;
  std::optional<std::int64_t> first_ns;
  std::int64_t last_t = -1;  // the time line so far (never goes back)
  std::int64_t next_checkpoint = 0;
  std::string last_geometry;  // serialized, to keep only distinct ones
  SSL_WrapperPacket wrapper;  // reused: its storage stays allocated
  ::Referee referee;
  // The referee's rate limit, as the live viewer's relay: a message at most every 100 ms, the
  // newest; one held back is kept when the interval is over.
  std::optional<RefereeState> held;
  std::int64_t next_keep = std::numeric_limits<std::int64_t>::min();
  std::shared_ptr<const std::string> earlier_event;
  std::optional<RefereeSpan> span;

  explicit Loader(LogTimeline& timeline) : tl(timeline) {}

  void Add(const sslog::LogRecord& r, std::int64_t offset, std::int64_t records_before) {
    ++tl.counts_.records;
    if (!Shown(r.type)) return;
    if (!first_ns) first_ns = r.timestamp_ns;
    const std::int64_t t = std::max(last_t, r.timestamp_ns - *first_ns);
    if (t >= (std::int64_t{1} << 48)) {
      throw std::runtime_error(tl.path_ + ": record " + std::to_string(records_before + 1) +
                               ": its time stamp is more than 78 hours after the first; the viewer shows shorter logs");
    }
    if (t > last_t && t >= next_checkpoint) {
      // Every earlier record is earlier in time: the wire playback may start here for any t after.
      tl.checkpoints_.push_back(Checkpoint{t, offset, records_before});
      next_checkpoint = t + tl.options_.checkpoint_every_ns;
    }
    last_t = t;
    switch (r.type) {
      case 4:
        Vision(r.payload, t);
        break;
      case 3:
        Referee(r.payload, t);
        break;
      case 5:
        ++tl.counts_.tracked_frames;
        break;
      default:
        ++tl.counts_.legacy_frames;
        break;
    }
  }

  void Vision(const std::string& payload, std::int64_t t) {
    if (!wrapper.ParseFromString(payload)) {
      ++tl.counts_.undecodable;
      return;
    }
    if (wrapper.has_geometry()) {
      ++tl.counts_.geometries;
      std::string bytes;
      wrapper.geometry().SerializeToString(&bytes);
      if (bytes != last_geometry) {
        last_geometry = std::move(bytes);
        tl.geometries_.push_back(FromPacket(wrapper.geometry(), t));
      }
    }
    if (!wrapper.has_detection()) return;
    const SSL_DetectionFrame& d = wrapper.detection();
    const auto camera = static_cast<std::uint64_t>(std::min<std::uint32_t>(d.camera_id(), 0xFFFF));
    tl.frames_.push_back(Frame{static_cast<std::uint64_t>(t) << 16 | camera,
                               static_cast<std::uint32_t>(tl.detections_.size()), d.frame_number()});
    const std::size_t before = tl.detections_.size();
    for (const SSL_DetectionBall& b : d.balls()) {
      tl.detections_.push_back(Detection{Mm(b.x()), Mm(b.y()), b.has_z() ? Mm(b.z()) : std::int16_t{0}, kBall,
                                         Confidence(b.confidence())});
    }
    for (const auto* robots : {&d.robots_blue(), &d.robots_yellow()}) {
      const std::uint8_t team = robots == &d.robots_blue() ? kBlue : kYellow;
      for (const SSL_DetectionRobot& rb : *robots) {
        if (!rb.has_robot_id() || rb.robot_id() > kMaxId) continue;
        std::int16_t heading = kNoHeading;
        if (rb.has_orientation() && std::isfinite(rb.orientation())) {
          const double yaw = std::remainder(static_cast<double>(rb.orientation()), 2 * M_PI);  // [-pi, pi]
          heading = static_cast<std::int16_t>(std::lround(yaw / kHeadingUnit));
        }
        tl.detections_.push_back(Detection{Mm(rb.x()), Mm(rb.y()), heading,
                                           static_cast<std::uint8_t>(team + rb.robot_id()),
                                           Confidence(rb.confidence())});
      }
    }
    ++tl.counts_.vision_frames;
    tl.counts_.detections += static_cast<std::int64_t>(tl.detections_.size() - before);
  }

  void Referee(const std::string& payload, std::int64_t t) {
    // Only complete messages, as the live viewer takes them.
    if (!referee.ParseFromString(payload)) {
      ++tl.counts_.undecodable;
      return;
    }
    ++tl.counts_.referee_messages;
    if (span && t - span->end_ns <= kRefereeSilence) {
      span->end_ns = t;
    } else {
      if (span) tl.referee_spans_.push_back(*span);
      span = RefereeSpan{t, t};
    }
    // One held back went out when its interval was over, before this one came.
    if (held && t >= next_keep) Keep(std::move(*held), next_keep);
    held.reset();
    if (referee.game_events_size() > 0) {
      earlier_event = std::make_shared<const std::string>(
          referee.game_events(referee.game_events_size() - 1).SerializeAsString());
    }
    RefereeState state{t, payload, earlier_event};
    if (t >= next_keep) {
      Keep(std::move(state), t);
    } else {
      held = std::move(state);
    }
  }

  void Keep(RefereeState state, std::int64_t t) {
    state.t_ns = t;
    tl.referee_.push_back(std::move(state));
    next_keep = t + kRefereeIntervalNs;
  }

  void Finish() {
    if (held) Keep(std::move(*held), std::max(next_keep, held->t_ns));
    if (span) tl.referee_spans_.push_back(*span);
    tl.first_unix_ns_ = first_ns.value_or(0);
    tl.duration_ns_ = std::max<std::int64_t>(0, last_t);
    tl.counts_.referee_states = static_cast<std::int64_t>(tl.referee_.size());
    tl.frames_.push_back(Frame{static_cast<std::uint64_t>(tl.duration_ns_) << 16,
                               static_cast<std::uint32_t>(tl.detections_.size()), 0});  // the end of the last
    tl.frames_.shrink_to_fit();
    tl.detections_.shrink_to_fit();
    tl.geometries_.shrink_to_fit();
    tl.referee_.shrink_to_fit();
    tl.referee_spans_.shrink_to_fit();
    tl.checkpoints_.shrink_to_fit();
  }
};

std::unique_ptr<LogTimeline> LogTimeline::Load(const std::string& file, const Options& options) {
  std::unique_ptr<LogTimeline> tl(new LogTimeline());
  tl->options_ = options;
  tl->path_ = file;
  tl->default_geometry_.field = DivisionBField();
  sslog::LogReader reader(file);
  Loader loader(*tl);
  try {
    while (const auto record = reader.Next()) loader.Add(*record, reader.RecordOffset(), reader.Records() - 1);
  } catch (const sslog::LogFormatError& e) {
    tl->damage_ = e;
  }
  loader.Finish();
  return tl;
}

LogTimeline::~LogTimeline() = default;

std::size_t LogTimeline::MemoryBytes() const {
  std::size_t bytes = sizeof(*this) + frames_.capacity() * sizeof(Frame) + detections_.capacity() * sizeof(Detection) +
                      referee_.capacity() * sizeof(RefereeState) + referee_spans_.capacity() * sizeof(RefereeSpan) +
                      checkpoints_.capacity() * sizeof(Checkpoint) + geometries_.capacity() * sizeof(Geometry);
  const std::string* last_event = nullptr;
  for (const RefereeState& r : referee_) {
    if (r.payload.capacity() > 15) bytes += r.payload.capacity() + 1;  // beyond the short-string buffer
    if (r.earlier_event && r.earlier_event.get() != last_event) bytes += r.earlier_event->capacity() + 48;
    last_event = r.earlier_event.get();
  }
  for (const Geometry& g : geometries_) {
    bytes += g.field.lines.capacity() * (sizeof(FieldLine) + 16) + g.field.arcs.capacity() * (sizeof(FieldArc) + 16) +
             g.cameras.capacity() * sizeof(CameraInfo);
  }
  return bytes;
}

// ---------------------------------------------------------------------------------------------
// Queries

const LogTimeline::Geometry& LogTimeline::GeometryAt(std::int64_t t_ns, std::size_t* index) const {
  if (geometries_.empty()) {
    if (index) *index = 0;
    return default_geometry_;
  }
  auto it = std::upper_bound(geometries_.begin(), geometries_.end(), t_ns,
                             [](std::int64_t t, const Geometry& g) { return t < g.t_ns; });
  const std::size_t i = it == geometries_.begin() ? 0 : static_cast<std::size_t>(it - geometries_.begin()) - 1;
  if (index) *index = i;
  return geometries_[i];
}

void LogTimeline::SampleAt(std::int64_t t_ns, viewer::WorldSample& sample, std::vector<VisionFrame>& frames) const {
  const Geometry& geometry = GeometryAt(t_ns);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  sample.step = 0;
  sample.sim_time_ns = t_ns;
  sample.ball_position = Vec3(nan, nan, nan);
  sample.ball_velocity = Vec3(nan, nan, nan);
  sample.ball_radius = geometry.ball_radius;
  sample.robots.clear();
  frames.clear();
  if (frames_.size() < 2) return;

  // Each camera's latest frame in the window (the frames' index, newest first).
  std::vector<std::size_t> used;
  const auto end = frames_.end() - 1;  // the last is where the detections end, not a frame
  auto it = std::upper_bound(frames_.begin(), end, t_ns, [](std::int64_t t, const Frame& f) { return t < f.T(); });
  while (it != frames_.begin()) {
    --it;
    if (t_ns - it->T() > options_.merge_window_ns) break;
    const bool seen =
        std::any_of(used.begin(), used.end(), [&](std::size_t i) { return frames_[i].Camera() == it->Camera(); });
    if (!seen) used.push_back(static_cast<std::size_t>(it - frames_.begin()));
  }
  std::sort(used.begin(), used.end(),
            [&](std::size_t a, std::size_t b) { return frames_[a].Camera() < frames_[b].Camera(); });

  struct Sum {
    double w = 0, x = 0, y = 0, c = 0, s = 0, wyaw = 0;
  };
  std::map<std::uint8_t, Sum> robots;  // by `who`: blue before yellow, each by id
  struct Ball {
    double x, y, z, w;
    int camera;
  };
  std::vector<Ball> balls;
  // A zero confidence still counts a little.
  const auto weight = [](const Detection& d) { return std::max(1.0, static_cast<double>(d.confidence)); };
  for (const std::size_t i : used) {
    const Frame& f = frames_[i];
    VisionFrame out;
    out.camera_id = f.Camera();
    out.frame_number = f.frame_number;
    out.t_capture_ns = f.T();
    out.t_sent_ns = f.T();
    // This camera's most confident detection of each robot.
    std::map<std::uint8_t, const Detection*> best;
    for (std::uint32_t k = f.first; k < frames_[i + 1].first; ++k) {
      const Detection& d = detections_[k];
      const double x = d.x * kMm, y = d.y * kMm;
      if (d.who == kBall) {
        const double z = std::max(0, static_cast<int>(d.a)) * kMm;
        out.balls.push_back(DetectedBall{x, y, z, d.confidence / 255.0});
        balls.push_back(Ball{x, y, z, weight(d), f.Camera()});
        continue;
      }
      const bool blue = d.who < kYellow;
      const double yaw = d.a == kNoHeading ? nan : d.a * kHeadingUnit;
      out.robots.push_back(DetectedRobot{RobotId{blue ? Team::kBlue : Team::kYellow, d.who - (blue ? kBlue : kYellow)},
                                         x, y, yaw, d.confidence / 255.0});
      const Detection*& b = best[d.who];
      if (!b || d.confidence > b->confidence) b = &d;
    }
    for (const auto& [who, d] : best) {
      Sum& s = robots[who];
      const double w = weight(*d);
      s.w += w;
      s.x += w * d->x * kMm;
      s.y += w * d->y * kMm;
      if (d->a != kNoHeading) {
        s.c += w * std::cos(d->a * kHeadingUnit);
        s.s += w * std::sin(d->a * kHeadingUnit);
        s.wyaw += w;
      }
    }
    frames.push_back(std::move(out));
  }
  for (const auto& [who, s] : robots) {
    viewer::RobotSample r;
    const bool blue = who < kYellow;
    r.id = RobotId{blue ? Team::kBlue : Team::kYellow, who - (blue ? kBlue : kYellow)};
    r.x = s.x / s.w;
    r.y = s.y / s.w;
    r.yaw = s.wyaw > 0 ? std::atan2(s.s, s.c) : nan;
    r.vx = r.vy = r.w = nan;
    r.radius = geometry.robot_radius;
    sample.robots.push_back(r);
  }
  if (!balls.empty()) {
    const Ball* best = &balls.front();
    for (const Ball& b : balls) {
      if (b.w > best->w) best = &b;
    }
    // The same ball in the other cameras: each one's nearest to the best, if close.
    std::map<int, const Ball*> nearest;
    for (const Ball& b : balls) {
      if (b.camera == best->camera) continue;
      const double dist = std::hypot(b.x - best->x, b.y - best->y);
      if (dist > kBallMergeRadius) continue;
      const Ball*& n = nearest[b.camera];
      if (!n || dist < std::hypot(n->x - best->x, n->y - best->y)) n = &b;
    }
    double x = best->w * best->x, y = best->w * best->y, z = best->w * best->z, sum = best->w;
    for (const auto& [camera, b] : nearest) {
      x += b->w * b->x;
      y += b->w * b->y;
      z += b->w * b->z;
      sum += b->w;
    }
    // A detection's height is 0 on the carpet (ssl-vision does not measure it): the centre is a radius up.
    sample.ball_position = Vec3(x / sum, y / sum, std::max(z / sum, geometry.ball_radius));
  }
}

std::int64_t LogTimeline::FramesBetween(std::int64_t from_ns, std::int64_t to_ns) const {
  if (frames_.size() < 2) return 0;
  const auto after = [](std::int64_t t, const Frame& f) { return t < f.T(); };
  const auto a = std::upper_bound(frames_.begin(), frames_.end() - 1, from_ns, after);
  const auto b = std::upper_bound(frames_.begin(), frames_.end() - 1, to_ns, after);
  return b > a ? b - a : 0;
}

std::size_t LogTimeline::RefereeIndexAt(std::int64_t t_ns) const {
  const auto it = std::upper_bound(referee_.begin(), referee_.end(), t_ns,
                                   [](std::int64_t t, const RefereeState& r) { return t < r.t_ns; });
  return static_cast<std::size_t>(it - referee_.begin());
}

std::string LogTimeline::RefereeAt(std::int64_t t_ns, std::size_t* index) const {
  const std::size_t i = RefereeIndexAt(t_ns);
  if (index) *index = i;
  if (i == 0) return {};
  const auto it = referee_.begin() + static_cast<std::ptrdiff_t>(i - 1);
  ::Referee message;
  GameEvent earlier;
  message.ParseFromString(it->payload);  // parsed once already, when the log was loaded
  const bool has_earlier = it->earlier_event && earlier.ParseFromString(*it->earlier_event);
  return viewer::EncodeReferee(message, has_earlier ? &earlier : nullptr);
}

std::optional<std::int64_t> LogTimeline::RefereeAgeAt(std::int64_t t_ns) const {
  auto it = std::upper_bound(referee_spans_.begin(), referee_spans_.end(), t_ns,
                             [](std::int64_t t, const RefereeSpan& s) { return t < s.start_ns; });
  if (it == referee_spans_.begin()) return std::nullopt;
  --it;
  // Inside a span messages came at least every 0.5 s: none has been missed yet.
  return t_ns <= it->end_ns ? 0 : t_ns - it->end_ns;
}

const LogTimeline::Checkpoint& LogTimeline::CheckpointAt(std::int64_t t_ns) const {
  auto it = std::upper_bound(checkpoints_.begin(), checkpoints_.end(), t_ns,
                             [](std::int64_t t, const Checkpoint& c) { return t < c.t_ns; });
  return it == checkpoints_.begin() ? checkpoints_.front() : *(it - 1);
}

}  // namespace ubersim::cli
