// SPDX-License-Identifier: Apache-2.0
// Field markings as SSL-Vision names them (docs/model-files.md, reference/ssl-protocols.md §1.7).
#include <numbers>

#include "ubersim/kernel/model.hpp"

namespace ubersim::kernel {

void BuildFieldMarkings(FieldGeometry& g) {
  // Field centre at the origin, x along the length, the left goal at -x; points on line centres.
  const double lx = 0.5 * g.field_length;
  const double wy = 0.5 * g.field_width;
  const double px = lx - g.penalty_area_depth;
  const double py = 0.5 * g.penalty_area_width;
  const double t = g.line_thickness;

  g.lines.clear();
  g.arcs.clear();
  g.lines.push_back({"TopTouchLine", -lx, wy, lx, wy, t});
  g.lines.push_back({"BottomTouchLine", -lx, -wy, lx, -wy, t});
  g.lines.push_back({"LeftGoalLine", -lx, -wy, -lx, wy, t});
  g.lines.push_back({"RightGoalLine", lx, -wy, lx, wy, t});
  g.lines.push_back({"HalfwayLine", 0.0, -wy, 0.0, wy, t});
  g.lines.push_back({"CenterLine", -lx, 0.0, lx, 0.0, t});
  if (g.penalty_area_depth > 0 && g.penalty_area_width > 0) {
    g.lines.push_back({"LeftPenaltyStretch", -px, -py, -px, py, t});
    g.lines.push_back({"RightPenaltyStretch", px, -py, px, py, t});
    g.lines.push_back({"LeftFieldLeftPenaltyStretch", -lx, -py, -px, -py, t});
    g.lines.push_back({"LeftFieldRightPenaltyStretch", -lx, py, -px, py, t});
    g.lines.push_back({"RightFieldRightPenaltyStretch", lx, -py, px, -py, t});
    g.lines.push_back({"RightFieldLeftPenaltyStretch", lx, py, px, py, t});
  }
  if (g.center_circle_radius > 0) {
    g.arcs.push_back({"CenterCircle", 0.0, 0.0, g.center_circle_radius, 0.0, 2.0 * std::numbers::pi, t});
  }
}

}  // namespace ubersim::kernel
