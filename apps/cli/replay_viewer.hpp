// SPDX-License-Identifier: Apache-2.0
// `ubersim replay FILE --viewer` (docs/log-files.md): the browser viewer's page, served by the
// viewer's own server (plugins/transports/viewer), showing a log loaded into a LogTimeline, with a
// time slider. One clock — position, playing, speed — drives both the page and, with --send, the
// wire playback, so the datagrams on the network follow the slider: a seek jumps in the file
// too, a pause stops sending, the speed paces both.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>

#include <ubersim/log.hpp>

#include "replay_timeline.hpp"
#include "ssl_log.hpp"

namespace ubersim::cli {

/// Where a replay stands: log time that runs with the wall clock times the speed while playing.
/// Thread-safe; the viewer's server thread and the wire playback read it, the page's commands
/// change it.
class PlayClock {
 public:
  using Clock = std::chrono::steady_clock;

  /// What At() says.
  struct Position {
    std::int64_t t_ns = 0;         ///< log time
    bool playing = false;          ///< time runs
    double speed = 1;              ///< log s per wall s
    std::uint64_t jumps = 0;       ///< seeks and loop restarts so far (the wire playback follows them)
    std::uint64_t changes = 0;     ///< any change so far (seek, play, pause, speed)
  };

  /// Starts at 0, playing at `speed`; `loop`: start again at the end instead of stopping there.
  PlayClock(std::int64_t duration_ns, double speed, bool loop, Clock::time_point now);

  /// The position at `now` (at the end without loop: stopped there; with loop: from 0 again).
  Position At(Clock::time_point now);
  /// Jumps to t (clamped to the log).
  void Seek(std::int64_t t_ns, Clock::time_point now);
  /// Plays (from the start when stopped at the end) or pauses.
  void SetPlaying(bool playing, Clock::time_point now);
  /// Times the recorded rate, from now on.
  void SetSpeed(double speed, Clock::time_point now);
  /// Waits until `until`, or until something changed since `changes` was read.
  void WaitUntil(Clock::time_point until, std::uint64_t changes);
  /// Wakes every WaitUntil.
  void Wake();

 private:
  Position AtLocked(Clock::time_point now);
  void Changed();

  std::int64_t duration_ns_;
  bool loop_;
  std::mutex mutex_;
  std::condition_variable changed_;
  // Position at anchor_wall_ is anchor_t_; while playing it runs on at speed_.
  std::int64_t anchor_t_ = 0;
  Clock::time_point anchor_wall_;
  bool playing_ = true;
  double speed_ = 1;
  std::uint64_t jumps_ = 0, changes_ = 0;
};

/// How the page is served.
struct ReplayViewerOptions {
  std::string file;                   ///< shown on the page
  std::string address = "127.0.0.1";  ///< numeric address the server listens on
  std::uint16_t port = 8080;          ///< 0: the system picks one
  double rate = 60;                   ///< state messages a second
  double speed = 1;                   ///< times the recorded rate at start
  bool loop = false;                  ///< start again at the end
};

/// Sends one record onto the network (the wire playback); types 2 to 5 only reach it.
using SendRecord = std::function<void(const sslog::LogRecord&)>;

/// Serves the page and plays `timeline` until `stop` says so (polled at least every 50 ms).
/// With `send`, re-reads the file in step with the clock and hands it each record as the
/// position passes it. `on_listening` gets the page's address once the server listens. Throws
/// std::runtime_error when the port cannot be had.
void RunReplayViewer(const LogTimeline& timeline, const ReplayViewerOptions& options, const SendRecord& send,
                     const std::function<bool()>& stop, const std::function<void(const std::string& url)>& on_listening,
                     Log& log);

}  // namespace ubersim::cli
