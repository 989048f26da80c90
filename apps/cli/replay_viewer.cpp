// SPDX-License-Identifier: Apache-2.0
#include "replay_viewer.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include "viewer_protocol.hpp"
#include "viewer_server.hpp"

namespace ubersim::cli {
namespace {

using SteadyClock = PlayClock::Clock;

constexpr auto kStopPoll = std::chrono::milliseconds(50);  // longest wait between two looks at `stop`
constexpr std::int64_t kRateWindowNs = 1'000'000'000;      // the vision rate: frames in the last log second
constexpr int kSkipCheck = 1024;                            // records skipped between two looks at the clock
// What the page is told when it seeks back before the first Referee message: show no match.
constexpr const char* kNoReferee = R"({"type":"referee","cleared":true})";

std::int64_t Ns(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e9)); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// PlayClock

PlayClock::PlayClock(std::int64_t duration_ns, double speed, bool loop, Clock::time_point now)
    : duration_ns_(std::max<std::int64_t>(0, duration_ns)), loop_(loop), anchor_wall_(now), speed_(speed) {}

PlayClock::Position PlayClock::AtLocked(Clock::time_point now) {
  std::int64_t t = anchor_t_;
  if (playing_) {
    t += static_cast<std::int64_t>(std::chrono::duration<double, std::nano>(now - anchor_wall_).count() * speed_);
  }
  if (t >= duration_ns_ && playing_) {
    if (loop_ && duration_ns_ > 0) {
      t %= duration_ns_;
      anchor_t_ = t;
      anchor_wall_ = now;
      ++jumps_;
      Changed();
    } else {
      t = duration_ns_;
      anchor_t_ = t;
      anchor_wall_ = now;
      playing_ = false;  // stopped at the end
      Changed();
    }
  }
  return Position{std::clamp<std::int64_t>(t, 0, duration_ns_), playing_, speed_, jumps_, changes_};
}

PlayClock::Position PlayClock::At(Clock::time_point now) {
  std::lock_guard lock(mutex_);
  return AtLocked(now);
}

void PlayClock::Seek(std::int64_t t_ns, Clock::time_point now) {
  std::lock_guard lock(mutex_);
  anchor_t_ = std::clamp<std::int64_t>(t_ns, 0, duration_ns_);
  anchor_wall_ = now;
  ++jumps_;
  Changed();
}

void PlayClock::SetPlaying(bool playing, Clock::time_point now) {
  std::lock_guard lock(mutex_);
  const Position p = AtLocked(now);
  anchor_t_ = p.t_ns;
  anchor_wall_ = now;
  if (playing && !playing_ && p.t_ns >= duration_ns_) {  // play at the end: from the start
    anchor_t_ = 0;
    ++jumps_;
  }
  playing_ = playing;
  Changed();
}

void PlayClock::SetSpeed(double speed, Clock::time_point now) {
  std::lock_guard lock(mutex_);
  anchor_t_ = AtLocked(now).t_ns;
  anchor_wall_ = now;
  speed_ = speed;
  Changed();
}

void PlayClock::WaitUntil(Clock::time_point until, std::uint64_t changes) {
  std::unique_lock lock(mutex_);
  changed_.wait_until(lock, until, [&] { return changes_ != changes; });
}

void PlayClock::Wake() { changed_.notify_all(); }

void PlayClock::Changed() {
  ++changes_;
  changed_.notify_all();
}

// ---------------------------------------------------------------------------------------------
// The wire playback: the file read again, record by record, as the clock passes them.

namespace {

class WireFollower {
 public:
  WireFollower(const LogTimeline& timeline, const std::string& file, const SendRecord& send)
      : timeline_(timeline), reader_(file), send_(send) {}

  // Sends what the clock has passed, or waits until the next record is due (or the clock changes).
  void Step(PlayClock& clock, const std::function<bool()>& stop) {
    const auto now = SteadyClock::now();
    const PlayClock::Position p = clock.At(now);
    if (p.jumps != jumps_ || !started_) {
      started_ = true;
      jumps_ = p.jumps;
      Reposition(p.t_ns, clock, stop);
      return;
    }
    if (next_ && p.playing && next_t_ <= p.t_ns) {
      send_(*next_);
      ReadNext();
      return;
    }
    auto until = now + kStopPoll;
    if (next_ && p.playing) {
      const auto due = now + std::chrono::duration_cast<SteadyClock::duration>(
                                 std::chrono::duration<double, std::nano>((next_t_ - p.t_ns) / p.speed));
      until = std::min(until, due);
    }
    clock.WaitUntil(until, p.changes);
  }

 private:
  // The first record at or after t: from the checkpoint before t, or on from here when t is ahead.
  void Reposition(std::int64_t t, PlayClock& clock, const std::function<bool()>& stop) {
    const LogTimeline::Checkpoint& cp = timeline_.CheckpointAt(t);
    if (!(next_ && cp.t_ns <= next_t_ && next_t_ <= t)) {
      try {
        reader_.Seek(cp.offset, cp.records_before);
      } catch (const sslog::LogFormatError&) {
        next_.reset();  // the damage, reported when the log was loaded
        return;
      }
      last_t_ = cp.t_ns;
      ReadNext();
    }
    for (int n = 0; next_ && next_t_ < t; ++n) {
      // A later seek (a slider being dragged) or Ctrl-C makes this one moot.
      if (n % kSkipCheck == kSkipCheck - 1 && (clock.At(SteadyClock::now()).jumps != jumps_ || stop())) return;
      ReadNext();
    }
  }

  // The next record of types 2 to 5, with its time on the time line; none at the end (or damage).
  void ReadNext() {
    next_.reset();
    try {
      while (auto r = reader_.Next()) {
        if (r->type < 2 || r->type > 5) continue;
        last_t_ = std::max(last_t_, r->timestamp_ns - timeline_.FirstUnixNs());
        next_t_ = last_t_;
        next_ = std::move(r);
        return;
      }
    } catch (const sslog::LogFormatError&) {
      // The damage, reported when the log was loaded: the time line ends before it too.
    }
  }

  const LogTimeline& timeline_;
  sslog::LogReader reader_;
  const SendRecord& send_;
  bool started_ = false;
  std::uint64_t jumps_ = 0;
  std::optional<sslog::LogRecord> next_;
  std::int64_t next_t_ = 0;
  std::int64_t last_t_ = 0;
};

// The page's side: the server's callbacks, all on its thread.
class ReplayPage {
 public:
  ReplayPage(const LogTimeline& timeline, const ReplayViewerOptions& options, bool sending, PlayClock& clock)
      : timeline_(timeline), options_(options), clock_(clock) {
    info_.file = std::filesystem::path(options.file).filename().string();
    info_.duration = static_cast<double>(timeline.DurationNs()) * 1e-9;
    info_.start_unix = static_cast<double>(timeline.FirstUnixNs()) * 1e-9;
    info_.sending = sending;
    hello_ = EncodeHello(timeline.GeometryAt(0, &geometry_));
  }

  viewer::ViewerServer::Callbacks Callbacks() {
    viewer::ViewerServer::Callbacks cb;
    cb.hello = [this] { return hello_; };
    cb.catch_up = [this] {
      std::vector<std::string> out;
      if (!referee_.empty()) out.push_back(referee_);
      return out;
    };
    cb.on_message = [this](std::string_view text) { return OnMessage(text); };
    cb.latest_state = [this] { return state_; };
    cb.tick = [this] { Tick(); };
    return cb;
  }

  void SetServer(viewer::ViewerServer* server) { server_ = server; }

 private:
  std::string EncodeHello(const LogTimeline::Geometry& g) const {
    // The page shows a match only when the hello names where it comes from.
    const std::string referee = timeline_.Count().referee_messages > 0 ? "the log" : "";
    return viewer::EncodeHello(info_.file, options_.rate, g.field, g.cameras, referee, &info_);
  }

  std::string OnMessage(std::string_view text) {
    const viewer::ReplayCommand c = viewer::DecodeReplayCommand(text, info_);
    if (!c.error.empty()) return viewer::EncodeReply(c.cmd, c.id, c.error);
    const auto now = SteadyClock::now();
    if (c.seek) clock_.Seek(Ns(*c.seek), now);
    if (c.playing) clock_.SetPlaying(*c.playing, now);
    if (c.speed) clock_.SetSpeed(*c.speed, now);
    Tick();  // the page sees where it went at once
    return viewer::EncodeReply(c.cmd, c.id);
  }

  void Tick() {
    const PlayClock::Position p = clock_.At(SteadyClock::now());
    std::size_t geometry = 0;
    const LogTimeline::Geometry& g = timeline_.GeometryAt(p.t_ns, &geometry);
    if (geometry != geometry_) {  // the log's field changed: pages draw the new one
      geometry_ = geometry;
      hello_ = EncodeHello(g);
      Broadcast(hello_, viewer::ViewerServer::Channel::kHello);
    }
    if (timeline_.RefereeIndexAt(p.t_ns) != referee_index_) {
      referee_ = timeline_.RefereeAt(p.t_ns, &referee_index_);
      Broadcast(referee_.empty() ? std::string(kNoReferee) : referee_, viewer::ViewerServer::Channel::kReferee);
    }
    timeline_.SampleAt(p.t_ns, sample_, frames_);
    viewer::ViewerStatus status;
    status.real_time_factor = p.playing ? p.speed : 0;
    status.cameras = static_cast<int>(frames_.size());
    status.vision_rate = static_cast<double>(timeline_.FramesBetween(p.t_ns - kRateWindowNs, p.t_ns)) /
                         std::max(1, status.cameras) / (static_cast<double>(kRateWindowNs) * 1e-9);
    status.clients = server_ ? server_->Clients() : 0;
    status.paused = !p.playing;
    status.speed_factor = p.speed;
    if (const auto age = timeline_.RefereeAgeAt(p.t_ns)) status.referee_age = static_cast<double>(*age) * 1e-9;
    status.replay = viewer::ReplayStatus{static_cast<double>(p.t_ns) * 1e-9, info_.duration, p.speed, p.playing};
    state_ = viewer::EncodeState(sample_, frames_, status);
    if (status.clients > 0) Broadcast(state_, viewer::ViewerServer::Channel::kState);
  }

  void Broadcast(const std::string& message, viewer::ViewerServer::Channel channel) {
    if (server_) server_->Broadcast(std::make_shared<const std::string>(message), channel);
  }

  const LogTimeline& timeline_;
  const ReplayViewerOptions& options_;
  PlayClock& clock_;
  viewer::ViewerServer* server_ = nullptr;
  viewer::ReplayInfo info_;
  std::string hello_;
  std::size_t geometry_ = 0;
  std::size_t referee_index_ = 0;  // 0: none shown
  std::string referee_;            // its JSON ("": none)
  std::string state_;
  viewer::WorldSample sample_;
  std::vector<VisionFrame> frames_;
};

}  // namespace

void RunReplayViewer(const LogTimeline& timeline, const ReplayViewerOptions& options, const SendRecord& send,
                     const std::function<bool()>& stop, const std::function<void(const std::string& url)>& on_listening,
                     Log& log) {
  PlayClock clock(timeline.DurationNs(), options.speed, options.loop, SteadyClock::now());
  ReplayPage page(timeline, options, static_cast<bool>(send), clock);
  viewer::ViewerServer::Options o;
  o.address = options.address;
  o.port = options.port;
  o.busy_hint = "choose another with --viewer-port";
  const auto period =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(1.0 / options.rate));
  viewer::ViewerServer server(o, page.Callbacks(), period, log);
  page.SetServer(&server);
  // The clock starts when the page can be seen.
  clock.Seek(0, SteadyClock::now());
  server.Start();
  if (on_listening) on_listening(server.Url());

  std::optional<WireFollower> wire;
  if (send) wire.emplace(timeline, options.file, send);
  while (!stop()) {
    if (wire) {
      wire->Step(clock, stop);
    } else {
      const PlayClock::Position p = clock.At(SteadyClock::now());
      clock.WaitUntil(SteadyClock::now() + kStopPoll, p.changes);
    }
  }
  server.Stop();
}

}  // namespace ubersim::cli
