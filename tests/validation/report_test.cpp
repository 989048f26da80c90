// SPDX-License-Identifier: Apache-2.0
// The validation report: metric verdicts, the SVG plot writer, the report folder.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "ubersim/validation/report.hpp"
#include "ubersim/validation/svg_plot.hpp"

namespace ubersim::validation {
namespace {

namespace fs = std::filesystem;

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(Metric, PassIsInclusiveAndRejectsNaN) {
  EXPECT_TRUE((Metric{"a", 1.0, "", 1.0, 2.0, ""}.Pass()));
  EXPECT_TRUE((Metric{"a", 2.0, "", 1.0, 2.0, ""}.Pass()));
  EXPECT_FALSE((Metric{"a", 2.0001, "", 1.0, 2.0, ""}.Pass()));
  EXPECT_FALSE((Metric{"a", std::nan(""), "", -1e9, 1e9, ""}.Pass()));
  ScenarioResult r;
  r.id = "s";
  r.metrics = {Metric{"good", 1, "", 0, 2, ""}, Metric{"bad", 3, "", 0, 2, ""}};
  EXPECT_FALSE(r.Pass());
  EXPECT_EQ(r.Get("bad").value, 3);
  EXPECT_THROW(r.Get("missing"), std::out_of_range);
}

TEST(Svg, OnePolylinePerSeriesWithEveryFinitePoint) {
  Plot p;
  p.title = "speed <m/s> & time";
  p.x_label = "t (s)";
  p.y_label = "v (m/s)";
  p.series = {Series{"sim", {0, 1, 2, 3}, {0, 1, 4, 9}, false},
              Series{"model", {0, 1, 2}, {0, std::numeric_limits<double>::infinity(), 4}, true}};
  const std::string svg = RenderSvg(p);
  EXPECT_EQ(svg.rfind("<svg xmlns=\"http://www.w3.org/2000/svg\"", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_EQ(Count(svg, "<polyline"), 2);
  EXPECT_EQ(Count(svg, "stroke-dasharray"), 2);  // the dashed curve and its legend line
  EXPECT_NE(svg.find("speed &lt;m/s&gt; &amp; time"), std::string::npos);  // escaped
  // First series: four points; second: the infinite one is left out.
  const std::size_t first = svg.find("points=\"");
  const std::size_t second = svg.find("points=\"", first + 1);
  const std::string pts1 = svg.substr(first, svg.find('"', first + 8) - first);
  const std::string pts2 = svg.substr(second, svg.find('"', second + 8) - second);
  EXPECT_EQ(Count(pts1, ","), 4);
  EXPECT_EQ(Count(pts2, ","), 2);
}

TEST(Report, WritesTheTableAndEveryPlot) {
  const fs::path dir = fs::temp_directory_path() / ("ubersim_report_test_" + std::to_string(::getpid()));
  ScenarioResult r;
  r.id = "demo";
  r.title = "Demo";
  r.setup = "Set up like this.";
  r.metrics = {Metric{"inside", 1.5, "m", 1, 2, "a source"}, Metric{"outside", 5, "m", 1, 2, "a source"}};
  Plot p;
  p.file = "demo.svg";
  p.title = "Demo plot";
  p.series = {Series{"s", {0, 1}, {0, 1}, false}};
  r.plots = {p};
  WriteReport(dir, {r}, "ubersim validate-physics --only demo");
  std::ifstream in(dir / "README.md");
  const std::string md((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(md.find("**1 of 2 numbers within their bands.**"), std::string::npos) << md;
  EXPECT_NE(md.find("| demo | outside | 5 | 1 … 2 | m | **OUT** | a source |"), std::string::npos) << md;
  EXPECT_NE(md.find("![Demo plot](demo.svg)"), std::string::npos) << md;
  EXPECT_NE(md.find("`ubersim validate-physics --only demo`"), std::string::npos) << md;
  EXPECT_TRUE(fs::exists(dir / "demo.svg"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ubersim::validation
