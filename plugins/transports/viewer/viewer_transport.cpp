// SPDX-License-Identifier: Apache-2.0
// viewer: the browser viewer (docs/viewer.md). Serves its built-in page over HTTP and streams
// the world to every browser over a WebSocket; the page's controls come back as position and
// clock events, the same path the protocols' teleports and clock commands take.
//
// The simulation thread only copies a compact sample of the world, at most `rate` times per
// wall-clock second, and each camera frame's detections; encoding and sending happen on the
// server's own thread, which also keeps only the newest message for a slow browser. So the
// viewer costs the physics the same whether no browser, a fast one or a stalled one is connected.
//
// The match: like a team's software, the viewer listens for the league's Referee messages (the
// game controller's, or `ubersim run --referee builtin`'s) on their multicast group, and relays
// the match state to the browsers when it changes, at most ten times a second.
#include <atomic>
#include <chrono>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <ubersim/ubersim.hpp>

#include "multicast_receiver.hpp"
#include "transport_common/network.hpp"
#include "transport_common/reject_log.hpp"
#include "ubersim_plugin_schema.hpp"
#include "viewer_protocol.hpp"
#include "viewer_referee.hpp"
#include "viewer_server.hpp"

namespace {

using ubersim::viewer::CommandLimits;
using ubersim::viewer::MulticastReceiver;
using ubersim::viewer::RefereeRelay;
using ubersim::viewer::ViewerServer;
using ubersim::viewer::ViewerStatus;
using ubersim::viewer::WorldSample;
using SteadyClock = std::chrono::steady_clock;

// Sim time standing still this long (wall clock) shows as paused.
constexpr auto kPausedAfter = std::chrono::milliseconds(500);
// While the world stands still, how often the viewer asks for the state (to show edits).
constexpr auto kRefreshWhilePaused = std::chrono::milliseconds(250);
// Window of the real-time factor and the vision rate.
constexpr auto kRateWindow = std::chrono::seconds(1);
// The game controller sends 40 Referee messages a second; a scoreboard reads well at 10.
constexpr auto kRefereeInterval = std::chrono::milliseconds(100);

class ViewerTransport final : public ubersim::Transport {
 public:
  ~ViewerTransport() override { Stop(); }

  void Start(ubersim::TransportContext& ctx) override {
    const ubersim::ParamView& p = ctx.Params();
    ViewerServer::Options o;
    o.address = p.GetString("address", o.address);
    o.port = static_cast<std::uint16_t>(p.GetInt("port", o.port));
    o.max_clients = static_cast<int>(p.GetInt("max_clients", o.max_clients));
    const double rate = p.GetDouble("rate", 60.0);
    period_ = std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(1.0 / rate));
    events_ = &ctx.Events();

    const ubersim::FieldGeometry& field = ctx.Field();
    limits_.half_length = 0.5 * (field.carpet_length > 0 ? field.carpet_length
                                                        : field.field_length + 2 * field.boundary_width);
    limits_.half_width = 0.5 * (field.carpet_width > 0 ? field.carpet_width
                                                      : field.field_width + 2 * field.boundary_width);
    context_ = &ctx;
    rate_ = rate;
    field_name_ = field.name;
    refusals_ = std::make_unique<ubersim::transport::RejectLog>(ctx.Logger(), "viewer command refused");
    if (p.GetBool("show_referee", true)) OpenReferee(ctx);
    hello_ = ubersim::viewer::EncodeHello(ctx.WorldName(), rate, field, ctx.Cameras(), referee_source_);

    ViewerServer::Callbacks callbacks;
    callbacks.hello = [this] {
      std::lock_guard lock(mutex_);
      return hello_;
    };
    callbacks.catch_up = [this] {
      // A page that connects mid-match sees the score at once, not at the next change.
      std::vector<std::string> out;
      if (relay_) {
        if (auto latest = relay_->Latest()) out.push_back(*latest);
      }
      return out;
    };
    callbacks.on_message = [this](std::string_view text) { return OnMessage(text); };
    callbacks.latest_state = [this] { return EncodeLatest(); };
    callbacks.tick = [this] { Tick(); };
    try {
      server_ = std::make_unique<ViewerServer>(o, std::move(callbacks), period_, ctx.Logger());
    } catch (const std::exception& e) {
      throw ubersim::PluginError(e.what());
    }
    server_->Start();
    if (referee_receiver_) referee_receiver_->Start();
  }

  void Publish(const ubersim::WorldSnapshot& snapshot) override {
    // Time going back is a reset: sample it whatever the rate, it may be all there is to see.
    const bool reset = snapshot.sim_time_ns < published_time_ns_.load(std::memory_order_relaxed);
    published_step_ = snapshot.step;
    published_time_ns_.store(snapshot.sim_time_ns, std::memory_order_relaxed);
    if (snapshot.field && snapshot.field->name != field_name_) FieldChanged(*snapshot.field);
    const auto now = SteadyClock::now();
    if (now < next_sample_ && !reset) return;
    next_sample_ = now + period_;
    std::lock_guard lock(mutex_);
    ubersim::viewer::SampleSnapshot(snapshot, sample_);
    have_sample_ = true;
  }

  // A client changed the field (the simulation protocol's geometry): pages draw the new one, and
  // drags are limited to its carpet.
  void FieldChanged(const ubersim::FieldGeometry& field) {
    field_name_ = field.name;
    auto hello = std::make_shared<const std::string>(
        ubersim::viewer::EncodeHello(context_->WorldName(), rate_, field, context_->Cameras(), referee_source_));
    {
      std::lock_guard lock(mutex_);
      hello_ = *hello;
      limits_.half_length = 0.5 * field.carpet_length;
      limits_.half_width = 0.5 * field.carpet_width;
    }
    if (server_) server_->Broadcast(hello, ViewerServer::Channel::kHello);
  }

  void OnVisionFrame(const ubersim::VisionFrame& frame) override {
    std::lock_guard lock(mutex_);
    Camera& c = cameras_[frame.camera_id];
    c.frame = frame;
    c.received = SteadyClock::now();
    ++frames_received_;
  }

  std::string Endpoint() const override {
    return server_ ? server_->Url() + " (open it in a browser)" : std::string();
  }

  void Stop() override {
    if (referee_receiver_) referee_receiver_->Stop();  // first: its datagrams end in Broadcast
    if (server_) server_->Stop();
    if (refusals_) refusals_->Flush();
    if (referee_rejects_) referee_rejects_->Flush();
  }

 private:
  struct Camera {
    ubersim::VisionFrame frame;
    SteadyClock::time_point received;
  };
  struct RateSample {
    SteadyClock::time_point wall;
    std::int64_t sim_time_ns;
    std::uint64_t frames;
  };

  // Opens the referee's group as a team's software does: on loopback, and on the default route's
  // interface unless the world is local-only. A socket that cannot be opened costs the match
  // display, not the viewer (a warning says why); a setting that is wrong stops the start.
  void OpenReferee(ubersim::TransportContext& ctx) {
    const ubersim::ParamView& p = ctx.Params();
    MulticastReceiver::Options o;
    o.group = p.GetString("referee_address", o.group);
    o.port = static_cast<std::uint16_t>(p.GetInt("referee_port", o.port));
    o.name = "viewer referee";
    if (!MulticastReceiver::IsIpv4Group(o.group)) {
      throw p["referee_address"].Error("'" + o.group + "' is not an IPv4 multicast group (the league's: 224.5.23.1)");
    }
    o.interfaces = ubersim::transport::ResolveAddresses({"auto"}, ctx.LocalOnly());
    referee_rejects_ = std::make_unique<ubersim::transport::RejectLog>(ctx.Logger(), "referee datagram ignored");
    relay_ = std::make_unique<RefereeRelay>(kRefereeInterval, [this](std::shared_ptr<const std::string> json) {
      if (server_) server_->Broadcast(std::move(json), ViewerServer::Channel::kReferee);
    });
    try {
      referee_receiver_ = std::make_unique<MulticastReceiver>(
          o,
          [this](std::span<const std::uint8_t> bytes) {
            if (!relay_->OnDatagram(bytes, SteadyClock::now())) {
              referee_rejects_->Reject("not a Referee message (" + std::to_string(bytes.size()) + " bytes)");
            }
          },
          [this](const std::string& reason) { referee_rejects_->Reject(reason); });
    } catch (const std::exception& e) {
      ctx.Logger().Warning(std::string("no match display: ") + e.what());
      relay_.reset();
      return;
    }
    std::string joined;
    for (const std::string& a : referee_receiver_->Joined()) {
      joined += (joined.empty() ? "" : ", ") + ubersim::transport::DescribeAddress(a);
    }
    for (const std::string& f : referee_receiver_->JoinFailures()) {
      ctx.Logger().Warning("referee group " + o.group + " not joined on " + f);
    }
    referee_source_ = o.group + ":" + std::to_string(referee_receiver_->Port());
    ctx.Logger().Info("shows the match from the referee on " + referee_source_ + " (joined on " + joined + ")");
  }

  // Server thread: a page's command → events, and the reply.
  std::string OnMessage(std::string_view text) {
    CommandLimits limits;
    {
      std::lock_guard lock(mutex_);  // FieldChanged may change them
      limits = limits_;
    }
    ubersim::viewer::DecodedCommand c = ubersim::viewer::DecodeCommand(text, limits);
    if (!c.error.empty()) {
      refusals_->Reject((c.cmd.empty() ? std::string() : "'" + c.cmd + "': ") + c.error);
      return ubersim::viewer::EncodeReply(c.cmd, c.id, c.error);
    }
    for (ubersim::Event& e : c.events) events_->Post(std::move(e));
    if (c.speed_factor) speed_factor_ = c.speed_factor;
    if (c.cmd == "move" || c.cmd == "kick" || c.cmd == "reset") refresh_now_ = true;
    return ubersim::viewer::EncodeReply(c.cmd, c.id);
  }

  // Server thread, every sample period: the status, then the state to every browser.
  void Tick() {
    const auto now = SteadyClock::now();
    if (relay_) relay_->Tick(now);  // a referee message held back by the rate limit
    WorldSample sample;
    std::vector<ubersim::VisionFrame> frames;
    std::uint64_t frames_received = 0;
    int cameras_seen = 0;
    {
      std::lock_guard lock(mutex_);
      if (!have_sample_) return;
      sample = sample_;
      for (const auto& [id, c] : cameras_) {
        frames.push_back(c.frame);
        if (now - c.received <= kRateWindow) ++cameras_seen;
      }
      frames_received = frames_received_;
    }
    // The world's own time (every step), not the sample's (every 1/rate): the last steps before
    // a pause may fall between two samples.
    const std::int64_t published = published_time_ns_.load(std::memory_order_relaxed);
    if (rates_.empty() || published != last_sim_time_ns_) {
      last_sim_time_ns_ = published;
      last_time_change_ = now;
      refreshed_at_stop_ = false;
    } else if (published != sample.sim_time_ns && !refreshed_at_stop_) {
      // The world stopped after the last sample: fetch its exact state once, at once.
      refresh_now_ = true;
      refreshed_at_stop_ = true;
    }
    const RateSample rate{now, sample.sim_time_ns, frames_received};
    rates_.push_back(rate);
    while (rates_.size() > 2 && now - rates_.front().wall > kRateWindow) rates_.pop_front();

    ViewerStatus status;
    const RateSample& first = rates_.front();
    const double wall = std::chrono::duration<double>(now - first.wall).count();
    if (wall > 0) {
      status.real_time_factor = static_cast<double>(rate.sim_time_ns - first.sim_time_ns) * 1e-9 / wall;
      status.vision_rate = static_cast<double>(rate.frames - first.frames) / wall /
                           std::max(1, cameras_seen);
    }
    status.cameras = cameras_seen;
    status.clients = server_->Clients();
    status.paused = now - last_time_change_ > kPausedAfter;
    status.speed_factor = speed_factor_;
    if (const auto last = relay_ ? relay_->LastReceived() : std::nullopt) {
      status.referee_age = std::chrono::duration<double>(now - *last).count();
    }
    {
      std::lock_guard lock(mutex_);
      status_ = status;
    }
    if (status.paused || refresh_now_) RefreshWhilePaused(now, sample);
    if (status.clients == 0) return;
    server_->Broadcast(std::make_shared<const std::string>(
        ubersim::viewer::EncodeState(sample, frames, status)));
  }

  // A world that stands still publishes nothing; ask for the state of every object so that what
  // a page or another client moved shows (answered on the simulation thread, cheap, and only
  // while nothing steps).
  void RefreshWhilePaused(SteadyClock::time_point now, const WorldSample& sample) {
    if (!refresh_now_ && now - last_refresh_ < kRefreshWhilePaused) return;
    refresh_now_ = false;
    last_refresh_ = now;
    events_->Post(ubersim::QueryEvent{ubersim::Target::Ball(), [this](const ubersim::ObjectState& s) {
      std::lock_guard lock(mutex_);
      // Answered on the simulation thread, where Publish keeps the time of the last step.
      sample_.step = published_step_;
      sample_.sim_time_ns = published_time_ns_.load(std::memory_order_relaxed);
      sample_.ball_position = s.pose.position;
      sample_.ball_velocity = s.twist.linear;
    }});
    for (std::size_t i = 0; i < sample.robots.size(); ++i) {
      const ubersim::RobotId id = sample.robots[i].id;
      events_->Post(ubersim::QueryEvent{ubersim::Target::Robot(id), [this, i, id](const ubersim::ObjectState& s) {
        std::lock_guard lock(mutex_);
        if (!s.found || i >= sample_.robots.size() || !(sample_.robots[i].id == id)) return;
        sample_.robots[i].present = s.present;
        sample_.robots[i].SetMotion(s.pose, s.twist);
      }});
    }
  }

  // GET /api/state (server thread).
  std::string EncodeLatest() {
    std::lock_guard lock(mutex_);
    if (!have_sample_) return {};
    std::vector<ubersim::VisionFrame> frames;
    for (const auto& [id, c] : cameras_) frames.push_back(c.frame);
    ViewerStatus status = status_;
    status.clients = server_->Clients();
    return ubersim::viewer::EncodeState(sample_, frames, status);
  }

  // Set in Start, then read-only.
  ubersim::TransportContext* context_ = nullptr;
  double rate_ = 60.0;
  SteadyClock::duration period_{};
  ubersim::EventSink* events_ = nullptr;
  CommandLimits limits_;  // under mutex_ (the field may change)
  std::string hello_;
  std::unique_ptr<ubersim::transport::RejectLog> refusals_;
  std::string referee_source_;  // "224.5.23.1:10003", or "" without a referee socket
  std::unique_ptr<ubersim::transport::RejectLog> referee_rejects_;
  std::unique_ptr<RefereeRelay> relay_;  // thread-safe: receive thread and server thread
  // Simulation thread only (written by Publish, read by query replies).
  std::string field_name_;
  SteadyClock::time_point next_sample_{};
  std::int64_t published_step_ = 0;
  // Written by the simulation thread every step, read by the server thread.
  std::atomic<std::int64_t> published_time_ns_{0};
  // Shared between the simulation thread (Publish, OnVisionFrame, query replies) and the server
  // thread (Tick, EncodeLatest).
  std::mutex mutex_;
  WorldSample sample_;
  bool have_sample_ = false;
  std::map<int, Camera> cameras_;
  std::uint64_t frames_received_ = 0;
  ViewerStatus status_;
  // Server thread only.
  std::deque<RateSample> rates_;
  std::int64_t last_sim_time_ns_ = -1;
  SteadyClock::time_point last_time_change_{};
  SteadyClock::time_point last_refresh_{};
  std::optional<double> speed_factor_;
  bool refresh_now_ = false;
  bool refreshed_at_stop_ = false;
  // Last: stopped (and their threads joined) before the members above are destroyed; the
  // referee's receiver before the server its datagrams are broadcast on.
  std::unique_ptr<ViewerServer> server_;
  std::unique_ptr<MulticastReceiver> referee_receiver_;
};

}  // namespace

UBERSIM_REGISTER_TRANSPORT(ViewerTransport, "viewer", "1.0.0", ubersim_plugin::kSchema)
