// SPDX-License-Identifier: Apache-2.0
// Field markings, named and placed as SSL-Vision does.
#include <numbers>
#include <string>

#include <gtest/gtest.h>

#include "ubersim/kernel/model.hpp"

namespace {

using ubersim::FieldArc;
using ubersim::FieldGeometry;
using ubersim::FieldLine;

FieldGeometry DivB() {
  FieldGeometry g;
  g.field_length = 9.0;
  g.field_width = 6.0;
  g.penalty_area_depth = 1.0;
  g.penalty_area_width = 2.0;
  g.center_circle_radius = 0.5;
  g.line_thickness = 0.01;
  return g;
}

const FieldLine& Line(const FieldGeometry& g, const std::string& name) {
  for (const auto& l : g.lines) {
    if (l.name == name) return l;
  }
  throw std::runtime_error("no line " + name);
}

void ExpectLine(const FieldGeometry& g, const std::string& name, double x1, double y1, double x2, double y2) {
  const FieldLine& l = Line(g, name);
  EXPECT_DOUBLE_EQ(l.x1, x1) << name;
  EXPECT_DOUBLE_EQ(l.y1, y1) << name;
  EXPECT_DOUBLE_EQ(l.x2, x2) << name;
  EXPECT_DOUBLE_EQ(l.y2, y2) << name;
  EXPECT_DOUBLE_EQ(l.thickness, 0.01) << name;
}

TEST(FieldMarkings, DivBLinesAreWhereSslVisionPutsThem) {
  FieldGeometry g = DivB();
  ubersim::kernel::BuildFieldMarkings(g);
  ASSERT_EQ(g.lines.size(), 12u);
  ExpectLine(g, "TopTouchLine", -4.5, 3.0, 4.5, 3.0);
  ExpectLine(g, "BottomTouchLine", -4.5, -3.0, 4.5, -3.0);
  ExpectLine(g, "LeftGoalLine", -4.5, -3.0, -4.5, 3.0);
  ExpectLine(g, "RightGoalLine", 4.5, -3.0, 4.5, 3.0);
  ExpectLine(g, "HalfwayLine", 0.0, -3.0, 0.0, 3.0);
  ExpectLine(g, "CenterLine", -4.5, 0.0, 4.5, 0.0);
  ExpectLine(g, "LeftPenaltyStretch", -3.5, -1.0, -3.5, 1.0);
  ExpectLine(g, "RightPenaltyStretch", 3.5, -1.0, 3.5, 1.0);
  ExpectLine(g, "LeftFieldLeftPenaltyStretch", -4.5, -1.0, -3.5, -1.0);
  ExpectLine(g, "LeftFieldRightPenaltyStretch", -4.5, 1.0, -3.5, 1.0);
  ExpectLine(g, "RightFieldRightPenaltyStretch", 4.5, -1.0, 3.5, -1.0);
  ExpectLine(g, "RightFieldLeftPenaltyStretch", 4.5, 1.0, 3.5, 1.0);
  ASSERT_EQ(g.arcs.size(), 1u);
  const FieldArc& c = g.arcs[0];
  EXPECT_EQ(c.name, "CenterCircle");
  EXPECT_DOUBLE_EQ(c.cx, 0.0);
  EXPECT_DOUBLE_EQ(c.cy, 0.0);
  EXPECT_DOUBLE_EQ(c.radius, 0.5);
  EXPECT_DOUBLE_EQ(c.a1, 0.0);
  EXPECT_DOUBLE_EQ(c.a2, 2.0 * std::numbers::pi);
  EXPECT_DOUBLE_EQ(c.thickness, 0.01);
}

TEST(FieldMarkings, RebuildingReplacesTheMarkings) {
  FieldGeometry g = DivB();
  ubersim::kernel::BuildFieldMarkings(g);
  g.field_length = 12.0;
  g.penalty_area_depth = 1.8;
  g.penalty_area_width = 3.6;
  ubersim::kernel::BuildFieldMarkings(g);
  EXPECT_EQ(g.lines.size(), 12u);
  EXPECT_EQ(g.arcs.size(), 1u);
  ExpectLine(g, "TopTouchLine", -6.0, 3.0, 6.0, 3.0);
  ExpectLine(g, "RightPenaltyStretch", 4.2, -1.8, 4.2, 1.8);
}

TEST(FieldMarkings, NoDefenseAreaOrCircleGivesOnlyTheOuterLines) {
  FieldGeometry g = DivB();
  g.penalty_area_depth = 0.0;
  g.center_circle_radius = 0.0;
  ubersim::kernel::BuildFieldMarkings(g);
  EXPECT_EQ(g.lines.size(), 6u);
  EXPECT_TRUE(g.arcs.empty());
}

}  // namespace
