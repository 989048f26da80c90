// SPDX-License-Identifier: Apache-2.0
// A log for the browser viewer (`ubersim replay FILE --viewer`, docs/log-files.md): read once,
// kept as what the page draws — each camera frame's detections to the millimetre, the distinct
// field geometries, the Referee messages at most ten a second — not as the vision payloads; and,
// for the wire playback, where in the file each second of it begins.
// Answers "what was there at log time t" by merging the cameras' latest frames. No sockets here.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <ubersim/world_state.hpp>

#include "ssl_log.hpp"
#include "viewer_protocol.hpp"

namespace ubersim::cli {

/// The log's contents on a time line: t is ns since the first shown or sent record (types 2 to 5),
/// from the records' receive times, never going back (a time stamp below an earlier one counts as
/// that one, as LogWriter writes it).
class LogTimeline {
 public:
  /// How the cameras are merged, and how often the file is indexed.
  struct Options {
    std::int64_t merge_window_ns = 50'000'000;        ///< a camera's frame shows this long after it arrived
    std::int64_t checkpoint_every_ns = 1'000'000'000;  ///< file offsets kept for the wire playback's seeks
  };

  /// One field geometry of the log (a vision packet's geometry), in m.
  struct Geometry {
    std::int64_t t_ns = 0;            ///< the first record that carried it
    FieldGeometry field;              ///< field size and markings
    std::vector<CameraInfo> cameras;  ///< cameras with a known position (derived_camera_world_*)
    double ball_radius = 0.0215;      ///< m
    double robot_radius = 0.09;       ///< m (max_robot_radius)
  };

  /// Where the wire playback picks the file up: a record all earlier records precede in time.
  struct Checkpoint {
    std::int64_t t_ns = 0;            ///< its time (every record before it is earlier)
    std::int64_t offset = 0;          ///< its byte offset in the uncompressed stream
    std::int64_t records_before = 0;  ///< records before it in the file
  };

  /// What was read.
  struct Counts {
    std::int64_t records = 0;           ///< records in the file (up to the damage)
    std::int64_t vision_frames = 0;     ///< camera frames (type 4 detections)
    std::int64_t detections = 0;        ///< robots and balls in them
    std::int64_t geometries = 0;        ///< geometry packets (distinct ones kept)
    std::int64_t referee_messages = 0;  ///< Referee messages (type 3)
    std::int64_t referee_states = 0;    ///< Referee messages kept (at most 10 a second)
    std::int64_t tracked_frames = 0;    ///< type 5, not shown (sent with the rest)
    std::int64_t legacy_frames = 0;     ///< type 2, not shown (sent with the rest)
    std::int64_t undecodable = 0;       ///< payloads of types 3 and 4 that did not parse
  };

  /// Reads `file` to its end. Throws what LogReader's constructor throws (a missing or foreign
  /// file). A file damaged further on keeps what came before the damage; Damage() says where.
  static std::unique_ptr<LogTimeline> Load(const std::string& file, const Options& options);
  static std::unique_ptr<LogTimeline> Load(const std::string& file) { return Load(file, Options{}); }
  ~LogTimeline();
  LogTimeline(const LogTimeline&) = delete;
  LogTimeline& operator=(const LogTimeline&) = delete;

  std::int64_t DurationNs() const { return duration_ns_; }      ///< t of the last shown or sent record
  std::int64_t FirstUnixNs() const { return first_unix_ns_; }   ///< the time stamp of t = 0
  bool Empty() const { return checkpoints_.empty(); }            ///< no record of types 2 to 5
  const Counts& Count() const { return counts_; }
  /// The error that ended the reading, if the file is damaged.
  const std::optional<sslog::LogFormatError>& Damage() const { return damage_; }
  /// Bytes held (the vectors' capacity and the referee texts), to tell the user.
  std::size_t MemoryBytes() const;

  /// The geometry in force at t: the last one that arrived at or before t (the first one before
  /// it arrived); its index, for noticing a change. Without any, a Division B field.
  const Geometry& GeometryAt(std::int64_t t_ns, std::size_t* index = nullptr) const;
  /// The world at t: each camera's latest frame that arrived at or before t and at most the merge
  /// window before it, merged (below), into `sample` (at t; robots blue first, then by id) and
  /// `frames` (those frames, their times on the time line). Velocities are unknown (NaN); a ball
  /// nobody sees is at NaN.
  ///
  /// Merging: a robot seen by several cameras (where their images overlap) is at the
  /// confidence-weighted mean of its detections, its heading the weighted circular mean; within
  /// one camera the most confident detection of an id counts. The ball is the most confident
  /// detection, averaged with the nearest one (within 0.2 m) of each other camera.
  void SampleAt(std::int64_t t_ns, viewer::WorldSample& sample, std::vector<VisionFrame>& frames) const;
  /// Camera frames that arrived in (from, to].
  std::int64_t FramesBetween(std::int64_t from_ns, std::int64_t to_ns) const;
  /// The referee message shown at t, as the viewer's JSON (viewer_referee.hpp); "" before the
  /// first. `index` (0 before the first, then 1, 2, …) tells whether it changed since an earlier call.
  std::string RefereeAt(std::int64_t t_ns, std::size_t* index = nullptr) const;
  /// RefereeAt's index alone (cheap: no JSON).
  std::size_t RefereeIndexAt(std::int64_t t_ns) const;
  /// ns since the last Referee message at or before t; nullopt before the first.
  std::optional<std::int64_t> RefereeAgeAt(std::int64_t t_ns) const;
  /// The last checkpoint at or before t (the first for t before it). Only when !Empty().
  const Checkpoint& CheckpointAt(std::int64_t t_ns) const;

 private:
  LogTimeline() = default;

  // One camera frame, 16 bytes: its detections are detections_[first, the next frame's first).
  struct Frame {
    std::uint64_t t_camera;  // t_ns << 16 | camera: log time up to 2^48 ns (78 hours), camera ids to 65535
    std::uint32_t first;
    std::uint32_t frame_number;
    std::int64_t T() const { return static_cast<std::int64_t>(t_camera >> 16); }
    int Camera() const { return static_cast<int>(t_camera & 0xFFFF); }
  };
  // A robot or ball in a frame, 8 bytes: mm and 0.1 mrad, to the page's precision and better than
  // a camera's.
  struct Detection {
    std::int16_t x, y;        // mm
    std::int16_t a;           // a robot's heading, 1e-4 rad (kNoHeading: none); a ball's height, mm
    std::uint8_t who;         // kBall, or a robot: kBlue + id, kYellow + id (ids 0 to 126)
    std::uint8_t confidence;  // 0..255
  };
  static constexpr std::uint8_t kBall = 0, kBlue = 1, kYellow = 128, kMaxId = 126;
  static constexpr std::int16_t kNoHeading = -32768;
  // A Referee message kept (at most 10 a second): its payload, and the last game event of the
  // last message that carried any (shared by the states after it), as the live viewer shows it.
  struct RefereeState {
    std::int64_t t_ns;
    std::string payload;
    std::shared_ptr<const std::string> earlier_event;
  };
  // Referee messages came every <= 0.5 s from start to end.
  struct RefereeSpan {
    std::int64_t start_ns, end_ns;
  };
  struct Loader;

  Options options_;
  std::string path_;
  std::int64_t first_unix_ns_ = 0;
  std::int64_t duration_ns_ = 0;
  Counts counts_;
  std::optional<sslog::LogFormatError> damage_;
  std::vector<Frame> frames_;  // in time order, and one more at the end: where the last one's detections end
  std::vector<Detection> detections_;
  std::vector<Geometry> geometries_;
  std::vector<RefereeState> referee_;
  std::vector<RefereeSpan> referee_spans_;
  std::vector<Checkpoint> checkpoints_;
  Geometry default_geometry_;
};

/// Division B's field (the rules' numbers), for a log without geometry.
FieldGeometry DivisionBField();

}  // namespace ubersim::cli
