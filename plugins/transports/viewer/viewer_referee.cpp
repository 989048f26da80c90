// SPDX-License-Identifier: Apache-2.0
#include "viewer_referee.hpp"

#include <cctype>
#include <cmath>
#include <string_view>
#include <utility>

#include <rapidjson/stringbuffer.h>
#include <rapidjson/writer.h>

#include "ssl_gc_common.pb.h"
#include "ssl_gc_game_event.pb.h"
#include "ssl_gc_referee_message.pb.h"

namespace ubersim::viewer {
namespace {

using Writer = rapidjson::Writer<rapidjson::StringBuffer>;
namespace pb = google::protobuf;

constexpr double kMicro = 1e-6;  // µs → s
constexpr double kMilli = 1e-3;  // mm → m

// Text from the network as valid UTF-8: a browser drops a WebSocket whose text frame is not, so
// every byte that does not start a well-formed sequence becomes U+FFFD.
std::string ValidUtf8(std::string_view in) {
  std::string out;
  out.reserve(in.size());
  std::size_t i = 0;
  while (i < in.size()) {
    const auto b = static_cast<unsigned char>(in[i]);
    std::size_t n = 0;
    std::uint32_t min = 0, cp = 0;
    if (b < 0x80) n = 1;
    else if ((b & 0xE0) == 0xC0) n = 2, min = 0x80, cp = b & 0x1F;
    else if ((b & 0xF0) == 0xE0) n = 3, min = 0x800, cp = b & 0x0F;
    else if ((b & 0xF8) == 0xF0) n = 4, min = 0x10000, cp = b & 0x07;
    bool ok = n > 0 && i + n <= in.size();
    for (std::size_t k = 1; ok && k < n; ++k) {
      const auto c = static_cast<unsigned char>(in[i + k]);
      ok = (c & 0xC0) == 0x80;
      cp = (cp << 6) | (c & 0x3F);
    }
    // No overlong forms, no UTF-16 surrogates, nothing above U+10FFFF (RFC 3629).
    if (ok && n > 1) ok = cp >= min && cp <= 0x10FFFF && (cp < 0xD800 || cp > 0xDFFF);
    if (ok) {
      out.append(in.substr(i, n));
      i += n;
    } else {
      out.append("\xEF\xBF\xBD");
      ++i;
    }
  }
  return out;
}

void String(Writer& w, const std::string& value) {
  const std::string valid = ValidUtf8(value);
  w.String(valid.c_str(), static_cast<rapidjson::SizeType>(valid.size()));
}

void Text(Writer& w, const char* key, const std::string& value) {
  w.Key(key);
  String(w, value);
}

void Seconds(Writer& w, const char* key, double us) {
  w.Key(key);
  w.Double(us * kMicro);
}

// "yellow", "blue", or nullptr for UNKNOWN.
const char* TeamName(int team) {
  return team == YELLOW ? "yellow" : team == BLUE ? "blue" : nullptr;
}

void TeamInfo(Writer& w, const char* key, const Referee::TeamInfo& t) {
  w.Key(key);
  w.StartObject();
  Text(w, "name", t.name());
  w.Key("score");
  w.Uint(t.score());
  w.Key("red_cards");
  w.Uint(t.red_cards());
  w.Key("yellow_cards");
  w.Uint(t.yellow_cards());
  // Each card's time left, µs in the message.
  w.Key("yellow_card_times");
  w.StartArray();
  for (std::uint32_t us : t.yellow_card_times()) w.Double(us * kMicro);
  w.EndArray();
  w.Key("timeouts");
  w.Uint(t.timeouts());
  Seconds(w, "timeout_time", t.timeout_time());
  w.Key("goalkeeper");
  w.Uint(t.goalkeeper());
  w.Key("fouls");
  if (t.has_foul_counter()) w.Uint(t.foul_counter()); else w.Null();
  w.Key("ball_placement_failures");
  if (t.has_ball_placement_failures()) w.Uint(t.ball_placement_failures()); else w.Null();
  w.Key("can_place_ball");
  if (t.has_can_place_ball()) w.Bool(t.can_place_ball()); else w.Null();
  w.Key("max_allowed_bots");
  if (t.has_max_allowed_bots()) w.Uint(t.max_allowed_bots()); else w.Null();
  w.EndObject();
}

// The event's type name, and the team and robot its payload names (by reflection: every payload
// that has them calls them by_team and by_bot, and new event types need no code here).
void Event(Writer& w, const GameEvent& e, bool current) {
  w.StartObject();
  const pb::Reflection* reflection = e.GetReflection();
  const pb::OneofDescriptor* oneof = GameEvent::descriptor()->FindOneofByName("event");
  const pb::FieldDescriptor* set = oneof ? reflection->GetOneofFieldDescriptor(e, oneof) : nullptr;
  w.Key("type");
  if (e.has_type()) {
    w.String(GameEvent::Type_Name(e.type()).c_str());
  } else if (set) {  // the payload's field is named after the type, in lower case
    std::string name = set->name();
    for (char& c : name) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    w.String(name.c_str());
  } else {
    w.String(GameEvent::Type_Name(GameEvent::UNKNOWN_GAME_EVENT_TYPE).c_str());
  }
  const char* team = nullptr;
  std::optional<std::uint32_t> bot;
  if (set && set->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE) {
    const pb::Message& payload = reflection->GetMessage(e, set);
    const pb::Reflection* r = payload.GetReflection();
    const pb::Descriptor* d = payload.GetDescriptor();
    const pb::FieldDescriptor* by_team = d->FindFieldByName("by_team");
    if (by_team && by_team->enum_type() == Team_descriptor() && r->HasField(payload, by_team)) {
      team = TeamName(r->GetEnumValue(payload, by_team));
    }
    const pb::FieldDescriptor* by_bot = d->FindFieldByName("by_bot");
    if (by_bot && by_bot->cpp_type() == pb::FieldDescriptor::CPPTYPE_UINT32 && r->HasField(payload, by_bot)) {
      bot = r->GetUInt32(payload, by_bot);
    }
  }
  w.Key("by_team");
  if (team) w.String(team); else w.Null();
  w.Key("by_bot");
  if (bot) w.Uint(*bot); else w.Null();
  w.Key("current");
  w.Bool(current);
  w.EndObject();
}

}  // namespace

std::string EncodeReferee(const Referee& r, const GameEvent* earlier_event) {
  rapidjson::StringBuffer buffer;
  Writer w(buffer);
  w.SetMaxDecimalPlaces(6);  // 1 µs, 1 µm
  w.StartObject();
  w.Key("type");
  w.String("referee");
  w.Key("stage");
  w.String(Referee::Stage_Name(r.stage()).c_str());
  w.Key("stage_time_left");
  if (r.has_stage_time_left()) w.Double(static_cast<double>(r.stage_time_left()) * kMicro); else w.Null();
  w.Key("command");
  w.String(Referee::Command_Name(r.command()).c_str());
  w.Key("command_counter");
  w.Uint(r.command_counter());
  w.Key("next_command");
  if (r.has_next_command()) w.String(Referee::Command_Name(r.next_command()).c_str()); else w.Null();
  w.Key("action_time_left");
  if (r.has_current_action_time_remaining()) {
    w.Double(static_cast<double>(r.current_action_time_remaining()) * kMicro);
  } else {
    w.Null();
  }
  // mm in the message (vision's frame); a non-finite float goes out as null, not as broken JSON.
  w.Key("designated_position");
  const bool placed = r.has_designated_position() && std::isfinite(r.designated_position().x()) &&
                      std::isfinite(r.designated_position().y());
  if (placed) {
    w.StartObject();
    w.Key("x");
    w.Double(r.designated_position().x() * kMilli);
    w.Key("y");
    w.Double(r.designated_position().y() * kMilli);
    w.EndObject();
  } else {
    w.Null();
  }
  w.Key("blue_team_on_positive_half");
  if (r.has_blue_team_on_positive_half()) w.Bool(r.blue_team_on_positive_half()); else w.Null();
  TeamInfo(w, "yellow", r.yellow());
  TeamInfo(w, "blue", r.blue());
  w.Key("game_event");
  if (r.game_events_size() > 0) {
    Event(w, r.game_events(r.game_events_size() - 1), true);
  } else if (earlier_event) {
    Event(w, *earlier_event, false);
  } else {
    w.Null();
  }
  w.Key("game_events");
  w.Int(r.game_events_size());
  w.Key("status_message");
  if (r.has_status_message()) String(w, r.status_message()); else w.Null();
  w.Key("source");
  if (r.has_source_identifier()) String(w, r.source_identifier()); else w.Null();
  w.Key("match_type");
  w.String(MatchType_Name(r.match_type()).c_str());
  w.EndObject();
  return buffer.GetString();
}

// ---------------------------------------------------------------- relay

struct RefereeRelay::Messages {
  Referee latest;
  GameEvent earlier;  // the last event of the last message that carried any
  bool has_earlier = false;
};

RefereeRelay::RefereeRelay(Clock::duration min_interval, Send send)
    : min_interval_(min_interval), send_(std::move(send)), messages_(std::make_unique<Messages>()) {}

RefereeRelay::~RefereeRelay() = default;

bool RefereeRelay::OnDatagram(std::span<const std::uint8_t> bytes, Clock::time_point now) {
  Referee parsed;
  // False for bytes that are not protobuf and for a message without its required fields.
  if (!parsed.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) return false;
  std::lock_guard lock(mutex_);
  ++received_;
  last_received_ = now;
  if (parsed.game_events_size() > 0) {
    messages_->earlier = parsed.game_events(parsed.game_events_size() - 1);
    messages_->has_earlier = true;
  }
  messages_->latest.Swap(&parsed);
  pending_ = true;
  if (now >= next_send_) SendLocked(now);
  return true;
}

void RefereeRelay::Tick(Clock::time_point now) {
  std::lock_guard lock(mutex_);
  if (pending_ && now >= next_send_) SendLocked(now);
}

void RefereeRelay::SendLocked(Clock::time_point now) {
  pending_ = false;
  std::string json = EncodeReferee(messages_->latest, messages_->has_earlier ? &messages_->earlier : nullptr);
  if (sent_ && *sent_ == json) return;  // e.g. the game controller repeating a halted state
  sent_ = std::make_shared<const std::string>(std::move(json));
  next_send_ = now + min_interval_;
  if (send_) send_(sent_);
}

std::shared_ptr<const std::string> RefereeRelay::Latest() const {
  std::lock_guard lock(mutex_);
  return sent_;
}

std::optional<RefereeRelay::Clock::time_point> RefereeRelay::LastReceived() const {
  std::lock_guard lock(mutex_);
  return last_received_;
}

std::uint64_t RefereeRelay::Received() const {
  std::lock_guard lock(mutex_);
  return received_;
}

}  // namespace ubersim::viewer
