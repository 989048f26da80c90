// SPDX-License-Identifier: Apache-2.0
#include "referee_engine.hpp"

#include <algorithm>
#include <cmath>

namespace ubersim::match {
namespace {

constexpr std::int64_t kNs = 1'000'000'000;
constexpr double kTouchMargin = 0.02;       // a robot touches the ball within its radius + the ball's + this, m
constexpr double kTouchMaxHeight = 0.15;    // a ball above this is not touched by a robot, m
constexpr double kKickMoved = 0.05;         // a kick-off or free kick is taken once the ball moved this far [R 5.4], m
constexpr double kNoProgressDistance = 0.1; // the game controller's "ball moved" for no progress, m
constexpr double kSteadySpeed = 0.2;        // a steady ball (engine/common.go), m/s
constexpr double kStopDistance = 0.5;       // robots keep this far from the ball in STOP [R 5.1.1], m
constexpr double kReadyDistance = 0.54;     // 0.5 + robot radius − tolerance: a robot closer blocks resuming, m
constexpr double kStopSpeed = 1.5;          // robots slower than this in STOP, m/s
constexpr double kGraceTime = 2.0;          // grace for the STOP speed limit and for defenders, s
constexpr double kPlacementNeeded = 1.0;    // no placement when the ball is this close to the target, m
constexpr double kDefenseAreaClearance = 0.7;  // ... and this far from both defense areas, m
constexpr double kPlacementRobotClearance = 0.05;  // no robot this close to a placed ball, m
constexpr double kMaxGoalHeight = 0.15;     // a goal is invalid when the ball went higher after the scorer's last touch, m
constexpr int kEarlyEndGoals = 10;          // a team with this many goals and a lead > 1 ends the match [R 4.4.3]

double Dist(P2 a, P2 b) { return std::hypot(a.x - b.x, a.y - b.y); }
double Speed(P2 v) { return std::hypot(v.x, v.y); }
int TeamIndex(Team t) { return t == Team::kBlue ? 0 : 1; }
Team Other(Team t) { return t == Team::kBlue ? Team::kYellow : Team::kBlue; }
bool IsRunning(Referee::Command c) {
  return c == Referee::NORMAL_START || c == Referee::FORCE_START || c == Referee::DIRECT_FREE_BLUE ||
         c == Referee::DIRECT_FREE_YELLOW;
}
bool IsBreak(Referee::Stage s) {
  return s == Referee::NORMAL_HALF_TIME || s == Referee::EXTRA_TIME_BREAK || s == Referee::EXTRA_HALF_TIME ||
         s == Referee::PENALTY_SHOOTOUT_BREAK;
}
bool IsPre(Referee::Stage s) {
  return s == Referee::NORMAL_FIRST_HALF_PRE || s == Referee::NORMAL_SECOND_HALF_PRE;
}
Referee::Command Kickoff(Team t) { return t == Team::kBlue ? Referee::PREPARE_KICKOFF_BLUE : Referee::PREPARE_KICKOFF_YELLOW; }
Referee::Command Direct(Team t) { return t == Team::kBlue ? Referee::DIRECT_FREE_BLUE : Referee::DIRECT_FREE_YELLOW; }
Referee::Command Placement(Team t) { return t == Team::kBlue ? Referee::BALL_PLACEMENT_BLUE : Referee::BALL_PLACEMENT_YELLOW; }
bool IsKickoff(Referee::Command c) { return c == Referee::PREPARE_KICKOFF_BLUE || c == Referee::PREPARE_KICKOFF_YELLOW; }
bool IsDirect(Referee::Command c) { return c == Referee::DIRECT_FREE_BLUE || c == Referee::DIRECT_FREE_YELLOW; }
bool IsPlacement(Referee::Command c) { return c == Referee::BALL_PLACEMENT_BLUE || c == Referee::BALL_PLACEMENT_YELLOW; }
Team TeamOf(Referee::Command c) {
  switch (c) {
    case Referee::PREPARE_KICKOFF_BLUE: case Referee::PREPARE_PENALTY_BLUE: case Referee::DIRECT_FREE_BLUE:
    case Referee::TIMEOUT_BLUE: case Referee::BALL_PLACEMENT_BLUE: case Referee::GOAL_BLUE:
      return Team::kBlue;
    default:
      return Team::kYellow;
  }
}
Vector2* Set(Vector2* v, P2 p) {
  v->set_x(static_cast<float>(p.x));
  v->set_y(static_cast<float>(p.y));
  return v;
}

}  // namespace

::Team WireTeam(Team t) { return t == Team::kBlue ? ::BLUE : ::YELLOW; }

RefereeEngine::RefereeEngine(const RefereeConfig& config, const FieldGeometry& field, std::int64_t unix_offset_ns,
                             RefereeMode mode)
    : config_(config), mode_(mode), rules_(field), unix_offset_ns_(unix_offset_ns) {
  const bool a = config_.division == Division::kA;
  const unsigned robots = a ? 11 : 6;
  for (Team t : {Team::kYellow, Team::kBlue}) {
    Referee::TeamInfo& info = Info(t);
    info.set_name(t == Team::kBlue ? config_.blue_name : config_.yellow_name);
    info.set_score(0);
    info.set_red_cards(0);
    info.set_yellow_cards(0);
    info.set_timeouts(4);
    info.set_timeout_time(300'000'000);
    info.set_goalkeeper(static_cast<unsigned>(t == Team::kBlue ? config_.blue_keeper : config_.yellow_keeper));
    info.set_foul_counter(0);
    info.set_ball_placement_failures(0);
    info.set_can_place_ball(t == Team::kBlue ? config_.blue_can_place : config_.yellow_can_place);
    info.set_max_allowed_bots(robots);
    info.set_bot_substitution_intent(false);
    info.set_ball_placement_failures_reached(false);
    info.set_bot_substitution_allowed(false);
    info.set_bot_substitutions_left(5);
    info.set_bot_substitution_time_left(0);
  }
  // The game controller's initial state (§1.4): halted before the first half, kick-off next.
  msg_.set_stage(Referee::NORMAL_FIRST_HALF_PRE);
  msg_.set_stage_time_left(static_cast<std::int64_t>(config_.half_duration * 1e6));
  msg_.set_command(Referee::HALT);
  msg_.set_command_counter(0);
  msg_.set_command_timestamp(Micros(0));
  msg_.set_packet_timestamp(Micros(0));
  msg_.set_blue_team_on_positive_half(config_.blue_on_positive_half);
  msg_.set_next_command(Kickoff(config_.first_kickoff));
  msg_.set_current_action_time_remaining(0);
  msg_.set_source_identifier(config_.source_identifier);
  msg_.set_match_type(config_.match_type);
  next_team_ = config_.first_kickoff;
  last_touch_team_ = config_.first_kickoff;
}

std::uint64_t RefereeEngine::Micros(std::int64_t t_ns) const {
  return static_cast<std::uint64_t>(std::max<std::int64_t>(0, t_ns + unix_offset_ns_) / 1000);
}

Referee::TeamInfo& RefereeEngine::Info(Team t) { return t == Team::kBlue ? *msg_.mutable_blue() : *msg_.mutable_yellow(); }
const Referee::TeamInfo& RefereeEngine::Info(Team t) const { return t == Team::kBlue ? msg_.blue() : msg_.yellow(); }

int RefereeEngine::GoalSideOf(Team defending) const {
  const bool blue_positive = msg_.blue_team_on_positive_half();
  return (defending == Team::kBlue) == blue_positive ? 1 : -1;
}

bool RefereeEngine::CanPlace(Team t) const {
  const auto& info = Info(t);
  return info.can_place_ball() && !info.ball_placement_failures_reached();
}

std::vector<Referee> RefereeEngine::TakeCommandMessages() {
  std::vector<Referee> out;
  out.swap(command_messages_);
  return out;
}

void RefereeEngine::Issue(Referee::Command command, std::int64_t t_ns) {
  msg_.set_command(command);
  msg_.set_command_counter(msg_.command_counter() + 1);
  msg_.set_command_timestamp(Micros(t_ns));
  msg_.set_packet_timestamp(Micros(t_ns));
  const bool a = config_.division == Division::kA;
  double action = 0;
  if (IsPlacement(command)) action = config_.placement_time;
  if (IsDirect(command)) action = a ? 5.0 : 10.0;
  if (IsKickoff(command) || command == Referee::NORMAL_START) action = config_.kickoff_time;
  msg_.set_current_action_time_remaining(static_cast<std::int64_t>(action * 1e6));
  if (IsRunning(command)) {
    // A running command clears the designated position, the next command and the events (§2.1).
    msg_.clear_designated_position();
    msg_.clear_next_command();
    msg_.clear_game_events();
  }
  OnCommand(command, t_ns);
  command_messages_.push_back(msg_);
}

// What a new command means for the watching (both modes: the built-in referee's own commands and
// the game controller's).
void RefereeEngine::OnCommand(Referee::Command command, std::int64_t t_ns) {
  t_command_ns_ = t_ns;
  reported_ = false;
  control_requested_ = false;
  if (IsRunning(command)) {
    in_play_ = command == Referee::FORCE_START;
    if (autoref()) {
      kick_point_ = last_ball_;
      // The team taking the restart touches first: the kick-off's (the previous command) or the free kick's.
      if (IsDirect(command)) last_touch_team_ = TeamOf(command);
      if (command == Referee::NORMAL_START && IsKickoff(previous_command_)) last_touch_team_ = TeamOf(previous_command_);
      last_touch_bot_ = -1;
    }
    progress_point_ = kick_point_;
    t_progress_ns_ = t_ns;
  }
  if (command == Referee::STOP || command == Referee::HALT) {
    t_stop_ns_ = t_ns;
    in_play_ = false;
    stop_speed_fouled_.clear();
  }
  if (IsPlacement(command)) {
    in_play_ = false;
    if (autoref()) {
      placing_team_ = TeamOf(command);
      t_placement_ns_ = t_ns;
      const P2 target = Designated();
      placement_best_ = Dist(last_ball_, target);
      t_placement_progress_ns_ = t_ns;
    }
  }
  previous_command_ = command;
}

void RefereeEngine::Follow(const Referee& gc) {
  const bool new_command = !followed_ || gc.command_counter() != msg_.command_counter() || gc.command() != msg_.command();
  if (!followed_ || gc.stage() != msg_.stage()) stage_requested_ = false;
  msg_ = gc;
  followed_ = true;
  if (new_command) OnCommand(gc.command(), t_last_ns_);
}

std::vector<GameEvent> RefereeEngine::TakeGameEvents() {
  std::vector<GameEvent> out;
  out.swap(events_out_);
  return out;
}

std::vector<ControlRequest> RefereeEngine::TakeControlRequests() {
  std::vector<ControlRequest> out;
  out.swap(control_out_);
  return out;
}

void RefereeEngine::Stop(std::int64_t t_ns, std::optional<Referee::Command> next, std::optional<P2> designated) {
  if (next) {
    msg_.set_next_command(*next);
    original_next_ = *next;
    next_team_ = TeamOf(*next);
  }
  if (designated) {
    msg_.mutable_designated_position()->set_x(static_cast<float>(designated->x * 1000));
    msg_.mutable_designated_position()->set_y(static_cast<float>(designated->y * 1000));
  }
  placement_attempts_ = 0;
  t_referee_placed_ns_ = -1;
  in_play_ = false;
  Issue(Referee::STOP, t_ns);
}

void RefereeEngine::AddEvent(GameEvent event) {
  event.add_origin("UberSim");
  history_times_.push_back(t_last_ns_);
  if (autoref()) {
    // The game controller fills in id and time stamp itself (§1.6).
    events_out_.push_back(event);
    history_.push_back(std::move(event));
    return;
  }
  event.set_created_timestamp(Micros(t_last_ns_));
  event.set_id(std::to_string(history_.size() + 1));
  *msg_.add_game_events() = event;
  history_.push_back(std::move(event));
}

void RefereeEngine::SetStage(Referee::Stage stage, std::int64_t t_ns) {
  msg_.set_stage(stage);
  msg_.clear_game_events();
  double left = 0;
  if (stage == Referee::NORMAL_FIRST_HALF || stage == Referee::NORMAL_SECOND_HALF || IsPre(stage)) {
    left = config_.half_duration;
  } else if (stage == Referee::NORMAL_HALF_TIME) {
    left = config_.half_time_break;
  }
  msg_.set_stage_time_left(static_cast<std::int64_t>(left * 1e6));
  if (stage == Referee::NORMAL_SECOND_HALF_PRE) {
    // Placement failures count per half [R 5.2].
    for (Team t : {Team::kBlue, Team::kYellow}) {
      Info(t).set_ball_placement_failures(0);
      Info(t).set_ball_placement_failures_reached(false);
    }
  }
  (void)t_ns;
}

void RefereeEngine::CountDown(std::int64_t dt_ns) {
  const std::int64_t dt_us = dt_ns / 1000;
  const bool running = IsRunning(msg_.command());
  if (running || IsBreak(msg_.stage())) {
    msg_.set_stage_time_left(msg_.stage_time_left() - dt_us);
  }
  if (running || IsPlacement(msg_.command())) {
    msg_.set_current_action_time_remaining(
        std::max<std::int64_t>(msg_.current_action_time_remaining() - dt_us, -1'800'000'000));
  }
  if (!running) return;
  // Yellow cards count down in playing time only.
  for (Team t : {Team::kBlue, Team::kYellow}) {
    auto* times = Info(t).mutable_yellow_card_times();
    for (int i = 0; i < times->size(); ++i) {
      const auto left = static_cast<std::int64_t>(times->Get(i)) - dt_us;
      times->Set(i, static_cast<std::uint32_t>(std::max<std::int64_t>(0, left)));
    }
  }
}

void RefereeEngine::TrackTouches(const FieldView& v) {
  for (int i = 0; i < 2; ++i) max_height_since_touch_[i] = std::max(max_height_since_touch_[i], v.ball_z - v.ball_radius);
  if (v.ball_z > kTouchMaxHeight) return;
  const RobotView* nearest = nullptr;
  double best = 1e9;
  for (const RobotView& r : v.robots) {
    if (!r.present) continue;
    const double gap = Dist(r.pos, v.ball) - r.radius - v.ball_radius;
    if (gap < kTouchMargin && gap < best) {
      best = gap;
      nearest = &r;
    }
  }
  if (nearest == nullptr) return;
  last_touch_team_ = nearest->id.team;
  last_touch_bot_ = nearest->id.id;
  max_height_since_touch_[TeamIndex(nearest->id.team)] = 0;
}

std::vector<FieldRequest> RefereeEngine::Update(const FieldView& v) {
  std::vector<FieldRequest> out;
  if (!started_) {
    started_ = true;
    t_last_ns_ = v.t_ns;
    t_command_ns_ = t_stop_ns_ = v.t_ns;
    msg_.set_command_timestamp(Micros(v.t_ns));
  }
  const std::int64_t dt = std::max<std::int64_t>(0, v.t_ns - t_last_ns_);
  t_last_ns_ = v.t_ns;
  last_ball_ = v.ball;
  TrackTouches(v);
  if (autoref()) {
    Autoref(v, out);
    return out;
  }
  msg_.set_packet_timestamp(Micros(v.t_ns));
  CountDown(dt);
  if (finished()) return out;

  // A half ends on time (the game controller leaves this to a human; nobody else is here).
  const Referee::Stage stage = msg_.stage();
  if ((stage == Referee::NORMAL_FIRST_HALF || stage == Referee::NORMAL_SECOND_HALF) && msg_.stage_time_left() <= 0) {
    EndOfHalf(v.t_ns);
    return out;
  }
  if (stage == Referee::NORMAL_HALF_TIME) {
    if (msg_.stage_time_left() <= 0) {
      SetStage(Referee::NORMAL_SECOND_HALF_PRE, v.t_ns);
      // The second half's kick-off goes to the team that did not kick off the first.
      Stop(v.t_ns, Kickoff(Other(config_.first_kickoff)), P2{0, 0});
    }
    return out;
  }

  const Referee::Command c = msg_.command();
  if (c == Referee::HALT) {
    if (Seconds(v.t_ns - t_command_ns_) >= config_.resume_after_halt) Stop(v.t_ns, std::nullopt, std::nullopt);
    return out;
  }
  if (IsRunning(c)) {
    WatchKickTaken(v);
    WatchRunning(v, out);
  } else if (IsPlacement(c)) {
    WatchPlacement(v, out);
  } else if (c == Referee::STOP || IsKickoff(c)) {
    WatchStop(v, out);
  }
  WatchFouls(v, out);
  WatchCards(v, out);
  return out;
}

void RefereeEngine::EndOfHalf(std::int64_t t_ns) {
  in_play_ = false;
  Issue(Referee::HALT, t_ns);
  if (msg_.stage() == Referee::NORMAL_FIRST_HALF) {
    SetStage(Referee::NORMAL_HALF_TIME, t_ns);
  } else {
    SetStage(Referee::POST_GAME, t_ns);
  }
  msg_.clear_next_command();
  msg_.clear_designated_position();
}

void RefereeEngine::WatchKickTaken(const FieldView& v) {
  if (in_play_) return;
  // After a kick-off or free kick the ball is in play once it moved 0.05 m, or when time is up.
  if (Dist(v.ball, kick_point_) >= kKickMoved || msg_.current_action_time_remaining() < 0) {
    in_play_ = true;
    progress_point_ = v.ball;
    t_progress_ns_ = v.t_ns;
  }
}

void RefereeEngine::WatchRunning(const FieldView& v, std::vector<FieldRequest>& out) {
  (void)out;
  if (autoref() && reported_) return;  // reported once; the game controller decides
  if (const auto exit = rules_.Left(v.ball, v.ball_radius, v.ball_z)) {
    const Team toucher = last_touch_team_;
    GameEvent e;
    if (exit->kind == Exit::kGoal) {
      // The ball entered the goal at x sign goal_side: the team defending it concedes.
      const Team conceding = GoalSideOf(Team::kBlue) == exit->goal_side ? Team::kBlue : Team::kYellow;
      const Team scoring = Other(conceding);
      int on_field = 0;
      for (const RobotView& r : v.robots) on_field += r.present && r.id.team == scoring;
      const bool too_high = max_height_since_touch_[TeamIndex(scoring)] > kMaxGoalHeight;
      const bool too_many = on_field > static_cast<int>(Info(scoring).max_allowed_bots());
      GameEvent::Goal* g = nullptr;
      if (autoref()) {
        // An autoreferee reports a possible goal; the game controller judges and scores it.
        e.set_type(GameEvent::POSSIBLE_GOAL);
        g = e.mutable_possible_goal();
      } else if (!too_high && !too_many) {
        e.set_type(GameEvent::GOAL);
        g = e.mutable_goal();
      } else {
        e.set_type(GameEvent::INVALID_GOAL);
        g = e.mutable_invalid_goal();
        g->set_message(too_high ? "the ball went higher than 0.15 m after the scoring team's last touch"
                                : "the scoring team had too many robots on the field");
      }
      g->set_by_team(WireTeam(scoring));
      g->set_kicking_team(WireTeam(toucher));
      if (last_touch_bot_ >= 0) g->set_kicking_bot(static_cast<unsigned>(last_touch_bot_));
      Set(g->mutable_location(), exit->location);
      g->set_max_ball_height(static_cast<float>(max_height_since_touch_[TeamIndex(scoring)]));
      g->set_num_robots_by_team(static_cast<unsigned>(on_field));
      if (autoref()) {
        AddEvent(e);
        reported_ = true;
        return;
      }
      AddEvent(e);
      if (e.type() == GameEvent::GOAL) {
        Info(scoring).set_score(Info(scoring).score() + 1);
        // The game controller first publishes the deprecated GOAL_x command with its own counter step.
        Issue(scoring == Team::kBlue ? Referee::GOAL_BLUE : Referee::GOAL_YELLOW, v.t_ns);
        const unsigned s = Info(scoring).score(), o = Info(conceding).score();
        if (s >= kEarlyEndGoals && s > o + 1) {
          Issue(Referee::HALT, v.t_ns);
          SetStage(Referee::POST_GAME, v.t_ns);
          return;
        }
        // After a goal the team that conceded kicks off [R 5.3.2].
        Stop(v.t_ns, Kickoff(conceding), P2{0, 0});
        return;
      }
      // An invalid goal restarts as a goal-line crossing.
    }
    const BallExit as_line = exit->kind == Exit::kGoal ? BallExit{Exit::kGoalLine, exit->location, exit->goal_side} : *exit;
    if (e.type() != GameEvent::INVALID_GOAL) {
      GameEvent::BallLeftField* b = nullptr;
      if (as_line.kind == Exit::kTouchLine) {
        e.set_type(GameEvent::BALL_LEFT_FIELD_TOUCH_LINE);
        b = e.mutable_ball_left_field_touch_line();
      } else {
        e.set_type(GameEvent::BALL_LEFT_FIELD_GOAL_LINE);
        b = e.mutable_ball_left_field_goal_line();
      }
      b->set_by_team(WireTeam(toucher));
      if (last_touch_bot_ >= 0) b->set_by_bot(static_cast<unsigned>(last_touch_bot_));
      Set(b->mutable_location(), as_line.location);
      AddEvent(e);
    }
    if (autoref()) {
      reported_ = true;
      return;
    }
    // The team that did not touch it last takes the free kick (§3.3).
    const Team kicker = Other(toucher);
    const bool corner = as_line.kind == Exit::kGoalLine && GoalSideOf(toucher) == as_line.goal_side;
    Stop(v.t_ns, Direct(kicker), rules_.PlacementAfter(as_line, corner));
    return;
  }
  // Too many robots: a team with more robots on the field than it may have (the simulator takes
  // robots off for cards itself: this is a world or a team that put too many on). The game
  // controller stops and restarts neutrally; raised at most once per 10 s per team.
  if (!autoref()) {
    for (Team t : {Team::kBlue, Team::kYellow}) {
      int on_field = 0;
      for (const RobotView& r : v.robots) on_field += r.present && r.id.team == t;
      const int allowed = static_cast<int>(Info(t).max_allowed_bots());
      const int ti = TeamIndex(t);
      if (on_field <= allowed || v.t_ns < t_too_many_ns_[ti]) continue;
      t_too_many_ns_[ti] = v.t_ns + 10 * kNs;
      GameEvent e;
      e.set_type(GameEvent::TOO_MANY_ROBOTS);
      auto* m = e.mutable_too_many_robots();
      m->set_by_team(WireTeam(t));
      m->set_num_robots_allowed(allowed);
      m->set_num_robots_on_field(on_field);
      Set(m->mutable_ball_location(), v.ball);
      AddEvent(e);
      Stop(v.t_ns, Referee::FORCE_START, rules_.ValidFreeKickPoint(v.ball));
      return;
    }
  }
  // No progress: the ball moved less than 0.1 m for 5 s (A) / 10 s (B) while both may play (the
  // game controller detects it itself).
  if (!in_play_ || autoref()) return;
  if (Dist(v.ball, progress_point_) >= kNoProgressDistance) {
    progress_point_ = v.ball;
    t_progress_ns_ = v.t_ns;
    return;
  }
  const double limit = config_.division == Division::kA ? 5.0 : 10.0;
  const double stalled = Seconds(v.t_ns - t_progress_ns_);
  if (stalled > limit) {
    GameEvent e;
    e.set_type(GameEvent::NO_PROGRESS_IN_GAME);
    Set(e.mutable_no_progress_in_game()->mutable_location(), v.ball);
    e.mutable_no_progress_in_game()->set_time(static_cast<float>(stalled));
    AddEvent(e);
    Stop(v.t_ns, Referee::FORCE_START, rules_.ValidFreeKickPoint(v.ball));
  }
}

P2 RefereeEngine::Designated() const {
  return {msg_.designated_position().x() / 1000.0, msg_.designated_position().y() / 1000.0};  // mm on the wire
}

bool RefereeEngine::PlacementNeeded(const FieldView& v, bool exact) const {
  if (!msg_.has_designated_position()) return false;
  const P2 target = Designated();
  if (exact) return Dist(v.ball, target) > config_.placement_tolerance;
  return Dist(v.ball, target) > kPlacementNeeded || !rules_.InsideField(v.ball) ||
         rules_.DistanceToDefenseArea(v.ball) < kDefenseAreaClearance || Speed(v.ball_vel) > kSteadySpeed;
}

void RefereeEngine::RefereePlaces(P2 where, std::int64_t t_ns, std::vector<FieldRequest>& out) {
  FieldRequest r;
  r.kind = FieldRequest::Kind::kPlaceBall;
  r.position = where;
  out.push_back(r);
  t_referee_placed_ns_ = t_ns;
}

bool RefereeEngine::Ready(const FieldView& v, Referee::Command next) const {
  if (Speed(v.ball_vel) > kSteadySpeed) return false;
  const bool kickoff = next == Referee::NORMAL_START;
  const Team attacker = next_team_;
  for (const RobotView& r : v.robots) {
    if (!r.present) continue;
    if (kickoff) {
      // Kick-off: every robot in its own half (one robot radius of tolerance); only the
      // attackers may be in the centre circle.
      const int own_side = GoalSideOf(r.id.team);
      if (own_side * r.pos.x < -r.radius) return false;
      if (r.id.team != attacker && std::hypot(r.pos.x, r.pos.y) < 0.5) return false;
    } else if (IsDirect(next) && r.id.team == attacker) {
      continue;  // before a free kick only the defenders keep away
    } else if (Dist(r.pos, v.ball) < kReadyDistance) {
      return false;
    }
  }
  return true;
}

void RefereeEngine::WatchStop(const FieldView& v, std::vector<FieldRequest>& out) {
  const double since_stop = Seconds(v.t_ns - t_stop_ns_);
  const Referee::Command c = msg_.command();
  if (IsKickoff(c)) {
    // Prepared: the kick-off starts once everyone is in place (or waited long enough).
    if (Seconds(v.t_ns - t_command_ns_) < config_.preparation_time) return;
    if (PlacementNeeded(v, true) && (t_referee_placed_ns_ < 0 || Seconds(v.t_ns - t_referee_placed_ns_) > 1.0)) {
      RefereePlaces({0, 0}, v.t_ns, out);
      return;
    }
    if (!Ready(v, Referee::NORMAL_START) && Seconds(v.t_ns - t_command_ns_) < config_.ready_timeout) return;
    kick_point_ = v.ball;
    if (IsPre(msg_.stage())) {
      SetStage(msg_.stage() == Referee::NORMAL_FIRST_HALF_PRE ? Referee::NORMAL_FIRST_HALF : Referee::NORMAL_SECOND_HALF,
               v.t_ns);
    }
    last_touch_team_ = TeamOf(c);
    last_touch_bot_ = -1;
    Issue(Referee::NORMAL_START, v.t_ns);
    return;
  }
  if (!msg_.has_next_command()) return;  // a plain STOP: the next decision comes from elsewhere
  const Referee::Command next = msg_.next_command();
  const bool referee_places = IsKickoff(next) || next == Referee::FORCE_START || next == Referee::PREPARE_PENALTY_BLUE ||
                              next == Referee::PREPARE_PENALTY_YELLOW;
  if (PlacementNeeded(v, IsKickoff(next))) {
    const P2 target = Designated();
    if (referee_places || placement_attempts_ >= 2 || !CanPlace(next_team_)) {
      // Kick-offs, penalties, force starts, and free kicks no team may place: the referee
      // (the simulator) places the ball, once the robots had time to stop.
      if (since_stop >= config_.resume_after_halt &&
          (t_referee_placed_ns_ < 0 || Seconds(v.t_ns - t_referee_placed_ns_) > 1.0)) {
        RefereePlaces(target, v.t_ns, out);
      }
      return;
    }
    if (since_stop < config_.preparation_time) return;
    placing_team_ = next_team_;
    ++placement_attempts_;
    t_placement_ns_ = v.t_ns;
    placement_best_ = Dist(v.ball, target);
    t_placement_progress_ns_ = v.t_ns;
    Issue(Placement(placing_team_), v.t_ns);
    return;
  }
  // Resume: 2 s after the stoppage (or the placement command), once ready.
  const std::int64_t since = placement_attempts_ > 0 ? std::max(t_placement_ns_, t_stop_ns_) : t_stop_ns_;
  if (Seconds(v.t_ns - since) < config_.preparation_time) return;
  if (placement_attempts_ > 0 && Seconds(v.t_ns - t_placement_ns_) < config_.preparation_time) return;
  if (!Ready(v, next) && Seconds(v.t_ns - t_stop_ns_) < config_.ready_timeout) return;
  kick_point_ = v.ball;
  last_touch_team_ = next_team_;
  last_touch_bot_ = -1;
  if (IsKickoff(next)) {
    msg_.clear_next_command();
    msg_.set_next_command(Referee::NORMAL_START);
    Issue(next, v.t_ns);  // designated position (the centre) stays during the preparation
    return;
  }
  Issue(next, v.t_ns);
}

void RefereeEngine::WatchPlacement(const FieldView& v, std::vector<FieldRequest>& out) {
  const P2 target = Designated();
  const double d = Dist(v.ball, target);
  if (d < placement_best_ - 0.1) {
    placement_best_ = d;
    t_placement_progress_ns_ = v.t_ns;
  }
  double nearest = 1e9;
  for (const RobotView& r : v.robots) {
    if (r.present) nearest = std::min(nearest, Dist(r.pos, v.ball) - r.radius - v.ball_radius);
  }
  const double clearance = msg_.next_command() == Referee::FORCE_START ? kStopDistance : kPlacementRobotClearance;
  if (autoref() && reported_) return;
  if (d <= config_.placement_tolerance && Speed(v.ball_vel) < kSteadySpeed && nearest >= clearance) {
    GameEvent e;
    e.set_type(GameEvent::PLACEMENT_SUCCEEDED);
    auto* s = e.mutable_placement_succeeded();
    s->set_by_team(WireTeam(placing_team_));
    s->set_time_taken(static_cast<float>(Seconds(v.t_ns - t_placement_ns_)));
    s->set_precision(static_cast<float>(d));
    AddEvent(e);
    if (autoref()) {
      reported_ = true;  // the game controller stops and counts
      return;
    }
    auto& info = Info(placing_team_);
    info.set_ball_placement_failures(info.ball_placement_failures() > 0 ? info.ball_placement_failures() - 1 : 0);
    in_play_ = false;
    Issue(Referee::STOP, v.t_ns);
    t_stop_ns_ = t_placement_ns_;  // resuming counts from the placement command
    return;
  }
  if (!autoref() && msg_.current_action_time_remaining() < 0) {
    GameEvent e;
    e.set_type(GameEvent::PLACEMENT_FAILED);
    e.mutable_placement_failed()->set_by_team(WireTeam(placing_team_));
    e.mutable_placement_failed()->set_remaining_distance(static_cast<float>(d));
    AddEvent(e);
    auto& info = Info(placing_team_);
    info.set_ball_placement_failures(info.ball_placement_failures() + 1);
    if (static_cast<int>(info.ball_placement_failures()) >= config_.max_placement_failures) {
      info.set_ball_placement_failures_reached(true);
    }
    if (placement_attempts_ == 1 && IsDirect(msg_.next_command())) {
      // The other team gets the free kick and places.
      msg_.set_next_command(Direct(Other(placing_team_)));
      next_team_ = Other(placing_team_);
    } else {
      msg_.set_next_command(original_next_);  // both failed: the referee places, the original command follows
      next_team_ = TeamOf(original_next_);
      placement_attempts_ = 2;
    }
    Issue(Referee::STOP, v.t_ns);
    return;
  }
  // A team that does not place: the simulator does, as the field's referee would.
  if (Seconds(v.t_ns - t_placement_progress_ns_) >= config_.referee_places_after) {
    RefereePlaces(target, v.t_ns, out);
    if (autoref()) {
      t_placement_progress_ns_ = v.t_ns;  // the placed ball is then reported as placed
      return;
    }
    placement_attempts_ = 2;  // placed by the referee: nobody places again in this stoppage
    Issue(Referee::STOP, v.t_ns);
    t_stop_ns_ = t_placement_ns_;
  }
}

void RefereeEngine::Foul(Team team, GameEvent event, std::vector<FieldRequest>& out, const FieldView& v) {
  AddEvent(event);
  if (autoref()) return;  // the game controller counts fouls and gives cards
  auto& info = Info(team);
  info.set_foul_counter(info.foul_counter() + 1);
  if (config_.fouls_per_card > 0 && info.foul_counter() % static_cast<unsigned>(config_.fouls_per_card) == 0) {
    GameEvent card;
    card.set_type(GameEvent::MULTIPLE_FOULS);
    card.mutable_multiple_fouls()->set_by_team(WireTeam(team));
    AddEvent(card);
    info.set_yellow_cards(info.yellow_cards() + 1);
    info.add_yellow_card_times(static_cast<std::uint32_t>(config_.yellow_card_time * 1e6));
  }
  WatchCards(v, out);
}

void RefereeEngine::WatchFouls(const FieldView& v, std::vector<FieldRequest>& out) {
  const Referee::Command c = msg_.command();
  // Too fast in STOP: 1.5 m/s after a 2 s grace, once per robot per stoppage (not while placing).
  if (c == Referee::STOP && Seconds(v.t_ns - t_stop_ns_) > kGraceTime) {
    for (const RobotView& r : v.robots) {
      if (!r.present || Speed(r.vel) <= kStopSpeed) continue;
      if (std::find(stop_speed_fouled_.begin(), stop_speed_fouled_.end(), r.id) != stop_speed_fouled_.end()) continue;
      stop_speed_fouled_.push_back(r.id);
      GameEvent e;
      e.set_type(GameEvent::BOT_TOO_FAST_IN_STOP);
      auto* f = e.mutable_bot_too_fast_in_stop();
      f->set_by_team(WireTeam(r.id.team));
      f->set_by_bot(static_cast<unsigned>(r.id.id));
      Set(f->mutable_location(), r.pos);
      f->set_speed(static_cast<float>(Speed(r.vel)));
      Foul(r.id.team, e, out, v);
    }
  }
  // Defenders keep 0.5 m from the ball at the opponent's free kick until it is in play; the kick
  // timer starts again when they do not (2 s grace per team).
  if (IsDirect(c) && !in_play_) {
    const Team defender = Other(TeamOf(c));
    const int di = TeamIndex(defender);
    if (Seconds(v.t_ns - t_command_ns_) < kGraceTime || v.t_ns < t_defender_grace_ns_[di]) return;
    for (const RobotView& r : v.robots) {
      if (!r.present || r.id.team != defender) continue;
      const double d = Dist(r.pos, v.ball) - r.radius;
      if (d >= kStopDistance) continue;
      GameEvent e;
      e.set_type(GameEvent::DEFENDER_TOO_CLOSE_TO_KICK_POINT);
      auto* f = e.mutable_defender_too_close_to_kick_point();
      f->set_by_team(WireTeam(defender));
      f->set_by_bot(static_cast<unsigned>(r.id.id));
      Set(f->mutable_location(), r.pos);
      f->set_distance(static_cast<float>(d));
      t_defender_grace_ns_[di] = v.t_ns + static_cast<std::int64_t>(kGraceTime * kNs);
      const bool a = config_.division == Division::kA;
      msg_.set_current_action_time_remaining(static_cast<std::int64_t>((a ? 5.0 : 10.0) * 1e6));
      Foul(defender, e, out, v);
      break;
    }
  }
}

void RefereeEngine::WatchCards(const FieldView& v, std::vector<FieldRequest>& out) {
  const unsigned limit = config_.division == Division::kA ? 11 : 6;
  for (Team t : {Team::kBlue, Team::kYellow}) {
    auto& info = Info(t);
    // Expired cards go; the robot limit follows the cards still running.
    auto* times = info.mutable_yellow_card_times();
    std::vector<std::uint32_t> active;
    for (auto left : *times) {
      if (left > 0) active.push_back(left);
    }
    std::sort(active.begin(), active.end());
    unsigned allowed = info.max_allowed_bots();  // the game controller's, when following one
    if (!autoref()) {
      times->Clear();
      for (auto left : active) times->Add(left);
      allowed = limit - std::min<unsigned>(limit, static_cast<unsigned>(active.size()) + info.red_cards());
      info.set_max_allowed_bots(allowed);
    }
    // The simulator takes a robot off for each card (the highest id that is not the keeper), as
    // the team would within its 10 s, and puts it back where the halfway line meets the touch
    // line when the card is over.
    auto& off = off_for_card_[TeamIndex(t)];
    int present = 0;  // on the field and not already sent off (a take-off applies a step later)
    for (const RobotView& r : v.robots) {
      present += r.present && r.id.team == t && std::find(off.begin(), off.end(), r.id) == off.end();
    }
    // Only for cards: a team that simply has too many robots is the TOO_MANY_ROBOTS event's.
    const std::size_t cards = active.size() + info.red_cards();
    if (present > static_cast<int>(allowed) && off.size() < cards) {
      const RobotView* pick = nullptr;
      for (const RobotView& r : v.robots) {
        if (!r.present || r.id.team != t || r.id.id == static_cast<int>(info.goalkeeper())) continue;
        if (std::find(off.begin(), off.end(), r.id) != off.end()) continue;
        if (pick == nullptr || r.id.id > pick->id.id) pick = &r;
      }
      if (pick != nullptr) {
        FieldRequest req;
        req.kind = FieldRequest::Kind::kTakeOff;
        req.robot = pick->id;
        out.push_back(req);
        off.push_back(pick->id);
      }
    } else if (!off.empty() && present + 1 <= static_cast<int>(allowed) && IsRunning(msg_.command())) {
      FieldRequest req;
      req.kind = FieldRequest::Kind::kPutOn;
      req.robot = off.front();
      const int side = GoalSideOf(t);
      req.position = {side * 0.3, -rules_.half_width() + 0.1};
      out.push_back(req);
      off.erase(off.begin());
    }
  }
}

void RefereeEngine::Autoref(const FieldView& v, std::vector<FieldRequest>& out) {
  if (!followed_) return;  // nothing heard from the game controller yet
  const Referee::Stage stage = msg_.stage();
  const Referee::Command c = msg_.command();
  // The stage does not advance by itself in the game controller (§2.1): ask for the next one.
  if (!stage_requested_) {
    std::optional<Referee::Stage> next;
    if ((stage == Referee::NORMAL_FIRST_HALF || stage == Referee::NORMAL_SECOND_HALF) && msg_.stage_time_left() <= 0) {
      next = stage == Referee::NORMAL_FIRST_HALF ? Referee::NORMAL_HALF_TIME : Referee::POST_GAME;
    } else if (stage == Referee::NORMAL_HALF_TIME && msg_.stage_time_left() <= 0) {
      next = Referee::NORMAL_SECOND_HALF_PRE;
    }
    if (next) {
      ControlRequest r;
      r.stage = next;
      control_out_.push_back(r);
      stage_requested_ = true;
      return;
    }
  }
  if (stage == Referee::POST_GAME) return;
  const bool next_is_kickoff = msg_.has_next_command() &&
                               (IsKickoff(msg_.next_command()) || msg_.next_command() == Referee::PREPARE_PENALTY_BLUE ||
                                msg_.next_command() == Referee::PREPARE_PENALTY_YELLOW);
  // The referee's hands: the ball to the centre (or the mark) for kick-offs and penalties.
  if ((c == Referee::STOP || c == Referee::HALT || IsKickoff(c)) && msg_.has_designated_position() &&
      (next_is_kickoff || IsKickoff(c)) && PlacementNeeded(v, true) &&
      Seconds(v.t_ns - t_command_ns_) >= config_.resume_after_halt &&
      (t_referee_placed_ns_ < 0 || Seconds(v.t_ns - t_referee_placed_ns_) > 1.0)) {
    const P2 target = Designated();
    RefereePlaces(target, v.t_ns, out);
  }
  if (c == Referee::HALT && !control_requested_ && !IsBreak(stage) &&
      Seconds(v.t_ns - t_command_ns_) >= config_.resume_after_halt) {
    // HALT ends with STOP (auto-continue never leaves HALT); a goal the game controller halted
    // for is accepted first, as an operator would.
    bool possible = false, decided = false;
    Team scorer = Team::kYellow;
    for (const GameEvent& e : msg_.game_events()) {
      if (e.type() == GameEvent::POSSIBLE_GOAL) {
        possible = true;
        scorer = e.possible_goal().by_team() == ::BLUE ? Team::kBlue : Team::kYellow;
      }
      decided = decided || e.type() == GameEvent::GOAL || e.type() == GameEvent::INVALID_GOAL;
    }
    ControlRequest r;
    if (possible && !decided) {
      r.accept_goal = true;
      r.for_team = scorer;
    } else {
      r.command = Referee::STOP;
    }
    control_out_.push_back(r);
    control_requested_ = true;
  }
  if (IsRunning(c)) {
    WatchKickTaken(v);
    WatchRunning(v, out);
  } else if (IsPlacement(c)) {
    WatchPlacement(v, out);
  }
  WatchFouls(v, out);
  WatchCards(v, out);
}

}  // namespace ubersim::match
