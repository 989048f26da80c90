// SPDX-License-Identifier: Apache-2.0
// A field's recording as `ubersim calibrate` fits it: every camera frame of an SSL log (all
// cameras, ordered by capture time, SI units), the cameras' positions from the geometry, and the
// robot commands a team's software recorded beside it (docs/calibrate.md, "Commands").
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "samples.hpp"

namespace ubersim::calibrate {

/// ÜberSim's record types for commands (the league leaves ids past 6 free; TIGERs use 1002/1003):
/// the payload is the league's simulation `RobotControl` a team's software sent to that team's robots.
inline constexpr std::int32_t kRobotControlBlueRecord = 1201;    ///< RobotControl for blue
inline constexpr std::int32_t kRobotControlYellowRecord = 1202;  ///< RobotControl for yellow

/// What a log held, record by record, for the report.
struct LogCounts {
  std::int64_t records = 0;             ///< every record read
  std::int64_t detection_frames = 0;    ///< vision detection frames kept
  std::int64_t duplicate_frames = 0;    ///< the same camera frame recorded twice (two interfaces)
  std::int64_t geometry_packets = 0;    ///< vision geometry packets
  std::int64_t command_records = 0;     ///< RobotControl records (types 1201, 1202)
  std::int64_t other_records = 0;       ///< referee, tracker, index and unknown types: not used
  std::int64_t undecodable = 0;         ///< vision or command payloads that did not parse
  std::string first_undecodable;        ///< where the first one was ("log.gz: record 12 at byte 4096")
};

/// The field's size as the geometry announced it, m.
struct FieldSize {
  double length = 0;  ///< between the goal lines
  double width = 0;   ///< between the touch lines
};

/// One recording (one or more log files of the same session), on one clock.
struct LogSession {
  std::vector<std::string> paths;                       ///< the files read
  std::int64_t t0_ns = 0;                               ///< Unix ns of the session clock's zero (first capture)
  std::vector<CameraFrame> frames;                      ///< every camera frame, ordered by t_capture
  std::map<int, Eigen::Vector3d> cameras;               ///< camera positions from the geometry, m
  std::optional<FieldSize> field;                       ///< from the geometry
  /// Commands per robot, time-ordered; global-velocity commands are stored with `global` set and
  /// turned into the robot's frame once its track is known (SessionTracks).
  std::map<RobotKey, std::vector<CommandSample>> commands;
  std::map<RobotKey, std::vector<bool>> command_is_global;  ///< per command: (x, y) were field-frame
  LogCounts counts;                                     ///< what was read
  double duration() const;                              ///< first to last capture, s
};

/// Reads SSL log files (.log or .log.gz) into one session. Vision detection frames (type 4) give
/// the frames, geometry packets the cameras and field, records 1201/1202 the commands; other types
/// are counted and skipped. Throws sslog::LogFormatError (file, record, byte offset) for a damaged
/// or truncated file, std::runtime_error when a file cannot be opened or holds no camera frame, or
/// when more than a tenth of its vision records do not parse (with the first one's place).
LogSession ReadLogSession(const std::vector<std::string>& paths);

}  // namespace ubersim::calibrate
