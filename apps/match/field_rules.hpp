// SPDX-License-Identifier: Apache-2.0
// The field as the rules measure it: where the lines, goals and defense areas are, which way a
// ball left, and where the ball goes for the free kick that follows (ssl-match-protocols.md §3.3,
// the game controller's placement offsets). Field frame, m.
#pragma once

#include <optional>

#include <ubersim/world_state.hpp>

#include "field_view.hpp"

namespace ubersim::match {

/// How the ball left the field.
enum class Exit { kTouchLine, kGoalLine, kGoal };

/// Where and how the ball left the field.
struct BallExit {
  Exit kind = Exit::kTouchLine;  ///< which line
  P2 location;                   ///< where it crossed the line, m
  int goal_side = 0;             ///< +1 / -1: the goal line (x sign) for kGoalLine and kGoal
};

/// The rules' view of one field geometry.
class FieldRules {
 public:
  /// From the world's field.
  explicit FieldRules(const FieldGeometry& field);

  double half_length() const { return half_length_; }  ///< centre to goal line, m
  double half_width() const { return half_width_; }    ///< centre to touch line, m

  /// The ball has left the field (entirely over a line) at `ball` (radius r, height z): how, or
  /// nothing while it is in. A ball fully behind the goal line between the posts and under the
  /// crossbar height is a goal.
  std::optional<BallExit> Left(P2 ball, double radius, double z) const;
  /// Inside the field lines (the ball's centre).
  bool InsideField(P2 p) const;
  /// Distance from `p` to the nearer defense area (0 inside), m.
  double DistanceToDefenseArea(P2 p) const;
  /// Inside the defense area on the side `side` (+1 / -1, x sign), grown by `margin`.
  bool InDefenseArea(P2 p, int side, double margin) const;
  /// Where the free kick after `exit` is taken: `corner` when the team that touched last defends
  /// that goal line (a corner kick for the attackers), else a goal kick (§3.3).
  P2 PlacementAfter(const BallExit& exit, bool corner) const;
  /// A free-kick point: at least 0.2 m inside the lines and 1 m from both defense areas, pushed
  /// out along the nearer axis when it is not.
  P2 ValidFreeKickPoint(P2 p) const;
  /// The penalty mark in front of the goal at x sign `side`.
  P2 PenaltyMark(int side) const;

 private:
  double half_length_, half_width_, goal_half_width_, goal_height_;
  double defense_depth_, defense_half_width_, penalty_mark_distance_;
};

}  // namespace ubersim::match
