// SPDX-License-Identifier: Apache-2.0
// The built-in referee: one rule engine that watches the field (FieldView) and both detects what
// the league's autoreferees detect and decides what the game controller decides, publishing the
// league's Referee message. Its clock is the simulation's. What it asks of the field (the ball to
// the centre for a kick-off, a robot off for a yellow card) comes back as FieldRequests, which the
// simulator carries out as a human referee would. Scope and numbers: docs/match.md.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <ubersim/world_state.hpp>

#include "field_rules.hpp"
#include "field_view.hpp"
#include "ssl_gc_referee_message.pb.h"

namespace ubersim::match {

/// The division the match is played in (robot limit and time limits).
enum class Division { kA, kB };

/// How the built-in referee runs a match; the defaults are the game controller's (§3.8) except
/// where a headless match has no human to wait for.
struct RefereeConfig {
  Division division = Division::kA;        ///< Div A: 11 robots, 5 s free kicks; Div B: 6, 10 s
  double half_duration = 300.0;            ///< playing time per half, s
  double half_time_break = 300.0;          ///< s
  double kickoff_time = 10.0;              ///< after NORMAL_START the ball is in play at the latest, s
  double placement_time = 30.0;            ///< a team's time to place the ball, s
  double placement_tolerance = 0.15;       ///< ball within this of the target counts as placed, m
  double preparation_time = 2.0;           ///< STOP (or a placement command) to the next command, s
  double resume_after_halt = 1.0;          ///< HALT to STOP when nobody else ends it, s
  double ready_timeout = 10.0;             ///< continue even though robots keep too close, s
  double referee_places_after = 3.0;       ///< the simulator places the ball when a placement makes no progress for this long, s
  double yellow_card_time = 120.0;         ///< s of playing time
  int fouls_per_card = 3;                  ///< every third foul is a yellow card
  int max_placement_failures = 5;          ///< then the team may not place for the rest of the half
  Team first_kickoff = Team::kYellow;      ///< kicks off the first half
  bool blue_on_positive_half = false;      ///< blue defends the goal at +x
  std::string yellow_name = "Yellow";      ///< team names
  std::string blue_name = "Blue";          ///< team names
  int yellow_keeper = 0;                   ///< goalkeeper ids
  int blue_keeper = 0;                     ///< goalkeeper ids
  bool yellow_can_place = true;            ///< the team places the ball itself (else the simulator does)
  bool blue_can_place = true;              ///< the team places the ball itself (else the simulator does)
  MatchType match_type = FRIENDLY;         ///< published match type
  std::string source_identifier = "ubersim-builtin-referee";  ///< published source_identifier
};

/// What the referee asks the field to do (the simulator does it as a human referee would).
struct FieldRequest {
  enum class Kind { kPlaceBall, kTakeOff, kPutOn } kind = Kind::kPlaceBall;  ///< what
  P2 position;     ///< kPlaceBall, kPutOn: where, m
  RobotId robot;   ///< kTakeOff, kPutOn: which robot
};

/// What the engine plays: the whole game controller (built-in referee) or the autoreferee of a
/// real game controller, whose Referee messages it follows (Follow) and to which it reports.
enum class RefereeMode { kGameController, kAutoref };

/// What an autoreferee asks of the game controller besides its game events (the field's side of a
/// match: resuming after HALT, advancing the stage, accepting a goal).
struct ControlRequest {
  std::optional<Referee::Command> command;  ///< a new command (STOP)
  std::optional<Referee::Stage> stage;      ///< the next stage
  bool accept_goal = false;                 ///< accept the possible goal the game controller halted for
  Team for_team = Team::kYellow;            ///< accept_goal: the scoring team
};

/// The referee's rule engine: detects what the league's autoreferees detect, and (as the built-in
/// referee) decides what the game controller decides.
class RefereeEngine {
 public:
  /// A match on `field` under `config`; `unix_offset_ns` turns simulated time into the Unix time
  /// stamps the messages carry (0: plain simulated time).
  RefereeEngine(const RefereeConfig& config, const FieldGeometry& field, std::int64_t unix_offset_ns = 0,
                RefereeMode mode = RefereeMode::kGameController);

  /// kAutoref: takes the game controller's latest message as the state (its command, stage,
  /// placement position and teams).
  void Follow(const Referee& game_controller);
  /// kAutoref: the game events detected since the last call, for the game controller.
  std::vector<GameEvent> TakeGameEvents();
  /// kAutoref: what the game controller is asked to do since the last call.
  std::vector<ControlRequest> TakeControlRequests();

  /// Watches the field at `view.t_ns` (never earlier than the last call) and returns what the
  /// field must do now.
  std::vector<FieldRequest> Update(const FieldView& view);

  /// The state now, as the game controller publishes it.
  const Referee& message() const { return msg_; }
  /// Every message that carried a new command since the last call, oldest first (the game
  /// controller publishes each command change at once, besides its 40 Hz state).
  std::vector<Referee> TakeCommandMessages();
  /// Every game event so far, oldest first.
  const std::vector<GameEvent>& history() const { return history_; }
  /// The simulated time of each event of history(), ns.
  const std::vector<std::int64_t>& history_times() const { return history_times_; }
  /// The match is over (POST_GAME).
  bool finished() const { return msg_.stage() == Referee::POST_GAME; }

 private:

  void Issue(Referee::Command command, std::int64_t t_ns);
  void OnCommand(Referee::Command command, std::int64_t t_ns);
  void Autoref(const FieldView& v, std::vector<FieldRequest>& out);
  bool autoref() const { return mode_ == RefereeMode::kAutoref; }
  void Stop(std::int64_t t_ns, std::optional<Referee::Command> next, std::optional<P2> designated);
  void AddEvent(GameEvent event);
  void SetStage(Referee::Stage stage, std::int64_t t_ns);
  void CountDown(std::int64_t dt_ns);
  void TrackTouches(const FieldView& v);
  void WatchRunning(const FieldView& v, std::vector<FieldRequest>& out);
  void WatchStop(const FieldView& v, std::vector<FieldRequest>& out);
  void WatchPlacement(const FieldView& v, std::vector<FieldRequest>& out);
  void WatchKickTaken(const FieldView& v);
  void WatchFouls(const FieldView& v, std::vector<FieldRequest>& out);
  void WatchCards(const FieldView& v, std::vector<FieldRequest>& out);
  void Foul(Team team, GameEvent event, std::vector<FieldRequest>& out, const FieldView& v);
  void EndOfHalf(std::int64_t t_ns);
  bool Ready(const FieldView& v, Referee::Command next) const;
  bool PlacementNeeded(const FieldView& v, bool exact) const;
  P2 Designated() const;  // the designated position, m
  void RefereePlaces(P2 where, std::int64_t t_ns, std::vector<FieldRequest>& out);
  Referee::TeamInfo& Info(Team t);
  const Referee::TeamInfo& Info(Team t) const;
  int GoalSideOf(Team defending) const;
  bool CanPlace(Team t) const;
  std::uint64_t Micros(std::int64_t t_ns) const;
  double Seconds(std::int64_t t_ns) const { return static_cast<double>(t_ns) * 1e-9; }

  RefereeConfig config_;
  RefereeMode mode_;
  FieldRules rules_;
  std::int64_t unix_offset_ns_;
  Referee msg_;
  std::vector<Referee> command_messages_;
  std::vector<GameEvent> history_;
  std::vector<std::int64_t> history_times_;
  bool started_ = false;
  std::int64_t t_last_ns_ = 0;
  std::int64_t t_command_ns_ = 0;      // when the current command was issued
  std::int64_t t_stop_ns_ = 0;          // when the current stoppage began
  // Running play.
  bool in_play_ = false;                // the ball is in play (after a kick-off / free kick: once kicked)
  P2 kick_point_;                       // where the kick-off or free kick is taken from
  P2 progress_point_;                   // no progress: where the ball was last seen moving from
  std::int64_t t_progress_ns_ = 0;
  // Touches.
  Team last_touch_team_ = Team::kYellow;
  int last_touch_bot_ = -1;
  double max_height_since_touch_[2] = {0, 0};
  // Stoppage and placement.
  Team next_team_ = Team::kYellow;        // the team of the next command (free kick, kick-off)
  Team placing_team_ = Team::kYellow;
  std::int64_t t_placement_ns_ = 0;     // when the placement command was issued
  int placement_attempts_ = 0;          // in this stoppage
  Referee::Command original_next_ = Referee::HALT;
  double placement_best_ = 1e9;         // closest the ball came to the target, m
  std::int64_t t_placement_progress_ns_ = 0;
  std::int64_t t_referee_placed_ns_ = -1;  // the simulator placed the ball then (-1: not in this stoppage)
  // Fouls and cards.
  std::vector<RobotId> stop_speed_fouled_;  // robots already fouled for speed in this stoppage
  std::int64_t t_defender_grace_ns_[2] = {0, 0};
  std::int64_t t_too_many_ns_[2] = {0, 0};  // no TOO_MANY_ROBOTS for the team before then
  std::vector<RobotId> off_for_card_[2];  // robots taken off for a card, in order
  // Autoreferee.
  P2 last_ball_;
  Referee::Command previous_command_ = Referee::HALT;
  bool followed_ = false;
  bool reported_ = false;            // this command's situation was reported (ball out, goal, placed)
  bool control_requested_ = false;   // this command's HALT → STOP or goal acceptance was asked for
  bool stage_requested_ = false;     // this stage's end was asked for
  std::vector<GameEvent> events_out_;
  std::vector<ControlRequest> control_out_;
};

/// The league's team enum of ours.
::Team WireTeam(Team t);

}  // namespace ubersim::match
