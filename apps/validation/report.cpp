// SPDX-License-Identifier: Apache-2.0
#include "ubersim/validation/report.hpp"

#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "ubersim/validation/svg_plot.hpp"

namespace ubersim::validation {
namespace {

std::string Fixed(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

void WriteFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace

void WriteReport(const std::filesystem::path& dir, const std::vector<ScenarioResult>& results,
                 const std::string& command) {
  std::filesystem::create_directories(dir);
  int passed = 0, metrics = 0;
  for (const ScenarioResult& r : results) {
    for (const Metric& m : r.metrics) {
      ++metrics;
      passed += m.Pass() ? 1 : 0;
    }
  }
  std::string md;
  md += "# Physics validation\n\n";
  md += "Written by `" + command + "`; the test suite (`tests/validation`) runs the same scenarios and "
        "asserts the same bands. Bands come from `../shared/reference/physics.md` (published numbers) "
        "and from the issue's acceptance criteria; the basis column says which.\n\n";
  md += "**" + std::to_string(passed) + " of " + std::to_string(metrics) + " numbers within their bands.**\n\n";
  md += "| scenario | metric | value | band | unit | | basis |\n|---|---|---|---|---|---|---|\n";
  for (const ScenarioResult& r : results) {
    for (const Metric& m : r.metrics) {
      md += "| " + r.id + " | " + m.name + " | " + Fixed(m.value) + " | " + Fixed(m.low) + " … " +
            Fixed(m.high) + " | " + m.unit + " | " + (m.Pass() ? "ok" : "**OUT**") + " | " + m.basis + " |\n";
    }
  }
  for (const ScenarioResult& r : results) {
    md += "\n## " + r.title + " (`" + r.id + "`)\n\n" + r.setup + "\n";
    for (const Plot& p : r.plots) {
      WriteFile(dir / p.file, RenderSvg(p));
      md += "\n![" + p.title + "](" + p.file + ")\n";
    }
  }
  WriteFile(dir / "README.md", md);
}

}  // namespace ubersim::validation
