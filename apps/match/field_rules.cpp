// SPDX-License-Identifier: Apache-2.0
#include "field_rules.hpp"

#include <algorithm>
#include <cmath>

namespace ubersim::match {
namespace {

// The game controller's offsets (statemachine/placementPos.go via ssl-match-protocols.md §3.3).
constexpr double kLineDistance = 0.2;      // from touch and goal lines
constexpr double kGoalKickDistance = 1.0;  // goal kick: from the goal line
constexpr double kDefenseAreaMargin = 1.0; // free kicks stay this far from a defense area

int Sign(double v) { return v < 0 ? -1 : 1; }

}  // namespace

FieldRules::FieldRules(const FieldGeometry& f)
    : half_length_(f.field_length / 2),
      half_width_(f.field_width / 2),
      goal_half_width_(f.goal_width / 2),
      goal_height_(f.goal_height > 0 ? f.goal_height : 0.16),
      defense_depth_(f.penalty_area_depth),
      defense_half_width_(f.penalty_area_width / 2),
      penalty_mark_distance_(f.goal_center_to_penalty_mark) {}

std::optional<BallExit> FieldRules::Left(P2 b, double r, double z) const {
  // Lines belong to the field: the ball is out once it is entirely over the line.
  if (std::abs(b.x) > half_length_ + r) {
    BallExit e;
    e.goal_side = Sign(b.x);
    e.location = {e.goal_side * half_length_, std::clamp(b.y, -half_width_, half_width_)};
    const bool between_posts = std::abs(b.y) < goal_half_width_;
    e.kind = between_posts && z < goal_height_ ? Exit::kGoal : Exit::kGoalLine;
    return e;
  }
  if (std::abs(b.y) > half_width_ + r) {
    BallExit e;
    e.kind = Exit::kTouchLine;
    e.location = {std::clamp(b.x, -half_length_, half_length_), Sign(b.y) * half_width_};
    return e;
  }
  return std::nullopt;
}

bool FieldRules::InsideField(P2 p) const { return std::abs(p.x) <= half_length_ && std::abs(p.y) <= half_width_; }

bool FieldRules::InDefenseArea(P2 p, int side, double margin) const {
  const double inner = half_length_ - defense_depth_ - margin;
  return side * p.x >= inner && std::abs(p.y) <= defense_half_width_ + margin;
}

double FieldRules::DistanceToDefenseArea(P2 p) const {
  double best = 1e9;
  for (int side : {-1, 1}) {
    const double x0 = half_length_ - defense_depth_;
    const double dx = std::max(0.0, x0 - side * p.x);
    const double dy = std::max(0.0, std::abs(p.y) - defense_half_width_);
    best = std::min(best, std::hypot(dx, dy));
  }
  return best;
}

P2 FieldRules::ValidFreeKickPoint(P2 p) const {
  P2 q{std::clamp(p.x, -(half_length_ - kLineDistance), half_length_ - kLineDistance),
       std::clamp(p.y, -(half_width_ - kLineDistance), half_width_ - kLineDistance)};
  const int side = Sign(q.x);
  if (InDefenseArea(q, side, kDefenseAreaMargin)) {
    const double inner = half_length_ - defense_depth_ - kDefenseAreaMargin;
    const double out_x = side * q.x - inner;                       // way out towards the centre
    const double out_y = defense_half_width_ + kDefenseAreaMargin - std::abs(q.y);  // way out sideways
    if (out_x <= out_y) {
      q.x = side * inner;
    } else {
      q.y = Sign(q.y) * (defense_half_width_ + kDefenseAreaMargin);
    }
  }
  return q;
}

P2 FieldRules::PlacementAfter(const BallExit& e, bool corner) const {
  if (e.kind == Exit::kTouchLine) {
    return ValidFreeKickPoint({e.location.x, e.location.y});
  }
  const double from_goal_line = corner ? kLineDistance : kGoalKickDistance;
  const P2 p{e.goal_side * (half_length_ - from_goal_line), Sign(e.location.y) * (half_width_ - kLineDistance)};
  return ValidFreeKickPoint(p);
}

P2 FieldRules::PenaltyMark(int side) const { return {side * (half_length_ - penalty_mark_distance_), 0.0}; }

}  // namespace ubersim::match
