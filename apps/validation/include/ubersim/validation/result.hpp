// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <string>
#include <vector>

// What a physics-validation scenario measured: numbers with their acceptance bands and sources,
// and the curves to plot. `ubersim validate-physics` writes them; the tests assert the same ones.
namespace ubersim::validation {

/// One measured number and the band it must fall in (inclusive).
struct Metric {
  std::string name;    ///< stable key, e.g. "sliding_deceleration"
  double value = 0;    ///< measured, in `unit`
  std::string unit;    ///< SI unit text ("m/s²", "m", "" for ratios)
  double low = 0;      ///< lowest accepted value
  double high = 0;     ///< highest accepted value
  std::string basis;   ///< where the band comes from (physics.md section, the paper, the issue)
  /// True when low <= value <= high (and value is finite).
  bool Pass() const;
};

/// One curve of a plot.
struct Series {
  std::string label;          ///< legend text
  std::vector<double> x;      ///< abscissae
  std::vector<double> y;      ///< ordinates, same length as x
  bool dashed = false;        ///< reference curves are dashed
  bool points = false;        ///< measured data: a dot per point instead of a line
};

/// A line plot written as an SVG file.
struct Plot {
  std::string file;           ///< file name, e.g. "ball-roll-2.svg"
  std::string title;          ///< heading
  std::string x_label;        ///< with unit
  std::string y_label;        ///< with unit
  std::vector<Series> series; ///< curves, drawn in order
  bool equal_axes = false;    ///< same scale on x and y (paths on the field)
};

/// Everything one scenario produced.
struct ScenarioResult {
  std::string id;                 ///< stable id, e.g. "ball_roll_2"
  std::string title;              ///< one line
  std::string setup;              ///< how it was run, a few sentences
  std::vector<Metric> metrics;    ///< numbers with bands
  std::vector<Plot> plots;        ///< figures
  /// True when every metric passes.
  bool Pass() const;
  /// The metric named `name`; throws std::out_of_range when absent.
  const Metric& Get(const std::string& name) const;
};

}  // namespace ubersim::validation
