// SPDX-License-Identifier: Apache-2.0
#include "match_session.hpp"

#include <chrono>
#include <cmath>
#include <span>
#include <stdexcept>

#include "game_controller_link.hpp"
#include "tracker_packets.hpp"
#include "transport_common/multicast_sender.hpp"
#include "transport_common/wire_clock.hpp"
#include "vision_packets.hpp"

namespace ubersim::match {
namespace {

std::span<const std::uint8_t> Bytes(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

std::int64_t PeriodNs(double rate) { return rate > 0 ? static_cast<std::int64_t>(std::llround(1e9 / rate)) : 0; }

}  // namespace

struct MatchSession::Senders {
  std::unique_ptr<transport::MulticastSender> referee;
  std::unique_ptr<transport::MulticastSender> tracker;
  // Vision as recorded: the same packet builder the ssl_vision transport sends with.
  std::unique_ptr<transport::WireClock> vision_clock;
  ssl_vision::GeometryInputs geometry;
  std::int64_t next_geometry_ns = 0;
};

MatchSession::MatchSession(kernel::World& world, MatchOptions options, Log& log)
    : world_(world), options_(std::move(options)), log_(log), senders_(std::make_unique<Senders>()) {
  const bool local = options_.local_only || world_.model().local_only;
  auto sender = [&](const std::string& group, std::uint16_t port, const char* name) {
    transport::MulticastSender::Options o;
    o.group = group;
    o.port = port;
    o.local_only = local;
    o.name = name;
    return std::make_unique<transport::MulticastSender>(o);
  };
  // The field as the geometry packets describe it: recorded, and sent to a game controller.
  const WorldSnapshot truth = world_.GroundTruth();
  senders_->geometry.field = *truth.field;
  for (const auto& c : world_.perception().cameras) senders_->geometry.cameras.push_back({c.id, c.position});
  senders_->geometry.ball_radius = truth.ball.radius;
  if (options_.referee) {
    const RefereeMode mode = options_.game_controller.empty() ? RefereeMode::kGameController : RefereeMode::kAutoref;
    referee_ = std::make_unique<RefereeEngine>(*options_.referee, *truth.field, UnixOffset(), mode);
    if (mode == RefereeMode::kAutoref) link_ = std::make_unique<GameControllerLink>(options_.game_controller);
    if (options_.network) senders_->referee = sender(options_.referee_address, options_.referee_port, "referee");
  }
  tracker_uuid_ = UuidFromSeed(world_.model().seed);
  tracker_rng_.seed(world_.model().seed ^ 0x6e6f697365ULL);  // "noise": its own stream, the same per world
  if (options_.tracker) {
    if (options_.network) senders_->tracker = sender(options_.tracker_address, options_.tracker_port, "tracker");
  }
  if (options_.recorder) {
    // The detections' own time stamps on the session's clock, so they agree with the records'.
    senders_->vision_clock = std::make_unique<transport::WireClock>(
        options_.unix_timestamps ? transport::TimestampMode::kUnix : transport::TimestampMode::kSim,
        [this] { return static_cast<double>(UnixOffset() + world_.clock().time_ns()) * 1e-9; });
    world_.SetVisionObserver([this](const VisionFrame& frame) {
      const std::int64_t offset = UnixOffset();
      if (frame.t_sent_ns >= senders_->next_geometry_ns) {
        std::string g;
        ssl_vision::GeometryPacket(senders_->geometry).SerializeToString(&g);
        options_.recorder(frame.t_sent_ns + offset, WireMessage::kVision, g);
        senders_->next_geometry_ns = frame.t_sent_ns + 3'000'000'000LL;  // as the transport's geometry_interval
      }
      const CameraInfo* camera = nullptr;
      for (const auto& c : senders_->geometry.cameras) {
        if (c.id == frame.camera_id) camera = &c;
      }
      senders_->vision_clock->Update(world_.clock().time_ns());
      std::string bytes;
      ssl_vision::DetectionPacket(frame, *senders_->vision_clock, senders_->geometry.intrinsics, camera, {})
          .SerializeToString(&bytes);
      options_.recorder(frame.t_sent_ns + offset, WireMessage::kVision, bytes);
    });
  }
}

MatchSession::~MatchSession() {
  if (options_.recorder) world_.SetVisionObserver(nullptr);
}

std::int64_t MatchSession::UnixOffset() {
  if (!options_.unix_timestamps) return 0;
  if (!unix_offset_ns_ && options_.unix_offset_ns) unix_offset_ns_ = options_.unix_offset_ns;
  if (!unix_offset_ns_) {
    // Anchored once: stamps keep the simulation's spacing exactly, also faster than real time.
    const auto now = std::chrono::system_clock::now().time_since_epoch();
    unix_offset_ns_ = std::chrono::duration_cast<std::chrono::nanoseconds>(now).count() - world_.clock().time_ns();
  }
  return *unix_offset_ns_;
}

std::string MatchSession::GameController() const { return link_ ? link_->Describe() : std::string(); }

std::vector<std::string> MatchSession::Endpoints() const {
  std::vector<std::string> out;
  if (senders_->referee) out.push_back("referee: " + senders_->referee->Describe());
  if (senders_->tracker) out.push_back("tracker: " + senders_->tracker->Describe());
  return out;
}

void MatchSession::Send(WireMessage type, const std::string& bytes, std::int64_t sim_ns) {
  transport::MulticastSender* s = type == WireMessage::kReferee ? senders_->referee.get() : senders_->tracker.get();
  if (s != nullptr) s->Send(Bytes(bytes));
  if (options_.recorder) options_.recorder(sim_ns + UnixOffset(), type, bytes);
}

void MatchSession::Carry(const std::vector<FieldRequest>& requests, const WorldSnapshot& truth) {
  for (const FieldRequest& r : requests) {
    PositionEvent e;
    switch (r.kind) {
      case FieldRequest::Kind::kPlaceBall:
        e.target = Target::Ball();
        e.position = Vec3(r.position.x, r.position.y, truth.ball.radius);
        e.velocity = Vec3::Zero();
        e.angular_velocity = Vec3::Zero();
        log_.Info("referee places the ball at (" + std::to_string(r.position.x) + ", " + std::to_string(r.position.y) + ")");
        break;
      case FieldRequest::Kind::kTakeOff:
        e.target = Target::Robot(r.robot);
        e.present = false;
        log_.Info("referee takes " + ToString(r.robot) + " off the field (yellow card)");
        break;
      case FieldRequest::Kind::kPutOn:
        e.target = Target::Robot(r.robot);
        e.present = true;
        e.position = Vec3(r.position.x, r.position.y, 0);
        e.velocity = Vec3::Zero();
        log_.Info("referee puts " + ToString(r.robot) + " back on the field (card over)");
        break;
    }
    world_.events().Post(std::move(e));
  }
}

namespace {

// The GC-internal command of a Referee command the CI client asks for (only STOP is needed).
Command GcCommand(Referee::Command c) {
  Command out;
  out.set_type(c == Referee::HALT ? Command::HALT : Command::STOP);
  out.set_for_team(::UNKNOWN);
  return out;
}

}  // namespace

void MatchSession::ExchangeWithGameController(const WorldSnapshot& truth, std::int64_t now) {
  CiInput in;
  in.set_timestamp(now + UnixOffset());
  *in.mutable_tracker_packet() = TrackedPacket(truth, ci_frame_++, UnixOffset(), {tracker_uuid_, "UberSim ground truth"});
  if (!ci_started_) {
    // The field once, and the engine's events accepted without a human (behaviour ACCEPT, §1.6).
    *in.mutable_geometry() = ssl_vision::GeometryPacket(senders_->geometry).geometry();
    Input* config = in.add_api_inputs();
    for (const char* type : {"BALL_LEFT_FIELD_TOUCH_LINE", "BALL_LEFT_FIELD_GOAL_LINE", "POSSIBLE_GOAL",
                             "PLACEMENT_SUCCEEDED", "BOT_TOO_FAST_IN_STOP", "DEFENDER_TOO_CLOSE_TO_KICK_POINT"}) {
      (*config->mutable_config_delta()->mutable_game_event_behavior())[type] = Config::BEHAVIOR_ACCEPT;
    }
    ci_started_ = true;
  }
  for (GameEvent& e : referee_->TakeGameEvents()) {
    *in.add_api_inputs()->mutable_change()->mutable_add_game_event_change()->mutable_game_event() = std::move(e);
  }
  for (const ControlRequest& r : referee_->TakeControlRequests()) {
    Input* input = in.add_api_inputs();
    if (r.command) *input->mutable_change()->mutable_new_command_change()->mutable_command() = GcCommand(*r.command);
    if (r.stage) input->mutable_change()->mutable_change_stage_change()->set_new_stage(*r.stage);
    if (r.accept_goal) {
      input->mutable_continue_action()->set_type(ContinueAction::ACCEPT_GOAL);
      input->mutable_continue_action()->set_for_team(WireTeam(r.for_team));
    }
  }
  const std::vector<Referee> answers = link_->Exchange(in);
  std::string bytes;
  for (const Referee& m : answers) {
    m.SerializeToString(&bytes);
    Send(WireMessage::kReferee, bytes, now);
  }
  referee_->Follow(answers.back());
}

void MatchSession::AfterStep() {
  const std::int64_t step = world_.clock().steps();
  if (step == last_step_) return;
  last_step_ = step;
  const std::int64_t now = world_.clock().time_ns();
  const bool referee_due = referee_ != nullptr;
  const bool tracker_due = options_.tracker && now >= next_tracker_ns_;
  if (!referee_due && !tracker_due) return;
  const WorldSnapshot truth = world_.GroundTruth();
  if (referee_) {
    Carry(referee_->Update(ViewOf(truth)), truth);
  }
  if (link_) {
    if (now >= next_ci_ns_) {
      ExchangeWithGameController(truth, now);
      next_ci_ns_ = now + PeriodNs(options_.ci_rate);
    }
  } else if (referee_) {
    std::string bytes;
    const auto commands = referee_->TakeCommandMessages();
    for (const Referee& m : commands) {
      m.SerializeToString(&bytes);
      Send(WireMessage::kReferee, bytes, now);
    }
    if (!commands.empty() || now >= next_referee_ns_) {
      if (commands.empty()) {
        referee_->message().SerializeToString(&bytes);
        Send(WireMessage::kReferee, bytes, now);
      }
      next_referee_ns_ = now + PeriodNs(options_.referee_rate);
    }
  }
  if (tracker_due) {
    std::string bytes;
    const kernel::PerceptionModel& p = world_.perception();
    const TrackerNoise noise{p.ball_position_sigma, p.robot_position_sigma, p.robot_orientation_sigma, &tracker_rng_};
    const TrackerSource source{tracker_uuid_, options_.tracker_noise ? "UberSim truth with vision noise" : "UberSim ground truth"};
    TrackedPacket(truth, tracker_frame_++, UnixOffset(), source, options_.tracker_noise ? &noise : nullptr)
        .SerializeToString(&bytes);
    Send(WireMessage::kTracker, bytes, now);
    next_tracker_ns_ = now + PeriodNs(options_.tracker_rate);
  }
}

}  // namespace ubersim::match
