// SPDX-License-Identifier: Apache-2.0
// A small SVG line-plot writer: enough for a validation report a person reads in a browser or on
// the repository page, with no plotting dependency.
#include "ubersim/validation/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace ubersim::validation {
namespace {

constexpr double kWidth = 720, kHeight = 440;
constexpr double kLeft = 70, kRight = 170, kTop = 40, kBottom = 55;  // margins, px
constexpr const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b"};

std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", std::abs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool Empty() const { return lo > hi; }
};

// A tick step of 1, 2 or 5 × 10^k giving about `count` ticks.
double NiceStep(double span, int count) {
  const double raw = span / count;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * mag >= raw) return m * mag;
  }
  return 10 * mag;
}

// Widens the range to whole tick steps; returns the step.
double Nice(Range& r) {
  if (r.Empty()) { r.lo = 0; r.hi = 1; }
  if (r.hi - r.lo < 1e-12) { r.lo -= 0.5; r.hi += 0.5; }
  const double step = NiceStep(r.hi - r.lo, 6);
  r.lo = std::floor(r.lo / step) * step;
  r.hi = std::ceil(r.hi / step) * step;
  return step;
}

}  // namespace

std::string RenderSvg(const Plot& plot) {
  Range xr, yr;
  for (const Series& s : plot.series) {
    for (double v : s.x) xr.Add(v);
    for (double v : s.y) yr.Add(v);
  }
  double x_step = Nice(xr), y_step = Nice(yr);
  const double pw = kWidth - kLeft - kRight, ph = kHeight - kTop - kBottom;
  if (plot.equal_axes) {
    // One metre is as long across as up: grow the shorter range around its centre.
    const double scale = std::max((xr.hi - xr.lo) / pw, (yr.hi - yr.lo) / ph);
    const double xc = 0.5 * (xr.lo + xr.hi), yc = 0.5 * (yr.lo + yr.hi);
    xr.lo = xc - 0.5 * scale * pw; xr.hi = xc + 0.5 * scale * pw;
    yr.lo = yc - 0.5 * scale * ph; yr.hi = yc + 0.5 * scale * ph;
    x_step = NiceStep(xr.hi - xr.lo, 6);
    y_step = NiceStep(yr.hi - yr.lo, 6);
  }
  auto px = [&](double x) { return kLeft + (x - xr.lo) / (xr.hi - xr.lo) * pw; };
  auto py = [&](double y) { return kTop + ph - (y - yr.lo) / (yr.hi - yr.lo) * ph; };

  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kWidth << "\" height=\"" << kHeight
    << "\" viewBox=\"0 0 " << kWidth << " " << kHeight << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  o << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  o << "<text x=\"" << kLeft << "\" y=\"24\" font-size=\"15\" font-weight=\"bold\">" << Escape(plot.title)
    << "</text>\n";
  // Grid and ticks.
  o << "<g stroke=\"#ddd\" stroke-width=\"1\">\n";
  for (double x = std::ceil(xr.lo / x_step) * x_step; x <= xr.hi + 1e-9 * x_step; x += x_step) {
    o << "<line x1=\"" << px(x) << "\" y1=\"" << kTop << "\" x2=\"" << px(x) << "\" y2=\"" << kTop + ph << "\"/>\n";
  }
  for (double y = std::ceil(yr.lo / y_step) * y_step; y <= yr.hi + 1e-9 * y_step; y += y_step) {
    o << "<line x1=\"" << kLeft << "\" y1=\"" << py(y) << "\" x2=\"" << kLeft + pw << "\" y2=\"" << py(y) << "\"/>\n";
  }
  o << "</g>\n<g text-anchor=\"middle\">\n";
  for (double x = std::ceil(xr.lo / x_step) * x_step; x <= xr.hi + 1e-9 * x_step; x += x_step) {
    o << "<text x=\"" << px(x) << "\" y=\"" << kTop + ph + 16 << "\">" << Number(x) << "</text>\n";
  }
  o << "</g>\n<g text-anchor=\"end\">\n";
  for (double y = std::ceil(yr.lo / y_step) * y_step; y <= yr.hi + 1e-9 * y_step; y += y_step) {
    o << "<text x=\"" << kLeft - 6 << "\" y=\"" << py(y) + 4 << "\">" << Number(y) << "</text>\n";
  }
  o << "</g>\n";
  o << "<rect x=\"" << kLeft << "\" y=\"" << kTop << "\" width=\"" << pw << "\" height=\"" << ph
    << "\" fill=\"none\" stroke=\"#333\"/>\n";
  o << "<text x=\"" << kLeft + pw / 2 << "\" y=\"" << kHeight - 14 << "\" text-anchor=\"middle\">"
    << Escape(plot.x_label) << "</text>\n";
  o << "<text transform=\"translate(16," << kTop + ph / 2 << ") rotate(-90)\" text-anchor=\"middle\">"
    << Escape(plot.y_label) << "</text>\n";
  // Curves, clipped to the plot area.
  o << "<clipPath id=\"area\"><rect x=\"" << kLeft << "\" y=\"" << kTop << "\" width=\"" << pw
    << "\" height=\"" << ph << "\"/></clipPath>\n<g clip-path=\"url(#area)\" fill=\"none\" stroke-width=\"2\">\n";
  for (std::size_t i = 0; i < plot.series.size(); ++i) {
    const Series& s = plot.series[i];
    const std::size_t n = std::min(s.x.size(), s.y.size());
    if (s.points) {
      // One small dot per measurement: scattered data joined by a line reads as a trajectory.
      o << "<g fill=\"" << kColours[i % 6] << "\" stroke=\"none\">\n";
      for (std::size_t k = 0; k < n; ++k) {
        if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k])) continue;
        char buf[80];
        std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"1.6\"/>\n", px(s.x[k]), py(s.y[k]));
        o << buf;
      }
      o << "</g>\n";
      continue;
    }
    o << "<polyline stroke=\"" << kColours[i % 6] << "\"" << (s.dashed ? " stroke-dasharray=\"6 4\"" : "")
      << " points=\"";
    for (std::size_t k = 0; k < n; ++k) {
      if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k])) continue;
      char buf[48];
      std::snprintf(buf, sizeof buf, "%.1f,%.1f ", px(s.x[k]), py(s.y[k]));
      o << buf;
    }
    o << "\"/>\n";
  }
  o << "</g>\n";
  // Legend on the right.
  for (std::size_t i = 0; i < plot.series.size(); ++i) {
    const double y = kTop + 12 + 20.0 * static_cast<double>(i);
    o << "<line x1=\"" << kLeft + pw + 12 << "\" y1=\"" << y << "\" x2=\"" << kLeft + pw + 36 << "\" y2=\"" << y
      << "\" stroke=\"" << kColours[i % 6] << "\" stroke-width=\"2\""
      << (plot.series[i].dashed ? " stroke-dasharray=\"6 4\"" : "")
      << (plot.series[i].points ? " stroke-dasharray=\"2 4\"" : "") << "/>\n";
    o << "<text x=\"" << kLeft + pw + 42 << "\" y=\"" << y + 4 << "\">" << Escape(plot.series[i].label)
      << "</text>\n";
  }
  o << "</svg>\n";
  return o.str();
}

}  // namespace ubersim::validation
